//! The numbers of `cas`'s zero test ([`cas::ZeroTest`]): expressions evaluated at fixed generic
//! points and compared with their size there. `cas` evaluates no floats; whoever creates a pool
//! for a derivation hands it [`GenericPoints`] with [`cas::Pool::set_zero_test`].

use cas::{ExprId, Pool, ZeroTest};

use crate::eval::{value_and_magnitude, value_and_scale};

/// How many generic points [`GenericPoints::at_generic_point`] has.
pub const GENERIC_POINTS: usize = 2;

/// The zero test's numbers at fixed generic points: every symbol at an irrational-looking value
/// in (0.3, 0.8), the same on every run, so every decision is too.
#[derive(Clone, Copy, Debug, Default)]
pub struct GenericPoints;

impl GenericPoints {
    /// The value and the magnitude of each expression at generic point `point` (of
    /// [`GENERIC_POINTS`]): see [`value_and_magnitude`].
    pub fn at_generic_point(pool: &Pool, exprs: &[ExprId], point: usize) -> Vec<(f64, f64)> {
        let step = [0.618_033_988_749_895, 0.414_213_562_373_095][point % GENERIC_POINTS];
        let values: Vec<f64> = (0..pool.symbol_count())
            .map(|i| 0.3 + 0.5 * ((i as f64 + 1.0) * step).fract())
            .collect();
        exprs.iter().map(|e| value_and_magnitude(pool, *e, &values)).collect()
    }
}

impl ZeroTest for GenericPoints {
    /// Evaluates at a fixed generic point (every symbol at an irrational-looking value in
    /// (0.3, 0.8)) and reports whether the value is clearly not zero, relative to the size of
    /// the terms that make it up ([`value_and_scale`]).
    fn clearly_nonzero_somewhere(&self, pool: &Pool, e: ExprId) -> bool {
        let values: Vec<f64> = (0..pool.symbol_count())
            .map(|i| 0.3 + 0.5 * ((i as f64 + 1.0) * 0.618_033_988_749_895).fract())
            .collect();
        let (value, scale) = value_and_scale(pool, e, &values);
        value.is_finite() && scale.is_finite() && value.abs() > 1e-6 * scale.max(f64::MIN_POSITIVE)
    }

    /// Its value against the size of its terms, as the generic-point test weighs a value.
    fn sign_of_constant(&self, pool: &Pool, e: ExprId) -> Option<i8> {
        let (value, scale) = value_and_scale(pool, e, &vec![0.0; pool.symbol_count()]);
        let clear = value.is_finite() && value.abs() > 1e-6 * scale.max(f64::MIN_POSITIVE);
        clear.then_some(if value < 0.0 { -1 } else { 1 })
    }

    /// At each generic point, `target` and the rows by value and magnitude
    /// ([`GenericPoints::at_generic_point`]): Gram–Schmidt against the rows, one after another,
    /// and what is left of the target must be zero relative to its magnitude.
    fn combination_at_generic_points(
        &self,
        pool: &Pool,
        target: &[ExprId],
        rows: &[Vec<ExprId>],
    ) -> Option<Vec<usize>> {
        let mut used = std::collections::BTreeSet::new();
        for point in 0..GENERIC_POINTS {
            let numbers = |exprs: &[ExprId]| -> (Vec<f64>, f64) {
                let values = Self::at_generic_point(pool, exprs, point);
                let scale = values.iter().map(|(_, m)| *m).fold(0.0, f64::max);
                (values.into_iter().map(|(v, _)| v).collect(), scale)
            };
            let (mut residual, scale) = numbers(target);
            if !scale.is_finite() || !residual.iter().all(|v| v.is_finite()) {
                return None;
            }
            // Gram–Schmidt against the rows, one after another.
            let mut done: Vec<Vec<f64>> = Vec::new();
            for (k, row) in rows.iter().enumerate() {
                let (mut v, _) = numbers(row);
                for d in &done {
                    let along: f64 = v.iter().zip(d).map(|(a, b)| a * b).sum();
                    v.iter_mut().zip(d).for_each(|(a, b)| *a -= along * b);
                }
                let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
                if !norm.is_finite() || norm <= 1e-12 * scale.max(f64::MIN_POSITIVE) {
                    continue;
                }
                v.iter_mut().for_each(|a| *a /= norm);
                let along: f64 = residual.iter().zip(&v).map(|(a, b)| a * b).sum();
                if along.abs() > 1e-9 * scale {
                    used.insert(k);
                }
                residual.iter_mut().zip(&v).for_each(|(a, b)| *a -= along * b);
                done.push(v);
            }
            if residual.iter().any(|r| r.abs() > 1e-9 * scale.max(f64::MIN_POSITIVE)) {
                return None;
            }
        }
        Some(used.into_iter().collect())
    }
}
