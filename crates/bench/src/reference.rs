//! Exact references that integrators are measured against: the complete elliptic integral
//! (the pendulum's period) and a quadrature for fall times from the energy integral.

/// The complete elliptic integral of the first kind, K(k) = π / (2 AGM(1, √(1 − k²))).
pub fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    // The mean converges quadratically; a fixed bound guards against rounding keeping a and b
    // a few ulps apart for ever.
    for _ in 0..64 {
        if (a - b).abs() <= 4.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = ((a + b) / 2.0, (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

/// ∫ f over [a, b] by composite three-point Gauss–Legendre, which never evaluates the ends
/// (where the integrands of fall times are singular).
pub fn gauss_legendre(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
    let nodes = [(-(0.6f64).sqrt(), 5.0 / 9.0), (0.0, 8.0 / 9.0), ((0.6f64).sqrt(), 5.0 / 9.0)];
    let h = (b - a) / panels as f64;
    (0..panels)
        .map(|i| {
            let mid = a + (i as f64 + 0.5) * h;
            nodes.iter().map(|(x, w)| w * f(mid + x * h / 2.0)).sum::<f64>() * h / 2.0
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_reproduce_known_values() {
        // K(0) = π/2; K(1/√2) = Γ(1/4)²/(4√π) = 1.8540746773013719.
        assert!((elliptic_k(0.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((elliptic_k(0.5f64.sqrt()) - 1.854_074_677_301_371_9).abs() < 1e-14);
        // ∫₀¹ 1/√x dx = 2, with the singular end never evaluated.
        let i = gauss_legendre(|x| 1.0 / x.sqrt(), 0.0, 1.0, 20_000);
        assert!((i - 2.0).abs() < 1e-2, "{i}");
    }
}
