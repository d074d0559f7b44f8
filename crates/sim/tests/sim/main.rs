//! The integrators' tests and the contact problems' solver's in one binary (one link instead of
//! five), a module each, with the closed-form oscillator the integrators share.

mod auto;
mod complementarity;
mod contacts;
mod integrators;
mod oscillator;
mod radau;
