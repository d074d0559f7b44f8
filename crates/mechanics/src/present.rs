//! The derived equations in the forms people read: each equation of motion normalised the way
//! a hand derivation writes it, and the `show` quantities, symbolic and at the start.

use std::collections::HashMap;

use cas::ExprId;
use model::Value;

use crate::derive::Derivation;
use crate::start_solution::StartSolution;

/// One equation `lhs = rhs`.
#[derive(Clone, Copy, Debug)]
pub struct Equation {
    pub lhs: ExprId,
    pub rhs: ExprId,
}

impl Derivation {
    /// The equations of motion as a hand derivation writes them: each row divided by what its
    /// acceleration coefficients have in common, accelerations and velocity terms on the left,
    /// the rest (gravity, applied forces, reactions) on the right.
    pub fn equations(&mut self) -> Vec<Equation> {
        let n = self.coords.len();
        let mut out = Vec::new();
        for i in 0..n {
            let rhs = self.right_side(i);
            let pool = &mut self.model.pool;
            if !self.mass_matrix[i].iter().all(|e| pool.prints_in_full(*e)) {
                // A bicycle's row: it prints as operation counts whatever is done to it.
                let lhs = times_accelerations(pool, &self.mass_matrix[i], &self.accels);
                out.push(Equation { lhs, rhs });
                continue;
            }
            let row: Vec<ExprId> = self.mass_matrix[i].iter().map(|e| pool.simplify(*e)).collect();
            let (content, _) = pool.common_content(&row);
            // The diagonal of a mass matrix is positive: keep its term's sign positive.
            let lead = if pool.is_zero(row[i]) {
                row.iter().find(|e| !pool.is_zero(**e))
            } else {
                Some(&row[i])
            };
            let lead_negative = lead.is_some_and(|e| pool.looks_negative(*e));
            let inverse = pool.powi(content, -1);
            let inverse = if lead_negative { pool.neg(inverse) } else { inverse };
            let mut lhs_terms = Vec::new();
            for (j, m) in row.iter().enumerate() {
                let c = pool.mul2(*m, inverse);
                let c = pool.factor_content(c);
                if pool.is_zero(c) {
                    continue;
                }
                let parts = pool.terms(c);
                let c = collect_by_motion(pool, &parts);
                let a = pool.sym(self.accels[j]);
                lhs_terms.push(pool.mul2(c, a));
            }
            let rhs = pool.mul2(rhs, inverse);
            let rhs = pool.simplify(rhs);
            let (moving, still) = self.split_by_rates(rhs);
            let pool = &mut self.model.pool;
            lhs_terms.extend(moving.into_iter().map(|t| pool.neg(t)));
            let lhs = collect_by_motion(pool, &lhs_terms);
            let rhs = collect_by_motion(pool, &still);
            out.push(Equation { lhs, rhs });
        }
        for m in self.multipliers.clone() {
            let pool = &mut self.model.pool;
            let (jacobian, bias) = (&m.rows.jacobian, m.rows.bias);
            if !jacobian.iter().chain([&bias]).all(|e| pool.prints_in_full(*e)) {
                let lhs = times_accelerations(pool, jacobian, &self.accels);
                out.push(Equation { lhs, rhs: bias });
                continue;
            }
            let row: Vec<ExprId> = jacobian.iter().map(|e| pool.simplify(*e)).collect();
            let (content, _) = pool.common_content(&row);
            let inverse = pool.powi(content, -1);
            let mut terms = Vec::new();
            for (j, jm) in row.iter().enumerate() {
                let a = pool.sym(self.accels[j]);
                let c = pool.mul2(*jm, inverse);
                let c = pool.factor_content(c);
                terms.push(pool.mul2(c, a));
            }
            let rhs = pool.mul2(bias, inverse);
            let rhs = pool.simplify(rhs);
            let (moving, still) = self.split_by_rates(rhs);
            let pool = &mut self.model.pool;
            terms.extend(moving.into_iter().map(|t| pool.neg(t)));
            let lhs = collect_by_motion(pool, &terms);
            let rhs = collect_by_motion(pool, &still);
            out.push(Equation { lhs, rhs });
        }
        out
    }

    /// fᵢ + Σ Jᵢ·λ: what row `i` of M·q̈ equals.
    fn right_side(&mut self, i: usize) -> ExprId {
        let pool = &mut self.model.pool;
        let mut parts = vec![self.forcing[i]];
        for m in &self.multipliers {
            let lambda = pool.sym(m.lambda);
            parts.push(pool.mul2(m.force_direction()[i], lambda));
        }
        pool.add(&parts)
    }

    /// Splits a sum into the terms with rates in them and the rest.
    fn split_by_rates(&mut self, e: ExprId) -> (Vec<ExprId>, Vec<ExprId>) {
        let rates = self.rates.clone();
        let pool = &mut self.model.pool;
        let (mut moving, mut still) = (Vec::new(), Vec::new());
        for t in pool.terms(e) {
            if rates.iter().any(|r| pool.depends_on(t, *r)) {
                moving.push(t);
            } else {
                still.push(t);
            }
        }
        (moving, still)
    }

    /// How a `show` item is labelled: a lone coordinate, rate or quantity by its symbol
    /// (`θ̈`), anything else as the scene wrote it.
    pub fn show_label(&self, show: &model::Show, style: cas::Style) -> String {
        match &show.value {
            Value::Scalar(e) => match self.model.pool.as_sym(*e) {
                Some(s) => self.model.pool.symbol_text(s, style),
                None => show.label.clone(),
            },
            _ => show.label.clone(),
        }
    }

    /// The `show` items (not `at start`), derived and simplified.
    pub fn shown(&mut self) -> Vec<(model::Show, Value)> {
        let shows: Vec<_> = self.model.shows.iter().filter(|s| !s.at_start).cloned().collect();
        shows
            .into_iter()
            .map(|s| {
                let v = self.expand_value(&s.value, false);
                let v = v.map(|e| {
                    let e = self.of_state(e);
                    self.model.pool.factor_content(e)
                });
                (s, v)
            })
            .collect()
    }

    /// The `show at start` items at the initial state, exactly where the algebra stays within
    /// its budget; past it, the items are left for numbers (the `verify` crate).
    pub fn shows_at_start(&mut self) -> StartShows {
        let shows: Vec<_> = self.model.shows.iter().filter(|s| s.at_start).cloned().collect();
        if shows.is_empty() {
            return StartShows::Exact(Vec::new());
        }
        match self.unknowns_at_start() {
            StartSolution::Exact(at_start) => StartShows::Exact(
                shows
                    .into_iter()
                    .map(|s| {
                        // The multipliers at the start come from the solved system, exactly.
                        let v = self.expand_value(&s.value, true);
                        let v = v.map(|e| {
                            let z = self.model.pool.subst(e, &at_start);
                            let z = self.model.pool.together(z);
                            self.model.pool.factor_content(z)
                        });
                        (s, v)
                    })
                    .collect(),
            ),
            StartSolution::Singular => {
                let unknowns = self.unknowns().len();
                StartShows::Numeric { unknowns, shows, because: NumericStart::SingularInAlgebra }
            }
            StartSolution::TooLarge { unknowns } => {
                StartShows::Numeric { unknowns, shows, because: NumericStart::TooManyUnknowns }
            }
            StartSolution::Numeric { unknowns } => {
                StartShows::Numeric { unknowns, shows, because: NumericStart::PositionsSolved }
            }
        }
    }
}

/// The `show at start` items, as the algebra could find them.
#[derive(Clone, Debug)]
pub enum StartShows {
    /// Exactly, in the parameters.
    Exact(Vec<(model::Show, Value)>),
    /// These items need numbers, for the reason given.
    Numeric { unknowns: usize, shows: Vec<model::Show>, because: NumericStart },
}

/// Why the start is left to numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NumericStart {
    /// The exact solve of the unknowns outgrew its budget.
    TooManyUnknowns,
    /// The start's positions were solved in numbers from the kept constraints.
    PositionsSolved,
    /// The exact solve found the system singular. Its zero test decides large entries at
    /// generic points, so numbers at the start have the last word.
    SingularInAlgebra,
}

impl NumericStart {
    /// Why, in the words of a report.
    pub fn words(self, unknowns: usize) -> String {
        match self {
            NumericStart::TooManyUnknowns => {
                format!("{unknowns} unknowns are too many to solve for exactly")
            }
            NumericStart::PositionsSolved => {
                "the start positions were solved numerically from the constraints".to_string()
            }
            NumericStart::SingularInAlgebra => {
                format!("the exact solve of {unknowns} unknowns found no pivot")
            }
        }
    }
}

/// The sum of `terms` with the terms that move alike gathered: those whose factors of
/// coordinates, rates and time agree share one coefficient of parameters, as a hand
/// derivation writes (A + m·l² − C)·sin θ·cos θ·φ̇² rather than three terms.
pub fn collect_by_motion(pool: &mut cas::Pool, terms: &[ExprId]) -> ExprId {
    use cas::SymbolKind;
    let mut groups: Vec<(ExprId, Vec<ExprId>)> = Vec::new();
    // Where each motion's group is: a sum as long as a large model's T has thousands of terms.
    let mut group_of: HashMap<ExprId, usize> = HashMap::new();
    for t in terms {
        let (coef, factors) = pool.factors(*t);
        let (mut motion, mut constant) = (Vec::new(), Vec::new());
        for f in factors {
            let moves = pool
                .free_symbols(f.0)
                .iter()
                .any(|s| !matches!(pool.symbol(*s).kind, SymbolKind::Param));
            if moves {
                motion.push(f);
            } else {
                constant.push(f);
            }
        }
        let one = cas::Rational::from_integer(1.into());
        let motion = pool.product(&one, &motion);
        let constant = pool.product(&coef, &constant);
        match group_of.get(&motion) {
            Some(&g) => groups[g].1.push(constant),
            None => {
                group_of.insert(motion, groups.len());
                groups.push((motion, vec![constant]));
            }
        }
    }
    let mut gathered = Vec::new();
    for (motion, constants) in groups {
        if constants.len() == 1 {
            gathered.push(pool.mul2(constants[0], motion));
            continue;
        }
        // What the coefficients share comes out, a sign with it: −g·(m₁ + m₂), not
        // (−m₁·g − m₂·g).
        let sum = pool.add(&constants);
        let coefficient = pool.factor_content(sum);
        let terms = pool.terms(coefficient);
        if terms.len() < 2 {
            gathered.push(pool.mul2(coefficient, motion));
            continue;
        }
        // A number the terms share stands in front, where the motion keeps it from being
        // distributed again, and a sum of mostly negative terms reads better negated:
        // ½·(A + m·l²)·sin²θ·φ̇² and −2·(A − C + m·l²)·X.
        // Only where it leaves whole numbers inside without making new ones: ½·(A + m·l²), but
        // I₂ + ¼·m₂·l₂² stays as it is rather than ¼·(4·I₂ + m₂·l₂²).
        let (content, rest) = pool.content(coefficient);
        let sizes: Vec<cas::Rational> =
            terms.iter().map(|t| cas::number::Signed::abs(&pool.split_coefficient(*t).0)).collect();
        let alike = sizes.iter().all(|q| *q == sizes[0]);
        let (content, rest) = match pool.as_num(content) {
            Some(q) if alike || q.is_integer() => (content, rest),
            _ => (pool.one(), coefficient),
        };
        let negative = terms.iter().filter(|t| pool.looks_negative(**t)).count();
        let (content, rest) = if 2 * negative > terms.len() {
            (pool.neg(content), pool.neg(rest))
        } else {
            (content, rest)
        };
        gathered.push(pool.mul(&[content, rest, motion]));
    }
    pool.add(&gathered)
}

/// Σⱼ rowⱼ·q̈ⱼ, as built.
fn times_accelerations(pool: &mut cas::Pool, row: &[ExprId], accels: &[cas::SymId]) -> ExprId {
    let terms: Vec<ExprId> = row
        .iter()
        .zip(accels)
        .map(|(e, a)| {
            let a = pool.sym(*a);
            pool.mul2(*e, a)
        })
        .collect();
    pool.add(&terms)
}
