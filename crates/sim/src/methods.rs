//! The method table: one entry per integrator, holding every fact about it that the rest of
//! the house asks (its names, the form of the problem it integrates, what it can do) and the
//! constructor of its stepper. A method is added here and in the file of its stepper; the
//! driver, the lockstep, the engine and the front ends read the entry and name no method.

use nalgebra::Complex;

use crate::auto::Auto;
use crate::erk::{stability_radius, Adaptive, Pair, Rk4, Tableau, RK4_TABLEAU};
use crate::gauss::Gauss;
use crate::radau::Radau;
use crate::run::Settings;
use crate::stepper::Stepper;
use crate::{Components, Problem};

/// An integrator: a handle into [`TABLE`], whose entry at its index says what it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Rk4,
    Bs3,
    Dopri5,
    Dop853,
    Midpoint,
    Gauss,
    Radau,
    Auto,
}

/// The form of the equations a method integrates, which the engine builds the problem in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// y = (q, q̇), M·q̈ = f solved for the accelerations at each evaluation, constraints kept
    /// with multipliers solved with the augmented system and Baumgarte stabilisation.
    Physical,
    /// y = (q, p), the canonical variables a symplectic method conserves the structure of.
    /// The augmented system has no counterpart there: no constraints kept with multipliers.
    Canonical,
    /// As [`Form::Physical`] without constraints kept with multipliers; with them, the
    /// differential–algebraic system of index 3 in (q, q̇, q̈, λ), the constraints as they are
    /// (see [`crate::Components`]).
    Algebraic,
}

/// When a method asks for the Jacobian of the right-hand side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Jacobian {
    /// Never.
    Unused,
    /// For the Newton iteration of every step: its exact partials pay to lower before the run.
    Newton,
    /// Only once the method turns implicit partway through a run (as `auto` does when the
    /// scene turns stiff): lowered then, on demand, since most runs never ask.
    OnSwitch,
}

/// What an explicit method's stability region is read from, and whether the lockstep takes it.
#[derive(Clone, Copy)]
pub(crate) enum Explicit {
    /// A fixed-step method of this tableau.
    Fixed(Tableau),
    /// An adaptive pair: its propagating method's tableau, and several runs stepped at once.
    Pair(Pair),
}

/// One method's entry in the table.
pub struct Entry {
    pub method: Method,
    /// The name runs, scenes and outputs know it by.
    pub name: &'static str,
    /// Other names accepted for it.
    pub aliases: &'static [&'static str],
    /// What it is, in one line, as `--help` lists it.
    pub summary: &'static str,
    pub form: Form,
    /// Whether it controls its step by an error estimate (taking a tolerance) rather than
    /// stepping at a fixed step (taking the step).
    pub adaptive: bool,
    /// Whether its map of the state is symplectic, so that the energy error stays bounded.
    pub symplectic: bool,
    pub jacobian: Jacobian,
    /// Whether it interpolates inside a step by a continuous extension of its own order;
    /// otherwise by the cubic Hermite of the step's ends.
    pub dense_output: bool,
    /// Whether a run of it carries on through the jumps of one-sided contacts (guards located
    /// on its dense output, the mode switched, the method restarted with
    /// `Dense::after_switch`): the methods of the physical form, `auto` with them, and radau
    /// on the differential–algebraic form (`Constrained`, whose open contacts' rows are
    /// 0 = λ, its accelerations and multipliers solved anew after each jump). The canonical
    /// form keeps no multipliers.
    pub contacts: bool,
    /// For an explicit method, what limits its step's stability; `None` for implicit ones.
    pub(crate) explicit: Option<Explicit>,
    /// The methods a switching method runs by turns, starting with the first and changing at
    /// each switch its stepper reports; empty for one that runs alone.
    pub(crate) sides: &'static [Method],
    /// Its stepper for a run by `settings` of a problem of this size and structure.
    pub(crate) stepper: fn(&Settings, &dyn Problem) -> Box<dyn Stepper>,
}

/// Every method, in the order of the enum.
pub static TABLE: [Entry; 8] = [
    Entry {
        method: Method::Rk4,
        name: "rk4",
        aliases: &[],
        summary: "Classic Runge–Kutta, fixed step",
        form: Form::Physical,
        adaptive: false,
        symplectic: false,
        jacobian: Jacobian::Unused,
        dense_output: false,
        contacts: true,
        explicit: Some(Explicit::Fixed(RK4_TABLEAU)),
        sides: &[],
        stepper: |s, p| Box::new(Rk4::new(p.dim(), s.step)),
    },
    Entry {
        method: Method::Bs3,
        name: "bs3",
        aliases: &["rk23"],
        summary: "Bogacki–Shampine 3(2), adaptive",
        form: Form::Physical,
        adaptive: true,
        symplectic: false,
        jacobian: Jacobian::Unused,
        dense_output: true,
        contacts: true,
        explicit: Some(Explicit::Pair(Pair::Bs3)),
        sides: &[],
        stepper: |s, p| Box::new(Adaptive::for_tolerance(Pair::Bs3, p.dim(), s.tolerance)),
    },
    Entry {
        method: Method::Dopri5,
        name: "dopri5",
        aliases: &["rk45"],
        summary: "Dormand–Prince 5(4), adaptive",
        form: Form::Physical,
        adaptive: true,
        symplectic: false,
        jacobian: Jacobian::Unused,
        dense_output: true,
        contacts: true,
        explicit: Some(Explicit::Pair(Pair::Dopri5)),
        sides: &[],
        stepper: |s, p| Box::new(Adaptive::for_tolerance(Pair::Dopri5, p.dim(), s.tolerance)),
    },
    Entry {
        method: Method::Dop853,
        name: "dop853",
        aliases: &[],
        summary: "Dormand–Prince 8(5,3), adaptive",
        form: Form::Physical,
        adaptive: true,
        symplectic: false,
        jacobian: Jacobian::Unused,
        dense_output: true,
        contacts: true,
        explicit: Some(Explicit::Pair(Pair::Dop853)),
        sides: &[],
        stepper: |s, p| Box::new(Adaptive::for_tolerance(Pair::Dop853, p.dim(), s.tolerance)),
    },
    Entry {
        method: Method::Midpoint,
        name: "midpoint",
        aliases: &[],
        summary: "Implicit midpoint rule, fixed step, symplectic",
        form: Form::Canonical,
        adaptive: false,
        symplectic: true,
        jacobian: Jacobian::Newton,
        dense_output: false,
        contacts: false,
        explicit: None,
        sides: &[],
        stepper: |s, p| Box::new(Gauss::new(1, p.dim(), s.step)),
    },
    Entry {
        method: Method::Gauss,
        name: "gauss",
        aliases: &["gauss4"],
        summary: "Two-stage Gauss–Legendre (order 4), fixed step, symplectic",
        form: Form::Canonical,
        adaptive: false,
        symplectic: true,
        jacobian: Jacobian::Newton,
        dense_output: false,
        contacts: false,
        explicit: None,
        sides: &[],
        stepper: |s, p| Box::new(Gauss::new(2, p.dim(), s.step)),
    },
    Entry {
        method: Method::Radau,
        name: "radau",
        aliases: &["radau5"],
        summary: "Radau IIA (order 5), adaptive and implicit: stiff scenes, and kept \
                  constraints as they are",
        form: Form::Algebraic,
        adaptive: true,
        symplectic: false,
        jacobian: Jacobian::Newton,
        dense_output: true,
        contacts: true,
        explicit: None,
        sides: &[],
        stepper: |s, p| Box::new(Radau::new(p.components(), s.tolerance)),
    },
    Entry {
        method: Method::Auto,
        name: "auto",
        aliases: &[],
        summary: "DOP853 while the scene is not stiff, radau while it is, switching as it \
                  changes",
        form: Form::Physical,
        adaptive: true,
        symplectic: false,
        jacobian: Jacobian::OnSwitch,
        dense_output: true,
        contacts: true,
        explicit: None,
        sides: &crate::auto::SIDES,
        stepper: |s, p| Box::new(Auto::new(p.dim(), s.tolerance)),
    },
];

/// The names of the methods, in the order of the table.
const fn names() -> [&'static str; TABLE.len()] {
    let mut names = [""; TABLE.len()];
    let mut k = 0;
    while k < TABLE.len() {
        names[k] = TABLE[k].name;
        k += 1;
    }
    names
}

impl Method {
    pub const NAMES: [&'static str; TABLE.len()] = names();

    /// The method a run takes when neither the scene nor the front end names one.
    pub const DEFAULT: Method = Method::Dop853;

    /// Every method, in the order of the table.
    pub fn all() -> impl Iterator<Item = Method> {
        TABLE.iter().map(|e| e.method)
    }

    /// The method of this name or alias.
    pub fn from_name(name: &str) -> Option<Method> {
        TABLE.iter().find(|e| e.name == name || e.aliases.contains(&name)).map(|e| e.method)
    }

    /// Its entry in the table.
    pub fn entry(self) -> &'static Entry {
        &TABLE[self as usize]
    }

    pub fn name(self) -> &'static str {
        self.entry().name
    }

    pub fn form(self) -> Form {
        self.entry().form
    }

    pub fn jacobian(self) -> Jacobian {
        self.entry().jacobian
    }

    pub fn is_adaptive(self) -> bool {
        self.entry().adaptive
    }

    /// Whether the method is symplectic, and so wants canonical variables.
    pub fn is_symplectic(self) -> bool {
        self.entry().symplectic
    }

    /// Whether the method solves implicit equations with the Jacobian of the right-hand side,
    /// so that lowering the partials for the exact one pays.
    pub fn uses_jacobian(self) -> bool {
        self.jacobian() != Jacobian::Unused
    }

    /// Whether the method is explicit, and so has a stability limit on its step.
    pub fn is_explicit(self) -> bool {
        self.entry().explicit.is_some()
    }

    /// The largest step an explicit method stays stable at for a mode of eigenvalue λ: the
    /// radius of its stability region along λ's direction over |λ| (on the negative real axis
    /// 2.785 for rk4, 3.31 for dopri5, 6.0 for dop853). `None` for implicit methods, which
    /// `auto` is on the stiff side.
    pub fn stable_step(self, eigenvalue: Complex<f64>) -> Option<f64> {
        let tableau = match self.entry().explicit? {
            Explicit::Fixed(tableau) => tableau,
            Explicit::Pair(pair) => pair.tableau(),
        };
        let size = eigenvalue.norm();
        if !(size > 0.0 && size.is_finite()) {
            return Some(f64::INFINITY);
        }
        Some(stability_radius(tableau, eigenvalue / size) / size)
    }

    /// Whether the method can integrate constraints kept with multipliers. Those are solved
    /// with the augmented system on (q, q̇), which the symplectic methods, working in canonical
    /// variables (q, p), do not have.
    pub fn handles_multipliers(self) -> bool {
        self.form() != Form::Canonical
    }

    /// Whether a run of the method carries on through contacts opening, closing and landing
    /// (see [`Entry::contacts`]).
    pub fn handles_contacts(self) -> bool {
        self.entry().contacts
    }

    /// Whether the method integrates differential–algebraic problems (see
    /// [`crate::Components`]); it then takes constraints kept with multipliers as they are,
    /// with no stabilisation.
    pub fn handles_algebraic(self) -> bool {
        self.form() == Form::Algebraic
    }

    /// The adaptive explicit pair the lockstep steps runs of this method with, if it does.
    pub(crate) fn lockstep_pair(self) -> Option<Pair> {
        match self.entry().explicit? {
            Explicit::Pair(pair) => Some(pair),
            Explicit::Fixed(_) => None,
        }
    }

    /// The method's stepper for a run by `settings` of `problem`'s size and structure.
    pub(crate) fn stepper(self, settings: &Settings, problem: &dyn Problem) -> Box<dyn Stepper> {
        assert!(
            self.handles_algebraic() || problem.components() == Components::ordinary(problem.dim()),
            "{} integrates ordinary differential equations only",
            self.name()
        );
        (self.entry().stepper)(settings, problem)
    }

    /// The methods it runs by turns, switching at each of its stepper's switches; empty for a
    /// method that runs alone.
    pub fn sides(self) -> &'static [Method] {
        self.entry().sides
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_entry_sits_at_its_methods_index_and_every_name_is_one_methods() {
        for (k, entry) in TABLE.iter().enumerate() {
            assert_eq!(entry.method as usize, k, "{}", entry.name);
            assert_eq!(Method::from_name(entry.name), Some(entry.method));
            for alias in entry.aliases {
                assert_eq!(Method::from_name(alias), Some(entry.method), "{alias}");
            }
        }
        let mut names: Vec<&str> = TABLE
            .iter()
            .flat_map(|e| std::iter::once(e.name).chain(e.aliases.iter().copied()))
            .collect();
        let count = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), count, "a name given to two methods");
    }

    #[test]
    fn the_facts_of_an_entry_agree_with_one_another() {
        for entry in &TABLE {
            let m = entry.method;
            // A symplectic map is one of canonical variables, and a canonical form is there
            // for one; the lockstep takes adaptive pairs only.
            assert_eq!(entry.symplectic, entry.form == Form::Canonical, "{}", entry.name);
            if m.lockstep_pair().is_some() {
                assert!(entry.adaptive, "{}", entry.name);
            }
            assert!(!(m.is_explicit() && m.uses_jacobian()), "{}", entry.name);
            // Contacts are kept multipliers whose modes jump: never in canonical variables.
            assert!(!entry.contacts || m.handles_multipliers(), "{}", entry.name);
            // A switching method runs each of its sides in the form it integrates.
            for side in entry.sides {
                assert!(side.sides().is_empty() && side.handles_multipliers(), "{}", entry.name);
            }
        }
        assert_eq!(Method::Auto.sides()[0].lockstep_pair(), Some(crate::auto::EXPLICIT_PAIR));
    }
}
