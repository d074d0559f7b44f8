//! Expansion, zero recognition and the simplifications that make printed equations read like a
//! careful hand derivation.

use std::collections::BTreeMap;

use rustc_hash::FxHashMap;

use num_traits::{One, Signed, ToPrimitive, Zero};

use crate::number::{self, Rational};
use crate::pool::{ExprId, Func, Node, Pool};

/// Past this many terms an expansion is abandoned and the product kept as it is.
const EXPANSION_TERM_LIMIT: usize = 20_000;

/// Past this many terms (counted before like terms combine) `simplify` leaves an expression as
/// it is: expanding and folding cost grows faster than the terms, and a model this size (a
/// bicycle's frames in space) is for numbers and generated code, not for reading.
pub const SIMPLIFY_TERM_LIMIT: usize = 4_000;

/// Past this many terms the algebraic zero test gives up (and the numeric check decides).
const ZERO_TEST_TERM_LIMIT: usize = 2_000;

/// sin and cos of sums with more parts than this are not expanded in the zero test.
const ANGLE_SUM_PARTS_LIMIT: usize = 4;

impl Pool {
    /// Multiplies out products of sums and positive integer powers of sums, everywhere
    /// (inside function arguments too). Negative powers of sums stay as they are. Memoised.
    pub fn expand(&mut self, e: ExprId) -> ExprId {
        if let Some(&r) = self.expand_memo.get(&e) {
            return r;
        }
        // A node whose parts expand to themselves is its own expansion: the constructors would
        // rebuild the same canonical node from them, at the cost of interning every step.
        let r = match self.node(e).clone() {
            Node::Num(_) | Node::Sym(_) | Node::Pi => e,
            Node::Add(c, terms) => {
                let expanded: Vec<ExprId> = terms.iter().map(|(t, _)| self.expand(*t)).collect();
                if expanded.iter().zip(terms.iter()).all(|(x, (t, _))| x == t) {
                    e
                } else {
                    let parts = expanded.into_iter().zip(terms.iter().map(|(_, k)| k.clone()));
                    self.sum_of(c, parts)
                }
            }
            Node::Mul(c, factors) => {
                let atoms = factors.iter().all(|(b, _)| {
                    matches!(self.node(*b), Node::Sym(_) | Node::Func(..)) && self.expand(*b) == *b
                });
                if atoms {
                    e
                } else {
                    self.expand_product(&c, &factors)
                }
            }
            Node::Pow(b, x) => {
                let (eb, ex) = (self.expand(b), self.expand(x));
                if (eb, ex) == (b, x) {
                    e
                } else {
                    self.pow(eb, ex)
                }
            }
            Node::Func(f, a) => {
                let ea = self.expand(a);
                if ea == a {
                    e
                } else {
                    self.func(f, ea)
                }
            }
            Node::Atan2(y, x) => {
                let (ey, ex) = (self.expand(y), self.expand(x));
                if (ey, ex) == (y, x) {
                    e
                } else {
                    self.atan2(ey, ex)
                }
            }
        };
        self.expand_memo.insert(e, r);
        r
    }

    /// Records `expanded` as what [`Pool::expand`] gives for `e`, for a caller that has it by
    /// a shorter route: the kinetic energy as ½·q̇ᵀ·M·q̇ from an expanded mass matrix, rather
    /// than squares of long sums multiplied out. It must be exactly `expand(e)` (the same
    /// canonical sum); builds with debug assertions, the tests among them, check that it is.
    pub fn remember_expansion(&mut self, e: ExprId, expanded: ExprId) {
        #[cfg(debug_assertions)]
        {
            let direct = self.expand(e);
            assert_eq!(direct, expanded, "a remembered expansion differs from expand's");
        }
        self.expand_memo.insert(e, expanded);
    }

    fn expand_product(&mut self, c: &Rational, factors: &[(ExprId, Rational)]) -> ExprId {
        let mut terms: Vec<ExprId> = vec![self.num(c.clone())];
        let mut plain: Vec<ExprId> = Vec::new();
        for (b, x) in factors {
            let b = self.expand(*b);
            let repeat = if x.is_integer() && x.is_positive() { x.to_u32() } else { None };
            match (self.node(b), repeat) {
                (Node::Add(..), Some(n)) => {
                    let sum_terms = self.terms(b);
                    for _ in 0..n {
                        if terms.len() * sum_terms.len() > EXPANSION_TERM_LIMIT {
                            plain.push(b);
                            continue;
                        }
                        let mut next = Vec::with_capacity(terms.len() * sum_terms.len());
                        for &t in &terms {
                            for &s in &sum_terms {
                                next.push(self.mul2(t, s));
                            }
                        }
                        terms = next;
                    }
                }
                _ => plain.push(self.powq(b, x)),
            }
        }
        let rest = self.mul(&plain);
        let parts: Vec<ExprId> = terms.into_iter().map(|t| self.mul2(t, rest)).collect();
        let sum = self.add(&parts);
        // Multiplying by `rest` may have produced new products of sums (rest = (a+b)^-1 cancels
        // nothing, but rest containing a sum to a positive power does); one more pass settles it.
        if parts.len() > 1 && self.has_sum_factor(rest) {
            self.expand(sum)
        } else {
            sum
        }
    }

    /// Whether expanding `e` would give more than `limit` terms, counted before like terms
    /// combine (an upper bound), without expanding: linear in the size of `e` as a graph.
    pub fn expansion_exceeds(&self, e: ExprId, limit: usize) -> bool {
        let mut memo = FxHashMap::default();
        self.expanded_terms(e, limit, &mut memo) > limit
    }

    /// The number of terms `expand` would multiply out, saturated just past `limit`.
    fn expanded_terms(
        &self,
        e: ExprId,
        limit: usize,
        memo: &mut FxHashMap<ExprId, usize>,
    ) -> usize {
        if let Some(&n) = memo.get(&e) {
            return n;
        }
        let cap = limit.saturating_add(1);
        let n = match self.node(e) {
            Node::Num(_) | Node::Sym(_) | Node::Pi | Node::Func(..) | Node::Atan2(..) => 1,
            Node::Add(_, terms) => {
                let mut n = 1usize;
                for (t, _) in terms.iter() {
                    n = n.saturating_add(self.expanded_terms(*t, limit, memo)).min(cap);
                }
                n
            }
            Node::Mul(_, factors) => {
                let mut n = 1usize;
                for (b, x) in factors.iter() {
                    // A sum to a negative or fractional power stays one factor.
                    let Some(repeat) = x.is_integer().then(|| x.to_u32()).flatten() else {
                        continue;
                    };
                    let m = self.expanded_terms(*b, limit, memo);
                    for _ in 0..repeat {
                        n = n.saturating_mul(m).min(cap);
                    }
                }
                n
            }
            Node::Pow(b, x) => {
                let repeat = self.as_num(*x).filter(|q| q.is_integer()).and_then(|q| q.to_u32());
                let m = self.expanded_terms(*b, limit, memo);
                let mut n = 1usize;
                for _ in 0..repeat.unwrap_or(0) {
                    n = n.saturating_mul(m).min(cap);
                }
                n
            }
        };
        memo.insert(e, n);
        n
    }

    fn has_sum_factor(&self, e: ExprId) -> bool {
        let (_, fs) = self.factors(e);
        fs.iter().any(|(b, x)| {
            x.is_positive() && x.is_integer() && matches!(self.node(*b), Node::Add(..))
        })
    }

    /// Rewrites even powers of cos as powers of (1 − sin²) and expands, so that polynomials in
    /// sin and cos of the same argument have one form. Used to recognise zero, not to print.
    pub fn trig_normal(&mut self, e: ExprId) -> ExprId {
        let e = self.expand(e);
        let mut memo = FxHashMap::default();
        let r = self.rewrite_cos_squares(e, &mut memo);
        self.expand(r)
    }

    fn rewrite_cos_squares(&mut self, e: ExprId, memo: &mut FxHashMap<ExprId, ExprId>) -> ExprId {
        if let Some(&r) = memo.get(&e) {
            return r;
        }
        let r = match self.node(e).clone() {
            Node::Add(c, terms) => {
                let mut parts = vec![self.num(c)];
                for (t, k) in terms.iter() {
                    let t = self.rewrite_cos_squares(*t, memo);
                    parts.push(self.scale(t, k));
                }
                self.add(&parts)
            }
            Node::Mul(c, factors) => {
                let mut parts = vec![self.num(c)];
                for (b, x) in factors.iter() {
                    let b2 = self.rewrite_cos_squares(*b, memo);
                    match (self.node(b2).clone(), x.to_i64()) {
                        (Node::Func(Func::Cos, u), Some(n)) if x.is_integer() && n >= 2 => {
                            let s = self.sin(u);
                            let s2 = self.powi(s, 2);
                            let one = self.one();
                            let c2 = self.sub(one, s2);
                            parts.push(self.powi(c2, n / 2));
                            parts.push(self.powi(b2, n % 2));
                        }
                        _ => parts.push(self.powq(b2, x)),
                    }
                }
                self.mul(&parts)
            }
            Node::Func(f, a) => {
                let a = self.rewrite_cos_squares(a, memo);
                match f {
                    Func::Sin | Func::Cos => self.expand_angle(f, a),
                    // tan u = sin u / cos u, so that tan and sec forms meet the others.
                    Func::Tan => {
                        let s = self.expand_angle(Func::Sin, a);
                        let c = self.expand_angle(Func::Cos, a);
                        self.div(s, c)
                    }
                    _ => self.func(f, a),
                }
            }
            _ => e,
        };
        memo.insert(e, r);
        r
    }

    /// How deeply trigonometric functions nest inside each other's arguments.
    fn trig_depth(&self, e: ExprId) -> usize {
        let mut memo: FxHashMap<ExprId, usize> = FxHashMap::default();
        self.trig_depth_memo(e, &mut memo)
    }

    fn trig_depth_memo(&self, e: ExprId, memo: &mut FxHashMap<ExprId, usize>) -> usize {
        if let Some(&d) = memo.get(&e) {
            return d;
        }
        let below =
            self.children(e).into_iter().map(|c| self.trig_depth_memo(c, memo)).max().unwrap_or(0);
        let d = below + usize::from(matches!(self.node(e), Node::Func(..)));
        memo.insert(e, d);
        d
    }

    /// sin and cos of a sum or of an integer multiple, as polynomials in sin and cos of the
    /// parts: sin(a + b) = sin a cos b + cos a sin b, sin(2a) = 2 sin a cos a.
    fn expand_angle(&mut self, f: Func, a: ExprId) -> ExprId {
        let split = match self.node(a).clone() {
            Node::Add(c, t) if t.len() + usize::from(!c.is_zero()) <= ANGLE_SUM_PARTS_LIMIT => {
                let terms = self.terms(a);
                let first = terms[0];
                let rest = self.add(&terms[1..]);
                Some((first, rest))
            }
            Node::Mul(c, fs)
                if c.is_integer() && c.abs() >= number::int(2) && c.abs() <= number::int(6) =>
            {
                let one = self.product(&Rational::one(), &fs);
                let unit = if c.is_negative() { self.neg(one) } else { one };
                let sign = if c.is_negative() { -1 } else { 1 };
                let rest = self.product(&(c - number::int(sign)), &fs);
                Some((unit, rest))
            }
            _ => None,
        };
        let Some((x, y)) = split else { return self.func(f, a) };
        let (sx, cx) = (self.expand_angle(Func::Sin, x), self.expand_angle(Func::Cos, x));
        let (sy, cy) = (self.expand_angle(Func::Sin, y), self.expand_angle(Func::Cos, y));
        let r = if f == Func::Sin {
            let p = self.mul2(sx, cy);
            let q = self.mul2(cx, sy);
            self.add2(p, q)
        } else {
            let p = self.mul2(cx, cy);
            let q = self.mul2(sx, sy);
            self.sub(p, q)
        };
        self.expand(r)
    }

    /// Multiplies a sum by the product of the (integer, negative-power) denominators of its
    /// terms, so that `a/(a+b) + b/(a+b) − 1` becomes a polynomial that expands to zero.
    /// Returns the numerator; the result is zero exactly when `e` is (where `e` is defined).
    pub fn numerator(&mut self, e: ExprId) -> ExprId {
        let mut e = self.expand(e);
        for _ in 0..4 {
            let Node::Add(_, terms) = self.node(e).clone() else { return e };
            let mut denominators: BTreeMap<ExprId, Rational> = BTreeMap::new();
            for (t, _) in terms.iter() {
                let (_, fs) = self.factors(*t);
                for (b, x) in fs {
                    if x.is_negative() && self.as_num(b).is_none() {
                        let need = -x.floor();
                        let slot = denominators.entry(b).or_default();
                        if need > *slot {
                            *slot = need;
                        }
                    }
                }
            }
            if denominators.is_empty() {
                return e;
            }
            // Multiply term by term, so each denominator cancels against its own power before
            // any sum is multiplied out.
            let mut factors = Vec::new();
            for (b, x) in denominators {
                factors.push(self.powq(b, &x));
            }
            let clear = self.mul(&factors);
            let mut parts = Vec::new();
            for t in self.terms(e) {
                let m = self.mul2(t, clear);
                parts.push(self.expand(m));
            }
            e = self.add(&parts);
        }
        e
    }

    /// Whether `e` is identically zero, decided by algebra: expansion, clearing denominators,
    /// and sin² + cos² = 1. `false` means "not shown to be zero", not "shown non-zero".
    pub fn is_identically_zero(&mut self, e: ExprId) -> bool {
        if self.is_zero(e) {
            return true;
        }
        // One point where the value is clearly not zero proves it is not identically zero,
        // and costs far less than the algebra below.
        if self.clearly_nonzero_somewhere(e) {
            return false;
        }
        let x = self.expand(e);
        if self.is_zero(x) {
            return true;
        }
        let n = self.numerator(x);
        if self.is_zero(n) {
            return true;
        }
        // Rewriting trigonometric functions of sums multiplies terms; past a size the numeric
        // check decides instead.
        if self.terms(n).len() > ZERO_TEST_TERM_LIMIT || self.trig_depth(n) > 2 {
            return false;
        }
        let t = self.trig_normal(n);
        if self.is_zero(t) {
            return true;
        }
        let t = self.numerator(t);
        if self.is_zero(t) {
            return true;
        }
        // Clearing denominators (from tan = sin/cos) can bring back cos² to normalise.
        let t = self.trig_normal(t);
        self.is_zero(t)
    }

    /// The form to show a person: expanded, with sin²u + cos²u folded into 1 wherever a pair of
    /// terms allows it.
    /// Memoised: a report simplifies the same entries of M several times over.
    pub fn simplify(&mut self, e: ExprId) -> ExprId {
        if let Some(&r) = self.simplify_memo.get(&e) {
            return r;
        }
        if self.expansion_exceeds(e, SIMPLIFY_TERM_LIMIT) {
            return e;
        }
        let x = self.expand(e);
        let x = self.fold_pythagoras(x);
        let x = self.fold_pythagoras_groups(x);
        let r = self.fold_angle_sums(x);
        self.simplify_memo.insert(e, r);
        r
    }

    /// In a sum, folds pairs of products of sines and cosines of two angles into one function
    /// of their sum or difference: `X·sin a·sin b + X·cos a·cos b` → `X·cos(a − b)`,
    /// `X·sin a·cos b − X·cos a·sin b` → `X·sin(a − b)`, and the `a + b` forms. Each fold
    /// removes a term; the first term in the sum's order that has a partner folds first
    /// (`fold`: without scanning the sum again after each fold).
    pub fn fold_angle_sums(&mut self, e: ExprId) -> ExprId {
        self.fold_angle_sums_worklist(e)
    }

    /// In a sum, folds pairs of terms with sin²u + cos²u = 1:
    /// `c·X·sin²u + c·X·cos²u` → `c·X`, and `c·X − c·X·cos²u` → `c·X·sin²u` (likewise with sin
    /// and cos exchanged). Each fold removes a term; the first term in the sum's order that has
    /// a partner folds first (`fold`: without scanning the sum again after each fold).
    pub fn fold_pythagoras(&mut self, e: ExprId) -> ExprId {
        self.fold_pythagoras_worklist(e)
    }

    /// One fraction over a common denominator: `a/(a+b) − 1` → `−b/(a + b)`. Sums in the
    /// denominator lose their monomial content to the numerator, so `m/(L + 3·L·sin²θ)` becomes
    /// `m/(L·(1 + 3·sin²θ))` and can cancel against it.
    pub fn together(&mut self, e: ExprId) -> ExprId {
        let x = self.expand(e);
        let terms = self.terms(x);
        let mut denominators: BTreeMap<ExprId, Rational> = BTreeMap::new();
        for &t in &terms {
            let (_, fs) = self.factors(t);
            for (b, p) in fs {
                if p.is_negative() && p.is_integer() && self.as_num(b).is_none() {
                    let slot = denominators.entry(b).or_insert_with(Rational::zero);
                    if -p.clone() > *slot {
                        *slot = -p;
                    }
                }
            }
        }
        if denominators.is_empty() {
            return x;
        }
        let all: Vec<(ExprId, Rational)> =
            denominators.iter().map(|(b, k)| (*b, k.clone())).collect();
        let clear = self.product(&Rational::one(), &all);
        let parts: Vec<ExprId> = terms
            .iter()
            .map(|t| {
                let m = self.mul2(*t, clear);
                self.expand(m)
            })
            .collect();
        let numerator = self.add(&parts);
        let numerator = self.expand(numerator);
        // Split each sum in the denominator into its content and a primitive part.
        let mut monomial = self.one();
        let mut sums = Vec::new();
        for (b, k) in all {
            if matches!(self.node(b), Node::Add(..)) {
                let (c, r) = self.content(b);
                let ck = self.powq(c, &k);
                monomial = self.mul2(monomial, ck);
                sums.push((r, k));
            } else {
                let bk = self.powq(b, &k);
                monomial = self.mul2(monomial, bk);
            }
        }
        let (g, rest) = self.content(numerator);
        let inverse = self.powi(monomial, -1);
        let scale = self.mul2(g, inverse);
        let rest = self.factor_content(rest);
        let den: Vec<(ExprId, Rational)> = sums.into_iter().map(|(r, k)| (r, -k)).collect();
        let den = self.product(&Rational::one(), &den);
        self.mul(&[scale, rest, den])
    }

    /// Whether `e` is clearly not zero at a generic point, by the zero test's numbers
    /// ([`Pool::set_zero_test`]); `false` without them.
    fn clearly_nonzero_somewhere(&self, e: ExprId) -> bool {
        self.zero_test().is_some_and(|z| z.clearly_nonzero_somewhere(self, e))
    }

    /// Whether `e` is zero at the generic points of the zero test's numbers (two points, every
    /// symbol at an irrational-looking value in (0.3, 0.8)), relative to its magnitude there
    /// (every part by its absolute value, so that cancellations nested however deep show): how
    /// an expression too large for the algebra is taken to vanish identically. Without those
    /// numbers ([`Pool::set_zero_test`]), only a literal zero vanishes.
    pub fn vanishes_at_generic_points(&self, e: ExprId) -> bool {
        // Zero is the combination of no rows.
        self.is_zero(e) || self.combination_at_generic_points(&[e], &[]).is_some()
    }

    /// Whether the vector `target` is, at every generic point, a combination of the vectors
    /// `rows` (each as long as it), the coefficients free to change from point to point; the
    /// rows the combination needs, by index, if so. For identities between expressions too
    /// large for the algebra, as [`Pool::vanishes_at_generic_points`] (the same points and
    /// magnitudes); `None` without the zero test's numbers ([`Pool::set_zero_test`]).
    pub fn combination_at_generic_points(
        &self,
        target: &[ExprId],
        rows: &[Vec<ExprId>],
    ) -> Option<Vec<usize>> {
        self.zero_test()?.combination_at_generic_points(self, target, rows)
    }

    /// The simplified form with its monomial content pulled out in front of a sum:
    /// `1/12·m·L²·(1 + 3·sin²θ)` rather than `1/12·m·L² + ¼·m·L²·sin²θ`.
    pub fn factor_content(&mut self, e: ExprId) -> ExprId {
        // A quotient by sums keeps its denominator: factor the numerator alone.
        let (c, fs) = self.factors(e);
        let is_denominator = |p: &Self, (b, x): &(ExprId, Rational)| {
            x.is_negative() && matches!(p.node(*b), Node::Add(..))
        };
        if fs.iter().any(|f| is_denominator(self, f)) {
            let (den, num): (Vec<_>, Vec<_>) =
                fs.into_iter().partition(|f| is_denominator(self, f));
            let num = self.product(&c, &num);
            let num = self.factor_content(num);
            let den = self.product(&Rational::one(), &den);
            return self.mul2(num, den);
        }
        let s = self.simplify(e);
        let (c, rest) = self.content(s);
        if let (Node::Add(k, terms), None) = (self.node(rest).clone(), self.as_num(c)) {
            // −m·g·l·(2·cos θ₁ + cos θ₂) rather than m·g·l·(−2·cos θ₁ − cos θ₂).
            let negative = terms.iter().filter(|(_, q)| q.is_negative()).count()
                + usize::from(k.is_negative());
            let (c, rest) = if 2 * negative > terms.len() + usize::from(!k.is_zero()) {
                (self.neg(c), self.neg(rest))
            } else {
                (c, rest)
            };
            let rest = self.fold_pythagoras(rest);
            let rest = self.perfect_square(rest).unwrap_or(rest);
            self.mul2(c, rest)
        } else {
            self.perfect_square(s).unwrap_or(s)
        }
    }

    /// `a² ± 2ab + b²` as `(a ± b)²`, for a sum of three terms two of which are squares.
    pub fn perfect_square(&mut self, e: ExprId) -> Option<ExprId> {
        let terms = self.terms(e);
        if terms.len() != 3 {
            return None;
        }
        let mut roots = Vec::new();
        for &t in &terms {
            let (c, fs) = self.factors(t);
            if !c.is_positive() {
                continue;
            }
            let half = number::ratio(1, 2);
            let (rc, rr) = number::rational_root(&c, &half)?;
            if !rr.is_one() {
                continue;
            }
            if fs.iter().all(|(_, x)| (x * number::int(1) / number::int(2)).is_integer()) {
                let halved: Vec<(ExprId, Rational)> =
                    fs.iter().map(|(b, x)| (*b, x / number::int(2))).collect();
                roots.push((t, self.product(&rc, &halved)));
            }
        }
        for i in 0..roots.len() {
            for j in i + 1..roots.len() {
                let (ti, a) = roots[i];
                let (tj, b) = roots[j];
                let Some(&cross) = terms.iter().find(|t| **t != ti && **t != tj) else { continue };
                for sign in [1i64, -1] {
                    let b_signed = self.scale(b, &number::int(sign));
                    let ab = self.mul2(a, b_signed);
                    let twice = self.scale(ab, &number::int(2));
                    if self.expand(twice) == cross {
                        let sum = self.add2(a, b_signed);
                        return Some(self.powi(sum, 2));
                    }
                }
            }
        }
        None
    }

    /// Splits `e` into its monomial content and the rest, `e = content · rest`: the positive
    /// gcd of the rational coefficients times every factor common to all terms at its lowest
    /// power. `(m L²/4 sin²θ + m L²/12)` → `(m L²/12, 3 sin²θ + 1)`.
    pub fn content(&mut self, e: ExprId) -> (ExprId, ExprId) {
        self.common_content(&[e])
    }

    /// The monomial content shared by several expressions, and the first divided by it.
    pub fn common_content(&mut self, exprs: &[ExprId]) -> (ExprId, ExprId) {
        let mut gcd: Option<Rational> = None;
        let mut common: Option<BTreeMap<ExprId, Rational>> = None;
        // Each term's coefficient and factors, read from the sum rather than built as terms.
        let mut all_terms: Vec<(Rational, Vec<(ExprId, Rational)>)> = Vec::new();
        for &x in exprs {
            match self.node(x) {
                Node::Add(c, terms) => {
                    for (t, k) in terms.iter() {
                        let (tc, fs) = self.factors(*t);
                        all_terms.push((number::times(&tc, k), fs));
                    }
                    if !c.is_zero() {
                        all_terms.push((c.clone(), Vec::new()));
                    }
                }
                _ if self.is_zero(x) => {}
                _ => all_terms.push(self.factors(x)),
            }
        }
        for (c, fs) in all_terms {
            gcd = Some(match gcd {
                None => c.abs(),
                Some(g) => number::gcd(&g, &c),
            });
            let fs: BTreeMap<ExprId, Rational> =
                fs.into_iter().filter(|(b, _)| self.as_num(*b).is_none()).collect();
            common = Some(match common {
                None => fs,
                Some(prev) => prev
                    .into_iter()
                    .filter_map(|(b, x)| {
                        let y = fs.get(&b)?;
                        // Only powers of the same sign can be common (m² and m⁻¹ share nothing).
                        if x.is_positive() != y.is_positive() {
                            return None;
                        }
                        Some((b, if x.abs() < y.abs() { x } else { y.clone() }))
                    })
                    .collect(),
            });
        }
        let Some(gcd) = gcd else {
            let first = exprs.first().copied().unwrap_or(self.zero());
            return (self.one(), first);
        };
        let common: Vec<(ExprId, Rational)> = common.unwrap_or_default().into_iter().collect();
        let content = self.product(&gcd, &common);
        let first = exprs.first().copied().unwrap_or(self.zero());
        let inverse = self.powi(content, -1);
        // Term by term, so a common 1/(a + b) cancels before any sum is multiplied out.
        let first = self.expand(first);
        let parts: Vec<ExprId> =
            self.terms(first).into_iter().map(|t| self.mul2(t, inverse)).collect();
        let rest = self.add(&parts);
        (content, rest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parameters of these names, declared in order, as expressions.
    fn params<const N: usize>(p: &mut Pool, names: [&str; N]) -> [ExprId; N] {
        names.map(|name| {
            let s = p.param(name);
            p.sym(s)
        })
    }

    /// (sin² + cos²)² and ³ multiplied out fold whole, beside other terms and under a factor:
    /// r·sin⁴λ + 2·r·sin²λ·cos²λ + r·cos⁴λ + R − r is R, and under sin²θ the same again.
    #[test]
    fn the_square_of_pythagoras_folds() {
        let mut p = Pool::new();
        let [r, big_r, lambda, theta] = params(&mut p, ["r", "R", "l", "th"]);
        let (s, c) = (p.sin(lambda), p.cos(lambda));
        let (s2, c2, s4, c4) = (p.powi(s, 2), p.powi(c, 2), p.powi(s, 4), p.powi(c, 4));
        let square = |p: &mut Pool, x: ExprId| {
            let a = p.mul2(x, s4);
            let b = p.mul(&[x, s2, c2]);
            let b = p.scale(b, &number::int(2));
            let d = p.mul2(x, c4);
            p.add(&[a, b, d])
        };
        let folded = square(&mut p, r);
        let e = p.add(&[folded, big_r]);
        let e = p.sub(e, r);
        assert_eq!(p.simplify(e), big_r);
        let sin_theta = p.sin(theta);
        let under = p.powi(sin_theta, 2);
        let x = p.mul2(r, under);
        let e = square(&mut p, x);
        assert_eq!(p.simplify(e), x);
        // The cube, as the pairwise folds leave it: sin⁶ + 3·sin²·cos² + cos⁶ − 1 is zero, and
        // with sin λ·cos λ in front, still zero.
        let (s6, c6) = (p.powi(s, 6), p.powi(c, 6));
        let mixed = p.mul(&[s2, c2]);
        let mixed = p.scale(mixed, &number::int(3));
        let one = p.one();
        let cube = p.add(&[s6, mixed, c6]);
        let cube = p.sub(cube, one);
        let folded = p.simplify(cube);
        assert!(p.is_zero(folded));
        let front = p.mul(&[r, s, c]);
        let e = p.mul2(front, cube);
        let folded = p.simplify(e);
        assert!(p.is_zero(folded));
        // Not one term modulo sin² + cos² = 1 (it is 2 − sin², or 1 + cos²), and no pair
        // folds: sin⁴ + 3·sin²·cos² + 2·cos⁴ is left alone.
        let mixed = p.mul(&[s2, c2]);
        let mixed = p.scale(mixed, &number::int(3));
        let twice = p.scale(c4, &number::int(2));
        let e = p.add(&[s4, mixed, twice]);
        assert_eq!(p.simplify(e), e);
        // The constant may stand apart from a group that folds: 1 + sin²·cos⁴ + 2·sin⁴·cos²
        // + sin⁶ is 1 + sin².
        let (s6, c4s2, s4c2) = (p.powi(s, 6), p.mul(&[s2, c4]), p.mul(&[s4, c2]));
        let s4c2 = p.scale(s4c2, &number::int(2));
        let e = p.add(&[one, c4s2, s4c2, s6]);
        let expected = p.add(&[one, s2]);
        assert_eq!(p.simplify(e), expected);
    }

    /// A term in the groups of two angles: the first fold changes it, and the second, built
    /// on its old coefficient, must not take it away: (sin²u + cos²u)²·sin⁴v + (sin²v + cos²v)²
    /// multiplied out (its sin⁴v in both groups) is 1 + sin⁴v, and what simplify makes of it
    /// is equal.
    #[test]
    fn groups_that_share_a_term_fold_exactly() {
        let mut p = Pool::new();
        let [u, v] = params(&mut p, ["u", "v"]);
        let square_of = |p: &mut Pool, a: ExprId, front: ExprId| {
            let (s, c) = (p.sin(a), p.cos(a));
            let (s2, c2, s4, c4) = (p.powi(s, 2), p.powi(c, 2), p.powi(s, 4), p.powi(c, 4));
            let mixed = p.mul(&[front, s2, c2]);
            let mixed = p.scale(mixed, &number::int(2));
            let a = p.mul2(front, s4);
            let b = p.mul2(front, c4);
            p.add(&[a, mixed, b])
        };
        let sin_v = p.sin(v);
        let sin4_v = p.powi(sin_v, 4);
        let one = p.one();
        let first = square_of(&mut p, u, sin4_v);
        let second = square_of(&mut p, v, one);
        let e = p.add(&[first, second]);
        let simplified = p.simplify(e);
        let difference = p.sub(simplified, e);
        assert!(p.is_identically_zero(difference), "{}", p.print(simplified, crate::Style::Ascii));
    }

    #[test]
    fn zero_needs_common_denominators_and_pythagoras() {
        let mut p = Pool::new();
        let a = p.param("a");
        let a = p.sym(a);
        let b = p.param("b");
        let b = p.sym(b);
        let s = p.add2(a, b);
        let fa = p.div(a, s);
        let fb = p.div(b, s);
        let one = p.one();
        let sum = p.add(&[fa, fb]);
        let e = p.sub(sum, one);
        assert!(!p.is_zero(e));
        assert!(p.is_identically_zero(e));

        let th = p.param("th");
        let th = p.sym(th);
        let s = p.sin(th);
        let c = p.cos(th);
        let s2 = p.powi(s, 2);
        let c2 = p.powi(c, 2);
        let e = p.add(&[s2, c2]);
        let e = p.sub(e, one);
        assert!(p.is_identically_zero(e));
        let sum = p.add(&[s2, c2]);
        let f = p.simplify(sum);
        assert_eq!(f, one);
    }

    #[test]
    fn content_pulls_out_common_monomials() {
        let mut p = Pool::new();
        let m = p.param("m");
        let m = p.sym(m);
        let l = p.param("L");
        let l = p.sym(l);
        let th = p.param("th");
        let th = p.sym(th);
        let s = p.sin(th);
        let s2 = p.powi(s, 2);
        let l2 = p.powi(l, 2);
        let t1 = p.mul(&[m, l2, s2]);
        let t1 = p.scale(t1, &number::ratio(1, 4));
        let t2 = p.mul(&[m, l2]);
        let t2 = p.scale(t2, &number::ratio(1, 12));
        let e = p.add2(t1, t2);
        let (content, rest) = p.content(e);
        let ml2 = p.mul(&[m, l2]);
        assert_eq!(content, p.scale(ml2, &number::ratio(1, 12)));
        let three_s2 = p.scale(s2, &number::int(3));
        let one = p.one();
        assert_eq!(rest, p.add2(three_s2, one));
    }
}
