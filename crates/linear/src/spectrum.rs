//! The eigenvalues of A and the verdict on stability: sorted so that rounding does not
//! shuffle them from one value of a sweep to the next, with the first integrals' zeros taken
//! out first where the case calls for it, and the verdict apart from them.

use nalgebra::DMatrix;

use crate::dense::{null_space, null_space_within};
use crate::eigen::{self, Eigenvalue};

/// What an expected eigenvalue (`expect linearized: eigenvalue = …`) may differ from the one
/// found by, relatively to the largest |eigenvalue|, where the eigenvalue's own bound is
/// smaller: the expected value is exact, the one found comes through A's entries evaluated in
/// floating point.
pub const RELATIVE_TOLERANCE: f64 = 1e-8;

/// How small motions about the reference behave, by the real parts of the eigenvalues, each
/// against its own bound on rounding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stability {
    /// Every real part is below minus its bound: small motions die out.
    Stable,
    /// None is above its bound, some is within it of zero: small motions neither grow nor
    /// die out (at first order).
    MarginallyStable,
    /// Some real part is above its bound: some small motion grows.
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
    /// Each eigenvalue's bound on how far rounding may have moved it, in the same order.
    pub bounds: Vec<f64>,
    pub stability: Stability,
    /// The largest of the bounds.
    pub tolerance: f64,
    pub first_integrals: usize,
    pub cyclic_zeros: usize,
}

impl Spectrum {
    /// All the eigenvalues of A, the verdict on all of them; `None` if A is not finite or the
    /// iteration does not converge.
    pub fn of(a: &DMatrix<f64>) -> Option<Spectrum> {
        Some(Spectrum::from_values(eigen::eigenvalues(a)?, 0, a.trace()))
    }

    /// The spectrum of eigenvalues `values` of a matrix of trace `trace`.
    fn from_values(mut values: Vec<Eigenvalue>, first_integrals: usize, trace: f64) -> Spectrum {
        sort(&mut values);
        let stability = stability_apart(&values, first_integrals, trace);
        let tolerance = values.iter().map(|z| z.bound).fold(0.0, f64::max);
        Spectrum {
            eigenvalues: values.iter().map(|z| (z.re, z.im)).collect(),
            bounds: values.iter().map(|z| z.bound).collect(),
            stability,
            tolerance,
            first_integrals,
            cyclic_zeros: 0,
        }
    }

    /// With `count` zeros more, those of cyclic positions kept in the state (exact, so of
    /// bound 0): the verdict stays that of the rest.
    pub fn with_cyclic_zeros(mut self, count: usize) -> Spectrum {
        let mut values: Vec<Eigenvalue> = self
            .eigenvalues
            .iter()
            .zip(&self.bounds)
            .map(|(&(re, im), &bound)| Eigenvalue { re, im, bound })
            .collect();
        values.extend(std::iter::repeat_n(Eigenvalue { re: 0.0, im: 0.0, bound: 0.0 }, count));
        sort(&mut values);
        self.eigenvalues = values.iter().map(|z| (z.re, z.im)).collect();
        self.bounds = values.iter().map(|z| z.bound).collect();
        self.cyclic_zeros = count;
        self
    }

    /// The eigenvalues with A's first integrals deflated first ([`deflated_eigenvalues`]), the
    /// verdict apart from their zeros.
    pub fn deflated(a: &DMatrix<f64>) -> Option<Spectrum> {
        let (values, first_integrals) = deflated_eigenvalues(a)?;
        // The first integrals' part of A (Lᵀ·A = 0) adds nothing to its trace.
        Some(Spectrum::from_values(values, first_integrals, a.trace()))
    }
}

/// By real part from the largest down (those within their bound of zero as zero, so that
/// rounding does not shuffle the eigenvalues of an undamped system from one value of a sweep
/// to the next), then by imaginary part.
fn sort(values: &mut [Eigenvalue]) {
    let key = |z: &Eigenvalue| if z.re.abs() <= z.bound { 0.0 } else { z.re };
    values.sort_by(|x, y| key(y).total_cmp(&key(x)).then(y.im.total_cmp(&x.im)));
}

/// The eigenvalues of A with its first integrals taken out first: each ℓ with ℓᵀ·A = 0 (a
/// conserved combination of the state, as the rates of ignorable coordinates give) is an
/// eigenvalue 0, and A maps everything into ℓ⊥, so that in an orthonormal basis (Q, L) of
/// ℓ⊥ and of the ℓ, A = [QᵀAQ, ·; 0, 0] and the rest are the eigenvalues of QᵀAQ. Without
/// this, where an oscillation's pair meets those zeros (the rolling coin's critical spin) the
/// eigenvalues of a Jordan block of order three move by the cube root of the rounding.
fn deflated_eigenvalues(a: &DMatrix<f64>) -> Option<(Vec<Eigenvalue>, usize)> {
    let size = a.nrows();
    if size == 0 || a.iter().any(|x| !x.is_finite()) {
        return eigen::eigenvalues(a).map(|v| (v, 0));
    }
    // A first integral's row of A is zero up to rounding; a tighter threshold than for
    // constraints keeps an eigenvalue merely passing through zero (the bicycle's capsize mode
    // at its critical speed) out of the first integrals.
    let conserved = null_space_within(a.transpose(), 1e-13)?;
    let c = conserved.ncols();
    if c == 0 || a.amax() == 0.0 {
        return eigen::eigenvalues(a).map(|v| (v, 0));
    }
    // Q: an orthonormal basis of the complement, from the null space of the ℓᵀ.
    let q = null_space(conserved.transpose())?;
    if q.ncols() + c != size {
        return eigen::eigenvalues(a).map(|v| (v, 0));
    }
    let reduced = q.transpose() * a * &q;
    let mut values = eigen::eigenvalues(&reduced)?;
    values.extend(std::iter::repeat_n(Eigenvalue { re: 0.0, im: 0.0, bound: 0.0 }, c));
    Some((values, c))
}

/// The verdict on the eigenvalues apart from `first_integrals` of their exact zeros (each
/// first integral's direction leads to a neighbouring steady motion, not away from this one:
/// the bicycle's forward speed, the sleigh's), each real part against its own bound.
///
/// The real parts add up to A's trace, `trace`: a conservative system's spectrum is symmetric
/// about the imaginary axis (λ with −λ̄), its trace 0 (no damping puts nothing on A's
/// diagonal), and it cannot be stable whatever rounding does to its real parts.
fn stability_apart(values: &[Eigenvalue], first_integrals: usize, trace: f64) -> Stability {
    let rest = apart_from_first_integrals(values, first_integrals);
    if rest.iter().any(|z| z.re > z.bound) {
        Stability::Unstable
    } else if !rest.is_empty() && rest.iter().all(|z| z.re < -z.bound) && trace < 0.0 {
        Stability::Stable
    } else {
        Stability::MarginallyStable
    }
}

/// The eigenvalues without `first_integrals` of their exact zeros (the deflated ones).
fn apart_from_first_integrals(values: &[Eigenvalue], first_integrals: usize) -> Vec<Eigenvalue> {
    let mut skip = first_integrals;
    values
        .iter()
        .filter(|z| {
            let drop = skip > 0 && (z.re, z.im, z.bound) == (0.0, 0.0, 0.0);
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
    let values: Vec<Eigenvalue> = numbers
        .eigenvalues
        .iter()
        .zip(&numbers.bounds)
        .map(|(&(re, im), &bound)| Eigenvalue { re, im, bound })
        .collect();
    apart_from_first_integrals(&values, set_aside)
        .iter()
        .map(|z| z.re)
        .fold(f64::NEG_INFINITY, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn verdict(values: &[(f64, f64, f64)]) -> Stability {
        let values: Vec<Eigenvalue> =
            values.iter().map(|&(re, im, bound)| Eigenvalue { re, im, bound }).collect();
        let trace = values.iter().map(|z| z.re).sum();
        stability_apart(&values, 0, trace)
    }

    #[test]
    fn verdicts_follow_the_real_parts_against_their_own_bounds() {
        assert_eq!(verdict(&[(-1.0, 2.0, 1e-15), (-1.0, -2.0, 1e-15)]), Stability::Stable);
        assert_eq!(verdict(&[(0.0, 2.0, 0.0), (0.0, -2.0, 0.0)]), Stability::MarginallyStable);
        let rounded = [(1e-12, 2.0, 1e-11), (-1e-12, -2.0, 1e-11)];
        assert_eq!(verdict(&rounded), Stability::MarginallyStable);
        assert_eq!(verdict(&[(3.0, 0.0, 1e-15), (-3.0, 0.0, 1e-15)]), Stability::Unstable);
        assert_eq!(verdict(&[(0.0, 0.0, 0.0)]), Stability::MarginallyStable);
        // A slow root is judged on its own bound, not on the fast root's size.
        assert_eq!(verdict(&[(-1.0, 0.0, 1e-6), (-1e9, 0.0, 1e-6)]), Stability::Stable);
        // Real parts that rounding pushed below their bounds, in a spectrum whose trace is 0:
        // symmetric, so not stable.
        let pushed: Vec<Eigenvalue> = [(-1e-3, 1.0), (-1e-3, -1.0)]
            .iter()
            .map(|&(re, im)| Eigenvalue { re, im, bound: 1e-6 })
            .collect();
        assert_eq!(stability_apart(&pushed, 0, 0.0), Stability::MarginallyStable);
    }

    #[test]
    fn eigenvalues_are_sorted() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, 0.0]);
        let e = Spectrum::of(&a).expect("converges").eigenvalues;
        assert_eq!(e.len(), 2);
        assert!((e[0].1 - 2.0).abs() < 1e-14 && (e[1].1 + 2.0).abs() < 1e-14, "{e:?}");
    }

    #[test]
    fn stiff_spectra_are_judged_root_by_root() {
        // Roots −1 and −1e9: stable, though 1e-8 × 1e9 is above the slow root.
        let damped = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1e9, -(1e9 + 1.0)]);
        assert_eq!(Spectrum::of(&damped).expect("converges").stability, Stability::Stable);
        // Undamped, with stiffnesses 1 and 1e8 between unit masses: ±i·ω of both modes, no
        // real part beyond its bound.
        #[rustfmt::skip]
        let undamped = DMatrix::from_row_slice(4, 4, &[
            0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 1.0,
            -(1.0 + 1e8), 1e8, 0.0, 0.0,
            1e8, -1e8, 0.0, 0.0,
        ]);
        let s = Spectrum::of(&undamped).expect("converges");
        assert_eq!(s.stability, Stability::MarginallyStable, "{s:?}");
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
