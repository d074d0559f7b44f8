//! The sine and cosine of eight arguments at once, lane by lane the bits of `libm::sincos`.
//!
//! `libm::sincos` (musl's, from FreeBSD's msun) branches on the argument's size: an early
//! return below 2^-27·√2, the polynomial kernels alone up to π/4, a reduction by a fixed
//! multiple of π/2 up to 9π/4, a reduction by the nearest multiple (one round, with a second
//! and third when the first cancels too much) up to 2^20·π/2, and a multi-precision one
//! beyond. Here every lane runs the same straight-line code, the one reduction round and both
//! kernels, with the multiple of π/2 and the quadrant chosen per lane by masks. Each step is
//! taken for all eight lanes before the next (an array a step), which the compiler turns into
//! vector instructions with the eight lanes' chains of dependent operations side by side;
//! one lane's whole computation after another's would leave the processor waiting on each
//! chain's latency. Each floating-point operation is the one libm performs, in the same order,
//! on the same constants (rounding to nearest, no fused multiply-add), so each lane gets libm's
//! bits. Up to 9π/4 libm's fixed multiple is the nearest one, and its single round is the
//! medium path's. A lane whose argument needs what the straight-line code does not do (a
//! second reduction round, the large-argument reduction, a NaN or an infinity) or lies next to
//! the end of a fixed range (where the fixed multiple may not be the nearest) is computed again
//! by `libm::sincos` alone.

/// Points per register of the batch tape, and arguments per call here: eight doubles fill two
/// AVX registers or four SSE ones, and a chunk this wide amortizes an instruction's dispatch
/// over enough arithmetic to leave it cheap.
pub const LANES: usize = 8;

pub(super) type Lanes = [f64; LANES];

// The reduction's constants, bit for bit libm's: 2/π to 53 bits, π/2 split as a 33-bit head
// and the tail π/2 − head, and 1.5·2^52, whose addition rounds a float to an integer.
const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
pub(super) const TO_INT: f64 = 1.5 / f64::EPSILON;

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

/// The sine and cosine of each lane of `x`, written into `sine_out` and `cosine_out`: exactly
/// `libm::sincos(x[i])` in lane `i`, for every argument. Written into the caller's arrays
/// rather than returned: the batch tape, copying a returned pair into its registers, ran a
/// program of two sines and cosines and thirty products a tenth slower.
#[inline(always)]
pub fn sin_cos_lanes(x: &Lanes, sine_out: &mut Lanes, cosine_out: &mut Lanes) {
    let (multiple, y0, y1, alone, elsewhere) = reduce(x);
    // libm's kernels at y0 + y1, |y0| ≲ π/4: the sine's polynomial as `k_sin` evaluates it with
    // the tail or, where `alone`, without (the tail is 0 there), the cosine's as `k_cos` does.
    let z = lanes(|i| y0[i] * y0[i]);
    let w = lanes(|i| z[i] * z[i]);
    let r = lanes(|i| S2 + z[i] * (S3 + z[i] * S4) + z[i] * w[i] * (S5 + z[i] * S6));
    let v = lanes(|i| z[i] * y0[i]);
    let sine_alone = lanes(|i| y0[i] + v[i] * (S1 + z[i] * r[i]));
    let sine_with_tail =
        lanes(|i| y0[i] - ((z[i] * (0.5 * y1[i] - v[i] * r[i]) - y1[i]) - v[i] * S1));
    let s = lanes(|i| pick(alone[i], sine_alone[i], sine_with_tail[i]));
    let r = lanes(|i| {
        z[i] * (C1 + z[i] * (C2 + z[i] * C3)) + w[i] * w[i] * (C4 + z[i] * (C5 + z[i] * C6))
    });
    let half = lanes(|i| 0.5 * z[i]);
    let w = lanes(|i| 1.0 - half[i]);
    let c = lanes(|i| w[i] + (((1.0 - w[i]) - half[i]) + (z[i] * r[i] - y0[i] * y1[i])));
    // sin and cos of y + n·π/2 from those of y by n mod 4: (s, c), (c, −s), (−s, −c), (−c, s).
    // n mod 4 is in the low bits of n + 1.5·2^52 (exact: |n| < 2^20); the swap and the signs
    // are bit operations, which need no comparison of 64-bit integers to vectorize.
    let n = masks(|i| (multiple[i] + TO_INT).to_bits());
    let odd = masks(|i| 0u64.wrapping_sub(n[i] & 1));
    let flip = |v: f64, sign: u64| f64::from_bits(v.to_bits() ^ sign);
    let mut sine = lanes(|i| flip(pick(odd[i], c[i], s[i]), (n[i] & 2) << 62));
    let mut cosine = lanes(|i| flip(pick(odd[i], s[i], c[i]), (n[i].wrapping_add(1) & 2) << 62));
    // Below 2^-27·√2 libm returns x and 1 without the kernels. The cosine's kernel gives 1
    // there too (x²/2 is below half an ulp of 1), but the sine's would turn −0 into +0.
    sine = lanes(|i| pick(mask(magnitude(x[i]) < TINY), x[i], sine[i]));
    if elsewhere.iter().fold(0, |any, e| any | e) != 0 {
        for i in (0..LANES).filter(|i| elsewhere[*i] != 0) {
            (sine[i], cosine[i]) = libm::sincos(x[i]);
        }
    }
    *sine_out = sine;
    *cosine_out = cosine;
}

/// Each lane's argument less a multiple n of π/2 as libm's first round leaves it: n as a
/// float, the head y0 and the tail y1; where |x| ≲ π/4 (`alone`, all ones) n = 0 and the
/// tail is 0; and all ones where libm computes otherwise (a second round, the large
/// reduction, NaN or ±∞) or may (next to the ends of its fixed ranges), where the lane's
/// values here are meaningless.
#[inline(always)]
fn reduce(x: &Lanes) -> (Lanes, Lanes, Lanes, Masks, Masks) {
    let size = lanes(|i| magnitude(x[i]));
    let alone = masks(|i| mask(size[i] < PIO4));
    // The nearest multiple, rounded by adding and subtracting 1.5·2^52. Up to 9π/4 libm takes
    // a fixed one per range instead, which is the nearest unless x·2/π is within
    // [`SURELY_NEAREST`] of a half-integer.
    let t = lanes(|i| x[i] * INV_PIO2);
    let nearest = lanes(|i| (t[i] + TO_INT) - TO_INT);
    let ambiguous =
        masks(|i| mask(size[i] < FIXED_END) & !mask(magnitude(t[i] - nearest[i]) < SURELY_NEAREST));
    let multiple = lanes(|i| pick(alone[i], 0.0, nearest[i]));
    // x − n·(π/2) in two floats: libm's first round.
    let r = lanes(|i| x[i] - multiple[i] * PIO2_1);
    let w = lanes(|i| multiple[i] * PIO2_1T);
    let y0 = lanes(|i| r[i] - w[i]);
    let y1 = lanes(|i| (r[i] - y0[i]) - w[i]);
    // libm's test for a second round is on the medium path only; here it is made on the fixed
    // ranges too, which sends libm a few more lanes (those within 2^-16·|x| of a multiple of
    // π/2), among them every lane of the high words near π/2, π, 3π/2 and 2π that libm reduces
    // as the medium path does (the first round cancels 20 binades or more there).
    let floor = lanes(|i| f64::from_bits((size[i].to_bits() & EXPONENT).wrapping_sub(CANCELLED)));
    let elsewhere = masks(|i| {
        let cancelled = !alone[i] & mask(magnitude(y0[i]) < floor[i]);
        cancelled | ambiguous[i] | !mask(size[i] < LARGE)
    });
    (multiple, y0, y1, alone, elsewhere)
}

pub(super) type Masks = [u64; LANES];

/// One step for every lane.
#[inline(always)]
pub(super) fn lanes(step: impl Fn(usize) -> f64) -> Lanes {
    std::array::from_fn(step)
}

/// One step for every lane, of masks or bits.
#[inline(always)]
pub(super) fn masks(step: impl Fn(usize) -> u64) -> Masks {
    std::array::from_fn(step)
}

/// |v|, by clearing the sign bit.
#[inline(always)]
pub(super) fn magnitude(v: f64) -> f64 {
    f64::from_bits(v.to_bits() & !(1 << 63))
}

/// All ones where `b`, else zero: a lane's condition as a mask for [`pick`].
#[inline(always)]
pub(super) fn mask(b: bool) -> u64 {
    0u64.wrapping_sub(u64::from(b))
}

/// `a` where `mask` is all ones, `b` where it is zero, by bits: no branch to keep the lanes
/// from vectorizing.
#[inline(always)]
pub(super) fn pick(mask: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
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
        let elsewhere = reduce(&x).4.map(|e| e != 0);
        assert_eq!(elsewhere, [false, false, false, false, true, true, true, true]);
        let (mut sine, mut cosine) = ([0.0; LANES], [0.0; LANES]);
        sin_cos_lanes(&x, &mut sine, &mut cosine);
        for i in 0..LANES {
            let (s, c) = libm::sincos(x[i]);
            assert_eq!((sine[i].to_bits(), cosine[i].to_bits()), (s.to_bits(), c.to_bits()));
        }
    }
}
