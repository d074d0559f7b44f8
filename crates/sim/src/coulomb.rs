//! The contact problems of contacts with Coulomb friction, in the plane: the forces of touching
//! contacts (w the rows' accelerations) or the impulses of an impact (w the rows' rates after
//! it, Newton's law on the normal), w = A·x + b, with each contact in one of its modes:
//!
//! - **open**: x = 0 on its rows, its normal w ≥ 0;
//! - **closed** (a frictionless contact): normal w = 0, x ≥ 0;
//! - **stick** (a gripping contact, or a rough one at tangential rest): normal and tangential
//!   w = 0, x_N ≥ 0, and for a rough one |x_T| < μ·x_N;
//! - **slip** s = ±1: normal w = 0, x_N ≥ 0, x_T = −μ·s·x_N, and, for a contact at tangential
//!   rest, s·w_T ≥ 0 (it moves the way it slips). A contact already slipping keeps its s.
//!
//! Every combination of modes is tried (this is Glocker's and Pfeiffer's decision between
//! stick and slip written out case by case, not pivoted), and every valid one kept: the
//! problem is no LCP once a column is bent by friction (A loses its symmetry), and with μ
//! large enough it can have no solution or several, Painlevé's paradoxes. Two answers that
//! give the same motion (X·x equal: a grazing contact open or closed, sticking at the edge of
//! the cone or slipping) are one; two that do not, and none, are reported as such, never
//! resolved by a rule of thumb.
//!
//! A stick is valid only strictly inside the cone (by the tolerance): at its edge the slip
//! gives the same motion and is taken, so that a run whose stick ended there does not stick
//! again at once.

use nalgebra::{DMatrix, DVector};

/// The law of one contact's rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// A normal row alone.
    Frictionless,
    /// A normal row and a tangential row held at zero while closed, with any force.
    Grip,
    /// A normal row and a tangential row with Coulomb's law of coefficient `mu`; `sliding`
    /// is the sign of the tangential rate of a contact that slips now, `None` at tangential
    /// rest.
    Coulomb { mu: f64, sliding: Option<f64> },
}

/// One contact's rows in the problem, and its law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactRows {
    pub normal: usize,
    /// Its tangential row: present for [`Law::Grip`] and [`Law::Coulomb`].
    pub tangent: Option<usize>,
    pub law: Law,
    /// Leave sticking out: its stick ended at the edge of the cone (its guard fired).
    pub no_stick: bool,
}

/// A contact's mode in an answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    Open,
    /// Closed without friction.
    Closed,
    /// Closed, its tangential rate held (a grip, or a rough contact inside its cone).
    Stick,
    /// Closed and slipping with the sign given: x_T = −μ·s·x_N.
    Slip(f64),
}

impl Mode {
    pub fn is_closed(self) -> bool {
        self != Mode::Open
    }
}

/// A valid answer: each contact's mode, the forces (or impulses) x per row, w = A·x + b.
#[derive(Clone, Debug, PartialEq)]
pub struct Answer {
    pub modes: Vec<Mode>,
    pub x: Vec<f64>,
    pub w: Vec<f64>,
}

/// Why there is no one answer.
#[derive(Clone, Debug, PartialEq)]
pub enum Trouble {
    /// No combination of modes is valid (Painlevé's inconsistent case, where friction is
    /// involved).
    None,
    /// Valid combinations give different motions (the indeterminate case): each one's modes.
    Several(Vec<Vec<Mode>>),
    /// More combinations than [`COMBINATIONS_LIMIT`].
    TooMany,
}

/// The most combinations of modes tried: four modes for each of six rough contacts at rest.
pub const COMBINATIONS_LIMIT: usize = 4096;

/// Solves the problem w = A·x + b over the contacts `contacts`, with `motion` = X (n × rows)
/// mapping x to the motion it makes (X·x: accelerations or a change of rates), `tolerance`
/// absolute on w (x's is scaled by A's diagonal). Returns the one answer, or the trouble.
pub fn solve(
    a: &DMatrix<f64>,
    b: &[f64],
    motion: &DMatrix<f64>,
    contacts: &[ContactRows],
    tolerance: f64,
) -> Result<Answer, Trouble> {
    let choices: Vec<Vec<Mode>> = contacts.iter().map(candidates).collect();
    let count = choices.iter().try_fold(1usize, |n, c| n.checked_mul(c.len()));
    if count.is_none_or(|n| n > COMBINATIONS_LIMIT) {
        return Err(Trouble::TooMany);
    }
    let diagonal = (0..b.len()).fold(0.0f64, |m, i| m.max(a[(i, i)].abs()));
    let force_tolerance = if diagonal > 0.0 { tolerance / diagonal } else { tolerance };
    let mut found: Vec<(Answer, DVector<f64>)> = Vec::new();
    let mut pick = vec![0usize; contacts.len()];
    loop {
        let modes: Vec<Mode> = pick.iter().zip(&choices).map(|(&p, c)| c[p]).collect();
        if let Some(answer) = try_modes(a, b, contacts, &modes, tolerance, force_tolerance) {
            let moved = motion * DVector::from_column_slice(&answer.x);
            let scale = moved.amax().max(1.0);
            let same = found.iter().any(|(_, m)| (m - &moved).amax() <= 1e3 * tolerance * scale);
            if !same {
                found.push((answer, moved));
            }
        }
        // The next combination, the last contact's mode fastest.
        let mut k = contacts.len();
        loop {
            if k == 0 {
                return match found.len() {
                    0 => Err(Trouble::None),
                    1 => Ok(found.pop().map(|(a, _)| a).unwrap_or_else(|| unreachable!())),
                    _ => Err(Trouble::Several(found.into_iter().map(|(a, _)| a.modes).collect())),
                };
            }
            k -= 1;
            pick[k] += 1;
            if pick[k] < choices[k].len() {
                break;
            }
            pick[k] = 0;
        }
    }
}

/// The modes a contact may take, the preferred first where two give the same motion: closed
/// before open (a grazing contact stays in touch), stick before slip.
fn candidates(contact: &ContactRows) -> Vec<Mode> {
    match contact.law {
        Law::Frictionless => vec![Mode::Closed, Mode::Open],
        Law::Grip => vec![Mode::Stick, Mode::Open],
        Law::Coulomb { sliding: Some(s), .. } => vec![Mode::Slip(s), Mode::Open],
        Law::Coulomb { sliding: None, .. } if contact.no_stick => {
            vec![Mode::Slip(1.0), Mode::Slip(-1.0), Mode::Open]
        }
        Law::Coulomb { sliding: None, .. } => {
            vec![Mode::Stick, Mode::Slip(1.0), Mode::Slip(-1.0), Mode::Open]
        }
    }
}

/// The answer of one combination of modes, if it is valid.
fn try_modes(
    a: &DMatrix<f64>,
    b: &[f64],
    contacts: &[ContactRows],
    modes: &[Mode],
    tolerance: f64,
    force_tolerance: f64,
) -> Option<Answer> {
    let rows = b.len();
    // The unknowns: each closed contact's normal force (its column bent by a slip's tangential
    // force) and each sticking contact's tangential force; the equations: w = 0 on the same
    // rows.
    let mut unknowns: Vec<(usize, Option<(usize, f64)>)> = Vec::new();
    for (contact, &mode) in contacts.iter().zip(modes) {
        match mode {
            Mode::Open => {}
            Mode::Closed => unknowns.push((contact.normal, None)),
            Mode::Stick => {
                unknowns.push((contact.normal, None));
                unknowns.push((contact.tangent?, None));
            }
            Mode::Slip(s) => {
                let Law::Coulomb { mu, .. } = contact.law else { return None };
                unknowns.push((contact.normal, Some((contact.tangent?, -mu * s))));
            }
        }
    }
    let k = unknowns.len();
    let mut x = vec![0.0; rows];
    if k > 0 {
        let system = DMatrix::from_fn(k, k, |i, j| {
            let (row, column) = (unknowns[i].0, unknowns[j]);
            a[(row, column.0)] + column.1.map_or(0.0, |(t, f)| f * a[(row, t)])
        });
        let rhs = DVector::from_fn(k, |i, _| -b[unknowns[i].0]);
        let bent = unknowns.iter().any(|u| u.1.is_some());
        let u = if bent {
            system.clone().full_piv_lu().solve(&rhs)?
        } else {
            crate::complementarity::least_norm(system.clone(), &rhs).0
        };
        // Redundant rows that disagree have no solution: the residual says so.
        let residual = &system * &u - &rhs;
        if !u.iter().all(|v| v.is_finite()) || residual.amax() > tolerance {
            return None;
        }
        for (j, &(row, bend)) in unknowns.iter().enumerate() {
            x[row] += u[j];
            if let Some((t, f)) = bend {
                x[t] += f * u[j];
            }
        }
    }
    let w: Vec<f64> =
        (0..rows).map(|i| b[i] + (0..rows).map(|j| a[(i, j)] * x[j]).sum::<f64>()).collect();
    for (contact, &mode) in contacts.iter().zip(modes) {
        let n = contact.normal;
        let valid = match mode {
            Mode::Open => w[n] >= -tolerance,
            Mode::Closed => x[n] >= -force_tolerance,
            Mode::Stick => {
                x[n] >= -force_tolerance
                    && match (contact.law, contact.tangent) {
                        (Law::Coulomb { mu, .. }, Some(t)) => {
                            x[t].abs() < mu * x[n] - force_tolerance
                        }
                        _ => true,
                    }
            }
            Mode::Slip(s) => {
                x[n] >= -force_tolerance
                    && match (contact.law, contact.tangent) {
                        (Law::Coulomb { sliding: None, .. }, Some(t)) => s * w[t] >= -tolerance,
                        _ => true,
                    }
            }
        };
        if !valid {
            return None;
        }
    }
    Some(Answer { modes: modes.to_vec(), x, w })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block of unit mass on a floor, its coordinates (x, y): normal row y, tangential x.
    fn block(b: [f64; 2], mu: f64, sliding: Option<f64>) -> Result<Answer, Trouble> {
        let a = DMatrix::identity(2, 2);
        let rows = [ContactRows {
            normal: 0,
            tangent: Some(1),
            law: Law::Coulomb { mu, sliding },
            no_stick: false,
        }];
        // Rows (y, x); motion (x, y).
        let motion = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 1.0, 0.0]);
        solve(&a, &b, &motion, &rows, 1e-12)
    }

    #[test]
    fn a_block_pushed_within_its_cone_sticks_and_beyond_it_slips() {
        // Gravity −1 on the normal row, a push 0.3 along: μ = 0.5 holds it.
        let held = block([-1.0, 0.3], 0.5, None).expect("one answer");
        assert_eq!(held.modes, vec![Mode::Stick]);
        assert_eq!((held.x[0], held.x[1]), (1.0, -0.3));
        // μ = 0.2 does not: it slips forward, the force μ·N against it.
        let slips = block([-1.0, 0.3], 0.2, None).expect("one answer");
        assert_eq!(slips.modes, vec![Mode::Slip(1.0)]);
        assert!((slips.x[1] + 0.2).abs() < 1e-15 && (slips.w[1] - 0.1).abs() < 1e-15);
    }

    #[test]
    fn a_sliding_block_decelerates_and_a_lifted_one_flies() {
        let sliding = block([-1.0, 0.0], 0.4, Some(-1.0)).expect("one answer");
        assert_eq!(sliding.modes, vec![Mode::Slip(-1.0)]);
        assert!((sliding.w[1] - 0.4).abs() < 1e-15);
        let flies = block([2.0, 0.0], 0.4, Some(1.0)).expect("one answer");
        assert_eq!((flies.modes[0], flies.x[0]), (Mode::Open, 0.0));
    }

    #[test]
    fn at_the_edge_of_the_cone_the_slip_is_taken() {
        let edge = block([-1.0, 0.5], 0.5, None).expect("one motion");
        assert_eq!(edge.modes, vec![Mode::Slip(1.0)]);
    }

    /// Painlevé's coefficient negative: a = 1 + μ·s·k with the tangential force feeding the
    /// normal row (A's off-diagonal k).
    fn painleve(b_normal: f64) -> Result<Answer, Trouble> {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 3.0]);
        let rows = [ContactRows {
            normal: 0,
            tangent: Some(1),
            law: Law::Coulomb { mu: 2.0, sliding: Some(1.0) },
            no_stick: false,
        }];
        solve(&a, &[b_normal, 0.0], &DMatrix::identity(2, 2), &rows, 1e-12)
    }

    #[test]
    fn painleves_cases_are_told_apart() {
        // a = 1 − 2 = −1: pressed in (b < 0), no force pushes; lifting (b > 0), both open
        // and a pushing force do.
        assert_eq!(painleve(-1.0), Err(Trouble::None));
        match painleve(1.0) {
            Err(Trouble::Several(modes)) => {
                assert_eq!(modes, vec![vec![Mode::Slip(1.0)], vec![Mode::Open]]);
            }
            other => panic!("{other:?}"),
        }
    }
}
