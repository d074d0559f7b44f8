//! Expressions: values in SI, attachment points, constants, and the value and dimension of an
//! expression in a role.

use cas::SymbolKind;
use lang::{BinOp, Diagnostic, Expr, ExprKind, Span};

use super::checks::Role;
use super::dims::Dims;
use super::{normalize, Binding, Resolver, Separation};
use crate::units::Form;
use crate::Value;

impl Resolver<'_> {
    /// A value written with a unit, converted to SI (`30 deg` is π/6, `10 cm` is 1/10).
    pub(super) fn in_si(
        &mut self,
        value: cas::ExprId,
        unit: Option<&lang::Unit>,
    ) -> Option<cas::ExprId> {
        let Some(unit) = unit else { return Some(value) };
        match crate::units::parse_unit(unit) {
            Ok((_, scale)) => {
                let k = self.model.pool.num(scale.rational);
                let pi = self.model.pool.pi();
                let pi = self.model.pool.powi(pi, i64::from(scale.pi_power));
                Some(self.model.pool.mul(&[value, k, pi]))
            }
            Err(d) => {
                self.error(d);
                None
            }
        }
    }

    /// Where a spring or damper is attached: a body (its centre of mass) or a fixed point;
    /// with the dimensions of its coordinates.
    fn anchor(&mut self, e: &Expr, role: &Role) -> Option<(Vec<cas::ExprId>, Vec<Form>)> {
        if let ExprKind::Name { name, primes: 0 } = &e.kind {
            if let Some(Binding::Body(i)) = self.scope.names.get(&normalize(name)) {
                let i = *i;
                return Some((
                    self.model.bodies[i].position.clone(),
                    self.scope.body_dims[i].position.clone(),
                ));
            }
        }
        let (value, dims) = self.value_in_role(e, role)?;
        let forms = self.shape(dims).forms();
        match value {
            Value::Vector(v) => Some((v, forms)),
            other => {
                self.error(
                    Diagnostic::error(e.span, format!("expected a body or a point, found {}", other.kind_name()))
                        .with_label("not an attachment")
                        .with_hint("attach to a `particle` or `body` by name, or to a fixed point such as (0, 0)"),
                );
                None
            }
        }
    }

    /// B − A for two attachments, padding the shorter with zeros (a 2D point in 3D), with the
    /// dimension of its length and the two ends as written (for drawing).
    pub(super) fn separation(&mut self, a: &Expr, b: &Expr, role: &Role) -> Option<Separation> {
        let (pa, pb) = (self.anchor(a, role), self.anchor(b, role));
        let (Some((pa, mut ends)), Some((pb, b_ends))) = (pa, pb) else { return None };
        ends.extend(b_ends);
        let length = self.separation_dims(ends, a.span, b.span);
        let n = pa.len().max(pb.len());
        let zero = self.model.pool.zero();
        let difference = (0..n)
            .map(|i| self.model.pool.sub(*pb.get(i).unwrap_or(&zero), *pa.get(i).unwrap_or(&zero)))
            .collect();
        Some(Separation { difference, length, ends: [pa, pb] })
    }

    /// |B − A|², with the separation it is of.
    pub(super) fn separation_squared(
        &mut self,
        a: &Expr,
        b: &Expr,
        role: &Role,
    ) -> Option<(cas::ExprId, Separation)> {
        let separation = self.separation(a, b, role)?;
        let squares: Vec<cas::ExprId> =
            separation.difference.iter().map(|x| self.model.pool.powi(*x, 2)).collect();
        Some((self.model.pool.add(&squares), separation))
    }

    /// A scalar that may not depend on coordinates or time (initial values, parameter values).
    pub(super) fn constant(&mut self, e: &Expr) -> Option<(cas::ExprId, Dims)> {
        let (v, dims) = self.scalar(e)?;
        let moving = self
            .model
            .pool
            .free_symbols(v)
            .iter()
            .any(|s| !matches!(self.model.pool.symbol(*s).kind, SymbolKind::Param));
        if let (false, Some(input)) = (moving, self.input_in(&Value::Scalar(v))) {
            let name = self.model.pool.symbol(input).name.clone();
            self.error(
                Diagnostic::error(e.span, "this value must be a constant")
                    .with_label(format!("depends on the input `{name}`"))
                    .with_hint(
                        "an input varies in time; constants may use numbers and parameters only",
                    ),
            );
            return None;
        }
        if moving {
            self.error(
                Diagnostic::error(e.span, "this value must be a constant")
                    .with_label("depends on a coordinate or on time")
                    .with_hint(
                        "initial values and parameter values may use numbers and parameters only",
                    ),
            );
            return None;
        }
        self.finite(v, e).then_some((v, dims))
    }

    /// [`Self::value`], refused when it has derivatives its role does not allow.
    pub(super) fn value_in_role(&mut self, e: &Expr, role: &Role) -> Option<(Value, Dims)> {
        let (v, dims) = self.value(e)?;
        let within = self.within_role(e, &v, role);
        if within {
            self.warn_kinks(e, &v, role);
        }
        within.then_some((v, dims))
    }

    /// [`Self::scalar`], refused when it has derivatives its role does not allow.
    pub(super) fn scalar_in_role(&mut self, e: &Expr, role: &Role) -> Option<(cas::ExprId, Dims)> {
        let (v, dims) = self.scalar(e)?;
        let within = self.within_role(e, &Value::Scalar(v), role);
        if within {
            self.warn_kinks(e, &Value::Scalar(v), role);
        }
        within.then_some((v, dims))
    }

    pub(super) fn scalar(&mut self, e: &Expr) -> Option<(cas::ExprId, Dims)> {
        match self.value(e)? {
            (Value::Scalar(x), dims) => Some((x, dims)),
            (other, _) => {
                self.error(
                    Diagnostic::error(
                        e.span,
                        format!("expected a scalar, found {}", other.kind_name()),
                    )
                    .with_label("not a scalar"),
                );
                None
            }
        }
    }

    /// The value of `e`, and what is known of its dimension.
    pub(super) fn value(&mut self, e: &Expr) -> Option<(Value, Dims)> {
        match &e.kind {
            ExprKind::Number(text) => match cas::number::parse_decimal(text) {
                Some(q) => {
                    let v = self.model.pool.num(q);
                    Some((Value::Scalar(v), self.number_dims(v, true)))
                }
                None => {
                    self.error(
                        Diagnostic::error(
                            e.span,
                            format!("`{text}` is not a number lagrange can use"),
                        )
                        .with_label("out of range")
                        .with_hint("exponents beyond ±4000 are not supported"),
                    );
                    None
                }
            },
            ExprKind::Name { name, primes } => self.name(name, *primes, e.span),
            ExprKind::Member { object, field, component: None } => {
                self.member(object, field, e.span)
            }
            // `roll.x.force`, as reports name a component's reaction, is `roll.force.x`.
            ExprKind::Member { object, field, component: Some(c) }
                if c.name == "force"
                    && matches!(field.name.as_str(), "x" | "y" | "z")
                    && matches!(
                        self.scope.names.get(&normalize(&object.name)),
                        Some(Binding::Constraint(_))
                    ) =>
            {
                let (v, dims) = self.member(object, c, e.span)?;
                self.component(v, dims, field, &format!("{}.force", object.name))
            }
            ExprKind::Member { object, field, component: Some(c) } => {
                let (v, dims) = self.member(object, field, e.span)?;
                self.component(v, dims, c, &format!("{}.{}", object.name, field.name))
            }
            ExprKind::Call { func, args } => self.call(func, args, e.span),
            ExprKind::Neg(inner) => {
                let (v, dims) = self.value(inner)?;
                let v = v.map(|x| self.model.pool.neg(x));
                let dims = match (dims, &v) {
                    (Dims::Number { decided, .. }, Value::Scalar(x)) => {
                        self.number_dims(*x, decided)
                    }
                    (dims, _) => dims,
                };
                Some((v, dims))
            }
            ExprKind::Binary { op, lhs, rhs } => {
                if let (BinOp::Mul | BinOp::Div, ExprKind::Neg(inner)) = (op, &lhs.kind) {
                    // `-a*b` is built as −(a·b), the product it prints back from: as (−a)·b a
                    // sum a would take the sign into its terms, `-(y + z)*x` would read back as
                    // `(-y - z)*x`, and print so.
                    let product = Expr {
                        kind: ExprKind::Binary { op: *op, lhs: inner.clone(), rhs: rhs.clone() },
                        span: Span { start: inner.span.start, end: rhs.span.end },
                    };
                    let negated = Expr { kind: ExprKind::Neg(Box::new(product)), span: e.span };
                    return self.value(&negated);
                }
                let (l, r) = (self.value(lhs), self.value(rhs));
                let ((l, l_dims), (r, r_dims)) = (l?, r?);
                let v = self.binary(*op, l, r, lhs, rhs)?;
                let dims = self.binary_dims(*op, (l_dims, r_dims), lhs, rhs, &v);
                Some((v, dims))
            }
            ExprKind::Tuple(items) => {
                let mut out = Vec::new();
                for item in items {
                    out.push(self.scalar(item));
                }
                let (out, dims): (Vec<_>, Vec<_>) =
                    out.into_iter().collect::<Option<Vec<_>>>()?.into_iter().unzip();
                let forms = dims.into_iter().map(|d| self.operand_form(d)).collect();
                Some((Value::Vector(out), Dims::Many(forms)))
            }
            ExprKind::Matrix(rows) => {
                let mut out = Vec::new();
                for row in rows {
                    let mut r = Vec::new();
                    for item in row {
                        r.push(self.scalar(item));
                    }
                    out.push(r.into_iter().collect::<Option<Vec<_>>>());
                }
                let out = out.into_iter().collect::<Option<Vec<_>>>()?;
                let (out, grid): (Vec<Vec<_>>, Vec<Vec<_>>) =
                    out.into_iter().map(|row| row.into_iter().unzip()).unzip();
                let width = out.first().map_or(0, |r| r.len());
                if out.iter().any(|r| r.len() != width) {
                    self.error(
                        Diagnostic::error(e.span, "the rows of this matrix have different lengths")
                            .with_label("ragged matrix")
                            .with_hint("separate entries with `,` and rows with `;`"),
                    );
                    return None;
                }
                Some((Value::Matrix(out), Dims::Grid(grid)))
            }
        }
    }
}
