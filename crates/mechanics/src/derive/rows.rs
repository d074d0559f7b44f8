//! What each kind of constraint means to a derivation, in one place: what elimination may
//! solve of it, the direction of its reaction, and, where it is kept, its rows at every level
//! with the way a run holds it against drift. Everything after this reads the rows
//! ([`ConstraintRows`]) rather than the kind, so that a new kind is a constructor here and an
//! arm in each of the matches on the kind: `ConstraintRows::of`, `restrains_positions`,
//! `eliminable` and `reaction_direction`.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId, SymbolKind};
use model::{Constraint, ConstraintKind, Model};

/// A kept constraint at every level, built once by the constructor of its kind.
///
/// Φ, the velocity row and the acceleration row J·q̈ = γ are all expressions in the remaining
/// coordinates; what is made of them later (the partials of [`crate::Partials`], ∂Φ/∂t for
/// the rate projection) is made of these fields by the methods below, so that no later stage
/// asks what kind of constraint it holds.
#[derive(Clone, Debug)]
pub struct ConstraintRows {
    /// Φ(q, t) of a constraint that restrains positions; `None` for one that restrains rates
    /// alone, whose lowest level is its velocity row.
    pub position: Option<ExprId>,
    /// The constraint at the velocity level, linear in the rates: Φ̇ = J·q̇ + ∂Φ/∂t of a
    /// position constraint, A·q̇ + b of a velocity constraint as written.
    pub velocity: ExprId,
    /// The coefficients of q̈ in the acceleration row, which are also those of q̇ in the
    /// velocity row: ∂Φ/∂q (∂Φ/∂q̇ for a velocity constraint).
    pub jacobian: Vec<ExprId>,
    /// γ = −(J̇·q̇ + ∂²Φ/∂t² + …): what J·q̈ must equal.
    pub bias: ExprId,
    /// How a run holds the constraint against drift.
    pub stabilisation: Stabilisation,
}

/// How a run keeps a constraint that only its acceleration row imposes from drifting: the
/// terms Baumgarte stabilisation adds to J·q̈ = γ, with rate α.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stabilisation {
    /// J·q̈ = γ − 2α·Φ̇ − α²·Φ: a position constraint drifts in Φ and in its rate.
    Position,
    /// J·q̈ = γ − α·(A·q̇ + b): a velocity constraint has no position level to drift at.
    Velocity,
}

impl ConstraintRows {
    /// The rows of a kept constraint of `kind` whose Φ, in the remaining coordinates, is
    /// `phi`. Simplified first, a row and its Jacobian print as a hand derivation writes them
    /// (a rolling coin's −r·cos ψ, not −r·sin²θ·cos ψ − r·cos ψ·cos²θ); past simplify's own
    /// size limit Φ stays as built. A row too large to print is kept as built too: multiplying
    /// it out loses what its parts share (a bicycle's front wheel rolling: 1,324 lowered
    /// operations as built, 6,367 expanded, its bias 7 times that).
    pub(super) fn of(
        pool: &mut Pool,
        kind: ConstraintKind,
        phi: ExprId,
        (coords, rates, accels): (&[SymId], &[SymId], &[SymId]),
    ) -> ConstraintRows {
        let phi = if pool.prints_in_full(phi) { pool.simplify(phi) } else { phi };
        match kind {
            // A contact, while closed, is a position constraint on its gap; its grip a velocity
            // row: what a run does with them while open is the run's (it drops their rows).
            ConstraintKind::Position | ConstraintKind::Contact => {
                ConstraintRows::of_positions(pool, phi, coords, accels)
            }
            ConstraintKind::Velocity | ConstraintKind::Grip => {
                ConstraintRows::of_rates(pool, phi, rates, accels)
            }
        }
    }

    /// Φ(q, t) = 0: differentiated twice for the acceleration row, stabilised on Φ and Φ̇.
    fn of_positions(
        pool: &mut Pool,
        phi: ExprId,
        coords: &[SymId],
        accels: &[SymId],
    ) -> ConstraintRows {
        let jacobian: Vec<ExprId> = coords.iter().map(|q| pool.diff(phi, *q)).collect();
        let velocity = pool.time_derivative(phi);
        let acceleration = pool.time_derivative(velocity);
        ConstraintRows {
            position: Some(phi),
            velocity,
            jacobian,
            bias: bias(pool, acceleration, accels),
            stabilisation: Stabilisation::Position,
        }
    }

    /// A(q, t)·q̇ + b(q, t) = 0: differentiated once, stabilised on itself.
    fn of_rates(pool: &mut Pool, phi: ExprId, rates: &[SymId], accels: &[SymId]) -> ConstraintRows {
        let jacobian: Vec<ExprId> = rates.iter().map(|v| pool.diff(phi, *v)).collect();
        let acceleration = pool.time_derivative(phi);
        ConstraintRows {
            position: None,
            velocity: phi,
            jacobian,
            bias: bias(pool, acceleration, accels),
            stabilisation: Stabilisation::Velocity,
        }
    }

    /// Φ at the constraint's lowest level, which a run keeps at zero and the stabilisation
    /// damps: Φ(q, t), or the velocity row where there is no position level.
    pub fn phi(&self) -> ExprId {
        self.position.unwrap_or(self.velocity)
    }

    /// The rate at which [`ConstraintRows::phi`] drifts, which a stabilisation damps beside it:
    /// Φ̇ where Φ is of positions; zero where Φ is a velocity row, a rate already.
    pub fn drift_rate(&self, pool: &Pool) -> ExprId {
        match self.position {
            Some(_) => self.velocity,
            None => pool.zero(),
        }
    }

    /// What the velocity row is with the rates at zero, so that it is J·q̇ plus this: ∂Φ/∂t
    /// (taken of Φ, which is smaller than Φ̇), or b of A·q̇ + b.
    pub fn rate_free(&self, pool: &mut Pool, time: SymId, rates: &[SymId]) -> ExprId {
        match self.position {
            Some(phi) => pool.diff(phi, time),
            None => {
                let still: HashMap<SymId, ExprId> =
                    rates.iter().map(|r| (*r, pool.zero())).collect();
                pool.subst(self.velocity, &still)
            }
        }
    }

    /// Each expression the rows hold, to be rewritten in place (an input's law put in place of
    /// its symbol).
    pub fn exprs_mut(&mut self) -> impl Iterator<Item = &mut ExprId> {
        self.jacobian
            .iter_mut()
            .chain([&mut self.bias])
            .chain(self.position.iter_mut())
            .chain([&mut self.velocity])
    }
}

/// γ of an acceleration row: what is left of it with the accelerations at zero, negated.
fn bias(pool: &mut Pool, acceleration: ExprId, accels: &[SymId]) -> ExprId {
    let zeros: HashMap<SymId, ExprId> = accels.iter().map(|a| (*a, pool.zero())).collect();
    let rest = pool.subst(acceleration, &zeros);
    pool.neg(rest)
}

/// Whether a constraint of `kind` restrains positions throughout a run, so that its time
/// derivative is a velocity row a velocity constraint may repeat. A contact restrains them
/// only while closed: a velocity constraint it would repeat is still needed while it is open.
pub(super) fn restrains_positions(kind: ConstraintKind) -> bool {
    match kind {
        ConstraintKind::Position => true,
        ConstraintKind::Velocity | ConstraintKind::Contact | ConstraintKind::Grip => false,
    }
}

/// Whether a kept constraint of `kind` may be left out as implied by the position constraints:
/// a velocity constraint may; a grip, which holds only while its contact is closed, may not.
pub(super) fn may_be_implied(kind: ConstraintKind) -> bool {
    matches!(kind, ConstraintKind::Velocity)
}

/// What elimination may solve for a coordinate: Φ(q, t) of a position constraint as written;
/// of a velocity constraint with constant coefficients the position constraint it integrates
/// to, marked as integrated (`true`); `None` for one that must be kept.
pub(super) fn eliminable(pool: &mut Pool, model: &Model, c: &Constraint) -> Option<(ExprId, bool)> {
    match c.kind {
        ConstraintKind::Position => Some((c.phi, false)),
        // A velocity constraint restrains rates only, unless it integrates to a position
        // constraint: with constant coefficients A·q̇ + b = 0 is A·(q − q₀) + b·t = 0.
        ConstraintKind::Velocity => integrate(pool, model, c.phi).map(|phi| (phi, true)),
        // A contact opens and closes: its coordinates stay free, and its rows are kept.
        ConstraintKind::Contact | ConstraintKind::Grip => None,
    }
}

/// The generalized force per unit multiplier of a constraint along coordinate q, in the
/// declared coordinates: ∂Φ/∂q for a position constraint, ∂Φ/∂q̇ for a velocity constraint
/// (the same direction, since ∂Φ̇/∂q̇ = ∂Φ/∂q).
pub(super) fn reaction_direction(pool: &mut Pool, c: &Constraint, q: SymId) -> ExprId {
    match c.kind {
        ConstraintKind::Position | ConstraintKind::Contact => pool.diff(c.phi, q),
        ConstraintKind::Velocity | ConstraintKind::Grip => {
            let rate = pool.rate(q).expect("coordinate");
            pool.diff(c.phi, rate)
        }
    }
}

/// The position constraint a velocity constraint A·q̇ + b = 0 integrates to when A and b are
/// constants (parameters only): A·(q − q₀) + b·t = 0, with q₀ the coordinates' initial values.
/// `None` for one whose coefficients move, which stays a velocity constraint.
fn integrate(pool: &mut Pool, model: &Model, phi: ExprId) -> Option<ExprId> {
    let mut terms = Vec::new();
    let mut rest = phi;
    for c in &model.coords {
        let rate = pool.rate(c.sym).expect("coordinate");
        let a = pool.diff(phi, rate);
        if pool.is_zero(a) {
            continue;
        }
        let constant = |pool: &mut Pool, e: ExprId| {
            pool.free_symbols(e).iter().all(|s| matches!(pool.symbol(*s).kind, SymbolKind::Param))
        };
        if !constant(pool, a) {
            return None;
        }
        let q = pool.sym(c.sym);
        let displacement = pool.sub(q, c.initial);
        terms.push(pool.mul2(a, displacement));
        let v = pool.sym(rate);
        let av = pool.mul2(a, v);
        rest = pool.sub(rest, av);
    }
    let rest = pool.simplify(rest);
    let b_constant =
        pool.free_symbols(rest).iter().all(|s| matches!(pool.symbol(*s).kind, SymbolKind::Param));
    if !b_constant {
        return None;
    }
    let t = pool.sym(model.time);
    terms.push(pool.mul2(rest, t));
    let sum = pool.add(&terms);
    Some(pool.simplify(sum))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{ascii, derived};

    /// A rod turning at a rate w in the plane: its Φ moves in time, so that its velocity row
    /// has a part without rates (∂Φ/∂t), and its drift rate is that row.
    #[test]
    fn a_moving_position_constraint_has_every_level() {
        let mut d = derived(
            "param m, w\ncoord x = 1\ncoord y = 0\nparticle p { mass m; position (x, y) }\nconstraint spin: x*sin(w*t) = y*cos(w*t)",
        );
        let (time, rates) = (d.model.time, d.rates.clone());
        let rows = d.multipliers[0].rows.clone();
        let pool = d.pool();
        assert_eq!(rows.position, Some(rows.phi()));
        assert_eq!(rows.drift_rate(pool), rows.velocity);
        assert_eq!(rows.stabilisation, super::Stabilisation::Position);
        let rate_free = rows.rate_free(pool, time, &rates);
        assert_eq!(ascii(pool, rate_free), "w*sin(w*t)*y + w*cos(w*t)*x");
    }

    /// A blade that cannot slide sideways restrains rates alone: its lowest level is its
    /// velocity row, which has nothing to drift at beside it.
    #[test]
    fn a_velocity_constraint_has_no_position_level() {
        let mut d = derived(
            "param m, I\ncoord x\ncoord y\ncoord theta\nbody blade { mass m; inertia I; position (x, y); angle theta }\nconstraint edge: y'*cos(theta) = x'*sin(theta)",
        );
        let (time, rates) = (d.model.time, d.rates.clone());
        let rows = d.multipliers[0].rows.clone();
        let pool = d.pool();
        assert_eq!((rows.position, rows.phi()), (None, rows.velocity));
        assert!(pool.is_zero(rows.drift_rate(pool)));
        assert_eq!(rows.stabilisation, super::Stabilisation::Velocity);
        let rate_free = rows.rate_free(pool, time, &rates);
        assert!(pool.is_zero(rate_free));
    }
}
