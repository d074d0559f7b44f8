//! What a `derive` report shows, computed once for every format: the equations, M and f, the
//! energies and reactions in their most readable exact form (factored when that is short),
//! the reactions with the accelerations solved for, the `show` values, those evaluated at the
//! start, and the start's state. Printing them is the front end's.

use cas::number::{One, Signed, Zero};
use cas::{ExprId, Pool, SymId};
use model::Value;

// The types a derive report is read from, for front ends that reach the core through `engine`.
pub use mechanics::{Derivation, Equation, IndependentForm, Multiplier};
pub use verify::{parameter_values, NumericValue, ShownAtStart};

/// Everything `derive` prints, computed once and shared by the formats.
pub struct Derived {
    pub equations: Vec<Equation>,
    pub mass_matrix: Vec<Vec<ExprId>>,
    pub forcing: Vec<ExprId>,
    pub kinetic: ExprId,
    pub potential: ExprId,
    pub lagrangian: Option<ExprId>,
    pub reactions: Vec<(SymId, ExprId)>,
    /// The reactions with accelerations solved for, where the system is small enough.
    pub reactions_of_state: Vec<(SymId, ExprId)>,
    pub shown: Vec<(model::Show, Value)>,
    pub at_start: ShownAtStart,
    pub start_state: Vec<(SymId, ExprId)>,
    /// The equations in the independent rates, where velocity constraints are kept and no
    /// contact force is asked for.
    pub independent: Option<mechanics::IndependentForm>,
    /// Each constraint's two sides as shown: as written, except a component of a vector
    /// constraint, which is its simplified Φ = 0 (the sum of a velocity and a cross product
    /// as written is pages long).
    pub constraint_sides: Vec<(ExprId, ExprId)>,
    /// Each contact as a report shows it, in the order written.
    pub contacts: Vec<DerivedContact>,
    /// Why each constraint that is neither eliminated nor kept was left out (a velocity
    /// constraint the position constraints already imply); `None` for the others.
    pub left_out: Vec<Option<String>>,
}

/// A contact as a report shows it: its gap, its law, its modes and its impact law.
pub struct DerivedContact {
    pub name: String,
    /// g(q, t) ≥ 0.
    pub gap: ExprId,
    pub restitution: ExprId,
    /// Coulomb's coefficient along its tangential rate, where it slips rather than grips.
    pub friction: Option<ExprId>,
    /// The tangential rate its grip holds at zero while it is closed.
    pub grip: Option<ExprId>,
    /// The condition it is watched under (`armed A`: while A > 0).
    pub armed: Option<ExprId>,
    /// In space, its second tangential rate, its reaction's symbol and its direction.
    pub cross: Option<(ExprId, SymId, Vec<ExprId>)>,
    /// Its reaction's symbol, and its grip's.
    pub force: SymId,
    pub grip_force: Option<SymId>,
    /// The generalized force per unit reaction, ∂g/∂q (and the grip's, ∂v/∂q̇), per remaining
    /// coordinate: what the reaction adds to the equations while the contact is closed.
    pub direction: Vec<ExprId>,
    pub grip_direction: Option<Vec<ExprId>>,
    /// The acceleration row it imposes while closed, J·q̈ = γ: J·q̈, and γ.
    pub acceleration: ExprId,
    pub bias: ExprId,
    pub closed_at_start: bool,
    /// Its impact law landing alone, where the system is small enough to solve exactly.
    pub impact: Option<mechanics::ImpactLaw>,
}

/// Each contact of a derivation as a report shows it.
fn contacts(d: &mut Derivation) -> Vec<DerivedContact> {
    let mut out = Vec::new();
    for k in 0..d.contacts.len() {
        let rows = d.contacts[k].clone();
        let contact = d.model.contacts[rows.contact].clone();
        let impact = d.impact_law(k);
        let pool = &mut d.model.pool;
        // Λ = −(1 + e)·m·ẏ reads better than its expansion.
        let impact = impact.map(|mut law| {
            law.impulse = compact(pool, law.impulse);
            law.tangential_impulse = law.tangential_impulse.map(|t| compact(pool, t));
            law.cross_impulse = law.cross_impulse.map(|t| compact(pool, t));
            law
        });
        let gap = pool.simplify(rows.normal.rows.phi());
        let grip = rows.grip.as_ref().map(|g| pool.simplify(g.rows.velocity));
        let cross = rows
            .cross
            .as_ref()
            .map(|g| (pool.simplify(g.rows.velocity), g.lambda, g.rows.jacobian.clone()));
        let bias = pool.simplify(rows.normal.rows.bias);
        let terms: Vec<ExprId> = rows
            .normal
            .rows
            .jacobian
            .iter()
            .zip(&d.accels)
            .map(|(j, a)| {
                let a = pool.sym(*a);
                pool.mul2(*j, a)
            })
            .collect();
        let acceleration = pool.add(&terms);
        out.push(DerivedContact {
            name: contact.name,
            gap,
            restitution: contact.restitution,
            friction: contact.friction,
            grip,
            armed: contact.armed,
            cross,
            force: rows.normal.lambda,
            grip_force: rows.grip.as_ref().map(|g| g.lambda),
            direction: rows.normal.rows.jacobian.clone(),
            grip_direction: rows.grip.as_ref().map(|g| g.rows.jacobian.clone()),
            acceleration,
            bias,
            closed_at_start: rows.closed_at_start,
            impact,
        });
    }
    out
}

/// The forms of a derivation that a report shows.
pub fn collect(d: &mut Derivation) -> Derived {
    let contacts = contacts(d);
    let equations = d.equations();
    let independent = d.independent_form();
    let constraint_sides = d
        .model
        .constraints
        .clone()
        .iter()
        .map(|c| match c.name.contains('.') {
            true => {
                // As the derivation keeps it: one too large to print is left as built.
                let pool = &mut d.model.pool;
                let phi = if pool.prints_in_full(c.phi) { pool.simplify(c.phi) } else { c.phi };
                (phi, pool.zero())
            }
            false => (c.lhs, c.rhs),
        })
        .collect();
    let left_out = d
        .model
        .constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let handled = d.eliminated.iter().any(|e| e.constraint == i)
                || d.multipliers.iter().any(|m| m.constraint == i);
            // The warning that left it out says why, under its caret; the report repeats that
            // where the constraint is listed.
            let warned = format!("`{}` restrains nothing more", c.name);
            let why = d.warnings.iter().find(|w| w.message.starts_with(&warned));
            (!handled).then(|| {
                why.map(|w| w.label.clone())
                    .filter(|l| !l.is_empty())
                    .unwrap_or_else(|| "the other constraints imply it".into())
            })
        })
        .collect();
    let pool = &mut d.model.pool;
    let mass_matrix = d
        .mass_matrix
        .iter()
        .map(|r| {
            r.iter()
                .map(|e| match pool.prints_in_full(*e) {
                    true => {
                        let f = pool.factor_content(*e);
                        gathered(pool, f)
                    }
                    false => *e,
                })
                .collect()
        })
        .collect();
    let forcing = d
        .forcing
        .iter()
        .map(|e| match pool.prints_in_full(*e) {
            true => {
                let s = pool.simplify(*e);
                gathered(pool, s)
            }
            false => *e,
        })
        .collect();
    let kinetic = readable(pool, d.kinetic);
    let potential = readable(pool, d.potential);
    let lagrangian = (!d.model.lagrangians.is_empty()).then(|| pool.simplify(d.lagrangian));
    let reactions = d.reactions.iter().map(|r| (r.symbol, compact(pool, r.expr))).collect();
    let reactions_of_state = d
        .reactions
        .clone()
        .into_iter()
        .map(|r| {
            let e = d.of_state(r.expr);
            (r.symbol, compact(&mut d.model.pool, e))
        })
        .collect();
    let shown = d.shown();
    let at_start = verify::shown_at_start(d);
    let mut start_state = Vec::new();
    for c in d.model.coords.clone() {
        if d.coords.contains(&c.sym) {
            start_state.push((c.sym, c.initial));
        }
    }
    for c in d.model.coords.clone() {
        if d.coords.contains(&c.sym) {
            let r = d.model.pool.rate(c.sym).expect("coordinate");
            start_state.push((r, c.initial_rate));
        }
    }
    Derived {
        equations,
        mass_matrix,
        forcing,
        kinetic,
        potential,
        lagrangian,
        reactions,
        reactions_of_state,
        shown,
        at_start,
        start_state,
        independent,
        constraint_sides,
        contacts,
        left_out,
    }
}

/// An energy in its compact form, gathered; unless it is too large to print as built (a
/// bicycle's T), which no example's simplifying brings back under the limit.
fn readable(pool: &mut Pool, e: ExprId) -> ExprId {
    if !pool.prints_in_full(e) {
        return e;
    }
    let c = compact(pool, e);
    gathered(pool, c)
}

/// A sum with its terms that move alike gathered under one coefficient of parameters.
fn gathered(pool: &mut Pool, e: ExprId) -> ExprId {
    let terms = pool.terms(e);
    if terms.len() < 2 {
        return e;
    }
    mechanics::collect_by_motion(pool, &terms)
}

/// The factored form when it is short (¾·m·(r + R)²·θ̇²), else the expanded one.
fn compact(pool: &mut Pool, e: ExprId) -> ExprId {
    let f = pool.factor_content(e);
    let (_, factors) = pool.factors(f);
    // A quotient by a sum stays one quotient; a sum in front stays factored when it is short.
    let quotient =
        factors.iter().any(|(b, x)| x.is_negative() && matches!(pool.node(*b), cas::Node::Add(..)));
    let short = quotient
        || factors.iter().all(|(b, x)| match pool.node(*b) {
            cas::Node::Add(c, terms) => terms.len() + usize::from(!c.is_zero()) <= 2 || !x.is_one(),
            _ => true,
        });
    if short {
        f
    } else {
        pool.simplify(e)
    }
}
