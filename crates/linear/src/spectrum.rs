//! The eigenvalues of A and the verdict on stability: sorted so that rounding does not
//! shuffle them from one value of a sweep to the next, with the first integrals' zeros taken
//! out first where the case calls for it, and the verdict apart from them.

use nalgebra::DMatrix;

use crate::dense::{null_space, null_space_within, MAX_ITERATIONS};

/// A real part counts as zero within this fraction of the largest |eigenvalue|: rounding in
/// the eigenvalues of a matrix of order ten is far below it, and a root of a double eigenvalue
/// (where stability changes) is still far above it a relative 1e-10 away.
pub const RELATIVE_TOLERANCE: f64 = 1e-8;

/// How small motions about the reference behave, by the real parts of the eigenvalues.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stability {
    /// Every real part is below −tolerance: small motions die out.
    Stable,
    /// None is above +tolerance, some is within it: small motions neither grow nor die out
    /// (at first order).
    MarginallyStable,
    /// Some real part is above +tolerance: some small motion grows.
    Unstable,
}

impl Stability {
    pub fn name(self) -> &'static str {
        match self {
            Stability::Stable => "stable",
            Stability::MarginallyStable => "marginally stable",
            Stability::Unstable => "unstable",
        }
    }
}

/// The eigenvalues of A and the verdict on them.
#[derive(Clone, Debug)]
pub(crate) struct Spectrum {
    pub eigenvalues: Vec<(f64, f64)>,
    pub stability: Stability,
    pub tolerance: f64,
    pub first_integrals: usize,
    pub cyclic_zeros: usize,
}

impl Spectrum {
    /// All the eigenvalues of A, the verdict on all of them; `None` if the iteration does not
    /// converge.
    pub fn of(a: &DMatrix<f64>) -> Option<Spectrum> {
        let eigenvalues = eigenvalues(a)?;
        let (stability, tolerance) = stability(&eigenvalues);
        Some(Spectrum { eigenvalues, stability, tolerance, first_integrals: 0, cyclic_zeros: 0 })
    }

    /// With `count` zeros more, those of cyclic positions kept in the state: the verdict and
    /// its tolerance stay those of the rest.
    pub fn with_cyclic_zeros(mut self, count: usize) -> Spectrum {
        self.eigenvalues.extend(std::iter::repeat_n((0.0, 0.0), count));
        let tolerance = self.tolerance;
        let key = |re: f64| if re.abs() <= tolerance { 0.0 } else { re };
        self.eigenvalues.sort_by(|x, y| key(y.0).total_cmp(&key(x.0)).then(y.1.total_cmp(&x.1)));
        self.cyclic_zeros = count;
        self
    }

    /// The eigenvalues with A's first integrals deflated first ([`deflated_eigenvalues`]), the
    /// verdict apart from their zeros.
    pub fn deflated(a: &DMatrix<f64>) -> Option<Spectrum> {
        let (eigenvalues, first_integrals) = deflated_eigenvalues(a)?;
        let (stability, tolerance) = stability_apart(&eigenvalues, first_integrals);
        Some(Spectrum { eigenvalues, stability, tolerance, first_integrals, cyclic_zeros: 0 })
    }
}

/// The eigenvalues of A as (re, im), by real part from the largest down (those within the
/// verdict's tolerance of zero as zero), then by imaginary part; `None` when the iteration
/// does not converge.
fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<(f64, f64)>> {
    if a.is_empty() {
        return Some(Vec::new());
    }
    if a.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let schur = nalgebra::Schur::try_new(a.clone(), f64::EPSILON, MAX_ITERATIONS)?;
    let mut out: Vec<(f64, f64)> =
        schur.complex_eigenvalues().iter().map(|z| (z.re, z.im)).collect();
    // Real parts within the verdict's tolerance of zero sort as zero, so that rounding does not
    // shuffle the eigenvalues of an undamped system from one value of a sweep to the next.
    let (_, tolerance) = stability(&out);
    let key = |re: f64| if re.abs() <= tolerance { 0.0 } else { re };
    out.sort_by(|x, y| key(y.0).total_cmp(&key(x.0)).then(y.1.total_cmp(&x.1)));
    Some(out)
}

/// The eigenvalues of A with its first integrals taken out first: each ℓ with ℓᵀ·A = 0 (a
/// conserved combination of the state, as the rates of ignorable coordinates give) is an
/// eigenvalue 0, and A maps everything into ℓ⊥, so that in an orthonormal basis (Q, L) of
/// ℓ⊥ and of the ℓ, A = [QᵀAQ, ·; 0, 0] and the rest are the eigenvalues of QᵀAQ. Without
/// this, where an oscillation's pair meets those zeros (the rolling coin's critical spin) the
/// eigenvalues of a Jordan block of order three move by the cube root of the rounding, far
/// above the verdict's tolerance.
fn deflated_eigenvalues(a: &DMatrix<f64>) -> Option<(Vec<(f64, f64)>, usize)> {
    let size = a.nrows();
    if size == 0 || a.iter().any(|x| !x.is_finite()) {
        return eigenvalues(a).map(|v| (v, 0));
    }
    // A first integral's row of A is zero up to rounding; a tighter threshold than for
    // constraints keeps an eigenvalue merely passing through zero (the bicycle's capsize mode
    // at its critical speed) out of the first integrals.
    let conserved = null_space_within(a.transpose(), 1e-13)?;
    let c = conserved.ncols();
    if c == 0 || a.amax() == 0.0 {
        return eigenvalues(a).map(|v| (v, 0));
    }
    // Q: an orthonormal basis of the complement, from the null space of the ℓᵀ.
    let q = null_space(conserved.transpose())?;
    if q.ncols() + c != size {
        return eigenvalues(a).map(|v| (v, 0));
    }
    let reduced = q.transpose() * a * &q;
    let mut values = eigenvalues(&reduced)?;
    values.extend(std::iter::repeat_n((0.0, 0.0), c));
    let (_, tolerance) = stability(&values);
    let key = |re: f64| if re.abs() <= tolerance { 0.0 } else { re };
    values.sort_by(|x, y| key(y.0).total_cmp(&key(x.0)).then(y.1.total_cmp(&x.1)));
    Some((values, c))
}

/// The verdict on the eigenvalues apart from `first_integrals` of their exact zeros (each
/// first integral's direction leads to a neighbouring steady motion, not away from this one:
/// the bicycle's forward speed, the sleigh's), and the tolerance it used.
fn stability_apart(eigenvalues: &[(f64, f64)], first_integrals: usize) -> (Stability, f64) {
    let scale = eigenvalues.iter().map(|(re, im)| (re * re + im * im).sqrt()).fold(0.0, f64::max);
    let tolerance = RELATIVE_TOLERANCE * scale;
    let rest = apart_from_first_integrals(eigenvalues, first_integrals);
    let verdict = if rest.iter().any(|(re, _)| *re > tolerance) {
        Stability::Unstable
    } else if !rest.is_empty() && rest.iter().all(|(re, _)| *re < -tolerance) {
        Stability::Stable
    } else {
        Stability::MarginallyStable
    };
    (verdict, tolerance)
}

/// The eigenvalues without `first_integrals` of their exact zeros (the deflated ones).
fn apart_from_first_integrals(
    eigenvalues: &[(f64, f64)],
    first_integrals: usize,
) -> Vec<(f64, f64)> {
    let mut skip = first_integrals;
    eigenvalues
        .iter()
        .filter(|z| {
            let drop = skip > 0 && **z == (0.0, 0.0);
            skip -= usize::from(drop);
            !drop
        })
        .copied()
        .collect()
}

/// The largest real part among the eigenvalues apart from the zeros of the first integrals
/// and of the cyclic positions kept.
pub(crate) fn largest_real_part(numbers: &crate::Numbers) -> f64 {
    let set_aside = numbers.first_integrals + numbers.cyclic_zeros;
    apart_from_first_integrals(&numbers.eigenvalues, set_aside)
        .iter()
        .map(|z| z.0)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The verdict on all the eigenvalues and the absolute tolerance it used.
fn stability(eigenvalues: &[(f64, f64)]) -> (Stability, f64) {
    stability_apart(eigenvalues, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_real_parts() {
        assert_eq!(stability(&[(-1.0, 2.0), (-1.0, -2.0)]).0, Stability::Stable);
        assert_eq!(stability(&[(0.0, 2.0), (0.0, -2.0)]).0, Stability::MarginallyStable);
        assert_eq!(stability(&[(1e-12, 2.0), (-1e-12, -2.0)]).0, Stability::MarginallyStable);
        assert_eq!(stability(&[(3.0, 0.0), (-3.0, 0.0)]).0, Stability::Unstable);
        assert_eq!(stability(&[(0.0, 0.0)]).0, Stability::MarginallyStable);
    }

    #[test]
    fn eigenvalues_are_sorted() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, 0.0]);
        let e = eigenvalues(&a).expect("converges");
        assert_eq!(e.len(), 2);
        assert!((e[0].1 - 2.0).abs() < 1e-14 && (e[1].1 + 2.0).abs() < 1e-14, "{e:?}");
    }

    #[test]
    fn a_first_integral_is_deflated_and_left_out_of_the_verdict() {
        // ẋ = 0 beside a damped oscillator: x is conserved, the rest dies out.
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -4.0, -1.0]);
        let s = Spectrum::deflated(&a).expect("converges");
        assert_eq!(s.first_integrals, 1);
        assert_eq!(s.stability, Stability::Stable);
        assert_eq!(Spectrum::of(&a).expect("converges").stability, Stability::MarginallyStable);
    }
}
