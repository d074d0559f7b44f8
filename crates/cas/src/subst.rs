//! Substitution of expressions for symbols.

use std::collections::HashMap;

use crate::pool::{ExprId, Node, Pool, SymId};

impl Pool {
    /// Replaces every symbol in `map` by its expression, re-canonicalising on the way up.
    /// Sub-expressions that mention none of the symbols are shared, not rebuilt.
    pub fn subst(&mut self, e: ExprId, map: &HashMap<SymId, ExprId>) -> ExprId {
        let mut memo = HashMap::new();
        self.subst_memo(e, map, &mut memo)
    }

    /// Like [`Pool::subst`], reusing `memo` across calls with the same map.
    pub fn subst_memo(
        &mut self,
        e: ExprId,
        map: &HashMap<SymId, ExprId>,
        memo: &mut HashMap<ExprId, ExprId>,
    ) -> ExprId {
        if let Some(&r) = memo.get(&e) {
            return r;
        }
        let touches = self.free_symbols(e).iter().any(|s| map.contains_key(s));
        let r = if !touches {
            e
        } else {
            match self.node(e).clone() {
                Node::Sym(s) => map[&s],
                Node::Num(_) | Node::Pi => e,
                Node::Add(c, terms) => {
                    let mut parts = vec![self.num(c)];
                    for (t, k) in terms.iter() {
                        let t = self.subst_memo(*t, map, memo);
                        parts.push(self.scale(t, k));
                    }
                    self.add(&parts)
                }
                Node::Mul(c, factors) => {
                    let mut parts = vec![self.num(c)];
                    for (b, x) in factors.iter() {
                        let b = self.subst_memo(*b, map, memo);
                        parts.push(self.powq(b, x));
                    }
                    self.mul(&parts)
                }
                Node::Pow(b, x) => {
                    let b = self.subst_memo(b, map, memo);
                    let x = self.subst_memo(x, map, memo);
                    self.pow(b, x)
                }
                Node::Func(f, a) => {
                    let a = self.subst_memo(a, map, memo);
                    self.func(f, a)
                }
                Node::Atan2(y, x) => {
                    let y = self.subst_memo(y, map, memo);
                    let x = self.subst_memo(x, map, memo);
                    self.atan2(y, x)
                }
            }
        };
        memo.insert(e, r);
        r
    }
}
