//! A zero-order hold: laws of the state sampled every period and held constant between
//! samples, as a discrete controller applies them. The held values sit in parameter slots;
//! the right-hand side jumps at each sample, so a run stops there and restarts its method.

use numeric::Tape;

/// Laws sampled at t = k·T (k = 0, 1, …) from the state at that instant, each held in its
/// parameter slot until the next sample.
#[derive(Clone)]
pub struct Hold {
    period: f64,
    /// The parameter slot each output of the law program fills.
    slots: Vec<usize>,
    /// Takes the dynamics program's inputs `[t, q, q̇, parameters]` and gives one value per
    /// slot.
    laws: Tape,
    input: Vec<f64>,
    values: Vec<f64>,
}

impl Hold {
    /// `laws` fills `slots`, one output each, sampled every `period` (positive and finite).
    pub fn new(period: f64, slots: Vec<usize>, laws: Tape) -> Self {
        assert!(period.is_finite() && period > 0.0);
        assert_eq!(laws.outputs(), slots.len());
        Hold {
            period,
            input: vec![0.0; laws.inputs()],
            values: vec![0.0; slots.len()],
            slots,
            laws,
        }
    }

    pub fn period(&self) -> f64 {
        self.period
    }

    /// The first sample time after `t`.
    pub fn next_after(&self, t: f64) -> f64 {
        next_sample(self.period, t)
    }

    /// Whether `t` is a sample time k·T, as [`Hold::next_after`] computes them (a run also
    /// stops at the knots of a series, where nothing is sampled).
    pub fn is_sample_time(&self, t: f64) -> bool {
        (t / self.period).round() * self.period == t
    }

    /// Samples the laws at (t, q, q̇) with the parameters as they are, and holds the values in
    /// their slots. Every law is evaluated before any slot changes: a law reads no input.
    pub(crate) fn sample(
        &mut self,
        t: f64,
        y: &[f64],
        parameters: &mut [f64],
    ) -> Result<(), usize> {
        let d = y.len();
        self.input[0] = t;
        self.input[1..1 + d].copy_from_slice(y);
        self.input[1 + d..].copy_from_slice(parameters);
        self.laws.eval(&self.input, &mut self.values);
        if let Some(k) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(self.slots[k]);
        }
        for (slot, value) in self.slots.iter().zip(&self.values) {
            parameters[*slot] = *value;
        }
        Ok(())
    }
}

/// The first k·T after `t`, with k counted rather than the periods summed, so that every run
/// lands on the same times.
fn next_sample(period: f64, t: f64) -> f64 {
    let k = (t / period).floor() + 1.0;
    let next = k * period;
    // t/T may round down at t = k·T itself.
    if next > t {
        next
    } else {
        (k + 1.0) * period
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_counted_from_zero_and_land_on_their_own_times() {
        assert_eq!(next_sample(0.1, 0.0), 0.1);
        assert_eq!(next_sample(0.1, 0.05), 0.1);
        for k in 1..1000 {
            let at = k as f64 * 0.1;
            assert_eq!(next_sample(0.1, at), (k + 1) as f64 * 0.1, "after sample {k}");
            assert_eq!(next_sample(0.1, at - 1e-9), at, "before sample {k}");
        }
    }
}
