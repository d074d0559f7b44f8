//! The sine and cosine of eight arguments at once, lane by lane the bits of `libm::sincos`.
//!
//! `libm::sincos` (musl's, from FreeBSD's msun) branches on the argument's size: an early
//! return below 2^-27·√2, the polynomial kernels alone up to π/4, a reduction by a fixed
//! multiple of π/2 up to 9π/4, a reduction by the nearest multiple (one round, with a second
//! and third when the first cancels too much) up to 2^20·π/2, and a multi-precision one
//! beyond. Here every lane runs the same straight-line code, the one reduction round and both
//! kernels, with the multiple of π/2 and the quadrant chosen per lane by masks, so the loops
//! over lanes compile to vector instructions. Each floating-point operation is the one libm
//! performs, in the same order, on the same constants (rounding to nearest, no fused
//! multiply-add), so each lane gets libm's bits. A lane whose argument needs what the
//! straight-line code does not do (a second reduction round, the large-argument reduction, a
//! NaN or an infinity) is computed again by `libm::sincos` alone.

use crate::batch::LANES;

type Lanes = [f64; LANES];

// The reduction's constants, bit for bit libm's: 2/π to 53 bits, π/2 split as a 33-bit head
// and the tail π/2 − head, and 1.5·2^52, whose addition rounds a float to an integer.
const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
const TO_INT: f64 = 1.5 / f64::EPSILON;

// The kernels' minimax coefficients on [−π/4, π/4], libm's bits.
const S1: f64 = f64::from_bits(0xBFC5_5555_5555_5549);
const S2: f64 = f64::from_bits(0x3F81_1111_1110_F8A6);
const S3: f64 = f64::from_bits(0xBF2A_01A0_19C1_61D5);
const S4: f64 = f64::from_bits(0x3EC7_1DE3_57B1_FE7D);
const S5: f64 = f64::from_bits(0xBE5A_E5E6_8A2B_9CEB);
const S6: f64 = f64::from_bits(0x3DE5_D93A_5ACF_D57C);
const C1: f64 = f64::from_bits(0x3FA5_5555_5555_554C);
const C2: f64 = f64::from_bits(0xBF56_C16C_16C1_5177);
const C3: f64 = f64::from_bits(0x3EFA_01A0_19CB_1590);
const C4: f64 = f64::from_bits(0xBE92_7E4F_809C_52AD);
const C5: f64 = f64::from_bits(0x3E21_EE9E_BDB4_B1C4);
const C6: f64 = f64::from_bits(0xBDA8_FAE9_BE88_38D4);

// libm's thresholds, on the high 32 bits of |x| (so each stands for a range of 2^32 floats;
// the bits matter, not the value they round to).
/// Below: 2^-27·√2, where sin x = x and cos x = 1 to the bit.
const TINY: u32 = 0x3E46_A09E;
/// Up to: π/4, the kernels' own interval.
const PIO4: u32 = 0x3FE9_21FB;
/// Up to: 3π/4, 5π/4, 7π/4 and 9π/4, the ranges reduced by a fixed multiple of π/2.
const FIXED_MULTIPLE_ENDS: [u32; 4] = [0x4002_D97C, 0x400F_6A7A, 0x4015_FDBC, 0x401C_463B];
/// Within the fixed ranges: π/2, π, 3π/2 and 2π, where the fixed reduction would cancel and
/// libm reduces by the nearest multiple instead.
const NEAR_MULTIPLES: [u32; 4] = [0x3FF9_21FB, 0x4009_21FB, 0x4012_D97C, 0x4019_21FB];
/// From: 2^20·π/2, reduced in multiple precision.
const LARGE: u32 = 0x4139_21FB;
/// A first reduction round that loses more than this many bits of exponent takes a second.
const CANCELLED: i32 = 16;

/// The sine and cosine of each lane of `x`: exactly `libm::sincos(x[i])` in lane `i`, for
/// every argument, at a fraction of the cost of eight calls.
pub fn sin_cos_lanes(x: &Lanes) -> (Lanes, Lanes) {
    let reduction = Reduction::of(x);
    let mut sine = [0.0; LANES];
    let mut cosine = [0.0; LANES];
    for i in 0..LANES {
        let (s, c) = kernels(reduction.head[i], reduction.tail[i], reduction.kernel_alone[i]);
        let (s, c) = rotate(s, c, reduction.quadrant[i]);
        // Below 2^-27·√2 libm returns x and 1 without the kernels.
        let tiny = reduction.tiny[i];
        sine[i] = if tiny { x[i] } else { s };
        cosine[i] = if tiny { 1.0 } else { c };
    }
    if reduction.elsewhere.iter().any(|e| *e) {
        for i in (0..LANES).filter(|i| reduction.elsewhere[*i]) {
            (sine[i], cosine[i]) = libm::sincos(x[i]);
        }
    }
    (sine, cosine)
}

/// Each lane's argument less a multiple n of π/2 as libm's first round leaves it, head and
/// tail, with n mod 4 and what the lane needs besides.
struct Reduction {
    head: Lanes,
    tail: Lanes,
    quadrant: [u64; LANES],
    /// |x| ≲ π/4: n = 0, no tail, and the sine's kernel in its form without one.
    kernel_alone: [bool; LANES],
    /// |x| < 2^-27·√2.
    tiny: [bool; LANES],
    /// The lanes libm computes otherwise: a second round, the large reduction, NaN or ±∞.
    elsewhere: [bool; LANES],
}

impl Reduction {
    #[inline(always)]
    fn of(x: &Lanes) -> Reduction {
        let mut reduction = Reduction {
            head: [0.0; LANES],
            tail: [0.0; LANES],
            quadrant: [0; LANES],
            kernel_alone: [false; LANES],
            tiny: [false; LANES],
            elsewhere: [false; LANES],
        };
        for i in 0..LANES {
            let high = high_word(x[i]);
            let multiple = multiple_of_pio2(x[i], high);
            let r = x[i] - multiple * PIO2_1;
            let w = multiple * PIO2_1T;
            let y0 = r - w;
            reduction.head[i] = y0;
            reduction.tail[i] = (r - y0) - w;
            // n mod 4 from the low bits of n + 1.5·2^52 (exact: |n| < 2^20).
            reduction.quadrant[i] = (multiple + TO_INT).to_bits() & 3;
            reduction.kernel_alone[i] = high <= PIO4;
            reduction.tiny[i] = high < TINY;
            let by_nearest = high > FIXED_MULTIPLE_ENDS[3] || NEAR_MULTIPLES.contains(&high);
            let lost = (high >> 20) as i32 - ((y0.to_bits() >> 52) & 0x7FF) as i32;
            reduction.elsewhere[i] = high >= LARGE || (by_nearest && lost > CANCELLED);
        }
        reduction
    }
}

/// The high 32 bits of |x|, which libm's thresholds compare.
#[inline(always)]
fn high_word(x: f64) -> u32 {
    (x.to_bits() >> 32) as u32 & 0x7FFF_FFFF
}

/// The multiple of π/2 that libm subtracts from `x`, as a float: none up to π/4; a fixed one
/// per range up to 9π/4 but near π/2, π, 3π/2 and 2π; beyond, and near those, the nearest,
/// rounded by adding and subtracting 1.5·2^52.
#[inline(always)]
fn multiple_of_pio2(x: f64, high: u32) -> f64 {
    let nearest = (x * INV_PIO2 + TO_INT) - TO_INT;
    let fixed = 1.0 + FIXED_MULTIPLE_ENDS[..3].iter().filter(|end| high > **end).count() as f64;
    let fixed = if x.is_sign_negative() { -fixed } else { fixed };
    if high <= PIO4 {
        0.0
    } else if high <= FIXED_MULTIPLE_ENDS[3] && !NEAR_MULTIPLES.contains(&high) {
        fixed
    } else {
        nearest
    }
}

/// libm's kernels at y0 + y1, |y0| ≲ π/4: the sine's polynomial as `k_sin` evaluates it with
/// a tail (`alone` false) or without one (true, y1 = 0), the cosine's as `k_cos` does.
#[inline(always)]
fn kernels(y0: f64, y1: f64, alone: bool) -> (f64, f64) {
    let z = y0 * y0;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * y0;
    let sine_alone = y0 + v * (S1 + z * r);
    let sine_with_tail = y0 - ((z * (0.5 * y1 - v * r) - y1) - v * S1);
    let sine = if alone { sine_alone } else { sine_with_tail };
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let half = 0.5 * z;
    let w = 1.0 - half;
    let cosine = w + (((1.0 - w) - half) + (z * r - y0 * y1));
    (sine, cosine)
}

/// sin and cos of y + n·π/2 from those of y, by n mod 4: (s, c), (c, −s), (−s, −c), (−c, s).
#[inline(always)]
fn rotate(s: f64, c: f64, quadrant: u64) -> (f64, f64) {
    let (s, c) = if quadrant & 1 == 1 { (c, s) } else { (s, c) };
    let sine = if quadrant & 2 == 2 { -s } else { s };
    let cosine = if quadrant == 1 || quadrant == 2 { -c } else { c };
    (sine, cosine)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One call whose lanes take every path: the tiny early return, the kernels alone, a fixed
    /// multiple, the nearest multiple in one round, a second round, the large reduction, NaN.
    #[test]
    fn one_call_mixes_the_straight_line_and_libm() {
        let near_pi = f64::from_bits(std::f64::consts::PI.to_bits() + 1);
        let x = [1e-10, 0.5, -2.0, 100.0, near_pi * 2.0, 1e7 * std::f64::consts::PI, 1e9, f64::NAN];
        let reduction = Reduction::of(&x);
        assert_eq!(reduction.tiny, [true, false, false, false, false, false, false, false]);
        assert_eq!(reduction.kernel_alone[..3], [true, true, false]);
        let elsewhere = [false, false, false, false, true, true, true, true];
        assert_eq!(reduction.elsewhere, elsewhere);
        let (sine, cosine) = sin_cos_lanes(&x);
        for i in 0..LANES {
            let (s, c) = libm::sincos(x[i]);
            assert_eq!((sine[i].to_bits(), cosine[i].to_bits()), (s.to_bits(), c.to_bits()));
        }
    }
}
