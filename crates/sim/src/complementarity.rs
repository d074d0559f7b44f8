//! The contact problems' solver: the mixed linear complementarity problem w = A·x + c that an
//! impact (x the impulses, w = γ⁺ + e·γ⁻) and the accelerations of touching contacts (x the
//! forces, w = g̈) pose, with normal rows (x ≥ 0, w ≥ 0, x·w = 0) and the tangential rows of
//! gripping contacts (w = 0 while their contact is active, x = 0 while it is not).
//!
//! This module owns the solve only: it knows nothing of how A and c were built, of contacts'
//! names or of events. [`solve`] enumerates the active sets of the normal rows when there are at
//! most [`ENUMERATION_LIMIT`] of them, and pivots with Lemke's method beyond that, enumerating
//! only the gripping contacts' active sets ([`lemke_with_grips`]). Either way an active set's
//! equalities are solved least-norm (by an eigendecomposition of their symmetric block, so
//! redundant rows are fine), keeping the active normal rows' x ≥ 0, and the answer is widened
//! to every frictionless normal row with w = 0 where that keeps w: for an LCP (normal rows
//! only) this is the least-norm x of all its solutions, so the two methods give the same x.
//!
//! **Errors.** `solve` returns `Result<Solution, Unsolved>`: the error is the enum [`Unsolved`],
//! not [`Inconsistent`] itself, which is held by [`Unsolved::Inconsistent`] (the rows that
//! cannot be satisfied together) and is the only variant a well-posed scene reaches. The others
//! say that the input was malformed or non-finite, that more than [`ENUMERATION_LIMIT`]
//! gripping contacts came with more than as many normal rows, or that rounding stalled Lemke's
//! pivoting. `From<Inconsistent>` is implemented, and a caller only interested in
//! inconsistency can match `Err(Unsolved::Inconsistent(Inconsistent { rows }))`.

use nalgebra::{DMatrix, DVector};

/// What a row of a contact problem is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// A contact's normal row: x ≥ 0, w ≥ 0, x·w = 0.
    Normal,
    /// A gripping contact's tangential row, belonging to normal row `normal`: while that
    /// normal row is active (in the chosen active set), w = 0 with x free; otherwise x = 0 and w
    /// is unconstrained.
    Tangent { normal: usize },
}

/// The solution: x (impulses or forces per row), w = A·x + c, and which rows are active (one
/// entry per row: a normal row in the active set, or a tangent row whose normal row is).
///
/// The conditions hold to the tolerance the problem was solved with: an active normal row's x
/// may be as low as −tolerance, an inactive one's w too, and an active row's w is within
/// ±tolerance of 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    pub x: Vec<f64>,
    pub w: Vec<f64>,
    pub active: Vec<bool>,
}

/// No x satisfies the conditions: the rows (indices) that could not be satisfied together.
#[derive(Clone, Debug, PartialEq)]
pub struct Inconsistent {
    pub rows: Vec<usize>,
}

/// Why [`solve`] gave no solution.
#[derive(Clone, Debug, PartialEq)]
pub enum Unsolved {
    /// No x satisfies the conditions. The rows named are a set of contacts (each normal row with
    /// its tangent rows) that cannot be satisfied together, found by dropping the contacts whose
    /// removal leaves the problem still unsolvable: none of them can be dropped.
    Inconsistent(Inconsistent),
    /// A, c or the tolerance is NaN or infinite; `rows` are the rows holding such a value (empty
    /// when only the tolerance is).
    NonFinite { rows: Vec<usize> },
    /// The shapes disagree (A not k×k for k rows and k values of c), a tangent row names a row
    /// that is not a normal row, or the tolerance is negative.
    Malformed { reason: &'static str },
    /// More than [`ENUMERATION_LIMIT`] normal rows (`normals` of them), of which more than
    /// [`ENUMERATION_LIMIT`] belong to gripping contacts: Lemke's method does not apply to
    /// tangent rows (their conditions switch with another row's), and enumerating the gripping
    /// contacts' 2^11 or more active sets was judged too slow.
    TooLarge { normals: usize },
    /// Lemke's pivoting used its budget of `pivots`, or ended on a basis whose solution does not
    /// hold to the tolerance: rounding on a badly conditioned or degenerate problem.
    Stalled { pivots: usize },
}

impl From<Inconsistent> for Unsolved {
    fn from(inconsistent: Inconsistent) -> Self {
        Unsolved::Inconsistent(inconsistent)
    }
}

/// The most normal rows whose active sets [`solve`] enumerates, and the most gripping contacts
/// whose active sets it enumerates past that. 2^10 = 1024 least-squares solves is the worst
/// case (the answer needs every row active): 5 ms for ten normal rows, 150 ms with two tangent
/// rows each, in an unoptimized build (the tests'); typical answers come much sooner, since the
/// order tries the fewest active rows first. Ten covers a block's eight corners with room to
/// spare. Past it Lemke's method takes a few pivots per row (0.3 ms for forty rows, unoptimized).
pub const ENUMERATION_LIMIT: usize = 10;

/// Eigenvalues below this fraction of the largest count as zero in the least-norm solves (of
/// symmetric blocks of A, whose eigenvalues are their singular values). A Delassus operator's
/// redundant rows leave eigenvalues at rounding (1e-16 of the largest); one just above this
/// threshold would be a condition number of 1e10, past which the solve's error on w would exceed
/// the 1e-10-relative tolerance callers pass.
const RELATIVE_RANK: f64 = 1e-10;

/// Below this, an entry of Lemke's pivot column (of the scaled problem, whose A has a unit
/// diagonal) counts as zero, not as a pivot.
const PIVOT_FLOOR: f64 = 1e-11;

/// Two ratios of Lemke's test within this fraction of each other tie, and the lexicographic
/// rule decides between them.
const RATIO_TIE: f64 = 1e-9;

/// Solves the mixed complementarity problem w = A·x + c with the conditions of `rows`.
/// `a` is k×k symmetric positive semidefinite (a Delassus operator W·M⁻¹·Wᵀ condensed over kept
/// equality constraints), possibly singular (redundant rows are normal: two gripping corners of
/// a planar block give 4 rows on 3 degrees of freedom). `tolerance` is absolute on w and x, in
/// the units of c (the caller passes something like 1e-10 × the scale of c). Among the x valid
/// for the active set found, returns the least-norm one.
///
/// With at most [`ENUMERATION_LIMIT`] normal rows it enumerates active sets ([`enumerate`]);
/// beyond, it pivots ([`lemke_with_grips`], which is [`lemke`] without gripping contacts, and
/// [`Unsolved::TooLarge`] past [`ENUMERATION_LIMIT`] gripping contacts). An active set's x is
/// the least-norm one that keeps the active normal rows' x ≥ 0 (the least-norm solution of its
/// equalities when that does). Where several active sets are valid (a block landing flat on
/// more corners than it has degrees of freedom), the set found is widened to every normal row
/// of a frictionless contact with w = 0, if that keeps the conditions and w. For an LCP (normal
/// rows only) that gives the least-norm x of all its solutions, the same from both methods,
/// which shares the impulse evenly between symmetric corners; widening may report a row with
/// x = 0 and w = 0 (grazing) as active. With gripping contacts the problem is no LCP and its
/// w need not be unique: enumeration prefers the fewest rows active, the pivoting search the
/// fewest gripping contacts active, and the two may then give different valid answers.
pub fn solve(
    a: &DMatrix<f64>,
    c: &[f64],
    rows: &[Row],
    tolerance: f64,
) -> Result<Solution, Unsolved> {
    let problem = Problem::new(a, c, rows, tolerance)?;
    if problem.normals.len() <= ENUMERATION_LIMIT {
        problem.enumerate()
    } else {
        problem.lemke()
    }
}

/// Solves the problem by enumerating the active sets of its normal rows, whatever their number
/// (2^normals solves in the worst case): fewest active first, then in lexicographic order of
/// their indices. The first valid one is widened as [`solve`] says.
pub fn enumerate(
    a: &DMatrix<f64>,
    c: &[f64],
    rows: &[Row],
    tolerance: f64,
) -> Result<Solution, Unsolved> {
    Problem::new(a, c, rows, tolerance)?.enumerate()
}

/// Solves a problem of normal rows only (an LCP) by Lemke's complementary pivoting, with the
/// covering vector of ones on the problem scaled to a unit diagonal, and the lexicographic
/// minimum-ratio rule so that it cannot cycle. For a positive semidefinite A it finds a solution
/// whenever there is one, and otherwise ends on a secondary ray: [`Unsolved::Inconsistent`]. The
/// basis it ends on is then polished as [`solve`] says.
pub fn lemke(a: &DMatrix<f64>, c: &[f64], tolerance: f64) -> Result<Solution, Unsolved> {
    let rows = vec![Row::Normal; c.len()];
    Problem::new(a, c, &rows, tolerance)?.lemke()
}

/// Solves a problem with gripping contacts by enumerating the active sets of the gripping
/// contacts' normal rows only (at most [`ENUMERATION_LIMIT`] of them; fewest active first,
/// then lexicographic) and pivoting with Lemke's method for the other normal rows. For each
/// choice G, the rows of the gripping contacts outside G are dropped (x = 0 there), the tangent
/// rows of those in G are equalities with x free, eliminated by a least-norm solve (their
/// Schur complement in A is positive semidefinite again), and Lemke's method solves the
/// remaining LCP of the normal rows. The choice is valid if G's normal rows come out active
/// and the dropped normal rows' w ≥ 0. This finds a solution whenever there is one: a solution
/// with gripping contacts G active solves G's reduced LCP, whose w every solution shares, and
/// so do the dropped rows' w (A·z = 0 for the difference z of two solutions). Without gripping
/// contacts it is Lemke's method alone.
pub fn lemke_with_grips(
    a: &DMatrix<f64>,
    c: &[f64],
    rows: &[Row],
    tolerance: f64,
) -> Result<Solution, Unsolved> {
    Problem::new(a, c, rows, tolerance)?.lemke()
}

/// A checked problem and the structure of its rows.
struct Problem<'a> {
    a: &'a DMatrix<f64>,
    c: &'a [f64],
    rows: &'a [Row],
    tolerance: f64,
    /// The indices of the normal rows, in order.
    normals: Vec<usize>,
}

/// How a pivoting run ended.
enum Pivoting {
    /// A complementary basis: x, the rows whose x is basic, and the pivots it took.
    Solved { x: Vec<f64>, basic: Vec<bool>, pivots: usize },
    /// A secondary ray: no solution.
    Ray,
    /// The budget of pivots ran out.
    Budget { pivots: usize },
}

impl<'a> Problem<'a> {
    fn new(
        a: &'a DMatrix<f64>,
        c: &'a [f64],
        rows: &'a [Row],
        tolerance: f64,
    ) -> Result<Self, Unsolved> {
        let k = rows.len();
        if a.nrows() != k || a.ncols() != k || c.len() != k {
            return Err(Unsolved::Malformed {
                reason: "A must be k×k and c of length k for k rows",
            });
        }
        for row in rows {
            if let Row::Tangent { normal } = *row {
                if !matches!(rows.get(normal), Some(Row::Normal)) {
                    return Err(Unsolved::Malformed {
                        reason: "a tangent row must name a normal row",
                    });
                }
            }
        }
        let non_finite: Vec<usize> = (0..k)
            .filter(|&i| !c[i].is_finite() || a.row(i).iter().any(|v| !v.is_finite()))
            .collect();
        if !non_finite.is_empty() || !tolerance.is_finite() {
            return Err(Unsolved::NonFinite { rows: non_finite });
        }
        if tolerance < 0.0 {
            return Err(Unsolved::Malformed { reason: "the tolerance must not be negative" });
        }
        let normals = (0..k).filter(|&i| rows[i] == Row::Normal).collect();
        Ok(Problem { a, c, rows, tolerance, normals })
    }

    /// Whether row `i` is in the equalities when the normal rows `active` are.
    fn in_equalities(&self, active: &[bool], i: usize) -> bool {
        match self.rows[i] {
            Row::Normal => active[i],
            Row::Tangent { normal } => active[normal],
        }
    }

    /// The least-norm x of the active set `active` (indexed by row, read at the normal rows),
    /// if it satisfies the conditions. The x solving the set's equalities are the least-norm
    /// one, x₀, plus the null space of their block of A, which leaves w unchanged (A is
    /// positive semidefinite: zᵀ·A·z = 0 makes A·z = 0). If x₀ pushes with a negative x on an
    /// active normal row, the least-norm x that does not is sought along that null space.
    fn attempt(&self, active: &[bool]) -> Option<Solution> {
        let k = self.rows.len();
        let equalities: Vec<usize> = (0..k).filter(|&i| self.in_equalities(active, i)).collect();
        let mut x = vec![0.0; k];
        if !equalities.is_empty() {
            let m = equalities.len();
            let block = DMatrix::from_fn(m, m, |r, s| self.a[(equalities[r], equalities[s])]);
            let rhs = DVector::from_iterator(m, equalities.iter().map(|&i| -self.c[i]));
            let (least, null) = least_norm(block, &rhs);
            let signed: Vec<usize> =
                (0..m).filter(|&r| self.rows[equalities[r]] == Row::Normal).collect();
            let pushes_back = signed.iter().any(|&r| least[r] < -self.tolerance);
            let solved = if pushes_back && null.ncols() > 0 {
                self.least_norm_nonnegative(&least, &null, &signed)?
            } else {
                least
            };
            for (r, &i) in equalities.iter().enumerate() {
                x[i] = solved[r];
            }
        }
        self.check(active, x)
    }

    /// x as the solution of the active set `active`, if it satisfies the conditions: the rows
    /// outside the set's equalities must have x = 0 (as attempts make them).
    fn check(&self, active: &[bool], x: Vec<f64>) -> Option<Solution> {
        let k = self.rows.len();
        let w = self.residual(&x);
        let tol = self.tolerance;
        let holds = (0..k).all(|i| match self.rows[i] {
            Row::Normal if active[i] => w[i].abs() <= tol && x[i] >= -tol,
            Row::Normal => w[i] >= -tol && x[i] == 0.0,
            Row::Tangent { normal } if active[normal] => w[i].abs() <= tol,
            Row::Tangent { .. } => x[i] == 0.0,
        });
        holds.then(|| Solution {
            x,
            w,
            active: (0..k).map(|i| self.in_equalities(active, i)).collect(),
        })
    }

    /// The least-norm y = x₀ + N·t with y ≥ 0 at the positions `signed`, where x₀ is orthogonal
    /// to the orthonormal columns of N, so that |y|² = |x₀|² + |t|². The least |t| with
    /// G·t ≥ −x₀ (G the rows `signed` of N) has t = Gᵀ·μ for the μ solving the complementarity
    /// problem G·Gᵀ·μ + x₀ ≥ 0, μ ≥ 0 (its conditions of optimality), of normal rows and
    /// positive semidefinite; `None` if it has no solution (no such y).
    fn least_norm_nonnegative(
        &self,
        least: &DVector<f64>,
        null: &DMatrix<f64>,
        signed: &[usize],
    ) -> Option<DVector<f64>> {
        let g = DMatrix::from_fn(signed.len(), null.ncols(), |r, s| null[(signed[r], s)]);
        let gram = &g * g.transpose();
        let offset: Vec<f64> = signed.iter().map(|&r| least[r]).collect();
        match pivot_lcp(&gram, &offset, self.tolerance) {
            Pivoting::Solved { x: mu, .. } => {
                let t = g.transpose() * DVector::from_vec(mu);
                Some(least + null * t)
            }
            Pivoting::Ray | Pivoting::Budget { .. } => None,
        }
    }

    /// w = A·x + c.
    fn residual(&self, x: &[f64]) -> Vec<f64> {
        let k = self.rows.len();
        (0..k).map(|i| self.c[i] + (0..k).map(|j| self.a[(i, j)] * x[j]).sum::<f64>()).collect()
    }

    /// The widest active set's solution: every frictionless normal row whose w is zero (to the
    /// tolerance) in `found` made active, if its x keeps the conditions and w, and `found`
    /// otherwise. The solutions of a positive semidefinite LCP share w, and those with the rows
    /// Z (where w = 0) active are all of them: the least-norm x of Z is the least-norm solution
    /// of the whole problem, the same whichever active set was found first. (With tangent rows
    /// the problem has no such structure: a gripping contact is not widened, as closing it would
    /// make a grazing contact grip that the solution found left open.)
    fn widen(&self, found: Solution) -> Solution {
        let gripping = self.gripping();
        let wide: Vec<bool> = (0..self.rows.len())
            .map(|i| {
                self.rows[i] == Row::Normal
                    && (found.active[i]
                        || (found.w[i].abs() <= self.tolerance && !gripping.contains(&i)))
            })
            .collect();
        let same = self.normals.iter().all(|&i| wide[i] == found.active[i]);
        if same {
            return found;
        }
        match self.attempt(&wide) {
            Some(widened)
                if (0..self.rows.len())
                    .all(|i| (widened.w[i] - found.w[i]).abs() <= self.tolerance) =>
            {
                widened
            }
            _ => found,
        }
    }

    fn enumerate(&self) -> Result<Solution, Unsolved> {
        match self.first_valid() {
            Some(found) => Ok(self.widen(found)),
            None => Err(self.inconsistent().into()),
        }
    }

    /// The first valid active set, fewest active first, then lexicographic.
    fn first_valid(&self) -> Option<Solution> {
        let mut active = vec![false; self.rows.len()];
        combinations(self.normals.len(), |chosen| {
            active.iter_mut().for_each(|a| *a = false);
            for &p in chosen {
                active[self.normals[p]] = true;
            }
            self.attempt(&active)
        })
    }

    fn lemke(&self) -> Result<Solution, Unsolved> {
        match self.search_gripping()? {
            Some(found) => Ok(self.widen(found)),
            None => Err(self.inconsistent().into()),
        }
    }

    /// The normal rows that have tangent rows.
    fn gripping(&self) -> Vec<usize> {
        let mut gripping: Vec<usize> = self
            .rows
            .iter()
            .filter_map(|row| match *row {
                Row::Tangent { normal } => Some(normal),
                Row::Normal => None,
            })
            .collect();
        gripping.sort_unstable();
        gripping.dedup();
        gripping
    }

    /// The first valid choice of active gripping contacts, each solved by Lemke's method for
    /// the other normal rows (see [`lemke_with_grips`]); `None` if no choice is valid.
    fn search_gripping(&self) -> Result<Option<Solution>, Unsolved> {
        let gripping = self.gripping();
        if gripping.len() > ENUMERATION_LIMIT {
            return Err(Unsolved::TooLarge { normals: self.normals.len() });
        }
        let mut stalled = None;
        let mut chosen_rows = vec![false; self.rows.len()];
        let found = combinations(gripping.len(), |chosen| {
            chosen_rows.iter_mut().for_each(|g| *g = false);
            for &p in chosen {
                chosen_rows[gripping[p]] = true;
            }
            match self.with_grips(&gripping, &chosen_rows) {
                Ok(Some(solution)) => Some(solution),
                Ok(None) => None,
                Err(pivots) => {
                    stalled = Some(pivots);
                    None
                }
            }
        });
        match (found, stalled) {
            (Some(solution), _) => Ok(Some(solution)),
            (None, Some(pivots)) => Err(Unsolved::Stalled { pivots }),
            (None, None) => Ok(None),
        }
    }

    /// The solution with the gripping contacts `chosen` (indexed by row) active and the other
    /// ones of `gripping` open, if there is one; `Err` with the pivots made if Lemke's method
    /// stalled.
    fn with_grips(&self, gripping: &[usize], chosen: &[bool]) -> Result<Option<Solution>, usize> {
        let k = self.rows.len();
        let tol = self.tolerance;
        let dropped = |i: usize| match self.rows[i] {
            Row::Normal => gripping.contains(&i) && !chosen[i],
            Row::Tangent { normal } => !chosen[normal],
        };
        let tangents: Vec<usize> =
            (0..k).filter(|&i| !dropped(i) && self.rows[i] != Row::Normal).collect();
        let normals: Vec<usize> = self.normals.iter().copied().filter(|&i| !dropped(i)).collect();
        let (t, n) = (tangents.len(), normals.len());
        let block = |r: &[usize], s: &[usize]| {
            DMatrix::from_fn(r.len(), s.len(), |p, q| self.a[(r[p], s[q])])
        };
        // x_T = −A_TT⁺·(c_T + A_TN·x_N) = −(y₀ + Y·x_N).
        let (reduced, offset, through): (DMatrix<f64>, Vec<f64>, _) = if t == 0 {
            (block(&normals, &normals), normals.iter().map(|&i| self.c[i]).collect(), None)
        } else {
            let a_tt = block(&tangents, &tangents);
            let a_tn = block(&tangents, &normals);
            let mut rhs = DMatrix::zeros(t, n + 1);
            for p in 0..t {
                rhs[(p, 0)] = self.c[tangents[p]];
            }
            rhs.columns_mut(1, n).copy_from(&a_tn);
            let y = pseudo_solve(a_tt.clone(), &rhs);
            // The tangent rows must be solvable at all: c_T in the range of A_TT.
            let misfit = &a_tt * y.column(0) - rhs.column(0);
            if misfit.amax() > tol {
                return Ok(None);
            }
            let y_n = y.columns(1, n).into_owned();
            let a_nt = a_tn.transpose();
            let schur = block(&normals, &normals) - &a_nt * &y_n;
            // Symmetric in exact arithmetic; kept so against rounding.
            let schur = (&schur + schur.transpose()) * 0.5;
            let shifted =
                DVector::from_iterator(n, normals.iter().map(|&i| self.c[i])) - &a_nt * y.column(0);
            (schur, shifted.iter().copied().collect(), Some(y))
        };
        let (x_n, basic, pivots) = match pivot_lcp(&reduced, &offset, tol) {
            Pivoting::Solved { x, basic, pivots } => (x, basic, pivots),
            Pivoting::Ray => return Ok(None),
            Pivoting::Budget { pivots } => return Err(pivots),
        };
        // Lemke's basis, then the rows whose x came out positive (the chosen grips active
        // throughout): the first whose least-norm solve holds.
        let mut by_basis = vec![false; k];
        let mut by_sign = vec![false; k];
        for (p, &i) in normals.iter().enumerate() {
            by_basis[i] = basic[p] || chosen[i];
            by_sign[i] = x_n[p] > tol || chosen[i];
        }
        for active in [&by_basis, &by_sign] {
            if let Some(found) = self.attempt(active) {
                return Ok(Some(found));
            }
        }
        // Lemke's own x, if it holds as it is.
        let mut x = vec![0.0; k];
        for (p, &i) in normals.iter().enumerate() {
            x[i] = x_n[p];
        }
        if let Some(y) = through {
            let x_t = -(y.column(0) + y.columns(1, n) * DVector::from_vec(x_n));
            for (p, &i) in tangents.iter().enumerate() {
                x[i] = x_t[p];
            }
        }
        match self.check(&by_basis, x) {
            Some(found) => Ok(Some(found)),
            // Without gripping contacts Lemke's answer is the answer: rounding spoilt it.
            None if gripping.is_empty() => Err(pivots),
            // With them, the choice may just be wrong (a dropped contact's w < 0).
            None => Ok(None),
        }
    }

    /// Lemke's pivots allowed: far more than the few per row that problems take.
    fn pivot_budget(&self) -> usize {
        50 * (self.rows.len() + 1)
    }

    /// Lemke's complementary pivoting on the tableau [I, −Ā, −d, c̄] of the problem scaled by
    /// D = diag(1/√A_ii) (Ā = D·A·D, c̄ = D·c, x = D·x̄), with d = 1. Basic variables are numbered
    /// w_i = i, x_i = n + i and the artificial z₀ = 2n.
    fn pivot(&self) -> Pivoting {
        let n = self.rows.len();
        // A diagonal at rounding's level (a row that is zero but for rounding) is not scaled
        // up: its entries would swamp the rest.
        let largest_diagonal = (0..n).fold(0.0f64, |m, i| m.max(self.a[(i, i)]));
        let scale: Vec<f64> = (0..n)
            .map(|i| {
                let d = self.a[(i, i)];
                if d > RELATIVE_RANK * largest_diagonal {
                    1.0 / d.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let c_scaled: Vec<f64> = (0..n).map(|i| scale[i] * self.c[i]).collect();
        if c_scaled.iter().all(|&v| v >= 0.0) {
            return Pivoting::Solved { x: vec![0.0; n], basic: vec![false; n], pivots: 0 };
        }
        let z0 = 2 * n;
        let rhs = 2 * n + 1;
        let mut tableau = DMatrix::zeros(n, 2 * n + 2);
        for i in 0..n {
            tableau[(i, i)] = 1.0;
            for j in 0..n {
                tableau[(i, n + j)] = -scale[i] * self.a[(i, j)] * scale[j];
            }
            tableau[(i, z0)] = -1.0;
            tableau[(i, rhs)] = c_scaled[i];
        }
        let mut basis: Vec<usize> = (0..n).collect();
        // Ties in the right-hand side are judged on the tolerance, scaled as c is.
        let max_scale = scale.iter().fold(0.0f64, |m, &s| m.max(s));
        let rhs_tie = self.tolerance * max_scale;

        // z₀ enters where the right-hand side is most negative (per unit of d): the
        // lexicographic minimum of the rows (c̄_i, B⁻¹_i) / d_i, with d = 1.
        let all: Vec<usize> = (0..n).collect();
        let first = lexicographic_minimum(&tableau, &all, &vec![1.0; n], rhs_tie);
        let mut entering = z0;
        let mut row = first;
        let budget = self.pivot_budget();
        for made in 0..budget {
            let leaving = basis[row];
            pivot_on(&mut tableau, row, entering);
            basis[row] = entering;
            if leaving == z0 {
                let mut x = vec![0.0; n];
                let mut basic = vec![false; n];
                for (r, &var) in basis.iter().enumerate() {
                    if (n..2 * n).contains(&var) {
                        let j = var - n;
                        x[j] = scale[j] * tableau[(r, rhs)];
                        basic[j] = true;
                    }
                }
                return Pivoting::Solved { x, basic, pivots: made + 1 };
            }
            // The complement of the variable that left enters next.
            entering = if leaving < n { leaving + n } else { leaving - n };
            let column: Vec<f64> = (0..n).map(|r| tableau[(r, entering)]).collect();
            let candidates: Vec<usize> = (0..n).filter(|&r| column[r] > PIVOT_FLOOR).collect();
            if candidates.is_empty() {
                return Pivoting::Ray;
            }
            row = lexicographic_minimum(&tableau, &candidates, &column, rhs_tie);
            // When z₀ ties for leaving, let it leave: that ends the run on a solution.
            if let Some(r) = candidates.iter().copied().find(|&r| basis[r] == z0) {
                let ratio = |r: usize| tableau[(r, rhs)] / column[r];
                if ties(ratio(r), ratio(row), rhs_tie / column[r].min(column[row])) {
                    row = r;
                }
            }
        }
        Pivoting::Budget { pivots: budget }
    }

    /// The rows of a set of contacts that cannot be satisfied together: starting from all of
    /// them, each contact (a normal row with its tangent rows) is dropped in turn if the rest
    /// is still unsolvable.
    fn inconsistent(&self) -> Inconsistent {
        let k = self.rows.len();
        let mut kept = vec![true; k];
        for &n in &self.normals {
            let mut trial = kept.clone();
            for i in 0..k {
                if i == n || self.rows[i] == (Row::Tangent { normal: n }) {
                    trial[i] = false;
                }
            }
            if !self.subproblem_solvable(&trial) {
                kept = trial;
            }
        }
        Inconsistent { rows: (0..k).filter(|&i| kept[i]).collect() }
    }

    /// Whether the problem restricted to the rows `kept` has a solution (by the same method
    /// [`solve`] would use on it).
    fn subproblem_solvable(&self, kept: &[bool]) -> bool {
        let index: Vec<usize> = (0..self.rows.len()).filter(|&i| kept[i]).collect();
        let position = |i: usize| index.iter().position(|&j| j == i);
        let m = index.len();
        let a = DMatrix::from_fn(m, m, |r, s| self.a[(index[r], index[s])]);
        let c: Vec<f64> = index.iter().map(|&i| self.c[i]).collect();
        let rows: Vec<Row> = index
            .iter()
            .map(|&i| match self.rows[i] {
                Row::Normal => Row::Normal,
                // A kept tangent row's normal row is kept with it.
                Row::Tangent { normal } => Row::Tangent { normal: position(normal).unwrap_or(0) },
            })
            .collect();
        let normals = (0..m).filter(|&i| rows[i] == Row::Normal).collect::<Vec<_>>();
        let sub = Problem { a: &a, c: &c, rows: &rows, tolerance: self.tolerance, normals };
        if sub.normals.len() <= ENUMERATION_LIMIT {
            sub.first_valid().is_some()
        } else {
            // A search that stalled proves nothing: the contact is kept as if it mattered.
            !matches!(sub.search_gripping(), Ok(None))
        }
    }
}

/// Calls `visit` with the combinations of positions 0..n (increasing), fewest first, then in
/// lexicographic order, until it returns something.
fn combinations<T>(n: usize, mut visit: impl FnMut(&[usize]) -> Option<T>) -> Option<T> {
    for size in 0..=n {
        let mut chosen: Vec<usize> = (0..size).collect();
        loop {
            if let Some(found) = visit(&chosen) {
                return Some(found);
            }
            // The next combination: the last position that can advance does, and those after
            // it follow it closely.
            let Some(p) = (0..size).rev().find(|&p| chosen[p] < n - size + p) else { break };
            chosen[p] += 1;
            for q in p + 1..size {
                chosen[q] = chosen[q - 1] + 1;
            }
        }
    }
    None
}

/// Lemke's method on an LCP of normal rows only.
fn pivot_lcp(a: &DMatrix<f64>, c: &[f64], tolerance: f64) -> Pivoting {
    let rows = vec![Row::Normal; c.len()];
    let normals = (0..c.len()).collect();
    Problem { a, c, rows: &rows, tolerance, normals }.pivot()
}

/// The least-norm least-squares solutions of the symmetric system m·Y = rhs, column by column,
/// with eigenvalues below [`RELATIVE_RANK`] of the largest (in size) taken as zero.
fn pseudo_solve(m: DMatrix<f64>, rhs: &DMatrix<f64>) -> DMatrix<f64> {
    let (values, vectors) = symmetric_eigen(m);
    let kept = range_of(&values);
    // Y = Σ v·(vᵀ·rhs)/λ over the kept eigenpairs.
    let mut y = DMatrix::zeros(vectors.nrows(), rhs.ncols());
    for &e in &kept {
        let v = vectors.column(e);
        let projected = v.transpose() * rhs / values[e];
        y += v * projected;
    }
    y
}

/// The least-norm least-squares solution of the symmetric system m·y = rhs, and an orthonormal
/// basis of m's null space (as columns), with eigenvalues below [`RELATIVE_RANK`] of the
/// largest (in size) taken as zero.
pub(crate) fn least_norm(m: DMatrix<f64>, rhs: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
    let (values, vectors) = symmetric_eigen(m);
    let kept = range_of(&values);
    let mut y = DVector::zeros(vectors.nrows());
    for &e in &kept {
        let v = vectors.column(e);
        y += v * (v.dot(rhs) / values[e]);
    }
    let null: Vec<usize> = (0..values.len()).filter(|e| !kept.contains(e)).collect();
    let basis = DMatrix::from_fn(vectors.nrows(), null.len(), |i, s| vectors[(i, null[s])]);
    (y, basis)
}

/// The eigenpairs that span the range: eigenvalues above [`RELATIVE_RANK`] of the largest in
/// size.
fn range_of(values: &[f64]) -> Vec<usize> {
    let largest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let threshold = RELATIVE_RANK * largest;
    (0..values.len()).filter(|&e| values[e].abs() > threshold).collect()
}

/// The most sweeps of Jacobi's method: it converges quadratically, in some ten sweeps for the
/// orders met here, so this cap is only reached by a matrix that is not finite.
const JACOBI_SWEEPS: usize = 100;

/// The eigenvalues and orthonormal eigenvectors (as columns) of the symmetric matrix m (its
/// mean with its transpose), by cyclic Jacobi rotations. Written here rather than taken from
/// nalgebra: its SVD, with a tight convergence threshold, returned factors that do not multiply
/// back to the matrix for a block with a zero row ([[2,0,0,2],[0,0,0,0],[0,0,2,0],[2,0,0,2]]),
/// and Jacobi's method is simple, accurate for symmetric matrices and its result orthogonal to
/// rounding.
fn symmetric_eigen(m: DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let n = m.nrows();
    let mut a = (&m + m.transpose()) * 0.5;
    let mut v = DMatrix::identity(n, n);
    // Off-diagonal entries below this are rounding, left alone: a hundredth of a unit in the
    // last place of the matrix's norm.
    let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    let negligible = 1e-2 * f64::EPSILON * norm;
    for _ in 0..JACOBI_SWEEPS {
        let mut largest_off: f64 = 0.0;
        for p in 0..n {
            for q in p + 1..n {
                largest_off = largest_off.max(a[(p, q)].abs());
            }
        }
        if largest_off <= negligible || !largest_off.is_finite() {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[(p, q)];
                if apq.abs() <= negligible {
                    continue;
                }
                // The rotation that zeroes a_pq (Numerical Recipes' form, stable for any θ).
                let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = if theta.abs() > 1e150 {
                    0.5 / theta
                } else {
                    let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
                    sign / (theta.abs() + (theta * theta + 1.0).sqrt())
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[(k, p)], a[(k, q)]);
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[(p, k)], a[(q, k)]);
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
                // Zero by construction; set so, rather than left at rounding.
                a[(p, q)] = 0.0;
                a[(q, p)] = 0.0;
                for k in 0..n {
                    let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                    v[(k, p)] = c * vkp - s * vkq;
                    v[(k, q)] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..n).map(|i| a[(i, i)]).collect(), v)
}

/// Whether two ratios of Lemke's test tie: equal to [`RATIO_TIE`] of their size, or within
/// `absolute` (the tolerance, for right-hand sides near zero).
fn ties(u: f64, v: f64, absolute: f64) -> bool {
    (u - v).abs() <= RATIO_TIE * u.abs().max(v.abs()) + absolute
}

/// The lexicographic minimum-ratio row among `candidates`: the least right-hand side over
/// the pivot column's entry, ties broken by the rows of B⁻¹ (the tableau's first n columns)
/// over the same entry. The rows of B⁻¹ are independent, so two rows never tie all through,
/// and no basis repeats: Lemke's method cannot cycle.
fn lexicographic_minimum(
    tableau: &DMatrix<f64>,
    candidates: &[usize],
    column: &[f64],
    rhs_tie: f64,
) -> usize {
    let n = tableau.nrows();
    let rhs = 2 * n + 1;
    let key = |r: usize, j: usize| {
        let value = if j == 0 { tableau[(r, rhs)] } else { tableau[(r, j - 1)] };
        value / column[r]
    };
    let mut best = candidates[0];
    for &r in &candidates[1..] {
        for j in 0..=n {
            let absolute = if j == 0 { rhs_tie / column[r].min(column[best]) } else { 0.0 };
            let (u, v) = (key(r, j), key(best, j));
            if ties(u, v, absolute) {
                continue;
            }
            if u < v {
                best = r;
            }
            break;
        }
    }
    best
}

/// Gauss–Jordan pivot of the tableau on (row, column).
fn pivot_on(tableau: &mut DMatrix<f64>, row: usize, column: usize) {
    let width = tableau.ncols();
    let p = tableau[(row, column)];
    for j in 0..width {
        tableau[(row, j)] /= p;
    }
    for r in 0..tableau.nrows() {
        if r == row {
            continue;
        }
        let f = tableau[(r, column)];
        if f != 0.0 {
            for j in 0..width {
                tableau[(r, j)] -= f * tableau[(row, j)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// V·diag(λ)·Vᵀ against m, and Vᵀ·V against the identity.
    fn assert_decomposes(m: &DMatrix<f64>) {
        let (values, vectors) = symmetric_eigen(m.clone());
        let n = m.nrows();
        let back =
            &vectors * DMatrix::from_diagonal(&DVector::from_vec(values)) * vectors.transpose();
        let scale = m.amax().max(1.0);
        assert!((back - m).amax() <= 1e-14 * scale, "{m}");
        assert!((vectors.transpose() * &vectors - DMatrix::identity(n, n)).amax() <= 1e-14);
    }

    #[test]
    fn jacobi_decomposes_where_nalgebras_svd_did_not() {
        // The block with a zero row on which nalgebra's SVD (with ε = f64::EPSILON) returned
        // factors that multiply back to something else.
        let m = DMatrix::from_row_slice(
            4,
            4,
            &[2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 2.0, 0.0, 0.0, 2.0],
        );
        assert_decomposes(&m);
        let (least, null) = least_norm(m, &DVector::from_vec(vec![1.0, 0.0, 1.0, 1.0]));
        assert!((least - DVector::from_vec(vec![0.25, 0.0, 0.5, 0.25])).amax() < 1e-15);
        assert_eq!(null.ncols(), 2);
        // Equal eigenvalues, a zero matrix, one entry, and a full symmetric one.
        assert_decomposes(&DMatrix::identity(5, 5));
        assert_decomposes(&DMatrix::zeros(3, 3));
        assert_decomposes(&DMatrix::from_element(1, 1, -3.0));
        assert_decomposes(&DMatrix::from_fn(6, 6, |i, j| 1.0 / (1.0 + i as f64 + j as f64)));
    }
}
