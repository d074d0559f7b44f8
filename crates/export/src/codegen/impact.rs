//! The impact map of a scene with contacts, as the generated code solves it: the contacts
//! flagged touching pose one complementarity problem with the two-sided constraints condensed
//! out, as `sim`'s run poses it (`crates/sim/src/mechanical/modes.rs`), and a solver written
//! out in each language (no dependency: the C needs only libm) enumerates its active sets.
//!
//! The problem: W the touching contacts' rows (each normal, then its grip), S the mass block
//! of the inverse of the augmented system [M −J_Eᵀ; J_E 0] of the two-sided rows, A = W·S·Wᵀ,
//! c = (1 + e)·γ⁻ per normal row and the tangential rate per grip row. Λ ≥ 0, w = A·Λ + c ≥ 0
//! and Λ·w = 0 per normal row; a grip row has w = 0 while its contact is active, Λ = 0
//! otherwise. Then q̇⁺ = q̇⁻ + S·WᵀΛ, the two-sided rows' impulses with it.
//!
//! The solver: the active sets of the normal rows, fewest first (then by increasing bit
//! mask), each solved least-norm: the set's block of A (symmetric positive semidefinite, and
//! singular where rows are redundant, as a block's two gripping corners resting flat are four
//! rows on three degrees of freedom) is diagonalised by cyclic Jacobi rotations, eigenvalues
//! below 1e-10 of the largest count as zero, and the least-norm x = Σ vᵢ·(vᵢ·b)/λᵢ over the
//! rest is a least-squares solution that is exact where the set's equations are consistent.
//! The first set whose x and w hold the conditions to 1e-10 of the largest |c| (x in the
//! units of w through A's diagonal) is the answer.

/// The status codes of the generated `impact`, as the C returns them (and the Rust module's
/// `ImpactStatus` names them).
pub const SOLVED: i32 = 0;
/// The augmented system of the two-sided constraints is singular.
pub const SINGULAR: i32 = 1;
/// No active set satisfies the conditions: the problem has no solution (or none the solver
/// finds to its tolerance).
pub const NO_SOLUTION: i32 = 2;
/// More than [`MOST_NORMALS`] contacts touch.
pub const TOO_MANY: i32 = 3;

/// The most touching contacts whose 2^k active sets the generated solver enumerates.
pub const MOST_NORMALS: usize = 20;

/// The contract of `impact`, for the generated comments (ASCII, one sentence a line).
pub fn contract(status: &[(&str, i32)]) -> String {
    let codes: Vec<String> =
        status.iter().map(|(what, code)| format!("\n  {code} {what}")).collect();
    format!(
        "The impact map: the rates after an impact at the contacts flagged touching, as\n\
         lagrange simulate's run solves it. W are the touching contacts' rows (each normal,\n\
         then its grip), S the mass block of the inverse of [M -J_E^T; J_E 0] over the\n\
         two-sided rows J_E, A = W S W^T, c = (1 + e) gamma_minus per normal row (gamma = J qd +\n\
         dg/dt, e the contact's restitution) and the tangential rate per grip row.\n\
         It finds impulses L with L >= 0, w = A L + c >= 0, L w = 0 per normal row, and per grip\n\
         row w = 0 while its contact is active (L = 0 otherwise); then\n\
         qd_plus = qd_minus + S W^T L.\n\
         impulses gets one value per multiplier slot, as the constraints lay them out: L at\n\
         the touching contacts' rows, 0 at the others, the two-sided rows' impulses at theirs.\n\
         The active sets of the normal rows are enumerated, fewest first, each solved least-norm\n\
         (a Jacobi eigendecomposition of its block of A; eigenvalues below 1e-10 of the largest\n\
         count as zero, so redundant rows are fine), and the first that holds the conditions to\n\
         1e-10 of the largest |c| is taken. A touching contact that is not approaching gets no\n\
         impulse unless another's impact pushes it; pass touching only where the gap is about 0.\n\
         Where the run holds a contact that was resting it takes e = 0; a resting contact has\n\
         gamma_minus about 0, so (1 + e) gamma_minus is about 0 either way.\n\
         On failure qd_plus and impulses are left as they were. Returns:{}",
        codes.concat()
    )
}

/// The C solver of the impact problem: `symmetric_eigen`, `least_norm` and `complementarity`,
/// with arrays of `rows` (the most rows a problem of the scene has).
pub fn c_solver(rows: usize) -> String {
    C_SOLVER.replace("ROWS", &rows.max(1).to_string())
}

/// The Rust solver, the same operations as [`c_solver`].
pub const RUST_SOLVER: &str = r#"/// Diagonalises the symmetric k×k matrix `a` (row-major) by cyclic Jacobi rotations: its
/// diagonal ends as the eigenvalues, the columns of `v` as the eigenvectors.
fn symmetric_eigen(k: usize, a: &mut [f64], v: &mut [f64]) {
    for i in 0..k {
        for j in 0..k {
            v[i * k + j] = if i == j { 1.0 } else { 0.0 };
        }
    }
    for _ in 0..100 {
        let mut off = 0.0;
        let mut diagonal = 0.0;
        for i in 0..k {
            diagonal += a[i * k + i] * a[i * k + i];
            for j in i + 1..k {
                off += a[i * k + j] * a[i * k + j];
            }
        }
        if off <= 1e-36 * diagonal || off == 0.0 {
            return;
        }
        for p in 0..k {
            for q in p + 1..k {
                let apq = a[p * k + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * k + q] - a[p * k + p]) / (2.0 * apq);
                let t = if theta.abs() > 1e150 {
                    0.5 / theta
                } else {
                    let t = 1.0 / (theta.abs() + (theta * theta + 1.0).sqrt());
                    if theta < 0.0 { -t } else { t }
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for r in 0..k {
                    let (arp, arq) = (a[r * k + p], a[r * k + q]);
                    a[r * k + p] = c * arp - s * arq;
                    a[r * k + q] = s * arp + c * arq;
                }
                for r in 0..k {
                    let (apr, aqr) = (a[p * k + r], a[q * k + r]);
                    a[p * k + r] = c * apr - s * aqr;
                    a[q * k + r] = s * apr + c * aqr;
                }
                for r in 0..k {
                    let (vrp, vrq) = (v[r * k + p], v[r * k + q]);
                    v[r * k + p] = c * vrp - s * vrq;
                    v[r * k + q] = s * vrp + c * vrq;
                }
            }
        }
    }
}

/// The least-norm least-squares x of a·x = b for the symmetric positive semidefinite k×k
/// `a` (destroyed): eigenvalues below 1e-10 of the largest count as zero.
fn least_norm(k: usize, a: &mut [f64], b: &[f64], x: &mut [f64]) {
    let mut v = vec![0.0; k * k];
    symmetric_eigen(k, a, &mut v);
    let largest = (0..k).fold(0.0_f64, |m, i| m.max(a[i * k + i].abs()));
    x[..k].fill(0.0);
    for l in 0..k {
        let lambda = a[l * k + l];
        if lambda <= 1e-10 * largest || lambda <= 0.0 {
            continue;
        }
        let along = (0..k).map(|i| v[i * k + l] * b[i]).sum::<f64>() / lambda;
        for i in 0..k {
            x[i] += v[i * k + l] * along;
        }
    }
}

/// Solves w = a·x + c (a row-major r×r, symmetric positive semidefinite) with x ≥ 0, w ≥ 0,
/// x·w = 0 at the normal rows (`normal_of[i] == i`) and, at a grip row (`normal_of[i]` its
/// contact's normal row), w = 0 while that row is active and x = 0 otherwise: the active sets
/// of the normal rows fewest first, each solved least-norm. Returns `SOLVED`, `NO_SOLUTION` or
/// `TOO_MANY` (as i32).
fn complementarity(r: usize, a: &[f64], c: &[f64], normal_of: &[usize], x: &mut [f64]) -> i32 {
    let normals: Vec<usize> = (0..r).filter(|&i| normal_of[i] == i).collect();
    let count = normals.len();
    if count > MOST_NORMALS {
        return 3;
    }
    let scale = c[..r].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let tol = 1e-10 * scale;
    let mut active = vec![false; r];
    for size in 0..=count {
        for mask in 0u64..1u64 << count {
            if mask.count_ones() as usize != size {
                continue;
            }
            active.fill(false);
            for (j, &i) in normals.iter().enumerate() {
                active[i] = mask >> j & 1 == 1;
            }
            let rows: Vec<usize> = (0..r).filter(|&i| active[normal_of[i]]).collect();
            let e = rows.len();
            let mut block: Vec<f64> =
                (0..e * e).map(|l| a[rows[l / e] * r + rows[l % e]]).collect();
            let rhs: Vec<f64> = rows.iter().map(|&i| -c[i]).collect();
            let mut y = vec![0.0; e];
            least_norm(e, &mut block, &rhs, &mut y);
            x[..r].fill(0.0);
            for (l, &i) in rows.iter().enumerate() {
                x[i] = y[l];
            }
            let holds = (0..r).all(|i| {
                let w = c[i] + (0..r).map(|j| a[i * r + j] * x[j]).sum::<f64>();
                match (normal_of[i] == i, active[normal_of[i]]) {
                    (true, true) => w.abs() <= tol && x[i] * a[i * r + i] >= -tol,
                    (true, false) => w >= -tol,
                    (false, true) => w.abs() <= tol,
                    (false, false) => true,
                }
            });
            if holds {
                return 0;
            }
        }
    }
    2
}
"#;

const C_SOLVER: &str = r#"/*
 * Diagonalises the symmetric k by k matrix a (row-major) by cyclic Jacobi rotations: its
 * diagonal ends as the eigenvalues, the columns of v as the eigenvectors.
 */
static void symmetric_eigen(int k, double *a, double *v)
{
    int sweep, i, j, p, q, r;
    for (i = 0; i < k; i++) {
        for (j = 0; j < k; j++) {
            v[i * k + j] = i == j ? 1.0 : 0.0;
        }
    }
    for (sweep = 0; sweep < 100; sweep++) {
        double off = 0.0;
        double diagonal = 0.0;
        for (i = 0; i < k; i++) {
            diagonal += a[i * k + i] * a[i * k + i];
            for (j = i + 1; j < k; j++) {
                off += a[i * k + j] * a[i * k + j];
            }
        }
        if (off <= 1e-36 * diagonal || off == 0.0) {
            return;
        }
        for (p = 0; p < k; p++) {
            for (q = p + 1; q < k; q++) {
                double apq = a[p * k + q];
                double theta, t, c, s;
                if (apq == 0.0) {
                    continue;
                }
                theta = (a[q * k + q] - a[p * k + p]) / (2.0 * apq);
                if (fabs(theta) > 1e150) {
                    t = 0.5 / theta;
                } else {
                    t = 1.0 / (fabs(theta) + sqrt(theta * theta + 1.0));
                    if (theta < 0.0) {
                        t = -t;
                    }
                }
                c = 1.0 / sqrt(t * t + 1.0);
                s = t * c;
                for (r = 0; r < k; r++) {
                    double arp = a[r * k + p], arq = a[r * k + q];
                    a[r * k + p] = c * arp - s * arq;
                    a[r * k + q] = s * arp + c * arq;
                }
                for (r = 0; r < k; r++) {
                    double apr = a[p * k + r], aqr = a[q * k + r];
                    a[p * k + r] = c * apr - s * aqr;
                    a[q * k + r] = s * apr + c * aqr;
                }
                for (r = 0; r < k; r++) {
                    double vrp = v[r * k + p], vrq = v[r * k + q];
                    v[r * k + p] = c * vrp - s * vrq;
                    v[r * k + q] = s * vrp + c * vrq;
                }
            }
        }
    }
}

/*
 * The least-norm least-squares x of a.x = b for the symmetric positive semidefinite k by k
 * a (destroyed): eigenvalues below 1e-10 of the largest count as zero.
 */
static void least_norm(int k, double *a, const double *b, double *x)
{
    double v[ROWS * ROWS];
    double largest = 0.0;
    int i, l;
    symmetric_eigen(k, a, v);
    for (i = 0; i < k; i++) {
        if (fabs(a[i * k + i]) > largest) {
            largest = fabs(a[i * k + i]);
        }
        x[i] = 0.0;
    }
    for (l = 0; l < k; l++) {
        double lambda = a[l * k + l];
        double along = 0.0;
        if (lambda <= 1e-10 * largest || lambda <= 0.0) {
            continue;
        }
        for (i = 0; i < k; i++) {
            along += v[i * k + l] * b[i];
        }
        along /= lambda;
        for (i = 0; i < k; i++) {
            x[i] += v[i * k + l] * along;
        }
    }
}

/*
 * Solves w = a.x + c (a row-major r by r, symmetric positive semidefinite) with x >= 0,
 * w >= 0, x.w = 0 at the normal rows (normal_of[i] == i) and, at a grip row (normal_of[i]
 * its contact's normal row), w = 0 while that row is active and x = 0 otherwise: the active
 * sets of the normal rows fewest first, each solved least-norm. Returns 0, 2 when no set
 * holds, 3 when more than 20 normal rows touch.
 */
static int complementarity(int r, const double *a, const double *c, const int *normal_of,
                           double *x)
{
    int normals[ROWS], rows[ROWS], active[ROWS];
    double block[ROWS * ROWS], rhs[ROWS], y[ROWS];
    double scale = 0.0, tol;
    int count = 0, size, i, j, l, e;
    unsigned long mask;
    for (i = 0; i < r; i++) {
        if (normal_of[i] == i) {
            normals[count++] = i;
        }
        if (fabs(c[i]) > scale) {
            scale = fabs(c[i]);
        }
    }
    if (count > 20) {
        return 3;
    }
    tol = 1e-10 * scale;
    for (size = 0; size <= count; size++) {
        for (mask = 0; mask < (1UL << count); mask++) {
            int bits = 0, holds = 1;
            for (j = 0; j < count; j++) {
                bits += (int)((mask >> j) & 1UL);
            }
            if (bits != size) {
                continue;
            }
            for (i = 0; i < r; i++) {
                active[i] = 0;
            }
            for (j = 0; j < count; j++) {
                active[normals[j]] = (int)((mask >> j) & 1UL);
            }
            e = 0;
            for (i = 0; i < r; i++) {
                if (active[normal_of[i]]) {
                    rows[e++] = i;
                }
            }
            for (l = 0; l < e * e; l++) {
                block[l] = a[rows[l / e] * r + rows[l % e]];
            }
            for (l = 0; l < e; l++) {
                rhs[l] = -c[rows[l]];
            }
            least_norm(e, block, rhs, y);
            for (i = 0; i < r; i++) {
                x[i] = 0.0;
            }
            for (l = 0; l < e; l++) {
                x[rows[l]] = y[l];
            }
            for (i = 0; i < r && holds; i++) {
                double w = c[i];
                for (j = 0; j < r; j++) {
                    w += a[i * r + j] * x[j];
                }
                if (normal_of[i] == i && active[i]) {
                    holds = fabs(w) <= tol && x[i] * a[i * r + i] >= -tol;
                } else if (normal_of[i] == i) {
                    holds = w >= -tol;
                } else if (active[normal_of[i]]) {
                    holds = fabs(w) <= tol;
                }
            }
            if (holds) {
                return 0;
            }
        }
    }
    return 2;
}

"#;
