//! The integrators' tests in one binary (one link instead of three), a module each, with the
//! closed-form oscillator they share.

mod auto;
mod contacts;
mod integrators;
mod oscillator;
mod radau;
