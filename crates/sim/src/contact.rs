//! One-sided contacts among a problem's kept constraints, and the record of the jumps of
//! their modes (landings, lift-offs, settling) that a run keeps.

/// A one-sided contact among a problem's kept constraints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// The multiplier whose row is the contact's gap g(q, t) ≥ 0 (position-stabilised: its Φ
    /// slot is g, its Φ̇ slot the normal rate γ = ġ).
    pub normal: usize,
    /// The multiplier of its grip row, if it grips: a velocity row
    /// ([`crate::Stabilisation::Velocity`], its Φ slot the tangential rate), held at zero with
    /// a free multiplier while the contact is closed, and given a tangential impulse at landing.
    pub grip: Option<usize>,
    /// A rough contact in space: the multiplier of its second tangential row (a velocity row
    /// as its grip's). Its friction is then the exact cone's: −μ·λ·γ_T/‖γ_T‖ while it slips,
    /// ‖λ_T‖ < μ·λ while it sticks, over the two rows.
    pub cross: Option<usize>,
    /// Newton's coefficient e ∈ [0, 1], on the normal rate.
    pub restitution: f64,
    /// Coulomb's coefficient μ ≥ 0 on its tangential row (`grip`'s multiplier), which it then
    /// holds only while it sticks (|λ_T| < μ·λ); `None` for a frictionless contact or a grip.
    pub friction: Option<f64>,
}

/// What happened to a contact at a jump of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeChange {
    /// It landed (g = 0 with γ < 0) and took an impulse by Newton's law; it is closed after
    /// if it stayed in touch (γ⁺ = 0 and a pushing reaction), else it bounced off.
    Impact,
    /// It landed so slowly against its own earlier impacts that its impacts accumulate (a
    /// bouncing ball's infinitely many before a finite time): the impact was made plastic
    /// (e = 0) and the contact closed, cutting the rest of the series' tail.
    Settled,
    /// It closed without an impact: touching at rest (g = 0, γ = 0) with a pushing reaction.
    Closed,
    /// It opened: its reaction fell to zero (or an impulse elsewhere separated it).
    LiftOff,
    /// Another contact's impact gave it an impulse while it stayed closed.
    Struck,
    /// A rough contact, closed, began to stick: its slip stopped and its cone holds it.
    Sticks,
    /// A rough contact, closed, began to slip (its tangential force reached μ·λ) or slips
    /// the other way: the event's `slip` says which.
    Slips,
}

/// A change of mode, as a run records it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModeEvent {
    /// When it happened: a jump's time, or the start's.
    pub time: f64,
    /// The index of the contact in the problem's list.
    pub contact: usize,
    /// What happened to it.
    pub kind: ModeChange,
    /// Whether the contact is closed after the event.
    pub closed: bool,
    /// The normal impulse Λ ≥ 0 it took (0 without an impact).
    pub impulse: f64,
    /// The tangential impulse of its grip, if it grips (in space, the size of its two).
    pub tangential: Option<f64>,
    /// The kinetic energy ½q̇ᵀMq̇ its impulses changed: the work Λ·(γ⁻ + γ⁺)/2 of its rows
    /// (normal and grip). The changes of an impact's contacts add up to the impact's.
    pub energy_change: f64,
    /// A rough contact's slip after the event: ±1 the sign of its tangential rate while it
    /// slips (1 in space, whichever way it slips), 0 while it sticks (and for a contact
    /// without friction, or open).
    pub slip: f64,
    /// Whether the impact this event was part of raised the kinetic energy beyond rounding,
    /// as Newton's law can with unequal restitutions across simultaneous contacts (Glocker):
    /// reported, not hidden.
    pub energy_rise: bool,
}
