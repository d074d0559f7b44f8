//! The Euler–Lagrange rows of the kinetic energy of translation, of planar rotation and of
//! rotation in space, without differentiating T twice. For T = ½·m·|ṙ|² with m constant,
//! Lagrange's equations are Newton's projected on the coordinates:
//!
//! d/dt ∂T/∂q̇ᵢ − ∂T/∂qᵢ = m·r̈·∂r/∂qᵢ, with r̈ = Σⱼ (∂r/∂qⱼ)·q̈ⱼ + a₀,
//!
//! so the term adds m·(∂r/∂qᵢ)·(∂r/∂qⱼ) to Mᵢⱼ and −m·a₀·∂r/∂qᵢ to fᵢ, where a₀ is r̈ with
//! every q̈ set to zero. A planar body's ½·I·θ̇² is the same with the angle for r.
//!
//! Differentiating T twice builds products of sums that are only expanded, and mostly cancel,
//! later: their size grows like the cube of the chain's length. These rows hold only what
//! survives. For translation and planar rotation they are the same polynomial in the same
//! sines, cosines and symbols as the rows by differentiation, so once `simplify` expands them
//! it sees the same sum, and prints the same equations. That holds where expansion is
//! canonical: positions built from sums, products, integer powers of sums and functions whose
//! derivatives are powers of functions; a position outside that (a square root or quotient of
//! a sum, `atan2`, `ln`) keeps its body on the route by differentiation.
//!
//! A body turning in space, T = ½·ωᵀ·I·ω with ω in body axes and I constant, is Euler's
//! equations projected the same way: with Wᵢ = ∂ω/∂q̇ᵢ (the partial angular velocity) and α₀
//! the body-axes derivative of ω with every q̈ set to zero, the term adds Wᵢᵀ·I·Wⱼ to Mᵢⱼ and
//! −Wᵢᵀ·(I·α₀ + ω × I·ω) to fᵢ. This route and differentiation agree only where Rᵀ·R = 1,
//! which for angles means modulo sin² + cos² = 1: their rows print alike once `simplify` has
//! folded those (every example's do), and a row too large to simplify is a sum of products of
//! short factors, which is what the numbers want. Euler parameters, whose ω is exact only on
//! their unit sphere, are differentiated.

use std::collections::{BTreeMap, HashMap, HashSet};

use cas::{ExprId, Func, Node, Pool, SymId, SymbolKind};
use model::{Model, Rotation};

/// One term ½·mass·|d position/dt|² of T, with the mass constant.
#[derive(Clone)]
pub(super) struct Inertial {
    pub mass: ExprId,
    /// The position in the remaining coordinates (for a planar body's rotation, its angle).
    pub position: Vec<ExprId>,
}

/// One term ½·ωᵀ·I·ω of T, a body turning in space, with I constant.
#[derive(Clone)]
pub(super) struct Turning {
    pub inertia: [[ExprId; 3]; 3],
    /// ω in body axes, in the remaining coordinates and their rates.
    pub omega: [ExprId; 3],
    /// Whether ω has a part no rate multiplies (a turning the scene prescribes in time).
    pub driven: bool,
}

/// The kinetic energy terms that take the structural route, in the remaining coordinates,
/// and their sum as `energies` built it (in all declared coordinates), so the rest of L can be
/// told apart: `(terms, their T)`.
pub(super) fn inertial_terms(
    pool: &mut Pool,
    model: &Model,
    map: &HashMap<SymId, ExprId>,
    coords: &[SymId],
) -> (Vec<InertialTerm>, ExprId) {
    let mut terms = Vec::new();
    let mut kinetic = Vec::new();
    let mut candidates: Vec<(ExprId, Vec<ExprId>, ExprId)> = Vec::new();
    for body in &model.bodies {
        // The term exactly as `energies` builds it, so that it cancels from L.
        let t = super::energies::translational_kinetic(pool, body);
        candidates.push((body.mass, body.position.clone(), t));
        if let Some(Rotation::Planar { inertia, angle }) = &body.rotation {
            let t = super::energies::planar_kinetic(pool, *inertia, *angle);
            candidates.push((*inertia, vec![*angle], t));
        }
    }
    let mut safe = HashSet::new();
    for (mass, position, t) in candidates {
        if !is_constant(pool, mass) {
            continue;
        }
        let position: Vec<ExprId> = position.iter().map(|x| pool.subst(*x, map)).collect();
        if !position.iter().all(|x| expands_canonically(pool, *x, &mut safe))
            || !position.iter().all(|x| moves_with(pool, *x, coords))
        {
            continue;
        }
        terms.push(InertialTerm::Moving(Inertial { mass, position }));
        kinetic.push(t);
    }
    for body in &model.bodies {
        let Some(rotation @ Rotation::Spatial { inertia, euler_parameters: None, .. }) =
            &body.rotation
        else {
            // Euler parameters give ω exactly only on their unit sphere, and the identity
            // behind this route needs it everywhere: they are differentiated.
            continue;
        };
        if !inertia.iter().flatten().all(|x| is_constant(pool, *x)) {
            continue;
        }
        let w = rotation.spatial_angular_velocity(pool, false).expect("in space");
        let t = super::energies::spatial_kinetic(pool, inertia, w);
        let omega = w.map(|x| pool.subst(x, map));
        if !omega.iter().all(|x| expands_canonically(pool, *x, &mut safe))
            || !omega.iter().all(|x| turns_with(pool, *x, coords))
        {
            continue;
        }
        let rates: HashMap<SymId, ExprId> = coords
            .iter()
            .map(|q| (pool.rate(*q).expect("coordinates have rates"), pool.zero()))
            .collect();
        let driven = omega.iter().any(|x| {
            let rest = pool.subst(*x, &rates);
            !pool.is_zero(rest)
        });
        terms.push(InertialTerm::Turning(Turning { inertia: *inertia, omega, driven }));
        kinetic.push(t);
    }
    let kinetic = pool.add(&kinetic);
    (terms, kinetic)
}

/// A kinetic-energy term on the structural route (its parts private to this module).
#[derive(Clone)]
pub(super) enum InertialTerm {
    Moving(Inertial),
    Turning(Turning),
}

/// Whether `e` is constant in time: parameters and numbers only.
fn is_constant(pool: &mut Pool, e: ExprId) -> bool {
    pool.free_symbols(e).iter().all(|s| matches!(pool.symbol(*s).kind, SymbolKind::Param))
}

/// Whether a position depends on nothing but the remaining coordinates (not their rates),
/// time and parameters.
fn moves_with(pool: &mut Pool, e: ExprId, coords: &[SymId]) -> bool {
    pool.free_symbols(e).iter().all(|s| match pool.symbol(*s).kind {
        SymbolKind::Param | SymbolKind::Time => true,
        SymbolKind::Coordinate { order: 0, .. } => coords.contains(s),
        SymbolKind::Coordinate { .. } => false,
    })
}

/// Whether an angular velocity depends on nothing but the remaining coordinates, their rates,
/// time and parameters.
fn turns_with(pool: &mut Pool, e: ExprId, coords: &[SymId]) -> bool {
    pool.free_symbols(e).iter().all(|s| match pool.symbol(*s).kind {
        SymbolKind::Param | SymbolKind::Time => true,
        SymbolKind::Coordinate { order: 0, .. } => coords.contains(s),
        SymbolKind::Coordinate { order: 1, .. } => coords.iter().any(|q| pool.rate(*q) == Some(*s)),
        SymbolKind::Coordinate { .. } => false,
    })
}

/// Whether `e`, and every derivative of it, expands to one canonical polynomial in its atoms:
/// no sum under a root or in a denominator, no symbolic exponent, and only functions whose
/// derivatives are again of that kind.
fn expands_canonically(pool: &Pool, e: ExprId, safe: &mut HashSet<ExprId>) -> bool {
    if safe.contains(&e) {
        return true;
    }
    let ok = match pool.node(e) {
        Node::Num(_) | Node::Sym(_) | Node::Pi => true,
        Node::Add(_, terms) => {
            let terms = terms.clone();
            terms.iter().all(|(t, _)| expands_canonically(pool, *t, safe))
        }
        Node::Mul(_, factors) => {
            let factors = factors.clone();
            factors.iter().all(|(b, x)| {
                let sum_ok = !matches!(pool.node(*b), Node::Add(..))
                    || (x.is_integer() && cas::number::Signed::is_positive(x));
                sum_ok && expands_canonically(pool, *b, safe)
            })
        }
        Node::Func(f, a) => {
            matches!(
                f,
                Func::Sin
                    | Func::Cos
                    | Func::Tan
                    | Func::Sinh
                    | Func::Cosh
                    | Func::Tanh
                    | Func::Exp
            ) && expands_canonically(pool, *a, safe)
        }
        Node::Pow(..) | Node::Atan2(..) => false,
    };
    if ok {
        safe.insert(e);
    }
    ok
}

/// The structural part of the rows: M (upper triangle filled, j ≥ i) and the part of f, both
/// raw (sums of products, not yet simplified), for the given terms.
pub(super) fn structural_rows(
    pool: &mut Pool,
    terms: &[InertialTerm],
    coords: &[SymId],
) -> (Vec<Vec<ExprId>>, Vec<ExprId>) {
    let n = coords.len();
    let index: HashMap<SymId, usize> = coords.iter().enumerate().map(|(i, q)| (*q, i)).collect();
    // Mᵢⱼ = Σ m·(∂r/∂qᵢ)·(∂r/∂qⱼ): the same product recurs down a chain, so each distinct
    // product is formed once and its masses added. A chain's masses come in runs of one mass
    // (a 64-link chain's m 87,000 times over), counted rather than added one by one.
    let mut mass_parts: Vec<Vec<BTreeMap<ExprId, Masses>>> = vec![vec![BTreeMap::new(); n]; n];
    let mut products: HashMap<(ExprId, ExprId), ExprId> = HashMap::new();
    // fᵢ = −Σ m·a₀·∂r/∂qᵢ: grouped by (∂r/∂qᵢ, m), so that a chain's accelerations are added
    // once per coordinate before the one product is formed.
    let mut force_parts: Vec<BTreeMap<(ExprId, ExprId), Vec<ExprId>>> = vec![BTreeMap::new(); n];
    for term in terms {
        let term = match term {
            InertialTerm::Moving(term) => term,
            InertialTerm::Turning(turn) => {
                turning_rows(pool, turn, coords, &mut products, &mut mass_parts, &mut force_parts);
                continue;
            }
        };
        for &x in &term.position {
            let moving: Vec<(usize, SymId)> = pool
                .free_symbols(x)
                .iter()
                .filter_map(|s| index.get(s).map(|&i| (i, *s)))
                .collect();
            let mut jacobian: Vec<(usize, ExprId)> = Vec::with_capacity(moving.len());
            for (i, s) in moving {
                let d = pool.diff(x, s);
                if !pool.is_zero(d) {
                    jacobian.push((i, d));
                }
            }
            if jacobian.is_empty() {
                continue;
            }
            for (a, &(i, di)) in jacobian.iter().enumerate() {
                for &(j, dj) in &jacobian[a..] {
                    let (i, j, di, dj) = if i <= j { (i, j, di, dj) } else { (j, i, dj, di) };
                    let p = *products.entry((di, dj)).or_insert_with(|| pool.mul2(di, dj));
                    mass_parts[i][j].entry(p).or_default().push(term.mass);
                }
            }
            let velocity = pool.time_derivative(x);
            let a0 = acceleration_without_q2(pool, velocity);
            if pool.is_zero(a0) {
                continue;
            }
            for &(i, di) in &jacobian {
                force_parts[i].entry((di, term.mass)).or_default().push(a0);
            }
        }
    }
    let mut mass = vec![vec![pool.zero(); n]; n];
    for i in 0..n {
        for j in i..n {
            let parts: Vec<ExprId> = std::mem::take(&mut mass_parts[i][j])
                .into_iter()
                .map(|(p, masses)| {
                    let m = masses.sum(pool);
                    pool.mul2(p, m)
                })
                .collect();
            mass[i][j] = pool.add(&parts);
        }
    }
    let sums = chain_sums(pool, force_parts.iter().flat_map(|groups| groups.values()));
    let forcing = force_parts
        .into_iter()
        .map(|groups| {
            let parts: Vec<ExprId> = groups
                .into_iter()
                .map(|((d, m), accelerations)| {
                    let a = match sums.get(&accelerations) {
                        Some(sum) => pool.add_collected(sum),
                        None => pool.add(&accelerations),
                    };
                    let t = pool.mul(&[m, d, a]);
                    pool.neg(t)
                })
                .collect();
            pool.add(&parts)
        })
        .collect();
    (mass, forcing)
}

/// The sums of the lists of accelerations that are a chain's: each list but its first
/// acceleration another list (coordinate i's are the points' from link i down, i + 1's the
/// same but link i's), collected from that list's sum in one pass rather than term by term
/// (a 64-link chain's rows had added 87,000 terms one by one). Only lists whose every
/// acceleration collects without making a node ([`Pool::collected`]) are taken, so the pool
/// gets the same nodes in the same order as adding each list would give it.
fn chain_sums<'a>(
    pool: &Pool,
    lists: impl Iterator<Item = &'a Vec<ExprId>>,
) -> HashMap<Vec<ExprId>, cas::Collected> {
    let mut lists: Vec<&Vec<ExprId>> = lists.filter(|l| l.len() > 1).collect();
    lists.sort_by_key(|l| l.len());
    let mut sums: HashMap<Vec<ExprId>, cas::Collected> = HashMap::new();
    for list in lists {
        if sums.contains_key(list.as_slice()) {
            continue;
        }
        let sum = match sums.get(&list[1..]) {
            Some(rest) => pool.collected(list[0]).map(|first| first.plus(rest)),
            // The first of a chain's lists, or no chain's: collected as `add` would.
            None => pool.collected_all(list),
        };
        if let Some(sum) = sum {
            sums.insert(list.clone(), sum);
        }
    }
    sums
}

/// The masses (or a turning body's moments of inertia) that multiply one product in M, in runs
/// of equal ones.
#[derive(Clone, Default)]
struct Masses(Vec<(ExprId, i64)>);

impl Masses {
    fn push(&mut self, mass: ExprId) {
        match self.0.last_mut() {
            Some((last, count)) if *last == mass => *count += 1,
            _ => self.0.push((mass, 1)),
        }
    }

    /// Their sum: the node `add` of every mass written out gives.
    fn sum(&self, pool: &mut Pool) -> ExprId {
        let terms: Vec<(ExprId, cas::Rational)> =
            self.0.iter().map(|(m, count)| (*m, cas::number::int(*count))).collect();
        pool.add_scaled(&terms)
    }
}

/// The parts a body turning in space adds to M (Wᵢᵀ·I·Wⱼ, one product of entries of W per
/// nonzero entry of I) and to f (−Wᵢᵀ·(I·α₀ + ω × I·ω)), in the groupings of
/// [`structural_rows`].
fn turning_rows(
    pool: &mut Pool,
    turn: &Turning,
    coords: &[SymId],
    products: &mut HashMap<(ExprId, ExprId), ExprId>,
    mass_parts: &mut [Vec<BTreeMap<ExprId, Masses>>],
    force_parts: &mut [BTreeMap<(ExprId, ExprId), Vec<ExprId>>],
) {
    let Turning { inertia, omega, .. } = turn;
    // The partial angular velocities, of the rates ω moves with.
    let mut partial: Vec<(usize, [ExprId; 3])> = Vec::new();
    for (i, q) in coords.iter().enumerate() {
        let rate = pool.rate(*q).expect("coordinates have rates");
        let w = omega.map(|x| pool.diff(x, rate));
        if !w.iter().all(|x| pool.is_zero(*x)) {
            partial.push((i, w));
        }
    }
    if partial.is_empty() {
        return;
    }
    let nonzero: Vec<(usize, usize)> = (0..3)
        .flat_map(|a| (0..3).map(move |b| (a, b)))
        .filter(|&(a, b)| !pool.is_zero(inertia[a][b]))
        .collect();
    for (k, &(i, wi)) in partial.iter().enumerate() {
        for &(j, wj) in &partial[k..] {
            for &(a, b) in &nonzero {
                let (x, y) = (wi[a], wj[b]);
                if pool.is_zero(x) || pool.is_zero(y) {
                    continue;
                }
                let p = *products.entry((x, y)).or_insert_with(|| pool.mul2(x, y));
                mass_parts[i][j].entry(p).or_default().push(inertia[a][b]);
            }
        }
    }
    let rates = angular_momentum_rate(pool, inertia, omega);
    let one = pool.one();
    for (a, rate) in rates.into_iter().enumerate() {
        if pool.is_zero(rate) {
            continue;
        }
        for &(i, wi) in &partial {
            if !pool.is_zero(wi[a]) {
                force_parts[i].entry((wi[a], one)).or_default().push(rate);
            }
        }
    }
}

/// I·α₀ + ω × I·ω, the body-axes rate of a body's angular momentum with every q̈ set to zero
/// (ω in body axes, I constant): what its rows take from f.
pub(super) fn angular_momentum_rate(
    pool: &mut Pool,
    inertia: &[[ExprId; 3]; 3],
    omega: &[ExprId; 3],
) -> [ExprId; 3] {
    let alpha = omega.map(|x| acceleration_without_q2(pool, x));
    let times = |pool: &mut Pool, v: &[ExprId; 3]| -> [ExprId; 3] {
        [0, 1, 2].map(|a| {
            let parts: Vec<ExprId> = (0..3).map(|b| pool.mul2(inertia[a][b], v[b])).collect();
            pool.add(&parts)
        })
    };
    let momentum = times(pool, omega);
    let spun = times(pool, &alpha);
    [0, 1, 2].map(|a| {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let ahead = pool.mul2(omega[b], momentum[c]);
        let behind = pool.mul2(omega[c], momentum[b]);
        let gyroscopic = pool.sub(ahead, behind);
        pool.add2(spun[a], gyroscopic)
    })
}

/// d/dt of a velocity with every acceleration q̈ taken as zero: Σ ∂v/∂q·q̇ + ∂v/∂t.
pub(super) fn acceleration_without_q2(pool: &mut Pool, velocity: ExprId) -> ExprId {
    let mut parts = Vec::new();
    for &s in pool.free_symbols(velocity).iter() {
        let rate = match pool.symbol(s).kind {
            SymbolKind::Time => pool.one(),
            SymbolKind::Coordinate { order: 0, .. } => {
                let r = pool.rate(s).expect("coordinates have rates");
                pool.sym(r)
            }
            // q̇ → q̈ is the part that goes to M; parameters do not move.
            _ => continue,
        };
        let partial = pool.diff(velocity, s);
        parts.push(pool.mul2(partial, rate));
    }
    pool.add(&parts)
}

/// The expansion of the kinetic energy `kinetic` (in the remaining coordinates) by a shorter
/// route than multiplying out its squares: ½·Σ Mᵢⱼ·q̇ᵢ·q̇ⱼ from the structural M (`mass`, upper
/// triangle, raw), plus the expansion of the terms the structural route did not take
/// (`kinetic` less `structural_kinetic`). `None` when a position moves with time itself, or a
/// body turns in time itself (a driven frame), so that T has terms of first and zeroth degree
/// in the rates that M does not hold.
pub(super) fn kinetic_expansion(
    pool: &mut Pool,
    terms: &[InertialTerm],
    mass: &[Vec<ExprId>],
    rates: &[SymId],
    kinetic: ExprId,
    structural_kinetic: ExprId,
) -> Option<ExprId> {
    for term in terms {
        match term {
            InertialTerm::Moving(term) => {
                for &x in &term.position {
                    let time = pool
                        .free_symbols(x)
                        .iter()
                        .any(|s| pool.symbol(*s).kind == SymbolKind::Time);
                    if time {
                        return None;
                    }
                }
            }
            InertialTerm::Turning(turn) if turn.driven => return None,
            InertialTerm::Turning(_) => {}
        }
    }
    let half = cas::number::ratio(1, 2);
    let mut parts = Vec::new();
    for (i, row) in mass.iter().enumerate() {
        for (j, &entry) in row.iter().enumerate().skip(i) {
            if pool.is_zero(entry) {
                continue;
            }
            let entry = pool.expand(entry);
            let (qi, qj) = (pool.sym(rates[i]), pool.sym(rates[j]));
            let t = pool.mul(&[entry, qi, qj]);
            let t = if i == j { pool.scale(t, &half) } else { t };
            parts.push(pool.expand(t));
        }
    }
    let rest = pool.sub(kinetic, structural_kinetic);
    parts.push(pool.expand(rest));
    Some(pool.add(&parts))
}

#[cfg(test)]
mod tests {
    use super::super::eliminate::{eliminate_constraints, remaining_coordinates};
    use super::super::testing::scene;
    use super::*;

    /// The body of `equations`' test of the turning rows takes this route (else that test
    /// would compare differentiation with itself), driven only when its frame turns in time.
    #[test]
    fn a_body_with_constant_inertia_turns_on_the_structural_route() {
        for (orientation, driven) in
            [("rotz(a)*rotx(b)*roty(c)", false), ("rotz(w*t)*rotx(a)*rotz(b)*roty(c)", true)]
        {
            let source = format!(
                "param m, w, A, B, C, D\ncoord a\ncoord b\ncoord c\nbody top {{ mass m; inertia [A, 0, D; 0, B, 0; D, 0, C]; orientation {orientation}; position (0, 0, 0) }}"
            );
            let (mut pool, model) = scene(&source);
            let eliminated = eliminate_constraints(&mut pool, &model).eliminated;
            let coordinates = remaining_coordinates(&mut pool, &model, &eliminated);
            let (terms, _) = inertial_terms(
                &mut pool,
                &model,
                &coordinates.elimination_map,
                &coordinates.coords,
            );
            let turning: Vec<bool> = terms
                .iter()
                .filter_map(|t| match t {
                    InertialTerm::Turning(turn) => Some(turn.driven),
                    InertialTerm::Moving(_) => None,
                })
                .collect();
            assert_eq!(turning, [driven], "{orientation}");
        }
    }
}
