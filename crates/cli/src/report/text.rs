//! The text report, for people: the sections line by line, matrices with tall brackets.

use super::*;

/// The report for people; `full` prints every entry whole (see [`TEXT_ENTRY_LIMIT`]).
pub fn text_with(d: &mut Derivation, full: bool) -> String {
    render(d, |d| Text { d, pool: &d.model.pool, full, out: Vec::new() })
}

/// The text report, a line at a time.
struct Text<'a> {
    d: &'a Derivation,
    pool: &'a Pool,
    full: bool,
    out: Vec<String>,
}

const U: Style = Style::Unicode;

impl Renderer for Text<'_> {
    fn section(&mut self, section: &Section) {
        match section {
            Section::Title(Some(title)) => {
                self.out.push(title.to_string());
                self.out.push("═".repeat(width(title)));
                self.out.push(String::new());
            }
            Section::Title(None) | Section::Model => {}
            Section::Parameters(params) => self.parameters(params),
            Section::Signals { inputs, outputs } => self.signals(inputs, outputs),
            Section::Coordinates { declared, .. } => self.coordinates(declared),
            Section::Constraints { constraints, sides, left_out } => {
                self.constraints(constraints, sides, left_out)
            }
            Section::Contacts(contacts) => self.contacts(contacts),
            Section::Energies { kinetic, potential, lagrangian } => {
                self.out.push("Energies".into());
                self.out.push(format!("  T = {}", self.print(*kinetic)));
                self.out.push(format!("  V = {}", self.print(*potential)));
                if let Some(l) = lagrangian {
                    self.out.push(format!("  L = {}", self.print(*l)));
                }
            }
            Section::Equations(equations) => {
                self.out.push("Equations of motion".into());
                for eq in *equations {
                    self.out.push(format!("  {} = {}", self.print(eq.lhs), self.print(eq.rhs)));
                }
            }
            Section::MassMatrix { mass, forcing, multipliers } => {
                self.mass_matrix(mass, forcing, multipliers)
            }
            Section::Independent(form) => self.independent(form),
            Section::Reactions { reactions, of_state } => self.reactions(reactions, of_state),
            Section::Shown(shown) => self.shown(shown),
            Section::AtStart { at_start, state } => self.at_start(at_start, state),
        }
    }

    fn finish(self) -> String {
        lines_text(&self.out)
    }
}

impl Text<'_> {
    fn print(&self, e: ExprId) -> String {
        entry(self.pool, e, self.full)
    }

    fn sym(&self, s: SymId) -> String {
        sym_text(self.pool, s, U)
    }

    fn parameters(&mut self, params: &[model::Param]) {
        if params.is_empty() {
            return;
        }
        self.out.push("Parameters".into());
        for p in params {
            let mut line = format!("  {}", self.sym(p.sym));
            if let Some(v) = p.value {
                line.push_str(&format!(" = {}", value_text(self.pool, v, U)));
            }
            if let Some(unit) = &p.unit {
                line.push_str(&format!(" {}", unit_text(unit, U)));
            }
            self.out.push(line);
        }
    }

    fn signals(&mut self, inputs: &[model::Input], outputs: &[model::Output]) {
        if !inputs.is_empty() {
            self.out.push("Inputs (each at its value when nothing drives it)".into());
        }
        for u in inputs {
            let mut line = format!("  {} = {}", self.sym(u.sym), value_text(self.pool, u.value, U));
            if let Some(unit) = &u.unit {
                line.push_str(&format!(" {}", unit_text(unit, U)));
            }
            self.out.push(line);
        }
        if !outputs.is_empty() {
            self.out.push("Outputs".into());
        }
        for o in outputs {
            self.out.push(format!("  {} = {}", o.name, self.pool.print(o.value, U)));
        }
    }

    fn coordinates(&mut self, coords: &[model::Coord]) {
        let (d, pool) = (self.d, self.pool);
        self.out.push("Coordinates".into());
        for c in coords {
            let name = self.sym(c.sym);
            if let Some(e) = d.eliminated.iter().find(|e| e.coord == c.sym) {
                let cname = &d.model.constraints[e.constraint].name;
                let solution = self.print(e.solution);
                self.out.push(format!("  {name} = {solution}   (eliminated by {cname})"));
            } else {
                let rate_symbol = pool.lookup_symbol(&format!("{}'", c.name));
                let rate = rate_symbol.map(|r| self.sym(r)).unwrap_or_default();
                let solved = if d.solved_start_positions.contains(&c.sym) {
                    ", solved from the constraints"
                } else {
                    ""
                };
                self.out.push(format!(
                    "  {name}   (from {name} {}, {rate} {}{solved})",
                    start_value_text(d, c.sym, c.initial, U),
                    start_value_text(d, rate_symbol.unwrap_or(c.sym), c.initial_rate, U)
                ));
            }
        }
    }

    fn constraints(
        &mut self,
        constraints: &[model::Constraint],
        sides: &[(ExprId, ExprId)],
        left_out: &[Option<String>],
    ) {
        if constraints.is_empty() {
            return;
        }
        // A contact's rows are listed with the contact, under Contacts.
        if constraints.iter().all(|c| c.kind.is_unilateral()) {
            return;
        }
        self.out.push("Constraints".into());
        for (i, c) in constraints.iter().enumerate() {
            if c.kind.is_unilateral() {
                continue;
            }
            let (lhs, rhs) = sides[i];
            self.out.push(format!("  {}: {} = {}", c.name, self.print(lhs), self.print(rhs)));
            let force = self.sym(c.force_symbol);
            let d = self.d;
            let kept = d.multipliers.iter().find(|m| m.constraint == i);
            if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                let what = if c.force_requested {
                    format!("; its reaction {force} is derived below")
                } else {
                    String::new()
                };
                if let Some(phi) = e.integrated {
                    self.out.push(format!("    integrates to {} = 0", self.print(phi)));
                }
                self.out.push(format!("    solved for {}{what}", self.sym(e.coord)));
            } else if let Some(why) = &left_out[i] {
                self.out.push(format!("    left out, as it restrains nothing more: {why}"));
            } else if kept.is_some_and(|m| m.rows.position.is_none()) {
                self.out.push(format!(
                    "    a velocity constraint, kept with the multiplier {force} (generalized force {force}·∂Φ/∂q̇)"
                ));
            } else {
                self.out.push(format!(
                    "    kept with the multiplier {force} (generalized force {force}·∂Φ/∂q)"
                ));
            }
        }
    }

    /// Each contact: its gap and law, what it adds while closed, and its impact law.
    fn contacts(&mut self, contacts: &[engine::derived::DerivedContact]) {
        if contacts.is_empty() {
            return;
        }
        let q: Vec<String> = self.d.coords.iter().map(|s| self.sym(*s)).collect();
        let rates: Vec<String> = self.d.rates.iter().map(|s| self.sym(*s)).collect();
        self.out.push("Contacts".into());
        for c in contacts {
            let force = self.sym(c.force);
            self.out.push(format!(
                "  {}: {} ≥ 0   (restitution {})",
                c.name,
                self.print(c.gap),
                self.print(c.restitution)
            ));
            let cone = c.cross.as_ref().map(|(v, f, _)| (self.print(*v), self.sym(*f)));
            let rough = match (c.grip, c.friction, c.grip_force) {
                (Some(slip), Some(mu), Some(tangent)) if cone.is_some() => {
                    let (tangent, mu, slip) = (self.sym(tangent), self.print(mu), self.print(slip));
                    let (cross, cross_force) = cone.clone().unwrap_or_default();
                    self.out.push(format!(
                        "    Coulomb friction μ = {mu}, the exact cone, along v = ({slip}, {cross})"
                    ));
                    self.out.push(format!(
                        "    sticks while ‖({tangent}, {cross_force})‖ < {mu}·{force}, holding \
                         v = 0; slips with ({tangent}, {cross_force}) = −{mu}·{force}·v/‖v‖"
                    ));
                    Some(mu)
                }
                (Some(slip), Some(mu), Some(tangent)) => {
                    let (tangent, mu, slip) = (self.sym(tangent), self.print(mu), self.print(slip));
                    self.out.push(format!("    Coulomb friction μ = {mu} along v = {slip}"));
                    self.out.push(format!(
                        "    sticks while |{tangent}| < {mu}·{force}, holding v = 0; slips with \
                         {tangent} = −{mu}·{force}·s, s = sign(v)"
                    ));
                    Some(mu)
                }
                (Some(grip), _, _) => {
                    self.out.push(format!("    grips: {} = 0 while closed", self.print(grip)));
                    None
                }
                _ => None,
            };
            if let Some(armed) = c.armed {
                self.out.push(format!(
                    "    armed while {} > 0 (open and unwatched otherwise; armed inside its gap, \
                     it waits for the gap to rise through 0)",
                    self.print(armed)
                ));
            }
            let start = if c.closed_at_start { "closed" } else { "open" };
            self.out.push(format!("    {start} at the start"));
            let direction: Vec<String> = c.direction.iter().map(|e| self.print(*e)).collect();
            self.out.push(format!(
                "    closed: {force} ≥ 0 adds {force}·({}) to the forces along ({}), and {} = {}",
                direction.join(", "),
                q.join(", "),
                self.print(c.acceleration),
                self.print(c.bias)
            ));
            if let (Some(gf), Some(gd)) = (c.grip_force, &c.grip_direction) {
                let gf = self.sym(gf);
                let gd: Vec<String> = gd.iter().map(|e| self.print(*e)).collect();
                let second = c.cross.as_ref().map(|(_, f, d)| {
                    let d: Vec<String> = d.iter().map(|e| self.print(*e)).collect();
                    (self.sym(*f), d.join(", "))
                });
                match (&rough, second) {
                    (Some(mu), Some((cf, cd))) => {
                        self.out.push(format!(
                            "            sticking: and {gf}·({}) + {cf}·({cd}), with v̇ = 0",
                            gd.join(", ")
                        ));
                        self.out.push(format!(
                            "            slipping: and −{mu}·{force}·(v₁·({}) + v₂·({cd}))/‖v‖, \
                             v free",
                            gd.join(", ")
                        ));
                    }
                    (Some(mu), None) => {
                        self.out.push(format!(
                            "            sticking: and {gf}·({}), with v̇ = 0",
                            gd.join(", ")
                        ));
                        self.out.push(format!(
                            "            slipping: and −{mu}·s·{force}·({}), v free",
                            gd.join(", ")
                        ));
                    }
                    (None, _) => {
                        self.out.push(format!("            and {gf}·({}), any sign", gd.join(", ")))
                    }
                }
            }
            self.out.push(format!("    open: {force} = 0, the equations without it"));
            match &c.impact {
                Some(law) => {
                    self.out.push(format!(
                        "    impact (rates before it on the right; landing at γ⁻ = {} < 0):",
                        self.print(law.normal_rate)
                    ));
                    if let (Some(mu), true) = (&rough, cone.is_some()) {
                        self.out.push(format!(
                            "      while it sticks, ‖Λ_T‖ ≤ {mu}·Λ (else it slips through it, \
                             Λ_T = −{mu}·Λ·v⁺/‖v⁺‖, which a run solves in numbers):"
                        ));
                    } else if let Some(mu) = &rough {
                        self.out.push(format!(
                            "      while it sticks, |Λ_T| ≤ {mu}·Λ (else it slips through it, \
                             Λ_T = −{mu}·Λ·sign(v⁺), which a run solves in numbers):"
                        ));
                    }
                    let impulses: Vec<ExprId> = std::iter::once(law.impulse)
                        .chain(law.tangential_impulse)
                        .chain(law.cross_impulse)
                        .collect();
                    if impulses.iter().any(|e| self.print(*e).chars().count() > 120) {
                        // Too long put in: the impulses as the problem that gives them.
                        let d: Vec<Vec<String>> = law
                            .delassus
                            .iter()
                            .map(|r| r.iter().map(|e| self.print(*e)).collect())
                            .collect();
                        let rows: Vec<String> =
                            d.iter().map(|r| format!("[{}]", r.join(", "))).collect();
                        self.out.push(format!("      D = W·M⁻¹·Wᵀ = [{}]", rows.join("; ")));
                        let normal = match self.pool.is_zero(c.restitution) {
                            true => "γ⁻".to_string(),
                            false => format!("(1 + {})·γ⁻", self.print(c.restitution)),
                        };
                        match (c.grip, &cone) {
                            (Some(v), Some((cross, _))) => self.out.push(format!(
                                "      D·(Λ, Λ_T, Λ_T2) = −({normal}, v⁻),  v⁻ = ({}, {cross})",
                                self.print(v)
                            )),
                            (Some(v), None) => self.out.push(format!(
                                "      D·(Λ, Λ_T) = −({normal}, v⁻),  v⁻ = {}",
                                self.print(v)
                            )),
                            (None, _) => self.out.push(format!("      D·Λ = −{normal}")),
                        }
                    } else {
                        self.out.push(format!("      Λ = {}", self.print(law.impulse)));
                        if let Some(t) = law.tangential_impulse {
                            self.out.push(format!("      Λ_T = {}", self.print(t)));
                        }
                        if let Some(t) = law.cross_impulse {
                            self.out.push(format!("      Λ_T2 = {}", self.print(t)));
                        }
                    }
                    // Long once the impulses are put in (a block's corner), the rates after read
                    // better as q̇ + U·Λ, as a hand derivation leaves them.
                    let long = law.rates_after.iter().any(|e| self.print(*e).chars().count() > 80);
                    let after = if long { &law.rates_in_impulses } else { &law.rates_after };
                    for (r, after) in rates.iter().zip(after) {
                        self.out.push(format!("      {r}⁺ = {}", self.print(*after)));
                    }
                }
                None => self.out.push(
                    "    impact: too large to solve exactly; a run solves it in numbers".into(),
                ),
            }
        }
        if contacts.len() > 1 {
            self.out.push(
                "  Contacts that land together, with those closed, solve one complementarity \
                 problem: Λ ≥ 0, γ⁺ + e·γ⁻ ≥ 0, Λ·(γ⁺ + e·γ⁻) = 0, γ⁺ = γ⁻ + W·M⁻¹·Wᵀ·Λ"
                    .into(),
            );
        }
    }

    fn mass_matrix(
        &mut self,
        mass: &[Vec<ExprId>],
        forcing: &[ExprId],
        multipliers: &[engine::derived::Multiplier],
    ) {
        let (pool, full) = (self.pool, self.full);
        let q: Vec<String> = self.d.coords.iter().map(|s| self.sym(*s)).collect();
        let extra = if multipliers.is_empty() { "" } else { " + Jᵀ·λ" };
        self.out
            .push(format!("Mass-matrix form  M(q)·q̈ = f(q, q̇){extra},  q = ({})", q.join(", ")));
        self.out.extend(bracketed(&cells(pool, mass, full), "  M = "));
        let f_rows: Vec<Vec<ExprId>> = forcing.iter().map(|e| vec![*e]).collect();
        self.out.extend(bracketed(&cells(pool, &f_rows, full), "  f = "));
        for m in multipliers {
            let name = self.sym(m.lambda);
            let row = cells(pool, std::slice::from_ref(&m.rows.jacobian), full);
            self.out.extend(bracketed(&row, &format!("  J({name}) = ")));
            self.out.push(format!("  γ({name}) = {}", self.print(m.rows.bias)));
            if let Some(force) = &m.force {
                // A slipping contact's: Coulomb's force rides on its normal one.
                let row = cells(pool, std::slice::from_ref(force), full);
                self.out.extend(bracketed(&row, &format!("  slipping, {name} acts along ")));
            }
        }
    }

    fn independent(&mut self, form: &engine::derived::IndependentForm) {
        let names = |s: &[SymId]| s.iter().map(|r| self.sym(*r)).collect::<Vec<_>>();
        let dependent: Vec<SymId> = form.dependent.iter().map(|(d, _)| *d).collect();
        let heading = format!(
            "In the independent rates  ({}; the constraints give {})",
            names(&form.independent).join(", "),
            names(&dependent).join(", ")
        );
        self.out.push(heading);
        for (d, e) in &form.dependent {
            self.out.push(format!("  {} = {}", self.sym(*d), self.print(*e)));
        }
        for e in &form.equations {
            self.out.push(format!("  {} = 0", self.print(*e)));
        }
    }

    fn reactions(&mut self, reactions: &[(SymId, ExprId)], of_state: &[(SymId, ExprId)]) {
        if reactions.is_empty() {
            return;
        }
        self.out.push("Reactions".into());
        for ((s, e), (_, explicit)) in reactions.iter().zip(of_state) {
            let mut line = format!("  {} = {}", self.sym(*s), self.print(*e));
            if explicit != e {
                line.push_str(&format!("\n    = {}", self.print(*explicit)));
            }
            self.out.push(line);
        }
    }

    fn shown(&mut self, shown: &[(model::Show, Value)]) {
        if shown.is_empty() {
            return;
        }
        let (d, pool) = (self.d, self.pool);
        self.out.push("Shown".into());
        for (show, v) in shown {
            let label = d.show_label(show, U);
            let unsolved = match v {
                Value::Scalar(e) => {
                    pool.as_sym(*e).filter(|s| d.multipliers.iter().any(|m| m.lambda == *s))
                }
                _ => None,
            };
            if unsolved.is_some() {
                // Past the size where the symbolic solution stays readable, say so rather than
                // print `λ = λ`.
                let unknowns = d.coords.len() + d.multipliers.len();
                self.out.push(format!(
                    "  {label}: a multiplier of the equations above; {unknowns} unknowns are too many to solve for it symbolically (`lagrange simulate --output {}` gives its values)",
                    show.label
                ));
                continue;
            }
            self.out.extend(value_lines(pool, self.full, &format!("  {label} = "), v));
        }
    }

    fn at_start(&mut self, at_start: &ShownAtStart, state: &[(SymId, ExprId)]) {
        let (d, pool) = (self.d, self.pool);
        let state: Vec<String> = state
            .iter()
            .map(|(s, e)| format!("{} {}", self.sym(*s), start_value_text(d, *s, *e, U)))
            .collect();
        let start_heading = || format!("At the start  ({})", state.join(", "));
        match at_start {
            ShownAtStart::Exact(items) if !items.is_empty() => {
                self.out.push(start_heading());
                for (show, v) in items {
                    let label = d.show_label(show, U);
                    self.out.extend(value_lines(pool, self.full, &format!("  {label} = "), v));
                }
            }
            ShownAtStart::Exact(_) => {}
            ShownAtStart::Numeric { items, unknowns, digits, params, because } => {
                self.out.push(start_heading());
                let at: Vec<String> = params
                    .iter()
                    .map(|(s, v)| format!("{} = {}", self.sym(*s), significant(*v, 15, U)))
                    .collect();
                self.out.push(format!(
                    "  solved numerically: {}; at {}, to about {digits} significant digits",
                    because.words(*unknowns),
                    at.join(", ")
                ));
                for (show, v) in items {
                    let label = d.show_label(show, U);
                    self.out.push(format!("  {label} ≈ {}", numeric_text(v, *digits, U)));
                }
            }
            ShownAtStart::Unvalued { unknowns, missing } => self.out.push(format!(
                "At the start: {unknowns} unknowns are too many to solve for exactly, and solving numerically needs a value for {}",
                missing.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ")
            )),
            ShownAtStart::Singular => self
                .out
                .push("At the start: the mass matrix is singular; nothing can be shown".into()),
        }
    }
}
