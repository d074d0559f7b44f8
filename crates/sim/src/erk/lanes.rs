//! The stages of an adaptive pair for [`LANES`] runs at once, kept lane by lane (value `i` of
//! stage `s` of every run side by side), so that one loop over the lanes forms every run's
//! stage argument and the compiler makes vector instructions of it. Each lane does exactly the
//! operations [`Adaptive`] does for its one run, in the same order, so a lane's step is the
//! same bits as the run's step taken alone.

use numeric::LANES;

use super::{Adaptive, Pair, DOP853_A, DOP853_BHH, DOP853_E5};

pub(crate) use crate::linalg::Lanes;

/// The stages of one trial step of every lane, and the state each started from.
pub(crate) struct Stages {
    pair: Pair,
    dim: usize,
    /// Value `i` of stage `s` at `s * dim + i`: 13 stages for DOP853 (12 and the derivative at
    /// the end), 7 for the 5(4) pair.
    k: Vec<Lanes>,
    /// The state each lane's step starts from.
    pub y: Vec<Lanes>,
    /// The argument of the stage being evaluated, then of the last one.
    pub tmp: Vec<Lanes>,
    /// Each lane's end of the step.
    pub y_new: Vec<Lanes>,
}

impl Stages {
    pub fn new(pair: Pair, dim: usize) -> Stages {
        let stages = pair.stage_count() + 1;
        let zeros = |count| vec![[0.0; LANES]; count];
        Stages {
            pair,
            dim,
            k: zeros(stages * dim),
            y: zeros(dim),
            tmp: zeros(dim),
            y_new: zeros(dim),
        }
    }

    pub fn pair(&self) -> Pair {
        self.pair
    }

    /// The arguments of the stage being evaluated (`tmp`, or `y_new` for the derivative at
    /// the end of the step), and stage `s` to be written, value by value.
    pub fn argument_and_stage(&mut self, s: usize, at_end: bool) -> (&[Lanes], &mut [Lanes]) {
        let args = if at_end { &self.y_new } else { &self.tmp };
        (args, &mut self.k[s * self.dim..(s + 1) * self.dim])
    }

    /// Starts lane `lane`'s step from the derivative at its start: the first stage.
    pub fn set_first_stage(&mut self, lane: usize, f: &[f64]) {
        for (k, v) in self.k[..self.dim].iter_mut().zip(f) {
            k[lane] = *v;
        }
    }

    /// After an accepted step, the next one starts where it ended: its last stage, the
    /// derivative there, is the next step's first (first same as last).
    pub fn carry_last_stage(&mut self, lane: usize) {
        let last = self.pair.stage_count() * self.dim;
        for i in 0..self.dim {
            self.k[i][lane] = self.k[last + i][lane];
        }
    }

    /// The argument of stage `s` (1 ≤ s < the stage count) of every lane into `tmp`:
    /// y + h·Σⱼ aₛⱼ kⱼ, summed as [`Adaptive`] sums it.
    #[inline(always)]
    pub fn argument(&mut self, s: usize, h: &Lanes) {
        let a = self.pair.a(s);
        combine(&self.k, self.dim, a, &self.y, h, &mut self.tmp);
    }

    /// Every lane's end of the step into `y_new`: y + h·Σⱼ bⱼ kⱼ.
    #[inline(always)]
    pub fn end(&mut self, h: &Lanes) {
        let b = self.pair.b();
        combine(&self.k, self.dim, b, &self.y, h, &mut self.y_new);
    }

    /// Every lane's error norm of the step of size `h` it just tried: [`Adaptive`]'s, with
    /// the sums over the stages in its order and then over the values.
    #[inline(always)]
    pub fn errors(&self, h: &Lanes, rtol: f64, atol: f64) -> Lanes {
        let (d, k) = (self.dim, &self.k);
        let scale = |i: usize| -> Lanes {
            let (y, y_new) = (&self.y[i], &self.y_new[i]);
            std::array::from_fn(|l| atol + y[l].abs().max(y_new[l].abs()) * rtol)
        };
        match self.pair.error_weights() {
            Some(weights) => {
                let mut sum = [0.0; LANES];
                for i in 0..d {
                    let mut acc = [0.0; LANES];
                    for (j, ej) in weights.iter().enumerate() {
                        for l in 0..LANES {
                            acc[l] += ej * k[j * d + i][l];
                        }
                    }
                    let scale = scale(i);
                    for l in 0..LANES {
                        let x = h[l] * acc[l] / scale[l];
                        sum[l] += x * x;
                    }
                }
                // `rms` of the d values, as `Adaptive` takes it.
                std::array::from_fn(|l| if d == 0 { 0.0 } else { (sum[l] / d as f64).sqrt() })
            }
            None => {
                let (mut e5, mut e3) = ([0.0; LANES], [0.0; LANES]);
                for i in 0..d {
                    let (mut a5, mut a3) = ([0.0; LANES], [0.0; LANES]);
                    for j in 0..12 {
                        let (w5, w3) = (DOP853_E5[j], DOP853_A[12][j] - DOP853_BHH[j]);
                        let kj = &k[j * d + i];
                        for l in 0..LANES {
                            a5[l] += w5 * kj[l];
                            a3[l] += w3 * kj[l];
                        }
                    }
                    let scale = scale(i);
                    for l in 0..LANES {
                        let (r5, r3) = (a5[l] / scale[l], a3[l] / scale[l]);
                        e5[l] += r5 * r5;
                        e3[l] += r3 * r3;
                    }
                }
                std::array::from_fn(|l| {
                    let denom = e5[l] + 0.01 * e3[l];
                    if denom == 0.0 {
                        0.0
                    } else {
                        h[l].abs() * e5[l] / (denom * d as f64).sqrt()
                    }
                })
            }
        }
    }

    /// Hairer's stiffness test on lane `lane`'s step just tried, as
    /// [`Adaptive::at_stability_limit`] makes it.
    pub fn at_stability_limit(&self, lane: usize, h: f64) -> bool {
        let (d, last) = (self.dim, self.pair.stage_count());
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..d {
            let dk = self.k[last * d + i][lane] - self.k[(last - 1) * d + i][lane];
            let dy = self.y_new[i][lane] - self.tmp[i][lane];
            num += dk * dk;
            den += dy * dy;
        }
        den > 0.0 && h.abs() * (num / den).sqrt() > self.pair.stiffness_bound()
    }

    /// Gives `stepper` lane `lane`'s stages and end of the step it accepted, for its dense
    /// output.
    pub fn load_step(&self, lane: usize, stepper: &mut Adaptive) {
        let d = self.dim;
        for (s, stage) in stepper.k.iter_mut().take(self.pair.stage_count() + 1).enumerate() {
            for (i, v) in stage.iter_mut().enumerate() {
                *v = self.k[s * d + i][lane];
            }
        }
        for (i, v) in stepper.y_new.iter_mut().enumerate() {
            *v = self.y_new[i][lane];
        }
    }
}

/// out = y + h·Σⱼ wⱼ kⱼ, value by value and lane by lane, the sum from the first stage on.
#[inline(always)]
fn combine(k: &[Lanes], d: usize, w: &[f64], y: &[Lanes], h: &Lanes, out: &mut [Lanes]) {
    for i in 0..d {
        let mut acc = [0.0; LANES];
        for (j, wj) in w.iter().enumerate() {
            let kj = &k[j * d + i];
            for l in 0..LANES {
                acc[l] += wj * kj[l];
            }
        }
        for l in 0..LANES {
            out[i][l] = y[i][l] + h[l] * acc[l];
        }
    }
}
