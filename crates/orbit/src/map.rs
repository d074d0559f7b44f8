//! The symmetry a return is mapped by before it is compared with its start: coordinates
//! swapped in pairs (a walker's legs, with their rates), then values added to coordinates or
//! rates (a position advanced by a step, an angle by a spoke). Both are affine with a
//! permutation for their derivative.

use engine::input::Assignment;
use engine::numbers::Prepared;
use engine::Error;

/// S(x) = Π·x + c on the state (q, q̇).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Symmetry {
    /// `order[i]` is the component of x that S puts at i.
    order: Vec<usize>,
    offset: Vec<f64>,
    /// Components the comparison leaves out: positions a motion does not come back to and
    /// need not (a cyclic coordinate, the distance a wheel has rolled).
    ignored: Vec<usize>,
}

impl Symmetry {
    /// The identity on a state of `size` components.
    pub fn identity(size: usize) -> Self {
        Symmetry { order: (0..size).collect(), offset: vec![0.0; size], ignored: Vec::new() }
    }

    /// The map of `swaps` (`a=b`: coordinates a and b exchanged, with their rates) and
    /// `shifts` (`name=value`, `name'=value`: the value, an expression of the parameters with
    /// an optional unit, added to the coordinate or its rate), at the `parameters`' values,
    /// leaving the coordinates `ignored` out of the comparison.
    pub fn new(
        prepared: &mut Prepared,
        parameters: &[f64],
        swaps: &[Assignment],
        shifts: &[Assignment],
        ignored: &[String],
    ) -> Result<Self, Error> {
        let names = prepared.coordinate_names();
        let n = names.len();
        let mut map = Symmetry::identity(2 * n);
        let slot = |name: &str, option: &str| -> Result<usize, Error> {
            names.iter().position(|c| c == name).ok_or_else(|| {
                Error::Input(format!(
                    "{option}: `{name}` is not a coordinate the motion has; one of {}",
                    names.join(", ")
                ))
            })
        };
        for name in ignored {
            map.ignored.push(slot(name.trim(), "--ignore")?);
        }
        for swap in swaps {
            let (a, b) = (swap.name.trim(), swap.value.trim());
            let (i, j) = (slot(a, "--swap")?, slot(b, "--swap")?);
            if i == j {
                return Err(Error::Input(format!("--swap {a}={b} exchanges `{a}` with itself")));
            }
            map.order.swap(i, j);
            map.order.swap(n + i, n + j);
        }
        for shift in shifts {
            let (base, primes) = shift.base();
            if primes > 1 {
                return Err(Error::Input(format!(
                    "--shift {}: a state has coordinates and their rates, not `{}`",
                    shift.name, shift.name
                )));
            }
            let i = slot(base, "--shift")? + primes * n;
            let value =
                prepared.derivation.model.resolve_value_for(&shift.name, &shift.value).map_err(
                    |diagnostics| Error::Expression { diagnostics, text: shift.value.clone() },
                )?;
            let model::Value::Scalar(e) = value else {
                return Err(Error::Input(format!(
                    "--shift {}: `{}` is {}, not a number",
                    shift.name,
                    shift.value,
                    value.kind_name()
                )));
            };
            let amount = prepared.constant(e, parameters);
            if !amount.is_finite() {
                return Err(Error::Input(format!(
                    "--shift {}: `{}` has no finite value at the parameters' values (it may \
                     name the state or t: a shift is a constant)",
                    shift.name, shift.value
                )));
            }
            map.offset[i] += amount;
        }
        Ok(map)
    }

    /// A unit row per component left out: normals the chart is kept orthogonal to.
    pub fn ignored_rows(&self) -> Vec<Vec<f64>> {
        let size = self.order.len();
        self.ignored
            .iter()
            .map(|&i| (0..size).map(|k| f64::from(u8::from(k == i))).collect())
            .collect()
    }

    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        self.order.iter().zip(&self.offset).map(|(&k, c)| x[k] + c).collect()
    }

    /// Π·v: the derivative of the map applied to a change of the state.
    pub fn permute(&self, v: &[f64]) -> Vec<f64> {
        self.order.iter().map(|&k| v[k]).collect()
    }

    /// Π·M for a row-major square M.
    pub fn carry(&self, matrix: &[f64]) -> Vec<f64> {
        let size = self.order.len();
        let mut out = vec![0.0; size * size];
        for (i, &k) in self.order.iter().enumerate() {
            out[i * size..(i + 1) * size].copy_from_slice(&matrix[k * size..(k + 1) * size]);
        }
        out
    }
}
