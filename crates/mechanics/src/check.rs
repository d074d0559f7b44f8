//! Deciding `expect` lines by algebra, and saying what is left for numbers where it cannot:
//! the numeric side (random states, the constraint surface, verdicts) is the `verify` crate's.

use std::collections::HashMap;

use cas::{ExprId, SymId, SymbolKind};

use crate::derive::Derivation;
use crate::start_solution::StartSolution;

/// What the algebra makes of one entry (lhs − rhs) of an `expect` line.
#[derive(Clone, Debug)]
pub enum Decision {
    /// The residual simplifies to zero.
    Exact,
    /// The residual simplifies to zero once the kept constraints are used (x² = L² − y²).
    ExactOnConstraints,
    /// The algebra could not decide: numbers must compare this residual (simplified) with
    /// zero at random states, solving for the accelerations and multipliers at each state when
    /// `solve` says so.
    Sample { residual: ExprId, solve: bool },
    /// At the start, whose unknowns are too many for the exact solve: numbers must solve the
    /// start at random parameter values and compare this residual with zero there.
    SampleAtStart { residual: ExprId, unknowns: usize },
    /// At the start, where the mass matrix (with the constraints' rows) is singular: nothing
    /// can be decided.
    SingularAtStart,
}

impl Derivation {
    /// Both sides of `expect` line `index`, each entry expanded into the remaining coordinates
    /// (the reactions of kept constraints stay multipliers).
    pub fn expect_sides(&mut self, index: usize) -> (Vec<ExprId>, Vec<ExprId>) {
        let expect = self.model.expects[index].clone();
        let lhs = self.expand_value(&expect.lhs, true).entries();
        let rhs = self.expand_value(&expect.rhs, true).entries();
        (lhs, rhs)
    }

    /// Decides one residual of an `expect at start:` line by algebra where it can.
    pub fn decide_at_start(&mut self, residual: ExprId) -> Decision {
        let at_start = match self.unknowns_at_start() {
            StartSolution::Exact(map) => map,
            StartSolution::Singular => return Decision::SingularAtStart,
            StartSolution::TooLarge { unknowns } | StartSolution::Numeric { unknowns } => {
                return Decision::SampleAtStart { residual, unknowns };
            }
        };
        let mut z = self.model.pool.subst(residual, &at_start);
        if self.model.pool.is_identically_zero(z) {
            return Decision::Exact;
        }
        if self.start_at_values_only {
            // The start is a start only at the parameters' values: decide there.
            let values = self.parameter_values();
            z = self.model.pool.subst(z, &values);
            if self.model.pool.is_identically_zero(z) {
                return Decision::Exact;
            }
        }
        // Only parameters are left: compare at random parameter values.
        let z = self.model.pool.simplify(z);
        Decision::Sample { residual: z, solve: false }
    }

    /// Decides one residual of an `expect` line (not at the start) by algebra where it can.
    pub fn decide_everywhere(&mut self, residual: ExprId) -> Decision {
        let unknowns = self.unknowns();
        let pool = &mut self.model.pool;
        let residual = pool.expand(residual);
        let involved: Vec<usize> =
            (0..unknowns.len()).filter(|&j| pool.depends_on(residual, unknowns[j])).collect();
        if involved.is_empty() {
            if pool.is_identically_zero(residual) {
                return Decision::Exact;
            }
            if self.vanishes_on_constraints(residual) {
                return Decision::ExactOnConstraints;
            }
            let r = self.model.pool.simplify(residual);
            return Decision::Sample { residual: r, solve: false };
        }
        // residual = a·u + b. It holds along the motion when it is a multiple of one row of the
        // equations of motion: a = c·row, b = −c·rhs.
        let a: Vec<ExprId> = unknowns.iter().map(|u| pool.diff(residual, *u)).collect();
        let linear = a.iter().all(|aj| unknowns.iter().all(|u| !pool.depends_on(*aj, *u)));
        if linear && self.is_row_multiple(residual, &a) {
            return Decision::Exact;
        }
        if self.vanishes_on_constraints(residual) {
            return Decision::ExactOnConstraints;
        }
        let r = self.model.pool.simplify(residual);
        Decision::Sample { residual: r, solve: true }
    }

    /// Whether the residual, with the unknowns solved for, vanishes once the constraints kept
    /// with multipliers are used: each one that is a square in some coordinate,
    /// a·q² + b = 0 with `a` constant and `b` free of q (x² + y² = L²), gives
    /// q = ±√(−b/a) and q̇ from Φ̇ = 0; the residual must vanish on both branches.
    fn vanishes_on_constraints(&mut self, residual: ExprId) -> bool {
        if self.multipliers.is_empty() {
            return false;
        }
        let unknowns = self.unknowns();
        let r = if unknowns.iter().any(|u| self.model.pool.depends_on(residual, *u)) {
            let Some(solved) = self.solved_unknowns() else { return false };
            self.model.pool.subst(residual, &solved)
        } else {
            residual
        };
        let pool = &mut self.model.pool;
        let mut branches: Vec<ExprId> = vec![pool.together(r)];
        let mut used = false;
        for m in self.multipliers.clone() {
            let Some(phi) = m.rows.position else { continue };
            let Some((q, root)) = square_in_one_coordinate(pool, phi, &self.coords) else {
                continue;
            };
            used = true;
            let rate = pool.rate(q).expect("coordinate");
            let mut next = Vec::new();
            for root in [root, pool.neg(root)] {
                // On Φ = 0 with q = root, Φ̇ = 0 fixes q̇ = d(root)/dt.
                let q_rate = pool.time_derivative(root);
                let map: HashMap<SymId, ExprId> = [(q, root), (rate, q_rate)].into();
                for b in &branches {
                    next.push(pool.subst(*b, &map));
                }
            }
            branches = next;
        }
        // Substituting the roots leaves quotients by (L² − y²) that only cancel over a common
        // denominator.
        used && branches.into_iter().all(|b| {
            let b = pool.together(b);
            pool.is_identically_zero(b)
        })
    }

    fn is_row_multiple(&mut self, residual: ExprId, a: &[ExprId]) -> bool {
        let unknowns = self.unknowns();
        let (rows, rhs) = self.system();
        let pool = &mut self.model.pool;
        let zeros: HashMap<SymId, ExprId> = unknowns.iter().map(|u| (*u, pool.zero())).collect();
        let b = pool.subst(residual, &zeros);
        let Some(j) = (0..a.len()).find(|&j| !pool.is_identically_zero(a[j])) else { return false };
        for (row, f) in rows.iter().zip(rhs.iter()) {
            if pool.is_identically_zero(row[j]) {
                continue;
            }
            let c = pool.div(a[j], row[j]);
            let mut ok = true;
            for (ak, rk) in a.iter().zip(row.iter()) {
                let p = pool.mul2(c, *rk);
                let d = pool.sub(*ak, p);
                if !pool.is_identically_zero(d) {
                    ok = false;
                    break;
                }
            }
            if ok {
                let p = pool.mul2(c, *f);
                let d = pool.add2(b, p);
                if pool.is_identically_zero(d) {
                    return true;
                }
            }
        }
        false
    }
}

/// For Φ = a·q² + b with `a` free of every coordinate, rate and time, and `b` free of q: the
/// coordinate q and √(−b/a).
fn square_in_one_coordinate(
    pool: &mut cas::Pool,
    phi: ExprId,
    coords: &[SymId],
) -> Option<(SymId, ExprId)> {
    let phi = pool.expand(phi);
    for &q in coords {
        if !pool.depends_on(phi, q) {
            continue;
        }
        let first = pool.diff(phi, q);
        let zero: HashMap<SymId, ExprId> = [(q, pool.zero())].into();
        let linear = pool.subst(first, &zero);
        if !pool.is_identically_zero(linear) {
            continue;
        }
        let second = pool.diff(first, q);
        let a = pool.simplify(second);
        let constant =
            pool.free_symbols(a).iter().all(|s| matches!(pool.symbol(*s).kind, SymbolKind::Param));
        if !constant || pool.is_identically_zero(a) {
            continue;
        }
        let b = pool.subst(phi, &zero);
        // Φ must be exactly a/2·q² + b: nothing of higher order in q.
        let half_a = pool.scale(a, &cas::number::ratio(1, 2));
        let q2 = pool.sym(q);
        let q2 = pool.powi(q2, 2);
        let quadratic = pool.mul2(half_a, q2);
        let rebuilt = pool.add2(quadratic, b);
        let difference = pool.sub(phi, rebuilt);
        if !pool.is_identically_zero(difference) {
            continue;
        }
        let ratio = pool.div(b, half_a);
        let minus = pool.neg(ratio);
        return Some((q, pool.sqrt(minus)));
    }
    None
}
