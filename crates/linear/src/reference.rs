//! The reference every case starts from: the `linearize about` lines merged item by item,
//! the checks that do not depend on the case (an eliminated coordinate named, positions
//! missing, equations that change with time there), which coordinates are cyclic, and the
//! Jacobians of the equations of motion at the reference that the holonomic and the kept
//! cases share.
//!
//! With q̈ = 0 at the reference, the term ∂M/∂q·q̈ of the linearized M·q̈ drops out, so the
//! Jacobians of f (and of Jᵀλ) are all there is to it: K = −∂(f + Jᵀλ)/∂q and C = −∂f/∂q̇.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use mechanics::Derivation;

use crate::LinearConstraint;

/// The reference's items, by coordinate and whether a rate, in the order written.
pub(crate) type Items = [((SymId, bool), (ExprId, Span))];

/// The items of every `linearize about` line, a later one overriding an earlier one of the
/// same coordinate and kind, in the order written.
pub(crate) fn items(d: &Derivation) -> Vec<((SymId, bool), (ExprId, Span))> {
    let mut given: HashMap<(SymId, bool), (ExprId, Span)> = HashMap::new();
    for line in &d.model.linearize {
        for item in &line.items {
            given.insert((item.coord, item.rate), (item.value, item.span));
        }
    }
    let mut items: Vec<_> = given.into_iter().collect();
    items.sort_by_key(|(_, (_, s))| (s.start, s.end));
    items
}

/// An item for a coordinate that a constraint eliminated: it is not one of the equations'.
pub(crate) fn eliminated(d: &Derivation, items: &Items) -> Vec<Diagnostic> {
    let mut errors = Vec::new();
    for ((coord, _), (_, item_span)) in items {
        if let Some(e) = d.eliminated.iter().find(|e| e.coord == *coord) {
            let name = d.model.pool.symbol(*coord).name.clone();
            let constraint = &d.model.constraints[e.constraint].name;
            errors.push(
                Diagnostic::error(*item_span, format!("`{name}` is eliminated by `{constraint}`"))
                    .with_label("not a coordinate of the equations")
                    .with_hint(format!(
                        "leave `{name}` out: its reference follows from the others through `{constraint}`"
                    )),
            );
        }
    }
    errors
}

/// Whether a coordinate appears in neither M nor f nor any kept constraint: only its rate
/// matters, and a steady motion may move it. An expression left unsimplified for its size
/// may still hold the coordinate where the algebra would cancel it (a wheel's spin in
/// sin² + cos²): there a derivative that is zero at generic points counts as absent.
pub(crate) fn is_cyclic(d: &mut Derivation, q: SymId) -> bool {
    let pool = &mut d.model.pool;
    let mut exprs: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    exprs.extend(&d.forcing);
    exprs.extend(d.multipliers.iter().map(|m| m.rows.phi()));
    !exprs.iter().any(|e| {
        pool.depends_on(*e, q) && {
            let d = pool.diff(*e, q);
            !pool.vanishes_at_generic_points(d)
        }
    })
}

/// Each coordinate's cyclic flag.
pub(crate) fn cyclic_flags(d: &mut Derivation) -> Vec<bool> {
    (0..d.coords.len()).map(|i| is_cyclic(d, d.coords[i])).collect()
}

/// "A reference that moves `θ` does not stay put", at the item that gives θ a rate; `why`
/// says what depends on θ, `may` which coordinates a steady motion may move.
pub(crate) fn moves(span: Span, name: &str, why: &str, may: &str) -> Diagnostic {
    Diagnostic::error(span, format!("a reference that moves `{name}` does not stay put"))
        .with_label(format!("{name} is not {why}"))
        .with_hint(format!(
            "a steady motion may move only {may}; give this one a position and rate 0"
        ))
}

/// "The rate of `y` follows from the constraints", at the item that gives it; `which` names
/// the constraints.
pub(crate) fn dependent_given(span: Span, name: &str, which: &str) -> Diagnostic {
    Diagnostic::error(span, format!("the rate of `{name}` follows from the {which} constraints"))
        .with_label("a dependent rate")
        .with_hint("leave it out: give the independent rates, and the constraints give this one")
}

/// The reference names no position for these coordinates (`what` says which kind of
/// coordinate may go without one: "a cyclic", "an ignorable").
pub(crate) fn missing_positions(
    pool: &Pool,
    missing: &[SymId],
    span: Span,
    what: &str,
) -> Option<Diagnostic> {
    let first = missing.first()?;
    let names: Vec<String> =
        missing.iter().map(|q| format!("`{}`", pool.symbol(*q).name)).collect();
    let (them, it) = if missing.len() == 1 { ("", "it") } else { ("s", "them") };
    Some(
        Diagnostic::error(
            span,
            format!("the reference gives no position for {}", names.join(", ")),
        )
        .with_label(format!("position{them} missing here"))
        .with_hint(format!(
            "add {it} to the line (`{} = …`); rates default to 0, and {what} coordinate \
                 needs no position",
            pool.symbol(*first).name
        )),
    )
}

/// A reference whose linearized equations still change with t is no equilibrium or steady
/// motion: refused, naming the reference. A drive or a schedule that is still there makes the
/// small motions those of a time-varying system.
pub(crate) fn refuse_time_dependence(
    pool: &mut Pool,
    exprs: &[ExprId],
    time: SymId,
    span: Span,
) -> Result<(), Vec<Diagnostic>> {
    let timed = exprs.iter().any(|e| {
        pool.depends_on(*e, time) && {
            let d = pool.diff(*e, time);
            !pool.is_identically_zero(d)
        }
    });
    if !timed {
        return Ok(());
    }
    Err(vec![Diagnostic::error(span, "the equations depend on time at this reference")
        .with_label("the linearized equations would change with t")
        .with_hint(
            "a reference needs equations that do not change with time: no drive or schedule \
             written with `t` may act there",
        )])
}

/// Every expression of M, C, K, the residual and the constraints' rows (and `more`), for
/// [`refuse_time_dependence`].
pub(crate) fn all_of(
    matrices: [&[Vec<ExprId>]; 3],
    residual: &[ExprId],
    constraints: &[LinearConstraint],
    more: &[ExprId],
) -> Vec<ExprId> {
    let mut all: Vec<ExprId> = matrices.iter().flat_map(|m| m.iter().flatten()).copied().collect();
    all.extend(residual);
    for c in constraints {
        all.extend(&c.jacobian);
        all.extend([c.phi, c.bias]);
    }
    all.extend(more);
    all
}

/// Where the reference puts each coordinate (see [`crate::Linearization`]'s fields).
pub(crate) struct Placed {
    pub cyclic: Vec<bool>,
    pub positions: Vec<Option<ExprId>>,
    pub rates: Vec<ExprId>,
}

/// M, C, K and the residual at a reference.
pub(crate) struct AtReference {
    pub mass: Vec<Vec<ExprId>>,
    pub damping: Vec<Vec<ExprId>>,
    pub stiffness: Vec<Vec<ExprId>>,
    pub residual: Vec<ExprId>,
}

/// The equations of motion with their kept constraints at the reference, as the holonomic
/// and the kept cases linearize them. With g = f + Jᵀλ (λ the multipliers' symbols): M,
/// C = −∂g/∂q̇ (= −∂f/∂q̇: J has no rates, for a velocity constraint either: it is linear in
/// them), K = −∂g/∂q (zero for a cyclic coordinate), and g, each put through `at` (the
/// reference substituted).
pub(crate) fn at_reference(
    d: &mut Derivation,
    cyclic: &[bool],
    at: &mut dyn FnMut(&mut Pool, ExprId) -> ExprId,
) -> AtReference {
    let n = d.coords.len();
    let (mut mass, mut damping, mut stiffness) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..n {
        let (mut m, mut c, mut k) = (Vec::new(), Vec::new(), Vec::new());
        for (i, is_cyclic) in cyclic.iter().enumerate() {
            // C and K are the residual's partials at rest, the same derivatives an implicit
            // method's exact Jacobian is made of (`Derivation::force_partial`).
            let (rate, coord) = (d.rates[i], d.coords[i]);
            let dc = d.force_partial(j, rate);
            let dk = (!is_cyclic).then(|| d.force_partial(j, coord));
            let pool = &mut d.model.pool;
            m.push(at(pool, d.mass_matrix[j][i]));
            c.push(at(pool, dc));
            k.push(match dk {
                Some(dk) => at(pool, dk),
                None => pool.zero(),
            });
        }
        mass.push(m);
        damping.push(c);
        stiffness.push(k);
    }
    let pool = &mut d.model.pool;
    let mut residual = d.forcing.to_vec();
    for m in &d.multipliers {
        let lambda = pool.sym(m.lambda);
        for (j, g) in residual.iter_mut().enumerate() {
            let force = pool.mul2(m.rows.jacobian[j], lambda);
            *g = pool.add2(*g, force);
        }
    }
    let residual: Vec<ExprId> = residual.iter().map(|g| at(pool, *g)).collect();
    AtReference { mass, damping, stiffness, residual }
}
