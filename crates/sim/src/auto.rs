//! `auto`: an explicit method while the problem is not stiff, radau while it is, switching
//! between them as the problem changes character, in the manner of LSODA (Petzold, 1983).
//!
//! The explicit side is DOP853, whose steps are the cheapest at the tolerances this project
//! runs at. It moves to radau when Hairer's stiffness test, which DOP853 makes on every
//! accepted step ([`Adaptive::stiff`]), fires on `STIFF_STEPS` steps with no run of
//! `CALM_STEPS` quiet ones between them: the step is then held down by stability, not by
//! accuracy. Radau moves back when its own steps, set by accuracy, have stayed within what
//! DOP853 could take stably for `CALM_RADAU_STEPS` steps in a row: h·ρ(J) below the same bound
//! the test uses, with ρ(J) the spectral radius of the Jacobian radau last evaluated. Both
//! counts make the switch lag the change a little, so the method does not flip back and forth
//! on a problem at the edge.
//!
//! Each side keeps its own dense output; the one that took the last step interpolates inside
//! it, so events, stop conditions and samples see one continuous solution across a switch.

use crate::erk::{Adaptive, Pair};
use crate::radau::Radau;
use crate::stepper::{Dense, Stepper};
use crate::{spectrum, Components, FaultKind, Method, Problem};

/// The explicit side.
pub(crate) const EXPLICIT_PAIR: Pair = Pair::Dop853;
/// The methods of the two sides, explicit first, as a run's segments name them.
pub(crate) const SIDES: [Method; 2] = [Method::Dop853, Method::Radau];
/// Steps limited by stability that make the explicit side stiff (Hairer's DOP853 uses 15).
const STIFF_STEPS: usize = 15;
/// Steps in a row not limited by stability that clear that count.
const CALM_STEPS: usize = 6;
/// Radau steps in a row within the explicit stability limit before moving back.
const CALM_RADAU_STEPS: usize = 15;

pub(crate) struct Auto {
    explicit: Adaptive,
    radau: Radau,
    on_radau: bool,
    /// The side that took the last step, whose dense output covers it.
    last_by_radau: bool,
    stiff_count: usize,
    calm_count: usize,
    /// Radau's steps in a row that the explicit side could have taken stably.
    within_limit: usize,
    /// ρ(J) of radau's latest Jacobian, and how many Jacobians radau had evaluated then.
    radius: f64,
    jacobians_seen: usize,
    switches: Vec<f64>,
}

impl Auto {
    pub fn new(dim: usize, tolerance: f64) -> Self {
        Auto {
            explicit: Adaptive::for_tolerance(EXPLICIT_PAIR, dim, tolerance),
            radau: Radau::new(Components::ordinary(dim), tolerance),
            on_radau: false,
            last_by_radau: false,
            stiff_count: 0,
            calm_count: 0,
            within_limit: 0,
            radius: f64::INFINITY,
            jacobians_seen: 0,
            switches: Vec::new(),
        }
    }

    fn explicit_step(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        let before = self.explicit.stiff;
        let t1 = self.explicit.advance(p, t, y, t_end)?;
        self.last_by_radau = false;
        if self.explicit.stiff > before {
            self.stiff_count += 1;
            self.calm_count = 0;
        } else {
            self.calm_count += 1;
            if self.calm_count >= CALM_STEPS {
                self.stiff_count = 0;
            }
        }
        if self.stiff_count >= STIFF_STEPS && t1 < t_end {
            self.on_radau = true;
            self.stiff_count = 0;
            self.calm_count = 0;
            self.within_limit = 0;
            self.radius = f64::INFINITY;
            self.radau.restart(self.explicit.last_step());
            self.switches.push(t1);
        }
        Ok(t1)
    }

    fn radau_step(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        let t1 = self.radau.advance(p, t, y, t_end)?;
        self.last_by_radau = true;
        if self.radau.jacobians() != self.jacobians_seen {
            self.jacobians_seen = self.radau.jacobians();
            let n = y.len();
            self.radius =
                spectrum::spectral_radius(self.radau.jacobian_matrix(), n).unwrap_or(f64::INFINITY);
        }
        let h = self.radau.last_step().unwrap_or(0.0);
        if h * self.radius <= EXPLICIT_PAIR.stiffness_bound() {
            self.within_limit += 1;
        } else {
            self.within_limit = 0;
        }
        if self.within_limit >= CALM_RADAU_STEPS && t1 < t_end {
            self.on_radau = false;
            self.within_limit = 0;
            self.explicit.restart(h);
            self.switches.push(t1);
        }
        Ok(t1)
    }
}

impl Dense for Auto {
    fn interpolate(&mut self, p: &mut dyn Problem, t: f64, out: &mut [f64]) {
        if self.last_by_radau {
            self.radau.interpolate(p, t, out)
        } else {
            self.explicit.interpolate(p, t, out)
        }
    }

    fn after_switch(&mut self) {
        self.explicit.after_switch();
        self.radau.after_switch();
    }

    fn after_jump(&mut self) {
        self.explicit.after_jump();
        self.radau.after_jump();
    }
}

impl Stepper for Auto {
    fn advance(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        if self.on_radau {
            self.radau_step(p, t, y, t_end)
        } else {
            self.explicit_step(p, t, y, t_end)
        }
    }

    fn evaluations(&self) -> usize {
        self.explicit.evaluations() + self.radau.evaluations()
    }

    fn rejected(&self) -> usize {
        self.explicit.rejected + self.radau.rejected()
    }

    fn stiff_steps(&self) -> usize {
        self.explicit.stiff
    }

    fn jacobians(&self) -> usize {
        self.radau.jacobians()
    }

    fn factorizations(&self) -> usize {
        self.radau.factorizations()
    }

    fn switches(&self) -> &[f64] {
        &self.switches
    }
}
