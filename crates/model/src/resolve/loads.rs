//! `force` and `torque` statements: a load on a body, with its point of application.

use lang::{Diagnostic, Expr, Ident, Span};

use super::checks::{FORCE, POSITION, TORQUE};
use super::{closest, normalize, space, Binding, Resolver};
use crate::{BodyKind, Load, Value};

impl Resolver<'_> {
    pub(super) fn load(
        &mut self,
        name: &Ident,
        body: &Ident,
        at: Option<&Expr>,
        value: &Expr,
        span: Span,
        torque: bool,
    ) {
        let key = normalize(&body.name);
        let index = match self.scope.names.get(&key) {
            Some(Binding::Body(i)) => *i,
            _ => {
                let bodies: Vec<String> =
                    self.model.bodies.iter().map(|b| b.name.clone()).collect();
                let mut d = Diagnostic::error(body.span, format!("no body named `{}`", body.name))
                    .with_label("not a particle or body");
                if let Some(near) = closest(&key, bodies.iter().map(String::as_str)) {
                    d = d.with_hint(format!("did you mean `{near}`?"));
                }
                self.error(d);
                return;
            }
        };
        let role = if torque { &TORQUE } else { &FORCE };
        let dim = self.model.bodies[index].position.len();
        let kind = self.model.bodies[index].kind();
        // The point a force acts at, when it is not the centre of mass.
        let mut point = None;
        if let Some(at) = at {
            if kind == BodyKind::Particle {
                self.error(
                    Diagnostic::error(at.span, "a particle is a point: a force on it acts there")
                        .with_label("a point of a particle")
                        .with_hint(format!(
                            "drop `at …`, or declare `{}` as a rigid `body`",
                            body.name
                        )),
                );
                return;
            }
            let Some((p, p_dims)) = self.value_in_role(at, &POSITION) else { return };
            match space::as_vector(&p).filter(|p| p.len() == dim) {
                Some(p) => point = Some((p, self.shape(p_dims).forms())),
                None => {
                    self.error(
                        Diagnostic::error(
                            at.span,
                            format!("expected a point, a {dim}-vector, found {}", p.kind_name()),
                        )
                        .with_label("not a point")
                        .with_hint("give the point in world axes, like the body's position"),
                    );
                    return;
                }
            }
        }
        let Some((v, dims)) = self.value_in_role(value, role) else { return };
        let v = match v {
            // `R*v` and written columns alike.
            Value::Matrix(_) => space::as_vector(&v).map(Value::Vector).unwrap_or(v),
            v => v,
        };
        self.load_energy(index, dims, value.span, torque, point.as_ref().map(|(_, f)| f.clone()));
        let ok = match (&v, torque) {
            (Value::Scalar(_), true) => kind == BodyKind::Planar,
            (Value::Vector(c), true) => kind == BodyKind::Spatial && c.len() == 3,
            (Value::Vector(c), false) => c.len() == dim,
            (Value::Scalar(_), false) => dim == 1,
            _ => false,
        };
        if torque && self.model.bodies[index].kind() == BodyKind::Particle {
            self.error(
                Diagnostic::error(
                    body.span,
                    format!("`{}` is a particle, and a torque needs a rigid body", body.name),
                )
                .with_label("a particle has no orientation")
                .with_hint("declare it with `body`, with an `inertia` and an `angle`"),
            );
            return;
        }
        if !ok {
            let expected = if torque && kind == BodyKind::Spatial {
                "a torque vector `(tx, ty, tz)` in world axes on a body in space".to_string()
            } else if torque {
                "a scalar torque on a rigid `body`".to_string()
            } else {
                format!("a {dim}-vector, like the body's position")
            };
            self.error(
                Diagnostic::error(
                    value.span,
                    format!("expected {expected}, found {}", v.kind_name()),
                )
                .with_label("here"),
            );
            return;
        }
        let at = point.map(|(p, _)| p);
        let load = Load { name: normalize(&name.name), body: index, value: v, at, span };
        if torque {
            self.model.torques.push(load);
        } else {
            self.model.forces.push(load);
        }
    }
}
