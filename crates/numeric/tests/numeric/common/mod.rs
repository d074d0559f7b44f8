//! What the tests of the lane functions share: a generator of the same arguments every run,
//! and the special floats.

/// A fixed-seed generator (SplitMix64), so every run checks the same arguments.
pub struct Numbers(pub u64);

impl Numbers {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Zeros, subnormals, the smallest normal, the largest floats, infinities and NaNs (quiet,
/// negative, signalling, with a payload).
pub fn special_values() -> Vec<f64> {
    let nans = [0x7FF8_0000_0000_0000, 0xFFF8_0000_0000_0000, 0x7FF0_0000_0000_0001];
    let mut values = vec![0.0, -0.0, 5e-324, -5e-324, 1e-310, -2.2e-308, f64::MIN_POSITIVE];
    values.extend([f64::MAX, f64::MIN, f64::INFINITY, f64::NEG_INFINITY]);
    values.extend(nans.iter().chain(&[0x7FFC_0000_DEAD_BEEF]).map(|b| f64::from_bits(*b)));
    values
}
