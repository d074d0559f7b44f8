//! The folds of `simplify` (sin²u + cos²u = 1 and its square, and products of sines and
//! cosines into one function of a sum or difference) in time near linear in the number of terms.
//!
//! Each fold looks, for one term, for a partner term that its own factors determine; the
//! folds take the first term (in the sum's order) that has a partner, fold it, and look
//! again. Scanning the whole sum again after each fold costs terms × folds, which on the
//! sums of a large model is most of the time. Here each term is examined once, and again
//! only when a term it could pair with changes: a term without a partner is filed under the
//! keys of the partners it would need, and a fold wakes the terms filed under the keys it
//! changes. The terms still to examine are taken in the sum's order, so every fold is the one
//! the full rescan would have made, and the result is the same.

use std::collections::{BTreeMap, BTreeSet};

use rustc_hash::FxHashMap;

use num_traits::{One, ToPrimitive, Zero};

use crate::number::{self, Rational};
use crate::pool::{ExprId, Func, Node, Pool};

/// What a partner is looked up by: a term of the sum, or its constant.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Term(ExprId),
    Constant,
}

/// The terms still to examine, and those waiting for a key to change.
struct Worklist {
    pending: BTreeSet<ExprId>,
    waiting: FxHashMap<Key, Vec<ExprId>>,
}

impl Worklist {
    fn new(terms: &BTreeMap<ExprId, Rational>) -> Self {
        Worklist { pending: terms.keys().copied().collect(), waiting: FxHashMap::default() }
    }

    /// The first term, in the sum's order, still to examine that is still in the sum.
    fn next(&mut self, terms: &BTreeMap<ExprId, Rational>) -> Option<ExprId> {
        while let Some(t) = self.pending.pop_first() {
            if terms.contains_key(&t) {
                return Some(t);
            }
        }
        None
    }

    /// `t` found no partner: it waits for one of the keys it looked up to change.
    fn park(&mut self, t: ExprId, looked_up: Vec<Key>) {
        for key in looked_up {
            self.waiting.entry(key).or_default().push(t);
        }
    }

    /// `key` changed: the terms that looked it up are examined again, and a term that changed
    /// is examined (again).
    fn changed(&mut self, key: Key) {
        if let Some(woken) = self.waiting.remove(&key) {
            self.pending.extend(woken);
        }
        if let Key::Term(t) = key {
            self.pending.insert(t);
        }
    }
}

/// A fold found for one term: the terms it removes, what replaces them and its coefficient.
struct Fold {
    remove: Vec<ExprId>,
    /// The constant's change, when the partner was the constant.
    constant_change: Option<Rational>,
    replacement: ExprId,
    coefficient: Rational,
}

impl Pool {
    /// [`Pool::fold_pythagoras`] with each term examined once, and again only when a term it
    /// could pair with changes.
    pub(crate) fn fold_pythagoras_worklist(&mut self, e: ExprId) -> ExprId {
        self.fold_worklist(e, |pool, t, k, terms, constant| {
            pool.pythagoras_partner(t, k, terms, constant)
        })
    }

    /// Folds a sum term by term with `partner`, which finds the first fold of a term (with its
    /// coefficient), and the keys it looked up, as the full rescan would.
    fn fold_worklist(
        &mut self,
        e: ExprId,
        mut partner: impl FnMut(
            &mut Pool,
            ExprId,
            &Rational,
            &BTreeMap<ExprId, Rational>,
            &Rational,
        ) -> (Option<Fold>, Vec<Key>),
    ) -> ExprId {
        let Node::Add(constant, terms) = self.node(e).clone() else { return e };
        let mut terms: BTreeMap<ExprId, Rational> = terms.iter().cloned().collect();
        let mut constant = constant;
        let mut work = Worklist::new(&terms);
        while let Some(t) = work.next(&terms) {
            let k = terms[&t].clone();
            let (found, looked_up) = partner(self, t, &k, &terms, &constant);
            let Some(fold) = found else {
                work.park(t, looked_up);
                continue;
            };
            for r in &fold.remove {
                terms.remove(r);
            }
            if let Some(change) = fold.constant_change {
                constant += change;
                work.changed(Key::Constant);
            }
            let changed =
                self.add_into(&mut constant, &mut terms, fold.replacement, &fold.coefficient);
            work.changed(changed);
        }
        self.sum_of(constant, terms)
    }

    /// Adds k·`e` to a sum held as its constant and its terms: to the constant when `e` is a
    /// number, else to `e`'s term, which leaves when it cancels. Which of the two changed.
    fn add_into(
        &mut self,
        constant: &mut Rational,
        terms: &mut BTreeMap<ExprId, Rational>,
        e: ExprId,
        k: &Rational,
    ) -> Key {
        let (c, t) = self.split_coefficient(e);
        let k = number::times(&c, k);
        if let Some(n) = self.as_num(t) {
            *constant += n * &k;
            return Key::Constant;
        }
        let entry = terms.entry(t).or_default();
        number::add_to(entry, &k);
        if entry.is_zero() {
            terms.remove(&t);
        }
        Key::Term(t)
    }

    /// The first sin²/cos² fold of term `t` (coefficient `k`), as the full rescan finds it, and
    /// the keys it looked up.
    fn pythagoras_partner(
        &mut self,
        t: ExprId,
        k: &Rational,
        terms: &BTreeMap<ExprId, Rational>,
        constant: &Rational,
    ) -> (Option<Fold>, Vec<Key>) {
        let mut looked_up = Vec::new();
        let (c, fs) = self.factors(t);
        for (i, (b, x)) in fs.iter().enumerate() {
            let (f, u) = match *self.node(*b) {
                Node::Func(f @ (Func::Cos | Func::Sin), u) => (f, u),
                _ => continue,
            };
            if *x < number::int(2) || !x.is_integer() {
                continue;
            }
            let other = if f == Func::Cos { self.sin(u) } else { self.cos(u) };
            let mut reduced = fs.clone();
            reduced[i].1 = x - number::int(2);
            let rest = self.product(&c, &reduced);
            let other2 = self.powi(other, 2);
            // c·X·cos² + c·X·sin² = c·X
            let partner = self.mul2(rest, other2);
            let (pc, pt) = self.split_coefficient(partner);
            looked_up.push(Key::Term(pt));
            if pt != t && terms.get(&pt).map(|pk| number::divided(pk, &pc)).as_ref() == Some(k) {
                let fold = Fold {
                    remove: vec![t, pt],
                    constant_change: None,
                    replacement: rest,
                    coefficient: k.clone(),
                };
                return (Some(fold), looked_up);
            }
            // k·X·cos² − k·X = −k·X·sin²
            let (rc, rt) = self.split_coefficient(rest);
            let numeric = self.as_num(rt).is_some();
            let partner_coef = if numeric {
                looked_up.push(Key::Constant);
                Some(constant * &rc.recip())
            } else {
                looked_up.push(Key::Term(rt));
                terms.get(&rt).map(|pk| number::divided(pk, &rc))
            };
            if partner_coef.as_ref() == Some(&-k.clone()) && !k.is_zero() {
                let folded = self.mul2(rest, other2);
                let mut remove = vec![t];
                let mut constant_change = None;
                if numeric {
                    constant_change = Some(-(&rc * &-k.clone()));
                } else {
                    remove.push(rt);
                }
                let fold =
                    Fold { remove, constant_change, replacement: folded, coefficient: -k.clone() };
                return (Some(fold), looked_up);
            }
        }
        (None, looked_up)
    }

    /// Folds what the pairwise folds leave of a polynomial in sin²u and cos²u that is one
    /// term modulo sin²u + cos²u = 1: the terms that share everything else (X, and an odd sin u
    /// or cos u) are gathered as X·Σ k·s^i·(1 − s)^j in s = sin²u, and as the same in cos²u,
    /// and where either has at most one term, and fewer than the terms gathered, it replaces
    /// them. (sin² + cos²)² and (sin² + cos²)³ multiplied out are what this finds: a unit axis
    /// written in angles leaves them in every product of rotations about it.
    pub(crate) fn fold_pythagoras_groups(&mut self, e: ExprId) -> ExprId {
        let Node::Add(constant, terms) = self.node(e).clone() else { return e };
        let heavy = self.heavy_angles(&terms);
        if heavy.is_empty() {
            return e;
        }
        let one = self.one();
        let groups = self.pythagoras_groups(&terms, &heavy);
        let original_constant = constant.clone();
        let mut terms: BTreeMap<ExprId, Rational> = terms.iter().cloned().collect();
        let mut constant = constant;
        let mut changed = false;
        for (key, mut members) in groups {
            // Every fold is an identity among its own members; one whose members another fold
            // has changed since (a term two angles share) is left for the next `simplify`.
            let unchanged = members.iter().all(|m| match m.term {
                Some(t) => terms.get(&t) == Some(&m.k),
                None => constant == m.k,
            });
            if !unchanged {
                continue;
            }
            let mut fold = one_term(&members);
            // The sum's constant belongs to the group of plain powers, where it may be what
            // makes it one term (sin⁶ + 3·sin²·cos² + cos⁶ − 1) or what keeps it from one.
            let plain = key.rest == one && key.odd_sin == 0 && key.odd_cos == 0;
            if fold.is_none()
                && plain
                && !original_constant.is_zero()
                && constant == original_constant
            {
                members.push(Member { term: None, sin: 0, cos: 0, k: constant.clone() });
                fold = one_term(&members);
            }
            let Some((poly, func)) = fold else { continue };
            for m in &members {
                match m.term {
                    Some(t) => {
                        terms.remove(&t);
                    }
                    None => constant -= &m.k,
                }
            }
            changed = true;
            let Some((degree, coefficient)) = poly.iter().enumerate().find(|(_, c)| !c.is_zero())
            else {
                continue;
            };
            let (sin_u, cos_u) = (self.sin(key.angle), self.cos(key.angle));
            let (sin_power, cos_power) = match func {
                Func::Sin => (2 * degree as i64 + i64::from(key.odd_sin), i64::from(key.odd_cos)),
                _ => (i64::from(key.odd_sin), 2 * degree as i64 + i64::from(key.odd_cos)),
            };
            let (s, c) = (self.powi(sin_u, sin_power), self.powi(cos_u, cos_power));
            let folded = self.mul(&[key.rest, s, c]);
            self.add_into(&mut constant, &mut terms, folded, coefficient);
        }
        if !changed {
            return e;
        }
        self.sum_of(constant, terms)
    }

    /// The angles u of the terms of degree 2 or more in sin²u and cos²u, sorted.
    fn heavy_angles(&self, terms: &[(ExprId, Rational)]) -> Vec<ExprId> {
        // A group that folds to one term and that the pairwise folds left has a term of degree
        // 2 or more in sin²u and cos²u: up to degree 1, the only such groups are their pairs.
        // The angles with such a term, found without building anything.
        let mut heavy: Vec<ExprId> = Vec::new();
        for (t, _) in terms.iter() {
            // A term of degree 2 is a product (sin²u·cos²u, sin⁴u).
            let Node::Mul(_, fs) = self.node(*t) else { continue };
            let mut degrees: Vec<(ExprId, u32)> = Vec::new();
            for (b, x) in fs.iter() {
                if let Node::Func(Func::Sin | Func::Cos, u) = self.node(*b) {
                    let half = x.is_integer().then(|| x.to_u32()).flatten().unwrap_or(0) / 2;
                    match degrees.iter_mut().find(|(v, _)| v == u) {
                        Some((_, d)) => *d += half,
                        None => degrees.push((*u, half)),
                    }
                }
            }
            heavy.extend(degrees.into_iter().filter(|(_, d)| *d >= 2).map(|(u, _)| u));
        }
        heavy.sort();
        heavy.dedup();
        heavy
    }

    /// The terms gathered by what they share besides powers of sin u and cos u, for each
    /// heavy angle u: X, and an odd sin u or cos u.
    fn pythagoras_groups(
        &mut self,
        terms: &[(ExprId, Rational)],
        heavy: &[ExprId],
    ) -> BTreeMap<GroupKey, Vec<Member>> {
        let mut groups: BTreeMap<GroupKey, Vec<Member>> = BTreeMap::new();
        for (t, k) in terms.iter() {
            let (c, fs) = self.factors(*t);
            let mut angles: Vec<ExprId> = fs
                .iter()
                .filter_map(|(b, x)| match self.node(*b) {
                    Node::Func(Func::Sin | Func::Cos, u)
                        if x.is_integer()
                            && x > &Rational::zero()
                            && heavy.binary_search(u).is_ok() =>
                    {
                        Some(*u)
                    }
                    _ => None,
                })
                .collect();
            angles.sort();
            angles.dedup();
            'angles: for u in angles {
                let (mut sin_power, mut cos_power) = (0u32, 0u32);
                let mut rest = Vec::with_capacity(fs.len());
                for (b, x) in &fs {
                    let power = match self.node(*b) {
                        Node::Func(Func::Sin, v) if *v == u => &mut sin_power,
                        Node::Func(Func::Cos, v) if *v == u => &mut cos_power,
                        _ => {
                            rest.push((*b, x.clone()));
                            continue;
                        }
                    };
                    // A quotient by sin u or cos u is no polynomial in them.
                    match x.is_integer().then(|| x.to_u32()).flatten() {
                        Some(n) => *power = n,
                        None => continue 'angles,
                    }
                }
                if (sin_power / 2) + (cos_power / 2) > GROUP_DEGREE_LIMIT {
                    continue;
                }
                let x = self.product(&c, &rest);
                let key =
                    GroupKey { angle: u, rest: x, odd_sin: sin_power % 2, odd_cos: cos_power % 2 };
                let member =
                    Member { term: Some(*t), sin: sin_power / 2, cos: cos_power / 2, k: k.clone() };
                groups.entry(key).or_default().push(member);
            }
        }
        groups
    }

    /// [`Pool::fold_angle_sums`] with each term examined once, and again only when a term it
    /// could pair with changes.
    pub(crate) fn fold_angle_sums_worklist(&mut self, e: ExprId) -> ExprId {
        self.fold_worklist(e, |pool, t, k, terms, _| pool.angle_sum_partner(t, k, terms))
    }

    /// The first angle-sum fold of term `t` (coefficient `k`), as the full rescan finds it,
    /// and the keys it looked up.
    fn angle_sum_partner(
        &mut self,
        t: ExprId,
        k: &Rational,
        terms: &BTreeMap<ExprId, Rational>,
    ) -> (Option<Fold>, Vec<Key>) {
        let mut looked_up = Vec::new();
        let (c, fs) = self.factors(t);
        let trig: Vec<(usize, Func, ExprId)> = fs
            .iter()
            .enumerate()
            .filter(|(_, (_, x))| x.is_one())
            .filter_map(|(i, (b, _))| match *self.node(*b) {
                Node::Func(f @ (Func::Sin | Func::Cos), u) => Some((i, f, u)),
                _ => None,
            })
            .collect();
        for &(i, fi, a) in &trig {
            for &(j, fj, b) in &trig {
                // sin a·sin b pairs with cos a·cos b; sin a·cos b with cos a·sin b.
                if i == j || a == b || fi != Func::Sin || (fj == Func::Sin && j < i) {
                    continue;
                }
                let mut partner_fs = fs.clone();
                partner_fs[i].0 = self.cos(a);
                partner_fs[j].0 = if fj == Func::Sin { self.cos(b) } else { self.sin(b) };
                let partner = self.product(&c, &partner_fs);
                let (pc, pt) = self.split_coefficient(partner);
                looked_up.push(Key::Term(pt));
                let Some(pk) = terms.get(&pt).map(|pk| number::divided(pk, &pc)) else { continue };
                let same = pk == *k;
                if !same && pk != -k.clone() {
                    continue;
                }
                let (angle, func, coefficient) = match (fj, same) {
                    (Func::Sin, true) => (self.sub(a, b), Func::Cos, k.clone()),
                    (Func::Sin, false) => (self.add2(a, b), Func::Cos, pk),
                    (_, false) => (self.sub(a, b), Func::Sin, k.clone()),
                    (_, true) => (self.add2(a, b), Func::Sin, k.clone()),
                };
                let mut rest = fs.clone();
                rest[i].1 = Rational::zero();
                rest[j].1 = Rational::zero();
                let rest = self.product(&c, &rest);
                let folded = self.func(func, angle);
                let replacement = self.mul2(rest, folded);
                let fold =
                    Fold { remove: vec![t, pt], constant_change: None, replacement, coefficient };
                return (Some(fold), looked_up);
            }
        }
        (None, looked_up)
    }
}

/// The highest degree in sin²u and cos²u a term may have to join a group: (sin² + cos²)³ is
/// of degree 3, and the polynomials grow as the square of the degree.
const GROUP_DEGREE_LIMIT: u32 = 8;

/// The group's polynomial in sin²u or in cos²u, whichever has fewer terms, and which, where it
/// has at most one term and fewer than the group has members.
fn one_term(members: &[Member]) -> Option<(Vec<Rational>, Func)> {
    if members.len() < 3 {
        // Pairs are the pairwise folds'.
        return None;
    }
    let in_sin = polynomial(members, |m| (m.sin, m.cos));
    let in_cos = polynomial(members, |m| (m.cos, m.sin));
    let nonzero = |p: &[Rational]| p.iter().filter(|c| !c.is_zero()).count();
    let (poly, func) = if nonzero(&in_sin) <= nonzero(&in_cos) {
        (in_sin, Func::Sin)
    } else {
        (in_cos, Func::Cos)
    };
    (nonzero(&poly) <= 1).then_some((poly, func))
}

/// Terms that differ only in even powers of sin u and cos u: the angle, what else they have
/// (coefficient included), and whether sin u and cos u are there to an odd power.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct GroupKey {
    angle: ExprId,
    rest: ExprId,
    odd_sin: u32,
    odd_cos: u32,
}

/// One term of a group, k·(sin²u)^sin·(cos²u)^cos (`None`: the sum's constant).
struct Member {
    term: Option<ExprId>,
    sin: u32,
    cos: u32,
    k: Rational,
}

/// Σ k·x^i·(1 − x)^j over the members, with (i, j) as `powers` picks them, as coefficients of
/// x⁰, x¹, …
fn polynomial(members: &[Member], powers: impl Fn(&Member) -> (u32, u32)) -> Vec<Rational> {
    let mut out: Vec<Rational> = Vec::new();
    for m in members {
        let (i, j) = powers(m);
        // (1 − x)^j by the binomial theorem.
        let mut binomial = number::int(1);
        for r in 0..=j {
            let degree = (i + r) as usize;
            if out.len() <= degree {
                out.resize(degree + 1, Rational::zero());
            }
            let sign = if r % 2 == 0 { number::int(1) } else { number::int(-1) };
            number::add_to(&mut out[degree], &(&m.k * &binomial * sign));
            binomial = binomial * number::int(i64::from(j - r)) / number::int(i64::from(r + 1));
        }
    }
    out
}
