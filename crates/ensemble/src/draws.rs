//! The varied values of every run: grid axes crossed, the first varying slowest, and at each
//! grid point the random draws. Run k's draws come from its own ChaCha20 stream (the seed's
//! key, stream k), so they do not depend on which runs were drawn before it or where: a chunk
//! of runs can be drawn alone, on any machine, and gives the same numbers.

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha20Rng;

use super::MAX_RUNS;
use engine::input::{Spread, Vary};
use engine::{Error, Setting};

/// The grid and the draws of an ensemble, checked.
pub(crate) struct Design {
    spreads: Vec<(String, Spread)>,
    /// Random draws per grid point (1 with no random spread).
    draws: usize,
    runs: usize,
}

impl Design {
    pub fn new(vary: &[Vary], runs: Option<usize>) -> Result<Design, Error> {
        if vary.is_empty() {
            return Err(Error::setting(
                Setting::Vary,
                " is needed: name a parameter to vary (`a=0:1:11`, `m=normal(1, 0.1)`)",
            ));
        }
        let random = vary.iter().any(|v| v.spread.is_random());
        let draws = match (random, runs) {
            (true, Some(n)) if n >= 1 => n,
            (true, Some(_)) => return Err(Error::setting(Setting::Runs, " must be at least 1")),
            (true, None) => {
                return Err(Error::setting(
                    Setting::Runs,
                    " is needed with random draws: say how many runs to draw",
                ))
            }
            (false, Some(_)) => {
                return Err(Error::setting(
                    Setting::Runs,
                    " counts random draws, and nothing is drawn: vary a parameter by \
                     normal(MU, SIGMA) or uniform(A, B), or leave it out",
                ))
            }
            (false, None) => 1,
        };
        let points = vary.iter().try_fold(1usize, |n, v| match v.spread {
            Spread::Grid { values, .. } => n.checked_mul(values),
            _ => Some(n),
        });
        let runs = points.and_then(|p| p.checked_mul(draws)).filter(|n| *n <= MAX_RUNS);
        let Some(runs) = runs else {
            return Err(Error::Input(format!(
                "the ensemble has more than {MAX_RUNS} runs; use fewer values or draws"
            )));
        };
        let spreads = vary.iter().map(|v| (v.parameter.clone(), v.spread)).collect();
        Ok(Design { spreads, draws, runs })
    }

    pub fn is_random(&self) -> bool {
        self.spreads.iter().any(|(_, s)| s.is_random())
    }

    /// The grid's axes: each parameter and its values.
    pub fn axes(&self) -> Vec<(String, Vec<f64>)> {
        let axis = |(name, spread): &(String, Spread)| match spread {
            Spread::Grid { values, .. } => {
                Some((name.clone(), (0..*values).map(|k| spread.grid_value(k)).collect()))
            }
            _ => None,
        };
        self.spreads.iter().filter_map(axis).collect()
    }

    /// How many runs the design has.
    pub fn runs(&self) -> usize {
        self.runs
    }

    /// How many parameters are varied.
    pub fn parameters(&self) -> usize {
        self.spreads.len()
    }

    /// Every run's values, in the order the parameters were given.
    #[cfg(test)]
    pub fn values(&self, seed: u64) -> Vec<Vec<f64>> {
        (0..self.runs).map(|k| self.run(seed, k)).collect()
    }

    /// Run `k`'s values, in the order the parameters were given: its grid point's, and its
    /// draws.
    pub fn run(&self, seed: u64, k: usize) -> Vec<f64> {
        let mut point = k / self.draws;
        let mut values = vec![0.0; self.spreads.len()];
        // The last axis varies fastest: peel the point's index from the back.
        for (slot, (_, spread)) in self.spreads.iter().enumerate().rev() {
            if let Spread::Grid { values: n, .. } = spread {
                values[slot] = spread.grid_value(point % n);
                point /= n;
            }
        }
        let mut rng = ChaCha20Rng::seed_from_u64(seed);
        rng.set_stream(k as u64);
        for (slot, (_, spread)) in self.spreads.iter().enumerate() {
            values[slot] = match *spread {
                Spread::Grid { .. } => continue,
                Spread::Normal { mean, deviation } => mean + deviation * standard_normal(&mut rng),
                Spread::Uniform { low, high } => low + (high - low) * unit(&mut rng),
            };
        }
        values
    }
}

/// A number in [0, 1) from the top 53 bits of the stream: every value a multiple of 2⁻⁵³.
fn unit(rng: &mut ChaCha20Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A standard normal number by the Box–Muller transform, with libm's logarithm and cosine so
/// that the bits are the same on every machine.
fn standard_normal(rng: &mut ChaCha20Rng) -> f64 {
    // 1 − u lies in (0, 1]: its logarithm is finite.
    let radius = (-2.0 * numeric::elementary::apply(cas::Func::Ln, 1.0 - unit(rng))).sqrt();
    let angle = 2.0 * std::f64::consts::PI * unit(rng);
    radius * numeric::elementary::apply(cas::Func::Cos, angle)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vary(texts: &[&str]) -> Vec<Vary> {
        texts.iter().map(|t| Vary::parse(t).expect(t)).collect()
    }

    #[test]
    fn grids_cross_with_the_last_axis_fastest() {
        let design = Design::new(&vary(&["a=0:1:2", "b=10:30:3"]), None).expect("a grid");
        let values = design.values(0);
        let expected: Vec<Vec<f64>> = [(0.0, 10.0), (0.0, 20.0), (0.0, 30.0), (1.0, 10.0)]
            .iter()
            .map(|(a, b)| vec![*a, *b])
            .collect();
        assert_eq!(values.len(), 6);
        assert_eq!(values[..4], expected[..]);
        assert_eq!(design.axes()[1], ("b".to_string(), vec![10.0, 20.0, 30.0]));
    }

    #[test]
    fn draws_depend_on_the_seed_and_the_run_alone() {
        let design = Design::new(&vary(&["m=normal(1, 0.5)", "g=uniform(9, 10)"]), Some(2000))
            .expect("draws");
        let values = design.values(7);
        assert_eq!(values, design.values(7));
        assert_ne!(values, design.values(8));
        // A run drawn alone is the same as in the whole.
        assert_eq!(design.run(7, 1234), values[1234]);
        let mean = values.iter().map(|v| v[0]).sum::<f64>() / 2000.0;
        let spread =
            (values.iter().map(|v| (v[0] - mean) * (v[0] - mean)).sum::<f64>() / 1999.0).sqrt();
        assert!((mean - 1.0).abs() < 0.05 && (spread - 0.5).abs() < 0.05, "{mean} {spread}");
        assert!(values.iter().all(|v| (9.0..10.0).contains(&v[1])));
    }

    #[test]
    fn runs_go_with_draws_only() {
        let error =
            |texts: &[&str], runs| Design::new(&vary(texts), runs).err().map(|e| e.to_string());
        assert!(error(&["a=0:1:2"], Some(5)).is_some_and(|e| e.contains("counts random draws")));
        assert!(error(&["m=normal(1, 1)"], None).is_some_and(|e| e.contains("is needed")));
        assert!(error(&[], None).is_some_and(|e| e.contains("`vary` is needed")));
        assert!(
            error(&["a=0:1:100000", "b=0:1:100000"], None).is_some_and(|e| e.contains("more than"))
        );
    }
}
