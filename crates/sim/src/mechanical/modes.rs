//! The modes of one-sided contacts: which are closed (their rows kept, their reactions
//! pushing), the guards a run watches to leave a mode, and the jumps between modes: impacts by
//! Newton's law, the reactions' complementarity problem that says which touching contacts
//! close, lift-offs, and the settling of accumulating impacts.
//!
//! # A jump
//!
//! 1. The touching contacts (the closed ones, and the open ones at g ≈ 0) are found. If an
//!    open one lands (γ < 0), all of them and the two-sided constraints take one impulse:
//!    the complementarity problem of the Delassus operator A = W·S·Wᵀ (S the mass block of
//!    the inverse of the augmented system that keeps the two-sided rows alone) with
//!    c = (1 + e)·γ⁻ per normal row (e = 0 for a contact that was closed, whose γ is drift),
//!    c = γ_T⁻ per grip row; then q̇⁺ = q̇⁻ + S·Wᵀ·Λ.
//! 2. Of the touching contacts at rest (γ ≈ 0) after it, the reactions' complementarity
//!    problem g̈ = A·λ + b closes those that push and opens the rest; the others open.
//! 3. The state is projected onto the new mode's constraints, positions then rates (the
//!    drift the stabilisation would otherwise push back out, adding energy), and a closed
//!    contact's grip row that depends on the rows kept before it is left out of the solves.
//!
//! # Tolerances
//!
//! Each is the run's tolerance `tol` (relative) times a scale of the contact's own, so that
//! they follow the scene's units:
//! - **touching** (g ≈ 0): g ≤ tol·L, with L the larger of |g| at the start and the size of
//!   the contact's gradient times that of q at the start (‖J‖₁·‖q‖∞). At the start a gap
//!   below −tol·L is a fault ([`FaultKind::Penetrating`]).
//! - **at rest** (γ ≈ 0): |γ| ≤ 100·tol·V for a contact that was closed, whose γ is the
//!   drift the integration and the stabilisation leave, and |γ| ≤ tol·V/100 for one that was
//!   open or just landed (the hysteresis that keeps a contact from chattering between the
//!   two), with V the larger of the largest |γ⁻| of its impacts and ‖J‖₁·‖q̇‖∞ at the start
//!   and at each jump. An open touching contact with γ below −tol·V/100 lands; a closed one
//!   never does (its γ is drift), but takes part in the impact of those that land, with e = 0.
//!   A closed contact that such an impact separates stays closed below the larger of its band
//!   and √(2·a·δ), the rate gained at its acceleration a (with every contact open) through
//!   δ = 64 ulps of the positions times its gradient: below it the flights are rounding (a
//!   rocking block's accumulating impacts otherwise end in a cycle that floating point keeps
//!   up, at about 5·10⁻⁸ m/s for a 1 m block).
//! - **pushing** (λ > 0): the complementarity problem of the reactions is solved to tol times
//!   the scale of g̈ with every contact open (the largest of its terms J·q̈ and γ, since g̈
//!   itself passes through zero where a reaction vanishes), and a contact whose reaction
//!   fell to zero (the lift-off its guard located) has that much added to its g̈ there, so
//!   that it opens rather than closing again at the same instant.
//! - **guards**: a closed contact's is its reaction λ, an open one's its gap g, offset by a
//!   little more than −g where it opened at g ≤ 0 (from a closed contact's drift), so that it
//!   starts positive and a landing within the next step is seen, at the depth it left.
//! - **settling**: a contact that lands at |γ⁻| < tol·S, with S the largest |γ⁻| of its
//!   impacts so far, lands plastically (e = 0) and closes ([`ModeChange::Settled`]). For a
//!   ball of restitution e landing at v, the impacts it would still have had take
//!   2ev/(g(1−e)) (the sum of 2eᵏv/g over k ≥ 1), and their accumulation point from the first
//!   impact at v₀ is at t₁ + 2ev₀/(g(1−e)) with t₁ = v₀/g, in all t∞ = v₀(1+e)/(g(1−e)). Cut
//!   at v < tol·v₀, the time lost is below 2e·tol·v₀/(g(1−e)), a fraction 2e/(1+e)·tol < tol
//!   of t∞; the ball gets there in ln(tol)/ln(e) impacts (93 at e = 0.8, tol = 1e-9).

use nalgebra::DMatrix;
use numeric::Tape;

use super::{Layout, Mechanical, Stabilisation};
use crate::complementarity::{self, Row};
use crate::{linalg, Contact, FaultKind, ModeChange, ModeEvent};

/// The band of γ, in tol·V, within which an open contact counts as at rest (below it, it
/// lands).
const OPEN_BAND: f64 = 1e-2;
/// The band of γ, in tol·V, within which a closed contact counts as at rest: its drift.
const CLOSED_BAND: f64 = 1e2;
/// The depth, in ulps of the positions (times the gap's gradient), that rounding moves a
/// contact by: the floor of the rates a closed contact separates at and still counts as at
/// rest.
const ROUNDING: f64 = 64.0;

/// The modes of the contacts, and the scales of their tolerances.
#[derive(Clone, Debug, Default)]
pub(super) struct Modes {
    /// Whether each contact is closed.
    closed: Vec<bool>,
    /// The run's tolerance, relative.
    tolerance: f64,
    /// Each contact's length scale L.
    length: Vec<f64>,
    /// Each contact's largest |γ⁻| at its impacts so far, S.
    impacts: Vec<f64>,
    /// Each contact's rate scale V.
    speed: Vec<f64>,
    /// Each open contact's guard is g + this: 0 for one that opened at g > 0, else a little
    /// more than −g there, so that the guard starts positive and the contact lands again at
    /// the depth it left (not deeper: a rocking block's corners would sink further at every
    /// landing).
    offset: Vec<f64>,
    /// Each rough contact's slip while closed: ±1 the sign of its tangential rate, 0 while it
    /// sticks (and for every other contact).
    slip: Vec<f64>,
    /// Each rough contact's tangential rate scale V_T (rough contacts).
    tangent_speed: Vec<f64>,
    /// Each rough contact in space: the direction of its slip decided at the last jump, the
    /// one its friction opposes while its slip velocity is within its band (a slip from rest
    /// starts at γ_T = 0, whose own direction is rounding's).
    direction: Vec<[f64; 2]>,
    /// A slipping contact's guard is s·γ_T + this: a little more than −s·γ_T where it began
    /// to slip, so that the guard starts positive.
    slip_offset: Vec<f64>,
    /// The rough contacts, in order: their guards follow the contacts'.
    rough: Vec<usize>,
    /// Whether each contact is armed (its condition positive; always, without one).
    armed: Vec<bool>,
    /// Whether each contact has an arming condition of its own.
    conditioned: Vec<bool>,
    /// An armed contact that was armed inside its gap (g < 0: a swing foot below the ground
    /// at mid-stance): it neither lands nor faults until its gap rises through 0.
    below: Vec<bool>,
    /// The law the last jump's impulse took, for its exact derivative.
    pub(super) struck: Struck,
}

/// The impulse of the last jump, as its derivative needs it ([`Mechanical::impact_derivative`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) enum Struck {
    /// None: the rates are those before the jump.
    #[default]
    None,
    /// Newton's law without friction on the rows that took the impulse (each multiplier, with
    /// its factor: 1 + e of a normal row, 1 of a grip), their rates after it −e times those
    /// before.
    Frictionless { rows: Vec<usize>, factors: Vec<f64> },
    /// Coulomb's law within the impact, whose modes switch with the state: no derivative is
    /// lowered for it.
    Coulomb,
}

/// What a jump changes of a problem besides the state (the modes and their scales, the rows
/// kept), saved to be put back after a trial jump: a saltation matrix differences the jump
/// map at states around the real one, on the problem itself rather than on copies of its
/// programs.
#[derive(Clone, Debug)]
pub(crate) struct ModesState {
    modes: Modes,
    kept: Vec<bool>,
    bends: Vec<super::Bend>,
}

/// What a guard of the contacts watches ([`Mechanical::watched_by`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Watched {
    /// A contact's gap while it is open, its reaction while it is closed.
    Contact(usize),
    /// A rough contact's stick (its force reaching the cone) or slip (its rate stopping).
    Friction(usize),
    /// Whether the slipping contacts' forces are still determined (Painlevé's jam).
    Solvability,
    /// A contact's arming condition.
    Arming(usize),
}

/// The rows of a complementarity problem: each row's multiplier, kind and contact.
struct Rows {
    multipliers: Vec<usize>,
    kinds: Vec<Row>,
    owners: Vec<usize>,
}

impl Mechanical {
    /// Makes the kept multipliers named by `contacts` one-sided: each contact's rows are kept
    /// only while it is closed. Which are closed is decided at the start of a run
    /// ([`crate::Problem::begin_modes`]); until then all are open.
    pub fn with_contacts(mut self, contacts: Vec<Contact>) -> Self {
        let m = self.layout.multipliers;
        for c in &contacts {
            assert!(c.normal < m && c.grip.is_none_or(|g| g < m), "a contact's multiplier");
            assert!((0.0..=1.0).contains(&c.restitution), "restitution in [0, 1]");
            assert!(c.friction.is_none_or(|mu| mu >= 0.0 && c.grip.is_some()), "μ ≥ 0 on a row");
            assert!(
                c.cross.is_none_or(|x| x < m && c.grip.is_some() && c.friction.is_some()),
                "a second tangential row belongs to a rough contact in space"
            );
        }
        let count = contacts.len();
        self.modes = Modes {
            closed: vec![false; count],
            tolerance: 0.0,
            length: vec![0.0; count],
            impacts: vec![0.0; count],
            speed: vec![0.0; count],
            offset: vec![0.0; count],
            slip: vec![0.0; count],
            direction: vec![[1.0, 0.0]; count],
            tangent_speed: vec![0.0; count],
            slip_offset: vec![0.0; count],
            rough: (0..count).filter(|&k| contacts[k].friction.is_some()).collect(),
            armed: vec![true; count],
            conditioned: vec![false; count],
            below: vec![false; count],
            struck: Struck::None,
        };
        self.contacts = contacts;
        self.update_kept();
        self
    }

    /// Sets each contact's restitution, in the order of [`Mechanical::contacts`]: a run at
    /// other parameter values than the problem was made with (an ensemble's) gives them here.
    pub fn set_restitutions(&mut self, restitutions: &[f64]) {
        assert_eq!(restitutions.len(), self.contacts.len(), "a restitution per contact");
        for (c, &e) in self.contacts.iter_mut().zip(restitutions) {
            assert!((0.0..=1.0).contains(&e), "restitution in [0, 1]");
            c.restitution = e;
        }
    }

    /// The one-sided contacts.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// Whether each contact is closed now.
    pub fn closed(&self) -> &[bool] {
        &self.modes.closed
    }

    /// The modes as they are now, for [`Mechanical::restore_modes`].
    pub(crate) fn modes_state(&self) -> ModesState {
        ModesState { modes: self.modes.clone(), kept: self.kept.clone(), bends: self.bends.clone() }
    }

    /// Puts back the modes saved by [`Mechanical::modes_state`].
    pub(crate) fn restore_modes(&mut self, state: &ModesState) {
        self.modes.clone_from(&state.modes);
        self.kept.clone_from(&state.kept);
        self.bends.clone_from(&state.bends);
        self.solved = None;
    }

    /// Sets each contact's coefficient of friction (rough contacts only; others keep `None`),
    /// as [`Mechanical::set_restitutions`] its restitution.
    pub fn set_frictions(&mut self, frictions: &[Option<f64>]) {
        assert_eq!(frictions.len(), self.contacts.len(), "a coefficient per contact");
        for (c, &mu) in self.contacts.iter_mut().zip(frictions) {
            assert_eq!(c.friction.is_some(), mu.is_some(), "rough contacts stay rough");
            assert!(mu.is_none_or(|mu| mu >= 0.0), "μ ≥ 0");
            c.friction = mu;
        }
    }

    /// Watches the contacts' arming conditions, the outputs of `conditions` (one per contact,
    /// from the dynamics program's inputs): a contact is watched only while its condition is
    /// positive. Each condition is a guard of its own, after the others.
    /// `conditioned` says which contacts have a condition of their own (the others' output is
    /// 1): only those may be armed inside their gap.
    pub fn with_arming(mut self, conditions: Tape, conditioned: Vec<bool>) -> Self {
        assert_eq!(conditions.outputs(), self.contacts.len(), "a condition per contact");
        assert_eq!(conditioned.len(), self.contacts.len(), "a flag per contact");
        self.modes.conditioned = conditioned;
        assert_eq!(conditions.inputs(), self.layout.dynamics_inputs(), "the dynamics' inputs");
        let values = vec![1.0; self.contacts.len()];
        self.arming = Some((conditions, values));
        self
    }

    /// Each contact's arming condition at (t, y), into the stored values.
    fn evaluate_arming(&mut self, t: f64, y: &[f64]) {
        let Some((tape, values)) = self.arming.as_mut() else { return };
        // Filled in place: the guards ask at every step.
        let input = tape.inputs_mut();
        input[0] = t;
        input[1..1 + y.len()].copy_from_slice(y);
        input[1 + y.len()..].copy_from_slice(&self.parameters);
        tape.run(values);
    }

    /// The contacts slipping now.
    pub(super) fn slipping_contacts(&self) -> Vec<usize> {
        (0..self.contacts.len()).filter(|&k| self.modes.slip[k] != 0.0).collect()
    }

    /// The multipliers of the two-sided constraints and of the closed contacts are kept, but
    /// a slipping contact's tangential row is not: its force is μ·λ against the slip, a bend
    /// of its normal column.
    fn update_kept(&mut self) {
        self.kept.fill(true);
        self.bends.clear();
        for (k, contact) in self.contacts.iter().enumerate() {
            let (closed, slip) = (self.modes.closed[k], self.modes.slip[k]);
            self.kept[contact.normal] = closed;
            if let (Some(grip), Some(cross), Some(mu)) =
                (contact.grip, contact.cross, contact.friction)
            {
                self.kept[grip] = closed && slip == 0.0;
                self.kept[cross] = closed && slip == 0.0;
                if closed && slip != 0.0 {
                    // The factors −μ·γ_i/‖γ_T‖ follow the state: aimed at each solve.
                    let band = self.modes.tolerance * self.modes.tangent_speed[k] * OPEN_BAND;
                    let fallback = self.modes.direction[k];
                    for (which, tangent) in [grip, cross].into_iter().enumerate() {
                        self.bends.push(super::Bend {
                            normal: contact.normal,
                            tangent,
                            factor: -mu * fallback[which],
                            cone: Some(super::Cone {
                                rates: [grip, cross],
                                which,
                                mu,
                                fallback,
                                band,
                            }),
                        });
                    }
                }
            } else if let Some(grip) = contact.grip {
                self.kept[grip] = closed && slip == 0.0;
                if let (true, Some(mu)) = (closed && slip != 0.0, contact.friction) {
                    self.bends.push(super::Bend {
                        normal: contact.normal,
                        tangent: grip,
                        factor: -mu * slip,
                        cone: None,
                    });
                }
            }
        }
        self.solved = None;
    }

    /// Keeps out the grip rows of closed contacts that depend on the rows kept before them
    /// (the two-sided ones, then each contact's normal and grip in turn), at the positions of
    /// the last evaluation: two gripping corners of a block resting flat give four rows on
    /// three degrees of freedom, and the augmented system would be singular. A grip row is a
    /// velocity row, so one that depends on the others is held by them; its multiplier is 0.
    fn drop_redundant_grips(&mut self) {
        let m = self.layout.multipliers;
        let two_sided = self.two_sided();
        let mut order: Vec<usize> = (0..m).filter(|&c| two_sided[c]).collect();
        for contact in &self.contacts {
            order.push(contact.normal);
            order.extend(contact.grip);
            order.extend(contact.cross);
        }
        let grips: Vec<usize> =
            self.contacts.iter().flat_map(|c| c.grip.into_iter().chain(c.cross)).collect();
        let mut basis: Vec<Vec<f64>> = Vec::new();
        for c in order {
            if !self.kept[c] {
                continue;
            }
            let mut r = self.jacobian_row(c).to_vec();
            let size = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            for b in &basis {
                let dot: f64 = r.iter().zip(b).map(|(x, y)| x * y).sum();
                for (x, y) in r.iter_mut().zip(b) {
                    *x -= dot * y;
                }
            }
            let rest = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            if rest <= 1e-8 * size && grips.contains(&c) {
                self.kept[c] = false;
            } else if rest > 0.0 {
                basis.push(r.iter().map(|x| x / rest).collect());
            }
        }
        self.solved = None;
    }

    /// Where multiplier `c`'s values start in the dynamics outputs.
    fn base(&self, c: usize) -> usize {
        let n = self.layout.coordinates;
        n * n + n + c * (n + 3)
    }

    fn jacobian_row(&self, c: usize) -> &[f64] {
        let (b, n) = (self.base(c), self.layout.coordinates);
        &self.dyn_out[b..b + n]
    }

    fn gap(&self, k: usize) -> f64 {
        let n = self.layout.coordinates;
        self.dyn_out[self.base(self.contacts[k].normal) + n + 1]
    }

    /// The rate of multiplier `c`'s row: ġ of a position row, the residual of a velocity row.
    pub(super) fn row_rate(&self, c: usize) -> f64 {
        let (b, n) = (self.base(c), self.layout.coordinates);
        match self.stabilisation[c] {
            Stabilisation::Position => self.dyn_out[b + n + 2],
            Stabilisation::Velocity => self.dyn_out[b + n + 1],
        }
    }

    /// The right-hand side row `c` imposes on J·q̈ while kept, stabilisation included.
    fn stabilised(&self, c: usize) -> f64 {
        let (b, n, a) = (self.base(c), self.layout.coordinates, self.baumgarte);
        let out = &self.dyn_out;
        match self.stabilisation[c] {
            Stabilisation::Position => {
                out[b + n] - 2.0 * a * out[b + n + 2] - a * a * out[b + n + 1]
            }
            Stabilisation::Velocity => out[b + n] - a * out[b + n + 1],
        }
    }

    /// A rough contact's tangential rates: one in the plane, two in space.
    fn tangential_rate(&self, k: usize) -> Vec<f64> {
        let contact = self.contacts[k];
        contact.grip.into_iter().chain(contact.cross).map(|t| self.row_rate(t)).collect()
    }

    fn normal_rate(&self, k: usize) -> f64 {
        self.row_rate(self.contacts[k].normal)
    }

    /// The rows of the contacts `set`: each normal, then its grip.
    fn rows_of(&self, set: &[usize]) -> Rows {
        let mut rows = Rows { multipliers: Vec::new(), kinds: Vec::new(), owners: Vec::new() };
        for &k in set {
            let normal = rows.kinds.len();
            rows.multipliers.push(self.contacts[k].normal);
            rows.kinds.push(Row::Normal);
            rows.owners.push(k);
            for grip in self.contacts[k].grip.into_iter().chain(self.contacts[k].cross) {
                rows.multipliers.push(grip);
                rows.kinds.push(Row::Tangent { normal });
                rows.owners.push(k);
            }
        }
        rows
    }

    /// The contacts' rows condensed through M and the two-sided constraints: X = S·Wᵀ (n × r)
    /// with S the mass block of the inverse of the augmented system that keeps only the
    /// two-sided rows, and the Delassus operator A = W·X (r × r, symmetric).
    fn condensed(
        &mut self,
        multipliers: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        let two_sided = self.two_sided();
        // The two-sided rows alone: the contacts' rows would be the identity's, which only
        // made the factorization larger (a rimless wheel's sixteen rows beside its M).
        let rows: Vec<usize> = (0..m).filter(|&c| two_sided[c]).collect();
        let order = n + rows.len();
        let mut system = DMatrix::zeros(order, order);
        super::load_kept(&self.dyn_out, n, &rows, &[], &mut system);
        let mut pivots = vec![0; order];
        linalg::lu_in_place(&mut system, &mut pivots)?;
        let r = multipliers.len();
        let mut x = DMatrix::zeros(n, r);
        let mut column = vec![0.0; order];
        for (j, &c) in multipliers.iter().enumerate() {
            column.fill(0.0);
            column[..n].copy_from_slice(self.jacobian_row(c));
            linalg::lu_solve(&system, &pivots, &mut column);
            for i in 0..n {
                x[(i, j)] = column[i];
            }
        }
        let mut a = DMatrix::zeros(r, r);
        for i in 0..r {
            let row = self.jacobian_row(multipliers[i]);
            for j in 0..r {
                a[(i, j)] = (0..n).map(|l| row[l] * x[(l, j)]).sum::<f64>();
            }
        }
        let a = (&a + a.transpose()) * 0.5;
        Ok((x, a))
    }

    /// The mask that keeps the two-sided rows alone.
    pub(super) fn two_sided(&self) -> Vec<bool> {
        let mut kept = vec![true; self.layout.multipliers];
        for contact in &self.contacts {
            kept[contact.normal] = false;
            for grip in contact.grip.into_iter().chain(contact.cross) {
                kept[grip] = false;
            }
        }
        kept
    }

    /// The gradient of guard `k` in (q, q̇) and its partial in t, exact, where it is a
    /// contact's gap (an open, armed contact's; `None` for any other guard): (∂Φ/∂q, 0) and
    /// Φ̇ − ∂Φ/∂q·q̇ of its normal row.
    pub(crate) fn gap_gradient(
        &mut self,
        t: f64,
        y: &[f64],
        k: usize,
    ) -> Result<Option<(Vec<f64>, f64)>, FaultKind> {
        let count = self.contacts.len();
        if k >= count || self.modes.closed[k] || !self.modes.armed[k] || self.modes.below[k] {
            return Ok(None);
        }
        let c = self.contacts[k].normal;
        if self.stabilisation[c] != Stabilisation::Position {
            return Ok(None);
        }
        let n = self.layout.coordinates;
        self.dynamics_at(t, y)?;
        let row = self.jacobian_row(c);
        let along: f64 = row.iter().zip(&y[n..]).map(|(j, v)| j * v).sum();
        let mut gradient = row.to_vec();
        gradient.resize(2 * n, 0.0);
        Ok(Some((gradient, self.dyn_out[self.base(c) + n + 2] - along)))
    }

    /// What guard `k` of the contacts watches, in the order [`Mechanical::contact_guards`]
    /// gives them: each contact's gap or reaction, each rough contact's stick or slip, the
    /// slipping contacts' solvability, each contact's arming condition.
    pub(crate) fn watched_by(&self, k: usize) -> Watched {
        let (count, rough) = (self.contacts.len(), self.modes.rough.len());
        let solvability = count + rough;
        if k < count {
            Watched::Contact(k)
        } else if k < solvability {
            Watched::Friction(self.modes.rough[k - count])
        } else if k == solvability && rough > 0 {
            Watched::Solvability
        } else {
            Watched::Arming(k - solvability - usize::from(rough > 0))
        }
    }

    /// How many guards the contacts have: one each, one more for each rough contact (its
    /// stick or its slip), and one for the solvability of the slipping contacts' forces.
    pub(super) fn contact_guard_count(&self) -> usize {
        let rough = self.modes.rough.len();
        let arming = if self.arming.is_some() { self.contacts.len() } else { 0 };
        self.contacts.len() + rough + usize::from(rough > 0) + arming
    }

    /// Guard `k` where it is an open contact's (its gap, or 1 while it is not armed), from a
    /// slice of the dynamics program with that gap alone: no solve, as
    /// [`Mechanical::contact_guards`] needs for the closed contacts' reactions. `None` for
    /// any other guard. The dynamics program's inputs move to (t, y), so the accelerations
    /// solved before are forgotten.
    pub(crate) fn open_gap(
        &mut self,
        t: f64,
        y: &[f64],
        k: usize,
    ) -> Result<Option<f64>, FaultKind> {
        if k >= self.contacts.len() || self.modes.closed[k] {
            return Ok(None);
        }
        if !self.modes.armed[k] {
            return Ok(Some(1.0));
        }
        let n = self.layout.coordinates;
        let output = self.base(self.contacts[k].normal) + n + 1;
        if !self.solved_at(t, y) {
            if self.gap_slices.len() != self.contacts.len() {
                self.gap_slices = vec![None; self.contacts.len()];
            }
            if self.gap_slices[k].is_none() {
                self.gap_slices[k] = Some(self.dynamics.slice([output]));
            }
            self.solved = None;
            self.sliced = None;
            self.mass_factored = false;
            self.kept_factors.valid = false;
            self.follow_signals(t);
            super::fill_inputs(self.dynamics.inputs_mut(), t, y, &self.parameters);
            if let Some(slice) = self.gap_slices[k].as_mut() {
                self.dynamics.run_slice(slice, &mut self.dyn_out);
                super::slice_finite(&self.dyn_out, slice, self.layout)?;
            }
        }
        let gap = self.gap(k);
        Ok(Some(if self.modes.below[k] { -gap } else { gap } + self.modes.offset[k]))
    }

    /// The guards: a closed contact's reaction λ, an open one's gap g; then each rough
    /// contact's stick (μ·λ − |λ_T| while it sticks) or slip (s·γ_T while it slips, offset
    /// to start positive); in space μ·λ − ‖λ_T‖, or d·γ_T less its band with d the slip's
    /// direction at the last jump; then the slipping contacts' solvability (1 when none
    /// slips).
    pub(super) fn contact_guards(
        &mut self,
        t: f64,
        y: &[f64],
        out: &mut [f64],
    ) -> Result<(), FaultKind> {
        // An open contact's guard is its gap, which the dynamics program gives: the solve
        // for the reactions is needed only where a closed contact's reaction is watched (a
        // ball in flight locates its landing without one).
        if self.modes.closed.iter().any(|&c| c) {
            self.accelerations(t, y)?;
        } else if !self.solved_at(t, y) && !self.completed_at(t, y)? {
            self.dynamics_at(t, y)?;
        }
        let n = self.layout.coordinates;
        let count = self.contacts.len();
        for k in 0..count {
            out[k] = if !self.modes.armed[k] {
                1.0
            } else if self.modes.below[k] {
                // Armed inside its gap: watched for rising through it.
                -self.gap(k) + self.modes.offset[k]
            } else if self.modes.closed[k] {
                self.solution[n + self.contacts[k].normal]
            } else {
                self.gap(k) + self.modes.offset[k]
            };
        }
        let rough = self.modes.rough.len();
        if self.arming.is_some() {
            self.evaluate_arming(t, y);
            let at = count + rough + usize::from(rough > 0);
            let values = &self.arming.as_ref().expect("arming").1;
            for k in 0..count {
                // While armed, the condition falling to 0 disarms; while not, its rising does.
                // A closed contact is held whatever its condition (a walker's stance foot).
                out[at + k] = match (self.modes.closed[k], self.modes.armed[k]) {
                    (true, _) => 1.0,
                    (false, true) => values[k],
                    (false, false) => -values[k],
                };
            }
        }
        if self.modes.rough.is_empty() {
            return Ok(());
        }
        for (j, &k) in self.modes.rough.iter().enumerate() {
            let contact = self.contacts[k];
            let (Some(tangent), Some(mu)) = (contact.grip, contact.friction) else {
                unreachable!("a rough contact has a tangential row")
            };
            let slip = self.modes.slip[k];
            if let (Some(cross), true) = (contact.cross, self.modes.closed[k]) {
                // In space: the cone's room while it sticks. While it slips, the slip
                // velocity along the direction decided at the last jump, above its band: a
                // signed rate, which passes through the band at a stop. Neither ‖γ_T‖² (a
                // double root) nor ‖γ_T‖ (a minimum, not a crossing: a step overshoots the
                // stop to a reversed slip and both ends of it are positive) change sign
                // there. A slip whose direction turns far enough reaches the band without
                // stopping; the jump then aims it again. A slip from rest starts below the
                // band, its guard negative: only a fall through zero fires.
                let (l, c) = (n + tangent, n + cross);
                out[count + j] = if slip == 0.0 {
                    mu * self.solution[n + contact.normal]
                        - crate::linalg::size2(self.solution[l], self.solution[c])
                } else {
                    let band = self.modes.tolerance * self.modes.tangent_speed[k] * OPEN_BAND;
                    let d = self.modes.direction[k];
                    d[0] * self.row_rate(tangent) + d[1] * self.row_rate(cross) - band
                };
                continue;
            }
            out[count + j] = if !self.modes.closed[k] {
                1.0
            } else if slip == 0.0 {
                mu * self.solution[n + contact.normal] - self.solution[n + tangent].abs()
            } else {
                slip * self.row_rate(tangent) + self.modes.slip_offset[k]
            };
        }
        out[count + self.modes.rough.len()] =
            if self.bends.is_empty() { 1.0 } else { self.solvability()? };
        Ok(())
    }

    /// det(A_bent)/det(A) over the kept contact rows, A their Delassus operator and A_bent
    /// the same with the slipping contacts' columns bent by their friction: 1 without
    /// friction, and zero where the slipping contacts' normal forces cease to be determined
    /// (Painlevé's coefficient a = w_N·M⁻¹·(w_N − μ·s·w_T)ᵀ of a single one).
    fn solvability(&mut self) -> Result<f64, FaultKind> {
        let two_sided = self.two_sided();
        let rows: Vec<usize> =
            (0..self.layout.multipliers).filter(|&c| self.kept[c] && !two_sided[c]).collect();
        let mut all = rows.clone();
        all.extend(self.bends.iter().map(|b| b.tangent));
        let (_, a) = self.condensed(&all)?;
        let r = rows.len();
        let plain = DMatrix::from_fn(r, r, |i, j| a[(i, j)]);
        let mut bent = plain.clone();
        for (b, bend) in self.bends.iter().enumerate() {
            let Some(j) = rows.iter().position(|&c| c == bend.normal) else { continue };
            for i in 0..r {
                bent[(i, j)] += bend.factor * a[(i, r + b)];
            }
        }
        let ratio = bent.determinant() / plain.determinant();
        Ok(if ratio.is_finite() { ratio } else { 0.0 })
    }

    /// Decides the modes at the start of a run of tolerance `tolerance`. With `held`, every
    /// contact touching within the closed band (its gap below 100·tol·L) is taken as closed
    /// before the decision, so that its rate is judged
    /// against the closed band (the drift a closed contact has) rather than the open one: a
    /// start that a run reached on a contact (a periodic orbit's section in mid-stance) stays
    /// on it, where the open band would read its drift as flight.
    pub(super) fn begin_contacts(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
        held: bool,
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let n = self.layout.coordinates;
        let count = self.contacts.len();
        self.modes.tolerance = tolerance;
        self.modes.closed = vec![false; count];
        self.modes.impacts = vec![0.0; count];
        self.modes.speed = vec![0.0; count];
        // A run starts afresh: no slip, and the tangential scales its own.
        self.modes.slip = vec![0.0; count];
        self.modes.tangent_speed = vec![0.0; count];
        self.update_kept();
        self.dynamics_at(t, y)?;
        self.evaluate_arming(t, y);
        let size = y[..n].iter().fold(0.0, |s: f64, v| s.max(v.abs()));
        let speed = y[n..].iter().fold(0.0, |s: f64, v| s.max(v.abs()));
        // A start reached on the contacts (held) is judged closed where it touches and rests
        // to half the digits: a start a Newton step moved along a section's chart is off the
        // manifold by the step's square (a walker's stance foot 4e-8 m above the ground and
        // falling at 7e-8 m/s after a step of 3e-4), far outside the run's bands, and it would
        // land at once. Those are put back on their manifold below; a foot leaving (a walker's
        // trailing one, at 0.08 m/s) is not held.
        let mut resting = vec![false; count];
        for k in 0..count {
            let gradient: f64 =
                self.jacobian_row(self.contacts[k].normal).iter().map(|v| v.abs()).sum();
            let length = self.gap(k).abs().max(gradient * size);
            self.modes.length[k] = length;
            let armed = self.arming.as_ref().is_none_or(|(_, values)| values[k] > 0.0);
            self.modes.armed[k] = armed;
            let half = tolerance.sqrt();
            resting[k] = held
                && armed
                && self.gap(k).abs() <= half * length
                && self.normal_rate(k).abs() <= half * gradient * speed;
            // A conditioned contact may start inside its gap: disarmed, or armed below it.
            // Below means inside beyond the touching tolerance: a contact touching within it
            // (a stance foot at a section in mid-stance, its gap rounding's) is touching.
            // So is one leaving, inside by rounding at half the digits: the contact a held start
            // has just lifted from (a rimless wheel's trailing spoke at its landing section).
            let leaving = held && self.gap(k) >= -half * length && self.normal_rate(k) > 0.0;
            let inside = self.gap(k) < -tolerance * length && !resting[k] && !leaving;
            self.modes.below[k] = armed && self.modes.conditioned[k] && inside;
            if !self.modes.conditioned[k] && inside {
                return Err(FaultKind::Penetrating { contact: k, gap: self.gap(k) });
            }
        }
        if held {
            self.modes.closed = resting;
            self.update_kept();
            if self.kept.iter().any(|&k| k) {
                self.project_positions(t, y)?;
                self.project_velocities(t, y)?;
                self.dynamics_at(t, y)?;
            }
        }
        self.contact_jump(t, y, &[])
    }

    /// The jump at (t, y), where the guards `fired` reached zero: the landing contacts' impact,
    /// then the touching contacts at rest closed or opened by their reactions.
    pub(super) fn contact_jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        fired: &[usize],
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let n = self.layout.coordinates;
        let count = self.contacts.len();
        let tol = self.modes.tolerance;
        let rough = self.modes.rough.clone();
        if !rough.is_empty() && fired.contains(&(count + rough.len())) {
            // The slipping contacts' normal forces grew without bound: Painlevé's jam.
            return Err(FaultKind::Painleve {
                contacts: self.slipping_contacts(),
                case: crate::PainleveCase::Jam,
                impact: false,
            });
        }
        self.modes.struck = Struck::None;
        self.dynamics_at(t, y)?;
        let speed = y[n..].iter().fold(0.0, |s: f64, v| s.max(v.abs()));
        for k in 0..count {
            let gradient: f64 =
                self.jacobian_row(self.contacts[k].normal).iter().map(|v| v.abs()).sum();
            let scale = self.modes.speed[k].max(gradient * speed).max(self.modes.impacts[k]);
            self.modes.speed[k] = scale;
            if let (Some(tangent), Some(_)) = (self.contacts[k].grip, self.contacts[k].friction) {
                let rows = std::iter::once(tangent).chain(self.contacts[k].cross);
                let gradient: f64 = rows
                    .map(|t| self.jacobian_row(t).iter().map(|v| v.abs()).sum::<f64>())
                    .fold(0.0, f64::max);
                let rate = self.tangential_rate(k).iter().map(|r| r * r).sum::<f64>().sqrt();
                let scale = self.modes.tangent_speed[k].max(gradient * speed).max(rate);
                self.modes.tangent_speed[k] = scale;
            }
        }
        // Arming: a contact whose condition fell to 0 is disarmed (and opens, if closed); one
        // whose condition rose is armed, below its surface if its gap is negative there; one
        // armed below whose gap rose through 0 is an ordinary open contact from here.
        if self.arming.is_some() {
            self.evaluate_arming(t, y);
            let at = count + rough.len() + usize::from(!rough.is_empty());
            for k in 0..count {
                if fired.contains(&(at + k)) {
                    let armed = !self.modes.armed[k];
                    self.modes.armed[k] = armed;
                    self.modes.below[k] = armed && self.gap(k) < -tol * self.modes.length[k];
                    if !armed {
                        self.modes.below[k] = false;
                    }
                } else if self.modes.below[k] && fired.contains(&k) {
                    self.modes.below[k] = false;
                }
            }
        }
        let before = self.modes.closed.clone();
        let slipped = self.modes.slip.clone();
        // A rough contact whose stick guard fired sticks no more here; one whose slip guard
        // fired is at tangential rest.
        let mut no_stick = vec![false; count];
        let mut stopped = vec![false; count];
        for (j, &k) in rough.iter().enumerate() {
            if fired.contains(&(count + j)) && before[k] {
                if slipped[k] == 0.0 {
                    no_stick[k] = true;
                } else if self.contacts[k].cross.is_none() {
                    stopped[k] = true;
                } else {
                    // In space the guard is the slip along its last direction: it stopped if
                    // its speed is that band's too (twice it: turned by less than 60°);
                    // otherwise its direction turned, and it slips on, aimed anew.
                    let band = tol * self.modes.tangent_speed[k] * OPEN_BAND;
                    let speed = self.tangential_rate(k).iter().map(|r| r * r).sum::<f64>().sqrt();
                    stopped[k] = speed <= 2.0 * band;
                }
            }
        }
        let watched = |modes: &Modes, k: usize| modes.armed[k] && !modes.below[k];
        let touching: Vec<usize> = (0..count)
            .filter(|&k| watched(&self.modes, k))
            .filter(|&k| before[k] || self.gap(k) <= tol * self.modes.length[k])
            .collect();
        let band = |modes: &Modes, k: usize, held: bool| {
            tol * modes.speed[k] * if held { CLOSED_BAND } else { OPEN_BAND }
        };
        let mut struck = vec![false; count];
        let mut settled = vec![false; count];
        let mut landed = vec![false; count];
        // Landed with e = 0: γ⁺ = 0 is the impact law itself where it took an impulse, whatever
        // rounding leaves of it (a walker's light feet make the Delassus operator ill-conditioned,
        // and γ⁺ misses a tight band by a rounding of 1/β times the rates').
        let mut plastic = vec![false; count];
        let mut impulses = vec![0.0; count];
        let mut tangential: Vec<Option<f64>> =
            self.contacts.iter().map(|c| c.grip.map(|_| 0.0)).collect();
        let mut energy = vec![0.0; count];
        let mut rise = false;
        let lands = |this: &Self, k: usize| {
            !before[k] && this.normal_rate(k) < -band(&this.modes, k, false)
        };
        if touching.iter().any(|&k| lands(self, k)) {
            // A landing slower than the rate gained falling through the rounding of the
            // positions is rounding too (a disk whose centre is at 0.2 m bounces in flights
            // shorter than an ulp of it): it settles.
            let free = self.open_accelerations()?;
            let size = y[..n].iter().fold(0.0, |s: f64, v| s.max(v.abs()));
            let rounding: Vec<f64> =
                (0..count).map(|k| self.rounding_rate(k, &free, size)).collect();
            self.dynamics_at(t, y)?;
            let rows = self.rows_of(&touching);
            let (x, a) = self.condensed(&rows.multipliers)?;
            let mut factors = vec![0.0; rows.kinds.len()];
            for (r, &mult) in rows.multipliers.iter().enumerate() {
                let k = rows.owners[r];
                let rate = self.row_rate(mult);
                factors[r] = match rows.kinds[r] {
                    Row::Normal => {
                        // A closed contact's γ is drift: absorbed plastically.
                        let mut e = if before[k] { 0.0 } else { self.contacts[k].restitution };
                        if lands(self, k) {
                            landed[k] = true;
                            // Accumulating impacts: far slower than the contact's own earlier ones.
                            if -rate < tol * self.modes.impacts[k] || -rate < rounding[k] {
                                settled[k] = true;
                                e = 0.0;
                            }
                            self.modes.impacts[k] = self.modes.impacts[k].max(-rate);
                            self.modes.speed[k] = self.modes.speed[k].max(-rate);
                            plastic[k] = e == 0.0;
                        }
                        1.0 + e
                    }
                    Row::Tangent { .. } => 1.0,
                };
            }
            let c: Vec<f64> = rows
                .multipliers
                .iter()
                .zip(&factors)
                .map(|(&mult, factor)| factor * self.row_rate(mult))
                .collect();
            let scale = c.iter().fold(0.0, |s: f64, v| s.max(v.abs()));
            let solution = if rows.owners.iter().any(|&k| self.contacts[k].friction.is_some()) {
                // Coulomb's law on the tangential impulses: every contact at tangential rest
                // after the impact, or slipping whichever way its rate goes.
                let laws = self.coulomb_rows(&rows, |_| None, &vec![false; count]);
                let answer = crate::coulomb::solve(&a, &c, &x, &laws, tol * scale)
                    .map_err(|e| painleve(e, &rows.owners, true))?;
                self.modes.struck = Struck::Coulomb;
                answer.x
            } else {
                let solution = complementarity::solve(&a, &c, &rows.kinds, tol * scale)
                    .map_err(|e| unsolved(e, &rows.owners, true))?;
                let took: Vec<usize> = (0..c.len()).filter(|&r| solution.active[r]).collect();
                self.modes.struck = Struck::Frictionless {
                    rows: took.iter().map(|&r| rows.multipliers[r]).collect(),
                    factors: took.iter().map(|&r| factors[r]).collect(),
                };
                solution.x
            };
            let before_rates = y[n..].to_vec();
            let mut kinetic = 0.0;
            {
                // ½q̇ᵀMq̇ before the impact, M column-major in the outputs.
                let out = &self.dyn_out;
                for i in 0..n {
                    for j in 0..n {
                        kinetic += 0.5 * before_rates[i] * out[j * n + i] * before_rates[j];
                    }
                }
            }
            for i in 0..n {
                y[n + i] += (0..rows.kinds.len()).map(|r| x[(i, r)] * solution[r]).sum::<f64>();
            }
            let mut total = 0.0;
            for (r, &mult) in rows.multipliers.iter().enumerate() {
                let k = rows.owners[r];
                let row = self.jacobian_row(mult);
                let mean: f64 = (0..n).map(|i| row[i] * (before_rates[i] + y[n + i])).sum();
                let work = 0.5 * solution[r] * mean;
                energy[k] += work;
                total += work;
                match rows.kinds[r] {
                    Row::Normal => impulses[k] = solution[r],
                    // In space, the size of the two tangential impulses.
                    Row::Tangent { .. } if self.contacts[k].cross == Some(mult) => {
                        tangential[k] =
                            Some(crate::linalg::size2(tangential[k].unwrap_or(0.0), solution[r]));
                    }
                    Row::Tangent { .. } => tangential[k] = Some(solution[r]),
                }
                if solution[r] != 0.0 {
                    struck[k] = true;
                }
            }
            rise = total > 1e3 * f64::EPSILON * kinetic.max(f64::MIN_POSITIVE);
            self.dynamics_at(t, y)?;
        }
        // The accelerations with every contact open.
        let free = if touching.is_empty() { Vec::new() } else { self.open_accelerations()? };
        let size = y[..n].iter().fold(0.0, |s: f64, v| s.max(v.abs()));
        // The touching contacts at rest: closed where their reactions push. A closed one that
        // an impact separates slower than the floating point of the positions can resolve
        // (the rate gained falling through a few ulps of them, at its acceleration with every
        // contact open) stays: below that, its flights are rounding, not motion.
        let resting: Vec<usize> = touching
            .iter()
            .copied()
            .filter(|&k| {
                let rate = self.normal_rate(k).abs();
                if landed[k] && plastic[k] && impulses[k] > 0.0 {
                    return true;
                }
                if !before[k] || landed[k] {
                    return rate <= band(&self.modes, k, false);
                }
                rate <= band(&self.modes, k, true).max(self.rounding_rate(k, &free, size))
            })
            .collect();
        let mut closed = vec![false; count];
        let mut slip = vec![0.0; count];
        if !resting.is_empty() {
            let rows = self.rows_of(&resting);
            let (moved, a) = self.condensed(&rows.multipliers)?;
            // g̈ = J·q̈ − (γ, stabilised) with every contact open; the scale of its tolerance
            // is that of its terms, since g̈ itself passes through zero where a reaction
            // vanishes (at a lift-off). Where the terms meet inside f (a particle on a sphere
            // in polar coordinates: r̈ = r·φ̇² − g·cos φ is one entry), J·q̈ is that small sum
            // too: the accelerations' own size, through J, stands for the terms then.
            let fastest = free.iter().fold(0.0, |m: f64, a| m.max(a.abs()));
            let mut scale: f64 = 0.0;
            let mut b: Vec<f64> = rows
                .multipliers
                .iter()
                .map(|&c| {
                    let row = self.jacobian_row(c);
                    let (driven, imposed) =
                        ((0..n).map(|i| row[i] * free[i]).sum::<f64>(), self.stabilised(c));
                    let through: f64 = row.iter().map(|v| v.abs()).sum::<f64>() * fastest;
                    scale = scale.max(driven.abs()).max(imposed.abs()).max(through);
                    driven - imposed
                })
                .collect();
            for (r, kind) in rows.kinds.iter().enumerate() {
                let k = rows.owners[r];
                // Twice the solver's tolerance: a row whose w is within it counts as grazing,
                // which the solver may take into the active set again.
                if *kind == Row::Normal && before[k] && fired.contains(&k) {
                    b[r] += 2.0 * tol * scale;
                }
            }
            if rows.owners.iter().any(|&k| self.contacts[k].friction.is_some()) {
                let modes = &self.modes;
                let sliding = |k: usize| {
                    let rate = self.tangential_rate(k);
                    let size = rate.iter().map(|r| r * r).sum::<f64>().sqrt();
                    let held = before[k] && slipped[k] == 0.0 && !landed[k];
                    let band =
                        tol * modes.tangent_speed[k] * if held { CLOSED_BAND } else { OPEN_BAND };
                    let direction = match rate[..] {
                        [v] => [v.signum(), 0.0],
                        [v, w] => [v / size, w / size],
                        _ => return None,
                    };
                    (!stopped[k] && size > band).then_some(direction)
                };
                let laws = self.coulomb_rows(&rows, sliding, &no_stick);
                let answer = crate::coulomb::solve(&a, &b, &moved, &laws, tol * scale)
                    .map_err(|e| painleve(e, &rows.owners, false))?;
                for (law, mode) in laws.iter().zip(&answer.modes) {
                    let k = rows.owners[law.normal];
                    closed[k] = mode.is_closed();
                    match *mode {
                        crate::coulomb::Mode::Slip(s) => slip[k] = s,
                        crate::coulomb::Mode::Slide(d) => {
                            slip[k] = 1.0;
                            self.modes.direction[k] = d;
                        }
                        _ => {}
                    }
                }
            } else {
                let solution = complementarity::solve(&a, &b, &rows.kinds, tol * scale)
                    .map_err(|e| unsolved(e, &rows.owners, false))?;
                for (r, kind) in rows.kinds.iter().enumerate() {
                    if *kind == Row::Normal && solution.active[r] {
                        closed[rows.owners[r]] = true;
                    }
                }
            }
        }
        // A contact that opened here is armed by its condition's sign now (it was held whatever
        // its condition while closed).
        if let Some((_, values)) = &self.arming {
            for k in 0..count {
                if before[k] && !closed[k] && self.modes.conditioned[k] {
                    self.modes.armed[k] = values[k] > 0.0;
                    self.modes.below[k] = false;
                }
            }
        }
        self.modes.closed = closed.clone();
        self.modes.slip = slip.clone();
        self.update_kept();
        self.drop_redundant_grips();
        // The state onto the new mode's constraints: the closed contacts' gaps and rates (and
        // the two-sided constraints') to zero, from the drift they had.
        if self.kept.iter().any(|&k| k) {
            self.project_positions(t, y)?;
            self.project_velocities(t, y)?;
            self.dynamics_at(t, y)?;
        }
        // An open contact's guard must start positive to see it land: one that opened at
        // g ≤ 0 (a closed contact's drift) could otherwise fall back within a step unseen.
        for k in 0..count {
            let gap = self.gap(k);
            self.modes.offset[k] = if gap > 0.0 || closed[k] || self.modes.below[k] {
                0.0
            } else {
                -gap * (1.0 + 4.0 * f64::EPSILON) + f64::MIN_POSITIVE
            };
        }
        // A slipping contact's guard must start positive too, from a slip that may have begun
        // at a tangential rate of rounding's size, or of the other sign.
        for k in 0..count {
            self.modes.slip_offset[k] = match (slip[k], self.contacts[k].grip) {
                _ if self.contacts[k].cross.is_some() => 0.0,
                (s, Some(tangent)) if s != 0.0 => {
                    let along = s * self.row_rate(tangent);
                    if along > 0.0 {
                        0.0
                    } else {
                        -along * (1.0 + 4.0 * f64::EPSILON) + f64::MIN_POSITIVE
                    }
                }
                _ => 0.0,
            };
        }
        let mut events = Vec::new();
        for k in 0..count {
            let kind = if landed[k] && !before[k] {
                Some(if settled[k] { ModeChange::Settled } else { ModeChange::Impact })
            } else if before[k] && !closed[k] {
                Some(ModeChange::LiftOff)
            } else if !before[k] && closed[k] {
                Some(ModeChange::Closed)
            } else if struck[k] {
                Some(ModeChange::Struck)
            } else {
                None
            };
            if let Some(kind) = kind {
                events.push(ModeEvent {
                    time: t,
                    contact: k,
                    kind,
                    closed: closed[k],
                    impulse: impulses[k],
                    tangential: tangential[k],
                    energy_change: energy[k],
                    slip: slip[k],
                    energy_rise: rise && (struck[k] || landed[k]),
                });
            }
            // A rough contact's stick or slip, where it changed: from slipping (or open) to
            // sticking, or to a slip (from sticking, open, or the other way).
            // In space a slip that stopped and slips again (its direction new) is a change too.
            let was = if before[k] { Some(slipped[k]) } else { None };
            let again = stopped[k] && slip[k] != 0.0 && self.contacts[k].cross.is_some();
            if self.contacts[k].friction.is_some() && closed[k] && (was != Some(slip[k]) || again) {
                events.push(ModeEvent {
                    time: t,
                    contact: k,
                    kind: if slip[k] == 0.0 { ModeChange::Sticks } else { ModeChange::Slips },
                    closed: true,
                    impulse: 0.0,
                    tangential: None,
                    energy_change: 0.0,
                    slip: slip[k],
                    energy_rise: false,
                });
            }
        }
        Ok(events)
    }
}

impl Mechanical {
    /// q̈ with every contact open, at the last evaluation.
    fn open_accelerations(&mut self) -> Result<Vec<f64>, FaultKind> {
        let two_sided = self.two_sided();
        let kept = std::mem::replace(&mut self.kept, two_sided);
        let solved = self.solve_dynamics();
        self.kept = kept;
        solved?;
        self.solved = None;
        Ok(self.solution[..self.layout.coordinates].to_vec())
    }

    /// The rate contact `k` gains falling through the depth rounding moves it by (δ, 64 ulps
    /// of the positions of size `size` times its gradient) at its acceleration with every
    /// contact open (`free`): √(2·a·δ). Below it, its flights and landings are rounding.
    fn rounding_rate(&self, k: usize, free: &[f64], size: f64) -> f64 {
        let c = self.contacts[k].normal;
        let row = self.jacobian_row(c);
        let falling =
            row.iter().zip(free).map(|(j, a)| j * a).sum::<f64>().abs() + self.stabilised(c).abs();
        let gradient: f64 = row.iter().map(|v| v.abs()).sum();
        let depth = ROUNDING * f64::EPSILON * gradient * size;
        (2.0 * falling * depth).sqrt()
    }

    /// The laws of the contacts of `rows` for [`crate::coulomb::solve`]: a rough contact's
    /// slip sign from `sliding` (`None` at tangential rest), and `no_stick` for those whose
    /// stick ended here.
    fn coulomb_rows(
        &self,
        rows: &Rows,
        sliding: impl Fn(usize) -> Option<[f64; 2]>,
        no_stick: &[bool],
    ) -> Vec<crate::coulomb::ContactRows> {
        use crate::coulomb::{ContactRows, Law};
        let mut laws = Vec::new();
        for (r, kind) in rows.kinds.iter().enumerate() {
            if *kind != Row::Normal {
                continue;
            }
            let k = rows.owners[r];
            let contact = self.contacts[k];
            let tangent = contact.grip.map(|_| r + 1);
            let cross = contact.cross.map(|_| r + 2);
            let law = match (contact.grip, contact.friction) {
                (Some(_), Some(mu)) if cross.is_some() => Law::Cone { mu, sliding: sliding(k) },
                (Some(_), Some(mu)) => Law::Coulomb { mu, sliding: sliding(k).map(|d| d[0]) },
                (Some(_), None) => Law::Grip,
                (None, _) => Law::Frictionless,
            };
            laws.push(ContactRows { normal: r, tangent, cross, law, no_stick: no_stick[k] });
        }
        laws
    }
}

/// The fault of a contact problem with friction that has no one answer: Painlevé's cases
/// (none, or several motions), its rows named by the contacts that own them (`owners`).
fn painleve(trouble: crate::coulomb::Trouble, owners: &[usize], impact: bool) -> FaultKind {
    use crate::coulomb::Trouble;
    let mut contacts = owners.to_vec();
    contacts.sort_unstable();
    contacts.dedup();
    let case = match trouble {
        Trouble::None => crate::PainleveCase::Inconsistent,
        Trouble::Several(_) => crate::PainleveCase::Indeterminate,
        Trouble::TooMany => {
            return FaultKind::ContactsUnsolved {
                contacts,
                impact,
                why: "more than six rough contacts at tangential rest touch at once",
            }
        }
        Trouble::Unsettled => {
            return FaultKind::ContactsUnsolved {
                contacts,
                impact,
                why: "the directions of several contacts slipping in space from rest did not \
                      settle: no direction of each was found that its slip and its friction share",
            }
        }
    };
    FaultKind::Painleve { contacts, case, impact }
}

/// The fault of a complementarity problem left unsolved, its rows named by the contacts that
/// own them (`owners`).
fn unsolved(e: complementarity::Unsolved, owners: &[usize], impact: bool) -> FaultKind {
    use complementarity::Unsolved;
    let why = match e {
        Unsolved::Inconsistent(i) => {
            return inconsistent(i.rows.iter().map(|&r| owners[r]).collect(), impact)
        }
        Unsolved::NonFinite { .. } => {
            return FaultKind::NonFinite { at: crate::NonFiniteAt::System };
        }
        Unsolved::Malformed { reason } => reason,
        Unsolved::TooLarge { .. } => "more than ten gripping contacts touch at once",
        Unsolved::Stalled { .. } => {
            "Lemke's pivoting stalled on a badly conditioned or degenerate problem"
        }
    };
    let mut contacts = owners.to_vec();
    contacts.sort_unstable();
    contacts.dedup();
    FaultKind::ContactsUnsolved { contacts, impact, why }
}

fn inconsistent(mut contacts: Vec<usize>, impact: bool) -> FaultKind {
    contacts.sort_unstable();
    contacts.dedup();
    FaultKind::ContactsInconsistent { contacts, impact }
}
