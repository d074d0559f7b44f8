//! The kept rows' saddle-point system [M −Jᵀ; J 0]·(q̈, λ) = (f, c) solved through its
//! blocks: M's LDLᵀ factors, Y = M⁻¹·Jᵀ and the Schur complement S = J·Y, whose LDLᵀ factors
//! give λ = S⁻¹·(c − J·M⁻¹·f) and then q̈ = M⁻¹·f + Y·λ.
//!
//! A mass matrix is symmetric positive definite and independent kept rows make S so: neither
//! factorization pivots, and with M's order a constant every loop's length is known. LU with
//! partial pivoting on the whole system had taken a quarter of a walker's periodic-orbit
//! search, most of it spent on the search for pivots and the swaps of rows that a saddle
//! point's blocks do not need. Where M is not positive definite, the rows are dependent, or
//! the pivots spread past [`CONDITION_LIMIT`], [`Saddle::factor`] says no and the caller
//! falls back to LU, which names the fault as before.

use super::{CONDITION_LIMIT, SMALL};

/// Runs `$body` with `$N` and `$K` the constants n and k, for every order n + k ≤ [`SMALL`]
/// with k ≥ 1 (`$otherwise` past them): both blocks' loops of known length.
macro_rules! with_orders {
    ($n:expr, $k:expr, |$N:ident, $K:ident| $body:expr, $otherwise:expr) => {
        with_orders!(@arms ($n, $k), $N, $K, $body, $otherwise,
            1: [1 2 3 4 5 6 7], 2: [1 2 3 4 5 6], 3: [1 2 3 4 5], 4: [1 2 3 4], 5: [1 2 3],
            6: [1 2], 7: [1])
    };
    (@arms $pair:expr, $N:ident, $K:ident, $body:expr, $otherwise:expr,
        $($n:literal: [$($k:literal)*]),*) => {
        match $pair {
            $($(($n, $k) => {
                const $N: usize = $n;
                const $K: usize = $k;
                $body
            })*)*
            _ => $otherwise,
        }
    };
}

/// The blocks' factors, for a system of order n + k ≤ [`SMALL`] with at least one kept row.
#[derive(Clone, Debug)]
pub struct Saddle {
    n: usize,
    k: usize,
    /// M's LDLᵀ factors, row-major: L's entry (i, j), j < i, at `i * SMALL + j`, D on the
    /// diagonal.
    mass: [f64; SMALL * SMALL],
    /// The kept rows of J, row r at `r * SMALL`.
    rows: [f64; SMALL * SMALL],
    /// Y = M⁻¹·Jᵀ, its column r at `r * SMALL`.
    y: [f64; SMALL * SMALL],
    /// S's LDLᵀ factors, laid out as `mass`'s.
    schur: [f64; SMALL * SMALL],
}

impl Default for Saddle {
    fn default() -> Self {
        let zeros = [0.0; SMALL * SMALL];
        Saddle { n: 0, k: 0, mass: zeros, rows: zeros, y: zeros, schur: zeros }
    }
}

impl Saddle {
    /// Factors the system of the dynamics outputs `out` (M column-major in its first n²
    /// entries, each multiplier's Jacobian row at `n² + n + c·(n + 3)`) with the multipliers
    /// `rows` kept. False, with nothing to solve with, where the blocks do not serve: no
    /// kept row, an order past [`SMALL`], M not positive definite, S not (dependent rows),
    /// or pivots spread past [`CONDITION_LIMIT`].
    pub fn factor(&mut self, out: &[f64], n: usize, rows: &[usize]) -> bool {
        let k = rows.len();
        if k == 0 || n + k > SMALL {
            return false;
        }
        self.n = n;
        self.k = k;
        with_orders!(n, k, |N, K| self.factor_fixed::<N, K>(out, rows), false)
    }

    fn factor_fixed<const N: usize, const K: usize>(
        &mut self,
        out: &[f64],
        rows: &[usize],
    ) -> bool {
        let rows: &[usize; K] = rows.try_into().expect("K kept rows");
        let mass = &out[..N * N];
        // The largest diagonal entry and the smallest pivot of both factorizations: in a
        // positive definite matrix no pivot exceeds its diagonal entry, so their ratio bounds
        // the spread LU's pivot test measures, and a vanishing pivot (dependent rows leave
        // rounding in S's) reads as a spread past any limit.
        let mut spread = (f64::INFINITY, 0.0f64);
        if !ldl_fixed::<N>(|i, j| mass[j * N + i], &mut self.mass, &mut spread) {
            return false;
        }
        for (r, &c) in rows.iter().enumerate() {
            let base = N * N + N + c * (N + 3);
            let row: &[f64; N] = out[base..base + N].try_into().expect("a Jacobian row");
            self.rows[r * SMALL..r * SMALL + N].copy_from_slice(row);
            let mut column: [[f64; 1]; N] = std::array::from_fn(|i| [row[i]]);
            ldl_solve_columns_fixed::<N, 1>(&self.mass, &mut column);
            for (y, v) in self.y[r * SMALL..r * SMALL + N].iter_mut().zip(&column) {
                *y = v[0];
            }
        }
        // S = J·Y, its lower triangle.
        let dot = |a: usize, b: usize| {
            let (row, column) = (&self.rows[a * SMALL..a * SMALL + N], &self.y[b * SMALL..]);
            row.iter().zip(column).fold(0.0, |sum, (u, v)| sum + u * v)
        };
        if !ldl_fixed::<K>(dot, &mut self.schur, &mut spread) {
            return false;
        }
        let (lo, hi) = spread;
        hi <= lo * CONDITION_LIMIT
    }

    /// Solves for the columns of `b` side by side, in place: rows 0..n hold f's entries and
    /// rows n..n + k the kept rows' c, and they are left holding q̈'s and λ's.
    pub fn solve_columns<const C: usize>(&self, b: &mut [[f64; C]]) {
        with_orders!(
            self.n,
            self.k,
            |N, K| self.solve_fixed::<N, K, C>(b),
            unreachable!("a saddle factored with n + k ≤ {SMALL} and k ≥ 1")
        )
    }

    /// Solves for one right side laid out as a dynamics solution is: f in `x[..n]`, the kept
    /// row r's c in `x[n + rows[r]]` (`rows` the kept multipliers factored), leaving q̈ in
    /// `x[..n]` and each kept λ where its c was. The other entries are not read or written.
    /// The same operations as [`Saddle::solve_columns`] on one column, so its bits, without
    /// gathering the right side into a block and scattering it back.
    pub fn solve_scattered(&self, x: &mut [f64], rows: &[usize]) {
        let mut b = [[0.0]; SMALL];
        let n = self.n;
        for (b, x) in b.iter_mut().zip(&x[..n]) {
            *b = [*x];
        }
        for (b, &c) in b[n..].iter_mut().zip(rows) {
            *b = [x[n + c]];
        }
        self.solve_columns(&mut b[..n + self.k]);
        for (x, b) in x.iter_mut().zip(&b[..n]) {
            *x = b[0];
        }
        for (b, &c) in b[n..].iter().zip(rows) {
            x[n + c] = b[0];
        }
    }

    fn solve_fixed<const N: usize, const K: usize, const C: usize>(&self, b: &mut [[f64; C]]) {
        let (f, c) = b.split_at_mut(N);
        let f: &mut [[f64; C]; N] = f.try_into().expect("the coordinates' rows");
        let c: &mut [[f64; C]; K] = (&mut c[..K]).try_into().expect("the kept rows");
        // u = M⁻¹·f, left in f.
        ldl_solve_columns_fixed::<N, C>(&self.mass, f);
        // c − J·u
        for (r, c) in c.iter_mut().enumerate() {
            let row = &self.rows[r * SMALL..r * SMALL + N];
            for (j, u) in row.iter().zip(f.iter()) {
                for (c, u) in c.iter_mut().zip(u) {
                    *c -= j * u;
                }
            }
        }
        // λ = S⁻¹·(c − J·u)
        ldl_solve_columns_fixed::<K, C>(&self.schur, c);
        // q̈ = u + Y·λ
        for (i, u) in f.iter_mut().enumerate() {
            for (r, lambda) in c.iter().enumerate() {
                let y = self.y[r * SMALL + i];
                for (u, lambda) in u.iter_mut().zip(lambda) {
                    *u += y * lambda;
                }
            }
        }
    }
}

/// LDLᵀ of the symmetric matrix whose entry (i, j), j ≤ i, is `entry(i, j)`, into `into`
/// ([`Saddle`]'s layout), widening `spread` (the smallest pivot, the largest diagonal entry).
/// False at a pivot that is not positive (or a NaN) or a diagonal entry that is not finite.
fn ldl_fixed<const N: usize>(
    entry: impl Fn(usize, usize) -> f64,
    into: &mut [f64; SMALL * SMALL],
    spread: &mut (f64, f64),
) -> bool {
    let m = into;
    for j in 0..N {
        let diagonal = entry(j, j);
        let mut d = diagonal;
        for p in 0..j {
            d -= m[j * SMALL + p] * m[j * SMALL + p] * m[p * SMALL + p];
        }
        if !(d > 0.0 && diagonal.is_finite()) {
            return false;
        }
        m[j * SMALL + j] = d;
        spread.0 = spread.0.min(d);
        spread.1 = spread.1.max(diagonal);
        for i in j + 1..N {
            let mut s = entry(i, j);
            for p in 0..j {
                s -= m[i * SMALL + p] * m[j * SMALL + p] * m[p * SMALL + p];
            }
            m[i * SMALL + j] = s / d;
        }
    }
    true
}

/// M⁻¹·b (or S⁻¹·b) in place for the columns of `b` side by side, with the LDLᵀ factors in
/// `mass` ([`Saddle`]'s layout).
fn ldl_solve_columns_fixed<const N: usize, const C: usize>(
    mass: &[f64; SMALL * SMALL],
    b: &mut [[f64; C]; N],
) {
    for i in 0..N {
        let mut s = b[i];
        for p in 0..i {
            let l = mass[i * SMALL + p];
            for (s, b) in s.iter_mut().zip(&b[p]) {
                *s -= l * b;
            }
        }
        b[i] = s;
    }
    for (i, b) in b.iter_mut().enumerate() {
        let d = mass[i * SMALL + i];
        *b = b.map(|v| v / d);
    }
    for i in (0..N).rev() {
        let mut s = b[i];
        for p in i + 1..N {
            let l = mass[p * SMALL + i];
            for (s, b) in s.iter_mut().zip(&b[p]) {
                *s -= l * b;
            }
        }
        b[i] = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{lu_in_place, lu_solve, Small, Square};

    /// The dynamics outputs of n coordinates with the given M, f and multipliers' rows.
    fn outputs(mass: &[Vec<f64>], rows: &[Vec<f64>]) -> Vec<f64> {
        let n = mass.len();
        let mut out = vec![0.0; n * n + n + rows.len() * (n + 3)];
        for j in 0..n {
            for i in 0..n {
                out[j * n + i] = mass[i][j];
            }
        }
        for (c, row) in rows.iter().enumerate() {
            out[n * n + n + c * (n + 3)..][..n].copy_from_slice(row);
        }
        out
    }

    #[test]
    fn agrees_with_lu_on_the_whole_system() {
        let mass = vec![
            vec![4.0, 1.0, 0.5, 0.2],
            vec![1.0, 3.0, 0.3, 0.1],
            vec![0.5, 0.3, 2.0, 0.4],
            vec![0.2, 0.1, 0.4, 1.5],
        ];
        let rows = vec![vec![1.0, -2.0, 0.5, 0.0], vec![0.0, 0.3, 1.0, -1.0], vec![9.0; 4]];
        let out = outputs(&mass, &rows);
        let kept = [0, 1];
        let mut saddle = Saddle::default();
        assert!(saddle.factor(&out, 4, &kept));
        let rhs = [0.3, -1.2, 2.5, 0.7, 0.9, -0.4];
        let mut ours = rhs;
        saddle.solve_scattered(&mut ours, &kept);
        let mut whole = Small::zeros(6).unwrap();
        for i in 0..4 {
            for j in 0..4 {
                whole[(i, j)] = mass[i][j];
            }
        }
        for (r, &c) in kept.iter().enumerate() {
            for j in 0..4 {
                whole[(4 + r, j)] = rows[c][j];
                whole[(j, 4 + r)] = -rows[c][j];
            }
        }
        let mut pivots = [0; 6];
        lu_in_place(&mut whole, &mut pivots).unwrap();
        let mut theirs = rhs;
        lu_solve(&whole, &pivots, &mut theirs);
        for (a, b) in ours.iter().zip(&theirs) {
            assert!((a - b).abs() < 1e-13, "{ours:?} against {theirs:?}");
        }
        // The columns side by side give each column the single solve's bits.
        let mut block = [[0.0; 2]; 6];
        for (i, row) in block.iter_mut().enumerate() {
            *row = [rhs[i], 2.0 * rhs[5 - i]];
        }
        saddle.solve_columns(&mut block);
        for (i, row) in block.iter().enumerate() {
            assert_eq!(row[0].to_bits(), ours[i].to_bits());
        }
        assert_eq!(whole.order(), 6);
    }

    #[test]
    fn says_no_where_lu_must_decide() {
        let mass = vec![vec![2.0, 0.0], vec![0.0, 1.0]];
        let mut saddle = Saddle::default();
        // Dependent rows: S is singular.
        let out = outputs(&mass, &[vec![1.0, 1.0], vec![2.0, 2.0]]);
        assert!(!saddle.factor(&out, 2, &[0, 1]));
        // M not positive definite.
        let out = outputs(&[vec![1.0, 0.0], vec![0.0, -1.0]], &[vec![1.0, 0.0]]);
        assert!(!saddle.factor(&out, 2, &[0]));
        // A NaN in M.
        let out = outputs(&[vec![f64::NAN, 0.0], vec![0.0, 1.0]], &[vec![1.0, 0.0]]);
        assert!(!saddle.factor(&out, 2, &[0]));
        // No kept row: M alone is LDLᵀ's.
        let out = outputs(&mass, &[vec![1.0, 0.0]]);
        assert!(!saddle.factor(&out, 2, &[]));
        assert!(saddle.factor(&out, 2, &[0]));
    }
}
