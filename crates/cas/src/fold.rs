//! The pairwise folds of `simplify` (sin²u + cos²u = 1, and products of sines and cosines
//! into one function of a sum or difference) in time near linear in the number of terms.
//!
//! Each fold looks, for one term, for a partner term that its own factors determine; the
//! folds take the first term (in the sum's order) that has a partner, fold it, and look
//! again. Scanning the whole sum again after each fold costs terms × folds, which on the
//! sums of a large model is most of the time. Here each term is examined once, and again
//! only when a term it could pair with changes: a term without a partner is filed under the
//! keys of the partners it would need, and a fold wakes the terms filed under the keys it
//! changes. The terms still to examine are taken in the sum's order, so every fold is the one
//! the full rescan would have made, and the result is the same.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use num_traits::{One, Zero};

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
    waiting: HashMap<Key, Vec<ExprId>>,
}

impl Worklist {
    fn new(terms: &BTreeMap<ExprId, Rational>) -> Self {
        Worklist { pending: terms.keys().copied().collect(), waiting: HashMap::new() }
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
        let Node::Add(constant, terms) = self.node(e).clone() else { return e };
        let mut terms: BTreeMap<ExprId, Rational> = terms.iter().cloned().collect();
        let mut constant = constant;
        let mut work = Worklist::new(&terms);
        while let Some(t) = work.next(&terms) {
            let k = terms[&t].clone();
            let (found, looked_up) = self.pythagoras_partner(t, &k, &terms, &constant);
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
            let (rc, rt) = self.split_coefficient(fold.replacement);
            if let Some(n) = self.as_num(rt) {
                constant += n * &rc * &fold.coefficient;
                work.changed(Key::Constant);
            } else {
                number::add_to(
                    terms.entry(rt).or_default(),
                    &number::times(&rc, &fold.coefficient),
                );
                if terms[&rt].is_zero() {
                    terms.remove(&rt);
                }
                work.changed(Key::Term(rt));
            }
        }
        self.sum_of(constant, terms)
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

    /// [`Pool::fold_angle_sums`] with each term examined once, and again only when a term it
    /// could pair with changes.
    pub(crate) fn fold_angle_sums_worklist(&mut self, e: ExprId) -> ExprId {
        let Node::Add(constant, terms) = self.node(e).clone() else { return e };
        let mut terms: BTreeMap<ExprId, Rational> = terms.iter().cloned().collect();
        let mut work = Worklist::new(&terms);
        while let Some(t) = work.next(&terms) {
            let k = terms[&t].clone();
            let (found, looked_up) = self.angle_sum_partner(t, &k, &terms);
            let Some(fold) = found else {
                work.park(t, looked_up);
                continue;
            };
            for r in &fold.remove {
                terms.remove(r);
            }
            let (fc, ft) = self.split_coefficient(fold.replacement);
            number::add_to(terms.entry(ft).or_default(), &number::times(&fc, &fold.coefficient));
            if terms[&ft].is_zero() {
                terms.remove(&ft);
            }
            work.changed(Key::Term(ft));
        }
        self.sum_of(constant, terms)
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
