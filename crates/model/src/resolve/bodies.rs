//! `particle` and `body` statements: mass, inertia, position and rotation of each body.

use std::collections::HashMap;

use cas::ExprId;
use lang::{Diagnostic, Expr, Ident, Property, Span};

use super::checks::{ANGLE, INERTIA, MASS, POSITION};
use super::dims::BodyDims;
use super::{closest, normalize, Binding, Resolver};
use crate::units::Form;
use crate::{Body, BodyKind, Rotation, Value};

/// What the properties of a `particle` or `body` give, each with its dimensions.
#[derive(Default)]
struct BodyProps<'a> {
    seen: HashMap<&'a str, Span>,
    /// A misspelled property is reported once, not again as missing.
    misspelled: Vec<&'a str>,
    mass: Option<ExprId>,
    inertia: Option<ExprId>,
    position: Option<Vec<ExprId>>,
    angle: Option<ExprId>,
    orientation: Option<(Vec<Vec<ExprId>>, Span)>,
    // The dimensions of each property, with where it is written.
    mass_dims: Option<Form>,
    inertia_dims: Option<(Form, Span)>,
    angle_dims: Option<Form>,
    inertia_written: Option<(Value, &'a Expr)>,
    position_dims: Vec<(Form, Span)>,
}

impl Resolver<'_> {
    pub(super) fn body(&mut self, name: &Ident, props: &[Property], kind: BodyKind, span: Span) {
        let allowed: &[&str] = match kind {
            BodyKind::Particle => &["mass", "position"],
            BodyKind::Planar | BodyKind::Spatial => {
                &["mass", "inertia", "position", "angle", "orientation"]
            }
        };
        let mut got = BodyProps::default();
        for p in props {
            self.body_property(name, p, kind, allowed, &mut got);
        }
        let (mut ok, spatial) = self.body_missing(name, kind, &got);
        let BodyProps {
            mass,
            inertia,
            position,
            angle,
            orientation,
            mass_dims,
            inertia_dims,
            angle_dims,
            inertia_written,
            position_dims,
            ..
        } = got;
        let rotation_rate = match spatial {
            // ω of a body in space is a rate of dimensionless rotation entries.
            true => Some(Form::default()),
            false => angle_dims.clone(),
        };
        self.body_energy(mass_dims.clone(), &position_dims, inertia_dims, rotation_rate.as_ref());
        if let (false, Some((written, expr))) = (spatial, &inertia_written) {
            if !matches!(written, Value::Scalar(_)) {
                self.error(
                    Diagnostic::error(expr.span, "a body turning in the plane has one inertia")
                        .with_label(format!("expected a scalar, found {}", written.kind_name()))
                        .with_hint(
                            "principal moments or a tensor need an `orientation` in space; in the \
                             plane give the inertia about the axis normal to it",
                        ),
                );
                ok = false;
            }
        }
        let spatial_rotation = match (orientation, inertia_written) {
            (Some((rows, span)), Some((written, expr))) => {
                self.spatial_rotation(name, rows, span, written, expr, position.as_deref())
            }
            _ => None,
        };
        if spatial && spatial_rotation.is_none() {
            ok = false;
        }
        let (Some(mass), Some(position), true) = (mass, position, ok) else { return };
        let index = self.model.bodies.len();
        if self.bind(name, Binding::Body(index)) {
            self.scope.body_dims.push(BodyDims {
                at: self.stmt,
                mass: mass_dims.unwrap_or_default(),
                position: position_dims.into_iter().map(|(f, _)| f).collect(),
                angle: angle_dims,
                spatial,
            });
            let rotation = match (kind, inertia, angle) {
                _ if spatial => spatial_rotation,
                (BodyKind::Planar, Some(inertia), Some(angle)) => {
                    Some(Rotation::Planar { inertia, angle })
                }
                _ => None,
            };
            self.model.bodies.push(Body {
                name: normalize(&name.name),
                mass,
                position,
                rotation,
                span,
            });
        }
    }

    /// One property of a `particle` or `body`: its value, or why it is not allowed.
    fn body_property<'a>(
        &mut self,
        name: &Ident,
        p: &'a Property,
        kind: BodyKind,
        allowed: &[&'a str],
        got: &mut BodyProps<'a>,
    ) {
        let key = p.key.name.as_str();
        if !allowed.contains(&key) {
            let mut d = Diagnostic::error(p.key.span, format!("unknown property `{key}`"))
                .with_label(format!("expected one of {}", allowed.join(", ")));
            if kind == BodyKind::Particle && matches!(key, "inertia" | "angle") {
                d = d.with_hint("a particle has no orientation; use `body` for a rigid body");
            } else if let Some(near) = closest(key, allowed.iter().copied()) {
                d = d.with_hint(format!("did you mean `{near}`?"));
                got.misspelled.push(near);
            }
            self.error(d);
            return;
        }
        if let Some(first) = got.seen.insert(key, p.key.span) {
            self.error(
                Diagnostic::error(p.key.span, format!("`{key}` is given twice"))
                    .with_label("again here")
                    .with_related(first, "first given here"),
            );
            return;
        }
        match key {
            "mass" => {
                let resolved = self.scalar_in_role(&p.value, &MASS);
                got.mass = resolved.as_ref().map(|(m, _)| *m);
                got.mass_dims = resolved.map(|(_, d)| self.form(d));
                if let Some(m) = got.mass {
                    self.check_sign(name, m, &p.value, false);
                }
            }
            "inertia" => {
                // A scalar for a planar body; in space also principal moments or a tensor,
                // decided once the got.orientation is known.
                let resolved = self.value_in_role(&p.value, &INERTIA);
                if let Some((v, d)) = resolved {
                    let forms = self.shape(d).forms();
                    got.inertia_dims = forms.first().cloned().map(|f| (f, p.value.span));
                    for f in &forms[1.min(forms.len())..] {
                        let what = "between the entries of an inertia";
                        self.scope.units.same(&forms[0], f, p.value.span, p.value.span, what);
                    }
                    if let Value::Scalar(i) = v {
                        got.inertia = Some(i);
                        self.check_sign(name, i, &p.value, true);
                    }
                    got.inertia_written = Some((v, &p.value));
                }
            }
            "orientation" => self.orientation_property(&p.value, got),
            "angle" => {
                let resolved = self.scalar_in_role(&p.value, &ANGLE);
                got.angle = resolved.as_ref().map(|(a, _)| *a);
                got.angle_dims = resolved.map(|(_, d)| self.form(d));
            }
            _ => self.position_property(&p.value, got),
        }
    }

    /// The `orientation` of a body in space: a 3×3 rotation matrix of dimensionless entries.
    fn orientation_property(&mut self, value: &Expr, got: &mut BodyProps<'_>) {
        let resolved = self.value_in_role(value, &ANGLE);
        match resolved {
            Some((Value::Matrix(m), d)) if m.len() == 3 && m.iter().all(|r| r.len() == 3) => {
                for f in self.shape(d).forms() {
                    let what = "an entry of an orientation";
                    self.scope.units.dimensionless(&f, value.span, what);
                }
                got.orientation = Some((m, value.span));
            }
            Some((other, _)) => self.error(
                Diagnostic::error(
                    value.span,
                    format!("an orientation is a 3×3 rotation matrix, not {}", other.kind_name()),
                )
                .with_label("expected a rotation")
                .with_hint(
                    "compose rotations such as `rotz(phi)*rotx(theta)*rotz(psi)`; a \
                     body turning in the plane takes `angle` instead",
                ),
            ),
            None => {}
        }
    }

    /// The `position` of a body: a vector of up to three entries, or a scalar on a line.
    fn position_property(&mut self, value: &Expr, got: &mut BodyProps<'_>) {
        let resolved = self.value_in_role(value, &POSITION);
        let resolved = resolved.map(|(v, d)| {
            let forms = self.shape(d).forms();
            got.position_dims = forms.into_iter().map(|f| (f, value.span)).collect();
            v
        });
        got.position = match resolved {
            Some(Value::Vector(v)) if v.len() <= 3 => Some(v),
            Some(Value::Scalar(x)) => Some(vec![x]),
            Some(other) => {
                self.error(
                    Diagnostic::error(
                        value.span,
                        format!("a position must be a vector, not {}", other.kind_name()),
                    )
                    .with_label("expected `(x, y)` or `(x, y, z)`"),
                );
                None
            }
            None => None,
        }
    }

    /// The properties a body lacks, each reported; whether it is whole and whether it is spatial.
    fn body_missing(&mut self, name: &Ident, kind: BodyKind, got: &BodyProps<'_>) -> (bool, bool) {
        let what = if kind == BodyKind::Particle { "particle" } else { "body" };
        let missing = |field: &str, hint: &str| {
            Diagnostic::error(name.span, format!("{what} `{}` has no {field}", name.name))
                .with_label(format!("{field} missing"))
                .with_hint(hint.to_string())
        };
        let mut ok = true;
        if got.mass.is_none() && !got.seen.contains_key("mass") && !got.misspelled.contains(&"mass")
        {
            let d = missing("mass", "add `mass m` inside the braces");
            self.error(d);
            ok = false;
        }
        if got.position.is_none()
            && !got.seen.contains_key("position")
            && !got.misspelled.contains(&"position")
        {
            let d = missing("position", "add `position (x, y)`: where its centre of mass is, as a function of the coordinates");
            self.error(d);
            ok = false;
        }
        let spatial = got.orientation.is_some() || got.seen.contains_key("orientation");
        if spatial {
            if let Some(first) = got.seen.get("angle") {
                self.error(
                    Diagnostic::error(*first, "a body has either an `angle` or an `orientation`")
                        .with_label("angle given")
                        .with_related(got.seen["orientation"], "orientation given")
                        .with_hint(
                            "`angle` turns a body in the plane; `orientation` turns it in space",
                        ),
                );
                ok = false;
            }
            if !got.seen.contains_key("inertia") && !got.misspelled.contains(&"inertia") {
                let d = missing(
                    "inertia",
                    "add `inertia (A, B, C)`: the principal moments about the centre of mass in \
                     body axes, or the full tensor `[Ixx, Ixy, Ixz; Ixy, Iyy, Iyz; Ixz, Iyz, Izz]`",
                );
                self.error(d);
                ok = false;
            }
        }
        if kind == BodyKind::Planar && !spatial {
            if got.inertia.is_none()
                && !got.seen.contains_key("inertia")
                && !got.misspelled.contains(&"inertia")
            {
                let d = missing("inertia", "add `inertia m*L^2/12` (about the centre of mass), or use `particle` for a point mass");
                self.error(d);
                ok = false;
            }
            if got.angle.is_none()
                && !got.seen.contains_key("angle")
                && !got.misspelled.contains(&"angle")
            {
                let d = missing(
                    "angle",
                    "add `angle theta`: the body's orientation; its angular velocity is angle'",
                );
                self.error(d);
                ok = false;
            }
        }
        (ok, spatial)
    }
}
