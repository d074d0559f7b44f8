//! Vectors and rotations as values: the functions a scene calls on them (`dot`, `cross`,
//! `norm`, `rotx`, `roty`, `rotz`, `rotation`, `transpose`, `dt`), each with its value and
//! its dimension, and the members of a rigid body in space (`omega`, `omega_body`, `axes`).

use cas::number::One;
use cas::{ExprId, Rational};
use lang::{Diagnostic, Expr, Ident, Span};

use super::dims::Dims;
use super::normalize;
use super::Resolver;
use crate::kinematics;
use crate::units::Form;
use crate::{Constraint, ConstraintKind, Placeholder, Rotation, Value};

/// The functions of vectors and matrices, with what each takes, for hints.
pub(super) const SPACE_FUNCTIONS: [(&str, &str); 10] = [
    ("dot", "two vectors of one length"),
    ("cross", "two 3-vectors"),
    ("norm", "a vector"),
    ("rotx", "an angle"),
    ("roty", "an angle"),
    ("rotz", "an angle"),
    ("rotation", "an axis (a 3-vector) and an angle"),
    ("quaternion", "four coordinates e0, e1, e2, e3 (Euler parameters)"),
    ("transpose", "a matrix"),
    ("dt", "any expression, vector or matrix"),
];

pub(super) fn is_space_function(name: &str) -> bool {
    SPACE_FUNCTIONS.iter().any(|(n, _)| *n == name)
}

/// A vector's entries, whether written `(x, y, z)` or as the column `[x; y; z]`.
pub(super) fn as_vector(v: &Value) -> Option<Vec<ExprId>> {
    match v {
        Value::Vector(v) => Some(v.clone()),
        Value::Matrix(m) if m.iter().all(|r| r.len() == 1) => {
            Some(m.iter().map(|r| r[0]).collect())
        }
        Value::Scalar(_) | Value::Matrix(_) => None,
    }
}

/// A dimensionless 3×3 grid: the dimension of a rotation matrix.
fn rotation_dims() -> Dims {
    Dims::Grid(vec![vec![Dims::Scalar(Form::default()); 3]; 3])
}

/// A call of one of [`SPACE_FUNCTIONS`] whose arguments have resolved.
struct SpaceCall<'a> {
    name: &'a str,
    /// What it takes, for the messages.
    takes: &'a str,
    args: &'a [Expr],
    values: Vec<Value>,
    span: Span,
}

impl Resolver<'_> {
    /// A call of one of [`SPACE_FUNCTIONS`].
    pub(super) fn space_call(
        &mut self,
        name: &str,
        args: &[Expr],
        span: Span,
    ) -> Option<(Value, Dims)> {
        let arity = match name {
            "rotation" | "dot" | "cross" => 2,
            "quaternion" => 4,
            _ => 1,
        };
        let takes = SPACE_FUNCTIONS.iter().find(|(n, _)| *n == name).map_or("", |(_, t)| *t);
        if args.len() != arity {
            self.error(
                Diagnostic::error(
                    span,
                    format!("`{name}` takes {arity} argument{}", if arity == 1 { "" } else { "s" }),
                )
                .with_label(format!("given {}", args.len()))
                .with_hint(format!("`{name}` takes {takes}")),
            );
            return None;
        }
        let mut resolved = Vec::new();
        for a in args {
            resolved.push(self.value(a));
        }
        let resolved = resolved.into_iter().collect::<Option<Vec<_>>>()?;
        let (values, dims): (Vec<Value>, Vec<Dims>) = resolved.into_iter().unzip();
        let call = SpaceCall { name, takes, args, values, span };
        match name {
            "dot" | "cross" => self.product_call(&call, dims),
            "norm" => {
                let Some(u) = as_vector(&call.values[0]) else {
                    return self.wrong_argument(&call, 0, "a vector");
                };
                let form = self.components(dims.into_iter().next().expect("one"), args[0].span);
                let squares: Vec<ExprId> = u.iter().map(|x| self.model.pool.powi(*x, 2)).collect();
                let sum = self.model.pool.add(&squares);
                let sum = self.model.pool.simplify(sum);
                Some((Value::Scalar(self.model.pool.sqrt(sum)), Dims::Scalar(form)))
            }
            "rotx" | "roty" | "rotz" => {
                let Value::Scalar(angle) = call.values[0] else {
                    return self.wrong_argument(&call, 0, "an angle");
                };
                let form = self.form(dims.into_iter().next().expect("one"));
                self.scope.units.dimensionless(
                    &form,
                    args[0].span,
                    &format!("the angle of {name}"),
                );
                let axis = match name {
                    "rotx" => 0,
                    "roty" => 1,
                    _ => 2,
                };
                let r = kinematics::elementary(&mut self.model.pool, axis, angle);
                Some((Value::Matrix(kinematics::rows(&r)), rotation_dims()))
            }
            "rotation" => self.rotation_call(&call, dims),
            "quaternion" => self.quaternion_call(&call, dims),
            "transpose" => self.transpose_call(&call, dims),
            _ => self.rate_call(&call, dims),
        }
    }

    /// A wrong argument of a call of one of [`SPACE_FUNCTIONS`], reported.
    fn wrong_argument(
        &mut self,
        call: &SpaceCall<'_>,
        i: usize,
        expected: &str,
    ) -> Option<(Value, Dims)> {
        let SpaceCall { name, takes, args, values, .. } = call;
        self.error(
            Diagnostic::error(
                args[i].span,
                format!("`{name}` takes {takes}, not {}", values[i].kind_name()),
            )
            .with_label(format!("expected {expected}")),
        );
        None
    }

    /// `dot(u, v)` or `cross(u, v)`: the product of two vectors, in the product of their units.
    fn product_call(&mut self, call: &SpaceCall<'_>, dims: Vec<Dims>) -> Option<(Value, Dims)> {
        let &SpaceCall { name, args, ref values, .. } = call;
        let (Some(u), Some(v)) = (as_vector(&values[0]), as_vector(&values[1])) else {
            let i = usize::from(as_vector(&values[0]).is_some());
            return self.wrong_argument(call, i, "a vector");
        };
        let length = if name == "cross" { 3 } else { u.len() };
        for (i, w) in [&u, &v].into_iter().enumerate() {
            if w.len() != length {
                return self.wrong_argument(call, i, &format!("a {length}-vector"));
            }
        }
        let mut dims = dims.into_iter();
        let a = self.components(dims.next().expect("two"), args[0].span);
        let b = self.components(dims.next().expect("two"), args[1].span);
        let product = a.plus(&b, &Rational::one());
        if name == "dot" {
            Some((
                Value::Scalar(kinematics::dot(&mut self.model.pool, &u, &v)),
                Dims::Scalar(product),
            ))
        } else {
            let w = kinematics::cross(&mut self.model.pool, &u, &v);
            Some((Value::Vector(w), Dims::Many(vec![product; 3])))
        }
    }

    /// `rotation(axis, angle)`: the rotation matrix about a non-zero axis.
    fn rotation_call(&mut self, call: &SpaceCall<'_>, dims: Vec<Dims>) -> Option<(Value, Dims)> {
        let &SpaceCall { args, ref values, .. } = call;
        let axis = as_vector(&values[0]).filter(|v| v.len() == 3);
        let Some(axis) = axis else { return self.wrong_argument(call, 0, "a 3-vector") };
        let Value::Scalar(angle) = values[1] else {
            return self.wrong_argument(call, 1, "an angle");
        };
        if axis.iter().all(|x| self.model.pool.is_identically_zero(*x)) {
            self.error(
                Diagnostic::error(args[0].span, "a rotation's axis cannot be zero")
                    .with_label("this vector is zero")
                    .with_hint("give the direction to turn about, such as (0, 0, 1)"),
            );
            return None;
        }
        if let Some(d) = self.zero_at_values(&axis, &args[0]) {
            self.error(d);
            return None;
        }
        let mut dims = dims.into_iter();
        self.components(dims.next().expect("two"), args[0].span);
        let form = self.form(dims.next().expect("two"));
        self.scope.units.dimensionless(&form, args[1].span, "the angle of a rotation");
        let axis = [axis[0], axis[1], axis[2]];
        let r = kinematics::about_axis(&mut self.model.pool, axis, angle);
        Some((Value::Matrix(kinematics::rows(&r)), rotation_dims()))
    }

    /// `quaternion(e0, e1, e2, e3)`: the rotation matrix of four Euler parameters.
    fn quaternion_call(&mut self, call: &SpaceCall<'_>, dims: Vec<Dims>) -> Option<(Value, Dims)> {
        let &SpaceCall { args, ref values, span, .. } = call;
        let mut e = Vec::new();
        for (i, v) in values.iter().enumerate() {
            match v {
                Value::Scalar(x) => e.push(*x),
                _ => return self.wrong_argument(call, i, "a scalar"),
            }
        }
        for (d, a) in dims.into_iter().zip(args) {
            let form = self.form(d);
            self.scope.units.dimensionless(&form, a.span, "an Euler parameter");
        }
        let e = [e[0], e[1], e[2], e[3]];
        let r = kinematics::from_quaternion(&mut self.model.pool, e);
        let rows = kinematics::rows(&r);
        self.scope.quaternions.push((rows.clone(), e, span));
        Some((Value::Matrix(rows), rotation_dims()))
    }

    /// `transpose(m)`: a matrix with its rows and columns swapped, dimensions too.
    fn transpose_call(&mut self, call: &SpaceCall<'_>, dims: Vec<Dims>) -> Option<(Value, Dims)> {
        let SpaceCall { values, .. } = call;
        let Value::Matrix(m) = &values[0] else { return self.wrong_argument(call, 0, "a matrix") };
        let t = kinematics::transpose(m);
        let dims = match dims.into_iter().next().expect("one") {
            Dims::Grid(g) => {
                let columns = g.first().map_or(0, Vec::len);
                let mut out: Vec<Vec<Dims>> = vec![Vec::new(); columns];
                for row in g {
                    for (j, d) in row.into_iter().enumerate() {
                        out[j].push(d);
                    }
                }
                Dims::Grid(out)
            }
            other => other,
        };
        Some((Value::Matrix(t), dims))
    }

    /// `dt(x)`: the total time derivative, entry by entry, with each dimension per time.
    fn rate_call(&mut self, call: &SpaceCall<'_>, dims: Vec<Dims>) -> Option<(Value, Dims)> {
        let &SpaceCall { ref values, span, .. } = call;
        // dt: the total time derivative, entry by entry.
        if !self.derivative_exists(&values[0], 1, span) {
            return None;
        }
        let value = values[0].clone().map(|x| self.total_rate(x, span));
        let dims = match dims.into_iter().next().expect("one") {
            Dims::Number { .. } => Dims::Scalar(Form::default()),
            Dims::Scalar(f) => Dims::Scalar(f.rate(1)),
            Dims::Many(v) => Dims::Many(v.iter().map(|f| f.rate(1)).collect()),
            Dims::Grid(g) => {
                let g = g
                    .into_iter()
                    .map(|row| {
                        row.into_iter().map(|d| Dims::Scalar(self.form(d).rate(1))).collect()
                    })
                    .collect();
                Dims::Grid(g)
            }
        };
        Some((value, dims))
    }

    /// The one dimension all components of a vector share, stated as a fact.
    pub(super) fn components(&mut self, d: Dims, span: Span) -> Form {
        let forms = self.shape(d).forms();
        let Some(first) = forms.first().cloned() else { return Form::default() };
        for f in &forms[1..] {
            self.scope.units.same(&first, f, span, span, "between the components of a vector");
        }
        first
    }
}

impl Resolver<'_> {
    /// The rotation of a body in space from its `orientation` and `inertia`: the inertia as a
    /// symmetric tensor in body axes (a scalar is the same about every axis, a 3-vector the
    /// principal moments), and the orientation checked to be a rotation.
    pub(super) fn spatial_rotation(
        &mut self,
        name: &Ident,
        orientation: Vec<Vec<ExprId>>,
        orientation_span: Span,
        inertia: Value,
        inertia_written: &Expr,
        position: Option<&[ExprId]>,
    ) -> Option<Rotation> {
        if let Some(p) = position.filter(|p| p.len() != 3) {
            self.error(
                Diagnostic::error(
                    name.span,
                    format!(
                        "`{}` turns in space but its position has {} components",
                        name.name,
                        p.len()
                    ),
                )
                .with_label("an orientation needs a 3-vector position")
                .with_hint("give the centre of mass as `(x, y, z)`"),
            );
            return None;
        }
        let tensor = self.inertia_tensor(name, &inertia, inertia_written)?;
        if let Some((_, e, _)) = self.scope.quaternions.iter().find(|(m, _, _)| *m == orientation) {
            // Orthogonal only where e0² + e1² + e2² + e3² = 1, which a constraint then keeps.
            let e = *e;
            self.unit_quaternion(name, e, orientation_span);
            let orientation = kinematics::matrix3(&orientation).expect("3×3 checked by the caller");
            let euler_parameters = Some(e);
            return Some(Rotation::Spatial { inertia: tensor, orientation, euler_parameters });
        }
        if !self.is_rotation(&orientation, orientation_span) {
            return None;
        }
        let orientation = kinematics::matrix3(&orientation).expect("3×3 checked by the caller");
        Some(Rotation::Spatial { inertia: tensor, orientation, euler_parameters: None })
    }

    /// The inertia of a body in space as a symmetric tensor in body axes: a scalar is the same
    /// about every axis, a 3-vector the principal moments. Checked to be one a body can have.
    fn inertia_tensor(
        &mut self,
        name: &Ident,
        inertia: &Value,
        inertia_written: &Expr,
    ) -> Option<[[ExprId; 3]; 3]> {
        let zero = self.model.pool.zero();
        let tensor: [[ExprId; 3]; 3] = match inertia {
            Value::Scalar(i) => {
                std::array::from_fn(|r| std::array::from_fn(|c| if r == c { *i } else { zero }))
            }
            Value::Vector(v) if v.len() == 3 => {
                std::array::from_fn(|r| std::array::from_fn(|c| if r == c { v[r] } else { zero }))
            }
            Value::Matrix(m) if kinematics::matrix3(m).is_some() => {
                let m = kinematics::matrix3(m).expect("checked");
                for (r, c) in [(0, 1), (0, 2), (1, 2)] {
                    let d = self.model.pool.sub(m[r][c], m[c][r]);
                    if !self.model.pool.is_identically_zero(d) {
                        self.error(
                            Diagnostic::error(
                                inertia_written.span,
                                "an inertia tensor is symmetric",
                            )
                            .with_label(format!(
                                "entry ({}, {}) differs from entry ({}, {})",
                                r + 1,
                                c + 1,
                                c + 1,
                                r + 1
                            ))
                            .with_hint(
                                "give Ixy, Ixz and Iyz once above the diagonal and again below it",
                            ),
                        );
                        return None;
                    }
                }
                m
            }
            other => {
                self.error(
                    Diagnostic::error(
                        inertia_written.span,
                        format!("expected the inertia of a body in space, found {}", other.kind_name()),
                    )
                    .with_label("not an inertia")
                    .with_hint(
                        "give the principal moments `(A, B, C)` or the tensor `[Ixx, Ixy, Ixz; Ixy, \
                         Iyy, Iyz; Ixz, Iyz, Izz]`, about the centre of mass in body axes",
                    ),
                );
                return None;
            }
        };
        let errors = self.diagnostics.errors.len();
        for (r, row) in tensor.iter().enumerate() {
            if !matches!(inertia, Value::Scalar(_)) {
                self.check_sign(name, row[r], inertia_written, true);
            }
        }
        if self.diagnostics.errors.len() == errors {
            self.check_inertia_tensor(name, &tensor, inertia_written);
        }
        Some(tensor)
    }

    /// Whether `orientation` is a rotation: Rᵀ·R = I and det R = 1; reported where it is
    /// written if not.
    fn is_rotation(&mut self, orientation: &[Vec<ExprId>], orientation_span: Span) -> bool {
        let rows = kinematics::transpose(orientation);
        let gram = kinematics::product(&mut self.model.pool, &rows, orientation);
        for (r, row) in gram.iter().enumerate() {
            for (c, entry) in row.iter().enumerate() {
                let identity = if r == c { self.model.pool.one() } else { self.model.pool.zero() };
                let d = self.model.pool.sub(*entry, identity);
                if !self.model.pool.is_identically_zero(d) {
                    self.error(
                        Diagnostic::error(orientation_span, "this orientation is not a rotation")
                            .with_label(format!(
                                "entry ({}, {}) of Rᵀ·R is not {}",
                                r + 1,
                                c + 1,
                                if r == c { 1 } else { 0 }
                            ))
                            .with_hint(
                                "build it from rotx, roty, rotz and rotation(axis, angle), whose \
                                 products are rotations",
                            ),
                    );
                    return false;
                }
            }
        }
        // Rᵀ·R = I leaves det R = ±1; −1 is a mirror image, and Rᵀ·Ṙ is then not the body's ω.
        let cross = kinematics::cross(&mut self.model.pool, &orientation[1], &orientation[2]);
        let det = kinematics::dot(&mut self.model.pool, &orientation[0], &cross);
        let one = self.model.pool.one();
        let off = self.model.pool.sub(det, one);
        if !self.model.pool.is_identically_zero(off) {
            self.error(
                Diagnostic::error(
                    orientation_span,
                    "this orientation is a reflection, not a rotation",
                )
                .with_label("its determinant is -1: it turns the body inside out")
                .with_hint(
                    "one axis is flipped (a left-handed frame), and ω from Rᵀ·Ṙ would not be the \
                         body's angular velocity; negate one column (a body axis) to make the \
                         frame right-handed, or build it from rotx, roty, rotz and \
                         rotation(axis, angle)",
                ),
            );
            return false;
        }
        true
    }
}

impl Resolver<'_> {
    /// The constraint e0² + e1² + e2² + e3² = 1 of a body oriented by Euler parameters, named
    /// `BODY_unit`; it is kept with a multiplier, so the parameters never leave the unit
    /// sphere, and a body that tumbles meets no singular configuration.
    fn unit_quaternion(&mut self, body: &Ident, e: [ExprId; 4], span: Span) {
        if self.model.constraints.iter().any(|c| c.quaternion == Some(e)) {
            return;
        }
        let squares: Vec<ExprId> = e.iter().map(|x| self.model.pool.powi(*x, 2)).collect();
        let lhs = self.model.pool.add(&squares);
        let rhs = self.model.pool.one();
        let phi = self.model.pool.sub(lhs, rhs);
        let index = self.model.constraints.len();
        let name = format!("{}_unit", normalize(&body.name));
        let force_symbol = self.model.pool.param(&format!("{name}.force"));
        self.model.placeholders.push((force_symbol, Placeholder::Reaction(index)));
        self.model.constraints.push(Constraint {
            name,
            kind: ConstraintKind::Position,
            lhs,
            rhs,
            phi,
            force_symbol,
            force_requested: false,
            lhs_coords: Vec::new(),
            quaternion: Some(e),
            span,
        });
    }
}

impl Resolver<'_> {
    /// `.x`, `.y` or `.z` of a vector value (`top.omega_body.z`, `roll.force.x`), with its
    /// dimension.
    pub(super) fn component(
        &mut self,
        value: Value,
        dims: Dims,
        field: &Ident,
        what: &str,
    ) -> Option<(Value, Dims)> {
        let components = as_vector(&value);
        let i = match field.name.as_str() {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => usize::MAX,
        };
        let Some(x) = components.as_ref().and_then(|c| c.get(i)).copied() else {
            let label = match &components {
                Some(c) if c.len() == 2 => "expected x or y".to_string(),
                Some(_) => "expected x, y or z".to_string(),
                None => format!("`{what}` is {}", value.kind_name()),
            };
            self.error(
                Diagnostic::error(field.span, format!("`{what}` has no `{}`", field.name))
                    .with_label(label)
                    .with_hint("a vector's components are `.x`, `.y` and `.z`"),
            );
            return None;
        };
        let forms = self.shape(dims).forms();
        Some((Value::Scalar(x), Dims::Scalar(forms.get(i).cloned().unwrap_or_default())))
    }
}

#[cfg(test)]
mod tests {
    /// The messages of the errors `body`'s line gets, in a scene around it.
    fn errors(params: &str, body: &str) -> Vec<String> {
        let source = format!("param m = 1 kg, {params}\ncoord a, c\n{body}\n");
        let file = lang::parse(&source).expect("parses");
        match crate::resolve(&file, &source) {
            Ok(_) => Vec::new(),
            Err(e) => e.into_iter().map(|d| format!("{}: {}", d.message, d.label)).collect(),
        }
    }

    fn body(inertia: &str, orientation: &str) -> String {
        format!(
            "body b {{ mass m; inertia {inertia}; orientation {orientation}; position (0, 0, 0) }}"
        )
    }

    #[test]
    fn thin_plates_and_rods_are_bodies_and_a_hair_past_them_is_not() {
        let p = "A = 1 kg*m^2, r = 2 m";
        for inertia in [
            "(A, A, 2*A)",
            "(0, m*r^2, m*r^2)",
            "(0, 0, 0)",
            "[2*A, A/2, 0; A/2, 2*A, 0; 0, 0, A]",
            "[sqrt(2), 1, 0; 1, sqrt(2), 0; 0, 0, 2*sqrt(2)]*A",
            "[A, A, 0; A, A, 0; 0, 0, 2*A]",
        ] {
            let e = errors(p, &body(inertia, "rotz(a)*rotx(c)"));
            assert!(e.is_empty(), "{inertia} refused: {e:?}");
        }
        for (inertia, says) in [
            ("(A, A, 2*A + A/10^6)", "more than the other two moments together"),
            ("(2.000001*A, A, A)", "`2.000001*A` is 2000001/1000000 kg·m²"),
            ("[2*A, A/2, 0; A/2, 2*A, 0; 0, 0, 0.999*A]", "one principal moment is more"),
            ("[A, A, 0; A, A*0.999, 0; 0, 0, 2*A]", "Ixx·Iyy − Ixy² is -1/1000"),
            ("[A, 0, A; 0, A, 0; A, 0, A/2]", "Ixx·Izz − Ixz² is -1/2"),
            ("[10, 9, 9; 9, 10, -9; 9, -9, 10]*A", "its determinant is -2888 "),
        ] {
            let e = errors(p, &body(inertia, "rotz(a)"));
            assert!(e.len() == 1 && e[0].contains(says), "{inertia}: {e:?}");
        }
    }

    #[test]
    fn an_inertia_that_depends_on_the_state_is_left_to_the_state() {
        let e = errors("A = 1 kg*m^2", &body("(A, A, A*(2 + sin(a)^2))", "rotz(a)"));
        assert!(e.is_empty(), "{e:?}");
    }

    #[test]
    fn a_reflection_is_refused_and_a_rotation_written_out_is_not() {
        let p = "A = 1 kg*m^2";
        let turn = "[cos(a), -sin(a), 0; sin(a), cos(a), 0; 0, 0, 1]";
        assert!(errors(p, &body("(A, A, A)", turn)).is_empty());
        for mirror in [
            "[cos(a), -sin(a), 0; sin(a), cos(a), 0; 0, 0, -1]",
            "rotz(a)*[1, 0, 0; 0, -1, 0; 0, 0, 1]",
            "-rotx(a)",
        ] {
            let e = errors(p, &body("(A, A, A)", mirror));
            assert!(e.len() == 1 && e[0].contains("a reflection"), "{mirror}: {e:?}");
        }
    }

    #[test]
    fn an_axis_zero_only_at_the_parameters_values_is_refused_at_the_axis() {
        let e = errors("A = 1 kg*m^2, k = 0, n = 1", &body("(A, A, A)", "rotation((k, 0, 0), a)"));
        assert!(e.len() == 1 && e[0].contains("(0, 0, 0) at the parameters' values"), "{e:?}");
        let e = errors("A = 1 kg*m^2, k = 0, n = 1", &body("(A, A, A)", "rotation((k, 0, n), a)"));
        assert!(e.is_empty(), "{e:?}");
        // An axis that moves is not judged at the parameters' values.
        let e = errors("A = 1 kg*m^2, k = 0", &body("(A, A, A)", "rotation((k, 0, c), a)"));
        assert!(e.is_empty(), "{e:?}");
    }
}
