//! Constraints kept with multipliers as they are: the equations of motion as the
//! differential–algebraic system of index 3 (index 2 when only velocities are constrained)
//! that an implicit method integrates with no stabilisation.

use crate::mechanical::{Layout, Mechanical, Stabilisation};
use crate::{Components, FaultKind, ModeEvent, NonFiniteAt, Problem};

/// y = (q, v, a, λ) with
///
/// ```text
///        q' = v
///        v' = a
///        0  = M(q)·a − f(q, v) − J(q)ᵀ·λ
///        0  = Φ(q)          for each kept position constraint
///        0  = A(q)·v + b    for each kept velocity constraint
/// ```
///
/// a mass matrix diag(I, I, 0, 0). An open contact's rows ([`Mechanical::with_contacts`]) are
/// 0 = λ instead, and its multipliers leave the residual; its modes jump as the stabilised
/// form's do, the accelerations and multipliers solved anew after each jump. The constraints hold at the position (or velocity) level
/// itself, so they do not drift as the second-derivative form J·a = γ lets them; q, v, a and λ
/// are indices 1, 2, 3, 3 (velocity constraints alone: 1, 1, 2, 2), which the method's error
/// control and Newton's iteration weigh by powers of the step.
#[derive(Clone)]
pub struct Constrained {
    inner: Mechanical,
}

impl Constrained {
    pub fn new(inner: Mechanical) -> Self {
        Constrained { inner }
    }

    /// The full state from (q, q̇) on the constraints: the accelerations and multipliers the
    /// augmented system [M −Jᵀ; J 0]·(a, λ) = (f, γ) gives there.
    pub fn consistent_state(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, FaultKind> {
        let solved = self.inner.unstabilised_accelerations(t, y)?;
        let mut state = y.to_vec();
        state.extend(solved);
        Ok(state)
    }

    /// The equations in their stabilised first-order form, to set their parameters.
    pub fn inner_mut(&mut self) -> &mut Mechanical {
        &mut self.inner
    }

    /// The equations in their stabilised first-order form.
    pub fn into_inner(self) -> Mechanical {
        self.inner
    }

    fn layout(&self) -> Layout {
        self.inner.layout
    }
}

impl Problem for Constrained {
    fn dim(&self) -> usize {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout();
        3 * n + m
    }

    fn rhs(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout();
        let (a, lambda) = (&y[2 * n..3 * n], &y[3 * n..]);
        out[..n].copy_from_slice(&y[n..2 * n]);
        out[n..2 * n].copy_from_slice(a);
        let kept = self.inner.kept().to_vec();
        let dynamics = self.inner.dynamics_at(t, &y[..2 * n])?;
        // M is stored by columns, then f, then per constraint its J row, γ, Φ and Φ̇.
        let rows = n * n + n;
        for i in 0..n {
            let mut r = -dynamics[n * n + i];
            for j in 0..n {
                r += dynamics[j * n + i] * a[j];
            }
            for (c, l) in lambda.iter().enumerate() {
                if kept[c] {
                    r -= dynamics[rows + c * (n + 3) + i] * l;
                }
            }
            out[2 * n + i] = r;
        }
        for c in 0..m {
            // Φ for a position constraint, A·q̇ + b for a velocity constraint; λ for an open
            // contact's row.
            out[3 * n + c] = if kept[c] { dynamics[rows + c * (n + 3) + n + 1] } else { lambda[c] };
        }
        // (q̇, q̈) = (v, a), then each coordinate's equation, then each constraint.
        crate::check_finite(out, |i| match i {
            i if i < 2 * n => crate::rate(i),
            i if i < 3 * n => NonFiniteAt::Residual { coordinate: i - 2 * n },
            i => NonFiniteAt::Constraint { constraint: i - 3 * n },
        })
    }

    fn components(&self) -> Components {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout();
        if self.inner.kinds().contains(&Stabilisation::Position) {
            Components { differential: 2 * n, by_index: [n, n, n + m] }
        } else {
            Components { differential: 2 * n, by_index: [2 * n, n + m, 0] }
        }
    }

    fn observations(&self) -> usize {
        self.inner.observations()
    }

    /// ∂F/∂y from the lowered partials: the rows q' = v and v' = a are identities, the
    /// residual's are (∂r/∂q, ∂r/∂v, M, −Jᵀ), and each constraint's are its Φ row's partials
    /// (J for a position constraint; ∂(A·v + b)/∂q and A for a velocity one).
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout();
        let d = 3 * n + m;
        jac.fill(0.0);
        for i in 0..n {
            jac[i * d + n + i] = 1.0;
            jac[(n + i) * d + 2 * n + i] = 1.0;
        }
        let kept = self.inner.kept().to_vec();
        let dynamics = self.inner.dynamics_at(t, &y[..2 * n])?;
        let rows = n * n + n;
        for i in 0..n {
            let row = (2 * n + i) * d;
            for j in 0..n {
                // M is stored by columns.
                jac[row + 2 * n + j] = dynamics[j * n + i];
            }
            for c in (0..m).filter(|&c| kept[c]) {
                jac[row + 3 * n + c] = -dynamics[rows + c * (n + 3) + i];
            }
        }
        // An open contact's row is 0 = λ.
        for c in (0..m).filter(|&c| !kept[c]) {
            jac[(3 * n + c) * d + 3 * n + c] = 1.0;
        }
        let Some(partials) = self.inner.partials_at(t, &y[..2 * n], &y[2 * n..])? else {
            return Ok(false);
        };
        // ∂(r, c, Φ, Φ̇)/∂(q, q̇), a row of 2n per value (see `Layout`).
        for i in 0..n {
            let row = (2 * n + i) * d;
            jac[row..row + 2 * n].copy_from_slice(&partials[i * 2 * n..(i + 1) * 2 * n]);
        }
        for c in (0..m).filter(|&c| kept[c]) {
            let row = (3 * n + c) * d;
            let phi = (n + m + c) * 2 * n;
            jac[row..row + 2 * n].copy_from_slice(&partials[phi..phi + 2 * n]);
        }
        Ok(true)
    }

    /// Records what the state's positions and velocities give, with the accelerations and
    /// multipliers solved from them rather than read from the state: as index-3 components,
    /// the state's own a and λ converge at a lower order than q and v (on the car axis at
    /// tolerance 1e-12, λ kept four digits where q kept ten), while the augmented system's
    /// solution at (q, v) is as accurate as they are.
    fn observe(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        let n = self.layout().coordinates;
        // The solve evaluates the dynamics at (t, q, v), whose constraint values the
        // observation reads; where the augmented system is singular the state's own a and λ
        // are all there is, and the dynamics are evaluated for the observation alone.
        let solved = match self.inner.unstabilised_accelerations(t, &y[..2 * n]) {
            Ok(solved) => solved,
            Err(_) => {
                self.inner.dynamics_at(t, &y[..2 * n])?;
                y[2 * n..].to_vec()
            }
        };
        self.inner.observe_given(t, &y[..2 * n], &solved, out);
        Ok(())
    }

    /// The augmented system's own diagnosis: a singular mass matrix, or the constraints'
    /// Jacobian that lost rank (and which constraints).
    fn explain_singular(&mut self, t: f64, y: &[f64]) -> Option<FaultKind> {
        let n = self.layout().coordinates;
        self.inner.unstabilised_accelerations(t, &y[..2 * n]).err()
    }

    fn next_sample(&self, t: f64) -> Option<f64> {
        self.inner.next_sample(t)
    }

    /// The accelerations and multipliers jump with the held values: solved anew at (q, q̇).
    fn sample(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        let n = self.layout().coordinates;
        self.inner.sample(t, &mut y[..2 * n])?;
        let solved = self.inner.unstabilised_accelerations(t, &y[..2 * n])?;
        y[2 * n..].copy_from_slice(&solved);
        Ok(())
    }

    /// The index-3 system holds Φ = 0 but not its derivative J·q̇ + ∂Φ/∂t = 0: the
    /// velocities' error across the constraints is what Radau IIA controls worst on it (of
    /// order 3 where the positions' is of order 5). Projecting q̇ onto the velocity level after
    /// each step removes it.
    fn project(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        if !self.inner.kinds().contains(&Stabilisation::Position) {
            return Ok(());
        }
        let n = self.layout().coordinates;
        self.inner.project_velocities(t, &mut y[..2 * n])
    }

    fn guards(&self) -> usize {
        self.inner.guards()
    }

    /// The stabilised form's guards, with the reactions as the constraints themselves give
    /// them (no stabilisation).
    fn guard_values(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        let n = self.layout().coordinates;
        self.inner.unstabilised(|inner| inner.guard_values(t, &y[..2 * n], out))
    }

    /// The stabilised form's start, then the accelerations and multipliers of the mode there.
    fn begin_modes(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let n = self.layout().coordinates;
        let events =
            self.inner.unstabilised(|inner| inner.begin_modes(t, &mut y[..2 * n], tolerance))?;
        let solved = self.inner.unstabilised_accelerations(t, &y[..2 * n])?;
        y[2 * n..].copy_from_slice(&solved);
        Ok(events)
    }

    /// The stabilised form's jump, then the accelerations and multipliers of the new mode.
    fn jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        fired: &[usize],
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let n = self.layout().coordinates;
        let events = self.inner.unstabilised(|inner| inner.jump(t, &mut y[..2 * n], fired))?;
        let solved = self.inner.unstabilised_accelerations(t, &y[..2 * n])?;
        y[2 * n..].copy_from_slice(&solved);
        Ok(events)
    }

    fn physical(&mut self, _t: f64, y: &[f64]) -> Vec<f64> {
        y[..2 * self.layout().coordinates].to_vec()
    }
}
