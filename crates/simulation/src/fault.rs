//! Why a run failed, where the numbers can tell: an explicit method that blew up is told the
//! mode it could not follow (from the exact Jacobian's spectrum at the last good state) and
//! the step it is stable at; an implicit method whose Newton iteration failed is told what it
//! reached and what to try.

use sim::{Fault, FaultKind, Mechanical, Method, Problem, Run};

use super::on_demand::lower_partials;
use engine::numbers::Prepared;

/// The fastest mode of the scene at the last good state of a run that failed, when it is
/// what held the explicit method's step down: an eigenvalue of ∂(q̇, q̈)/∂(q, q̇).
#[derive(Clone, Debug, PartialEq)]
pub struct FastestMode {
    /// The time of the state it was found at: the last before the fault, or the start.
    pub time: f64,
    /// The eigenvalue λ, 1/s (of a complex pair, the member with positive imaginary part).
    pub eigenvalue: (f64, f64),
    /// The coordinates that make up its eigenvector (indices into the state's names) with
    /// their shares of it, largest first; those under a tenth are left out.
    pub coordinates: Vec<(usize, f64)>,
    /// The largest step the method stays stable at for this mode.
    pub stable_step: f64,
    /// The step the method was taking, where it is known (rk4's fixed step, or the step an
    /// adaptive method fell to).
    pub step: Option<f64>,
}

/// A fault an explicit method meets when its step is far past the stability limit: the
/// solution grows by orders of magnitude per step until M(q) or a value breaks, or an
/// adaptive method cuts its step without end.
fn blow_up(kind: &FaultKind) -> bool {
    matches!(
        kind,
        FaultKind::NonFinite { .. }
            | FaultKind::SingularMass { .. }
            | FaultKind::SingularConstraints { .. }
            | FaultKind::StepTooSmall { .. }
            | FaultKind::TooManySteps { .. }
    )
}

/// Whether an adaptive run spent a good share of its steps at the stability limit (the test
/// the summary's `stiff:` line makes).
pub(crate) fn mostly_stiff(run: &Run) -> bool {
    run.stiff_steps >= 15 && 10 * run.stiff_steps >= run.steps
}

/// The fastest mode of an explicit `method`'s failed run, if stability is what failed it:
/// rk4's step past the mode's stable step, or an adaptive run held at the stability limit.
/// The mode is taken at the last state before the fault, unless the solution had already
/// blown up there (its fastest mode grows, which no step size cures); then at the start,
/// `y0`. The partials are lowered here, on demand, into `problem`.
pub(crate) fn fastest_mode(
    problem: &mut Mechanical,
    prepared: &mut Prepared,
    (method, step): (Method, f64),
    y0: &[f64],
    run: &Run,
) -> Option<FastestMode> {
    let fault: &Fault = run.fault.as_ref()?;
    if !(method.is_explicit() && blow_up(&fault.kind)) {
        return None;
    }
    if !problem.has_partials() {
        problem.set_partials(lower_partials(prepared).ok()?);
    }
    let n = problem.dim();
    let mut jac = vec![0.0; n * n];
    let mut modes = [(fault.time, fault.state.as_slice()), (0.0, y0)].into_iter().filter_map(
        |(time, state)| {
            problem.jacobian(time, state, &mut jac).ok()?.then_some(())?;
            let mode = sim::fastest_mode(&jac, n)?;
            // A growing mode (beyond rounding) is the blow-up itself, not its cause.
            let growing = mode.eigenvalue.re > 1e-6 * mode.eigenvalue.norm();
            (!growing).then_some((time, mode))
        },
    );
    let (time, mode) = modes.next()?;
    let stable_step = method.stable_step(mode.eigenvalue)?;
    // A fixed step is known; an adaptive one only where it fell to nothing.
    let adaptive = method.is_adaptive();
    let step = match (adaptive, &fault.kind) {
        (false, _) => Some(step),
        (true, FaultKind::StepTooSmall { step }) => Some(*step),
        (true, _) => None,
    };
    let limited = match (adaptive, step) {
        (false, Some(h)) => h > stable_step,
        _ => mostly_stiff(run),
    };
    if !limited {
        return None;
    }
    Some(FastestMode {
        time,
        eigenvalue: (mode.eigenvalue.re, mode.eigenvalue.im),
        coordinates: shares(&mode.shape),
        stable_step,
        step,
    })
}

/// The coordinates of an eigenvector's shape on (q, q̇), by their shares of its position half
/// (its rate half is λ times it), largest first, down to a tenth.
fn shares(shape: &[f64]) -> Vec<(usize, f64)> {
    let n = shape.len() / 2;
    let positions = &shape[..n];
    let total: f64 = positions.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Vec::new();
    }
    let mut v: Vec<(usize, f64)> = positions
        .iter()
        .enumerate()
        .map(|(i, u)| (i, u / total))
        .filter(|(_, share)| *share >= 0.1)
        .collect();
    v.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    v
}

/// The likely cause of a blow-up, when [`fastest_mode`] found the mode that caused it.
pub(crate) fn stiffness_cause(mode: &FastestMode, method: Method, names: &[String]) -> String {
    let time = mode.time;
    let (re, im) = mode.eigenvalue;
    let size = (re * re + im * im).sqrt();
    let eigenvalue =
        if im == 0.0 { format!("{re:.2e}/s") } else { format!("{re:.2e} ± {im:.2e}i /s") };
    let parts: Vec<String> = mode
        .coordinates
        .iter()
        .filter_map(|(i, share)| {
            names.get(*i).map(|name| format!("`{name}` ({:.0}%)", 100.0 * share))
        })
        .collect();
    let made_of =
        if parts.is_empty() { String::new() } else { format!(", moving {}", parts.join(", ")) };
    let name = method.name();
    let stable = mode.stable_step;
    let against = match mode.step {
        Some(h) if !method.is_adaptive() => {
            let ratio = h / stable;
            let ratio = if ratio < 100.0 { format!("{ratio:.1}") } else { format!("{ratio:.1e}") };
            format!(", and its step was {h:.1e} s, {ratio} times that")
        }
        Some(h) => format!(", and its step fell to {h:.1e} s"),
        None => String::new(),
    };
    let or_step = if method.is_adaptive() { "" } else { ", or --step below that limit" };
    format!(
        "the step, past {name}'s stability limit: the fastest mode at t = {time} has eigenvalue \
         λ ≈ {eigenvalue} (time scale {:.1e} s){made_of}; {name} is stable along it for steps \
         up to {stable:.1e} s{against}. The scene is stiff here: use --method radau (or auto), \
         whose step follows the slow motion{or_step}",
        1.0 / size
    )
}

/// What a fixed-step implicit method's failed Newton iteration reached, and what to try.
pub(crate) fn newton_failed(
    method: Method,
    step: f64,
    contraction: f64,
    exact_jacobian: bool,
) -> (String, String) {
    let (rate, jacobian) = (rate(contraction), jacobian(exact_jacobian));
    (
        format!(
            "Newton's iteration of {} did not converge at its fixed step of {step:.1e} s \
             ({rate}, with {jacobian} at the start of the step)",
            method.name()
        ),
        format!(
            "the motion changes too much within one step for an iteration that keeps the \
             Jacobian of the step's start: try --step {:.0e} or smaller, or --method radau, \
             which shortens its step where Newton struggles and is made for stiff scenes",
            step / 10.0
        ),
    )
}

/// What radau's Newton iteration, stalled at its smallest step, says is true.
pub(crate) fn newton_stalled(
    step: f64,
    contraction: f64,
    singular: bool,
    exact_jacobian: bool,
) -> (String, String) {
    let (rate, jacobian) = (rate(contraction), jacobian(exact_jacobian));
    let what = if singular {
        format!(
            "the implicit method's iteration matrix stayed singular down to a step of {step:.1e} \
             (with {jacobian})"
        )
    } else {
        format!(
            "Newton's iteration of the implicit method did not converge although the step was \
             cut to {step:.1e} ({rate}, with {jacobian})"
        )
    };
    (
        what,
        "the equations are not smooth here (a kink, a switch, a square root at zero), or the \
         kept constraints cannot all hold here; a smaller tolerance will not help: look at the \
         scene at the state above"
            .into(),
    )
}

/// How Newton's corrections went, from the ratio of the last two.
fn rate(contraction: f64) -> String {
    if !contraction.is_finite() {
        "its corrections were not finite".to_string()
    } else if contraction >= 1.0 {
        format!("its corrections grew by a factor {contraction:.2} per iteration")
    } else {
        format!("its corrections shrank by only a factor {contraction:.2} per iteration")
    }
}

fn jacobian(exact: bool) -> &'static str {
    if exact {
        "the exact Jacobian"
    } else {
        "a Jacobian from differences"
    }
}
