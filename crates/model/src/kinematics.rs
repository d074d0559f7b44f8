//! Rotations as expressions: the elementary rotation matrices a scene writes (`rotx`, `roty`,
//! `rotz`, `rotation(axis, angle)`), products and transposes of 3×3 matrices, and the angular
//! velocity of an orientation. What a rotation means for the energy is `mechanics`'s business;
//! these are the geometric facts `resolve` and `mechanics` share.

use cas::{ExprId, Pool};

/// A 3×3 matrix of expressions, row by row.
pub type Matrix3 = [[ExprId; 3]; 3];

/// The rotation by `angle` about the fixed axis `axis` (0 = x, 1 = y, 2 = z), right-handed:
/// it carries vectors given in the rotated axes into the fixed ones.
pub fn elementary(pool: &mut Pool, axis: usize, angle: ExprId) -> Matrix3 {
    let (c, s) = (pool.cos(angle), pool.sin(angle));
    let minus_s = pool.neg(s);
    let (zero, one) = (pool.zero(), pool.one());
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut r = [[zero; 3]; 3];
    r[axis][axis] = one;
    r[i][i] = c;
    r[j][j] = c;
    r[i][j] = minus_s;
    r[j][i] = s;
    r
}

/// The rotation by `angle` about the direction `axis` (any length but zero), by Rodrigues'
/// formula R = cos a·I + sin a·[k]× + (1 − cos a)·k·kᵀ with k the unit vector along `axis`.
pub fn about_axis(pool: &mut Pool, axis: [ExprId; 3], angle: ExprId) -> Matrix3 {
    let squares: Vec<ExprId> = axis.iter().map(|x| pool.powi(*x, 2)).collect();
    let length2 = pool.add(&squares);
    let length2 = pool.simplify(length2);
    let length = pool.sqrt(length2);
    let k = axis.map(|x| {
        let unit = pool.div(x, length);
        pool.simplify(unit)
    });
    let (c, s) = (pool.cos(angle), pool.sin(angle));
    let one = pool.one();
    let versine = pool.sub(one, c);
    let mut r = [[pool.zero(); 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            let outer = pool.mul(&[versine, k[i], k[j]]);
            let diagonal = if i == j { c } else { pool.zero() };
            // [k]× has −k₃ at (1, 2), k₂ at (1, 3), −k₁ at (2, 3) and their opposites below.
            let cross = match (i, j) {
                (0, 1) => pool.neg(k[2]),
                (1, 0) => k[2],
                (0, 2) => k[1],
                (2, 0) => pool.neg(k[1]),
                (1, 2) => pool.neg(k[0]),
                (2, 1) => k[0],
                _ => pool.zero(),
            };
            let cross = pool.mul2(s, cross);
            let sum = pool.add(&[diagonal, cross, outer]);
            *entry = pool.simplify(sum);
        }
    }
    r
}

/// The rotation of the unit quaternion (Euler parameters) e0 + e1·i + e2·j + e3·k. The formula
/// is a rotation only where e0² + e1² + e2² + e3² = 1; a body oriented this way carries that
/// constraint.
pub fn from_quaternion(pool: &mut Pool, e: [ExprId; 4]) -> Matrix3 {
    let [e0, e1, e2, e3] = e;
    let sq = |pool: &mut Pool, x: ExprId| pool.powi(x, 2);
    let two = pool.int(2);
    let twice = |pool: &mut Pool, a: ExprId, b: ExprId, c: ExprId, d: ExprId, plus: bool| {
        let ab = pool.mul2(a, b);
        let cd = pool.mul2(c, d);
        let s = if plus { pool.add2(ab, cd) } else { pool.sub(ab, cd) };
        pool.mul2(two, s)
    };
    let diagonal = |pool: &mut Pool, plus: ExprId| {
        let (s0, s1, s2, s3) = (sq(pool, e0), sq(pool, e1), sq(pool, e2), sq(pool, e3));
        let all = [s0, s1, s2, s3];
        let terms: Vec<ExprId> = [e0, e1, e2, e3]
            .iter()
            .zip(all)
            .map(|(x, s)| if *x == e0 || *x == plus { s } else { pool.neg(s) })
            .collect();
        pool.add(&terms)
    };
    [
        [diagonal(pool, e1), twice(pool, e1, e2, e0, e3, false), twice(pool, e1, e3, e0, e2, true)],
        [twice(pool, e1, e2, e0, e3, true), diagonal(pool, e2), twice(pool, e2, e3, e0, e1, false)],
        [twice(pool, e1, e3, e0, e2, false), twice(pool, e2, e3, e0, e1, true), diagonal(pool, e3)],
    ]
}

/// A·B for matrices of expressions of any compatible shapes, each entry simplified: in a
/// product of rotations about one axis, cos a·cos b − sin a·sin b becomes cos(a + b) here,
/// once, instead of in every term of the energy built from it.
pub fn product(pool: &mut Pool, a: &[Vec<ExprId>], b: &[Vec<ExprId>]) -> Vec<Vec<ExprId>> {
    let columns = b.first().map_or(0, Vec::len);
    a.iter()
        .map(|row| {
            (0..columns)
                .map(|j| {
                    let terms: Vec<ExprId> =
                        row.iter().zip(b).map(|(x, brow)| pool.mul2(*x, brow[j])).collect();
                    let sum = pool.add(&terms);
                    pool.simplify(sum)
                })
                .collect()
        })
        .collect()
}

/// A·v, each entry simplified as in [`product`].
pub fn apply(pool: &mut Pool, a: &[Vec<ExprId>], v: &[ExprId]) -> Vec<ExprId> {
    a.iter()
        .map(|row| {
            let terms: Vec<ExprId> = row.iter().zip(v).map(|(x, y)| pool.mul2(*x, *y)).collect();
            let sum = pool.add(&terms);
            pool.simplify(sum)
        })
        .collect()
}

/// Aᵀ.
pub fn transpose(a: &[Vec<ExprId>]) -> Vec<Vec<ExprId>> {
    let columns = a.first().map_or(0, Vec::len);
    (0..columns).map(|j| a.iter().map(|row| row[j]).collect()).collect()
}

/// u × v of two 3-vectors.
pub fn cross(pool: &mut Pool, u: &[ExprId], v: &[ExprId]) -> Vec<ExprId> {
    let mut component = |i: usize, j: usize| {
        let a = pool.mul2(u[i], v[j]);
        let b = pool.mul2(u[j], v[i]);
        pool.sub(a, b)
    };
    vec![component(1, 2), component(2, 0), component(0, 1)]
}

/// u · v.
pub fn dot(pool: &mut Pool, u: &[ExprId], v: &[ExprId]) -> ExprId {
    let terms: Vec<ExprId> = u.iter().zip(v).map(|(a, b)| pool.mul2(*a, *b)).collect();
    pool.add(&terms)
}

/// A fixed-size copy of a 3×3 matrix given as rows.
pub fn matrix3(rows: &[Vec<ExprId>]) -> Option<Matrix3> {
    if rows.len() != 3 || rows.iter().any(|r| r.len() != 3) {
        return None;
    }
    Some(std::array::from_fn(|i| std::array::from_fn(|j| rows[i][j])))
}

/// Rows of a fixed-size matrix.
pub fn rows(m: &Matrix3) -> Vec<Vec<ExprId>> {
    m.iter().map(|r| r.to_vec()).collect()
}

/// ω in body axes from the orientation R (body to world): Rᵀ·Ṙ is the skew matrix of ω, so
/// ω = ((RᵀṘ)₃₂, (RᵀṘ)₁₃, (RᵀṘ)₂₁), each simplified (the sin² + cos² of Euler angles fold).
pub fn angular_velocity_in_body_axes(pool: &mut Pool, orientation: &Matrix3) -> [ExprId; 3] {
    angular_velocity(pool, orientation, false)
}

/// ω in world axes: Ṙ·Rᵀ is its skew matrix, so ω = ((ṘRᵀ)₃₂, (ṘRᵀ)₁₃, (ṘRᵀ)₂₁).
pub fn angular_velocity_in_world_axes(pool: &mut Pool, orientation: &Matrix3) -> [ExprId; 3] {
    angular_velocity(pool, orientation, true)
}

/// The vector of the skew matrix Rᵀ·Ṙ (body axes) or Ṙ·Rᵀ (world axes).
fn angular_velocity(pool: &mut Pool, orientation: &Matrix3, world: bool) -> [ExprId; 3] {
    let rate: Vec<Vec<ExprId>> = orientation
        .iter()
        .map(|row| row.iter().map(|e| pool.time_derivative(*e)).collect())
        .collect();
    // (RᵀṘ)ᵢⱼ = Σₖ Rₖᵢ·Ṙₖⱼ and (ṘRᵀ)ᵢⱼ = Σₖ Ṙᵢₖ·Rⱼₖ
    let mut entry = |i: usize, j: usize| {
        let terms: Vec<ExprId> = (0..3)
            .map(|k| match world {
                false => pool.mul2(orientation[k][i], rate[k][j]),
                true => pool.mul2(rate[i][k], orientation[j][k]),
            })
            .collect();
        let sum = pool.add(&terms);
        pool.simplify(sum)
    };
    [entry(2, 1), entry(0, 2), entry(1, 0)]
}

/// ω of a body oriented by Euler parameters e, from their rates: 2·G(e)·ė in body axes and
/// 2·E(e)·ė in world axes. Equal to the ω of [`from_quaternion`] on the unit sphere, and a
/// quadratic in e instead of a sextic off it.
pub fn angular_velocity_of_euler_parameters(
    pool: &mut Pool,
    e: [ExprId; 4],
    world: bool,
) -> [ExprId; 3] {
    let rates = e.map(|x| pool.time_derivative(x));
    // Rows of G (body) or E (world), each entry ±e_k, as (sign, index) pairs.
    let rows: [[(i64, usize); 4]; 3] = if world {
        [
            [(-1, 1), (1, 0), (-1, 3), (1, 2)],
            [(-1, 2), (1, 3), (1, 0), (-1, 1)],
            [(-1, 3), (-1, 2), (1, 1), (1, 0)],
        ]
    } else {
        [
            [(-1, 1), (1, 0), (1, 3), (-1, 2)],
            [(-1, 2), (-1, 3), (1, 0), (1, 1)],
            [(-1, 3), (1, 2), (-1, 1), (1, 0)],
        ]
    };
    rows.map(|row| {
        let terms: Vec<ExprId> = row
            .iter()
            .zip(rates)
            .map(|((sign, k), rate)| {
                let two = pool.int(2 * sign);
                pool.mul(&[two, e[*k], rate])
            })
            .collect();
        pool.add(&terms)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity_minus(pool: &mut Pool, m: &[Vec<ExprId>]) -> Vec<ExprId> {
        let mut out = Vec::new();
        for (i, row) in m.iter().enumerate() {
            for (j, e) in row.iter().enumerate() {
                let id = if i == j { pool.one() } else { pool.zero() };
                out.push(pool.sub(*e, id));
            }
        }
        out
    }

    #[test]
    fn elementary_rotations_are_orthogonal_and_turn_the_right_way() {
        let mut pool = Pool::new();
        let a = pool.param("a");
        let a = pool.sym(a);
        for axis in 0..3 {
            let r = rows(&elementary(&mut pool, axis, a));
            let rt = transpose(&r);
            let p = product(&mut pool, &rt, &r);
            for e in identity_minus(&mut pool, &p) {
                assert!(pool.is_identically_zero(e));
            }
        }
        // rotz(a) carries x to (cos a, sin a, 0).
        let r = rows(&elementary(&mut pool, 2, a));
        let (one, zero) = (pool.one(), pool.zero());
        let x = apply(&mut pool, &r, &[one, zero, zero]);
        assert_eq!(x, [pool.cos(a), pool.sin(a), zero]);
    }

    #[test]
    fn rodrigues_about_a_coordinate_axis_is_the_elementary_rotation() {
        let mut pool = Pool::new();
        let a = pool.param("a");
        let a = pool.sym(a);
        let (zero, two) = (pool.zero(), pool.int(2));
        let general = about_axis(&mut pool, [zero, two, zero], a);
        let simple = elementary(&mut pool, 1, a);
        for i in 0..3 {
            for j in 0..3 {
                let d = pool.sub(general[i][j], simple[i][j]);
                assert!(pool.is_identically_zero(d), "({i}, {j})");
            }
        }
    }

    #[test]
    fn a_spin_about_z_has_its_rate_along_z_in_both_axes() {
        let mut pool = Pool::new();
        let q = pool.coordinate("psi");
        let psi = pool.sym(q);
        let r = elementary(&mut pool, 2, psi);
        let rate = pool.rate(q).map(|s| pool.sym(s)).unwrap();
        let zero = pool.zero();
        assert_eq!(angular_velocity_in_body_axes(&mut pool, &r), [zero, zero, rate]);
        assert_eq!(angular_velocity_in_world_axes(&mut pool, &r), [zero, zero, rate]);
    }
}
