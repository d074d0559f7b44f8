//! From a model to equations of motion: constraints eliminated or kept as multipliers, the
//! energies, the Euler–Lagrange equations in mass-matrix form, and reactions where asked for.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId, SymbolKind};
use lang::Diagnostic;
use model::{BodyKind, Model, Placeholder, Value};

use crate::linear;

/// A constraint solved for one coordinate, which then leaves the equations.
#[derive(Clone, Debug)]
pub struct Elimination {
    pub constraint: usize,
    pub coord: SymId,
    /// The coordinate as a function of the remaining ones (and time).
    pub solution: ExprId,
}

/// A constraint kept in the equations through its multiplier λ (its reaction), with
/// generalized force λ·∂Φ/∂q, and its acceleration-level row J·q̈ = γ.
#[derive(Clone, Debug)]
pub struct Multiplier {
    pub constraint: usize,
    pub lambda: SymId,
    /// Φ in the remaining coordinates.
    pub phi: ExprId,
    /// ∂Φ/∂q, one entry per coordinate.
    pub jacobian: Vec<ExprId>,
    /// γ = −(J̇·q̇ + ∂²Φ/∂t² + …): what J·q̈ must equal.
    pub bias: ExprId,
}

/// The reaction of an eliminated constraint, from the Euler–Lagrange equation of the
/// coordinate it removed. In terms of coordinates, rates, accelerations (and multipliers).
#[derive(Clone, Debug)]
pub struct Reaction {
    pub constraint: usize,
    pub symbol: SymId,
    pub expr: ExprId,
}

/// Everything derived from a model. Owns the model (and with it the expression pool).
pub struct Derivation {
    pub model: Model,
    /// The coordinates left after elimination, in declaration order.
    pub coords: Vec<SymId>,
    pub rates: Vec<SymId>,
    pub accels: Vec<SymId>,
    pub eliminated: Vec<Elimination>,
    pub multipliers: Vec<Multiplier>,
    /// q, q̇ and q̈ of each eliminated coordinate, as expressions of the remaining ones.
    pub elimination_map: HashMap<SymId, ExprId>,
    pub kinetic: ExprId,
    pub potential: ExprId,
    pub lagrangian: ExprId,
    /// Generalized forces of the applied forces, torques and dissipation.
    pub generalized_forces: Vec<ExprId>,
    /// M(q, t), with M·q̈ = f (+ Jᵀλ when there are multipliers).
    pub mass_matrix: Vec<Vec<ExprId>>,
    pub forcing: Vec<ExprId>,
    pub reactions: Vec<Reaction>,
    pub warnings: Vec<Diagnostic>,
    /// q̈ and λ solved symbolically, for small systems; computed on first use.
    solved: Option<Option<HashMap<SymId, ExprId>>>,
    /// The unknowns at the start; computed on first use.
    pub(crate) start: Option<crate::start::StartSolution>,
}

impl Derivation {
    pub fn pool(&mut self) -> &mut Pool {
        &mut self.model.pool
    }

    /// The unknowns of one instant: accelerations, then multipliers.
    pub fn unknowns(&self) -> Vec<SymId> {
        let mut u = self.accels.clone();
        u.extend(self.multipliers.iter().map(|m| m.lambda));
        u
    }

    /// The rows of the full linear system in the unknowns: `rows · u = rhs`.
    /// First the equations of motion (M q̈ − Jᵀλ = f), then the constraints (J q̈ = γ).
    pub fn system(&mut self) -> (Vec<Vec<ExprId>>, Vec<ExprId>) {
        let n = self.coords.len();
        let mut rows = Vec::new();
        let mut rhs = Vec::new();
        for i in 0..n {
            let mut row = self.mass_matrix[i].clone();
            for m in &self.multipliers {
                let j = m.jacobian[i];
                row.push(self.model.pool.neg(j));
            }
            rows.push(row);
            rhs.push(self.forcing[i]);
        }
        for m in &self.multipliers {
            let mut row = m.jacobian.clone();
            row.extend(std::iter::repeat_n(self.model.pool.zero(), self.multipliers.len()));
            rows.push(row);
            rhs.push(m.bias);
        }
        (rows, rhs)
    }

    /// Replaces KE, PE and reactions by what they are, and eliminated coordinates by their
    /// solutions. With `keep_multipliers`, the reactions of constraints kept with multipliers
    /// stay the unknowns λ of the equations of motion (as checks want them), rather than their
    /// solved forms (as `show` wants them).
    pub fn expand_quantities(&mut self, e: ExprId, keep_multipliers: bool) -> ExprId {
        let kept: Vec<usize> = if keep_multipliers {
            self.multipliers.iter().map(|m| m.constraint).collect()
        } else {
            Vec::new()
        };
        let mut map: HashMap<SymId, ExprId> = HashMap::new();
        for (s, kind) in self.model.placeholders.clone() {
            let value = match kind {
                Placeholder::KineticEnergy => Some(self.kinetic),
                Placeholder::PotentialEnergy => Some(self.potential),
                Placeholder::Reaction(c) if kept.contains(&c) => None,
                Placeholder::Reaction(c) => {
                    self.reactions.iter().find(|r| r.constraint == c).map(|r| r.expr)
                }
            };
            if let Some(v) = value {
                map.insert(s, v);
            }
        }
        let e = self.model.pool.subst(e, &map);
        self.model.pool.subst(e, &self.elimination_map)
    }

    pub fn expand_value(&mut self, v: &Value, keep_multipliers: bool) -> Value {
        v.map(|e| self.expand_quantities(e, keep_multipliers))
    }

    /// The initial state: each remaining coordinate and rate at its `coord` value, t = 0.
    pub fn initial_state(&mut self) -> HashMap<SymId, ExprId> {
        let mut state = HashMap::new();
        let time = self.model.time;
        state.insert(time, self.model.pool.zero());
        for c in self.model.coords.clone() {
            if !self.coords.contains(&c.sym) {
                continue;
            }
            state.insert(c.sym, c.initial);
            let rate = self.model.pool.rate(c.sym).expect("coordinate");
            state.insert(rate, c.initial_rate);
        }
        state
    }

    /// Accelerations and multipliers as expressions of the state, for systems small enough
    /// (at most four unknowns) that the symbolic solution stays readable.
    pub fn solved_unknowns(&mut self) -> Option<HashMap<SymId, ExprId>> {
        if self.solved.is_none() {
            let unknowns = self.unknowns();
            let result = if unknowns.is_empty() || unknowns.len() > SYMBOLIC_SOLVE_LIMIT {
                None
            } else {
                let (rows, rhs) = self.system();
                linear::solve(&mut self.model.pool, &rows, &rhs)
                    .map(|x| unknowns.into_iter().zip(x).collect())
            };
            self.solved = Some(result);
        }
        self.solved.clone().flatten()
    }

    /// An expression with accelerations and multipliers replaced by their solved forms, where
    /// the system is small enough to have them; unchanged otherwise.
    pub fn of_state(&mut self, e: ExprId) -> ExprId {
        match self.solved_unknowns() {
            Some(map) => {
                let x = self.model.pool.subst(e, &map);
                self.model.pool.together(x)
            }
            None => e,
        }
    }
}

/// Derives the equations of motion of a model.
pub fn derive(mut model: Model) -> Result<Derivation, Vec<Diagnostic>> {
    let mut errors = Vec::new();
    let mut warnings = Vec::new();
    let dim = model.dimension();
    let pool = &mut model.pool;

    // --- constraints: eliminate where one coordinate can be solved for --------------------
    let declared: Vec<SymId> = model.coords.iter().map(|c| c.sym).collect();
    let mut solved: HashMap<SymId, ExprId> = HashMap::new();
    let mut eliminated: Vec<Elimination> = Vec::new();
    let mut kept: Vec<usize> = Vec::new();
    for (ci, c) in model.constraints.iter().enumerate() {
        let phi = pool.subst(c.phi, &solved);
        let phi = pool.expand(phi);
        if pool.is_identically_zero(phi) {
            errors.push(
                Diagnostic::error(
                    c.span,
                    format!("constraint `{}` is implied by the ones before it", c.name),
                )
                .with_label("redundant")
                .with_hint("remove it: it adds no condition"),
            );
            continue;
        }
        let free = pool.free_symbols(phi);
        // Prefer a coordinate written alone on the left (`y = …`), then the latest declared.
        let mut candidates: Vec<SymId> = c
            .lhs_coords
            .iter()
            .copied()
            .filter(|q| free.contains(q) && !solved.contains_key(q))
            .collect();
        for q in declared.iter().rev() {
            if free.contains(q) && !candidates.contains(q) && !solved.contains_key(q) {
                candidates.push(*q);
            }
        }
        let mut done = false;
        for q in candidates {
            let a = pool.diff(phi, q);
            let a = pool.simplify(a);
            let a_free = pool.free_symbols(a);
            // Linear in q, with a coefficient that never vanishes as the system moves.
            let depends_on_motion =
                a_free.iter().any(|s| !matches!(pool.symbol(*s).kind, SymbolKind::Param));
            if depends_on_motion || pool.is_identically_zero(a) {
                continue;
            }
            let qe = pool.sym(q);
            let step = pool.div(phi, a);
            let sol = pool.sub(qe, step);
            let sol = pool.simplify(sol);
            // Earlier solutions that mention q now use the new one.
            let single: HashMap<SymId, ExprId> = [(q, sol)].into_iter().collect();
            for v in solved.values_mut() {
                let s = pool.subst(*v, &single);
                *v = pool.simplify(s);
            }
            for e in eliminated.iter_mut() {
                e.solution = solved[&e.coord];
            }
            solved.insert(q, sol);
            eliminated.push(Elimination { constraint: ci, coord: q, solution: sol });
            done = true;
            break;
        }
        if !done {
            kept.push(ci);
        }
    }
    for e in eliminated.iter_mut() {
        e.solution = solved[&e.coord];
    }

    let coords: Vec<SymId> = declared.iter().copied().filter(|q| !solved.contains_key(q)).collect();
    let rates: Vec<SymId> = coords.iter().map(|q| pool.rate(*q).expect("coordinate")).collect();
    let accels: Vec<SymId> = rates.iter().map(|q| pool.rate(*q).expect("coordinate")).collect();

    // q, q̇, q̈ of each eliminated coordinate in terms of the rest.
    let mut elimination_map: HashMap<SymId, ExprId> = HashMap::new();
    for e in &eliminated {
        let v = pool.time_derivative(e.solution);
        let a = pool.time_derivative(v);
        let r = pool.rate(e.coord).expect("coordinate");
        let rr = pool.rate(r).expect("coordinate");
        elimination_map.insert(e.coord, e.solution);
        elimination_map.insert(r, v);
        elimination_map.insert(rr, a);
    }

    // --- energies in all declared coordinates --------------------------------------------
    let mut kinetic_terms = Vec::new();
    let mut potential_terms = Vec::new();
    let half = cas::number::ratio(1, 2);
    let gravity_dir: Option<Vec<ExprId>> = model.gravity.as_ref().map(|g| match &g.direction {
        // `along` gives a direction only: gravity's strength is g whatever the vector's length.
        Some(d) => {
            let squares: Vec<ExprId> = d.iter().map(|x| pool.powi(*x, 2)).collect();
            let norm2 = pool.add(&squares);
            let norm = pool.sqrt(norm2);
            d.iter().map(|x| pool.div(*x, norm)).collect()
        }
        None => {
            let mut d = vec![pool.zero(); dim];
            d[dim - 1] = pool.int(-1);
            d
        }
    });
    for body in &model.bodies {
        let mut v2 = Vec::new();
        for x in &body.position {
            let v = pool.time_derivative(*x);
            v2.push(pool.powi(v, 2));
        }
        let speed2 = pool.add(&v2);
        let t = pool.mul2(body.mass, speed2);
        kinetic_terms.push(pool.scale(t, &half));
        if let (BodyKind::Rigid, Some(i), Some(angle)) = (body.kind, body.inertia, body.angle) {
            let w = pool.time_derivative(angle);
            let w2 = pool.powi(w, 2);
            let t = pool.mul2(i, w2);
            kinetic_terms.push(pool.scale(t, &half));
        }
        if let (Some(g), Some(dir)) = (&model.gravity, &gravity_dir) {
            // V = −m g (d · r): the work gravity does is lost as potential energy.
            let parts: Vec<ExprId> =
                body.position.iter().zip(dir.iter()).map(|(x, d)| pool.mul2(*x, *d)).collect();
            let along = pool.add(&parts);
            let v = pool.mul(&[body.mass, g.strength, along]);
            potential_terms.push(pool.neg(v));
        }
    }
    for p in &model.potentials {
        potential_terms.push(p.expr);
    }
    let kinetic_full = pool.add(&kinetic_terms);
    let potential_full = pool.add(&potential_terms);
    let mut lag_terms = vec![kinetic_full, pool.neg(potential_full)];
    lag_terms.extend(model.lagrangians.iter().map(|l| l.expr));
    let lagrangian_full = pool.add(&lag_terms);
    let dissipation_full = {
        let d: Vec<ExprId> = model.dissipation.iter().map(|d| d.expr).collect();
        pool.add(&d)
    };

    // Generalized forces in any set of coordinates: Σ F·∂r/∂q + τ ∂angle/∂q − ∂D/∂q̇.
    let generalized_force = |pool: &mut Pool, q: SymId, map: &HashMap<SymId, ExprId>| -> ExprId {
        let mut parts = Vec::new();
        for f in &model.forces {
            let body = &model.bodies[f.body];
            let comps = match &f.value {
                Value::Vector(v) => v.clone(),
                Value::Scalar(s) => vec![*s],
                Value::Matrix(_) => Vec::new(),
            };
            for (fc, x) in comps.iter().zip(body.position.iter()) {
                let x = pool.subst(*x, map);
                let fc = pool.subst(*fc, map);
                let dx = pool.diff(x, q);
                parts.push(pool.mul2(fc, dx));
            }
        }
        for t in &model.torques {
            let (Value::Scalar(tau), Some(angle)) = (&t.value, model.bodies[t.body].angle) else {
                continue;
            };
            let angle = pool.subst(angle, map);
            let tau = pool.subst(*tau, map);
            let da = pool.diff(angle, q);
            parts.push(pool.mul2(tau, da));
        }
        let d = pool.subst(dissipation_full, map);
        let rate = pool.rate(q).expect("coordinate");
        let dd = pool.diff(d, rate);
        parts.push(pool.neg(dd));
        pool.add(&parts)
    };

    // --- the reduced system --------------------------------------------------------------
    let kinetic = pool.subst(kinetic_full, &elimination_map);
    let potential = pool.subst(potential_full, &elimination_map);
    let lagrangian = pool.subst(lagrangian_full, &elimination_map);
    let time = model.time;
    let n = coords.len();
    let mut mass_matrix = vec![vec![pool.zero(); n]; n];
    let mut forcing = Vec::with_capacity(n);
    let mut generalized_forces = Vec::with_capacity(n);
    for i in 0..n {
        // p_i = ∂L/∂q̇_i; d/dt p_i = Σ_j M_ij q̈_j + Σ_j ∂p_i/∂q_j q̇_j + ∂p_i/∂t.
        let p = pool.diff(lagrangian, rates[i]);
        for j in 0..n {
            mass_matrix[i][j] = pool.diff(p, rates[j]);
        }
        let mut parts = Vec::new();
        let q_force = generalized_force(pool, coords[i], &elimination_map);
        generalized_forces.push(q_force);
        parts.push(q_force);
        parts.push(pool.diff(lagrangian, coords[i]));
        for j in 0..n {
            let dp = pool.diff(p, coords[j]);
            let qd = pool.sym(rates[j]);
            let t = pool.mul2(dp, qd);
            parts.push(pool.neg(t));
        }
        let dpt = pool.diff(p, time);
        parts.push(pool.neg(dpt));
        forcing.push(pool.add(&parts));
    }
    // Folding sin² + cos² and angle sums (cos θ₁ cos θ₂ + sin θ₁ sin θ₂ = cos(θ₁ − θ₂)) leaves
    // fewer operations for the numbers to do, and is what every report prints anyway.
    for row in mass_matrix.iter_mut() {
        for e in row.iter_mut() {
            *e = pool.simplify(*e);
        }
    }
    for e in forcing.iter_mut() {
        *e = pool.simplify(*e);
    }
    for (i, q) in coords.iter().enumerate() {
        if mass_matrix[i].iter().all(|e| pool.is_identically_zero(*e)) {
            let span =
                model.coords.iter().find(|c| c.sym == *q).map(|c| c.span).unwrap_or_default();
            errors.push(
                Diagnostic::error(span, format!("no kinetic energy depends on the rate of `{}`", pool.symbol(*q).name))
                    .with_label("this coordinate has no inertia")
                    .with_hint("the mass matrix would be singular: place a body that moves with this coordinate, or remove it"),
            );
        }
    }

    // --- constraints kept with multipliers ------------------------------------------------
    let mut multipliers = Vec::new();
    for &ci in &kept {
        let c = &model.constraints[ci];
        let phi = pool.subst(c.phi, &elimination_map);
        let phi = pool.expand(phi);
        let jacobian: Vec<ExprId> = coords.iter().map(|q| pool.diff(phi, *q)).collect();
        let velocity = pool.time_derivative(phi);
        let acceleration = pool.time_derivative(velocity);
        let zeros: HashMap<SymId, ExprId> = accels.iter().map(|a| (*a, pool.zero())).collect();
        let rest = pool.subst(acceleration, &zeros);
        let bias = pool.neg(rest);
        multipliers.push(Multiplier {
            constraint: ci,
            lambda: c.force_symbol,
            phi,
            jacobian,
            bias,
        });
    }
    if !errors.is_empty() {
        return Err(errors);
    }

    // --- reactions of eliminated constraints, where asked for -----------------------------
    let mut reactions = Vec::new();
    let requested = eliminated.iter().any(|e| model.constraints[e.constraint].force_requested);
    if requested {
        // For each eliminated coordinate e: d/dt ∂L/∂ė − ∂L/∂e − Q_e = Σ_c λ_c ∂Φ_c/∂e, all
        // in the full coordinates, then expressed in the remaining ones.
        let k = eliminated.len();
        let mut a = vec![vec![pool.zero(); k]; k];
        let mut b = Vec::with_capacity(k);
        let identity: HashMap<SymId, ExprId> = HashMap::new();
        for (row, e) in eliminated.iter().enumerate() {
            let rate = pool.rate(e.coord).expect("coordinate");
            let p = pool.diff(lagrangian_full, rate);
            let dp = pool.time_derivative(p);
            let dl = pool.diff(lagrangian_full, e.coord);
            let q_force = generalized_force(pool, e.coord, &identity);
            let lhs = pool.sub(dp, dl);
            let mut lhs = pool.sub(lhs, q_force);
            for m in &multipliers {
                let c = &model.constraints[m.constraint];
                let dphi = pool.diff(c.phi, e.coord);
                let lam = pool.sym(m.lambda);
                let t = pool.mul2(dphi, lam);
                lhs = pool.sub(lhs, t);
            }
            let lhs = pool.subst(lhs, &elimination_map);
            b.push(pool.simplify(lhs));
            for (col, f) in eliminated.iter().enumerate() {
                let dphi = pool.diff(model.constraints[f.constraint].phi, e.coord);
                a[row][col] = pool.subst(dphi, &elimination_map);
            }
        }
        match linear::solve(pool, &a, &b) {
            Some(lambdas) => {
                for (e, expr) in eliminated.iter().zip(lambdas) {
                    let c = &model.constraints[e.constraint];
                    if c.force_requested {
                        reactions.push(Reaction {
                            constraint: e.constraint,
                            symbol: c.force_symbol,
                            expr,
                        });
                    }
                }
            }
            None => {
                let c = &model.constraints[eliminated[0].constraint];
                warnings.push(
                    Diagnostic::warning(
                        c.span,
                        "the reactions of these constraints cannot be separated",
                    )
                    .with_label("reaction not derived"),
                );
            }
        }
    }

    let mut derivation = Derivation {
        model,
        coords,
        rates,
        accels,
        eliminated,
        multipliers,
        elimination_map,
        kinetic,
        potential,
        lagrangian,
        generalized_forces,
        mass_matrix,
        forcing,
        reactions,
        warnings,
        solved: None,
        start: None,
    };
    derivation.solve_multiplier_reactions();
    derivation.warn_about_overridden_initial_values();
    Ok(derivation)
}

impl Derivation {
    /// An eliminated coordinate's initial value comes from its constraint; one written in the
    /// scene that disagrees with it would be silently ignored, so say so.
    fn warn_about_overridden_initial_values(&mut self) {
        let mut state = self.initial_state();
        // Compare with the parameters' values, as the numbers will see them.
        for p in &self.model.params {
            if let Some(v) = p.value {
                state.insert(p.sym, v);
            }
        }
        for e in self.eliminated.clone() {
            let Some(c) = self.model.coords.iter().find(|c| c.sym == e.coord).cloned() else {
                continue;
            };
            if !c.initial_given {
                continue;
            }
            let pool = &mut self.model.pool;
            let implied = pool.subst(e.solution, &state);
            let implied = pool.simplify(implied);
            let given = pool.subst(c.initial, &state);
            let difference = pool.sub(given, implied);
            if pool.is_identically_zero(difference) {
                continue;
            }
            let constraint = self.model.constraints[e.constraint].name.clone();
            let text = pool.print(implied, cas::Style::Ascii);
            self.warnings.push(
                Diagnostic::warning(c.span, format!("the initial value of `{}` is ignored", c.name))
                    .with_label(format!("`{constraint}` fixes it at {text}"))
                    .with_hint(format!(
                        "the constraint `{constraint}` eliminates `{}`: drop its initial value, or make it {text}",
                        c.name
                    )),
            );
        }
    }
}

/// Past this many unknowns the symbolic solution of the full system is too large to be worth
/// printing; the reactions of kept constraints then stay multipliers, found numerically.
const SYMBOLIC_SOLVE_LIMIT: usize = 4;

impl Derivation {
    /// The reactions of constraints kept with multipliers, as expressions of the state: the
    /// multipliers of the solved system M q̈ − Jᵀλ = f, J q̈ = γ.
    fn solve_multiplier_reactions(&mut self) {
        let wanted: Vec<usize> = (0..self.multipliers.len())
            .filter(|&i| self.model.constraints[self.multipliers[i].constraint].force_requested)
            .collect();
        let n = self.coords.len();
        if wanted.is_empty() || n + self.multipliers.len() > SYMBOLIC_SOLVE_LIMIT {
            return;
        }
        let Some(solved) = self.solved_unknowns() else { return };
        for i in wanted {
            let m = &self.multipliers[i];
            let expr = self.model.pool.factor_content(solved[&m.lambda]);
            self.reactions.push(Reaction { constraint: m.constraint, symbol: m.lambda, expr });
        }
    }
}
