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
//!
//! # In space
//!
//! A rough contact in space ([`Law::Cone`]) has two tangential rows and the exact cone
//! ‖x_T‖ ≤ μ·x_N. It sticks (both rows w = 0, ‖x_T‖ < μ·x_N) or slips along a unit direction d:
//! x_T = −μ·x_N·d, and, at tangential rest, w_T = α·d with α ≥ 0 (it moves the way it slips,
//! the friction against it). That last condition is no longer linear in the unknowns: the
//! problem is a second-order cone complementarity problem. A contact already slipping keeps
//! its direction, the slip velocity's; for one at rest the direction is found:
//!
//! - **one contact at rest slipping** in a combination: d = (cos θ, sin θ), and each θ gives a
//!   linear system whose w_T must be parallel to d, r(θ) = d × w_T(θ) = 0. The circle is
//!   scanned at [`ANGLES`] points for changes of sign of r, each refined by bisection to the
//!   last bits; every root with α ≥ 0 is an answer. A root where r touches zero without
//!   changing sign is missed: a double root, at which the slip's direction is not isolated.
//! - **several at rest slipping** together: a fixed point d_k ← w_T,k/‖w_T,k‖ from the
//!   directions against the sticking forces (or the free accelerations), accepted only with
//!   each ‖d_k × w_T,k‖ within the tolerance; when it does not settle and nothing else is
//!   valid, the trouble is [`Trouble::Unsettled`], not a guess.

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
    /// A normal row and two tangential rows with the exact cone of coefficient `mu`;
    /// `sliding` is the unit direction of the slip velocity of a contact that slips now,
    /// `None` at tangential rest.
    Cone { mu: f64, sliding: Option<[f64; 2]> },
}

/// One contact's rows in the problem, and its law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactRows {
    pub normal: usize,
    /// Its tangential row: present for [`Law::Grip`], [`Law::Coulomb`] and [`Law::Cone`].
    pub tangent: Option<usize>,
    /// Its second tangential row: present for [`Law::Cone`].
    pub cross: Option<usize>,
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
    /// Closed and slipping in space along the unit direction d: x_T = −μ·x_N·d.
    Slide([f64; 2]),
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
    /// No combination is valid, and for one of them the directions of several contacts
    /// slipping in space from rest were not settled by their iteration: whether it is
    /// Painlevé's inconsistent case is not known.
    Unsettled,
}

/// The points at which the circle of a slip's directions is scanned for the one direction
/// that Coulomb's law allows (one contact slipping from rest in space).
pub const ANGLES: usize = 96;

/// The most rounds of the fixed point on several slipping directions.
const ROUNDS: usize = 200;

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
    let mut unsettled = false;
    let mut pick = vec![0usize; contacts.len()];
    loop {
        let modes: Vec<Mode> = pick.iter().zip(&choices).map(|(&p, c)| c[p]).collect();
        let problem = Problem { a, b, contacts, tolerance, force_tolerance };
        let (answers, settled) = problem.directions(&modes);
        unsettled |= !settled;
        for answer in answers {
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
                    0 if unsettled => Err(Trouble::Unsettled),
                    0 => Err(Trouble::None),
                    1 => Ok(found.remove(0).0),
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
        Law::Cone { sliding: Some(d), .. } => vec![Mode::Slide(d), Mode::Open],
        // A slide of a direction still to be found ([`FREE`]).
        Law::Cone { sliding: None, .. } if contact.no_stick => vec![Mode::Slide(FREE), Mode::Open],
        Law::Cone { sliding: None, .. } => vec![Mode::Stick, Mode::Slide(FREE), Mode::Open],
    }
}

/// The direction of a slide in space that is still to be found: a contact at rest that
/// slips whichever way Coulomb's law lets it.
const FREE: [f64; 2] = [0.0, 0.0];

/// One problem's data, for the answers of its combinations of modes.
struct Problem<'a> {
    a: &'a DMatrix<f64>,
    b: &'a [f64],
    contacts: &'a [ContactRows],
    tolerance: f64,
    force_tolerance: f64,
}

impl Problem<'_> {
    /// The valid answers of one combination of modes: one at most when every slide's
    /// direction is given; otherwise every direction of the one free slide that Coulomb's law
    /// allows, or the fixed point of several. The flag is false where several free slides'
    /// iteration did not settle.
    fn directions(&self, modes: &[Mode]) -> (Vec<Answer>, bool) {
        let free: Vec<usize> =
            (0..modes.len()).filter(|&k| modes[k] == Mode::Slide(FREE)).collect();
        let valid = |modes: &[Mode]| self.try_modes(modes, true);
        match free.len() {
            0 => (valid(modes).into_iter().collect(), true),
            1 => (self.on_the_circle(modes, free[0]), true),
            _ => self.fixed_point(modes, &free),
        }
    }

    /// d × w_T for a slide along `d` of contact `k` with the other modes `modes`, and the
    /// answer; `None` where that system has no solution.
    fn misalignment(&self, modes: &mut [Mode], k: usize, d: [f64; 2]) -> Option<(f64, Answer)> {
        modes[k] = Mode::Slide(d);
        let answer = self.try_modes(modes, false)?;
        let (t, c) = (self.contacts[k].tangent?, self.contacts[k].cross?);
        Some((d[0] * answer.w[c] - d[1] * answer.w[t], answer))
    }

    /// The directions of contact `k`'s slide from rest that Coulomb's law allows: the roots
    /// of d(θ) × w_T(θ) on the circle, each checked as an answer.
    fn on_the_circle(&self, modes: &[Mode], k: usize) -> Vec<Answer> {
        let mut modes = modes.to_vec();
        let at = |theta: f64| {
            let (s, c) = numeric::elementary::sin_cos(theta);
            [c, s]
        };
        let step = std::f64::consts::TAU / ANGLES as f64;
        let mut roots: Vec<f64> = Vec::new();
        let mut last: Option<(f64, f64)> = None;
        for i in 0..=ANGLES {
            let theta = i as f64 * step;
            let Some((r, _)) = self.misalignment(&mut modes, k, at(theta)) else {
                last = None;
                continue;
            };
            if r == 0.0 && i < ANGLES {
                roots.push(theta);
            } else if let Some((before, r0)) = last {
                if r0 != 0.0 && r0.signum() != r.signum() {
                    // Bisection to the last bits: r is continuous between solvable points.
                    let (mut lo, mut hi, mut r_lo) = (before, theta, r0);
                    for _ in 0..64 {
                        let mid = 0.5 * (lo + hi);
                        if mid <= lo || mid >= hi {
                            break;
                        }
                        match self.misalignment(&mut modes, k, at(mid)) {
                            Some((rm, _)) if rm.signum() == r_lo.signum() && rm != 0.0 => {
                                (lo, r_lo) = (mid, rm);
                            }
                            Some(_) => hi = mid,
                            None => break,
                        }
                    }
                    roots.push(0.5 * (lo + hi));
                }
            }
            last = Some((theta, r));
        }
        roots
            .into_iter()
            .filter_map(|theta| {
                modes[k] = Mode::Slide(at(theta));
                self.try_modes(&modes, true)
            })
            .collect()
    }

    /// Several contacts slipping from rest at once: their directions by the fixed point
    /// d_k ← w_T,k/‖w_T,k‖, started against the forces that would hold them (or along the
    /// accelerations without them).
    fn fixed_point(&self, modes: &[Mode], free: &[usize]) -> (Vec<Answer>, bool) {
        let mut modes = modes.to_vec();
        let rows = |k: usize| (self.contacts[k].tangent, self.contacts[k].cross);
        let mut start = modes.clone();
        for &k in free {
            start[k] = Mode::Stick;
        }
        let held = self.try_modes(&start, false);
        for &k in free {
            let (Some(t), Some(c)) = rows(k) else { return (Vec::new(), true) };
            let guess = match &held {
                Some(h) => [-h.x[t], -h.x[c]],
                None => [self.b[t], self.b[c]],
            };
            let size = crate::linalg::size2(guess[0], guess[1]);
            modes[k] = Mode::Slide(if size > 0.0 {
                [guess[0] / size, guess[1] / size]
            } else {
                [1.0, 0.0]
            });
        }
        for _ in 0..ROUNDS {
            let Some(answer) = self.try_modes(&modes, false) else { return (Vec::new(), true) };
            let slip = |k: usize| {
                let (t, c) = (rows(k).0.unwrap_or(0), rows(k).1.unwrap_or(0));
                let Mode::Slide(d) = modes[k] else { return ([1.0, 0.0], [0.0, 0.0]) };
                (d, [answer.w[t], answer.w[c]])
            };
            let aligned = free.iter().all(|&k| {
                let (d, w) = slip(k);
                (d[0] * w[1] - d[1] * w[0]).abs() <= self.tolerance
            });
            if aligned {
                return (self.try_modes(&modes, true).into_iter().collect(), true);
            }
            let mut change: f64 = 0.0;
            let mut next = modes.clone();
            for &k in free {
                let (d, w) = slip(k);
                let size = crate::linalg::size2(w[0], w[1]);
                if size > 0.0 {
                    let along = [w[0] / size, w[1] / size];
                    change = change.max(crate::linalg::size2(along[0] - d[0], along[1] - d[1]));
                    next[k] = Mode::Slide(along);
                }
            }
            modes = next;
            if change <= 4.0 * f64::EPSILON {
                break;
            }
        }
        (Vec::new(), false)
    }
}

impl Problem<'_> {
    /// The answer of one combination of modes (every slide's direction given), if its system
    /// has one, and, with `check`, if it is valid.
    fn try_modes(&self, modes: &[Mode], check: bool) -> Option<Answer> {
        let Problem { a, b, contacts, tolerance, force_tolerance } = *self;
        let rows = b.len();
        // The unknowns: each closed contact's normal force (its column bent by a slip's
        // tangential force, along one row in the plane, two in space) and each sticking
        // contact's tangential forces; the equations: w = 0 on the same rows.
        let mut unknowns: Vec<(usize, Vec<(usize, f64)>)> = Vec::new();
        for (contact, &mode) in contacts.iter().zip(modes) {
            match mode {
                Mode::Open => {}
                Mode::Closed => unknowns.push((contact.normal, Vec::new())),
                Mode::Stick => {
                    unknowns.push((contact.normal, Vec::new()));
                    unknowns.push((contact.tangent?, Vec::new()));
                    if let Some(c) = contact.cross {
                        unknowns.push((c, Vec::new()));
                    }
                }
                Mode::Slip(s) => {
                    let Law::Coulomb { mu, .. } = contact.law else { return None };
                    unknowns.push((contact.normal, vec![(contact.tangent?, -mu * s)]));
                }
                Mode::Slide(d) => {
                    let Law::Cone { mu, .. } = contact.law else { return None };
                    let bends = vec![(contact.tangent?, -mu * d[0]), (contact.cross?, -mu * d[1])];
                    unknowns.push((contact.normal, bends));
                }
            }
        }
        let k = unknowns.len();
        let mut x = vec![0.0; rows];
        if k > 0 {
            let system = DMatrix::from_fn(k, k, |i, j| {
                let (row, column) = (unknowns[i].0, &unknowns[j]);
                a[(row, column.0)] + column.1.iter().map(|&(t, f)| f * a[(row, t)]).sum::<f64>()
            });
            let rhs = DVector::from_fn(k, |i, _| -b[unknowns[i].0]);
            let bent = unknowns.iter().any(|u| !u.1.is_empty());
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
            for (j, (row, bends)) in unknowns.iter().enumerate() {
                x[*row] += u[j];
                for &(t, f) in bends {
                    x[t] += f * u[j];
                }
            }
        }
        let w: Vec<f64> =
            (0..rows).map(|i| b[i] + (0..rows).map(|j| a[(i, j)] * x[j]).sum::<f64>()).collect();
        if !check {
            return Some(Answer { modes: modes.to_vec(), x, w });
        }
        for (contact, &mode) in contacts.iter().zip(modes) {
            let n = contact.normal;
            let valid = match mode {
                Mode::Open => w[n] >= -tolerance,
                Mode::Closed => x[n] >= -force_tolerance,
                Mode::Stick => {
                    x[n] >= -force_tolerance
                        && match (contact.law, contact.tangent, contact.cross) {
                            (Law::Coulomb { mu, .. }, Some(t), _) => {
                                x[t].abs() < mu * x[n] - force_tolerance
                            }
                            (Law::Cone { mu, .. }, Some(t), Some(c)) => {
                                crate::linalg::size2(x[t], x[c]) < mu * x[n] - force_tolerance
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
                // From rest it must move the way it slips: w_T = α·d with α ≥ 0 (its
                // parallel part is the circle's or the fixed point's to find).
                Mode::Slide(d) => {
                    x[n] >= -force_tolerance
                        && match (contact.law, contact.tangent, contact.cross) {
                            (Law::Cone { sliding: None, .. }, Some(t), Some(c)) => {
                                let along = d[0] * w[t] + d[1] * w[c];
                                let across = d[0] * w[c] - d[1] * w[t];
                                along >= -tolerance && across.abs() <= tolerance.max(1e-9 * along)
                            }
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::size2;

    /// A block of unit mass on a floor, its coordinates (x, y): normal row y, tangential x.
    fn block(b: [f64; 2], mu: f64, sliding: Option<f64>) -> Result<Answer, Trouble> {
        let a = DMatrix::identity(2, 2);
        let rows = [ContactRows {
            normal: 0,
            tangent: Some(1),
            cross: None,
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
            cross: None,
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

    /// Contacts in space, each three rows (normal, then its two tangential ones) from `first`.
    fn cones(count: usize, mu: f64, sliding: Option<[f64; 2]>) -> Vec<ContactRows> {
        (0..count)
            .map(|k| ContactRows {
                normal: 3 * k,
                tangent: Some(3 * k + 1),
                cross: Some(3 * k + 2),
                law: Law::Cone { mu, sliding },
                no_stick: false,
            })
            .collect()
    }

    fn in_space(a: &DMatrix<f64>, b: &[f64], rows: &[ContactRows]) -> Result<Answer, Trouble> {
        solve(a, b, &DMatrix::identity(b.len(), b.len()), rows, 1e-12)
    }

    /// Coulomb's law in space holds for contact `k` of an answer that slides from rest: the
    /// normal row closed, the force on the cone against d, and the tangential acceleration
    /// along d, not against it.
    fn holds_slipping(answer: &Answer, k: usize, mu: f64) -> [f64; 2] {
        let Mode::Slide(d) = answer.modes[k] else { panic!("{answer:?}") };
        let (n, t, c) = (3 * k, 3 * k + 1, 3 * k + 2);
        assert!(answer.w[n].abs() < 1e-12 && answer.x[n] > 0.0, "{answer:?}");
        assert!((size2(d[0], d[1]) - 1.0).abs() < 1e-15);
        assert!((answer.x[t] + mu * answer.x[n] * d[0]).abs() < 1e-14, "{answer:?}");
        assert!((answer.x[c] + mu * answer.x[n] * d[1]).abs() < 1e-14, "{answer:?}");
        let (along, across) =
            (d[0] * answer.w[t] + d[1] * answer.w[c], d[0] * answer.w[c] - d[1] * answer.w[t]);
        assert!(along > 0.0 && across.abs() < 1e-12 * along.max(1.0), "{answer:?}");
        d
    }

    #[test]
    fn a_block_in_space_sticks_inside_the_cone_and_slips_along_the_push_beyond_it() {
        let a = DMatrix::identity(3, 3);
        // Gravity −1 on the normal row, a push (0.3, 0.4) along the floor, of size 0.5.
        let b = [-1.0, 0.3, 0.4];
        let held = in_space(&a, &b, &cones(1, 0.6, None)).expect("one answer");
        assert_eq!(held.modes, vec![Mode::Stick]);
        assert_eq!((held.x[1], held.x[2]), (-0.3, -0.4));
        let slips = in_space(&a, &b, &cones(1, 0.4, None)).expect("one answer");
        let d = holds_slipping(&slips, 0, 0.4);
        assert!((d[0] - 0.6).abs() < 1e-15 && (d[1] - 0.8).abs() < 1e-15, "{d:?}");
        // What is left of the push accelerates it: 0.5 − 0.4.
        assert!((size2(slips.w[1], slips.w[2]) - 0.1).abs() < 1e-15);
        // At the edge of the cone the slip is taken, as in the plane.
        let edge = in_space(&a, &b, &cones(1, 0.5, None)).expect("one motion");
        assert!(matches!(edge.modes[0], Mode::Slide(_)), "{edge:?}");
    }

    #[test]
    fn a_contact_sliding_in_space_is_decelerated_against_its_slip() {
        let a = DMatrix::identity(3, 3);
        let d = [0.28, -0.96];
        let sliding = in_space(&a, &[-2.0, 0.0, 0.0], &cones(1, 0.25, Some(d))).expect("one");
        assert_eq!(sliding.modes, vec![Mode::Slide(d)]);
        assert!(
            (sliding.w[1] + 0.5 * d[0]).abs() < 1e-15 && (sliding.w[2] + 0.5 * d[1]).abs() < 1e-15
        );
    }

    /// Rows coupled through the inertia (a body whose contact point's tangential and normal
    /// accelerations share terms): the slip's direction differs from the push's, and the
    /// circle finds the one Coulomb's law allows.
    #[test]
    fn a_coupled_contact_slips_from_rest_the_one_way_the_law_allows() {
        let l = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 0.4, 0.9, 0.0, -0.3, 0.5, 0.7]);
        let a = &l * l.transpose();
        let b = [-1.0, 0.8, 0.3];
        for mu in [0.2, 0.35] {
            let answer = in_space(&a, &b, &cones(1, mu, None)).expect("one answer");
            let d = holds_slipping(&answer, 0, mu);
            let push =
                [b[1] / crate::linalg::size2(b[1], b[2]), b[2] / crate::linalg::size2(b[1], b[2])];
            assert!((d[0] * push[1] - d[1] * push[0]).abs() > 1e-3, "along the push: {d:?}");
        }
        // With μ large enough it sticks, its force inside the cone.
        let held = in_space(&a, &b, &cones(1, 3.0, None)).expect("one answer");
        assert_eq!(held.modes, vec![Mode::Stick]);
        assert!(size2(held.x[1], held.x[2]) < 3.0 * held.x[0]);
    }

    /// Two contacts at rest slipping together, coupled: their directions by the fixed point,
    /// each held to Coulomb's law.
    #[test]
    fn two_contacts_in_space_slip_from_rest_together() {
        let mut a = DMatrix::identity(6, 6);
        for (i, j, v) in [(0, 3, 0.2), (1, 4, 0.1), (2, 5, -0.15), (1, 5, 0.05)] {
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
        let b = [-1.0, 0.9, 0.2, -0.8, -0.1, 0.7];
        let answer = in_space(&a, &b, &cones(2, 0.3, None)).expect("one answer");
        for k in 0..2 {
            holds_slipping(&answer, k, 0.3);
        }
    }
}
