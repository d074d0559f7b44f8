//! The integrators' tests and the contact problems' solver's in one binary (one link instead of
//! four), a module each, with the closed-form oscillator the integrators share.

mod auto;
mod complementarity;
mod integrators;
mod oscillator;
mod radau;
