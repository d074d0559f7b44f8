//! Names and members: what a name or `body.field` stands for, and the report of an unknown
//! name with the nearest known one.

use lang::{Diagnostic, Ident, Span};

use super::dims::Dims;
use super::{closest, normalize, Binding, Resolver};
use crate::units::Form;
use crate::{BodyKind, Rotation, Value};

impl Resolver<'_> {
    pub(super) fn name(&mut self, raw: &str, primes: u8, span: Span) -> Option<(Value, Dims)> {
        let value = self.name_value(raw, primes, span)?;
        let name = normalize(raw);
        let dims = match (name.as_str(), &value) {
            ("t", _) if !self.scope.names.contains_key("t") => Dims::Scalar(crate::units::time()),
            ("pi", Value::Scalar(pi)) if !self.scope.names.contains_key("pi") && primes == 0 => {
                self.number_dims(*pi, true)
            }
            ("pi", _) if !self.scope.names.contains_key("pi") => {
                Dims::Scalar(Form::default().rate(primes))
            }
            _ => self.name_dims(raw, &name, primes),
        };
        if let Dims::Scalar(f) = &dims {
            self.scope.units.used(f, span);
        }
        Some((value, dims))
    }

    fn name_value(&mut self, raw: &str, primes: u8, span: Span) -> Option<Value> {
        let name = normalize(raw);
        self.scope.used.insert(name.clone());
        let base = match name.as_str() {
            "t" if !self.scope.names.contains_key("t") => {
                if primes > 0 {
                    self.error(
                        Diagnostic::error(span, "`t` is time; it has no rate")
                            .with_label("t' is always 1")
                            .with_hint("write `1`"),
                    );
                    return None;
                }
                return Some(Value::Scalar(self.model.pool.sym(self.model.time)));
            }
            "pi" if !self.scope.names.contains_key("pi") => Value::Scalar(self.model.pool.pi()),
            _ => match self.scope.names.get(&name).cloned() {
                Some(Binding::Param(s)) => {
                    if primes > 0 {
                        self.error(
                            Diagnostic::error(
                                span,
                                format!("`{raw}` is a parameter, constant in time"),
                            )
                            .with_label("has no rate")
                            .with_hint(format!("declare it with `coord {raw}` if it moves")),
                        );
                        return None;
                    }
                    Value::Scalar(self.model.pool.sym(s))
                }
                Some(Binding::Input(s)) => {
                    if primes > 0 {
                        self.error(
                            Diagnostic::error(
                                span,
                                format!("`{raw}` is an input; its rate is not known"),
                            )
                            .with_label("the rate of an input")
                            .with_hint(
                                "an input is given as a value in time, not with its derivatives",
                            ),
                        );
                        return None;
                    }
                    Value::Scalar(self.model.pool.sym(s))
                }
                // KE stands for an expression only derived later; its rates are symbols of
                // their own (see `total_rate`), taken below as a `let` name's are.
                Some(Binding::Quantity(s)) => Value::Scalar(self.model.pool.sym(s)),
                Some(Binding::Coord(s)) => {
                    if primes > 2 {
                        let base = self.model.pool.symbol(s).name.clone();
                        self.past_acceleration(span, primes, &base, true);
                        return None;
                    }
                    let d = self
                        .model
                        .pool
                        .derivative_symbol(s, primes)
                        .expect("coordinates have rates");
                    return Some(Value::Scalar(self.model.pool.sym(d)));
                }
                Some(Binding::Let(v)) => v,
                Some(Binding::Body(_)) | Some(Binding::Constraint(_)) => {
                    let what = if matches!(self.scope.names.get(&name), Some(Binding::Body(_))) {
                        "a body: write `NAME.position`, `NAME.velocity` or `NAME.omega`"
                    } else {
                        "a constraint: write `NAME.force` for its reaction"
                    };
                    self.error(
                        Diagnostic::error(span, format!("`{raw}` is not a value"))
                            .with_label("names a body or constraint")
                            .with_hint(format!("`{raw}` is {what}")),
                    );
                    return None;
                }
                None => {
                    self.unknown_name(raw, &name, span);
                    return None;
                }
            },
        };
        if primes == 0 {
            return Some(base);
        }
        if !self.derivative_exists(&base, primes, span) {
            return None;
        }
        // A rate of a `let` name or a quantity: the total time derivative.
        Some(base.map(|mut x| {
            for _ in 0..primes {
                x = self.total_rate(x, span);
            }
            x
        }))
    }

    pub(super) fn unknown_name(&mut self, raw: &str, name: &str, span: Span) {
        if let Some((decl, what)) = self.scope.declared.get(name).copied() {
            if decl.start > span.start && !self.in_outputs {
                self.error(
                    Diagnostic::error(
                        span,
                        format!("the {what} `{raw}` is used before it is declared"),
                    )
                    .with_label("used here")
                    .with_related(decl, "declared here")
                    .with_hint(format!("move the declaration of `{raw}` above its first use")),
                );
                return;
            }
            // Declared, but its declaration had an error of its own: already reported.
            return;
        }
        let mut candidates: Vec<&str> = self.scope.names.keys().map(String::as_str).collect();
        candidates.extend(["t", "pi"]);
        candidates.sort_unstable();
        let mut d =
            Diagnostic::error(span, format!("unknown name `{raw}`")).with_label("not declared");
        d = match closest(name, candidates) {
            Some(near) => d.with_hint(format!("did you mean `{near}`?")),
            None => d.with_hint(format!(
                "declare it first: `coord {raw}` for a coordinate, `param {raw}` for a constant, `let {raw} = …` for a name"
            )),
        };
        self.error(d);
    }

    pub(super) fn member(
        &mut self,
        object: &Ident,
        field: &Ident,
        span: Span,
    ) -> Option<(Value, Dims)> {
        if let Some(Binding::Let(v)) = self.scope.names.get(&normalize(&object.name)) {
            if !matches!(v, Value::Scalar(_)) {
                // A component of a vector `let`.
                let (v, dims) = self.name(&object.name, 0, object.span)?;
                return self.component(v, dims, field, &object.name);
            }
        }
        let value = self.member_value(object, field, span)?;
        let body = match self.scope.names.get(&normalize(&object.name)) {
            Some(Binding::Body(i)) => Some(*i),
            _ => None,
        };
        Some((value, self.member_dims(object, field, body)))
    }

    fn member_value(&mut self, object: &Ident, field: &Ident, span: Span) -> Option<Value> {
        let name = normalize(&object.name);
        match self.scope.names.get(&name).cloned() {
            Some(Binding::Body(i)) => self.body_member(i, object, field),
            Some(Binding::Constraint(components)) => {
                self.reaction_member(&components, object, field, span)
            }
            _ => self.unknown_member(&name, object),
        }
    }

    /// `body.field`: a body's position, velocity, mass, angle or angular velocity.
    fn body_member(&mut self, i: usize, object: &Ident, field: &Ident) -> Option<Value> {
        let body = self.model.bodies[i].clone();
        let fields: &[&str] = match body.kind() {
            BodyKind::Particle => &["position", "velocity", "mass", "x", "y", "z"],
            BodyKind::Planar => &["position", "velocity", "mass", "angle", "omega", "x", "y", "z"],
            BodyKind::Spatial => {
                &["position", "velocity", "mass", "omega", "omega_body", "axes", "x", "y", "z"]
            }
        };
        if let Some(rotation @ Rotation::Spatial { orientation, .. }) = &body.rotation {
            let orientation = *orientation;
            let pool = &mut self.model.pool;
            let spatial = match field.name.as_str() {
                "omega" | "omega_body" => {
                    let world = field.name == "omega";
                    rotation
                        .spatial_angular_velocity(pool, world)
                        .map(|w| Value::Vector(w.to_vec()))
                }
                "axes" => Some(Value::Matrix(crate::kinematics::rows(&orientation))),
                _ => None,
            };
            if spatial.is_some() {
                return spatial;
            }
        }
        let value = match field.name.as_str() {
            "position" => Some(Value::Vector(body.position.clone())),
            "velocity" => Some(Value::Vector(
                body.position.iter().map(|x| self.model.pool.time_derivative(*x)).collect(),
            )),
            "mass" => Some(Value::Scalar(body.mass)),
            "angle" => body.angle().map(Value::Scalar),
            "omega" => body.angle().map(|a| Value::Scalar(self.model.pool.time_derivative(a))),
            "x" => body.position.first().map(|x| Value::Scalar(*x)),
            "y" => body.position.get(1).map(|x| Value::Scalar(*x)),
            "z" => body.position.get(2).map(|x| Value::Scalar(*x)),
            _ => None,
        };
        let value = match field.name.as_str() {
            "angle" if body.kind() == BodyKind::Spatial => None,
            _ => value,
        };
        if value.is_none() {
            let mut d =
                Diagnostic::error(field.span, format!("`{}` has no `{}`", object.name, field.name))
                    .with_label(format!("expected one of {}", fields.join(", ")));
            if body.kind() == BodyKind::Spatial && field.name == "angle" {
                d = d.with_hint(
                    "a body turning in space has no single angle: its orientation is \
                     `axes`, its angular velocity `omega` (world axes) or `omega_body`",
                );
            } else if body.kind() == BodyKind::Particle
                && matches!(field.name.as_str(), "omega" | "angle")
            {
                d = d.with_hint(
                    "a particle has no orientation; declare a rigid `body` with an `angle`",
                );
            } else if let Some(near) = closest(&field.name, fields.iter().copied()) {
                d = d.with_hint(format!("did you mean `{near}`?"));
            }
            self.error(d);
        }
        value
    }

    /// `constraint.force`: the reaction of a constraint, in `show` and `expect` lines only.
    fn reaction_member(
        &mut self,
        components: &[Option<usize>],
        object: &Ident,
        field: &Ident,
        span: Span,
    ) -> Option<Value> {
        // A gripping contact's tangential reaction is `NAME.grip`, beside its normal `NAME.force`.
        // In space it is the vector of its two tangential rows' reactions.
        let contact = components.first().copied().flatten().and_then(|normal| {
            self.model.contacts.iter().find(|c| c.normal == normal).map(|c| (c.grip, c.cross))
        });
        let grip = contact.and_then(|c| c.0);
        let components: Vec<Option<usize>> = match (field.name.as_str(), contact) {
            ("grip", Some((Some(g), None))) => vec![Some(g)],
            ("grip", Some((Some(g), Some(c)))) => vec![Some(g), Some(c)],
            _ => components.to_vec(),
        };
        let components = &components[..];
        if field.name != "force" && !(field.name == "grip" && grip.is_some()) {
            self.error(
                Diagnostic::error(field.span, format!("a constraint has no `{}`", field.name))
                    .with_label("expected `force`")
                    .with_hint(format!("`{}.force` is its reaction", object.name)),
            );
            return None;
        }
        if self.in_drawing {
            self.error(
                Diagnostic::error(span, "a reaction cannot be drawn")
                    .with_label("a force, not a point")
                    .with_hint(
                        "a `draw` line places shapes with positions, which may use the \
                         coordinates, their rates and `t`",
                    ),
            );
            return None;
        }
        if !self.in_outputs {
            self.error(
                Diagnostic::error(span, "a reaction can only be shown or checked")
                    .with_label("used in the model itself")
                    .with_hint("use `.force` in `show` and `expect` lines"),
            );
            return None;
        }
        let mut forces = Vec::new();
        for component in components {
            forces.push(match component {
                Some(i) => {
                    self.model.constraints[*i].force_requested = true;
                    self.model.pool.sym(self.model.constraints[*i].force_symbol)
                }
                // A component that always holds exerts nothing.
                None => self.model.pool.zero(),
            });
        }
        // A vector constraint's reaction is the vector of its components' reactions.
        // (A contact's grip row is named after its contact, `NAME.grip`, and is one scalar.)
        let vector = components.len() > 1
            || (field.name == "force"
                && components
                    .iter()
                    .flatten()
                    .any(|i| self.model.constraints[*i].name.contains('.')));
        match vector {
            false => Some(Value::Scalar(forces[0])),
            true => Some(Value::Vector(forces)),
        }
    }

    /// `name.field` where `name` is neither a body nor a constraint: reported, unless already.
    fn unknown_member(&mut self, name: &str, object: &Ident) -> Option<Value> {
        if self.scope.declared.contains_key(name) {
            // Declared but failed to resolve: already reported.
            return None;
        }
        let mut candidates: Vec<&str> = self
            .scope
            .names
            .iter()
            .filter(|(_, b)| matches!(b, Binding::Body(_) | Binding::Constraint(_)))
            .map(|(k, _)| k.as_str())
            .collect();
        candidates.sort_unstable();
        let mut d = Diagnostic::error(
            object.span,
            format!("no body or constraint named `{}`", object.name),
        )
        .with_label("unknown");
        if let Some(near) = closest(name, candidates) {
            d = d.with_hint(format!("did you mean `{near}`?"));
        }
        self.error(d);
        None
    }
}
