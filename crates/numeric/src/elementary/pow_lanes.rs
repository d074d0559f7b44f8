//! Eight bases raised to one exponent at once, lane by lane the bits of `libm::pow`.
//!
//! `libm::pow` (musl's, from FreeBSD's msun) first sorts out the special exponents (0, ±1, 2,
//! 1/2, NaN, ±∞, |y| > 2^31) and bases (1, zeros, infinities, NaN, negatives, subnormals).
//! What remains, a positive normal base and an ordinary exponent, takes one path: log2 x in
//! two floats (the mantissa moved into [√(3/4), √3), an odd series in (m − b)/(m + b) about
//! b = 1 or 1.5), y·log2 x in two floats, the nearest integer n split off (halves away from
//! zero), 2^(what is left) by a rational approximation, and n added to the exponent's bits,
//! after checks for a result that overflows or falls below the normal floats. Here every lane
//! runs that path as straight-line code, its branches (the mantissa's interval, whether an
//! integer is split off) turned into masks and selects, each step taken for all eight lanes
//! before the next so that the compiler turns it into vector instructions. Each floating-point
//! operation is the one libm performs, in the same order, on the same constants (rounding to
//! nearest, no fused multiply-add), so each lane gets libm's bits. A lane outside that path
//! (a base that is not positive, normal and finite, or a result beyond 2^±1021, short of
//! where libm's overflow, underflow and subnormal branches begin) is computed again by
//! `libm::pow` alone. A base of exactly 1, for which libm returns 1 early, gives 1 on the
//! straight line too (every term of its logarithm is a zero). An exponent of 1/2 is a square
//! root in libm, and here, lane by lane; any other special exponent sends every lane to libm.

use super::lanes::{lanes, magnitude, mask, masks, pick, Lanes, Masks, TO_INT};
use crate::LANES;

// log2 x's constants, libm's bits: the series' coefficients, 2/(3·ln 2) whole and as a 24-bit
// head and its tail, and log2 1.5 as a head and tail (added where the mantissa is near 1.5).
const L1: f64 = f64::from_bits(0x3FE3_3333_3333_3303);
const L2: f64 = f64::from_bits(0x3FDB_6DB6_DB6F_ABFF);
const L3: f64 = f64::from_bits(0x3FD5_5555_518F_264D);
const L4: f64 = f64::from_bits(0x3FD1_7460_A91D_4101);
const L5: f64 = f64::from_bits(0x3FCD_864A_93C9_DB65);
const L6: f64 = f64::from_bits(0x3FCA_7E28_4A45_4EEF);
const CP: f64 = f64::from_bits(0x3FEE_C709_DC3A_03FD);
const CP_H: f64 = f64::from_bits(0x3FEE_C709_E000_0000);
const CP_L: f64 = f64::from_bits(0xBE3E_2FE0_145B_01F5);
const LOG2_OF_1_5_H: f64 = f64::from_bits(0x3FE2_B803_4000_0000);
const LOG2_OF_1_5_L: f64 = f64::from_bits(0x3E4C_FDEB_43CF_D006);

// 2^r's constants, libm's bits: ln 2 whole and as a head and tail, and the coefficients of the
// rational approximation.
const LG2: f64 = f64::from_bits(0x3FE6_2E42_FEFA_39EF);
const LG2_H: f64 = f64::from_bits(0x3FE6_2E43_0000_0000);
const LG2_L: f64 = f64::from_bits(0xBE20_5C61_0CA8_6C39);
const P1: f64 = f64::from_bits(0x3FC5_5555_5555_553E);
const P2: f64 = f64::from_bits(0xBF66_C16C_16BE_BD93);
const P3: f64 = f64::from_bits(0x3F11_566A_AF25_DE2C);
const P4: f64 = f64::from_bits(0xBEBB_BD41_C5D2_6BF1);
const P5: f64 = f64::from_bits(0x3E66_3769_72BE_A4D0);

// libm compares high words (the upper 32 bits); each threshold is written here as the float
// that starts a range, so that lanes are sorted by float comparisons, which vectorize with
// every instruction set.
/// From: a mantissa (in [1, 2)) past √(3/2), where the series is about 1.5 (high word
/// 0x3FF3988F).
const NEAR_1_5: f64 = f64::from_bits(0x3FF3_988F << 32);
/// From: a mantissa past √3, which libm halves (and adds 1 to the exponent) so that the series
/// is about 1 again (high word 0x3FFBB67A).
const HALVED: f64 = f64::from_bits(0x3FFB_B67A << 32);
/// From: |y·log2 x| whose high word exceeds 0.5's, where libm splits off the nearest integer.
const SPLIT: f64 = f64::from_bits(0x3FE0_0001 << 32);
/// Below: |y·log2 x| whose power is a normal float by libm's last step however it rounds: the
/// exponent n added is at most 1021 in size, to a float in [1/2, 2).
const NORMAL_RESULT: f64 = 1021.0;
/// Up to: the high word of |y| on libm's main path (beyond 2^31 it takes others).
const ORDINARY_EXPONENT: u64 = 0x41E0_0000;

const MANTISSA: u64 = (1 << 52) - 1;
const ONE: u64 = 0x3FF0_0000_0000_0000;
const SIGN: u64 = 1 << 63;

/// `x[i]` to the power `y` in each lane: exactly `libm::pow(x[i], y)` in lane `i`, for every
/// base and exponent.
#[inline(always)]
pub fn pow_lanes(x: &Lanes, y: f64) -> Lanes {
    let (mut power, elsewhere) = if y == 0.5 {
        // libm's square root: for a positive base (and for +0, which goes to libm here with
        // the zeros, whose signs it treats apart).
        (lanes(|i| x[i].sqrt()), masks(|i| !mask(x[i] > 0.0)))
    } else if ordinary(y) {
        main_path(x, y)
    } else {
        return x.map(|base| libm::pow(base, y));
    };
    if elsewhere.iter().fold(0, |any, e| any | e) != 0 {
        for i in (0..LANES).filter(|i| elsewhere[*i] != 0) {
            power[i] = libm::pow(x[i], y);
        }
    }
    power
}

/// Whether libm takes its main path for every positive normal base at exponent `y`: finite,
/// nonzero, none of ±1, 2 and 1/2 (which it computes otherwise), |y| ≤ 2^31 by its high word.
fn ordinary(y: f64) -> bool {
    let size = magnitude(y);
    size.is_finite()
        && size != 0.0
        && size != 1.0
        && y != 2.0
        && y != 0.5
        && size.to_bits() >> 32 <= ORDINARY_EXPONENT
}

/// libm's main path in every lane, and all ones where a lane's base or result is outside it
/// (the lane's value then meaningless). `y` is [`ordinary`].
#[inline(always)]
fn main_path(x: &Lanes, y: f64) -> (Lanes, Masks) {
    let (t1, t2) = log2(x);
    // y·log2 x as p_h + p_l: y split as t1 is, into its high word and the rest.
    let y1 = head(y);
    let p_l = lanes(|i| (y - y1) * t1[i] + y * t2[i]);
    let p_h = lanes(|i| y1 * t1[i]);
    let z = lanes(|i| p_l[i] + p_h[i]);
    let power = exp2(&p_h, &p_l, &z);
    let elsewhere = masks(|i| {
        let normal = mask(x[i] >= f64::MIN_POSITIVE) & mask(x[i] < f64::INFINITY);
        !(normal & mask(magnitude(z[i]) < NORMAL_RESULT))
    });
    (power, elsewhere)
}

/// log2 x as libm's pow forms it, t1 + t2 with t1's low word zero, for positive normal x
/// (elsewhere meaningless).
#[inline(always)]
fn log2(x: &Lanes) -> (Lanes, Lanes) {
    // x = 2^e·m with m in [1, 2); above √3 libm takes m/2 and e + 1. Around 1.5 (`middle`) the
    // series is in (m − 1.5)/(m + 1.5) and log2 1.5 is added back.
    let bits = masks(|i| x[i].to_bits());
    let m = lanes(|i| f64::from_bits((bits[i] & MANTISSA) | ONE));
    let halved = masks(|i| !mask(m[i] < HALVED));
    let middle = masks(|i| !mask(m[i] < NEAR_1_5) & !halved[i]);
    let ax = lanes(|i| pick(halved[i], m[i] * 0.5, m[i]));
    // e as a float, read off the exponent's bits by way of 1.5·2^52, whose ulp is 1.
    let e = lanes(|i| {
        let biased = (bits[i] >> 52).wrapping_add(halved[i] & 1);
        f64::from_bits(TO_INT.to_bits().wrapping_add(biased)) - (TO_INT + 1023.0)
    });
    let b = lanes(|i| pick(middle[i], 1.5, 1.0));
    let dp_h = lanes(|i| pick(middle[i], LOG2_OF_1_5_H, 0.0));
    let dp_l = lanes(|i| pick(middle[i], LOG2_OF_1_5_L, 0.0));
    // s = (m − b)/(m + b) as ss, and as s_h + s_l with s_h its high word.
    let u = lanes(|i| ax[i] - b[i]);
    let v = lanes(|i| 1.0 / (ax[i] + b[i]));
    let ss = lanes(|i| u[i] * v[i]);
    let s_h = lanes(|i| head(ss[i]));
    // m + b's high part, built by libm from m's high word directly.
    let t_h = lanes(|i| {
        let high = ((ax[i].to_bits() >> 33) | 0x2000_0000) + 0x8_0000 + (middle[i] & 0x4_0000);
        f64::from_bits(high << 32)
    });
    let t_l = lanes(|i| ax[i] - (t_h[i] - b[i]));
    let s_l = lanes(|i| v[i] * ((u[i] - s_h[i] * t_h[i]) - s_h[i] * t_l[i]));
    // The series, then 3 + s_h² + r split, times s in two floats.
    let s2 = lanes(|i| ss[i] * ss[i]);
    let r = lanes(|i| {
        let s2 = s2[i];
        s2 * s2 * (L1 + s2 * (L2 + s2 * (L3 + s2 * (L4 + s2 * (L5 + s2 * L6)))))
    });
    let r = lanes(|i| r[i] + s_l[i] * (s_h[i] + ss[i]));
    let s2 = lanes(|i| s_h[i] * s_h[i]);
    let t_h = lanes(|i| head(3.0 + s2[i] + r[i]));
    let t_l = lanes(|i| r[i] - ((t_h[i] - 3.0) - s2[i]));
    let u = lanes(|i| s_h[i] * t_h[i]);
    let v = lanes(|i| s_l[i] * t_h[i] + t_l[i] * ss[i]);
    let p_h = lanes(|i| head(u[i] + v[i]));
    let p_l = lanes(|i| v[i] - (p_h[i] - u[i]));
    // Times 2/(3·ln 2), plus log2 b and e.
    let z_h = lanes(|i| CP_H * p_h[i]);
    let z_l = lanes(|i| CP_L * p_h[i] + p_l[i] * CP + dp_l[i]);
    let t1 = lanes(|i| head(((z_h[i] + z_l[i]) + dp_h[i]) + e[i]));
    let t2 = lanes(|i| z_l[i] - (((t1[i] - e[i]) - dp_h[i]) - z_h[i]));
    (t1, t2)
}

/// 2^(p_h + p_l) as libm's pow forms it, z = p_l + p_h, for |z| < [`NORMAL_RESULT`]
/// (elsewhere meaningless).
#[inline(always)]
fn exp2(p_h: &Lanes, p_l: &Lanes, z: &Lanes) -> Lanes {
    // Where |z| > 1/2 by its high word, libm takes off n, the nearest integer with halves away
    // from zero, from p_h: as floats, the floor of |z| + 1/2 (exact: |z| < 2^10, or the floor
    // is 1) with z's sign. The floor is the nearest integer (by adding and subtracting
    // 1.5·2^52) less 1 where that is above.
    let size = lanes(|i| magnitude(z[i]));
    let up = lanes(|i| size[i] + 0.5);
    let nearest = lanes(|i| (up[i] + TO_INT) - TO_INT);
    let floor = lanes(|i| nearest[i] - pick(mask(nearest[i] > up[i]), 1.0, 0.0));
    let n = lanes(|i| {
        let signed = f64::from_bits(floor[i].to_bits() | (z[i].to_bits() & SIGN));
        pick(mask(size[i] >= SPLIT), signed, 0.0)
    });
    let p_h = lanes(|i| p_h[i] - n[i]);
    // 2^r = e^(r·ln 2) for r = p_h + p_l, r·ln 2 as z + w.
    let t = lanes(|i| head(p_l[i] + p_h[i]));
    let u = lanes(|i| t[i] * LG2_H);
    let v = lanes(|i| (p_l[i] - (t[i] - p_h[i])) * LG2 + t[i] * LG2_L);
    let z = lanes(|i| u[i] + v[i]);
    let w = lanes(|i| v[i] - (z[i] - u[i]));
    let t = lanes(|i| z[i] * z[i]);
    let t1 = lanes(|i| {
        let t = t[i];
        z[i] - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))))
    });
    let r = lanes(|i| (z[i] * t1[i]) / (t1[i] - 2.0) - (w[i] + z[i] * w[i]));
    let power = lanes(|i| 1.0 - (r[i] - z[i]));
    // Times 2^n by adding n to the exponent's bits; n's two's complement is the low bits of
    // n + 1.5·2^52.
    lanes(|i| {
        let n = (n[i] + TO_INT).to_bits().wrapping_sub(TO_INT.to_bits());
        f64::from_bits(power[i].to_bits().wrapping_add(n << 52))
    })
}

/// `v` with its low word cleared: the head libm splits a float into.
#[inline(always)]
fn head(v: f64) -> f64 {
    f64::from_bits(v.to_bits() & !0xFFFF_FFFF)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bases a step-size control meets, and most others, take the straight line rather
    /// than libm: otherwise the tests against libm would hold libm to itself.
    #[test]
    fn error_norms_take_the_straight_line() {
        for y in [-1.0 / 8.0, -1.0 / 5.0, 1.0 / 3.0, -37.1, 1e-3] {
            for call in 0..1000 {
                let x = std::array::from_fn(|lane| {
                    libm::pow(10.0, -6.0 + 12.0 * (call * LANES + lane) as f64 / 8000.0)
                });
                assert!(main_path(&x, y).1.iter().all(|e| *e == 0), "{x:?} ^ {y}");
            }
        }
    }

    /// One call whose lanes take every way: the series about 1 and about 1.5, a halved
    /// mantissa, no integer split off, a base of 1, a subnormal, a negative base, a result past
    /// 2^1021.
    #[test]
    fn one_call_mixes_the_straight_line_and_libm() {
        let x = [0.3, 1.4, 1.9, 1.0 + 1e-9, 1.0, 1e-310, -2.0, 1e-300];
        let y = -3.5;
        let elsewhere = main_path(&x, y).1.map(|e| e != 0);
        assert_eq!(elsewhere, [false, false, false, false, false, true, true, true]);
        let power = pow_lanes(&x, y);
        for i in 0..LANES {
            assert_eq!(power[i].to_bits(), libm::pow(x[i], y).to_bits(), "lane {i}");
        }
    }
}
