//! What `simulate --animate` shows, in numbers: the scene's figures at every recorded time.
//!
//! By default each particle is a dot (its mass sets the size), each rigid body its centre with
//! its body axes, each spring and damper a link between its ends; the scene's `draw` lines add
//! lines, circles and polylines. Every coordinate of every figure is an expression of the state,
//! lowered with the run's other observations and evaluated at the same recorded times, so the
//! figures move exactly as the recorded quantities do. Rendering them is the front end's.

use cas::{ExprId, SymbolKind};
use model::{Figure as Drawn, LinkKind, Rotation};

use engine::numbers::Prepared;

/// The figures of a run, frame by frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// The scene's title, if it has one.
    pub title: Option<String>,
    /// 2 for a scene in the plane, 3 for one in space.
    pub dimension: usize,
    /// The recorded times, one frame each.
    pub times: Vec<f64>,
    /// E(t) − E(0) at each frame.
    pub energy_error: Vec<f64>,
    /// Whether the energy should be conserved (no forces, dissipation or explicit time).
    pub conservative: bool,
    pub figures: Vec<Figure>,
    /// The scene's contacts, each with whether it is closed at each frame.
    pub contacts: Vec<ContactTrack>,
    /// The run's contact events (impacts, lift-offs, settlings), in the order they happened.
    pub contact_events: Vec<sim::ModeEvent>,
}

/// A contact through a run: its name, and whether it is closed at each frame. At a jump the
/// run records two frames at one time, the one before it (the contact's mode before) and the
/// one after.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactTrack {
    pub name: String,
    pub closed: Vec<bool>,
}

impl ContactTrack {
    /// The contacts named `names` through frames recorded at `times`, from the run's events
    /// (each event's `closed` says the mode after it; a contact is open until one closes it).
    pub fn of(names: &[String], times: &[f64], events: &[sim::ModeEvent]) -> Vec<ContactTrack> {
        let mut closed = vec![false; names.len()];
        let mut tracks: Vec<ContactTrack> = names
            .iter()
            .map(|name| ContactTrack {
                name: name.clone(),
                closed: Vec::with_capacity(times.len()),
            })
            .collect();
        let mut next = 0;
        for (i, &t) in times.iter().enumerate() {
            // The frame before a jump (the next frame at its time) has the modes before it.
            let before_jump = times.get(i + 1) == Some(&t);
            while let Some(event) = events.get(next) {
                if event.time < t || (event.time == t && !before_jump) {
                    if let Some(c) = closed.get_mut(event.contact) {
                        *c = event.closed;
                    }
                    next += 1;
                } else {
                    break;
                }
            }
            for (track, &c) in tracks.iter_mut().zip(&closed) {
                track.closed.push(c);
            }
        }
        tracks
    }
}

/// One figure: what it is, and its numbers at each frame (the layout [`FigureKind`] gives).
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    pub kind: FigureKind,
    /// The body's or link's name, or the `draw` line as written.
    pub label: String,
    /// One row per recorded time.
    pub frames: Vec<Vec<f64>>,
}

/// What a figure is, with what stays constant through the run. A point is `dimension` numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum FigureKind {
    /// A particle; a frame is its position. The mass (NaN where it is not a constant) sizes
    /// the dot.
    Particle { mass: f64 },
    /// A rigid body; a frame is its centre, then each body axis as a unit vector in world
    /// axes (two in the plane, three in space). `axis_length` is twice its largest radius of
    /// gyration, 0 where that is not a positive constant (the front end picks a length).
    Body { axis_length: f64 },
    /// A spring or damper; a frame is its two ends. `fixed` marks an end that never moves.
    Link { damper: bool, fixed: [bool; 2] },
    /// `draw line`: a frame is its two ends.
    Line,
    /// `draw circle`: a frame is its centre, then its radius.
    Circle,
    /// `draw polyline`: a frame is its points, in order.
    Polyline,
}

/// The figures as expressions, laid out for the observation program.
pub(crate) struct Plan {
    figures: Vec<(FigureKind, String, usize)>,
    /// Every number of every figure, figure after figure.
    pub exprs: Vec<ExprId>,
}

impl Plan {
    /// The scene's figures: the default ones for its bodies and links, then its `draw` lines,
    /// expanded into the remaining coordinates. Constants are taken at `parameters`.
    pub(crate) fn new(prepared: &mut Prepared, parameters: &[f64]) -> Plan {
        let mut plan = Plan { figures: Vec::new(), exprs: Vec::new() };
        let dimension = prepared.derivation.model.dimension();
        let model = &prepared.derivation.model;
        let bodies = model.bodies.clone();
        let links = model.links.clone();
        let drawings = model.drawings.clone();
        for body in &bodies {
            let mut numbers = padded(prepared, &body.position, dimension);
            let mass = constant(prepared, body.mass, parameters);
            let kind = match &body.rotation {
                None => FigureKind::Particle { mass },
                Some(Rotation::Planar { inertia, angle }) => {
                    let pool = &mut prepared.derivation.model.pool;
                    let (cos, sin) = (pool.cos(*angle), pool.sin(*angle));
                    let (zero, minus_sin) = (pool.zero(), pool.neg(sin));
                    let axes = [cos, sin, zero, minus_sin, cos, zero];
                    // A planar body in a scene in space turns about z.
                    let per_axis = dimension;
                    for axis in axes.chunks(3) {
                        numbers.extend(axis[..per_axis].iter().map(|e| expand(prepared, *e)));
                    }
                    let gyration = constant(prepared, *inertia, parameters) / mass;
                    FigureKind::Body { axis_length: axis_length(gyration) }
                }
                Some(Rotation::Spatial { inertia, orientation, .. }) => {
                    // Body axis j in world axes is column j of the orientation.
                    for j in 0..3 {
                        for row in orientation {
                            numbers.push(expand(prepared, row[j]));
                        }
                    }
                    let largest = (0..3)
                        .map(|i| constant(prepared, inertia[i][i], parameters))
                        .fold(f64::NAN, f64::max);
                    FigureKind::Body { axis_length: axis_length(largest / mass) }
                }
            };
            plan.push(kind, body.name.clone(), numbers);
        }
        for link in &links {
            let mut numbers = Vec::new();
            let mut fixed = [false; 2];
            for (end, fixed) in link.ends.iter().zip(&mut fixed) {
                let end = padded(prepared, end, dimension);
                *fixed = end.iter().all(|e| is_constant(prepared, *e));
                numbers.extend(end);
            }
            let damper = link.kind == LinkKind::Damper;
            plan.push(FigureKind::Link { damper, fixed }, link.name.clone(), numbers);
        }
        for drawing in &drawings {
            let (kind, numbers) = match &drawing.figure {
                Drawn::Line { from, to } => {
                    let mut numbers = padded(prepared, from, dimension);
                    numbers.extend(padded(prepared, to, dimension));
                    (FigureKind::Line, numbers)
                }
                Drawn::Circle { centre, radius } => {
                    let mut numbers = padded(prepared, centre, dimension);
                    numbers.push(expand(prepared, *radius));
                    (FigureKind::Circle, numbers)
                }
                Drawn::Polyline(points) => {
                    let numbers =
                        points.iter().flat_map(|p| padded(prepared, p, dimension)).collect();
                    (FigureKind::Polyline, numbers)
                }
            };
            plan.push(kind, drawing.label.clone(), numbers);
        }
        plan
    }

    fn push(&mut self, kind: FigureKind, label: String, numbers: Vec<ExprId>) {
        self.figures.push((kind, label, numbers.len()));
        self.exprs.extend(numbers);
    }

    /// The figures at each recorded time, read from the trajectory's columns `first..`.
    pub(crate) fn figures(&self, rows: &[Vec<f64>], first: usize) -> Vec<Figure> {
        let mut column = first;
        let mut figures = Vec::new();
        for (kind, label, width) in &self.figures {
            let frames = rows.iter().map(|row| row[column..column + width].to_vec()).collect();
            figures.push(Figure { kind: kind.clone(), label: label.clone(), frames });
            column += width;
        }
        figures
    }
}

/// A point in the scene's dimension (a point in the plane gets z = 0 in space), expanded.
fn padded(prepared: &mut Prepared, point: &[ExprId], dimension: usize) -> Vec<ExprId> {
    let zero = prepared.derivation.model.pool.zero();
    (0..dimension).map(|i| expand(prepared, point.get(i).copied().unwrap_or(zero))).collect()
}

/// Eliminated coordinates replaced by what the constraints make them.
fn expand(prepared: &mut Prepared, e: ExprId) -> ExprId {
    prepared.derivation.expand_quantities(e, false)
}

/// Whether `e` stays put: it depends on parameters only.
fn is_constant(prepared: &mut Prepared, e: ExprId) -> bool {
    let pool = &mut prepared.derivation.model.pool;
    let symbols = pool.free_symbols(e);
    symbols.iter().all(|s| matches!(pool.symbol(*s).kind, SymbolKind::Param))
}

/// The value of a constant at the parameters' values; NaN where `e` moves.
fn constant(prepared: &mut Prepared, e: ExprId, parameters: &[f64]) -> f64 {
    let e = expand(prepared, e);
    if is_constant(prepared, e) {
        prepared.constant(e, parameters)
    } else {
        f64::NAN
    }
}

/// Twice the radius of gyration √(I/m), from I/m; 0 where that is not a positive number.
fn axis_length(inertia_per_mass: f64) -> f64 {
    if inertia_per_mass.is_finite() && inertia_per_mass > 0.0 {
        2.0 * inertia_per_mass.sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod contact_tests {
    use super::ContactTrack;
    use sim::{ModeChange, ModeEvent};

    fn event(time: f64, contact: usize, kind: ModeChange, closed: bool) -> ModeEvent {
        ModeEvent {
            time,
            contact,
            kind,
            closed,
            impulse: 0.0,
            tangential: None,
            energy_change: 0.0,
            slip: 0.0,
            energy_rise: false,
        }
    }

    /// A contact closed at the start, lifting off, landing (two frames at the jump's time,
    /// before and after) and settling: each frame has the mode in force there.
    #[test]
    fn each_frame_has_the_modes_in_force_and_a_jump_two() {
        let names = ["floor".to_string(), "wall".to_string()];
        let times = [0.0, 0.5, 1.0, 1.0, 1.5, 2.0, 2.0];
        let events = [
            event(0.0, 1, ModeChange::Closed, true),
            event(0.7, 1, ModeChange::LiftOff, false),
            event(1.0, 0, ModeChange::Impact, false),
            event(2.0, 0, ModeChange::Settled, true),
        ];
        let tracks = ContactTrack::of(&names, &times, &events);
        assert_eq!(tracks[0].closed, [false, false, false, false, false, false, true]);
        assert_eq!(tracks[1].closed, [true, true, false, false, false, false, false]);
        assert_eq!(tracks[1].name, "wall");
    }
}
