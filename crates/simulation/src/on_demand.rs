//! The exact Jacobian lowered when a method first asks for it: `auto` spends its explicit
//! steps without one, and most scenes never turn stiff, so the partials' derivation and
//! lowering (a noticeable share of a short run on a large scene) are paid only on a switch.

use numeric::Tape;
use sim::{Components, FaultKind, Mechanical, ModeEvent, Problem};

use engine::numbers::Prepared;
use engine::Error;

/// A [`Mechanical`] problem whose partials program is lowered from `prepared` on the first
/// call of [`Problem::jacobian`].
pub(crate) struct OnDemand<'a> {
    pub mechanical: Mechanical,
    prepared: &'a mut Prepared,
    /// Lowering was tried (and either gave the program or failed for good).
    tried: bool,
}

impl<'a> OnDemand<'a> {
    pub fn new(mechanical: Mechanical, prepared: &'a mut Prepared) -> Self {
        OnDemand { mechanical, prepared, tried: false }
    }
}

/// The partials program of a problem on (q, q̇), lowered from the derivation's partials the
/// first time and kept in `prepared` for the runs after.
pub(crate) fn lower_partials(prepared: &mut Prepared) -> Result<Tape, Error> {
    prepared.partials_program().map(Tape::new)
}

impl Problem for OnDemand<'_> {
    fn dim(&self) -> usize {
        self.mechanical.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        self.mechanical.rhs(t, y, dy)
    }
    fn observations(&self) -> usize {
        self.mechanical.observations()
    }
    fn observe(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        self.mechanical.observe(t, y, out)
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        if !self.tried {
            self.tried = true;
            // A program that does not lower leaves the method its differences.
            if let Ok(tape) = lower_partials(self.prepared) {
                self.mechanical.set_partials(tape);
            }
        }
        self.mechanical.jacobian(t, y, jac)
    }
    fn components(&self) -> Components {
        self.mechanical.components()
    }
    fn explain_singular(&mut self, t: f64, y: &[f64]) -> Option<FaultKind> {
        self.mechanical.explain_singular(t, y)
    }
    fn physical(&mut self, t: f64, y: &[f64]) -> Vec<f64> {
        self.mechanical.physical(t, y)
    }
    fn next_sample(&self, t: f64) -> Option<f64> {
        self.mechanical.next_sample(t)
    }
    fn sample(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        self.mechanical.sample(t, y)
    }
    // The contacts' modes: without these the trait's defaults (no guards) would run a scene
    // with contacts as if it had none, its bodies passing through each other.
    fn guards(&self) -> usize {
        self.mechanical.guards()
    }
    fn guard_values(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        self.mechanical.guard_values(t, y, out)
    }
    fn begin_modes(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        self.mechanical.begin_modes(t, y, tolerance)
    }
    fn jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        fired: &[usize],
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        self.mechanical.jump(t, y, fired)
    }
}
