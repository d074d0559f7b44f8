//! Checking `expect` lines against the derivation: by algebra where it decides, otherwise at
//! many random states the system can reach (on its constraints), always saying which.

use std::collections::HashMap;

use cas::{ExprId, SymId, SymbolKind};
use lang::Diagnostic;
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::admissible::{random_state, state_symbols, value_and_scale, ConstraintSet};
use crate::derive::Derivation;
use crate::start::StartSolution;

/// How many random states a numeric check uses.
pub const SAMPLES: usize = 24;
const RELATIVE_TOLERANCE: f64 = 1e-9;

/// The outcome of one `expect` line.
#[derive(Clone, Debug)]
pub enum Verdict {
    /// The residual simplifies to zero.
    Exact,
    /// The residual simplifies to zero once the kept constraints are used (x² = L² − y²).
    ExactOnConstraints,
    /// The algebra could not decide; the residual vanished at this many random states.
    Numeric { samples: usize, sampling: Sampling },
    /// The residual is not zero.
    Fails(Failure),
    /// Neither algebra nor numbers could decide (e.g. no state where everything is defined).
    Undecided { reason: String },
}

/// Where the random states of a numeric verdict came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Sampling {
    /// Anywhere: the system has no constraint kept with a multiplier.
    Anywhere,
    /// On the constraint surface: positions on Φ = 0, rates on Φ̇ = 0.
    OnConstraints,
    /// At the start, at random parameter values, with the unknowns of the start solved
    /// numerically (there were too many for the algebra).
    AtStart { unknowns: usize },
}

#[derive(Clone, Debug)]
pub struct Failure {
    /// Which entry of a vector or matrix equation, if it has several.
    pub component: Option<usize>,
    /// lhs − rhs, simplified (with accelerations, where the equation has them).
    pub residual: ExprId,
    /// A state where the residual is not zero, and its value there.
    pub state: Vec<(SymId, f64)>,
    pub value: f64,
}

impl Verdict {
    pub fn holds(&self) -> bool {
        matches!(self, Verdict::Exact | Verdict::ExactOnConstraints | Verdict::Numeric { .. })
    }
}

impl Derivation {
    /// Checks every `expect` line, in order.
    pub fn check_all(&mut self) -> Vec<Verdict> {
        (0..self.model.expects.len()).map(|i| self.check(i)).collect()
    }

    /// Checks one `expect` line.
    pub fn check(&mut self, index: usize) -> Verdict {
        let expect = self.model.expects[index].clone();
        let lhs = self.expand_value(&expect.lhs, true).entries();
        let rhs = self.expand_value(&expect.rhs, true).entries();
        let many = lhs.len() > 1;
        let mut numeric: Option<(usize, Sampling)> = None;
        let mut on_constraints = false;
        for (k, (l, r)) in lhs.into_iter().zip(rhs).enumerate() {
            let residual = self.model.pool.sub(l, r);
            let verdict = if expect.at_start {
                self.check_at_start(residual)
            } else {
                self.check_everywhere(residual)
            };
            match verdict {
                Verdict::Exact => {}
                Verdict::ExactOnConstraints => on_constraints = true,
                Verdict::Numeric { samples, sampling } => {
                    numeric =
                        Some(numeric.map_or((samples, sampling), |(n, s)| {
                            (n.min(samples), s.max(sampling))
                        }))
                }
                Verdict::Fails(mut f) => {
                    f.component = many.then_some(k);
                    return Verdict::Fails(f);
                }
                undecided => return undecided,
            }
        }
        match numeric {
            Some((samples, sampling)) => Verdict::Numeric { samples, sampling },
            None if on_constraints => Verdict::ExactOnConstraints,
            None => Verdict::Exact,
        }
    }

    fn check_at_start(&mut self, residual: ExprId) -> Verdict {
        let at_start = match self.unknowns_at_start() {
            StartSolution::Exact(map) => map,
            StartSolution::Singular => {
                return Verdict::Undecided {
                    reason: "the mass matrix is singular at the start".into(),
                }
            }
            StartSolution::TooLarge { unknowns } => {
                return self.numeric_at_start(residual, unknowns);
            }
        };
        let z = self.model.pool.subst(residual, &at_start);
        if self.model.pool.is_identically_zero(z) {
            return Verdict::Exact;
        }
        // Only parameters are left: compare at random parameter values.
        let z = self.model.pool.simplify(z);
        self.numeric(z, false)
    }

    fn check_everywhere(&mut self, residual: ExprId) -> Verdict {
        let unknowns = self.unknowns();
        let pool = &mut self.model.pool;
        let residual = pool.expand(residual);
        let involved: Vec<usize> =
            (0..unknowns.len()).filter(|&j| pool.depends_on(residual, unknowns[j])).collect();
        if involved.is_empty() {
            if pool.is_identically_zero(residual) {
                return Verdict::Exact;
            }
            if self.vanishes_on_constraints(residual) {
                return Verdict::ExactOnConstraints;
            }
            let r = self.model.pool.simplify(residual);
            return self.numeric(r, false);
        }
        // residual = a·u + b. It holds along the motion when it is a multiple of one row of the
        // equations of motion: a = c·row, b = −c·rhs.
        let a: Vec<ExprId> = unknowns.iter().map(|u| pool.diff(residual, *u)).collect();
        let linear = a.iter().all(|aj| unknowns.iter().all(|u| !pool.depends_on(*aj, *u)));
        if linear && self.is_row_multiple(residual, &a) {
            return Verdict::Exact;
        }
        if self.vanishes_on_constraints(residual) {
            return Verdict::ExactOnConstraints;
        }
        let r = self.model.pool.simplify(residual);
        self.numeric(r, true)
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
            let Some((q, root)) = square_in_one_coordinate(pool, m.phi, &self.coords) else {
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

    /// Solves the equations of motion numerically at a state, filling in the unknowns.
    fn solve_unknowns(&mut self, values: &mut [f64]) -> Option<()> {
        let unknowns = self.unknowns();
        if unknowns.is_empty() {
            return Some(());
        }
        let (rows, rhs) = self.system();
        let pool = &self.model.pool;
        let mut memo = HashMap::new();
        let n = unknowns.len();
        let a = DMatrix::from_fn(n, n, |i, j| pool.eval_memo(rows[i][j], values, &mut memo));
        let b = DVector::from_fn(n, |i, _| pool.eval_memo(rhs[i], values, &mut memo));
        if !a.iter().chain(b.iter()).all(|x| x.is_finite()) {
            return None;
        }
        let x = a.lu().solve(&b)?;
        for (u, v) in unknowns.iter().zip(x.iter()) {
            values[u.index()] = *v;
        }
        Some(())
    }

    fn numeric(&mut self, residual: ExprId, with_unknowns: bool) -> Verdict {
        // A fixed seed: the same scene is checked at the same states in every run.
        let mut rng = ChaCha8Rng::seed_from_u64(0x1a9_2a96e);
        let syms = state_symbols(self);
        let constraints = ConstraintSet::first(self, self.multipliers.len());
        let sampling =
            if constraints.is_empty() { Sampling::Anywhere } else { Sampling::OnConstraints };
        let mut good = 0;
        let mut reached = 0;
        for _ in 0..SAMPLES * 4 {
            if good == SAMPLES {
                break;
            }
            let mut values = random_state(self, &mut rng);
            if constraints.project(self, &mut values).is_err() {
                continue;
            }
            reached += 1;
            if with_unknowns && self.solve_unknowns(&mut values).is_none() {
                continue;
            }
            if let Some(f) = self.failure_at(residual, &values, &syms) {
                return Verdict::Fails(f);
            }
            if self.defined_at(residual, &values) {
                good += 1;
            }
        }
        if good == 0 {
            let reason = if reached == 0 {
                "no random start reached a state that satisfies the constraints"
            } else {
                "no random state where the expressions are defined"
            };
            return Verdict::Undecided { reason: reason.into() };
        }
        Verdict::Numeric { samples: good, sampling }
    }

    /// `expect at start:` past the algebra's budget: at random parameter values, the start is
    /// solved numerically and the residual evaluated there.
    fn numeric_at_start(&mut self, residual: ExprId, unknowns: usize) -> Verdict {
        let mut rng = ChaCha8Rng::seed_from_u64(0x5747_a247);
        let params: Vec<SymId> = self.model.params.iter().map(|p| p.sym).collect();
        let mut good = 0;
        for _ in 0..SAMPLES * 4 {
            if good == SAMPLES {
                break;
            }
            let values: Vec<(SymId, f64)> =
                params.iter().map(|p| (*p, rng.gen_range(0.5..2.0))).collect();
            let Some(start) = self.start_numeric(&values) else { continue };
            let shown: Vec<SymId> = params.clone();
            if let Some(mut f) = self.failure_at(residual, &start.values, &shown) {
                f.state.retain(|(s, _)| params.contains(s));
                return Verdict::Fails(f);
            }
            if self.defined_at(residual, &start.values) {
                good += 1;
            }
        }
        if good == 0 {
            return Verdict::Undecided {
                reason: "the start could not be solved at any parameter values tried".into(),
            };
        }
        Verdict::Numeric { samples: good, sampling: Sampling::AtStart { unknowns } }
    }

    fn defined_at(&self, residual: ExprId, values: &[f64]) -> bool {
        let (value, scale) = value_and_scale(self, residual, values, &mut HashMap::new());
        value.is_finite() && scale.is_finite()
    }

    /// A failure when the residual is defined and not zero at this state.
    fn failure_at(&mut self, residual: ExprId, values: &[f64], syms: &[SymId]) -> Option<Failure> {
        let (value, scale) = value_and_scale(self, residual, values, &mut HashMap::new());
        if !value.is_finite() || !scale.is_finite() {
            return None;
        }
        if value.abs() <= RELATIVE_TOLERANCE * (1.0 + scale) {
            return None;
        }
        let mut state: Vec<(SymId, f64)> = syms
            .iter()
            .filter(|s| self.model.pool.depends_on(residual, **s))
            .map(|s| (*s, values[s.index()]))
            .collect();
        state.extend(
            self.unknowns()
                .into_iter()
                .filter(|u| self.model.pool.depends_on(residual, *u))
                .map(|u| (u, values[u.index()])),
        );
        Some(Failure { component: None, residual, state, value })
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

/// How many random states the foresight of undecidable `expect` lines tries: enough that an
/// expression defined on a good part of the states is found defined at one of them.
const FORESIGHT_STATES: usize = 8;

impl Derivation {
    /// Warns, with the derivation, about `expect` lines that `check` will find undecidable:
    /// a side undefined at every state tried (`sqrt(-1 - x^2)`), or accelerations that cannot
    /// be solved for at the start. Tried at the kind of random states `check` uses.
    pub(crate) fn warn_about_undecidable_expects(&mut self) {
        let mut rng = ChaCha8Rng::seed_from_u64(0xf0_2e5e);
        let constraints = ConstraintSet::first(self, self.multipliers.len());
        for index in 0..self.model.expects.len() {
            let expect = self.model.expects[index].clone();
            let lhs = self.expand_value(&expect.lhs, true).entries();
            let rhs = self.expand_value(&expect.rhs, true).entries();
            let residuals: Vec<ExprId> =
                lhs.iter().zip(&rhs).map(|(l, r)| self.model.pool.sub(*l, *r)).collect();
            let unknowns = self.unknowns();
            // `check` solves for the accelerations at the start whatever the line says, and
            // elsewhere only when the line has them.
            let solve = expect.at_start
                || residuals
                    .iter()
                    .any(|r| unknowns.iter().any(|u| self.model.pool.depends_on(*r, *u)));
            let mut states = Vec::new();
            for _ in 0..FORESIGHT_STATES {
                let mut values = random_state(self, &mut rng);
                if expect.at_start {
                    self.start_values(&mut values);
                } else if constraints.project(self, &mut values).is_err() {
                    continue;
                }
                if solve && self.solve_unknowns(&mut values).is_none() {
                    continue;
                }
                states.push(values);
            }
            if states.is_empty() {
                if expect.at_start {
                    self.warnings.push(
                        Diagnostic::warning(
                            expect.span,
                            "`check` cannot decide this expectation: the mass matrix is \
                             singular at the start",
                        )
                        .with_label("the accelerations at the start cannot be solved for")
                        .with_hint(
                            "start away from the singular configuration (an angle or a radius \
                             where some coordinate stops moving any mass)",
                        ),
                    );
                }
                continue;
            }
            let pool = &self.model.pool;
            let undefined = |e: ExprId| states.iter().all(|v| !pool.eval(e, v).is_finite());
            if !residuals.iter().any(|r| undefined(*r)) {
                continue;
            }
            // Point at the side that is undefined, and inside it at the smallest part that is.
            let side = match lhs.iter().find(|e| undefined(**e)) {
                Some(e) => Some((*e, expect.lhs_span)),
                None => rhs.iter().find(|e| undefined(**e)).map(|e| (*e, expect.rhs_span)),
            };
            let Some((side, span)) = side else {
                // Each side is defined somewhere, but never both at once.
                let label = format!("none of {} random states defines both sides", states.len());
                self.warnings.push(
                    Diagnostic::warning(
                        expect.span,
                        "`check` cannot decide this expectation: its sides are never defined \
                         at the same state",
                    )
                    .with_label(label)
                    .with_hint(UNDEFINED_HINT),
                );
                continue;
            };
            let mut part = side;
            for _ in 0..MAX_DESCENT {
                match pool.children(part).into_iter().find(|c| undefined(*c)) {
                    Some(child) => part = child,
                    None => break,
                }
            }
            let text = pool.print(part, cas::Style::Unicode);
            let label = if text.chars().count() <= 48 {
                format!("{text} is not a real number at any of {} random states", states.len())
            } else {
                format!("not a real number at any of {} random states", states.len())
            };
            self.warnings.push(
                Diagnostic::warning(
                    span,
                    "`check` cannot decide this expectation: it is undefined wherever it is tried",
                )
                .with_label(label)
                .with_hint(UNDEFINED_HINT),
            );
        }
    }

    /// Puts the initial state into `values`: coordinates and rates at their `coord` values
    /// (at the parameters' values in `values`), time 0.
    fn start_values(&mut self, values: &mut [f64]) {
        let state = self.initial_state();
        let pool = &self.model.pool;
        let mut memo = HashMap::new();
        // Evaluated in full before any is written: the values depend on the parameters only.
        let evaluated: Vec<(SymId, f64)> =
            state.iter().map(|(s, e)| (*s, pool.eval_memo(*e, values, &mut memo))).collect();
        for (s, v) in evaluated {
            values[s.index()] = v;
        }
    }
}

/// Why an expression is undefined at every state `check` tries, and what to look at.
const UNDEFINED_HINT: &str = "`check` compares the sides at random states (parameters in \
     [0.5, 2], coordinates in [-1.2, 1.2], rates in [-1, 1]); check the sign under a square root \
     or a logarithm, or the argument of asin or acos";

/// How deep the search for the smallest undefined part of an expression goes.
const MAX_DESCENT: usize = 64;
