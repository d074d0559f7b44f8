//! Exact references that integrators are measured against: the complete elliptic integral
//! (the pendulum's period), a quadrature for fall times from the energy integral, and the
//! impact times of the two contact scenes with closed forms (a bouncing ball, Housner's
//! rocking block).

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

/// The impact times t₁, t₂, … of a ball dropped from rest at height `h0` onto a floor of
/// restitution `e` under gravity `g`: t₁ = √(2·h0/g), and each flight after the kth impact
/// lasts 2·eᵏ·t₁, so t_k = t₁·(1 + 2·(e + … + e^(k−1))). The first `count` of them.
pub fn bouncing_ball_impacts(g: f64, e: f64, h0: f64, count: usize) -> Vec<f64> {
    let first = (2.0 * h0 / g).sqrt();
    let (mut t, mut flight) = (first, 2.0 * e * first);
    let mut times = Vec::with_capacity(count);
    for _ in 0..count {
        times.push(t);
        t += flight;
        flight *= e;
    }
    times
}

/// Where the ball's impacts accumulate: t₁·(1 + e)/(1 − e).
pub fn bouncing_ball_accumulation(g: f64, e: f64, h0: f64) -> f64 {
    (2.0 * h0 / g).sqrt() * (1.0 + e) / (1.0 - e)
}

/// Housner's rate ratio per impact of a rigid block of half-width `b` and half-height `h`
/// rocking on gripping ground: angular momentum about the landing corner is conserved, so
/// θ̇⁺ = (1 − 3/2·sin²α)·θ̇⁻ with α = atan(b/h).
pub fn housner_ratio(b: f64, h: f64) -> f64 {
    let s = libm::sin(libm::atan(b / h));
    1.0 - 1.5 * s * s
}

/// The impact times before `until` of Housner's rocking block (half-width `b`, half-height
/// `h`, gravity `g`) released at rest at tilt `theta0` (0 < θ₀ < α) about one corner, up to
/// where they accumulate if that comes first.
///
/// About a corner the block is an inverted pendulum of radius R = √(b² + h²) and inertia
/// 4/3·m·R² there, so θ̇² = c·(cos(α − A) − cos(α − θ)) with c = 3g/(2R), A its amplitude
/// (where it rests). From θ = 0 to A or back takes τ(A) = ∫₀^A dθ/θ̇; after the release the
/// first landing is at τ(θ₀), and each impact multiplies the landing rate by
/// [`housner_ratio`], which gives the next amplitude, so the next landing comes 2·τ(A) later.
/// τ is computed with θ = A·(1 − u²), which leaves the smooth integrand
/// 2·√(A/c) / √(sin(α − A + z)·sinc z), z = A·u²/2, integrated by Gauss–Legendre to rounding.
pub fn rocking_block_impacts(g: f64, b: f64, h: f64, theta0: f64, until: f64) -> Vec<f64> {
    let alpha = libm::atan(b / h);
    let c = 1.5 * g / (b * b + h * h).sqrt();
    let ratio = housner_ratio(b, h);
    let tau = |a: f64| {
        let integrand = |u: f64| {
            let z = a * u * u / 2.0;
            let sinc = if z == 0.0 { 1.0 } else { libm::sin(z) / z };
            2.0 * (a / c).sqrt() / (libm::sin(alpha - a + z) * sinc).sqrt()
        };
        gauss_legendre(integrand, 0.0, 1.0, 200)
    };
    // cos(α − A) − cos α = 2·sin(α − A/2)·sin(A/2), which keeps its digits for small A.
    let rise = |a: f64| 2.0 * libm::sin(alpha - a / 2.0) * libm::sin(a / 2.0);
    // The amplitude that a landing rate ω reaches: rise(A) = ω²/c, by Newton's method.
    let amplitude = |w2: f64| {
        let mut a = w2 / (c * libm::sin(alpha));
        for _ in 0..50 {
            let slope = libm::sin(alpha - a);
            let next = a - (rise(a) - w2 / c) / slope;
            if (next - a).abs() <= 1e-16 * a {
                return next;
            }
            a = next;
        }
        a
    };
    let mut times = Vec::new();
    let (mut t, mut w2) = (tau(theta0), c * rise(theta0));
    while t < until {
        times.push(t);
        w2 *= ratio * ratio;
        let flight = 2.0 * tau(amplitude(w2));
        // Past the accumulation point of the impacts, the block rests.
        if flight.is_nan() || flight <= f64::EPSILON * t {
            break;
        }
        t += flight;
    }
    times
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

    #[test]
    fn the_contact_references_meet_their_limits() {
        // The ball's impacts approach their accumulation point.
        let times = bouncing_ball_impacts(9.81, 0.8, 1.0, 300);
        let end = bouncing_ball_accumulation(9.81, 0.8, 1.0);
        assert!((times[0] - (2.0f64 / 9.81).sqrt()).abs() < 1e-15);
        assert!((times[299] - end).abs() < 1e-12 * end, "{} {end}", times[299]);
        // A 3:1 block: sin²α = 1/10.
        assert!((housner_ratio(0.1, 0.3) - 0.85).abs() < 1e-15);
        // Released barely tilted, the block sees a torque that hardly changes over its
        // swing: θ̈ = −(c/2)·sin α, so it lands after √(2·θ₀/((c/2)·sin α)).
        let (g, b, h, theta0) = (9.81f64, 0.1f64, 0.3f64, 1e-7);
        let half = 0.75 * g / (b * b + h * h).sqrt() * libm::sin(libm::atan(b / h));
        let first = rocking_block_impacts(g, b, h, theta0, 1.0)[0];
        let expected = (2.0 * theta0 / half).sqrt();
        assert!((first - expected).abs() < 1e-6 * expected, "{first} {expected}");
    }
}
