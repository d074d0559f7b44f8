//! `draw` lines: shapes in world coordinates for `simulate --animate`. Their points are vector
//! expressions of the state (a body's name stands for its position, as in a spring), of the
//! scene's dimension; a drawing changes nothing in the equations.

use cas::ExprId;
use lang::{Diagnostic, Expr, ExprKind, Shape, Span};

use super::checks::DRAWING;
use super::{normalize, Binding, Resolver};
use crate::units::Form;
use crate::{Drawing, Figure, Value};

impl Resolver<'_> {
    /// A `draw` line: its shape resolved, or its mistakes reported.
    pub(super) fn draw(&mut self, shape: &Shape, span: Span) {
        self.in_drawing = true;
        let figure = self.figure(shape);
        self.in_drawing = false;
        if let Some(figure) = figure {
            let label = self.text(span);
            self.model.drawings.push(Drawing { label, figure, span });
        }
    }

    fn figure(&mut self, shape: &Shape) -> Option<Figure> {
        // Every coordinate of every point of one shape has one dimension (a length, in a scene
        // with units), and so has a circle's radius.
        let mut length: Option<(Form, Span)> = None;
        match shape {
            Shape::Line { from, to } => {
                let (from, to) = (self.point(from, &mut length), self.point(to, &mut length));
                Some(Figure::Line { from: from?, to: to? })
            }
            Shape::Circle { centre, radius: written } => {
                let centre = self.point(centre, &mut length);
                let (radius, dims) = self.scalar_in_role(written, &DRAWING)?;
                let form = self.operand_form(dims);
                if let Some((first, at)) = &length {
                    self.scope.units.same(first, &form, *at, written.span, "in this drawing");
                }
                Some(Figure::Circle { centre: centre?, radius })
            }
            Shape::Polyline(points) => {
                let points: Vec<Option<Vec<ExprId>>> =
                    points.iter().map(|p| self.point(p, &mut length)).collect();
                Some(Figure::Polyline(points.into_iter().collect::<Option<Vec<_>>>()?))
            }
        }
    }

    /// A point of a drawing, with as many components as the scene has dimensions (a point in
    /// the plane is padded with z = 0 in a scene in space).
    fn point(&mut self, e: &Expr, length: &mut Option<(Form, Span)>) -> Option<Vec<ExprId>> {
        let body = match &e.kind {
            ExprKind::Name { name, primes: 0 } => match self.scope.names.get(&normalize(name)) {
                Some(Binding::Body(i)) => Some(*i),
                _ => None,
            },
            _ => None,
        };
        let (mut point, forms) = match body {
            Some(i) => {
                (self.model.bodies[i].position.clone(), self.scope.body_dims[i].position.clone())
            }
            None => {
                let (value, dims) = self.value_in_role(e, &DRAWING)?;
                let forms = self.operand(dims).forms();
                match value {
                    Value::Vector(v) => (v, forms),
                    other => {
                        self.error(
                            Diagnostic::error(
                                e.span,
                                format!("expected a point, found {}", other.kind_name()),
                            )
                            .with_label("not a point")
                            .with_hint(
                                "a drawing's points are vectors such as `(0, 0)`, \
                                 `bob.position` or a body's name",
                            ),
                        );
                        return None;
                    }
                }
            }
        };
        for form in forms {
            match length {
                Some((first, at)) => {
                    self.scope.units.same(first, &form, *at, e.span, "in this drawing")
                }
                None => *length = Some((form, e.span)),
            }
        }
        let dimension =
            self.model.bodies.iter().map(|b| b.position.len()).max().unwrap_or(2).max(2);
        if point.len() > dimension {
            self.error(
                Diagnostic::error(
                    e.span,
                    format!(
                        "a point in space ({} components) in a scene in the plane",
                        point.len()
                    ),
                )
                .with_label("a point in space")
                .with_hint("every body of this scene moves in the plane: draw points `(x, y)`"),
            );
            return None;
        }
        point.resize(dimension, self.model.pool.zero());
        Some(point)
    }
}
