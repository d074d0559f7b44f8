//! The model of a scene: what its statements mean, as expressions in one [`cas::Pool`].
//!
//! `resolve` turns the spanned AST from `lang` into a [`Model`]: parameters, coordinates,
//! bodies placed as functions of the coordinates, constraints, forces, and the `show` and
//! `expect` items, with every name checked and every mistake reported with its span. This crate
//! knows what a scene says; deriving equations from it is the job of `mechanics`.

pub mod kinematics;
mod parameters;
mod resolve;
pub mod units;
mod value;

pub use parameters::{Given, ParameterError, ParameterValues};
pub use resolve::{
    closest, constant_value, dimension_errors, resolutions_on_this_thread, resolve, resolve_with,
    time_setting, Scope,
};
pub use value::Value;

use cas::{ExprId, Pool, SymId};
use lang::{Ident, Span, Unit};

/// What [`resolve_with`] checks besides names and meaning.
#[derive(Clone, Copy, Debug, Default)]
pub struct Checks {
    /// That every sum, equation and energy term has one dimension.
    pub units: bool,
    /// Let an input stand in a constraint: the front end puts a law of t and the coordinates
    /// (or the input's declared value) in its place before anything is derived, as a run does.
    /// Otherwise such a constraint is an error, since deriving it would differentiate the
    /// input in time.
    pub inputs_in_constraints: bool,
}

/// A named constant: symbolic in every derivation, its value used only for numbers.
#[derive(Clone, Debug)]
pub struct Param {
    pub name: String,
    pub sym: SymId,
    /// In terms of earlier parameters; `deg` values are already in radians.
    pub value: Option<ExprId>,
    pub unit: Option<Unit>,
    pub span: Span,
}

/// An exogenous signal u(t) (`input F = 0 N`): a symbol of its own in the derivation, which
/// keeps f(q, q̇, u, t), but not a constant of the scene: `--set` does not take it, and numbers
/// fill its slot (after the parameters') with `value` when nothing drives it. It stands only
/// where no time derivative is taken of it (forces, torques, potentials, dissipation), since
/// its rate is not known.
#[derive(Clone, Debug)]
pub struct Input {
    pub name: String,
    pub sym: SymId,
    /// The value when nothing drives it, in terms of the parameters, in SI.
    pub value: ExprId,
    pub unit: Option<Unit>,
    pub span: Span,
}

/// An `output NAME: EXPR` line: a named measured quantity of the state, the inputs and time,
/// whose gradients give the rows of C and D.
#[derive(Clone, Debug)]
pub struct Output {
    pub name: String,
    pub value: ExprId,
    pub span: Span,
}

/// A generalized coordinate with its initial value and rate.
#[derive(Clone, Debug)]
pub struct Coord {
    pub name: String,
    pub sym: SymId,
    pub initial: ExprId,
    pub initial_rate: ExprId,
    /// Whether the scene gave an initial value or rate (the defaults are 0).
    pub initial_given: bool,
    /// Whether the scene gave the initial rate; one it did not give may be set by the
    /// velocity constraints at the start.
    pub initial_rate_given: bool,
    /// Whether the start position may be solved from the kept position constraints: the
    /// scene gave none, or gave a guess (`coord y ~ -1`) to start the solve from.
    pub position_free: bool,
    pub span: Span,
}

/// What a body is. A `particle` statement makes a point mass and a `body` statement a planar
/// rigid body; spatial bodies are the model's already, ahead of the language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyKind {
    Particle,
    /// A rigid body turning in the plane.
    Planar,
    /// A rigid body turning in space.
    Spatial,
}

/// How a rigid body turns, with the inertia that goes with its rotation.
#[derive(Clone, Debug)]
pub enum Rotation {
    /// About the axis normal to the plane: the inertia about the centre of mass, and the angle,
    /// whose rate is the angular velocity.
    Planar { inertia: ExprId, angle: ExprId },
    /// In space: the inertia tensor about the centre of mass in body axes (symmetric), and the
    /// orientation, the rotation matrix from body axes to world axes, whose rate gives the
    /// angular velocity through ω̃ = Rᵀ·Ṙ (in body axes).
    Spatial {
        inertia: [[ExprId; 3]; 3],
        orientation: [[ExprId; 3]; 3],
        /// The Euler parameters when the orientation is `quaternion(e0, e1, e2, e3)`: ω is then
        /// 2·G(e)·ė, exact on the unit sphere their constraint keeps them on.
        euler_parameters: Option<[ExprId; 4]>,
    },
}

impl Rotation {
    /// ω of a body in space, in body axes (`world` false) or world axes.
    pub fn spatial_angular_velocity(&self, pool: &mut Pool, world: bool) -> Option<[ExprId; 3]> {
        let Rotation::Spatial { orientation, euler_parameters, .. } = self else { return None };
        Some(match (euler_parameters, world) {
            (Some(e), _) => kinematics::angular_velocity_of_euler_parameters(pool, *e, world),
            (None, false) => kinematics::angular_velocity_in_body_axes(pool, orientation),
            (None, true) => kinematics::angular_velocity_in_world_axes(pool, orientation),
        })
    }
}

#[derive(Clone, Debug)]
pub struct Body {
    pub name: String,
    pub mass: ExprId,
    /// Of the centre of mass: two or three components.
    pub position: Vec<ExprId>,
    /// `None` for a particle.
    pub rotation: Option<Rotation>,
    pub span: Span,
}

impl Body {
    pub fn kind(&self) -> BodyKind {
        match self.rotation {
            None => BodyKind::Particle,
            Some(Rotation::Planar { .. }) => BodyKind::Planar,
            Some(Rotation::Spatial { .. }) => BodyKind::Spatial,
        }
    }

    /// The angle of a planar body.
    pub fn angle(&self) -> Option<ExprId> {
        match self.rotation {
            Some(Rotation::Planar { angle, .. }) => Some(angle),
            _ => None,
        }
    }

    /// The inertia about the centre of mass of a planar body.
    pub fn planar_inertia(&self) -> Option<ExprId> {
        match self.rotation {
            Some(Rotation::Planar { inertia, .. }) => Some(inertia),
            _ => None,
        }
    }
}

/// What a constraint restrains, which decides how it is differentiated and how the integrator
/// keeps it from drifting. `mechanics` reads it where it decides what elimination may solve
/// and where it builds a kept constraint's rows (`mechanics::ConstraintRows`); later stages
/// read the rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConstraintKind {
    /// Φ(q, t) = 0: holonomic. Differentiated twice for the acceleration row; stabilised on
    /// both Φ and Φ̇.
    Position,
    /// A(q, t)·q̇ + b(q, t) = 0: a velocity (nonholonomic) constraint such as rolling without
    /// slipping, written with rates on either side (`y'*cos(theta) = x'*sin(theta)`).
    /// Differentiated once; stabilised on the residual itself.
    Velocity,
    /// g(q, t) ≥ 0: a one-sided contact (`contact floor: y >= 0`), Φ = g. While closed it is
    /// kept as a position constraint whose multiplier, its reaction, is never negative; while
    /// open it is absent. Never eliminated: its coordinates stay free.
    Contact,
    /// The tangential rate of a gripping contact, A(q, t)·q̇ + b (`grip x'`): held at zero with
    /// a free multiplier while its contact is closed, absent while it is open.
    Grip,
}

impl ConstraintKind {
    /// The kind as reports and the Python package name it.
    pub fn name(self) -> &'static str {
        match self {
            ConstraintKind::Position => "position",
            ConstraintKind::Velocity => "velocity",
            ConstraintKind::Contact => "contact",
            ConstraintKind::Grip => "grip",
        }
    }

    /// Whether a constraint of this kind belongs to a contact, which holds only while closed.
    pub fn is_unilateral(self) -> bool {
        matches!(self, ConstraintKind::Contact | ConstraintKind::Grip)
    }
}

/// A `contact` line: a one-sided constraint on a gap, its rows among the model's constraints
/// (the normal row of kind [`ConstraintKind::Contact`], and its grip's of kind
/// [`ConstraintKind::Grip`]), and its impact law.
#[derive(Clone, Debug)]
pub struct Contact {
    pub name: String,
    /// The index of its normal row in [`Model::constraints`]: Φ is the gap.
    pub normal: usize,
    /// The index of its grip's row, if it grips (or, with friction, its first slip rate's).
    pub grip: Option<usize>,
    /// A rough contact in space (`slip (V1, V2)`): the index of its second tangential rate's
    /// row (`NAME.cross`), of kind [`ConstraintKind::Grip`] as the first's. Its friction
    /// force is the exact cone's, against the slip velocity (V1, V2).
    pub cross: Option<usize>,
    /// Newton's coefficient of restitution e on the normal rate, in [0, 1] at the parameters'
    /// values (0 when not written: a plastic landing).
    pub restitution: ExprId,
    /// Coulomb's coefficient μ along the tangential row (`friction MU; slip V`); `None` for a
    /// frictionless contact, or one that grips (its tangential row held without a bound).
    pub friction: Option<ExprId>,
    /// The contact is watched only while this expression of the state is positive (`armed
    /// A`): a walker's swing foot passes below the ground at mid-stance unseen.
    pub armed: Option<ExprId>,
    pub span: Span,
}

/// A constraint `lhs = rhs`, kept as Φ = lhs − rhs: of positions (Φ(q, t)), or of velocities
/// (Φ linear in the rates).
#[derive(Clone, Debug)]
pub struct Constraint {
    pub name: String,
    pub kind: ConstraintKind,
    pub lhs: ExprId,
    pub rhs: ExprId,
    pub phi: ExprId,
    /// The symbol standing for its reaction (`floor.force`) wherever the scene mentions it.
    pub force_symbol: SymId,
    /// Whether any `show` or `expect` asks for the reaction.
    pub force_requested: bool,
    /// Coordinates written on the left-hand side, preferred for elimination.
    pub lhs_coords: Vec<SymId>,
    /// For the unit norm of Euler parameters that the scene did not write: the parameters.
    pub quaternion: Option<[ExprId; 4]>,
    pub span: Span,
}

#[derive(Clone, Debug)]
pub struct Gravity {
    pub strength: ExprId,
    /// As written; `None` means straight down (−y in 2D, −z in 3D).
    pub direction: Option<Vec<ExprId>>,
    pub span: Span,
}

/// An applied force at a body's centre of mass or at a point of it, or a torque on a rigid
/// body (a scalar in the plane, a vector in world axes in space).
#[derive(Clone, Debug)]
pub struct Load {
    pub name: String,
    pub body: usize,
    pub value: Value,
    /// The point a force acts at (world axes), when it is not the centre of mass.
    pub at: Option<Vec<ExprId>>,
    pub span: Span,
}

/// A term that contributes to the energy or dissipation, with where it was written.
#[derive(Clone, Debug)]
pub struct Term {
    pub expr: ExprId,
    pub span: Span,
}

/// A quantity the model computes but the scene only names: `KE`, `PE`, `floor.force`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placeholder {
    KineticEnergy,
    PotentialEnergy,
    Reaction(usize),
    /// The time derivative of another placeholder (`dt(KE)`, `KE'`), written at `span`: a
    /// symbol of its own, since differentiating the stand-in symbol would give 0.
    Rate {
        of: SymId,
        span: Span,
    },
}

/// A `show` item.
#[derive(Clone, Debug)]
pub struct Show {
    pub at_start: bool,
    /// The item as written in the scene, used as its label.
    pub label: String,
    pub value: Value,
    pub span: Span,
}

/// An `expect` line: `lhs = rhs`, for every state or at the start.
#[derive(Clone, Debug)]
pub struct Expect {
    pub at_start: bool,
    /// `expect impact NAME:`: the contact (its index in [`Model::contacts`]) at whose impact,
    /// alone, the left side's rates are taken after and the right side's before.
    pub impact: Option<usize>,
    /// `where q = …, q' = …` of an `expect impact` line: the state before the impact (the rest
    /// of it left general).
    pub before: Vec<About>,
    pub text: String,
    pub lhs: Value,
    pub rhs: Value,
    pub span: Span,
    /// Where each side is written.
    pub lhs_span: Span,
    pub rhs_span: Span,
}

/// A verdict on stability, as an `expect linearized:` line names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExpectedStability {
    Stable,
    MarginallyStable,
    Unstable,
}

/// What an `expect linearized:` line expects `lagrange linearize` to find at the scene's
/// reference, at the parameters' values.
#[derive(Clone, Debug)]
pub enum LinearExpectation {
    Stability(ExpectedStability),
    /// An eigenvalue re + im·i, constants of the parameters.
    Eigenvalue {
        re: ExprId,
        im: ExprId,
    },
    /// The value of a parameter (its index among the parameters) where the verdict changes.
    Critical {
        parameter: usize,
        value: ExprId,
    },
}

/// An `expect linearized:` line.
#[derive(Clone, Debug)]
pub struct LinearExpect {
    pub expectation: LinearExpectation,
    /// The line as written.
    pub text: String,
    pub span: Span,
}

/// What a `draw` line draws, in world coordinates: each point has as many components as the
/// scene has dimensions.
#[derive(Clone, Debug)]
pub enum Figure {
    Line {
        from: Vec<ExprId>,
        to: Vec<ExprId>,
    },
    Circle {
        centre: Vec<ExprId>,
        radius: ExprId,
    },
    /// Two points or more, joined in order.
    Polyline(Vec<Vec<ExprId>>),
}

/// A `draw` line: a shape `simulate --animate` draws at every frame. It takes no part in the
/// derivation.
#[derive(Clone, Debug)]
pub struct Drawing {
    /// The line as written.
    pub label: String,
    pub figure: Figure,
    pub span: Span,
}

/// Whether a [`Link`] stores energy or dissipates it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkKind {
    Spring,
    Damper,
}

/// A spring or damper between two points, kept for drawing; its energy or dissipation is
/// already among the potentials or the dissipation terms.
#[derive(Clone, Debug)]
pub struct Link {
    pub name: String,
    pub kind: LinkKind,
    /// The two ends as written: a body's position or a point (fixed or moving).
    pub ends: [Vec<ExprId>; 2],
    pub span: Span,
}

/// One value of a `linearize about` line: a coordinate's reference position, or its rate's.
#[derive(Clone, Debug)]
pub struct About {
    pub coord: SymId,
    /// The rate (`psi' = w`) rather than the position.
    pub rate: bool,
    /// A constant: numbers and parameters, in SI (of a state before an impact, possibly in
    /// terms of the other positions and rates).
    pub value: ExprId,
    /// The item as written (`psi' = w`).
    pub span: Span,
}

/// A `linearize about` line: the reference of small motions, an equilibrium or a steady
/// motion. A later line (the command line's `--about` is one) overrides an earlier one item by
/// item.
#[derive(Clone, Debug)]
pub struct Linearize {
    pub items: Vec<About>,
    pub span: Span,
}

/// A number of a `simulate` block with where it is written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Number {
    /// In SI: a time in seconds.
    pub value: f64,
    pub span: Span,
}

/// The settings of the scene's `simulate { … }` blocks, each read into its type and checked:
/// a setting given twice takes the later value; `output`, `stop` and `event` add up.
#[derive(Clone, Debug, Default)]
pub struct Simulation {
    /// The end time; positive.
    pub until: Option<Number>,
    /// The integration method as written. Which names exist is the integrator's to say: the
    /// front end checks it (`engine` against `sim::Method`).
    pub method: Option<Ident>,
    /// The tolerance of the adaptive methods; positive, without a unit.
    pub tolerance: Option<Number>,
    /// The step of the fixed-step methods; positive.
    pub step: Option<Number>,
    /// Quantities to record, as written: scene expressions resolved when a run asks for them.
    pub outputs: Vec<String>,
    /// Expressions whose zero ends the run, as written.
    pub stops: Vec<String>,
    /// Expressions whose zero crossings are recorded, as written.
    pub events: Vec<String>,
    /// Inputs driven in a run (`input F = -k*x`), each named once, the last line winning.
    pub drives: Vec<Drive>,
    /// The period at which the laws of `drives` are sampled and held (`hold 10 ms`); none:
    /// they act continuously. Its span is the whole setting, `hold` included.
    pub hold: Option<Number>,
}

/// An `input NAME = EXPR` setting of a `simulate` block: the input (one the scene declares)
/// and the law that drives it, as written, resolved when a run asks for it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Drive {
    pub input: String,
    pub law: String,
}

/// Everything a scene says, resolved.
#[derive(Clone)]
pub struct Model {
    /// What resolving the scene left for resolving more expressions against it.
    pub scope: Scope,
    pub pool: Pool,
    pub title: Option<String>,
    pub time: SymId,
    pub params: Vec<Param>,
    /// The `input` lines' signals, in the order written.
    pub inputs: Vec<Input>,
    /// The `output` lines, in the order written.
    pub outputs: Vec<Output>,
    pub coords: Vec<Coord>,
    pub bodies: Vec<Body>,
    pub constraints: Vec<Constraint>,
    /// The `contact` lines, in the order written; their rows are among `constraints`.
    pub contacts: Vec<Contact>,
    pub gravity: Option<Gravity>,
    pub potentials: Vec<Term>,
    pub forces: Vec<Load>,
    pub torques: Vec<Load>,
    pub dissipation: Vec<Term>,
    pub lagrangians: Vec<Term>,
    pub shows: Vec<Show>,
    pub expects: Vec<Expect>,
    /// The `expect linearized:` lines, in the order written.
    pub linear_expects: Vec<LinearExpect>,
    /// The `draw` lines, in the order written.
    pub drawings: Vec<Drawing>,
    /// The springs and dampers, in the order written.
    pub links: Vec<Link>,
    /// The `simulate { … }` blocks, read into their settings.
    pub simulation: Simulation,
    /// Each input that stands in a constraint, where [`Checks::inputs_in_constraints`] let it,
    /// with the error it would otherwise have been: a run that does not drive it reports it.
    pub inputs_in_constraints: Vec<(SymId, lang::Diagnostic)>,
    /// The `linearize about` lines, in the order written.
    pub linearize: Vec<Linearize>,
    pub placeholders: Vec<(SymId, Placeholder)>,
    /// `let` names with their values, in order, for printing.
    pub lets: Vec<(String, ExprId)>,
}

impl Model {
    pub fn placeholder(&self, s: SymId) -> Option<Placeholder> {
        self.placeholders.iter().find(|(p, _)| *p == s).map(|(_, k)| *k)
    }

    /// The symbols numbers fill before the state, each with its value: the parameters in
    /// declaration order (`None` for one without a value), then the inputs at the values they
    /// take when nothing drives them.
    pub fn constants(&self) -> Vec<(SymId, Option<ExprId>)> {
        let params = self.params.iter().map(|p| (p.sym, p.value));
        params.chain(self.inputs.iter().map(|u| (u.sym, Some(u.value)))).collect()
    }

    /// Whether `s` is an input's symbol.
    pub fn is_input(&self, s: SymId) -> bool {
        self.inputs.iter().any(|u| u.sym == s)
    }

    /// The spatial dimension of the scene: 3 when any body or force is 3D, else 2.
    pub fn dimension(&self) -> usize {
        self.bodies.iter().map(|b| b.position.len()).max().unwrap_or(2).max(2)
    }
}
