//! The DOP853 tableau, for code that prints the integrator in another language.

use super::{DOP853_A, DOP853_BHH, DOP853_C, DOP853_E5, MAX_FACTOR, MIN_FACTOR, SAFETY};

/// The DOP853 pair as a foreign integrator needs it to step as [`Method::Dop853`] does: the
/// nodes, the stage rows, the eighth-order weights, the two error estimators, and the step
/// controller's constants. Code generation prints it, so an exported model steps with the same
/// method.
///
/// [`Method::Dop853`]: crate::Method::Dop853
pub struct Dop853Tableau {
    /// c of the twelve stages.
    pub c: &'static [f64],
    /// a of the twelve stages, row s with s entries.
    pub a: &'static [&'static [f64]],
    /// The eighth-order weights that propagate.
    pub b: &'static [f64],
    /// The third-order weights: the third-order estimate is (b − bhh)·K.
    pub bhh: &'static [f64],
    /// The fifth-order estimate's weights.
    pub e5: &'static [f64],
    pub safety: f64,
    pub min_factor: f64,
    pub max_factor: f64,
}

/// The tableau [`super::Adaptive`] steps DOP853 with.
pub fn dop853_tableau() -> Dop853Tableau {
    Dop853Tableau {
        c: &DOP853_C[..12],
        a: &DOP853_A[..12],
        b: DOP853_A[12],
        bhh: &DOP853_BHH,
        e5: &DOP853_E5,
        safety: SAFETY,
        min_factor: MIN_FACTOR,
        max_factor: MAX_FACTOR,
    }
}
