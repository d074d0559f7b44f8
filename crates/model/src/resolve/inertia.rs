//! The inertia tensor of a body in space checked at the parameters' values: one that some
//! turning would give negative kinetic energy, or that no distribution of mass has, is an
//! error at the inertia as written.

use cas::number::{Signed, Zero};
use cas::{ExprId, Rational};
use lang::{Diagnostic, Expr, ExprKind, Ident};

use super::checks::{number_text, ROUNDING_MARGIN};
use super::Resolver;

/// How an inequality between known constants came out: exactly when the constant is a
/// rational, otherwise in floating point with a margin relative to `scale`, so that an exact
/// boundary (a thin plate's C = A + B written with `sqrt`) is not refused for rounding.
fn below_zero(pool: &cas::Pool, value: ExprId, scale: f64) -> bool {
    match pool.as_num(value) {
        Some(q) => q.is_negative(),
        None => {
            let x = numeric::eval(pool, value, &[]);
            x.is_finite() && x < -ROUNDING_MARGIN * scale.max(f64::MIN_POSITIVE)
        }
    }
}

/// The principal minors of a symmetric 3×3 matrix, each with the rows it is taken over
/// (counted from 1), smallest first: a symmetric matrix is positive semidefinite exactly when
/// none is negative (the leading minors alone would miss `diag(0, -1, 0)`).
fn principal_minors(pool: &mut cas::Pool, m: &[[ExprId; 3]; 3]) -> Vec<(Vec<usize>, ExprId, u32)> {
    let mut out: Vec<(Vec<usize>, ExprId, u32)> =
        (0..3).map(|i| (vec![i + 1], m[i][i], 1)).collect();
    for (r, c) in [(0, 1), (0, 2), (1, 2)] {
        let diagonal = pool.mul2(m[r][r], m[c][c]);
        let off = pool.powi(m[r][c], 2);
        out.push((vec![r + 1, c + 1], pool.sub(diagonal, off), 2));
    }
    let rows: Vec<Vec<ExprId>> = m.iter().map(|r| r.to_vec()).collect();
    let cross = crate::kinematics::cross(pool, &rows[1], &rows[2]);
    out.push((vec![1, 2, 3], crate::kinematics::dot(pool, &rows[0], &cross), 3));
    out
}

impl Resolver<'_> {
    /// A body's inertia tensor in space, at the parameters' values: positive semidefinite (or
    /// ½·ωᵀ·I·ω is negative for some ω, and the motion blows up), and with each principal
    /// moment at most the sum of the other two, as every distribution of mass has (equal for
    /// a thin plate). Left alone where the tensor depends on the state.
    pub(super) fn check_inertia_tensor(
        &mut self,
        body: &Ident,
        tensor: &[[ExprId; 3]; 3],
        written: &Expr,
    ) {
        let mut known = [[tensor[0][0]; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                let Some(k) = self.known(tensor[r][c]) else { return };
                known[r][c] = k;
            }
        }
        let scale = known
            .iter()
            .flatten()
            .map(|e| numeric::eval(&self.model.pool, *e, &[]).abs())
            .fold(0.0, f64::max);
        if !scale.is_finite() {
            return;
        }
        let diagonal = (0..3).all(|r| {
            (0..3)
                .all(|c| r == c || self.model.pool.as_num(known[r][c]).is_some_and(|q| q.is_zero()))
        });
        if self.is_semidefinite(body, &known, scale, written) {
            self.obeys_the_triangle(body, &known, scale, diagonal, written);
        }
    }

    /// Whether a tensor known in numbers is positive semidefinite (every principal minor at
    /// least 0, within rounding at its `scale`); reported at `written` if not.
    fn is_semidefinite(
        &mut self,
        body: &Ident,
        known: &[[ExprId; 3]; 3],
        scale: f64,
        written: &Expr,
    ) -> bool {
        if let Some((rows, minor)) = self.negative_minor(known, scale) {
            let axis = |i: usize| ["x", "y", "z"][i - 1];
            let value = number_text(&self.model.pool, minor);
            let label = match rows[..] {
                [r] => format!("I{0}{0} is {value} kg·m²", axis(r)),
                [r, c] => format!(
                    "I{0}{0}·I{1}{1} − I{0}{1}² is {value} kg²·m⁴: the product of inertia \
                     I{0}{1} is too large",
                    axis(r),
                    axis(c)
                ),
                _ => format!("its determinant is {value} kg³·m⁶"),
            };
            self.error(
                Diagnostic::error(
                    written.span,
                    format!("the inertia tensor of `{}` is not positive semidefinite", body.name),
                )
                .with_label(label)
                .with_hint(
                    "with it some turning would have negative kinetic energy; a tensor's \
                     diagonal entries are 0 or more and each product of inertia is at most \
                     the geometric mean of its two moments (Ixy² ≤ Ixx·Iyy); check signs and \
                     parameters' values",
                ),
            );
            return false;
        }
        true
    }

    /// Whether each principal moment of a tensor known in numbers is at most the sum of the
    /// other two; reported if not, at the moment itself where the moments are written apart.
    fn obeys_the_triangle(
        &mut self,
        body: &Ident,
        known: &[[ExprId; 3]; 3],
        scale: f64,
        diagonal: bool,
        written: &Expr,
    ) {
        // Σ = tr(I)/2·1 − I is the second moment ∫ r·rᵀ dm of the mass, which no mass
        // distribution can make indefinite; its diagonal is (B + C − A)/2 and so on.
        let trace = self.model.pool.add(&[known[0][0], known[1][1], known[2][2]]);
        let half = self.model.pool.num(Rational::new(1.into(), 2.into()));
        let half = self.model.pool.mul2(half, trace);
        let second: [[ExprId; 3]; 3] = std::array::from_fn(|r| {
            std::array::from_fn(|c| {
                let minus = self.model.pool.neg(known[r][c]);
                if r == c {
                    self.model.pool.add(&[half, minus])
                } else {
                    minus
                }
            })
        });
        if let Some((rows, _)) = self.negative_minor(&second, scale) {
            let span = match (&written.kind, diagonal && rows.len() == 1) {
                (ExprKind::Tuple(parts), true) if parts.len() == 3 => parts[rows[0] - 1].span,
                _ => written.span,
            };
            let moments = if diagonal {
                let i = rows[0] - 1;
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                let others = self.model.pool.add(&[known[j][j], known[k][k]]);
                let others = self.model.pool.simplify(others);
                let name = if span == written.span {
                    let axis = ["x", "y", "z"][i];
                    format!("I{axis}{axis}")
                } else {
                    format!("`{}`", self.text(span))
                };
                format!(
                    "{name} is {} kg·m², more than the other two moments together ({} kg·m²)",
                    number_text(&self.model.pool, known[i][i]),
                    number_text(&self.model.pool, others)
                )
            } else {
                "one principal moment is more than the other two together".to_string()
            };
            self.error(
                Diagnostic::error(
                    span,
                    format!("no rigid body has the inertia given to `{}`", body.name),
                )
                .with_label(moments)
                .with_hint(
                    "each principal moment is at most the sum of the other two (equal for a \
                     thin plate); e.g. a solid cylinder of radius r and height h about its \
                     centre has (m*(3*r^2 + h^2)/12, m*(3*r^2 + h^2)/12, m*r^2/2)",
                ),
            );
        }
    }

    /// The first principal minor of a matrix known in numbers that is below zero, within
    /// rounding at `scale`: the rows it is taken over, and its value.
    fn negative_minor(&mut self, m: &[[ExprId; 3]; 3], scale: f64) -> Option<(Vec<usize>, ExprId)> {
        for (rows, minor, degree) in principal_minors(&mut self.model.pool, m) {
            let minor = self.model.pool.simplify(minor);
            let scale = numeric::elementary::pow_int(scale, degree as i32);
            if below_zero(&self.model.pool, minor, scale) {
                return Some((rows, minor));
            }
        }
        None
    }
}
