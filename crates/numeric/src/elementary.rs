//! The elementary functions of every float the project computes from an expression: `libm`'s,
//! and integer powers by binary powering, so the same inputs give the same bits on every
//! machine (the standard library's versions are the platform's and may differ in the last
//! bit).

use cas::number::{Rational, ToPrimitive};
use cas::Func;

mod lanes;
mod pow_lanes;

pub use lanes::{sin_cos_lanes, LANES};
pub use pow_lanes::pow_lanes;

/// The float nearest a rational, or close to it: ratios of integers too large for a float are
/// scaled down together first.
pub fn to_f64(q: &Rational) -> f64 {
    q.to_f64().unwrap_or_else(|| {
        // Ratios of huge integers: scale both down before dividing.
        let shift = q.numer().bits().max(q.denom().bits()).saturating_sub(1000);
        let n = (q.numer() >> shift).to_f64().unwrap_or(f64::NAN);
        let d = (q.denom() >> shift).to_f64().unwrap_or(f64::NAN);
        n / d
    })
}

/// `f(a)` for one of the scene language's functions.
pub fn apply(f: Func, a: f64) -> f64 {
    match f {
        Func::Sin => libm::sin(a),
        Func::Cos => libm::cos(a),
        Func::Tan => libm::tan(a),
        Func::Asin => libm::asin(a),
        Func::Acos => libm::acos(a),
        Func::Atan => libm::atan(a),
        Func::Sinh => libm::sinh(a),
        Func::Cosh => libm::cosh(a),
        Func::Tanh => libm::tanh(a),
        Func::Exp => libm::exp(a),
        Func::Ln => libm::log(a),
        Func::Abs => libm::fabs(a),
        Func::Sign => sign(a),
    }
}

/// The sine and cosine of `a` at once: the same bits as [`apply`] gives for each, for about
/// the cost of one (one argument reduction). [`sin_cos_lanes`] gives the same bits at eight
/// arguments at once.
pub fn sin_cos(a: f64) -> (f64, f64) {
    libm::sincos(a)
}

/// −1, 0 or 1 by the sign of `a` (`f64::signum` gives 1 at 0); NaN stays NaN.
pub fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        a * 0.0
    }
}

pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// A real power `base^exponent`. [`pow_lanes`] gives the same bits at eight bases at once.
pub fn pow(base: f64, exponent: f64) -> f64 {
    libm::pow(base, exponent)
}

/// `x^n` by binary powering: the same sequence of multiplications on every machine, in the
/// tape and in generated code (`f64::powi` leaves its precision unspecified).
pub fn pow_int(x: f64, n: i32) -> f64 {
    let mut base = x;
    let mut k = n.unsigned_abs();
    let mut acc = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            acc *= base;
        }
        base *= base;
        k >>= 1;
    }
    if n < 0 {
        1.0 / acc
    } else {
        acc
    }
}

/// The decimal logarithm, for digits counted from a magnitude (a condition number).
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}
