//! Why a reference could not be analysed at some parameter values, and the diagnostic that
//! says so at the reference.

use cas::{Style, SymId};
use lang::{Diagnostic, Span};
use mechanics::Derivation;

/// A residual counts as zero within this fraction of the size of its terms.
pub(crate) const EQUILIBRIUM_TOLERANCE: f64 = 1e-9;

/// Why a reference could not be analysed at some parameter values.
#[derive(Clone, Debug)]
pub enum Fault {
    /// The accelerations there do not vanish.
    NotEquilibrium { accelerations: Vec<f64>, symbols: Vec<SymId> },
    /// The reference is off a kept constraint.
    OffConstraint { constraint: usize, value: f64 },
    /// The mass matrix (projected onto the constraints' null space) is singular there.
    SingularMass { condition: f64 },
    /// A value is NaN or infinite.
    NotFinite(&'static str),
    /// The kept constraints leave no small motion.
    NoMotion,
    /// The kept constraints do not fix the dependent rates at the reference (or the given
    /// rates break them).
    DependentRates { residual: f64 },
}

impl Fault {
    /// The diagnostic at the reference's `span`; `at` says at which value of a sweep (or is
    /// empty).
    pub fn diagnostic(&self, d: &Derivation, span: Span, at: &str) -> Diagnostic {
        let pool = &d.model.pool;
        match self {
            Fault::NotEquilibrium { accelerations, symbols } => {
                let listed: Vec<String> = symbols
                    .iter()
                    .zip(accelerations)
                    .map(|(a, v)| format!("{} = {}", pool.symbol_text(*a, Style::Unicode), v))
                    .collect();
                Diagnostic::error(
                    span,
                    format!("this reference is not an equilibrium or a steady motion{at}"),
                )
                .with_label(format!("the accelerations here: {}", listed.join(", ")))
                .with_hint(
                    "at a reference the accelerations vanish: choose positions (and rates of \
                     cyclic coordinates) where M⁻¹·f is zero",
                )
            }
            Fault::OffConstraint { constraint, value } => {
                let c = &d.model.constraints[*constraint];
                Diagnostic::error(
                    span,
                    format!("this reference is not on the constraint `{}`{at}", c.name),
                )
                .with_label(format!("Φ = {value} here"))
                .with_related(c.span, "the constraint")
                .with_hint("give positions that satisfy every constraint kept with a multiplier")
            }
            Fault::SingularMass { condition } => Diagnostic::error(
                span,
                format!("the mass matrix is singular at this reference{at}"),
            )
            .with_label(if condition.is_finite() {
                format!("condition number ≈ {condition:.1e}")
            } else {
                "exactly singular".to_string()
            })
            .with_hint(
                "the coordinates are singular here (Euler angles at gimbal lock, say): choose \
                 coordinates that are regular at the reference",
            ),
            Fault::NoMotion => Diagnostic::error(
                span,
                format!("the constraints leave no small motion about this reference{at}"),
            )
            .with_label("every δq here breaks a constraint")
            .with_hint("a reference needs room to move: fewer constraints than coordinates"),
            Fault::DependentRates { residual } => Diagnostic::error(
                span,
                format!("the kept constraints do not fix the dependent rates here{at}"),
            )
            .with_label(if residual.is_finite() {
                format!("their rows are singular or inconsistent (residual {residual:.1e})")
            } else {
                "their rows are singular here".to_string()
            })
            .with_hint(
                "give the independent rates of the steady motion in the reference (the \
                 constraints give the others), and positions where the constraints restrain \
                 independent directions",
            ),
            Fault::NotFinite(what) => Diagnostic::error(
                span,
                format!("{what} is not a finite number at this reference{at}"),
            )
            .with_label("NaN or infinite here")
            .with_hint("a division by zero or a function outside its domain at the reference"),
        }
    }
}
