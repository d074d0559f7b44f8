//! Exact rational numbers and the few number-theoretic helpers the algebra needs.

use num_bigint::BigInt;
use num_integer::Integer;
use num_rational::BigRational;
pub use num_traits::{One, Signed, ToPrimitive, Zero};

/// An exact rational number; big integers underneath, so nothing overflows silently.
pub type Rational = BigRational;

pub fn int(n: i64) -> Rational {
    Rational::from_integer(BigInt::from(n))
}

pub fn ratio(n: i64, d: i64) -> Rational {
    Rational::new(BigInt::from(n), BigInt::from(d))
}

// Sums and products of expressions add and multiply coefficients and exponents all the time,
// and nearly all of them are small integers. num-rational reduces every result by a gcd, two
// divisions and shifts, integers included; these skip that when both sides are integers (or
// one side is one), where there is nothing to reduce.

/// `*a += b`.
pub fn add_to(a: &mut Rational, b: &Rational) {
    if b.is_zero() {
        return;
    }
    if a.is_integer() && b.is_integer() {
        *a = Rational::from_integer(a.numer() + b.numer());
    } else {
        *a += b;
    }
}

/// `a + b`.
pub fn plus(a: &Rational, b: &Rational) -> Rational {
    if a.is_integer() && b.is_integer() {
        Rational::from_integer(a.numer() + b.numer())
    } else {
        a + b
    }
}

/// `a · b`.
pub fn times(a: &Rational, b: &Rational) -> Rational {
    if b.is_one() {
        return a.clone();
    }
    if a.is_one() {
        return b.clone();
    }
    if a.is_integer() && b.is_integer() {
        return Rational::from_integer(a.numer() * b.numer());
    }
    a * b
}

/// `*a *= b`.
pub fn scale_by(a: &mut Rational, b: &Rational) {
    if b.is_one() {
        return;
    }
    *a = times(a, b);
}

/// `a / b`.
pub fn divided(a: &Rational, b: &Rational) -> Rational {
    if b.is_one() {
        return a.clone();
    }
    a / b
}

/// Parses a decimal literal (`12`, `0.1`, `1e-3`, `2.5E+4`) into an exact rational.
pub fn parse_decimal(text: &str) -> Option<Rational> {
    let (mantissa, exponent) = match text.find(['e', 'E']) {
        Some(i) => (&text[..i], text[i + 1..].parse::<i64>().ok()?),
        None => (text, 0),
    };
    let (whole, frac) = match mantissa.find('.') {
        Some(i) => (&mantissa[..i], &mantissa[i + 1..]),
        None => (mantissa, ""),
    };
    if whole.is_empty() && frac.is_empty() {
        return None;
    }
    if !whole.chars().chain(frac.chars()).all(|c| c.is_ascii_digit()) {
        return None;
    }
    // Exponents past this are not physics, and 10^huge would exhaust memory.
    if exponent.abs() > 4000 {
        return None;
    }
    let digits: BigInt = format!("{whole}{frac}").parse().ok()?;
    let scale = exponent - frac.len() as i64;
    let ten = BigInt::from(10);
    Some(if scale >= 0 {
        Rational::from_integer(digits * num_traits::pow(ten, scale as usize))
    } else {
        Rational::new(digits, num_traits::pow(ten, (-scale) as usize))
    })
}

/// `q^n` for an integer `n`; `None` for `0^negative` or an exponent too large to be sane.
pub fn pow_int(q: &Rational, n: &BigInt) -> Option<Rational> {
    let n = n.to_i64()?;
    if q.is_zero() && n < 0 {
        return None;
    }
    if q.is_one() || n == 0 {
        return Some(Rational::one());
    }
    let bits = q.numer().bits().max(q.denom().bits());
    if n.unsigned_abs().saturating_mul(bits) > 1 << 20 {
        return None;
    }
    let p = num_traits::pow(q.clone(), n.unsigned_abs() as usize);
    Some(if n < 0 { p.recip() } else { p })
}

/// The largest `k` with `k^root` dividing `n` (for small prime factors), and what is left.
/// Used to pull perfect powers out of radicals: sqrt(12) = 2 sqrt(3).
fn split_perfect_power(n: &BigInt, root: u32) -> (BigInt, BigInt) {
    let mut outside = BigInt::one();
    let mut inside = n.clone();
    // Trial division is enough: radicands in mechanics are small integers.
    let mut p = BigInt::from(2);
    let limit = BigInt::from(10_000);
    while p <= limit && p.clone() * p.clone() <= inside {
        let pk = num_traits::pow(p.clone(), root as usize);
        while (&inside % &pk).is_zero() {
            inside /= &pk;
            outside *= &p;
        }
        p += 1;
    }
    if root == 2 || inside.bits() < 64 {
        // A leftover perfect power with a large prime base.
        if let Some(r) = exact_root(&inside, root) {
            outside *= &r;
            inside = BigInt::one();
        }
    }
    (outside, inside)
}

fn exact_root(n: &BigInt, root: u32) -> Option<BigInt> {
    if n.is_negative() {
        return None;
    }
    let r = n.nth_root(root);
    (num_traits::pow(r.clone(), root as usize) == *n).then_some(r)
}

/// Simplifies `q^(a/b)` for a positive rational `q` and a non-integer exponent `a/b`:
/// returns `(c, r)` with `q^(a/b) = c * r^(1/b)`, `c` rational and `r` a positive rational
/// with no perfect `b`-th power left in it (`r` is 1 when the power is exact).
pub fn rational_root(q: &Rational, exponent: &Rational) -> Option<(Rational, Rational)> {
    if !q.is_positive() {
        return None;
    }
    let b = exponent.denom().to_u32()?;
    if b > 64 {
        return None;
    }
    let a = exponent.numer();
    // Write q^(a/b) = (q^a)^(1/b), with q^a = n/d; then (n/d)^(1/b) = (n d^(b-1))^(1/b) / d.
    let qa = pow_int(q, a)?;
    let (n, d) = (qa.numer().clone(), qa.denom().clone());
    let radicand = n * num_traits::pow(d.clone(), (b - 1) as usize);
    let (outside, inside) = split_perfect_power(&radicand, b);
    Some((Rational::new(outside, d), Rational::from_integer(inside)))
}

pub fn is_integer(q: &Rational) -> bool {
    q.is_integer()
}

/// The greatest common divisor of two rationals: gcd of numerators over lcm of denominators,
/// so that both are integer multiples of it. Always positive.
pub fn gcd(a: &Rational, b: &Rational) -> Rational {
    if a.is_zero() {
        return b.abs();
    }
    if b.is_zero() {
        return a.abs();
    }
    Rational::new(a.numer().gcd(b.numer()), a.denom().lcm(b.denom()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_exact() {
        assert_eq!(parse_decimal("0.1"), Some(ratio(1, 10)));
        assert_eq!(parse_decimal("12"), Some(int(12)));
        assert_eq!(parse_decimal("1e-3"), Some(ratio(1, 1000)));
        assert_eq!(parse_decimal("2.5E+4"), Some(int(25000)));
        assert_eq!(parse_decimal("9.81"), Some(ratio(981, 100)));
        assert_eq!(parse_decimal("."), None);
    }

    #[test]
    fn radicals_pull_out_perfect_powers() {
        assert_eq!(rational_root(&int(12), &ratio(1, 2)), Some((int(2), int(3))));
        assert_eq!(rational_root(&int(4), &ratio(1, 2)), Some((int(2), int(1))));
        assert_eq!(rational_root(&ratio(1, 2), &ratio(1, 2)), Some((ratio(1, 2), int(2))));
        assert_eq!(rational_root(&int(8), &ratio(2, 3)), Some((int(4), int(1))));
        assert_eq!(rational_root(&int(3), &ratio(-1, 2)), Some((ratio(1, 3), int(3))));
    }
}
