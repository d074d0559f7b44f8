//! Small motions about a reference, exactly: the `linearize about` lines merged into one
//! reference, the coordinates that are cyclic there, and M, C, K of
//! M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ as expressions of the parameters (with the multipliers'
//! symbols where constraints are kept). Whether the reference is an equilibrium where the
//! algebra cannot say, and everything after (eigenvalues, stability), is for numbers.
//!
//! With q̈ = 0 at the reference, the term ∂M/∂q·q̈ of the linearized M·q̈ drops out, so the
//! Jacobians of f (and of Jᵀλ) are all there is to it: K = −∂(f + Jᵀλ)/∂q and C = −∂f/∂q̇.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use model::ConstraintKind;

use crate::derive::Derivation;

/// A kept constraint at the reference: its linearized row J·δq = 0, and Φ and γ there (both
/// must vanish for the reference to lie on it and stay there).
#[derive(Clone, Debug)]
pub struct LinearConstraint {
    /// Its index among the model's constraints.
    pub constraint: usize,
    pub kind: ConstraintKind,
    /// The multiplier's symbol (`rod.force`), which appears in K and in the residual.
    pub lambda: SymId,
    /// ∂Φ/∂q for a position constraint, ∂Φ/∂q̇ for a velocity constraint: its row of
    /// J·q̈ = γ, and the direction of its reaction.
    pub jacobian: Vec<ExprId>,
    /// Φ at the reference: a position constraint's value there (zero on it); a velocity
    /// constraint's with the dependent rates at 0 (see [`KeptLinearization`]).
    pub phi: ExprId,
    pub bias: ExprId,
    /// With velocity and position constraints kept together ([`KeptLinearization`]): its row
    /// at the velocity level, Φ for a velocity constraint and Φ̇ for a position one, with the
    /// dependent rates at 0 (so that it is J·q̇ of the given rates, and the rest); and, for a
    /// velocity constraint, ∂Φ/∂q (B of A·δq̇ + B·δq = 0). Empty otherwise.
    pub rate_row: Option<ExprId>,
    pub positions: Vec<ExprId>,
}

/// The reference of a scene keeping velocity constraints beside position constraints (or too
/// many velocity constraints for the independent rates' exact form): the dependent rates stay
/// symbols in every matrix, for numbers to solve from the constraints' `rate_row`s, and the
/// reduction to the independent coordinates and rates is done in numbers too.
#[derive(Clone, Debug)]
pub struct KeptLinearization {
    /// The coordinates (indices into `coords`) whose rates the constraints fix at the
    /// reference: one per kept constraint, chosen as the independent rates' form chooses.
    pub dependent: Vec<usize>,
}

/// M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ about a reference, exactly.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// The remaining coordinates, in the derivation's order; every matrix is indexed by them.
    pub coords: Vec<SymId>,
    /// Whether each is cyclic: in neither M nor f nor a kept constraint, so that its position
    /// does not enter, its column of K is zero, and δq of it can leave the state.
    pub cyclic: Vec<bool>,
    /// The reference position of each coordinate; `None` for a cyclic one not given.
    pub positions: Vec<Option<ExprId>>,
    /// The reference rate of each coordinate (0 unless given).
    pub rates: Vec<ExprId>,
    pub mass: Vec<Vec<ExprId>>,
    pub damping: Vec<Vec<ExprId>>,
    pub stiffness: Vec<Vec<ExprId>>,
    /// f + Jᵀλ at the reference, λ the multipliers' symbols: what M·q̈ is there. Zero at an
    /// equilibrium or a steady motion.
    pub residual: Vec<ExprId>,
    /// Whether the algebra shows the residual zero, for every value of the parameters (without
    /// kept constraints only: with them, the multipliers' values are for numbers to find).
    pub residual_is_zero: bool,
    pub constraints: Vec<LinearConstraint>,
    /// With velocity constraints kept: the equations in the independent rates, linearized
    /// (then `mass`, `damping` and `stiffness` are M̃, C̃, K̃ of M̃·δu̇ + C̃·δu + K̃·δp = 0, with
    /// u the independent rates and p the positions kept, and `constraints` is empty: the
    /// multipliers cancel in that form).
    pub independent: Option<RatesLinearization>,
    /// With velocity and position constraints kept together: how numbers finish the job.
    pub kept: Option<KeptLinearization>,
    /// The last `linearize about` line, which the reference is reported at.
    pub span: Span,
}

impl Derivation {
    /// Linearizes the equations of motion about the reference of the scene's `linearize about`
    /// lines (a later line overrides an earlier one item by item). Errors point at the items or
    /// lines at fault: a coordinate that was eliminated, a position missing, a non-cyclic
    /// coordinate given a rate, equations that depend on time there.
    pub fn linearize(&mut self) -> Result<Linearization, Vec<Diagnostic>> {
        let Some(span) = self.model.linearize.last().map(|l| l.span) else {
            return Err(vec![Diagnostic::error(Span::default(), "no `linearize about` line")
                .with_hint("add `linearize about q = …` naming the reference")]);
        };
        let mut errors = Vec::new();
        // The reference: later items override earlier ones.
        let mut given: HashMap<(SymId, bool), (ExprId, Span)> = HashMap::new();
        for line in &self.model.linearize {
            for item in &line.items {
                given.insert((item.coord, item.rate), (item.value, item.span));
            }
        }
        let mut items: Vec<((SymId, bool), (ExprId, Span))> = given.into_iter().collect();
        items.sort_by_key(|(_, (_, s))| (s.start, s.end));
        for ((coord, _), (_, item_span)) in &items {
            if let Some(e) = self.eliminated.iter().find(|e| e.coord == *coord) {
                let name = self.model.pool.symbol(*coord).name.clone();
                let constraint = &self.model.constraints[e.constraint].name;
                errors.push(
                    Diagnostic::error(
                        *item_span,
                        format!("`{name}` is eliminated by `{constraint}`"),
                    )
                    .with_label("not a coordinate of the equations")
                    .with_hint(format!(
                        "leave `{name}` out: its reference follows from the others through `{constraint}`"
                    )),
                );
            }
        }

        if self.multipliers.iter().any(|m| m.kind == ConstraintKind::Velocity) {
            if !errors.is_empty() {
                return Err(errors);
            }
            let mixed = self.multipliers.iter().any(|m| m.kind == ConstraintKind::Position);
            if mixed || self.multipliers.len() > crate::independent::DEPENDENT_LIMIT {
                return self.linearize_kept(span, &items);
            }
            return self.linearize_in_rates(span, &items);
        }

        let n = self.coords.len();
        let cyclic: Vec<bool> = (0..n).map(|i| self.is_cyclic(self.coords[i])).collect();
        let pool = &mut self.model.pool;
        let mut positions = vec![None; n];
        let mut rates = vec![pool.zero(); n];
        let mut map: HashMap<SymId, ExprId> = HashMap::new();
        for ((coord, rate), (value, item_span)) in &items {
            let Some(i) = self.coords.iter().position(|q| q == coord) else { continue };
            if *rate {
                rates[i] = *value;
                map.insert(self.rates[i], *value);
                if !cyclic[i] && !pool.is_zero(*value) {
                    let name = pool.symbol_text(*coord, cas::Style::Unicode);
                    errors.push(
                        Diagnostic::error(
                            *item_span,
                            format!("a reference that moves `{name}` does not stay put"),
                        )
                        .with_label(format!("{name} is not cyclic: M or f depends on it"))
                        .with_hint(
                            "a steady motion may move only cyclic coordinates (those in neither \
                             M nor f); give this one a position and rate 0",
                        ),
                    );
                }
            } else {
                positions[i] = Some(*value);
                map.insert(*coord, *value);
            }
        }
        for i in 0..n {
            map.entry(self.rates[i]).or_insert(pool.zero());
        }
        let missing: Vec<SymId> = (0..n)
            .filter(|&i| !cyclic[i] && positions[i].is_none())
            .map(|i| self.coords[i])
            .collect();
        errors.extend(missing_positions(pool, &missing, span, "a cyclic"));
        if !errors.is_empty() {
            return Err(errors);
        }

        let mut at = |pool: &mut Pool, e: ExprId| {
            let e = pool.subst(e, &map);
            pool.simplify(e)
        };
        let parts = Equations {
            mass: &self.mass_matrix,
            forcing: &self.forcing,
            multipliers: &self.multipliers,
            coords: &self.coords,
            rates: &self.rates,
        };
        let (mass, damping, stiffness, residual) = parts.at_reference(pool, &cyclic, &mut at);
        let residual_is_zero =
            self.multipliers.is_empty() && residual.iter().all(|r| pool.is_identically_zero(*r));
        let constraints: Vec<LinearConstraint> = self
            .multipliers
            .iter()
            .map(|m| LinearConstraint {
                constraint: m.constraint,
                kind: m.kind,
                lambda: m.lambda,
                jacobian: m.jacobian.iter().map(|e| at(pool, *e)).collect(),
                phi: at(pool, m.phi),
                bias: at(pool, m.bias),
                rate_row: None,
                positions: Vec::new(),
            })
            .collect();

        let time = self.model.time;
        refuse_time_dependence_of(
            pool,
            [&mass, &damping, &stiffness],
            &residual,
            &constraints,
            time,
            span,
        )?;

        Ok(Linearization {
            coords: self.coords.clone(),
            cyclic,
            positions,
            rates,
            mass,
            damping,
            stiffness,
            residual,
            residual_is_zero,
            constraints,
            independent: None,
            kept: None,
            span,
        })
    }

    /// Whether a coordinate appears in neither M nor f nor any kept constraint: only its rate
    /// matters, and a steady motion may move it. An expression left unsimplified for its size
    /// may still hold the coordinate where the algebra would cancel it (a wheel's spin in
    /// sin² + cos²): there a derivative that is zero at generic points counts as absent.
    fn is_cyclic(&mut self, q: SymId) -> bool {
        let pool = &mut self.model.pool;
        let mut exprs: Vec<ExprId> = self.mass_matrix.iter().flatten().copied().collect();
        exprs.extend(&self.forcing);
        exprs.extend(self.multipliers.iter().map(|m| m.phi));
        !exprs.iter().any(|e| {
            pool.depends_on(*e, q) && {
                let d = pool.diff(*e, q);
                !pool.vanishes_at_generic_points(d)
            }
        })
    }
}

/// The equations in the independent rates about a reference (Maggi's form, linearized), for a
/// scene with velocity constraints kept: the state is the positions kept and the independent
/// rates, δp and δu, with
///
/// M̃·δu̇ + C̃·δu + K̃·δp = 0 (the `Linearization`'s `mass`, `damping`, `stiffness`) and
/// δṗ = G·(δp, δu) (the kinematics: ṗ = u for an independent rate, the dependent rate's
/// expression for a dependent one).
#[derive(Clone, Debug)]
pub struct RatesLinearization {
    /// The independent rates u, in the coordinates' order.
    pub rates: Vec<SymId>,
    /// The coordinates (indices into `coords`) whose positions stay in the state: those the
    /// equations in the independent rates depend on, and those the rates of these depend on,
    /// in the coordinates' order. The others are ignorable (cyclic).
    pub kept: Vec<usize>,
    /// G: one row per position kept; columns the positions kept, then the independent rates.
    pub kinematics: Vec<Vec<ExprId>>,
    /// Each dependent rate and its expression in the positions and the independent rates.
    pub dependent: Vec<(SymId, ExprId)>,
    /// What each entry of the `Linearization`'s `residual` stands for: the acceleration of
    /// each independent rate (the residual is that equation's M̃·u̇ + h at u̇ = 0, h), then the
    /// rate of each dependent position kept (which must vanish for the reference to stay).
    pub residual_symbols: Vec<SymId>,
}

/// The reference's items, by coordinate and whether a rate, in the order written.
type Items = [((SymId, bool), (ExprId, Span))];

impl Derivation {
    /// Linearizes in the independent rates: see [`RatesLinearization`].
    fn linearize_in_rates(
        &mut self,
        span: Span,
        items: &Items,
    ) -> Result<Linearization, Vec<Diagnostic>> {
        if let Some(m) = self.multipliers.iter().find(|m| m.kind == ConstraintKind::Position) {
            let c = &self.model.constraints[m.constraint];
            return Err(vec![Diagnostic::error(
                c.span,
                format!(
                    "`{}` is a position constraint kept beside velocity constraints, which \
                     linearize does not handle yet",
                    c.name
                ),
            )
            .with_label("a position constraint kept with a multiplier")
            .with_related(span, "linearized here")
            .with_hint(
                "linearize handles velocity constraints when every kept constraint restrains \
                 velocities, or position constraints alone",
            )]);
        }
        let Some(form) = self.independent_form() else {
            let c = self
                .multipliers
                .iter()
                .find(|m| self.model.constraints[m.constraint].force_requested)
                .or(self.multipliers.first())
                .map(|m| &self.model.constraints[m.constraint]);
            let (at, name) = c.map_or((span, String::new()), |c| (c.span, c.name.clone()));
            return Err(vec![Diagnostic::error(
                at,
                "the equations in the independent rates could not be formed, which linearizing \
                 with velocity constraints needs",
            )
            .with_label(format!("`{name}` is kept with a multiplier"))
            .with_related(span, "linearized here")
            .with_hint(
                "the dependent rates must solve exactly (at most four kept constraints), and no \
                 `show` or `expect` line may ask for a kept constraint's reaction",
            )]);
        };
        let n = self.coords.len();
        let pool = &mut self.model.pool;
        let accels: Vec<SymId> = form
            .independent
            .iter()
            .map(|u| pool.rate(*u).expect("a rate has an acceleration"))
            .collect();
        // ṗ of each coordinate: u itself, or the dependent rate's expression.
        let kinematic: Vec<ExprId> = (0..n)
            .map(|i| {
                let r = self.rates[i];
                match form.dependent.iter().find(|(d, _)| *d == r) {
                    Some((_, e)) => *e,
                    None => pool.sym(r),
                }
            })
            .collect();
        let is_dependent: Vec<bool> =
            (0..n).map(|i| form.dependent.iter().any(|(d, _)| *d == self.rates[i])).collect();

        // The positions kept: those the equations depend on, and, in turn, those the rates of
        // kept positions depend on.
        let mut kept: Vec<bool> = (0..n)
            .map(|i| form.equations.iter().any(|e| pool.depends_on(*e, self.coords[i])))
            .collect();
        loop {
            let mut grew = false;
            for i in 0..n {
                if !kept[i] {
                    continue;
                }
                for (j, q) in self.coords.iter().enumerate() {
                    if !kept[j] && pool.depends_on(kinematic[i], *q) {
                        kept[j] = true;
                        grew = true;
                    }
                }
            }
            if !grew {
                break;
            }
        }
        let cyclic: Vec<bool> = kept.iter().map(|k| !k).collect();

        let mut errors = Vec::new();
        let mut positions = vec![None; n];
        let mut given_rates: Vec<Option<ExprId>> = vec![None; n];
        let mut map: HashMap<SymId, ExprId> = HashMap::new();
        for ((coord, rate), (value, item_span)) in items {
            let Some(i) = self.coords.iter().position(|q| q == coord) else { continue };
            let name = pool.symbol_text(*coord, cas::Style::Unicode);
            if !*rate {
                positions[i] = Some(*value);
                map.insert(*coord, *value);
            } else if is_dependent[i] {
                errors.push(
                    Diagnostic::error(
                        *item_span,
                        format!("the rate of `{name}` follows from the velocity constraints"),
                    )
                    .with_label("a dependent rate")
                    .with_hint(
                        "leave it out: give the independent rates, and the constraints give \
                         this one",
                    ),
                );
            } else {
                given_rates[i] = Some(*value);
                map.insert(self.rates[i], *value);
                if kept[i] && !pool.is_zero(*value) {
                    errors.push(
                        Diagnostic::error(
                            *item_span,
                            format!("a reference that moves `{name}` does not stay put"),
                        )
                        .with_label(format!(
                            "{name} is not ignorable: the equations in the independent rates \
                             depend on it"
                        ))
                        .with_hint(
                            "a steady motion may move only ignorable coordinates (those in \
                             neither the equations in the independent rates nor the rates of \
                             the positions they need); give this one a position and rate 0",
                        ),
                    );
                }
            }
        }
        for u in &form.independent {
            map.entry(*u).or_insert(pool.zero());
        }
        for a in &accels {
            map.insert(*a, pool.zero());
        }
        let missing: Vec<SymId> =
            (0..n).filter(|&i| kept[i] && positions[i].is_none()).map(|i| self.coords[i]).collect();
        errors.extend(missing_positions(pool, &missing, span, "an ignorable"));
        if !errors.is_empty() {
            return Err(errors);
        }

        let at = |pool: &mut Pool, e: ExprId| {
            let e = pool.subst(e, &map);
            pool.simplify(e)
        };
        let zero_accels: HashMap<SymId, ExprId> =
            accels.iter().map(|a| (*a, pool.zero())).collect();
        let kept_index: Vec<usize> = (0..n).filter(|&i| kept[i]).collect();
        let (mut mass, mut damping, mut stiffness, mut residual) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for e in &form.equations {
            let h = pool.subst(*e, &zero_accels);
            let mut m = Vec::new();
            for a in &accels {
                let d = pool.diff(*e, *a);
                m.push(at(pool, d));
            }
            let mut c = Vec::new();
            for u in &form.independent {
                let d = pool.diff(h, *u);
                c.push(at(pool, d));
            }
            let mut k = Vec::new();
            for &i in &kept_index {
                let d = pool.diff(h, self.coords[i]);
                k.push(at(pool, d));
            }
            mass.push(m);
            damping.push(c);
            stiffness.push(k);
            residual.push(at(pool, h));
        }
        let mut residual_symbols = accels.clone();
        let mut kinematics = Vec::new();
        for &i in &kept_index {
            let mut row = Vec::new();
            for &j in &kept_index {
                let d = pool.diff(kinematic[i], self.coords[j]);
                row.push(at(pool, d));
            }
            for u in &form.independent {
                let d = pool.diff(kinematic[i], *u);
                row.push(at(pool, d));
            }
            kinematics.push(row);
            if is_dependent[i] {
                residual.push(at(pool, kinematic[i]));
                residual_symbols.push(self.rates[i]);
            }
        }
        let rates: Vec<ExprId> = (0..n)
            .map(|i| {
                if is_dependent[i] {
                    at(pool, kinematic[i])
                } else {
                    given_rates[i].unwrap_or(pool.zero())
                }
            })
            .collect();
        let residual_is_zero = residual.iter().all(|r| pool.is_identically_zero(*r));

        let time = self.model.time;
        let mut all: Vec<ExprId> = mass
            .iter()
            .chain(&damping)
            .chain(&stiffness)
            .chain(&kinematics)
            .flatten()
            .copied()
            .collect();
        all.extend(&residual);
        refuse_time_dependence(pool, &all, time, span)?;

        Ok(Linearization {
            coords: self.coords.clone(),
            cyclic,
            positions,
            rates,
            mass,
            damping,
            stiffness,
            residual,
            residual_is_zero,
            constraints: Vec::new(),
            kept: None,
            independent: Some(RatesLinearization {
                rates: form.independent.clone(),
                kept: kept_index,
                kinematics,
                dependent: form.dependent.clone(),
                residual_symbols,
            }),
            span,
        })
    }
}

impl Derivation {
    /// Linearizes with position and velocity constraints kept together: see
    /// [`KeptLinearization`]. M, C and K are those of all the coordinates, K with the
    /// multipliers' symbols as in the holonomic case; each constraint adds its rows.
    fn linearize_kept(
        &mut self,
        span: Span,
        items: &Items,
    ) -> Result<Linearization, Vec<Diagnostic>> {
        let n = self.coords.len();
        let rows = self.velocity_rows();
        let Some(dependent_rates) = self.dependent_rates(&rows) else {
            return Err(vec![Diagnostic::error(
                span,
                "the kept constraints' rows do not each restrain a rate of their own here",
            )
            .with_label("no dependent rate for every constraint")
            .with_hint("leave one rate per kept constraint without a value at the start")]);
        };
        let dependent: Vec<usize> =
            dependent_rates.iter().filter_map(|r| self.rates.iter().position(|x| x == r)).collect();
        let cyclic: Vec<bool> = (0..n).map(|i| self.is_cyclic(self.coords[i])).collect();
        let pool = &mut self.model.pool;
        let mut errors = Vec::new();
        let mut positions = vec![None; n];
        let mut map: HashMap<SymId, ExprId> = HashMap::new();
        for ((coord, rate), (value, item_span)) in items {
            let Some(i) = self.coords.iter().position(|q| q == coord) else { continue };
            let name = pool.symbol_text(*coord, cas::Style::Unicode);
            if !*rate {
                positions[i] = Some(*value);
                map.insert(*coord, *value);
            } else if dependent.contains(&i) {
                errors.push(
                    Diagnostic::error(
                        *item_span,
                        format!("the rate of `{name}` follows from the kept constraints"),
                    )
                    .with_label("a dependent rate")
                    .with_hint(
                        "leave it out: give the independent rates, and the constraints give                          this one",
                    ),
                );
            } else {
                map.insert(self.rates[i], *value);
                if !cyclic[i] && !pool.is_zero(*value) {
                    errors.push(
                        Diagnostic::error(
                            *item_span,
                            format!("a reference that moves `{name}` does not stay put"),
                        )
                        .with_label(format!("{name} is not cyclic: M, f or a constraint depends on it"))
                        .with_hint(
                            "a steady motion may move only cyclic coordinates; give this one a                              position and rate 0",
                        ),
                    );
                }
            }
        }
        for (i, is_cyclic) in cyclic.iter().enumerate() {
            if !dependent.contains(&i) {
                map.entry(self.rates[i]).or_insert(pool.zero());
            }
            // A cyclic coordinate left in an expression too large to simplify does not change
            // its value (`is_cyclic`): any position stands for all.
            if *is_cyclic {
                map.entry(self.coords[i]).or_insert(pool.zero());
            }
        }
        let missing: Vec<SymId> = (0..n)
            .filter(|&i| !cyclic[i] && positions[i].is_none())
            .map(|i| self.coords[i])
            .collect();
        errors.extend(missing_positions(pool, &missing, span, "a cyclic"));
        if !errors.is_empty() {
            return Err(errors);
        }

        // One memo for every substitution: the derivatives share most of their parts.
        let mut memo = HashMap::new();
        let mut at = |pool: &mut Pool, e: ExprId| {
            let e = pool.subst_memo(e, &map, &mut memo);
            pool.simplify(e)
        };
        let parts = Equations {
            mass: &self.mass_matrix,
            forcing: &self.forcing,
            multipliers: &self.multipliers,
            coords: &self.coords,
            rates: &self.rates,
        };
        let (mass, damping, stiffness, residual) = parts.at_reference(pool, &cyclic, &mut at);
        // The dependent rates at 0 in the rows that solve for them.
        let zero_dependent: HashMap<SymId, ExprId> =
            dependent.iter().map(|&i| (self.rates[i], pool.zero())).collect();
        let mut constraints = Vec::new();
        for (m, row) in self.multipliers.iter().zip(&rows) {
            let rate_row = at(pool, *row);
            let rate_row = pool.subst(rate_row, &zero_dependent);
            let positions = match m.kind {
                ConstraintKind::Velocity => (0..n)
                    .map(|i| {
                        if cyclic[i] {
                            pool.zero()
                        } else {
                            let d = pool.diff(m.phi, self.coords[i]);
                            at(pool, d)
                        }
                    })
                    .collect(),
                ConstraintKind::Position => Vec::new(),
            };
            let phi = at(pool, m.phi);
            let phi = match m.kind {
                ConstraintKind::Velocity => pool.subst(phi, &zero_dependent),
                ConstraintKind::Position => phi,
            };
            constraints.push(LinearConstraint {
                constraint: m.constraint,
                kind: m.kind,
                lambda: m.lambda,
                jacobian: m.jacobian.iter().map(|e| at(pool, *e)).collect(),
                phi,
                bias: at(pool, m.bias),
                rate_row: Some(rate_row),
                positions,
            });
        }
        let rates: Vec<ExprId> = (0..n)
            .map(|i| map.get(&self.rates[i]).copied().unwrap_or_else(|| pool.sym(self.rates[i])))
            .collect();

        let time = self.model.time;
        refuse_time_dependence_of(
            pool,
            [&mass, &damping, &stiffness],
            &residual,
            &constraints,
            time,
            span,
        )?;

        Ok(Linearization {
            coords: self.coords.clone(),
            cyclic,
            positions,
            rates,
            mass,
            damping,
            stiffness,
            residual,
            residual_is_zero: false,
            constraints,
            independent: None,
            kept: Some(KeptLinearization { dependent }),
            span,
        })
    }
}

/// The equations of motion with their kept constraints, as the holonomic and the kept paths
/// linearize them.
struct Equations<'a> {
    mass: &'a [Vec<ExprId>],
    forcing: &'a [ExprId],
    multipliers: &'a [crate::derive::Multiplier],
    coords: &'a [SymId],
    rates: &'a [SymId],
}

/// M, C, K and the residual at a reference.
type AtReference = (Vec<Vec<ExprId>>, Vec<Vec<ExprId>>, Vec<Vec<ExprId>>, Vec<ExprId>);

impl Equations<'_> {
    /// With g = f + Jᵀλ (λ the multipliers' symbols): M, C = −∂f/∂q̇ (J has no rates, for a
    /// velocity constraint either: it is linear in them), K = −∂g/∂q (zero for a cyclic
    /// coordinate), and g, each put through `at` (the reference substituted).
    fn at_reference(
        &self,
        pool: &mut Pool,
        cyclic: &[bool],
        at: &mut dyn FnMut(&mut Pool, ExprId) -> ExprId,
    ) -> AtReference {
        let mut generalized = self.forcing.to_vec();
        for m in self.multipliers {
            let lambda = pool.sym(m.lambda);
            for (j, g) in generalized.iter_mut().enumerate() {
                let force = pool.mul2(m.jacobian[j], lambda);
                *g = pool.add2(*g, force);
            }
        }
        let (mut mass, mut damping, mut stiffness) = (Vec::new(), Vec::new(), Vec::new());
        for (j, g) in generalized.iter().enumerate() {
            let (mut m, mut c, mut k) = (Vec::new(), Vec::new(), Vec::new());
            for (i, is_cyclic) in cyclic.iter().enumerate() {
                m.push(at(pool, self.mass[j][i]));
                let df = pool.diff(self.forcing[j], self.rates[i]);
                let df = at(pool, df);
                c.push(pool.neg(df));
                k.push(if *is_cyclic {
                    pool.zero()
                } else {
                    let dg = pool.diff(*g, self.coords[i]);
                    let dg = at(pool, dg);
                    pool.neg(dg)
                });
            }
            mass.push(m);
            damping.push(c);
            stiffness.push(k);
        }
        let residual: Vec<ExprId> = generalized.iter().map(|g| at(pool, *g)).collect();
        (mass, damping, stiffness, residual)
    }
}

/// A reference is a fixed point of autonomous equations; a drive or a schedule that is still
/// there makes the small motions those of a time-varying system: refused.
fn refuse_time_dependence_of(
    pool: &mut Pool,
    matrices: [&[Vec<ExprId>]; 3],
    residual: &[ExprId],
    constraints: &[LinearConstraint],
    time: SymId,
    span: Span,
) -> Result<(), Vec<Diagnostic>> {
    let mut all: Vec<ExprId> = matrices.iter().flat_map(|m| m.iter().flatten()).copied().collect();
    all.extend(residual);
    for c in constraints {
        all.extend(&c.jacobian);
        all.extend(&c.positions);
        all.extend([c.phi, c.bias]);
    }
    refuse_time_dependence(pool, &all, time, span)
}

/// The reference names no position for these coordinates (`what` says which kind of
/// coordinate may go without one: "a cyclic", "an ignorable").
fn missing_positions(pool: &Pool, missing: &[SymId], span: Span, what: &str) -> Option<Diagnostic> {
    let first = missing.first()?;
    let names: Vec<String> =
        missing.iter().map(|q| format!("`{}`", pool.symbol(*q).name)).collect();
    let (them, it) = if missing.len() == 1 { ("", "it") } else { ("s", "them") };
    Some(
        Diagnostic::error(
            span,
            format!("the reference gives no position for {}", names.join(", ")),
        )
        .with_label(format!("position{them} missing here"))
        .with_hint(format!(
            "add {it} to the line (`{} = …`); rates default to 0, and {what} coordinate \
                 needs no position",
            pool.symbol(*first).name
        )),
    )
}

/// A reference whose linearized equations still change with t is no equilibrium or steady
/// motion: refused, naming the reference.
fn refuse_time_dependence(
    pool: &mut Pool,
    exprs: &[ExprId],
    time: SymId,
    span: Span,
) -> Result<(), Vec<Diagnostic>> {
    let timed = exprs.iter().any(|e| {
        pool.depends_on(*e, time) && {
            let d = pool.diff(*e, time);
            !pool.is_identically_zero(d)
        }
    });
    if !timed {
        return Ok(());
    }
    Err(vec![Diagnostic::error(span, "the equations depend on time at this reference")
        .with_label("the linearized equations would change with t")
        .with_hint(
            "a reference needs equations that do not change with time: no drive or schedule \
             written with `t` may act there",
        )])
}

#[cfg(test)]
mod tests {
    use crate::derive::testing::{ascii, derived};

    /// A matrix as text, row by row.
    type Text = Vec<Vec<String>>;

    /// M, C and K of a scene about its reference.
    fn matrices(source: &str) -> (Text, Text, Text) {
        let mut d = derived(source);
        let lin = d.linearize().expect("linearizes");
        let pool = d.pool();
        let text = |m: &[Vec<cas::ExprId>]| -> Text {
            m.iter().map(|r| r.iter().map(|e| ascii(pool, *e)).collect()).collect()
        };
        (text(&lin.mass), text(&lin.damping), text(&lin.stiffness))
    }

    const PENDULUM: &str = "
param m, L, g
coord theta
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
";

    #[test]
    fn the_pendulum_hangs_stably_and_stands_unstably() {
        let (m, c, k) = matrices(&format!("{PENDULUM}linearize about theta = 0"));
        assert_eq!(
            (m, c, k),
            (vec![vec!["m*L^2".to_string()]], vec![vec!["0".into()]], vec![vec!["m*L*g".into()]])
        );
        let (_, _, k) = matrices(&format!("{PENDULUM}linearize about theta = pi"));
        assert_eq!(k, [["-m*L*g"]]);
    }

    #[test]
    fn a_cart_is_cyclic_and_needs_no_position() {
        let source = "
param M, m, L, g
coord x, theta
particle cart { mass M; position (x, 0) }
particle bob { mass m; position (x + L*sin(theta), -L*cos(theta)) }
gravity g
linearize about theta = 0
";
        let mut d = derived(source);
        let lin = d.linearize().expect("linearizes");
        assert_eq!(lin.cyclic, [true, false]);
        assert!(lin.residual_is_zero);
        let (m, _, k) = matrices(source);
        assert_eq!(m, [["M + m", "m*L"], ["m*L", "m*L^2"]]);
        assert_eq!(k, [["0", "0"], ["0", "m*L*g"]]);
    }

    #[test]
    fn a_reference_names_every_position_and_moves_only_cyclic_coordinates() {
        let source = "
param m, L, g, w
coord theta, phi
particle bob { mass m; position (L*sin(theta)*cos(phi), L*sin(theta)*sin(phi), -L*cos(theta)) }
gravity g
";
        let mut d = derived(&format!("{source}linearize about phi' = w"));
        let errors = d.linearize().expect_err("θ has no position");
        assert!(errors[0].message.contains("no position for `theta`"), "{errors:?}");
        let mut d = derived(&format!("{source}linearize about theta = 0, theta' = w"));
        let errors = d.linearize().expect_err("θ moves");
        assert!(errors[0].message.contains("does not stay put"), "{errors:?}");
    }

    #[test]
    fn a_drive_in_time_has_no_reference() {
        let source = "
param m, k, F, w
coord x
particle p { mass m; position (x, 0) }
potential k/2*x^2
force push on p: (F*cos(w*t), 0)
linearize about x = 0
";
        let errors = derived(source).linearize().expect_err("driven");
        assert!(errors[0].message.contains("depend on time"), "{errors:?}");
    }
}
