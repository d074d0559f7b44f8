//! Signals given as time series: a value at each of a few times, linear between them, that a
//! problem puts into a parameter slot before each evaluation at time t.

/// A time series: strictly increasing times, a value at each, linear in between.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    times: Vec<f64>,
    values: Vec<f64>,
}

impl Series {
    /// The series of these samples, or why they are not one: at least two, finite, the
    /// times strictly increasing (the index of the first time that is not, otherwise).
    pub fn new(times: Vec<f64>, values: Vec<f64>) -> Result<Series, SeriesError> {
        if times.len() != values.len() || times.len() < 2 {
            return Err(SeriesError::TooShort);
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(SeriesError::NotIncreasing(k + 1));
        }
        if let Some(k) =
            times.iter().zip(&values).position(|(t, v)| !(t.is_finite() && v.is_finite()))
        {
            return Err(SeriesError::NotFinite(k));
        }
        Ok(Series { times, values })
    }

    /// The first sample time after `t`: a knot, where the series' slope jumps.
    pub fn next_knot_after(&self, t: f64) -> Option<f64> {
        let k = self.times.partition_point(|s| *s <= t);
        self.times.get(k).copied()
    }

    /// The first and last times.
    pub fn span(&self) -> (f64, f64) {
        (self.times[0], self.times[self.times.len() - 1])
    }

    /// The value at `t`, linear between the samples around it; held at the end value past
    /// an end (a run checks the span first, so only rounding reaches there).
    pub fn at(&self, t: f64) -> f64 {
        let (first, last) = self.span();
        if t <= first {
            return self.values[0];
        }
        if t >= last {
            return self.values[self.values.len() - 1];
        }
        // The last sample at or before t.
        let k = self.times.partition_point(|s| *s <= t) - 1;
        let (t0, t1, v0, v1) =
            (self.times[k], self.times[k + 1], self.values[k], self.values[k + 1]);
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }
}

/// Why samples are not a [`Series`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SeriesError {
    /// Fewer than two samples.
    TooShort,
    /// The time of this sample is not after the one before.
    NotIncreasing(usize),
    /// This sample has a time or value that is not a finite number.
    NotFinite(usize),
}

impl std::fmt::Display for SeriesError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SeriesError::TooShort => f.write_str("a series needs at least two samples"),
            SeriesError::NotIncreasing(k) => {
                write!(f, "the time of sample {k} (from 0) is not after the one before")
            }
            SeriesError::NotFinite(k) => write!(f, "sample {k} (from 0) is not a finite number"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_series_is_linear_between_its_samples() {
        let s = Series::new(vec![0.0, 1.0, 3.0], vec![0.0, 2.0, -2.0]).expect("a series");
        assert_eq!(
            [s.at(0.0), s.at(0.5), s.at(1.0), s.at(2.0), s.at(3.0)],
            [0.0, 1.0, 2.0, 0.0, -2.0]
        );
        assert_eq!(s.at(4.0), -2.0);
        assert_eq!(Series::new(vec![0.0], vec![1.0]), Err(SeriesError::TooShort));
        assert_eq!(
            Series::new(vec![0.0, 1.0, 1.0], vec![0.0; 3]),
            Err(SeriesError::NotIncreasing(2))
        );
    }
}
