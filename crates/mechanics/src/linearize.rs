//! Small motions about a reference, exactly: the `linearize about` lines merged into one
//! reference, the coordinates that are cyclic there, and M, C, K of
//! M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ as expressions of the parameters (with the multipliers'
//! symbols where constraints are kept). Whether the reference is an equilibrium where the
//! algebra cannot say, and everything after (eigenvalues, stability), is for numbers.
//!
//! With q̈ = 0 at the reference, the term ∂M/∂q·q̈ of the linearized M·q̈ drops out, so the
//! Jacobians of f (and of Jᵀλ) are all there is to it: K = −∂(f + Jᵀλ)/∂q and C = −∂f/∂q̇.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use model::ConstraintKind;

use crate::derive::Derivation;

/// A kept constraint at the reference: its linearized row J·δq = 0, and Φ and γ there (both
/// must vanish for the reference to lie on it and stay there).
#[derive(Clone, Debug)]
pub struct LinearConstraint {
    /// Its index among the model's constraints.
    pub constraint: usize,
    /// The multiplier's symbol (`rod.force`), which appears in K and in the residual.
    pub lambda: SymId,
    pub jacobian: Vec<ExprId>,
    pub phi: ExprId,
    pub bias: ExprId,
}

/// M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ about a reference, exactly.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// The remaining coordinates, in the derivation's order; every matrix is indexed by them.
    pub coords: Vec<SymId>,
    /// Whether each is cyclic: in neither M nor f nor a kept constraint, so that its position
    /// does not enter, its column of K is zero, and δq of it can leave the state.
    pub cyclic: Vec<bool>,
    /// The reference position of each coordinate; `None` for a cyclic one not given.
    pub positions: Vec<Option<ExprId>>,
    /// The reference rate of each coordinate (0 unless given).
    pub rates: Vec<ExprId>,
    pub mass: Vec<Vec<ExprId>>,
    pub damping: Vec<Vec<ExprId>>,
    pub stiffness: Vec<Vec<ExprId>>,
    /// f + Jᵀλ at the reference, λ the multipliers' symbols: what M·q̈ is there. Zero at an
    /// equilibrium or a steady motion.
    pub residual: Vec<ExprId>,
    /// Whether the algebra shows the residual zero, for every value of the parameters (without
    /// kept constraints only: with them, the multipliers' values are for numbers to find).
    pub residual_is_zero: bool,
    pub constraints: Vec<LinearConstraint>,
    /// The last `linearize about` line, which the reference is reported at.
    pub span: Span,
}

impl Derivation {
    /// Linearizes the equations of motion about the reference of the scene's `linearize about`
    /// lines (a later line overrides an earlier one item by item). Errors point at the items or
    /// lines at fault: a coordinate that was eliminated, a position missing, a non-cyclic
    /// coordinate given a rate, equations that depend on time there.
    pub fn linearize(&mut self) -> Result<Linearization, Vec<Diagnostic>> {
        let Some(span) = self.model.linearize.last().map(|l| l.span) else {
            return Err(vec![Diagnostic::error(Span::default(), "no `linearize about` line")
                .with_hint("add `linearize about q = …` naming the reference")]);
        };
        let mut errors = Vec::new();
        if let Some(m) = self.multipliers.iter().find(|m| m.kind == ConstraintKind::Velocity) {
            let c = &self.model.constraints[m.constraint];
            errors.push(
                Diagnostic::error(
                    c.span,
                    format!(
                        "`{}` is a velocity constraint, which linearize does not handle yet",
                        c.name
                    ),
                )
                .with_label("a velocity constraint")
                .with_related(span, "linearized here")
                .with_hint("linearize handles constraints of positions only"),
            );
            return Err(errors);
        }

        // The reference: later items override earlier ones.
        let mut given: HashMap<(SymId, bool), (ExprId, Span)> = HashMap::new();
        for line in &self.model.linearize {
            for item in &line.items {
                given.insert((item.coord, item.rate), (item.value, item.span));
            }
        }
        let mut items: Vec<((SymId, bool), (ExprId, Span))> = given.into_iter().collect();
        items.sort_by_key(|(_, (_, s))| (s.start, s.end));
        for ((coord, _), (_, item_span)) in &items {
            if let Some(e) = self.eliminated.iter().find(|e| e.coord == *coord) {
                let name = self.model.pool.symbol(*coord).name.clone();
                let constraint = &self.model.constraints[e.constraint].name;
                errors.push(
                    Diagnostic::error(
                        *item_span,
                        format!("`{name}` is eliminated by `{constraint}`"),
                    )
                    .with_label("not a coordinate of the equations")
                    .with_hint(format!(
                        "leave `{name}` out: its reference follows from the others through `{constraint}`"
                    )),
                );
            }
        }

        let n = self.coords.len();
        let cyclic: Vec<bool> = (0..n).map(|i| self.is_cyclic(self.coords[i])).collect();
        let pool = &mut self.model.pool;
        let mut positions = vec![None; n];
        let mut rates = vec![pool.zero(); n];
        let mut map: HashMap<SymId, ExprId> = HashMap::new();
        for ((coord, rate), (value, item_span)) in &items {
            let Some(i) = self.coords.iter().position(|q| q == coord) else { continue };
            if *rate {
                rates[i] = *value;
                map.insert(self.rates[i], *value);
                if !cyclic[i] && !pool.is_zero(*value) {
                    let name = pool.symbol_text(*coord, cas::Style::Unicode);
                    errors.push(
                        Diagnostic::error(
                            *item_span,
                            format!("a reference that moves `{name}` does not stay put"),
                        )
                        .with_label(format!("{name} is not cyclic: M or f depends on it"))
                        .with_hint(
                            "a steady motion may move only cyclic coordinates (those in neither \
                             M nor f); give this one a position and rate 0",
                        ),
                    );
                }
            } else {
                positions[i] = Some(*value);
                map.insert(*coord, *value);
            }
        }
        for i in 0..n {
            map.entry(self.rates[i]).or_insert(pool.zero());
        }
        let missing: Vec<String> = (0..n)
            .filter(|&i| !cyclic[i] && positions[i].is_none())
            .map(|i| format!("`{}`", pool.symbol(self.coords[i]).name))
            .collect();
        if !missing.is_empty() {
            let (them, it) = if missing.len() == 1 { ("", "it") } else { ("s", "them") };
            errors.push(
                Diagnostic::error(
                    span,
                    format!("the reference gives no position for {}", missing.join(", ")),
                )
                .with_label(format!("position{them} missing here"))
                .with_hint(format!(
                    "add {it} to the line (`{} = …`); rates default to 0, and a cyclic \
                     coordinate needs no position",
                    missing[0].trim_matches('`')
                )),
            );
        }
        if !errors.is_empty() {
            return Err(errors);
        }

        // K = −∂(f + Jᵀλ)/∂q and C = −∂f/∂q̇ (J of a position constraint has no rates).
        let mut generalized = self.forcing.clone();
        for m in &self.multipliers {
            let lambda = pool.sym(m.lambda);
            for (j, g) in generalized.iter_mut().enumerate() {
                let force = pool.mul2(m.jacobian[j], lambda);
                *g = pool.add2(*g, force);
            }
        }
        let at = |pool: &mut Pool, e: ExprId| {
            let e = pool.subst(e, &map);
            pool.simplify(e)
        };
        let (mut mass, mut damping, mut stiffness) = (Vec::new(), Vec::new(), Vec::new());
        for (j, g) in generalized.iter().enumerate() {
            let (mut m, mut c, mut k) = (Vec::new(), Vec::new(), Vec::new());
            for (i, is_cyclic) in cyclic.iter().enumerate() {
                m.push(at(pool, self.mass_matrix[j][i]));
                let df = pool.diff(self.forcing[j], self.rates[i]);
                let df = at(pool, df);
                c.push(pool.neg(df));
                k.push(if *is_cyclic {
                    pool.zero()
                } else {
                    let dg = pool.diff(*g, self.coords[i]);
                    let dg = at(pool, dg);
                    pool.neg(dg)
                });
            }
            mass.push(m);
            damping.push(c);
            stiffness.push(k);
        }
        let residual: Vec<ExprId> = generalized.iter().map(|g| at(pool, *g)).collect();
        let residual_is_zero =
            self.multipliers.is_empty() && residual.iter().all(|r| pool.is_identically_zero(*r));
        let constraints: Vec<LinearConstraint> = self
            .multipliers
            .iter()
            .map(|m| LinearConstraint {
                constraint: m.constraint,
                lambda: m.lambda,
                jacobian: m.jacobian.iter().map(|e| at(pool, *e)).collect(),
                phi: at(pool, m.phi),
                bias: at(pool, m.bias),
            })
            .collect();

        // A reference is a fixed point of autonomous equations; a drive or a schedule that
        // is still there makes the small motions those of a time-varying system.
        let time = self.model.time;
        let mut all: Vec<ExprId> =
            mass.iter().chain(&damping).chain(&stiffness).flatten().copied().collect();
        all.extend(&residual);
        for c in &constraints {
            all.extend(&c.jacobian);
            all.extend([c.phi, c.bias]);
        }
        let timed = all.iter().any(|e| {
            pool.depends_on(*e, time) && {
                let d = pool.diff(*e, time);
                !pool.is_identically_zero(d)
            }
        });
        if timed {
            return Err(vec![Diagnostic::error(
                span,
                "the equations depend on time at this reference",
            )
            .with_label("the linearized equations would change with t")
            .with_hint(
                "a reference needs equations that do not change with time: no drive or \
                 schedule written with `t` may act there",
            )]);
        }

        Ok(Linearization {
            coords: self.coords.clone(),
            cyclic,
            positions,
            rates,
            mass,
            damping,
            stiffness,
            residual,
            residual_is_zero,
            constraints,
            span,
        })
    }

    /// Whether a coordinate appears in neither M nor f nor any kept constraint: only its rate
    /// matters, and a steady motion may move it.
    fn is_cyclic(&mut self, q: SymId) -> bool {
        let pool = &mut self.model.pool;
        let mut exprs: Vec<ExprId> = self.mass_matrix.iter().flatten().copied().collect();
        exprs.extend(&self.forcing);
        exprs.extend(self.multipliers.iter().map(|m| m.phi));
        !exprs.iter().any(|e| pool.depends_on(*e, q))
    }
}

#[cfg(test)]
mod tests {
    use crate::derive::testing::{ascii, derived};

    /// A matrix as text, row by row.
    type Text = Vec<Vec<String>>;

    /// M, C and K of a scene about its reference.
    fn matrices(source: &str) -> (Text, Text, Text) {
        let mut d = derived(source);
        let lin = d.linearize().expect("linearizes");
        let pool = d.pool();
        let text = |m: &[Vec<cas::ExprId>]| -> Text {
            m.iter().map(|r| r.iter().map(|e| ascii(pool, *e)).collect()).collect()
        };
        (text(&lin.mass), text(&lin.damping), text(&lin.stiffness))
    }

    const PENDULUM: &str = "
param m, L, g
coord theta
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
";

    #[test]
    fn the_pendulum_hangs_stably_and_stands_unstably() {
        let (m, c, k) = matrices(&format!("{PENDULUM}linearize about theta = 0"));
        assert_eq!(
            (m, c, k),
            (vec![vec!["m*L^2".to_string()]], vec![vec!["0".into()]], vec![vec!["m*L*g".into()]])
        );
        let (_, _, k) = matrices(&format!("{PENDULUM}linearize about theta = pi"));
        assert_eq!(k, [["-m*L*g"]]);
    }

    #[test]
    fn a_cart_is_cyclic_and_needs_no_position() {
        let source = "
param M, m, L, g
coord x, theta
particle cart { mass M; position (x, 0) }
particle bob { mass m; position (x + L*sin(theta), -L*cos(theta)) }
gravity g
linearize about theta = 0
";
        let mut d = derived(source);
        let lin = d.linearize().expect("linearizes");
        assert_eq!(lin.cyclic, [true, false]);
        assert!(lin.residual_is_zero);
        let (m, _, k) = matrices(source);
        assert_eq!(m, [["M + m", "m*L"], ["m*L", "m*L^2"]]);
        assert_eq!(k, [["0", "0"], ["0", "m*L*g"]]);
    }

    #[test]
    fn a_reference_names_every_position_and_moves_only_cyclic_coordinates() {
        let source = "
param m, L, g, w
coord theta, phi
particle bob { mass m; position (L*sin(theta)*cos(phi), L*sin(theta)*sin(phi), -L*cos(theta)) }
gravity g
";
        let mut d = derived(&format!("{source}linearize about phi' = w"));
        let errors = d.linearize().expect_err("θ has no position");
        assert!(errors[0].message.contains("no position for `theta`"), "{errors:?}");
        let mut d = derived(&format!("{source}linearize about theta = 0, theta' = w"));
        let errors = d.linearize().expect_err("θ moves");
        assert!(errors[0].message.contains("does not stay put"), "{errors:?}");
    }

    #[test]
    fn a_drive_in_time_has_no_reference() {
        let source = "
param m, k, F, w
coord x
particle p { mass m; position (x, 0) }
potential k/2*x^2
force push on p: (F*cos(w*t), 0)
linearize about x = 0
";
        let errors = derived(source).linearize().expect_err("driven");
        assert!(errors[0].message.contains("depend on time"), "{errors:?}");
    }
}
