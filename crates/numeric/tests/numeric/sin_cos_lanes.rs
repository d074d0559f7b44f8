//! `sin_cos_lanes` against `libm` bit for bit, lane by lane: dense sweeps over the angles a
//! scene meets and every decade up to 1e300, the bits on either side of each threshold in
//! libm's code, and calls whose lanes take different paths.

use crate::common;

use common::{special_values, Numbers};
use numeric::elementary::sin_cos_lanes;
use numeric::LANES;

/// Every argument, eight a call, against `libm::sincos`, `libm::sin` and `libm::cos`; the
/// last call's spare lanes repeat its first argument. Panics with the first few mismatches.
fn check(args: &[f64]) {
    let mut wrong = Vec::new();
    for chunk in args.chunks(LANES) {
        let mut x = [chunk[0]; LANES];
        x[..chunk.len()].copy_from_slice(chunk);
        let (mut sine, mut cosine) = ([0.0; LANES], [0.0; LANES]);
        sin_cos_lanes(&x, &mut sine, &mut cosine);
        for (lane, &a) in x.iter().enumerate() {
            let (s, c) = libm::sincos(a);
            let want = [s, c, libm::sin(a), libm::cos(a)].map(f64::to_bits);
            let got = [sine[lane], cosine[lane], sine[lane], cosine[lane]].map(f64::to_bits);
            if got != want && wrong.len() < 5 {
                wrong.push(format!(
                    "lane {lane} x = {a:e} ({:#018x}): {got:x?} ≠ {want:x?}",
                    a.to_bits()
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{} checked:\n{}", args.len(), wrong.join("\n"));
}

/// Arguments per sweep; optimised builds (numeric's tests are, by the workspace's profile)
/// take the full count in about a second.
const SWEEP: usize = 2_000_000;

#[test]
fn a_dense_sweep_of_angles_gives_libms_bits() {
    let mut numbers = Numbers(0x5EED_0001);
    let uniform: Vec<f64> = (0..SWEEP).map(|_| (numbers.unit() * 2.0 - 1.0) * 1e4).collect();
    check(&uniform);
    // A regular grid over [−20, 20], offset by an irrational fraction of its step so that no
    // point falls on a multiple of π/2 by construction.
    let step = 40.0 / SWEEP as f64;
    let offset = step * (std::f64::consts::SQRT_2 - 1.0);
    let grid: Vec<f64> = (0..SWEEP).map(|k| -20.0 + offset + k as f64 * step).collect();
    check(&grid);
}

#[test]
fn every_decade_up_to_1e300_gives_libms_bits() {
    let mut numbers = Numbers(0x5EED_0002);
    let per_decade = SWEEP / 350;
    let args: Vec<f64> = (-40..300)
        .flat_map(|decade| (0..per_decade).map(move |k| (decade, k)))
        .map(|(decade, _)| {
            let magnitude = libm::pow(10.0, decade as f64 + numbers.unit());
            if numbers.next() & 1 == 1 {
                -magnitude
            } else {
                magnitude
            }
        })
        .collect();
    check(&args);
}

/// The high words libm compares |x| with: 2^-27·√2, 2^-26 (sin's own early return), π/4, 3π/4,
/// 5π/4, 7π/4, 9π/4, π/2, π, 3π/2, 2π (where the fixed reduction gives way to the nearest
/// multiple), 2^20·π/2, and ∞.
const THRESHOLDS: [u32; 14] = [
    0x3E46_A09E,
    0x3E50_0000,
    0x3FE9_21FB,
    0x4002_D97C,
    0x400F_6A7A,
    0x4015_FDBC,
    0x401C_463B,
    0x3FF9_21FB,
    0x4009_21FB,
    0x4012_D97C,
    0x4019_21FB,
    0x4139_21FB,
    0x7FEF_FFFF,
    0x7FF0_0000,
];

/// The floats on either side of each threshold, at both ends of its high word and of the
/// neighbouring ones, of either sign.
fn around_thresholds() -> Vec<f64> {
    let lows = [0, 1, 0x5440_0000, 0x7FFF_FFFF, 0x8000_0000, 0xFFFF_FFFE, 0xFFFF_FFFF];
    let mut args = Vec::new();
    for high in THRESHOLDS {
        for high in [high - 1, high, high + 1] {
            for low in lows {
                let bits = (u64::from(high) << 32) | low;
                args.extend([f64::from_bits(bits), -f64::from_bits(bits)]);
            }
        }
    }
    args
}

/// The floats within a few ulps of k·π/2, where the first round cancels and libm takes a
/// second or third: every k up to 4,096 and scattered ones up to 2^20, and of either sign.
fn near_multiples_of_pio2() -> Vec<f64> {
    let mut numbers = Numbers(0x5EED_0003);
    let ks = (1..=4096u64).chain((0..4096).map(|_| numbers.next() % (1 << 20) + 1));
    let mut args = Vec::new();
    for k in ks {
        let centre = (k as f64 * std::f64::consts::FRAC_PI_2).to_bits();
        for bits in centre - 4..=centre + 4 {
            args.extend([f64::from_bits(bits), -f64::from_bits(bits)]);
        }
    }
    args
}

/// Random floats in the high words of each threshold and its neighbours, and many in the first
/// word of the large reduction: there libm's first round would almost always give the same
/// bits as the multi-precision reduction, and only a dense sample tells them apart.
fn within_threshold_words() -> Vec<f64> {
    let mut numbers = Numbers(0x5EED_0005);
    let mut args = Vec::new();
    for high in THRESHOLDS {
        let count = if high == 0x4139_21FB { 1 << 16 } else { 2048 };
        for high in [high - 1, high, high + 1] {
            for _ in 0..count {
                let bits = (u64::from(high) << 32) | (numbers.next() >> 32);
                args.push(f64::from_bits(bits | (numbers.next() << 63)));
            }
        }
    }
    args
}

/// Arguments whose first reduction round cancels about l bits of their exponent, l = 8 to 60,
/// densely about 17 (where libm takes a second round, and the first would give other bits
/// about once in 2^15): k·π/2 − d with |d| ≈ 2^-l·k·π/2 < π/4, so k is the nearest multiple.
fn cancelling_by_degrees() -> Vec<f64> {
    let mut numbers = Numbers(0x5EED_0006);
    let mut args = Vec::new();
    for l in 8..=60 {
        let count = if (15..=19).contains(&l) { 1 << 17 } else { 2048 };
        let largest_k = 1u64 << (l - 2).min(20);
        for _ in 0..count {
            let k = (numbers.next() % largest_k + 1) as f64;
            let centre = k * std::f64::consts::FRAC_PI_2;
            let d = centre * libm::pow(2.0, -(l as f64) - numbers.unit()) * 1.5;
            args.push(if numbers.next() & 1 == 1 { -(centre + d) } else { centre - d });
        }
    }
    args
}

#[test]
fn libms_thresholds_and_special_values_give_its_bits() {
    check(&around_thresholds());
    check(&within_threshold_words());
    check(&near_multiples_of_pio2());
    check(&cancelling_by_degrees());
    check(&special_values());
}

/// The same arguments dealt out so that every call mixes the straight-line lanes with the
/// ones libm computes alone, each kind in every lane position.
#[test]
fn calls_that_mix_paths_give_libms_bits() {
    let kinds = [around_thresholds(), near_multiples_of_pio2(), special_values()];
    let mut numbers = Numbers(0x5EED_0004);
    let angles: Vec<f64> = (0..4096).map(|_| (numbers.unit() - 0.5) * 20.0).collect();
    let huge: Vec<f64> = (0..4096).map(|_| libm::pow(10.0, 7.0 + 290.0 * numbers.unit())).collect();
    let pools = [&kinds[0], &kinds[1], &kinds[2], &angles, &huge];
    let mut mixed = Vec::new();
    for call in 0..20_000 {
        for lane in 0..LANES {
            let pool = pools[(call + lane) % pools.len()];
            mixed.push(pool[(call * 7 + lane * 13) % pool.len()]);
        }
    }
    check(&mixed);
}
