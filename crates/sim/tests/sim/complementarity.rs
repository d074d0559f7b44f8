//! The contact problems' solver on problems with known answers: one contact in closed form, a
//! chain of balls, a block landing flat on eight feet, a planar block's two gripping corners
//! (redundant rows), alone and among ten other contacts (past the enumeration limit), random
//! and degenerate positive semidefinite problems on which enumeration and Lemke's method must
//! agree, large ones built around a known solution, and inconsistent and malformed input.

use nalgebra::DMatrix;
use sim::complementarity::{self, Inconsistent, Row, Solution, Unsolved, ENUMERATION_LIMIT};

/// The tolerance the callers pass: 1e-10 of the scale of c.
fn tolerance(c: &[f64]) -> f64 {
    1e-10 * c.iter().fold(1.0f64, |m, v| m.max(v.abs()))
}

/// W·M⁻¹·Wᵀ for a diagonal M.
fn delassus(w: &DMatrix<f64>, mass: &[f64]) -> DMatrix<f64> {
    let inverse =
        DMatrix::from_fn(mass.len(), mass.len(), |i, j| if i == j { 1.0 / mass[i] } else { 0.0 });
    w * inverse * w.transpose()
}

/// W·v.
fn rates(w: &DMatrix<f64>, v: &[f64]) -> Vec<f64> {
    (0..w.nrows()).map(|i| (0..v.len()).map(|j| w[(i, j)] * v[j]).sum()).collect()
}

/// Asserts the conditions of a problem of normal rows, to `tol`, and that w = A·x + c.
fn assert_complementary(a: &DMatrix<f64>, c: &[f64], s: &Solution, tol: f64) {
    for i in 0..c.len() {
        let w: f64 = c[i] + (0..c.len()).map(|j| a[(i, j)] * s.x[j]).sum::<f64>();
        assert!((w - s.w[i]).abs() <= tol, "row {i}: w = {} but A·x + c = {w}", s.w[i]);
        assert!(s.x[i] >= -tol && s.w[i] >= -tol, "row {i}: x = {}, w = {}", s.x[i], s.w[i]);
        assert!(s.x[i].min(s.w[i]) <= tol, "row {i}: x = {} and w = {}", s.x[i], s.w[i]);
    }
}

fn assert_close(got: &[f64], want: &[f64], within: f64) {
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() <= within, "entry {i}: {g} against {w} (all: {got:?})");
    }
}

#[test]
fn one_contact_is_the_closed_form() {
    let mut answered = 0;
    for a in [0.5, 1.0, 4.0] {
        for c in [-3.0, -1e-3, 0.0, 2.5] {
            let matrix = DMatrix::from_element(1, 1, a);
            let tol = tolerance(&[c]);
            let x = f64::max(0.0, -c / a);
            for s in [
                complementarity::solve(&matrix, &[c], &[Row::Normal], tol),
                complementarity::enumerate(&matrix, &[c], &[Row::Normal], tol),
                complementarity::lemke(&matrix, &[c], tol),
            ] {
                let s = s.expect("one contact with a > 0 always has a solution");
                assert_close(&s.x, &[x], 1e-14);
                assert_close(&s.w, &[a * x + c], 1e-14);
                // A row with c = 0 needs no x and has w = 0: it is reported active.
                assert_eq!(s.active, vec![c <= 0.0]);
                answered += 1;
            }
        }
    }
    assert_eq!(answered, 36);
}

#[test]
fn one_contact_without_mass_pushes_nothing() {
    let zero = DMatrix::zeros(1, 1);
    for c in [0.0, 1.5] {
        let s =
            complementarity::solve(&zero, &[c], &[Row::Normal], 1e-10).expect("c ≥ 0 needs no x");
        assert_eq!((s.x, s.w), (vec![0.0], vec![c]));
    }
    let expected = Err(Unsolved::Inconsistent(Inconsistent { rows: vec![0] }));
    assert_eq!(complementarity::solve(&zero, &[-1.0], &[Row::Normal], 1e-10), expected);
    assert_eq!(complementarity::lemke(&zero, &[-1.0], 1e-10), expected);
}

/// A chain of `balls` unit balls, the first moving at `speed` into the rest at rest: the
/// impact problem of its contacts (gap rate v_{j+1} − v_j) under Newton's law with `e`.
fn cradle(balls: usize, speed: f64, e: f64) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>, Vec<f64>) {
    let contacts = balls - 1;
    let w = DMatrix::from_fn(contacts, balls, |j, i| {
        if i == j + 1 {
            1.0
        } else if i == j {
            -1.0
        } else {
            0.0
        }
    });
    let mut v = vec![0.0; balls];
    v[0] = speed;
    let a = delassus(&w, &vec![1.0; balls]);
    let c = rates(&w, &v).iter().map(|g| (1.0 + e) * g).collect();
    (a, c, w, v)
}

#[test]
fn cradle_chain_agrees_between_enumeration_and_lemke() {
    for (balls, e) in [(2, 1.0), (3, 1.0), (5, 1.0), (5, 0.0), (8, 0.5), (11, 1.0)] {
        let (a, c, w, v) = cradle(balls, 2.0, e);
        let tol = tolerance(&c);
        let by_enumeration = complementarity::enumerate(&a, &c, &vec![Row::Normal; c.len()], tol)
            .expect("a chain of balls has a solution");
        let by_lemke =
            complementarity::lemke(&a, &c, tol).expect("a chain of balls has a solution");
        assert_complementary(&a, &c, &by_enumeration, tol);
        assert_complementary(&a, &c, &by_lemke, tol);
        // A has full rank: the solution is unique, x as well as w.
        assert_close(&by_lemke.x, &by_enumeration.x, 1e-12);
        assert_close(&by_lemke.w, &by_enumeration.w, 1e-12);
        // Momentum is kept: the impulses only pass it along the chain.
        let impulses = w.transpose() * nalgebra::DVector::from_column_slice(&by_lemke.x);
        let momentum: f64 = (0..balls).map(|i| v[i] + impulses[i]).sum();
        assert!((momentum - 2.0).abs() < 1e-12, "momentum {momentum}");
    }
    // Two balls, e = 1: the impulse is (1 + e)·m_r·speed with reduced mass 1/2, and they swap.
    let (a, c, _, _) = cradle(2, 2.0, 1.0);
    let s = complementarity::solve(&a, &c, &[Row::Normal], tolerance(&c)).expect("solvable");
    assert_close(&s.x, &[2.0], 1e-14);
    // Three balls, e = 1: both contacts active, with A = [[2, −1], [−1, 2]] and c = (−4, 0):
    // x = (8/3, 4/3), and the balls leave at (−2/3, 4/3, 4/3), whose squares sum to 2², as the
    // speeds' did before: (4 + 16 + 16)/9 = 4.
    let (a, c, _, _) = cradle(3, 2.0, 1.0);
    let s = complementarity::solve(&a, &c, &[Row::Normal; 2], tolerance(&c)).expect("solvable");
    assert_close(&s.x, &[8.0 / 3.0, 4.0 / 3.0], 1e-14);
    assert_close(&s.w, &[0.0, 0.0], 1e-14);
}

/// A block (half-sides 1, 0.6, 0.4, mass 2) on eight feet, its four bottom corners and the
/// middles of its four bottom edges, landing with velocity `v` = (v, ω) under Newton's law with
/// `e`: each foot's normal rate is v_z + ω_x·y − ω_y·x. The Delassus operator has rank 3.
fn block_on_eight_feet(v: [f64; 6], e: f64) -> (DMatrix<f64>, Vec<f64>) {
    let (a, b, h, m) = (1.0, 0.6, 0.4, 2.0);
    let feet = [(-a, -b), (0.0, -b), (a, -b), (a, 0.0), (a, b), (0.0, b), (-a, b), (-a, 0.0)];
    let w = DMatrix::from_fn(8, 6, |i, j| {
        let (x, y) = feet[i];
        [0.0, 0.0, 1.0, y, -x, 0.0][j]
    });
    // The inertia of a solid box about its centre.
    let inertia = [m * (b * b + h * h) / 3.0, m * (a * a + h * h) / 3.0, m * (a * a + b * b) / 3.0];
    let mass = [m, m, m, inertia[0], inertia[1], inertia[2]];
    let c = rates(&w, &v).iter().map(|g| (1.0 + e) * g).collect();
    (delassus(&w, &mass), c)
}

#[test]
fn block_landing_flat_on_eight_feet() {
    // Sliding and spinning about the vertical, falling at 3: every foot closes at 3.
    let v = [0.3, -0.1, -3.0, 0.0, 0.0, 0.7];
    for e in [0.0, 0.5] {
        let (a, c) = block_on_eight_feet(v, e);
        let tol = tolerance(&c);
        let s = complementarity::lemke(&a, &c, tol).expect("a landing has a solution");
        assert_complementary(&a, &c, &s, tol);
        // After the impact every foot rises at e·3 (γ⁺ = w − e·γ⁻), all eight active.
        let after: Vec<f64> = (0..8).map(|i| s.w[i] - e * c[i] / (1.0 + e)).collect();
        assert_close(&after, &[3.0 * e; 8], 1e-9);
        assert_eq!(s.active, vec![true; 8]);
        // The least-norm impulse shares the momentum m·(1 + e)·3 evenly between the feet.
        assert_close(&s.x, &[2.0 * (1.0 + e) * 3.0 / 8.0; 8], 1e-9);
        // Enumeration finds a pair of opposite feet first, then widens to the same answer.
        let by_enumeration =
            complementarity::enumerate(&a, &c, &[Row::Normal; 8], tol).expect("solvable");
        assert_close(&by_enumeration.x, &s.x, 1e-9);
        assert_close(&by_enumeration.w, &s.w, 1e-9);
    }
    // Landing tilted (rolling about x as it falls slowly): the feet at y = −0.6 close, those at
    // y = 0.6 open, and the two methods agree.
    let (a, c) = block_on_eight_feet([0.0, 0.0, -0.2, 2.0, 0.1, 0.0], 0.0);
    let tol = tolerance(&c);
    let by_lemke = complementarity::lemke(&a, &c, tol).expect("solvable");
    let by_enumeration =
        complementarity::enumerate(&a, &c, &[Row::Normal; 8], tol).expect("solvable");
    assert_complementary(&a, &c, &by_lemke, tol);
    assert_complementary(&a, &c, &by_enumeration, tol);
    assert_close(&by_lemke.w, &by_enumeration.w, 1e-9);
    assert_close(&by_lemke.x, &by_enumeration.x, 1e-9);
    assert!(by_lemke.active.iter().any(|&a| !a), "a tilted landing lifts some feet: {by_lemke:?}");
}

/// A linear congruential generator (Knuth's MMIX constants), for deterministic random problems
/// without a dependency.
struct Lcg(u64);

impl Lcg {
    /// Uniform in [−1, 1).
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// Uniform in lo..=hi.
    fn between(&mut self, lo: usize, hi: usize) -> usize {
        let span = (hi - lo + 1) as f64;
        lo + (((self.next() + 1.0) / 2.0 * span) as usize).min(hi - lo)
    }
}

#[test]
fn random_semidefinite_problems_agree_between_enumeration_and_lemke() {
    let mut random = Lcg(20261128);
    let (mut solved, mut inconsistent) = (0, 0);
    for _ in 0..60 {
        let n = random.between(2, 9);
        // B·Bᵀ with B n×r: positive semidefinite of rank r, often singular.
        let r = random.between(1, n);
        let b = DMatrix::from_fn(n, r, |_, _| random.next());
        let a = &b * b.transpose();
        let c: Vec<f64> = (0..n).map(|_| random.next()).collect();
        let tol = tolerance(&c);
        let by_lemke = complementarity::lemke(&a, &c, tol);
        let by_enumeration = complementarity::enumerate(&a, &c, &vec![Row::Normal; n], tol);
        match (by_lemke, by_enumeration) {
            (Ok(l), Ok(e)) => {
                assert_complementary(&a, &c, &l, 1e-9);
                assert_complementary(&a, &c, &e, 1e-9);
                assert_close(&l.w, &e.w, 1e-9);
                // Both answers are the least-norm x of all solutions.
                assert_close(&l.x, &e.x, 1e-9);
                solved += 1;
            }
            (Err(Unsolved::Inconsistent(l)), Err(Unsolved::Inconsistent(e))) => {
                assert_eq!(l, e);
                inconsistent += 1;
            }
            (l, e) => panic!("n = {n}, rank {r}: Lemke {l:?}, enumeration {e:?}"),
        }
    }
    assert!(solved >= 10 && inconsistent >= 1, "{solved} solved, {inconsistent} inconsistent");
}

#[test]
fn degenerate_integer_problems_agree_between_enumeration_and_lemke() {
    // Entries of B in {−1, 0, 1} and c in {−2, …, 2}: ties in every ratio test, repeated and
    // zero rows, many solutions x for one w. Both methods must give the least-norm one.
    let mut random = Lcg(99);
    let (mut solved, mut inconsistent) = (0, 0);
    for _ in 0..300 {
        let n = random.between(2, 10);
        let r = random.between(1, n);
        let b = DMatrix::from_fn(n, r, |_, _| random.between(0, 2) as f64 - 1.0);
        let a = &b * b.transpose();
        let c: Vec<f64> = (0..n).map(|_| random.between(0, 4) as f64 - 2.0).collect();
        let tol = tolerance(&c);
        let by_lemke = complementarity::lemke(&a, &c, tol);
        let by_enumeration = complementarity::enumerate(&a, &c, &vec![Row::Normal; n], tol);
        match (by_lemke, by_enumeration) {
            (Ok(l), Ok(e)) => {
                assert_complementary(&a, &c, &l, 1e-9);
                assert_close(&l.w, &e.w, 1e-9);
                assert_close(&l.x, &e.x, 1e-9);
                solved += 1;
            }
            (Err(Unsolved::Inconsistent(l)), Err(Unsolved::Inconsistent(e))) => {
                assert_eq!(l, e);
                inconsistent += 1;
            }
            (l, e) => panic!("{a} c = {c:?}: Lemke {l:?}, enumeration {e:?}"),
        }
    }
    assert!(solved >= 100 && inconsistent >= 50, "{solved} solved, {inconsistent} inconsistent");
}

#[test]
fn lemke_finds_planted_solutions_of_large_problems() {
    // Problems of 11 to 40 rows built around a solution: x* ≥ 0 and w* ≥ 0 complementary,
    // some rows with both zero (degenerate), c = w* − A·x*. A positive semidefinite LCP's w is
    // unique, so Lemke's must be w*.
    let mut random = Lcg(1843);
    for trial in 0..30 {
        let n = random.between(11, 40);
        let r = if trial % 3 == 0 { n } else { random.between(n / 3, n) };
        let b = DMatrix::from_fn(n, r, |_, _| random.next());
        let a = &b * b.transpose();
        let mut x = vec![0.0; n];
        let mut w = vec![0.0; n];
        for i in 0..n {
            match random.between(0, 2) {
                0 => x[i] = 1.0 + random.next(),
                1 => w[i] = 1.0 + random.next(),
                _ => {}
            }
        }
        let c: Vec<f64> =
            (0..n).map(|i| w[i] - (0..n).map(|j| a[(i, j)] * x[j]).sum::<f64>()).collect();
        let tol = tolerance(&c);
        let s = complementarity::solve(&a, &c, &vec![Row::Normal; n], tol)
            .unwrap_or_else(|e| panic!("trial {trial}, n = {n}, rank {r}: {e:?}"));
        assert_complementary(&a, &c, &s, 1e-8);
        assert_close(&s.w, &w, 1e-11);
    }
}

/// A planar block (half-width 1, half-height 1/2, mass 2, inertia 1) landing flat on two
/// gripping corners with velocity (v_x, v_y, ω): rows normal, tangent, normal, tangent, on 3
/// degrees of freedom. A corner at (x, −h) has normal rate v_y + ω·x and tangential rate
/// v_x + ω·h.
fn gripping_block(v: [f64; 3]) -> (DMatrix<f64>, Vec<f64>, Vec<Row>) {
    let (b, h) = (1.0, 0.5);
    let w = DMatrix::from_row_slice(4, 3, &[0.0, 1.0, -b, 1.0, 0.0, h, 0.0, 1.0, b, 1.0, 0.0, h]);
    let rows =
        vec![Row::Normal, Row::Tangent { normal: 0 }, Row::Normal, Row::Tangent { normal: 2 }];
    (delassus(&w, &[2.0, 2.0, 1.0]), rates(&w, &v), rows)
}

#[test]
fn gripping_corners_on_redundant_rows() {
    // Falling at 1 and sliding at 1/2, plastic: the block stops. Its momentum (1, −2) is taken
    // by the impulses, the normal ones split by the moment b·(N₁ − N₀) + h·(T₀ + T₁) = 0, and
    // the tangent ones, redundant, evenly (least norm).
    let (a, c, rows) = gripping_block([0.5, -1.0, 0.0]);
    let tol = tolerance(&c);
    let s = complementarity::solve(&a, &c, &rows, tol).expect("a gripping landing has a solution");
    assert_close(&s.w, &[0.0; 4], 1e-12);
    assert_close(&s.x, &[0.75, -0.5, 1.25, -0.5], 1e-12);
    assert_eq!(s.active, vec![true; 4]);

    // Rocking onto the left corner (ω > 0 lifts the right one): the right corner separates
    // and carries no tangential impulse, the left one grips. Angular momentum about the left
    // corner is kept: with the corner at r = (−1, −1/2) from the centre, the centre is at −r
    // from the corner, and I·ω⁺ − m·(r × v⁺) = I·ω⁻ − m·(r × v⁻), in planar cross products
    // r × v = r_x·v_y − r_y·v_x.
    let v = [0.0, -0.2, 1.0];
    let (a, c, rows) = gripping_block(v);
    let s = complementarity::solve(&a, &c, &rows, tolerance(&c)).expect("solvable");
    assert_eq!(s.active, vec![true, true, false, false]);
    assert_eq!(&s.x[2..], &[0.0, 0.0]);
    assert!(s.w[2] > 0.0 && s.x[0] > 0.0, "{s:?}");
    let (r, m, inertia) = ([-1.0, -0.5], 2.0, 1.0);
    let cross = |v: [f64; 2]| r[0] * v[1] - r[1] * v[0];
    let before = inertia * v[2] - m * cross([v[0], v[1]]);
    // v⁺ = v⁻ + M⁻¹·Wᵀ·x, with W's rows as in gripping_block.
    let (n, t) = (s.x[0], s.x[1]);
    let after_v = [v[0] + t / m, v[1] + n / m];
    let after_omega = v[2] + (-n + 0.5 * t) / inertia;
    let after = inertia * after_omega - m * cross(after_v);
    assert!((after - before).abs() < 1e-12, "angular momentum {before} → {after}");
    // The gripping corner stops: both its rates are 0.
    assert_close(&s.w[..2], &[0.0, 0.0], 1e-12);
}

/// Asserts the conditions of a mixed problem, to `tol`, and that w = A·x + c.
fn assert_conditions(a: &DMatrix<f64>, c: &[f64], rows: &[Row], s: &Solution, tol: f64) {
    for i in 0..c.len() {
        let w: f64 = c[i] + (0..c.len()).map(|j| a[(i, j)] * s.x[j]).sum::<f64>();
        assert!((w - s.w[i]).abs() <= tol, "row {i}: w = {} but A·x + c = {w}", s.w[i]);
        match rows[i] {
            Row::Normal if s.active[i] => {
                assert!(s.x[i] >= -tol && s.w[i].abs() <= tol, "{i}: {s:?}")
            }
            Row::Normal => assert!(s.x[i] == 0.0 && s.w[i] >= -tol, "{i}: {s:?}"),
            Row::Tangent { normal } => {
                assert_eq!(s.active[i], s.active[normal]);
                if s.active[i] {
                    assert!(s.w[i].abs() <= tol, "{i}: {s:?}");
                } else {
                    assert!(s.x[i] == 0.0, "{i}: {s:?}");
                }
            }
        }
    }
}

/// The gripping block beside `others` independent frictionless contacts of unit mass (A's
/// identity block), closing at 1 + o/10 or opening at 1/2 in turn.
fn gripping_block_among_others(v: [f64; 3], others: usize) -> (DMatrix<f64>, Vec<f64>, Vec<Row>) {
    let (block, mut c, mut rows) = gripping_block(v);
    let k = 4 + others;
    let a = DMatrix::from_fn(k, k, |i, j| {
        if i < 4 && j < 4 {
            block[(i, j)]
        } else if i == j {
            1.0
        } else {
            0.0
        }
    });
    c.extend((0..others).map(|o| if o % 2 == 0 { -1.0 - o as f64 / 10.0 } else { 0.5 }));
    rows.resize(k, Row::Normal);
    (a, c, rows)
}

#[test]
fn gripping_contacts_past_the_enumeration_limit() {
    // Two gripping corners and ten other contacts: twelve normal rows, so solve pivots, with
    // the gripping contacts' active sets enumerated. Enumeration over all twelve agrees.
    for v in [[0.5, -1.0, 0.0], [0.0, -0.2, 1.0], [0.3, 0.4, 0.0]] {
        let (a, c, rows) = gripping_block_among_others(v, 10);
        let tol = tolerance(&c);
        let pivoted = complementarity::solve(&a, &c, &rows, tol).expect("solvable");
        let by_grips = complementarity::lemke_with_grips(&a, &c, &rows, tol).expect("solvable");
        let enumerated = complementarity::enumerate(&a, &c, &rows, tol).expect("solvable");
        assert_eq!(pivoted, by_grips);
        assert_conditions(&a, &c, &rows, &pivoted, tol);
        assert_close(&pivoted.x, &enumerated.x, 1e-12);
        assert_close(&pivoted.w, &enumerated.w, 1e-12);
        assert_eq!(pivoted.active, enumerated.active);
        // The other contacts: those closing at 1 + o/10 take that impulse, the others none.
        for o in 0..10 {
            let x = if o % 2 == 0 { 1.0 + o as f64 / 10.0 } else { 0.0 };
            assert!((pivoted.x[4 + o] - x).abs() < 1e-12, "{pivoted:?}");
        }
    }
    // Eleven gripping contacts are more than the enumeration takes.
    let k = 22;
    let a = DMatrix::identity(k, k);
    let rows: Vec<Row> = (0..k)
        .map(|i| if i % 2 == 0 { Row::Normal } else { Row::Tangent { normal: i - 1 } })
        .collect();
    assert_eq!(
        complementarity::solve(&a, &vec![-1.0; k], &rows, 1e-10),
        Err(Unsolved::TooLarge { normals: 11 })
    );
}

#[test]
fn random_gripping_problems_are_solved_alike_by_both_searches() {
    // With tangent rows the problem is no LCP and its w need not be unique, so the two searches
    // (fewest rows active; fewest gripping contacts active, Lemke for the rest) may pick
    // different solutions; both must be valid, and they must agree on whether one exists.
    let mut random = Lcg(7);
    let (mut solved, mut inconsistent) = (0, 0);
    for _ in 0..60 {
        let normals = random.between(1, 5);
        let tangents = random.between(1, 4);
        let n = normals + tangents;
        let r = random.between(1, n);
        let b = DMatrix::from_fn(n, r, |_, _| random.next());
        let a = &b * b.transpose();
        let c: Vec<f64> = (0..n).map(|_| random.next()).collect();
        let rows: Vec<Row> = (0..n)
            .map(|i| {
                if i < normals {
                    Row::Normal
                } else {
                    Row::Tangent { normal: random.between(0, normals - 1) }
                }
            })
            .collect();
        let tol = tolerance(&c);
        let by_grips = complementarity::lemke_with_grips(&a, &c, &rows, tol);
        let enumerated = complementarity::enumerate(&a, &c, &rows, tol);
        match (by_grips, enumerated) {
            (Ok(g), Ok(e)) => {
                assert_conditions(&a, &c, &rows, &g, 1e-9);
                assert_conditions(&a, &c, &rows, &e, 1e-9);
                solved += 1;
            }
            (Err(Unsolved::Inconsistent(_)), Err(Unsolved::Inconsistent(_))) => inconsistent += 1,
            (g, e) => panic!("{rows:?}, rank {r}: by grips {g:?}, enumeration {e:?}"),
        }
    }
    assert!(solved >= 10 && inconsistent >= 1, "{solved} solved, {inconsistent} inconsistent");
}

#[test]
fn duplicated_contacts_share_the_impulse() {
    // Two (or twelve) identical rows: any split is valid; the least-norm one is even, from both
    // methods, however degenerate Lemke's ratio tests are.
    for n in [2, 12] {
        let a = DMatrix::from_element(n, n, 1.0);
        let c = vec![-1.0; n];
        let tol = tolerance(&c);
        let by_lemke = complementarity::lemke(&a, &c, tol).expect("solvable");
        let by_enumeration =
            complementarity::enumerate(&a, &c, &vec![Row::Normal; n], tol).expect("solvable");
        for s in [by_lemke, by_enumeration] {
            assert_close(&s.x, &vec![1.0 / n as f64; n], 1e-12);
            assert_close(&s.w, &vec![0.0; n], 1e-12);
        }
    }
}

#[test]
fn inconsistent_problems_name_their_rows() {
    // A particle between two walls that both close on it: no impulse opens both, as
    // w₀ + w₁ = c₀ + c₁ < 0 whatever x is.
    let a = DMatrix::from_row_slice(2, 2, &[1.0, -1.0, -1.0, 1.0]);
    let expected = Err(Unsolved::Inconsistent(Inconsistent { rows: vec![0, 1] }));
    assert_eq!(complementarity::solve(&a, &[-1.0, -1.0], &[Row::Normal; 2], 1e-10), expected);
    assert_eq!(complementarity::lemke(&a, &[-1.0, -1.0], 1e-10), expected);
    // One wall closing, the other opening faster: x₁ = 1 opens both.
    let s = complementarity::solve(&a, &[-1.0, 2.0], &[Row::Normal; 2], 1e-10).expect("solvable");
    assert_close(&s.x, &[1.0, 0.0], 1e-14);

    // The same pair among twelve independent contacts, past the enumeration limit: Lemke's
    // secondary ray, and the pair named.
    let n = 12;
    assert!(n > ENUMERATION_LIMIT);
    let mut big = DMatrix::identity(n, n);
    let (p, q) = (3, 7);
    big[(p, q)] = -1.0;
    big[(q, p)] = -1.0;
    let mut c = vec![-0.5; n];
    c[p] = -1.0;
    c[q] = -1.0;
    let expected = Err(Unsolved::Inconsistent(Inconsistent { rows: vec![p, q] }));
    assert_eq!(complementarity::solve(&big, &c, &vec![Row::Normal; n], 1e-10), expected);
    // Opened, the pair's problem is solvable, and the rest push at 1/2.
    c[q] = 2.0;
    let s = complementarity::solve(&big, &c, &vec![Row::Normal; n], 1e-10).expect("solvable");
    assert_complementary(&big, &c, &s, 1e-10);
    assert!((s.x[0] - 0.5).abs() < 1e-12 && (s.x[p] - 1.0).abs() < 1e-12 && s.x[q] == 0.0);

    // A gripping corner that would have to slide: a block whose tangent row moves with no
    // inertia to resist (A's tangent entry 0, c_T ≠ 0) cannot grip, and cannot stay open.
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
    let rows = [Row::Normal, Row::Tangent { normal: 0 }];
    let expected = Err(Unsolved::Inconsistent(Inconsistent { rows: vec![0, 1] }));
    assert_eq!(complementarity::solve(&a, &[-1.0, 0.5], &rows, 1e-10), expected);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let a = DMatrix::identity(2, 2);
    let normal = [Row::Normal; 2];
    assert_eq!(
        complementarity::solve(&a, &[f64::NAN, -1.0], &normal, 1e-10),
        Err(Unsolved::NonFinite { rows: vec![0] })
    );
    let mut infinite = a.clone();
    infinite[(1, 0)] = f64::INFINITY;
    assert_eq!(
        complementarity::lemke(&infinite, &[-1.0, -1.0], 1e-10),
        Err(Unsolved::NonFinite { rows: vec![1] })
    );
    assert_eq!(
        complementarity::solve(&a, &[-1.0, -1.0], &normal, f64::NAN),
        Err(Unsolved::NonFinite { rows: vec![] })
    );
    assert!(matches!(
        complementarity::solve(&a, &[-1.0], &normal, 1e-10),
        Err(Unsolved::Malformed { .. })
    ));
    assert!(matches!(
        complementarity::solve(
            &a,
            &[-1.0, -1.0],
            &[Row::Normal, Row::Tangent { normal: 1 }],
            1e-10
        ),
        Err(Unsolved::Malformed { .. })
    ));
    assert!(matches!(
        complementarity::solve(&a, &[-1.0, -1.0], &normal, -1.0),
        Err(Unsolved::Malformed { .. })
    ));
    // Nothing to solve.
    let empty = complementarity::solve(&DMatrix::zeros(0, 0), &[], &[], 1e-10).expect("empty");
    assert!(empty.x.is_empty() && empty.w.is_empty() && empty.active.is_empty());
}
