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
//! multiply-add), so each lane gets libm's bits. Up to 9π/4 libm's fixed multiple is the
//! nearest one, and its single round is the medium path's. A lane whose argument needs what
//! the straight-line code does not do (a second reduction round, the large-argument reduction,
//! a NaN or an infinity) or lies next to the end of a fixed range (where the fixed multiple
//! may not be the nearest) is computed again by `libm::sincos` alone.

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

// libm's thresholds compare the high 32 bits of |x|; each is written here as the float that
// starts the range (a high word h ≤ H is |x| below the float whose high word is H + 1), so
// that a lane is classified by float comparisons, which vectorize with every instruction set.
/// Below: 2^-27·√2, where sin x = x and cos x = 1 to the bit (high word 0x3E46A09E).
const TINY: f64 = f64::from_bits(0x3E46_A09E << 32);
/// Below: π/4, the kernels' own interval (high words up to 0x3FE921FB).
const PIO4: f64 = f64::from_bits(0x3FE9_21FC << 32);
/// Below: 9π/4, the end of the ranges libm reduces by a fixed multiple of π/2 (1 up to 3π/4,
/// then 2, 3 and 4 up to 5π/4, 7π/4 and 9π/4: high words up to 0x4002D97C, 0x400F6A7A,
/// 0x4015FDBC and 0x401C463B), where the nearest is taken beyond.
const FIXED_END: f64 = f64::from_bits(0x401C_463C << 32);
/// How far from a half-integer x·2/π must be for the nearest multiple of π/2 to be the fixed
/// one: the ends of the fixed ranges are the high words of (2k + 1)·π/4, and a high word spans
/// less than 3·10^-6 of x·2/π below 9π/4.
const SURELY_NEAREST: f64 = 0.5 - 1e-5;
/// From: 2^20·π/2, reduced in multiple precision (high word 0x413921FB).
const LARGE: f64 = f64::from_bits(0x4139_21FB << 32);
/// libm takes a second round when the first leaves y0 more than 16 binades below x.
const CANCELLED: u64 = 16 << 52;
const EXPONENT: u64 = 0x7FF << 52;

/// The sine and cosine of each lane of `x`: exactly `libm::sincos(x[i])` in lane `i`, for
/// every argument, at a fraction of the cost of eight calls.
pub fn sin_cos_lanes(x: &Lanes) -> (Lanes, Lanes) {
    let mut sine = [0.0; LANES];
    let mut cosine = [0.0; LANES];
    let mut elsewhere = [false; LANES];
    for i in 0..LANES {
        (sine[i], cosine[i], elsewhere[i]) = straight_line(x[i]);
    }
    if elsewhere.iter().any(|e| *e) {
        for i in (0..LANES).filter(|i| elsewhere[*i]) {
            (sine[i], cosine[i]) = libm::sincos(x[i]);
        }
    }
    (sine, cosine)
}

/// One lane's sine and cosine as libm computes them below 2^20·π/2 with one reduction round,
/// and whether the lane is one it computes otherwise (a second round, the large reduction,
/// NaN or ±∞) or may (next to the ends of its fixed ranges), whose values here are then
/// meaningless.
#[inline(always)]
fn straight_line(x: f64) -> (f64, f64, bool) {
    let size = f64::from_bits(x.to_bits() & !(1 << 63));
    let alone = mask(size < PIO4);
    let (multiple, ambiguous) = multiple_of_pio2(x, size, alone);
    // x − n·(π/2) in two floats, head and tail: libm's first round.
    let r = x - multiple * PIO2_1;
    let w = multiple * PIO2_1T;
    let y0 = r - w;
    let y1 = (r - y0) - w;
    // libm's test for a second round is on the medium path only; here it is made on the fixed
    // ranges too, which sends libm a few more lanes (those within 2^-16·|x| of a multiple of
    // π/2), among them every lane of the high words near π/2, π, 3π/2 and 2π that libm
    // reduces as the medium path does (the first round cancels 20 binades or more there).
    let floor = f64::from_bits((size.to_bits() & EXPONENT).wrapping_sub(CANCELLED));
    let cancelled = !alone & mask(f64::from_bits(y0.to_bits() & !(1 << 63)) < floor);
    let (s, c) = kernels(y0, y1, alone);
    let (s, c) = rotate(s, c, multiple);
    // Below 2^-27·√2 libm returns x and 1 without the kernels.
    let tiny = mask(size < TINY);
    (pick(tiny, x, s), pick(tiny, 1.0, c), cancelled | ambiguous | !mask(size < LARGE) != 0)
}

/// The multiple of π/2 that libm subtracts from `x`, as a float (none up to π/4, else the
/// nearest, rounded by adding and subtracting 1.5·2^52), and whether the lane must go to libm
/// because this may not be libm's multiple: up to 9π/4 libm takes a fixed one per range, which
/// is the nearest unless x·2/π is within [`SURELY_NEAREST`] of a half-integer.
#[inline(always)]
fn multiple_of_pio2(x: f64, size: f64, alone: u64) -> (f64, u64) {
    let t = x * INV_PIO2;
    let nearest = (t + TO_INT) - TO_INT;
    let off_centre = f64::from_bits((t - nearest).to_bits() & !(1 << 63));
    let ambiguous = mask(size < FIXED_END) & !mask(off_centre < SURELY_NEAREST);
    (pick(alone, 0.0, nearest), ambiguous)
}

/// All ones where `b`, else zero: a lane's condition as a mask for [`pick`].
#[inline(always)]
fn mask(b: bool) -> u64 {
    0u64.wrapping_sub(u64::from(b))
}

/// `a` where `mask` is all ones, `b` where it is zero, by bits: no branch to keep a loop over
/// lanes from vectorizing.
#[inline(always)]
fn pick(mask: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

/// libm's kernels at y0 + y1, |y0| ≲ π/4: the sine's polynomial as `k_sin` evaluates it with
/// a tail (`alone` false) or without one (true, y1 = 0), the cosine's as `k_cos` does.
#[inline(always)]
fn kernels(y0: f64, y1: f64, alone: u64) -> (f64, f64) {
    let z = y0 * y0;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * y0;
    let sine_alone = y0 + v * (S1 + z * r);
    let sine_with_tail = y0 - ((z * (0.5 * y1 - v * r) - y1) - v * S1);
    let sine = pick(alone, sine_alone, sine_with_tail);
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let half = 0.5 * z;
    let w = 1.0 - half;
    let cosine = w + (((1.0 - w) - half) + (z * r - y0 * y1));
    (sine, cosine)
}

/// sin and cos of y + n·π/2 from those of y, by n mod 4: (s, c), (c, −s), (−s, −c), (−c, s);
/// n mod 4 is in the low bits of n + 1.5·2^52 (exact: |n| < 2^20), and the swap and the signs
/// are bit operations, which need no comparison of 64-bit integers to vectorize.
#[inline(always)]
fn rotate(s: f64, c: f64, multiple: f64) -> (f64, f64) {
    let n = (multiple + TO_INT).to_bits();
    let odd = 0u64.wrapping_sub(n & 1);
    let (s, c) = (pick(odd, c, s).to_bits(), pick(odd, s, c).to_bits());
    let sine = s ^ ((n & 2) << 62);
    let cosine = c ^ ((n.wrapping_add(1) & 2) << 62);
    (f64::from_bits(sine), f64::from_bits(cosine))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One call whose lanes take every path: the tiny early return, the kernels alone, a fixed
    /// multiple, the nearest multiple in one round, a second round, the end of a fixed range
    /// (just above 3π/4, where libm subtracts π/2 and not π), the large reduction, NaN.
    #[test]
    fn one_call_mixes_the_straight_line_and_libm() {
        let near_pi = f64::from_bits(std::f64::consts::PI.to_bits() + 1);
        let x = [
            1e-10,
            0.5,
            -2.0,
            100.0,
            near_pi * 2.0,
            f64::from_bits(0x4002_D97C_FFFF_0000),
            1e7,
            f64::NAN,
        ];
        let elsewhere = x.map(|x| straight_line(x).2);
        assert_eq!(elsewhere, [false, false, false, false, true, true, true, true]);
        let (sine, cosine) = sin_cos_lanes(&x);
        for i in 0..LANES {
            let (s, c) = libm::sincos(x[i]);
            assert_eq!((sine[i].to_bits(), cosine[i].to_bits()), (s.to_bits(), c.to_bits()));
        }
    }
}
