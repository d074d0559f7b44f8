//! `pow_lanes` against `libm::pow` bit for bit, lane by lane: the error norms a step-size
//! control raises to −1/8 and −1/5, every decade of the floats, the bases near 1, the floats
//! about each of libm's thresholds (the mantissa's intervals, the nearest integer split off,
//! the ends of the normal results), powers of two (whose logarithms are exact, so that y·log2 x
//! falls on halves), zeros, subnormals, negatives, infinities and NaNs, each at a dozen
//! exponents and the special ones, and calls whose lanes take different paths.

use crate::common;

use common::{special_values, Numbers};
use numeric::elementary::pow_lanes;
use numeric::LANES;

/// The exponents every set of bases is raised to: the step-size controls' (DOP853's and
/// dopri5's), a square root, and others of either sign, with and without low bits.
const EXPONENTS: [f64; 8] = [-1.0 / 8.0, -1.0 / 5.0, 0.5, 1.0 / 3.0, -2.5, 7.25, 1e-3, -37.1];

/// Every base, eight a call, to the power `y` against `libm::pow`; the last call's spare lanes
/// repeat its first base. Panics with the first few mismatches.
fn check(bases: &[f64], y: f64) {
    let mut wrong = Vec::new();
    for chunk in bases.chunks(LANES) {
        let mut x = [chunk[0]; LANES];
        x[..chunk.len()].copy_from_slice(chunk);
        let power = pow_lanes(&x, y);
        for (lane, &base) in x.iter().enumerate() {
            let (got, want) = (power[lane].to_bits(), libm::pow(base, y).to_bits());
            if got != want && wrong.len() < 5 {
                wrong.push(format!(
                    "lane {lane}: {base:e} ({:#018x}) ^ {y:e}: {got:#018x} ≠ {want:#018x}",
                    base.to_bits()
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{} checked:\n{}", bases.len(), wrong.join("\n"));
}

/// `check` at each of the [`EXPONENTS`].
fn check_every_exponent(bases: &[f64]) {
    for y in EXPONENTS {
        check(bases, y);
    }
}

/// Bases spread evenly in logarithm over [10^lo, 10^hi).
fn log_uniform(numbers: &mut Numbers, count: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..count).map(|_| libm::pow(10.0, lo + (hi - lo) * numbers.unit())).collect()
}

/// Bases per sweep at the step-size controls' exponents; optimised builds (numeric's tests
/// are, by the workspace's profile) check them in well under a second.
const SWEEP: usize = 2_000_000;

#[test]
fn error_norms_to_the_step_size_controls_exponents_give_libms_bits() {
    let mut numbers = Numbers(0x9017_0001);
    let norms = log_uniform(&mut numbers, SWEEP, -6.0, 6.0);
    check(&norms, -1.0 / 8.0);
    check(&norms, -1.0 / 5.0);
    // A regular grid over (0, 4], where most accepted and rejected steps' norms fall.
    let step = 4.0 / SWEEP as f64;
    let grid: Vec<f64> = (1..=SWEEP).map(|k| k as f64 * step).collect();
    check(&grid, -1.0 / 8.0);
    check(&grid, -1.0 / 5.0);
    check_every_exponent(&norms[..SWEEP / 8]);
}

#[test]
fn every_decade_of_the_floats_gives_libms_bits() {
    let mut numbers = Numbers(0x9017_0002);
    let per_decade = 600;
    let mut bases = Vec::new();
    for decade in -308..308 {
        bases.extend(log_uniform(
            &mut numbers,
            per_decade,
            f64::from(decade),
            f64::from(decade + 1),
        ));
    }
    check_every_exponent(&bases);
}

/// The floats within a thousand ulps of 1 on either side, and scattered ones 2^-l away for l
/// up to 52, where log2 x is small and its low bits matter most.
fn near_one() -> Vec<f64> {
    let mut numbers = Numbers(0x9017_0003);
    let one = 1f64.to_bits();
    let mut bases: Vec<f64> = (one - 1000..=one + 1000).map(f64::from_bits).collect();
    for l in 1..=52 {
        for _ in 0..200 {
            let d = libm::pow(2.0, -f64::from(l) - numbers.unit());
            bases.extend([1.0 + d, 1.0 - d]);
        }
    }
    bases
}

/// The mantissas' high words at which libm's pow changes interval (after √(3/2) and from √3)
/// and at the ends of a binade, each with low words at either end and in the middle, at
/// exponents from the smallest normal to the largest.
fn around_thresholds() -> Vec<f64> {
    let highs = [0x3988D, 0x3988E, 0x3988F, 0xBB679, 0xBB67A, 0xBB67B, 0, 1, 0xFFFFE, 0xFFFFF];
    let lows = [0, 1, 0x8000_0000, 0xFFFF_FFFE, 0xFFFF_FFFF];
    let mut bases = Vec::new();
    for exponent in (1..2047).step_by(9).chain([1, 2, 1022, 1023, 1024, 2045, 2046]) {
        for high in highs {
            for low in lows {
                let bits = (exponent << 52) | (high << 32) | low;
                bases.push(f64::from_bits(bits));
            }
        }
    }
    bases
}

/// `count` random bases in the mantissas' high word `high`, at random exponents.
fn within_word(numbers: &mut Numbers, high: u64, count: usize) -> Vec<f64> {
    (0..count)
        .map(|_| {
            let exponent = 1 + numbers.next() % 2046;
            f64::from_bits((exponent << 52) | (high << 32) | (numbers.next() >> 32))
        })
        .collect()
}

/// Random bases in the mantissas' high words on either side of libm's two interval
/// thresholds.
fn within_threshold_words() -> Vec<f64> {
    let mut numbers = Numbers(0x9017_0006);
    let words = [0x3988E, 0x3988F, 0xBB679, 0xBB67A];
    words.iter().flat_map(|high| within_word(&mut numbers, *high, 16_384)).collect()
}

/// Which side of an interval threshold a base is taken on changes the bits only now and then:
/// with the threshold at √3 moved one high word on, about one base in 870,000 of that word
/// (one in 170,000 for the one at √(3/2)). Only a dense sample of the words on either side
/// tells the sides apart.
#[test]
fn the_words_on_either_side_of_an_interval_threshold_give_libms_bits() {
    let mut numbers = Numbers(0x9017_0007);
    for (high, count) in
        [(0x3988E, 1 << 20), (0x3988F, 1 << 20), (0xBB679, 1 << 22), (0xBB67A, 1 << 22)]
    {
        check(&within_word(&mut numbers, high, count), -1.0 / 8.0);
    }
}

/// Bases whose y·log2 x lies within a few ulps of `targets`: 2^(c/y), and its neighbours.
fn where_the_product_is(y: f64, targets: &[f64]) -> Vec<f64> {
    let mut bases = Vec::new();
    for c in targets {
        let centre = libm::pow(2.0, c / y);
        if centre.is_finite() && centre > 0.0 {
            let bits = centre.to_bits();
            bases.extend((bits.saturating_sub(8)..=bits + 8).map(f64::from_bits));
        }
    }
    bases
}

/// Where libm's path turns: y·log2 x about ±1/2 (the nearest integer split off or not), about
/// every half-integer up to 30 (rounded away from zero), about ±1021 and ±1022 (the end of
/// the straight-line lanes here), and about 1024 and −1075 (libm's overflow and underflow).
fn product_targets() -> Vec<f64> {
    let mut targets = vec![0.5, -0.5, 1021.0, -1021.0, 1022.0, -1022.0, 1024.0, -1075.0];
    targets.extend((-60..=60).map(|k| f64::from(k) * 0.5));
    targets.extend([0.499_999, 0.500_001, -0.499_999, -0.500_001]);
    targets
}

/// Every power of two, normal and subnormal: log2 x is exact, so y·log2 x often falls exactly
/// on a half-integer, where libm rounds away from zero.
fn powers_of_two() -> Vec<f64> {
    (-1074..1024).map(|e| libm::pow(2.0, f64::from(e))).collect()
}

/// The special floats (zeros, subnormals, the ends of the normal floats, infinities, NaNs),
/// ±1 and negatives.
fn special_bases() -> Vec<f64> {
    let mut bases = special_values();
    bases.extend([1.0, -1.0, -0.5, -2.0, -1e300, -3.0]);
    bases
}

/// Exponents libm treats apart (0, ±1, 2, 1/2, integers, NaN, ±∞, the ends of its ordinary
/// range about 2^31) or that are extreme.
fn special_exponents() -> Vec<f64> {
    let mut ys = vec![0.0, -0.0, 1.0, -1.0, 2.0, -2.0, -0.5, 3.0, 4.0, -7.0, 1e-300, 5e-324];
    ys.extend([f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e10, -1e10, 1e300]);
    let two_31 = (1u64 << 31) as f64;
    for y in [two_31, f64::from_bits(two_31.to_bits() + 1), f64::from_bits(0x41E0_0001 << 32)] {
        ys.extend([y, -y, f64::from_bits(y.to_bits() - 1)]);
    }
    ys
}

#[test]
fn libms_thresholds_and_special_values_give_its_bits() {
    check_every_exponent(&near_one());
    check_every_exponent(&around_thresholds());
    check_every_exponent(&within_threshold_words());
    check_every_exponent(&powers_of_two());
    check_every_exponent(&special_bases());
    for y in EXPONENTS {
        check(&where_the_product_is(y, &product_targets()), y);
    }
}

#[test]
fn special_exponents_give_libms_bits() {
    let mut numbers = Numbers(0x9017_0004);
    let mut bases = special_bases();
    bases.extend(near_one());
    bases.extend(log_uniform(&mut numbers, 4096, -300.0, 300.0));
    bases.extend(log_uniform(&mut numbers, 4096, -6.0, 6.0));
    for y in special_exponents() {
        check(&bases, y);
    }
}

/// The same bases dealt out so that every call mixes the straight-line lanes with the ones
/// libm computes alone, each kind in every lane position.
#[test]
fn calls_that_mix_paths_give_libms_bits() {
    let mut numbers = Numbers(0x9017_0005);
    let norms = log_uniform(&mut numbers, 4096, -6.0, 6.0);
    let kinds = [special_bases(), near_one(), around_thresholds(), powers_of_two(), norms];
    let mut mixed = Vec::new();
    for call in 0..20_000 {
        for lane in 0..LANES {
            let kind = &kinds[(call + lane) % kinds.len()];
            mixed.push(kind[(call * 7 + lane * 13) % kind.len()]);
        }
    }
    check_every_exponent(&mixed);
}
