//! The equations of motion differentiated by the state, exactly: the source of every exact
//! Jacobian (the first-order system's, the augmented system's with kept multipliers, the
//! index-3 formulation's) and of the stiffness and damping of a linearization.
//!
//! The equations are taken in residual form with the accelerations and multipliers as symbols
//! of their own, r = M(q)·q̈ − Jᵀ(q)·λ − f(q, q̇) and, per kept constraint, c = J·q̈ − γ, so
//! that their partials in q and q̇ hold q̈ and λ fixed. A Jacobian in numbers then comes from
//! one solve with the matrix [M −Jᵀ; J 0] the accelerations already need: differentiating
//! r = 0, c = 0 along the state gives [M −Jᵀ; J 0]·∂(q̈, λ) = −∂(r, c). About a reference
//! where q̈ = 0, ∂r/∂q is K and ∂r/∂q̇ is C of M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ.

use cas::{ExprId, SymId};

use crate::derive::Derivation;

/// ∂/∂q and ∂/∂q̇ of one family of rows: `positions[i][k]` is ∂(row i)/∂q_k and
/// `rates[i][k]` is ∂(row i)/∂q̇_k, over the remaining coordinates in the derivation's order.
#[derive(Clone, Debug, Default)]
pub struct StatePartials {
    pub positions: Vec<Vec<ExprId>>,
    pub rates: Vec<Vec<ExprId>>,
}

/// The partials of the equations of motion in residual form, in the symbols of the
/// derivation: its coordinates, rates, accelerations (`Derivation::accels`, held fixed) and
/// multipliers (each `Multiplier::lambda`, held fixed).
#[derive(Clone, Debug)]
pub struct Partials {
    /// Of r = M·q̈ − Jᵀ·λ − f: n rows.
    pub residual: StatePartials,
    /// Of c = J·q̈ − γ, one row per kept constraint.
    pub constraint: StatePartials,
    /// Of Φ of each kept constraint ([`crate::ConstraintRows::phi`]: a velocity constraint's
    /// residual A·q̇ + b).
    pub phi: StatePartials,
    /// Of each kept constraint's [`crate::ConstraintRows::drift_rate`].
    pub drift_rate: StatePartials,
}

impl Derivation {
    /// −∂(f + Jᵀλ)/∂s of row `i`, λ the multipliers' symbols: the residual's partial with
    /// the accelerations at rest. It is K's entry (s a coordinate) and C's (s a rate) about a
    /// reference, where q̈ = 0, and, with the mass matrix's term, the residual's partial every
    /// exact Jacobian is made of: one derivative for both.
    pub fn force_partial(&mut self, i: usize, s: SymId) -> ExprId {
        let pool = &mut self.model.pool;
        let mut terms = Vec::with_capacity(self.multipliers.len() + 1);
        for m in &self.multipliers {
            let dj = pool.diff(m.rows.jacobian[i], s);
            let lambda = pool.sym(m.lambda);
            let term = pool.mul2(dj, lambda);
            terms.push(pool.neg(term));
        }
        let df = pool.diff(self.forcing[i], s);
        terms.push(pool.neg(df));
        pool.add(&terms)
    }

    /// The partials of the equations of motion in residual form (see [`Partials`]). Each
    /// entry is a sum of memoised derivatives of M, J, f, γ and Φ, so that lowering them
    /// beside those expressions shares what they have in common.
    pub fn partials(&mut self) -> Partials {
        let n = self.coords.len();
        let state: Vec<SymId> = self.coords.iter().chain(&self.rates).copied().collect();
        let rows = self.partials_by(&state);
        Partials {
            residual: split(rows.residual, n),
            constraint: split(rows.constraint, n),
            phi: split(rows.phi, n),
            drift_rate: split(rows.drift_rate, n),
        }
    }
}

/// The partials of the equations of motion in residual form by constants of the scene (the
/// parameter slots a run fills), q, q̇, q̈ and λ held: `rows[i][j]` is ∂(row i)/∂p_j. They
/// are what the state's sensitivities to the parameters are integrated from, as
/// [`Partials`] is what its sensitivities to the start are.
#[derive(Clone, Debug, Default)]
pub struct ParameterPartials {
    /// Of r = M·q̈ − Jᵀ·λ − f: n rows.
    pub residual: Vec<Vec<ExprId>>,
    /// Of c = J·q̈ − γ, one row per kept constraint.
    pub constraint: Vec<Vec<ExprId>>,
    /// Of Φ of each kept constraint (a velocity constraint's residual A·q̇ + b).
    pub phi: Vec<Vec<ExprId>>,
    /// Of each kept constraint's [`crate::ConstraintRows::drift_rate`].
    pub drift_rate: Vec<Vec<ExprId>>,
}

impl Derivation {
    /// The partials of the equations in residual form by each of `constants` (see
    /// [`ParameterPartials`]). A derived parameter is a symbol of its own here, as it is a
    /// slot of its own in numbers: the chain rule through it to the parameters it follows is
    /// the caller's, who knows which of them are set.
    pub fn parameter_partials(&mut self, constants: &[SymId]) -> ParameterPartials {
        self.partials_by(constants)
    }

    /// The partials of the equations in residual form by each symbol of `constants` (the
    /// state's, or the parameter slots), q̈ and λ held: the rows of [`Partials`] and
    /// [`ParameterPartials`] alike, built in one order so that both share what they have in
    /// common.
    fn partials_by(&mut self, constants: &[SymId]) -> ParameterPartials {
        let n = self.coords.len();
        let accels: Vec<ExprId> = self.accels.iter().map(|a| self.model.pool.sym(*a)).collect();
        let multipliers = self.multipliers.clone();
        let mut residual = Vec::with_capacity(n);
        for i in 0..n {
            let mut row = Vec::with_capacity(constants.len());
            for &p in constants {
                let at_rest = self.force_partial(i, p);
                let pool = &mut self.model.pool;
                let mut terms: Vec<ExprId> = self.mass_matrix[i]
                    .iter()
                    .zip(&accels)
                    .map(|(entry, accel)| {
                        let dm = pool.diff(*entry, p);
                        pool.mul2(dm, *accel)
                    })
                    .collect();
                terms.push(at_rest);
                row.push(pool.add(&terms));
            }
            residual.push(row);
        }
        let pool = &mut self.model.pool;
        let mut out = ParameterPartials { residual, ..Default::default() };
        for m in &multipliers {
            let drift = m.rows.drift_rate(pool);
            let row: Vec<ExprId> = constants
                .iter()
                .map(|&p| {
                    let mut terms: Vec<ExprId> = m
                        .rows
                        .jacobian
                        .iter()
                        .zip(&accels)
                        .map(|(entry, accel)| {
                            let dj = pool.diff(*entry, p);
                            pool.mul2(dj, *accel)
                        })
                        .collect();
                    let dgamma = pool.diff(m.rows.bias, p);
                    terms.push(pool.neg(dgamma));
                    pool.add(&terms)
                })
                .collect();
            out.constraint.push(row);
            out.phi.push(constants.iter().map(|&p| pool.diff(m.rows.phi(), p)).collect());
            out.drift_rate.push(constants.iter().map(|&p| pool.diff(drift, p)).collect());
        }
        out
    }
}

/// Rows over (q, q̇) split into their q and q̇ halves.
fn split(rows: Vec<Vec<ExprId>>, n: usize) -> StatePartials {
    let mut out = StatePartials::default();
    for mut row in rows {
        let rates = row.split_off(n);
        out.positions.push(row);
        out.rates.push(rates);
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::derive::testing::{ascii, derived};

    #[test]
    fn a_pendulum_stiffens_with_its_angle_and_a_damper_with_its_rate() {
        let mut d = derived(
            "param m, L, g, c
coord theta
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
dissipation c/2*theta'^2",
        );
        let p = d.partials();
        let pool = d.pool();
        // r = m·L²·θ̈ + m·g·L·sin θ + c·θ̇.
        assert_eq!(ascii(pool, p.residual.positions[0][0]), "m*L*g*cos(theta)");
        assert_eq!(ascii(pool, p.residual.rates[0][0]), "c");
        assert!(p.constraint.positions.is_empty() && p.phi.rates.is_empty());
    }

    #[test]
    fn a_kept_rod_adds_its_multiplier_and_its_rows() {
        let mut d = derived(
            "param m, L, g
coord x, y
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g",
        );
        let p = d.partials();
        let pool = d.pool();
        let text = |rows: &[Vec<cas::ExprId>]| -> Vec<Vec<String>> {
            rows.iter().map(|r| r.iter().map(|e| ascii(pool, *e)).collect()).collect()
        };
        // r = m·(ẍ, ÿ) − λ·(2x, 2y) − (0, −m·g); c = 2x·ẍ + 2y·ÿ + 2ẋ² + 2ẏ².
        assert_eq!(text(&p.residual.positions), [["-2*rod.force", "0"], ["0", "-2*rod.force"]]);
        assert_eq!(text(&p.residual.rates), [["0", "0"], ["0", "0"]]);
        assert_eq!(text(&p.constraint.positions), [["2*x''", "2*y''"]]);
        assert_eq!(text(&p.constraint.rates), [["4*x'", "4*y'"]]);
        assert_eq!(text(&p.phi.positions), [["2*x", "2*y"]]);
        assert_eq!(text(&p.drift_rate.rates), [["2*x", "2*y"]]);
    }

    #[test]
    fn a_rods_length_and_a_dampers_rate_enter_their_rows() {
        let mut d = derived(
            "param m, L, g, c
coord x, y
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
dissipation c/2*x'^2",
        );
        let constants: Vec<cas::SymId> = d.model.params.iter().map(|p| p.sym).collect();
        let p = d.parameter_partials(&constants);
        let pool = d.pool();
        let text = |rows: &[Vec<cas::ExprId>]| -> Vec<Vec<String>> {
            rows.iter().map(|r| r.iter().map(|e| ascii(pool, *e)).collect()).collect()
        };
        // r = m·(ẍ, ÿ) − λ·(2x, 2y) − (−c·ẋ, −m·g), by m, L, g and c.
        assert_eq!(text(&p.residual), [["x''", "0", "0", "x'"], ["y'' + g", "0", "m", "0"]]);
        // The rod's length is in Φ alone: J, γ and Φ̇ do not hold it.
        assert_eq!(text(&p.constraint), [["0", "0", "0", "0"]]);
        assert_eq!(text(&p.phi), [["0", "-2*L", "0", "0"]]);
        assert_eq!(text(&p.drift_rate), [["0", "0", "0", "0"]]);
    }
}
