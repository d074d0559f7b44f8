//! The abstract syntax tree of a scene file; every node carries the byte span it came from.

/// A byte range `start..end` in the source text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }

    /// The smallest span covering both.
    pub fn join(self, other: Span) -> Span {
        Span { start: self.start.min(other.start), end: self.end.max(other.end) }
    }
}

/// A name as written, with where it was written.
#[derive(Clone, Debug, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    /// A decimal literal exactly as written: `12`, `0.1`, `1e-3`, `2.5E+4`.
    Number(String),
    /// A name with its time-derivative primes: `theta` (0), `x'` (1), `x''` (2).
    Name {
        name: String,
        primes: u8,
    },
    /// A quantity of a model object: `disk.omega`, `floor.force`, `rod.position`; or a
    /// component of a vector one, `top.omega_body.z`.
    Member {
        object: Ident,
        field: Ident,
        component: Option<Ident>,
    },
    /// `sin(theta)`, `atan2(y, x)`.
    Call {
        func: Ident,
        args: Vec<Expr>,
    },
    /// Unary minus.
    Neg(Box<Expr>),
    Binary {
        op: BinOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    /// A parenthesised list of two or more: `(x, y)` or `(x, y, z)`.
    Tuple(Vec<Expr>),
    /// `[a, b; c, d]`: rows separated by `;`, entries by `,`.
    Matrix(Vec<Vec<Expr>>),
}

/// A unit written after a value: `kg`, `m/s^2`, `kg*m^2`, `N*m`.
#[derive(Clone, Debug, PartialEq)]
pub struct Unit {
    /// Each named unit with its power, in the order written (`m/s^2` is `[(m, 1), (s, -2)]`).
    pub factors: Vec<(Ident, i32)>,
    pub span: Span,
}

/// The units a scene may write after a value. What each one means (its dimension and size in
/// SI) belongs to `model::units`; the parser needs the names only to tell a unit written where
/// none may stand from a missing `*`.
pub const UNIT_NAMES: [&str; 24] = [
    "kg", "g", "m", "km", "cm", "mm", "s", "ms", "min", "h", "Hz", "N", "J", "W", "Pa", "A", "C",
    "V", "T", "K", "rad", "deg", "rev", "rpm",
];

/// `name = value unit`, one item of a `param` or `input` line.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamDecl {
    pub name: Ident,
    pub value: Option<Expr>,
    pub unit: Option<Unit>,
}

/// One generalized coordinate of a `coord` line: `theta = pi/6, theta' = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct CoordDecl {
    pub name: Ident,
    /// Initial value (default 0).
    pub value: Option<Expr>,
    pub value_unit: Option<Unit>,
    /// Whether the value is a guess (`coord y ~ -1`), for the start's position to be solved
    /// from the kept constraints near it.
    pub guess: bool,
    /// Initial rate, from a `name' = …` item on the same line (default 0).
    pub rate: Option<Expr>,
    pub rate_unit: Option<Unit>,
}

/// `key value` inside a `particle { … }` or `body { … }` block.
#[derive(Clone, Debug, PartialEq)]
pub struct Property {
    pub key: Ident,
    pub value: Expr,
}

/// `key value…` inside a `simulate { … }` block, kept as written.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    pub key: Ident,
    /// What the setting sets, where the key takes one: `input F = …` names `F`.
    pub target: Option<Ident>,
    pub values: Vec<Expr>,
    pub unit: Option<Unit>,
}

/// One item of a `linearize about` line: the reference value of a coordinate (`theta = 0`)
/// or of its rate (`psi' = w`).
#[derive(Clone, Debug, PartialEq)]
pub struct AboutItem {
    pub name: Ident,
    /// 0 for the coordinate, 1 for its rate.
    pub primes: u8,
    pub value: Expr,
    pub unit: Option<Unit>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    pub kind: StmtKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum StmtKind {
    /// `scene "A title"`
    Scene { title: String },
    /// `param m = 1 kg, g = 9.81 m/s^2, k`
    Param(Vec<ParamDecl>),
    /// `input F = 0 N, tau`: exogenous signals with their values when nothing drives them
    Input(Vec<ParamDecl>),
    /// `output tip: L*sin(theta)`
    Output { name: Ident, value: Expr },
    /// `let h = L/2*cos(theta)`
    Let { name: Ident, value: Expr },
    /// `coord theta = pi/6, theta' = 0` or `coord x, y`
    Coord(Vec<CoordDecl>),
    /// `particle bead { mass m; position (x, y) }`
    Particle { name: Ident, props: Vec<Property> },
    /// `body rod { mass m; inertia m*L^2/12; position (x, y); angle theta }`
    Body { name: Ident, props: Vec<Property> },
    /// `constraint floor: y = L/2*cos(theta)` (the name is optional)
    Constraint { name: Option<Ident>, lhs: Expr, rhs: Expr },
    /// `contact floor: y >= 0 { restitution 4/5 }`: a one-sided constraint on the gap
    /// lhs − rhs (`at_least`, written `>=`) or rhs − lhs (`<=`), with its laws (`restitution`,
    /// `grip`) as written.
    Contact { name: Ident, lhs: Expr, rhs: Expr, at_least: bool, laws: Vec<Property> },
    /// `gravity g` or `gravity g along (0, -1)`
    Gravity { strength: Expr, direction: Option<Expr> },
    /// `potential k/2*(x - l0)^2`
    Potential(Expr),
    /// `force push on bead: (F0*cos(w*t), 0)`, or `force f on b at P: F` at the point P
    Force { name: Ident, body: Ident, at: Option<Expr>, value: Expr },
    /// `torque drive on rod: tau0`
    Torque { name: Ident, body: Ident, value: Expr },
    /// `spring s between cart and bob: k, l0` (the rest length is optional, default 0)
    Spring { name: Ident, a: Expr, b: Expr, stiffness: Expr, rest: Option<Expr> },
    /// `damper d between cart and wall: c`
    Damper { name: Ident, a: Expr, b: Expr, coefficient: Expr },
    /// `dissipation c/2*x'^2`
    Dissipation(Expr),
    /// `lagrangian m/2*x'^2 - k/2*x^2`
    Lagrangian(Expr),
    /// `show KE, disk.omega` or `show at start: theta''`
    Show { at_start: bool, items: Vec<Expr> },
    /// `expect lhs = rhs` or `expect at start: lhs = rhs`
    /// `expect impact floor: y' = -e*y'`: the left side after an impact at `floor`, alone,
    /// the right side before it.
    /// With `where q = …, q' = …` after it, at that state before the impact.
    Expect { at_start: bool, impact: Option<Ident>, lhs: Expr, rhs: Expr, before: Vec<AboutItem> },
    /// `expect linearized: unstable`: what `linearize` finds at the scene's reference
    ExpectLinearized(LinearExpectation),
    /// `simulate { until 2 s; method dop853 }`
    Simulate(Vec<Setting>),
    /// `linearize about theta = 0, theta' = 0`
    Linearize(Vec<AboutItem>),
    /// `draw line from (0, 0) to bob.position`: a shape for `simulate --animate`.
    Draw(Shape),
}

/// What an `expect linearized:` line expects of the linearization at the scene's reference.
#[derive(Clone, Debug, PartialEq)]
pub enum LinearExpectation {
    /// `stable`, `marginally stable` or `unstable`, as written (blanks made single).
    Verdict { word: String, span: Span },
    /// `eigenvalue = value` (a scalar, or `(re, im)`).
    Eigenvalue(Expr),
    /// `critical p = value`.
    Critical { parameter: Ident, value: Expr },
}

/// A shape of a `draw` line, in world coordinates; its points are vector expressions.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `line from A to B`
    Line { from: Expr, to: Expr },
    /// `circle at C radius r`
    Circle { centre: Expr, radius: Expr },
    /// `polyline A, B, C`: two points or more.
    Polyline(Vec<Expr>),
}

/// A whole scene file.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SceneFile {
    pub stmts: Vec<Stmt>,
}

impl Expr {
    /// The expression as an S-expression, without spans: `(+ a (* 2 b))`, `(neg x)`,
    /// `(call sin x)`, `(tuple x y)`, `(matrix (a b) (c d))`, `x''`, `disk.omega`.
    /// Handy for tests that compare structure but not positions.
    pub fn to_sexpr(&self) -> String {
        match &self.kind {
            ExprKind::Number(text) => text.clone(),
            ExprKind::Name { name, primes } => {
                format!("{name}{}", "'".repeat(usize::from(*primes)))
            }
            ExprKind::Member { object, field, component } => match component {
                Some(c) => format!("{}.{}.{}", object.name, field.name, c.name),
                None => format!("{}.{}", object.name, field.name),
            },
            ExprKind::Call { func, args } => {
                let args: Vec<String> = args.iter().map(Expr::to_sexpr).collect();
                format!("(call {} {})", func.name, args.join(" "))
            }
            ExprKind::Neg(inner) => format!("(neg {})", inner.to_sexpr()),
            ExprKind::Binary { op, lhs, rhs } => {
                let op = match op {
                    BinOp::Add => "+",
                    BinOp::Sub => "-",
                    BinOp::Mul => "*",
                    BinOp::Div => "/",
                    BinOp::Pow => "^",
                };
                format!("({op} {} {})", lhs.to_sexpr(), rhs.to_sexpr())
            }
            ExprKind::Tuple(items) => {
                let items: Vec<String> = items.iter().map(Expr::to_sexpr).collect();
                format!("(tuple {})", items.join(" "))
            }
            ExprKind::Matrix(rows) => {
                let rows: Vec<String> = rows
                    .iter()
                    .map(|row| {
                        let row: Vec<String> = row.iter().map(Expr::to_sexpr).collect();
                        format!("({})", row.join(" "))
                    })
                    .collect();
                format!("(matrix {})", rows.join(" "))
            }
        }
    }
}
