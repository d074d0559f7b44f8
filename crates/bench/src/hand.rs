//! The n-link planar pendulum written by hand, as the floor for generated code: point masses
//! m on massless links of length l, θᵢ from the downward vertical. With c_ij = n − max(i, j)
//! (0-based, the number of masses at or below the lower of links i and j),
//!   M_ij = c_ij m l² cos(θi − θj),
//!   f_i = −m l² Σ_j c_ij sin(θi − θj) θ̇j² − (n − i) m g l sin θi.
//! This file needs only `std`: the bench binary includes it, and writes it beside the
//! generated code so that rustc compiles both the same way.

/// M (column-major, n×n) and f of the n-link pendulum at (θ, θ̇), into `mass` and `f`.
/// `trig` is scratch of length 2n for the sines and cosines, computed once per angle:
/// cos(θi − θj) and sin(θi − θj) then follow by the difference formulas.
// What a person writes, compiled beside the generated code: the platform's sin and cos are the
// point of the comparison.
#[allow(clippy::too_many_arguments, clippy::disallowed_methods)]
pub fn n_link_mass_forcing(
    theta: &[f64],
    rate: &[f64],
    m: f64,
    l: f64,
    g: f64,
    trig: &mut [f64],
    mass: &mut [f64],
    f: &mut [f64],
) {
    let n = theta.len();
    let (sin, cos) = trig.split_at_mut(n);
    for i in 0..n {
        sin[i] = theta[i].sin();
        cos[i] = theta[i].cos();
    }
    let ml2 = m * l * l;
    // M is symmetric: each off-diagonal entry is computed once and stored twice.
    for i in 0..n {
        for j in i..n {
            let v = (n - j) as f64 * ml2 * (cos[i] * cos[j] + sin[i] * sin[j]);
            mass[j * n + i] = v;
            mass[i * n + j] = v;
        }
    }
    for i in 0..n {
        let mut acc = 0.0;
        for j in 0..n {
            let c = (n - i.max(j)) as f64;
            acc += c * (sin[i] * cos[j] - cos[i] * sin[j]) * rate[j] * rate[j];
        }
        f[i] = -ml2 * acc - (n - i) as f64 * m * g * l * sin[i];
    }
}
