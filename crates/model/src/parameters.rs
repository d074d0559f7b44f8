//! The parameters' values, computed one way for every front end and numeric path. A user sets
//! the free parameters; a derived parameter (one whose value names other parameters, `param
//! L = 2*a`) is never set: it follows from the parameters it names, in declaration order, as
//! the scene's text says. The inputs' declared values follow the parameters.
//!
//! `simulate --set`, an ensemble's runs, Python's `rhs(p=…)` and the generated code all read
//! their numbers here, so a value set in one front end means what it means in every other.

use std::fmt;

use cas::{ExprId, SymId};
use numeric::Evaluator;

use crate::Model;

/// What a front end gives a free parameter in place of the scene's value.
#[derive(Clone, Debug)]
pub enum Given {
    /// A number, in SI.
    Number(f64),
    /// An expression of the parameters declared before it (`--set b=2*a`), lowered from the
    /// model's pool.
    Expression(Box<Evaluator>),
}

impl Given {
    /// `e`, an expression in `model`'s pool, to be evaluated at the values of the parameters
    /// declared before the one it is given to.
    pub fn expression(model: &Model, e: ExprId) -> Given {
        Given::Expression(Box::new(Evaluator::new(&model.pool, &[e])))
    }
}

/// Why parameter values could not be computed.
#[derive(Clone, Debug, PartialEq)]
pub enum ParameterError {
    /// A parameter the scene gives no value and nothing else did.
    Missing { name: String },
    /// A derived parameter was given a value: its value names `sources`, and it follows the
    /// free parameters `roots` through them, which are the ones to set.
    Derived { name: String, sources: Vec<String>, roots: Vec<String> },
    /// A parameter (or an input's declared value) that is not a finite number.
    NotFinite { name: String, value: f64, input: bool },
    /// A value given to something that is not a parameter index of the scene.
    NoSuchParameter { index: usize },
}

impl fmt::Display for ParameterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParameterError::Missing { name } => write!(f, "parameter `{name}` has no value"),
            ParameterError::Derived { name, sources, roots } => {
                let quoted = |names: &[String]| {
                    list(&names.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>())
                };
                let (named, free) = (quoted(sources), quoted(roots));
                write!(f, "parameter `{name}` is derived from {named}; set {free} instead")
            }
            ParameterError::NotFinite { name, value, input } => {
                let what = if *input { "input" } else { "parameter" };
                write!(f, "{what} `{name}` evaluates to {value}")
            }
            ParameterError::NoSuchParameter { index } => {
                write!(f, "no parameter number {index} in the scene")
            }
        }
    }
}

/// `a`, `a and b`, `a, b and c`.
fn list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// The parameters' values of a model, lowered once: the scene's values, or those given to the
/// free parameters, with the derived ones recomputed. Independent of the pool once made, so a
/// compiled scene (Python's `rhs`) keeps it after the derivation is gone.
#[derive(Clone, Debug)]
pub struct ParameterValues {
    parameters: Vec<Entry>,
    inputs: Vec<Entry>,
    /// Scratch: a value per symbol of the pool, which the evaluators read by index.
    by_symbol: Vec<f64>,
}

#[derive(Clone, Debug)]
struct Entry {
    name: String,
    sym: SymId,
    value: Option<Evaluator>,
    /// The parameters its value names, by index (empty for a free parameter).
    sources: Vec<usize>,
}

impl ParameterValues {
    pub fn new(model: &Model) -> ParameterValues {
        let pool = &model.pool;
        let index_of = |s: &SymId| model.params.iter().position(|p| p.sym == *s);
        let entry = |name: &str, sym: SymId, value: Option<ExprId>| {
            let value = value.map(|e| Evaluator::new(pool, &[e]));
            let mut sources: Vec<usize> =
                value.iter().flat_map(|v| v.symbols()).filter_map(index_of).collect();
            sources.sort_unstable();
            sources.dedup();
            Entry { name: name.to_string(), sym, value, sources }
        };
        ParameterValues {
            parameters: model.params.iter().map(|p| entry(&p.name, p.sym, p.value)).collect(),
            inputs: model.inputs.iter().map(|u| entry(&u.name, u.sym, Some(u.value))).collect(),
            by_symbol: vec![f64::NAN; pool.symbol_count()],
        }
    }

    /// Every parameter's name, in declaration order (the order of the values).
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.parameters.iter().map(|e| e.name.as_str())
    }

    /// How many parameters the scene declares.
    pub fn len(&self) -> usize {
        self.parameters.len()
    }

    pub fn is_empty(&self) -> bool {
        self.parameters.is_empty()
    }

    /// Whether parameter `i`'s value names other parameters, so that it follows them.
    pub fn is_derived(&self, i: usize) -> bool {
        !self.parameters[i].sources.is_empty()
    }

    /// The indices of the free parameters, the ones a user may set, in declaration order.
    pub fn free(&self) -> Vec<usize> {
        (0..self.parameters.len()).filter(|i| !self.is_derived(*i)).collect()
    }

    /// The indices of the derived parameters, in declaration order.
    pub fn derived(&self) -> Vec<usize> {
        (0..self.parameters.len()).filter(|i| self.is_derived(*i)).collect()
    }

    /// The names of the parameters `i`'s value names.
    pub fn sources(&self, i: usize) -> Vec<String> {
        self.parameters[i].sources.iter().map(|k| self.parameters[*k].name.clone()).collect()
    }

    /// The error for a value given to the derived parameter `i`.
    pub fn derived_error(&self, i: usize) -> ParameterError {
        ParameterError::Derived {
            name: self.parameters[i].name.clone(),
            sources: self.sources(i),
            roots: self.roots(i).into_iter().map(|k| self.parameters[k].name.clone()).collect(),
        }
    }

    /// The free parameters `i` follows, through derived ones (`J = M*r^2/4` with `M = m1 + m2`
    /// follows m1, m2 and r), in declaration order: the ones a user sets to move it.
    pub fn roots(&self, i: usize) -> Vec<usize> {
        let mut found = Vec::new();
        let mut pending = self.parameters[i].sources.clone();
        while let Some(k) = pending.pop() {
            if self.is_derived(k) {
                pending.extend(&self.parameters[k].sources);
            } else if !found.contains(&k) {
                found.push(k);
            }
        }
        found.sort_unstable();
        found
    }

    /// The parameters' values in declaration order, then the inputs' declared values: the
    /// scene's values, with `given` (parameter index and value; the last one for an index
    /// wins) in place of those of free parameters. Derived parameters follow what they name.
    pub fn values(&mut self, mut given: Vec<(usize, Given)>) -> Result<Vec<f64>, ParameterError> {
        for (i, _) in &given {
            if *i >= self.parameters.len() {
                return Err(ParameterError::NoSuchParameter { index: *i });
            }
            if self.is_derived(*i) {
                return Err(self.derived_error(*i));
            }
        }
        self.by_symbol.fill(f64::NAN);
        let mut out = Vec::with_capacity(self.parameters.len() + self.inputs.len());
        for (i, entry) in self.parameters.iter_mut().enumerate() {
            let value = match given.iter_mut().rev().find(|(k, _)| *k == i) {
                Some((_, Given::Number(v))) => *v,
                Some((_, Given::Expression(e))) => e.eval(&self.by_symbol)[0],
                None => match &mut entry.value {
                    Some(e) => e.eval(&self.by_symbol)[0],
                    None => return Err(ParameterError::Missing { name: entry.name.clone() }),
                },
            };
            if !value.is_finite() {
                let name = entry.name.clone();
                return Err(ParameterError::NotFinite { name, value, input: false });
            }
            self.by_symbol[entry.sym.index()] = value;
            out.push(value);
        }
        for entry in &mut self.inputs {
            let Some(e) = &mut entry.value else { continue };
            let value = e.eval(&self.by_symbol)[0];
            if !value.is_finite() {
                let name = entry.name.clone();
                return Err(ParameterError::NotFinite { name, value, input: true });
            }
            out.push(value);
        }
        Ok(out)
    }

    /// The scene's own values, each parameter's and then each input's, `None` where there is
    /// none or it is not a finite number (and so for what follows from it): what a report
    /// shows beside the symbols.
    pub fn scene_values(&mut self) -> Vec<Option<f64>> {
        self.by_symbol.fill(f64::NAN);
        let mut out = Vec::with_capacity(self.parameters.len() + self.inputs.len());
        for entry in self.parameters.iter_mut().chain(&mut self.inputs) {
            let value = entry.value.as_mut().map_or(f64::NAN, |e| e.eval(&self.by_symbol)[0]);
            self.by_symbol[entry.sym.index()] = value;
            out.push(value.is_finite().then_some(value));
        }
        out
    }

    /// The values with numbers for the free parameters alone, in the order of [`Self::free`]:
    /// what a compiled scene is handed per call.
    pub fn values_of_free(&mut self, free: &[f64]) -> Result<Vec<f64>, ParameterError> {
        let given: Vec<(usize, Given)> =
            self.free().into_iter().zip(free).map(|(i, v)| (i, Given::Number(*v))).collect();
        self.values(given)
    }
}

#[cfg(test)]
mod tests {
    use super::{Given, ParameterError, ParameterValues};
    use crate::{resolve, Model};

    /// L and I derived, with I naming a derived L; b without a value; an input after them.
    const SCENE: &str = "param a = 1, m = 3, b\nparam L = 2*a\nparam I = m*L^2/12\n\
        input F = L/4\ncoord x = a\nparticle p { mass m; position (x, 0) }\n\
        force push on p: (F + b*I, 0)\n";

    fn model() -> Model {
        let ast = lang::parse(SCENE).expect("parses");
        resolve(&ast, SCENE).expect("resolves").0
    }

    #[test]
    fn derived_parameters_follow_the_free_ones_in_declaration_order() {
        let model = model();
        let mut plan = ParameterValues::new(&model);
        assert_eq!(plan.free(), [0, 1, 2]);
        assert_eq!(plan.derived(), [3, 4]);
        assert_eq!(plan.sources(4), ["m", "L"]);
        // b has no value: it must be given.
        assert_eq!(plan.values(vec![]), Err(ParameterError::Missing { name: "b".into() }));
        let values = plan.values_of_free(&[2.0, 3.0, 5.0]).expect("values");
        // L = 4, I = 3·16/12, and the input F = L/4 after them.
        assert_eq!(values, [2.0, 3.0, 5.0, 4.0, 4.0, 1.0]);
        let scene = plan.scene_values();
        assert_eq!(scene, [Some(1.0), Some(3.0), None, Some(2.0), Some(1.0), Some(0.5)]);
    }

    #[test]
    fn a_derived_parameter_is_not_set_and_an_expression_reads_the_ones_before_it() {
        let model = model();
        let mut plan = ParameterValues::new(&model);
        let refused = plan.values(vec![(2, Given::Number(1.0)), (3, Given::Number(9.0))]);
        assert_eq!(
            refused.unwrap_err().to_string(),
            "parameter `L` is derived from `a`; set `a` instead"
        );
        assert_eq!(
            plan.derived_error(4).to_string(),
            "parameter `I` is derived from `m` and `L`; set `a` and `m` instead"
        );
        // b = 2*m, the last value given for an index winning.
        let mut pool_model = model;
        let two_m = {
            let pool = &mut pool_model.pool;
            let m = pool.sym(pool_model.params[1].sym);
            let two = pool.int(2);
            pool.mul2(two, m)
        };
        let given = vec![
            (2, Given::Number(7.0)),
            (2, Given::expression(&pool_model, two_m)),
            (0, Given::Number(0.5)),
        ];
        let values = plan.values(given).expect("values");
        assert_eq!(values[..5], [0.5, 3.0, 6.0, 1.0, 0.25]);
        let nan = plan.values(vec![(1, Given::Number(f64::NAN))]);
        assert!(matches!(nan, Err(ParameterError::NotFinite { .. })), "{nan:?}");
    }
}
