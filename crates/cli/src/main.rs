//! `lagrange`: derive equations of motion from a scene file, and check them against
//! hand-derived results.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use engine::input::{Assignment, SweepRange};

#[derive(Parser)]
#[command(
    name = "lagrange",
    version,
    about = "Symbolic Lagrangian mechanics: derive and check equations of motion"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Derive the equations of motion of a scene and print them.
    Derive {
        file: PathBuf,
        /// How to print: text for people, latex, or json for programs.
        #[arg(long, value_enum, default_value_t = FormatArg::Text)]
        format: FormatArg,
        /// Write the report to this file (whole or not at all) instead of standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
        /// Print every entry of the text report whole; without it, one past 1,000 characters
        /// shows its size instead.
        #[arg(long)]
        full: bool,
    },
    /// Check every `expect` line of the scenes; exit 1 if one does not hold, 2 on a bad file.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// Write the scene of a family of systems of any size to standard output.
    Generate {
        /// n-link-pendulum or n-link-pendulum-on-cart
        #[arg(value_parser = clap::builder::PossibleValuesParser::new(lang::generate::Family::NAMES))]
        family: String,
        /// The number of links.
        #[arg(value_parser = clap::value_parser!(u16).range(1..=500))]
        n: u16,
    },
    /// Integrate the equations of motion of a scene and record quantities against time.
    /// Exit 2 on bad input, 1 when a numeric fault stopped the run (what was computed is
    /// still written).
    Simulate {
        file: PathBuf,
        #[command(flatten)]
        run: RunArgs,
        /// Quantities to record, comma-separated: coordinates, rates, reactions, KE, PE, any
        /// scene expression. Default: the scene's `output`, else the coordinates.
        #[arg(long)]
        output: Vec<String>,
        /// Write the recorded quantities here: .csv or .json (default: CSV on standard output).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Plot the recorded quantities and the energy error against time as SVG.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Write a self-contained HTML page that plays the motion (.html): the bodies, springs
        /// and `draw` shapes, with the energy error beside them.
        #[arg(long, value_name = "OUT.html")]
        animate: Option<PathBuf>,
        /// Write the run's contact events here as CSV (.csv): each impact, lift-off and
        /// settling, with its time, contact, impulses and the energy it changed.
        #[arg(long, value_name = "OUT.csv")]
        events: Option<PathBuf>,
        /// Record at this many evenly spaced times (the start and the end included), from the
        /// integrator's dense output; 0 records at every accepted step instead. Events and the
        /// end are always recorded.
        /// Default: 200, or 1000 with --animate (frames of the animation).
        #[arg(long)]
        samples: Option<usize>,
    },
    /// Run a scene many times over a grid of parameter values or random draws, on all cores,
    /// and record values of each run: a CSV row per run, and a picture. A run that fails is a
    /// row with its reason. Exit 2 on bad input.
    Ensemble {
        file: PathBuf,
        /// A parameter to vary: a grid axis `--vary a=-3:3:60` (N values from A to B; axes are
        /// crossed, the first varying slowest), or random draws `--vary "m=normal(1, 0.1)"`,
        /// `--vary "g=uniform(9.7, 9.9)"` with --runs. A start given by a parameter in `coord`
        /// follows it.
        #[arg(long, value_name = "NAME=SPEC", required = true)]
        vary: Vec<String>,
        /// The number of random draws (at each grid point, if there is a grid too).
        #[arg(long)]
        runs: Option<usize>,
        /// The seed of the random draws: the same seed gives the same draws on every machine.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// What to record per run, comma-separated: scene expressions at the end or at the
        /// stop (`t` is the stop's time), `max(EXPR)` and `min(EXPR)` over the run;
        /// `impacts(CONTACT)` and `settled(CONTACT)` (its impacts, when it settled).
        /// Default: the scene's `output`, else the coordinates, at the end.
        #[arg(long, value_name = "EXPRS")]
        record: Vec<String>,
        #[command(flatten)]
        run: RunArgs,
        /// Write the table here, .csv, whole or not at all (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Draw the first recorded quantity (.svg or .png): a heat map over two grid axes, a
        /// line over one, a histogram of random draws.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Threads to run on (default: the machine's cores). The table is the same whatever
        /// the number.
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024))]
        threads: Option<u16>,
    },
    /// Linearize about an equilibrium or a steady motion: M, C, K of M·δq̈ + C·δq̇ + K·δq = 0,
    /// the first-order form ẋ = A·x + B·u, y = C·x + D·u of the scene's inputs and outputs,
    /// its eigenvalues, the verdict on stability, controllability and observability. Exit 2 on
    /// bad input, a reference that is not an equilibrium included.
    Linearize {
        file: PathBuf,
        /// The reference, overriding or extending the scene's `linearize about` line:
        /// `--about "theta=0, psi'=60"`. Rates not given are 0.
        #[arg(long, value_name = "ITEMS")]
        about: Option<String>,
        /// Override a parameter: `--set g=1.62`.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<Assignment>,
        /// Tabulate the eigenvalues for n values of parameter p from a to b, and find where
        /// stability changes: `--sweep w=0:100:101`.
        #[arg(long, value_name = "P=A:B:N")]
        sweep: Option<SweepRange>,
        /// Leave the positions of cyclic coordinates out of the state (by default the state
        /// is the position and rate of every coordinate).
        #[arg(long)]
        drop_cyclic: bool,
        /// Linearize along a motion rather than about an equilibrium: `run` (the scene run
        /// with its `simulate` settings, --until, --method, --tolerance, --step, --samples and
        /// --set), or a CSV file with a column `t` and, for each coordinate x, the columns x
        /// and x' (and one per input). Gives A(t), B(t), C(t), D(t) at every sample and the
        /// state-transition matrix over the motion.
        #[arg(long, value_name = "run|FILE.csv")]
        along: Option<String>,
        #[command(flatten)]
        run: AlongRun,
        /// Draw the sweep's eigenvalues (real and imaginary parts against p) as SVG.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// How to print: text for people, or json for programs.
        #[arg(long, value_enum, default_value_t = LinearizeFormat::Text)]
        format: LinearizeFormat,
        /// Write the report to this file (whole or not at all) instead of standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// Export the scene as an FMI 2.0 FMU (Model Exchange and Co-Simulation in one archive),
    /// its binary compiled for this platform with the system C compiler (`cc`, or `CC`).
    Export {
        file: PathBuf,
        /// Write the FMU here (whole or not at all).
        #[arg(long, value_name = "OUT.fmu")]
        fmu: PathBuf,
        /// The Co-Simulation integrator's tolerance (relative and absolute) when the importer
        /// sets none; default: the scene's `simulate { tolerance … }`, else 1e-10.
        #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
        tolerance: Option<String>,
        /// The stop time of the FMU's default experiment, as the scene writes it (`10`,
        /// `1/4 min`; seconds without a unit); default: the scene's `simulate { until … }`,
        /// else 10.
        #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
        until: Option<String>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// Write the equations of motion as source code: a self-contained Rust module (only std
    /// needed), or C99 (a header and a source, only libm needed).
    Codegen {
        file: PathBuf,
        /// The language: rust (one module) or c (NAME.h and NAME.c, NAME the file's stem).
        #[arg(long, value_enum, default_value_t = LangArg::Rust)]
        lang: LangArg,
        /// Rust: write the module to this file (whole or not at all) instead of standard
        /// output. C: the directory to write NAME.h and NAME.c into (required).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// The generalized forces that make a given motion happen: τ = M(q)·q̈ − f(q, q̇, t) at
    /// every row of a trajectory. Exit 2 on bad input, 1 when the forces are not finite.
    InverseDynamics {
        file: PathBuf,
        /// The motion, as CSV: a column `t` and, for each coordinate x, the columns x, x' and
        /// x'' (as `simulate --output x,x',x''` writes them); other columns are ignored.
        #[arg(long, value_name = "FILE.csv")]
        trajectory: PathBuf,
        /// Override a parameter: `--set g=1.62`.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<Assignment>,
        /// Write the forces (CSV: t, then tau_x per coordinate) to this file, whole or not at
        /// all, instead of standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// Find a periodic orbit: Newton's method on a return map (to a section, a contact's
    /// landing, or over a fixed period), with the map's Jacobian from the exact variational
    /// equations; print the fixed point, the period, the Floquet multipliers and the verdict.
    /// Exit 2 on bad input, 1 when no orbit is found.
    Orbit {
        file: PathBuf,
        /// Where the map returns: an expression crossing zero (`theta`, `x = 2`), `impact`
        /// (any contact's landing) or `impact:NAME` (that contact's).
        #[arg(
            long,
            value_name = "EXPR",
            conflicts_with = "period",
            required_unless_present = "period"
        )]
        section: Option<String>,
        /// The direction an expression section is crossed in.
        #[arg(long, value_enum, default_value_t = DirectionArg::Rising)]
        direction: DirectionArg,
        /// A fixed period instead, for a driven scene: an expression of the parameters
        /// (`2*pi/w`), in seconds without a unit.
        #[arg(long, value_name = "TIME")]
        period: Option<String>,
        /// Before comparing a return with its start, add a value to a coordinate or a rate:
        /// `--shift theta=pi/4`, `--shift x=-2*l*sin(pi/8)` (a constant of the parameters).
        #[arg(long = "shift", value_name = "NAME=VALUE")]
        shift: Vec<Assignment>,
        /// Before comparing, exchange two coordinates and their rates (a walker's legs):
        /// `--swap a=b`.
        #[arg(long = "swap", value_name = "A=B")]
        swap: Vec<Assignment>,
        /// Leave a coordinate out of the comparison: a cyclic one a return need not repeat
        /// (the distance a wheel has rolled), `--ignore x`.
        #[arg(long = "ignore", value_name = "NAME")]
        ignore: Vec<String>,
        /// The longest a return may take, as the scene writes a time; default: the scene's
        /// `simulate { until … }`, else 10.
        #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
        until: Option<String>,
        #[command(flatten)]
        integrator: ExplicitRun,
        /// Override a parameter or the start Newton begins from: `--set w0=2`.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<Assignment>,
        /// Continue the orbit over N values of a parameter from A to B, each found from the
        /// one before (a fixed period's map round a fold by pseudo-arclength), and locate where
        /// a multiplier crosses the unit circle: `--sweep A=4:6:11`.
        #[arg(long, value_name = "P=A:B:N")]
        sweep: Option<SweepRange>,
        /// The most Newton iterations.
        #[arg(long, default_value_t = 30)]
        iterations: usize,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// Fit parameters and start values to measurements: Levenberg–Marquardt on the exact
    /// sensitivities of the runs, with standard errors and correlations. Exit 2 on bad input,
    /// 1 when a run faults or the fit does not converge.
    Fit {
        file: PathBuf,
        /// The measurements, CSV: a column `t` (seconds, increasing) and columns named by
        /// scene expressions (`theta`, `x'`, `KE`, an output); an empty cell is a value not
        /// measured.
        #[arg(long, value_name = "FILE.csv")]
        data: PathBuf,
        /// The unknowns, comma-separated: parameters (`c`) and start values (`theta(0)`,
        /// `theta'(0)`), each with an optional value to start from (`L=1.2`, in SI); default:
        /// the scene's value.
        #[arg(long, value_name = "NAMES", required = true)]
        free: Vec<String>,
        /// Keep an unknown within bounds: `--bound c=0:` (either side may be left open).
        /// Masses and inertias stay positive without one: a step that makes one negative is
        /// refused.
        #[arg(long = "bound", value_name = "NAME=LO:HI")]
        bound: Vec<String>,
        /// A column's noise level, in its unit: its residuals are divided by it
        /// (`--noise theta=0.01`). Default: 1 for every column, each residual in its unit.
        #[arg(long = "noise", value_name = "COLUMN=SIGMA")]
        noise: Vec<Assignment>,
        /// Multiple shooting: cut the record into this many shots of equal time, each from a
        /// start of its own, joined exactly at the optimum. For long or chaotic records.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=1000))]
        shots: u16,
        /// The most Levenberg–Marquardt iterations.
        #[arg(long, default_value_t = 100)]
        iterations: usize,
        #[command(flatten)]
        integrator: ExplicitRun,
        /// Override a parameter or a start value that is not free: `--set g=9.81`.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<Assignment>,
        /// Drive an input by a measured time series (`--input F=push.csv`) or a law.
        #[arg(long = "input", value_name = "NAME=EXPR")]
        input: Vec<Assignment>,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Write the report to this file (whole or not at all) instead of standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Write the scene with the fitted values in place of its own (.lag).
        #[arg(long, value_name = "OUT.lag")]
        fitted: Option<PathBuf>,
        /// Draw the data against the fitted motion, and the residuals, as SVG.
        #[arg(long, value_name = "OUT.svg")]
        plot: Option<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
    /// Measure every integrator over a ladder of tolerances or steps against a tight DOP853
    /// reference: error, wall time and right-hand-side evaluations.
    Bench {
        file: PathBuf,
        /// End time, as for simulate; default: the scene's `simulate { until … }`, else 10.
        #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
        until: Option<String>,
        /// Override a parameter or an initial value, as for simulate.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<Assignment>,
        /// End each run when this expression reaches zero, as for simulate.
        #[arg(long = "stop-when", value_name = "EXPR")]
        stop_when: Vec<String>,
        /// Drive an input by a law or a time series, as for simulate: every run, the reference
        /// included, is of the driven scene.
        #[arg(long = "input", value_name = "NAME=EXPR")]
        input: Vec<Assignment>,
        /// Hold the laws of `--input` between samples PERIOD apart, as for simulate.
        #[arg(long, value_name = "PERIOD", allow_hyphen_values = true)]
        hold: Option<String>,
        /// Time each run this many times and report the median.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Write the work–precision diagram (error against time, log–log) as SVG.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Do not check that terms added or equated have one dimension.
        #[arg(long)]
        no_units: bool,
    },
}

/// The integrator of the commands whose runs carry the variational equations (`orbit`, `fit`):
/// an explicit method, on whose steps Φ and S are integrated.
#[derive(Args)]
struct ExplicitRun {
    #[arg(long, value_parser = method_parser(),
          help = "An explicit integrator (default dop853)")]
    method: Option<sim::Method>,
    /// Tolerance of the adaptive methods (default: the scene's, else 1e-10).
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    tolerance: Option<String>,
    /// Step of the fixed-step methods.
    #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
    step: Option<String>,
}

impl ExplicitRun {
    /// The method's name, the tolerance and the step read; `None` after rendering on stderr
    /// what could not be read.
    fn read(self) -> Option<(Option<String>, Option<f64>, Option<f64>)> {
        let tolerance = ratio_option(engine::Setting::Tolerance, self.tolerance.as_deref())?;
        let step = time_option(engine::Setting::Step, self.step.as_deref())?;
        Some((self.method.map(|m| m.name().to_string()), tolerance, step))
    }
}

/// The settings of the run `linearize --along run` linearizes along, as `simulate` takes them.
#[derive(Args)]
struct AlongRun {
    /// With --along run: the end time, as for simulate.
    #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
    until: Option<String>,
    /// With --along run: the integrator, as for simulate; an explicit one, on whose steps Φ
    /// is integrated beside the run.
    #[arg(long, value_parser = method_parser())]
    method: Option<sim::Method>,
    /// With --along run: the tolerance of the adaptive methods, as for simulate.
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    tolerance: Option<String>,
    /// With --along run: the step of the fixed-step methods, as for simulate.
    #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
    step: Option<String>,
    /// With --along run: the number of evenly spaced samples (default 200; 0: every step).
    #[arg(long)]
    samples: Option<usize>,
}

impl AlongRun {
    /// The flags given, by name: each means something only with `--along run`.
    fn given(&self) -> Vec<&'static str> {
        let flags = [
            ("--until", self.until.is_some()),
            ("--method", self.method.is_some()),
            ("--tolerance", self.tolerance.is_some()),
            ("--step", self.step.is_some()),
            ("--samples", self.samples.is_some()),
        ];
        flags.into_iter().filter(|(_, given)| *given).map(|(flag, _)| flag).collect()
    }
}

/// The settings of a run, shared by `simulate` and `ensemble`.
#[derive(Args)]
struct RunArgs {
    /// End time, as the scene writes it (`10`, `2*pi`, `1/4 min`; seconds without a unit);
    /// default: the scene's `simulate { until … }`, else 10.
    #[arg(long, value_name = "TIME", allow_hyphen_values = true)]
    until: Option<String>,
    // The help of the method and of the two settings after it names the methods of `sim`'s
    // table.
    #[arg(long, value_parser = method_parser(),
          help = format!("The integrator (default {})", sim::Method::DEFAULT.name()))]
    method: Option<sim::Method>,
    #[arg(long, value_name = "TOL", allow_hyphen_values = true, help = format!(
        "Relative and absolute tolerance of the adaptive methods: {} (default 1e-10)",
        methods_taking(true)
    ))]
    tolerance: Option<String>,
    #[arg(long, value_name = "TIME", allow_hyphen_values = true, help = format!(
        "Step of {}, as the scene writes it (`1e-3`, `5 ms`); default: until/1000",
        methods_taking(false)
    ))]
    step: Option<String>,
    /// Override a parameter or an initial value: `--set g=1.62`, `--set theta=pi/3`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<Assignment>,
    /// Drive an input by an expression of t, the coordinates, their rates and the
    /// parameters, such as a state-feedback law: `--input "F=-20*x - 5*x'"`; or by a time
    /// series, `--input F=push.csv` (a time and a value a row, linear in between). An input
    /// not driven keeps its declared value.
    #[arg(long = "input", value_name = "NAME=EXPR")]
    input: Vec<Assignment>,
    /// Sample the laws of `--input` every PERIOD seconds and hold each value until the
    /// next sample (a zero-order hold, as a discrete controller acts), rather than apply
    /// them continuously. As the scene writes it (`0.02`, `20 ms`). Default: the scene's
    /// `simulate { hold … }`, else none.
    #[arg(long, value_name = "PERIOD", allow_hyphen_values = true)]
    hold: Option<String>,
    /// Stop when this expression reaches zero, or `lhs = rhs` holds: `--stop-when 'theta = pi/2'`.
    #[arg(long = "stop-when", value_name = "EXPR")]
    stop_when: Vec<String>,
    /// Record the times when this expression crosses zero.
    #[arg(long = "event", value_name = "EXPR")]
    event: Vec<String>,
    /// Do not check that terms added or equated have one dimension.
    #[arg(long)]
    no_units: bool,
}

impl RunArgs {
    /// The files a run reads: the scene, and the time series of `--input`.
    fn inputs<'a>(&'a self, scene: &'a std::path::Path) -> Vec<(&'a str, &'a std::path::Path)> {
        let mut inputs = vec![("", scene)];
        inputs.extend(self.input.iter().filter(|i| cli::series::is_series(i)).map(series_file));
        inputs
    }

    /// The engine's options of a run, the inputs' time series read from their files; `None`
    /// after saying on stderr which file could not be read.
    fn options(self) -> Option<simulation::Options> {
        let (input, input_series) = drives(self.input)?;
        Some(simulation::Options {
            until: time_option(engine::Setting::Until, self.until.as_deref())?,
            // The engine's options are shared with Python, which names the method.
            method: self.method.map(|m| m.name().to_string()),
            tolerance: ratio_option(engine::Setting::Tolerance, self.tolerance.as_deref())?,
            step: time_option(engine::Setting::Step, self.step.as_deref())?,
            set: self.set,
            input,
            input_series,
            hold: time_option(engine::Setting::Hold, self.hold.as_deref())?,
            stop_when: self.stop_when,
            events: self.event,
            no_units: self.no_units,
            ..Default::default()
        })
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum DirectionArg {
    Rising,
    Falling,
}

#[derive(Clone, Copy, ValueEnum)]
enum LangArg {
    Rust,
    C,
}

#[derive(Clone, Copy, ValueEnum)]
enum LinearizeFormat {
    Text,
    Json,
    /// With --along: a row per sample, every entry of A, B, C and D.
    Csv,
}

/// `--method`: the integrators of `sim`'s method table, each with its line of help, checked by
/// clap (a typo is told the possible values and the nearest one), with the same other names the
/// scene's `method` accepts.
fn method_parser() -> impl TypedValueParser<Value = sim::Method> {
    let values = sim::methods::TABLE.iter().map(|entry| {
        PossibleValue::new(entry.name).help(entry.summary).aliases(entry.aliases.iter().copied())
    });
    PossibleValuesParser::new(values)
        .map(|name| sim::Method::from_name(&name).expect("a name of the table's"))
}

/// The adaptive methods (which take a tolerance) or the fixed-step ones (a step), as a list in
/// words: `rk4, midpoint and gauss`.
fn methods_taking(adaptive: bool) -> String {
    let names: Vec<&str> =
        sim::Method::all().filter(|m| m.is_adaptive() == adaptive).map(|m| m.name()).collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => names.concat(),
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum FormatArg {
    Text,
    Latex,
    Json,
}

/// Says on stderr, and is `true`, when an output (a flag and its path) is one of the files the
/// command reads (each a flag, or the scene's empty name, and its path): writing it would
/// replace what was read.
fn writes_over_input(
    inputs: &[(&str, &std::path::Path)],
    outputs: &[(&str, Option<&std::path::Path>)],
) -> bool {
    for (flag, output) in outputs {
        let Some(output) = output else { continue };
        for (what, input) in inputs {
            if cli::same_file(input, output) {
                let read = if what.is_empty() {
                    "the scene file".to_string()
                } else {
                    format!("the {what} file")
                };
                eprintln!(
                    "error: {flag} {} would replace {read} {} that the command reads: write \
                     the output elsewhere",
                    output.display(),
                    input.display()
                );
                return true;
            }
        }
    }
    false
}

/// The file's text, or `None` after saying on stderr why it could not be read.
fn read_or_report(path: &std::path::Path) -> Option<String> {
    cli::read_scene(path).map_err(|e| eprint!("{e}")).ok()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Derive { file, format, out, no_units, full } => {
            if writes_over_input(&[("", &file)], &[("--out", out.as_deref())]) {
                return ExitCode::from(2);
            }
            derive(&file, format, out, no_units, full)
        }
        Command::Generate { family, n } => {
            let family = lang::generate::Family::from_name(&family).expect("clap checked the name");
            emit(&lang::generate::n_link(family, n as usize));
            ExitCode::SUCCESS
        }
        Command::Simulate { file, run, output, out, plot, animate, events, samples } => {
            let outputs = [
                ("--out", out.as_deref()),
                ("--plot", plot.as_deref()),
                ("--animate", animate.as_deref()),
            ];
            if writes_over_input(&run.inputs(&file), &outputs) {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let Some(options) = run.options() else { return ExitCode::from(2) };
            // An animation wants frames close enough to play smoothly.
            let default_samples = if animate.is_some() { 1000 } else { 200 };
            let options = simulation::Options {
                output,
                samples: samples.unwrap_or(default_samples),
                animate: animate.is_some(),
                ..options
            };
            simulate(&file, &source, &options, out, Figures { plot, animate, events })
        }
        Command::Ensemble { file, vary, runs, seed, record, run, out, plot, threads } => {
            let outputs = [("--out", out.as_deref()), ("--plot", plot.as_deref())];
            if writes_over_input(&run.inputs(&file), &outputs) {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let Some(simulate) = run.options() else { return ExitCode::from(2) };
            let mut varied = Vec::new();
            for text in &vary {
                match engine::input::Vary::parse(text) {
                    Ok(v) => varied.push(v),
                    Err(d) => {
                        eprint!("{}", cli::diagnostics::render("--vary", text, &[d]));
                        return ExitCode::from(2);
                    }
                }
            }
            let options = ::ensemble::Options { simulate, vary: varied, runs, seed, record };
            ensemble(&file, &source, &options, threads.map(usize::from), out, plot)
        }
        Command::Linearize {
            file,
            about,
            set,
            sweep,
            drop_cyclic,
            along,
            run,
            plot,
            format,
            out,
            no_units,
        } => {
            let outputs = [("--out", out.as_deref()), ("--plot", plot.as_deref())];
            let mut inputs = vec![("", file.as_path())];
            let trajectory = along.as_deref().filter(|a| *a != "run").map(std::path::Path::new);
            inputs.extend(trajectory.map(|t| ("--along", t)));
            if writes_over_input(&inputs, &outputs) {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            if let Some(along) = along {
                let others = [
                    ("--about", about.is_some()),
                    ("--sweep", sweep.is_some()),
                    ("--drop-cyclic", drop_cyclic),
                    ("--plot", plot.is_some()),
                ];
                if let Some((flag, _)) = others.iter().find(|(_, given)| *given) {
                    eprintln!(
                        "error: {flag} is about an equilibrium: it does not go with --along, \
                         which linearizes along a motion"
                    );
                    return ExitCode::from(2);
                }
                let options = AlongAsked { along, run, set, no_units };
                return linearize_along(&file, &source, options, format, out);
            }
            if let Some(flag) = run.given().first() {
                eprintln!("error: {flag} sets the run of --along run: give --along run too");
                return ExitCode::from(2);
            }
            if matches!(format, LinearizeFormat::Csv) {
                eprintln!(
                    "error: --format csv writes the matrices at every sample of a motion: give \
                     --along too"
                );
                return ExitCode::from(2);
            }
            // Typed here, read as text there; the same parser reads it back.
            let set = set.iter().map(Assignment::to_string).collect();
            let sweep = sweep.as_ref().map(SweepRange::to_string);
            let options = engine::linearize::Options { about, set, sweep, no_units, drop_cyclic };
            linearize(&file, &source, &options, format, out, plot)
        }
        Command::Export { file, fmu, tolerance, until, no_units } => {
            if writes_over_input(&[("", &file)], &[("--fmu", Some(&fmu))]) {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let Some(until) = time_option(engine::Setting::Until, until.as_deref()) else {
                return ExitCode::from(2);
            };
            let Some(tolerance) = ratio_option(engine::Setting::Tolerance, tolerance.as_deref())
            else {
                return ExitCode::from(2);
            };
            let options = export::fmu::ExportOptions { tolerance, until, no_units };
            export(&file, &source, &options, &fmu)
        }
        Command::Codegen { file, lang, out, no_units } => {
            if matches!(lang, LangArg::Rust)
                && writes_over_input(&[("", &file)], &[("--out", out.as_deref())])
            {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let path = file.display().to_string();
            let options = engine::Options { units: !no_units };
            match lang {
                LangArg::Rust => match export::codegen::codegen_with(&path, &source, options) {
                    Ok(module) => write_or_print(out.as_ref(), &module.source),
                    Err(e) => fail(&path, &e),
                },
                LangArg::C => codegen_c(&path, &source, options, out.as_deref()),
            }
        }
        Command::Orbit {
            file,
            section,
            direction,
            period,
            shift,
            swap,
            ignore,
            until,
            integrator,
            set,
            sweep,
            iterations,
            json,
            no_units,
        } => {
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let (Some(until), Some((method, tolerance, step))) =
                (time_option(engine::Setting::Until, until.as_deref()), integrator.read())
            else {
                return ExitCode::from(2);
            };
            let rising = matches!(direction, DirectionArg::Rising);
            let section = match (section, period) {
                (_, Some(period)) => orbit::Section::Period(period),
                (Some(text), None) => orbit::Section::parse(&text, rising),
                (None, None) => unreachable!("clap requires one"),
            };
            let words = section.words();
            let options = orbit::Options {
                run: simulation::Options {
                    until,
                    method,
                    tolerance,
                    step,
                    set,
                    no_units,
                    ..Default::default()
                },
                section,
                swaps: swap,
                shifts: shift,
                ignore,
                iterations,
            };
            let path = file.display().to_string();
            if let Some(range) = sweep {
                return match orbit::sweep::sweep(&source, &options, &range) {
                    Ok(swept) => {
                        let report = if json {
                            cli::orbit::sweep_json(&path, &swept, &words)
                        } else {
                            cli::orbit::sweep_text(&path, &swept, &words)
                        };
                        print!("{report}");
                        ExitCode::SUCCESS
                    }
                    Err(e) => fail(&path, &e),
                };
            }
            match orbit::orbit(&source, &options) {
                Ok(found) => {
                    let report = if json {
                        cli::orbit::json(&path, &found, &words)
                    } else {
                        cli::orbit::text(&path, &found, &words)
                    };
                    print!("{report}");
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&path, &e),
            }
        }
        Command::Fit {
            file,
            data,
            free,
            bound,
            noise,
            shots,
            iterations,
            integrator,
            set,
            input,
            json,
            out,
            fitted,
            plot,
            no_units,
        } => {
            let mut inputs = vec![("", file.as_path()), ("--data", data.as_path())];
            inputs.extend(input.iter().filter(|i| cli::series::is_series(i)).map(series_file));
            let outputs = [
                ("--out", out.as_deref()),
                ("--fitted", fitted.as_deref()),
                ("--plot", plot.as_deref()),
            ];
            if writes_over_input(&inputs, &outputs) {
                return ExitCode::from(2);
            }
            let (Some((method, tolerance, step)), Some((laws, series))) =
                (integrator.read(), drives(input))
            else {
                return ExitCode::from(2);
            };
            let run = simulation::Options {
                method,
                tolerance,
                step,
                set,
                input: laws,
                input_series: series,
                no_units,
                ..Default::default()
            };
            let request =
                cli::fit::Request { free, bound, noise, shots: shots as usize, iterations, json };
            let written = cli::fit::Written { out, fitted, plot };
            cli::fit::run(&file, &data, run, request, written)
        }
        Command::InverseDynamics { file, trajectory, set, out, no_units } => {
            let inputs = [("", file.as_path()), ("--trajectory", trajectory.as_path())];
            if writes_over_input(&inputs, &[("--out", out.as_deref())]) {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let options = engine::inverse::Options { set, no_units };
            inverse_dynamics(&file, &source, &trajectory, out, &options)
        }
        Command::Bench { file, until, set, stop_when, input, hold, repeats, plot, no_units } => {
            let mut inputs = vec![("", file.as_path())];
            inputs.extend(input.iter().filter(|i| cli::series::is_series(i)).map(series_file));
            if writes_over_input(&inputs, &[("--plot", plot.as_deref())]) {
                return ExitCode::from(2);
            }
            let Some(source) = read_or_report(&file) else { return ExitCode::from(2) };
            let Some((input, input_series)) = drives(input) else {
                return ExitCode::from(2);
            };
            let (Some(until), Some(hold)) = (
                time_option(engine::Setting::Until, until.as_deref()),
                time_option(engine::Setting::Hold, hold.as_deref()),
            ) else {
                return ExitCode::from(2);
            };
            let options = simulation::Options {
                until,
                set,
                stop_when,
                input,
                input_series,
                hold,
                no_units,
                ..Default::default()
            };
            bench(&file, &source, &options, repeats, plot)
        }
        Command::Check { files, no_units } => check(&files, no_units),
    }
}

/// A time given for `setting` (`--until 1/4 min`), in seconds, or `None` after rendering on
/// stderr what is wrong with it, a caret under the culprit.
fn time_option(setting: engine::Setting, text: Option<&str>) -> Option<Option<f64>> {
    let Some(text) = text else { return Some(None) };
    match engine::input::time(setting, text) {
        Ok(seconds) => Some(Some(seconds)),
        Err(diagnostics) => {
            let flag = format!("--{}", setting.name());
            eprint!("{}", cli::diagnostics::render(&flag, text, &diagnostics));
            None
        }
    }
}

/// A pure number given for `setting` (`--tolerance 10^-12`), or `None` after rendering on
/// stderr what is wrong with it.
fn ratio_option(setting: engine::Setting, text: Option<&str>) -> Option<Option<f64>> {
    let Some(text) = text else { return Some(None) };
    match engine::input::ratio(setting, text) {
        Ok(value) => Some(Some(value)),
        Err(diagnostics) => {
            let flag = format!("--{}", setting.name());
            eprint!("{}", cli::diagnostics::render(&flag, text, &diagnostics));
            None
        }
    }
}

/// The file of an input given as a time series, as [`writes_over_input`] names it.
fn series_file(input: &Assignment) -> (&str, &std::path::Path) {
    ("--input", std::path::Path::new(&input.value))
}

/// An input given as a time series, by name.
type Series = (String, sim::Series);

/// The `--input` laws and, read from their files, the time series; `None` after saying on
/// stderr which file could not be read.
fn drives(input: Vec<Assignment>) -> Option<(Vec<Assignment>, Vec<Series>)> {
    let (files, laws): (Vec<_>, Vec<_>) = input.into_iter().partition(cli::series::is_series);
    let mut series = Vec::new();
    for given in files {
        match cli::series::read(std::path::Path::new(&given.value)) {
            Ok(s) => series.push((given.name, s)),
            Err(e) => {
                eprintln!("error: --input {}: {e}", given.name);
                return None;
            }
        }
    }
    Some((laws, series))
}

/// `lagrange derive`: the report to standard output or `out`, the warnings to stderr.
fn derive(
    file: &std::path::Path,
    format: FormatArg,
    out: Option<PathBuf>,
    no_units: bool,
    full: bool,
) -> ExitCode {
    let Some(source) = read_or_report(file) else { return ExitCode::from(2) };
    let path = file.display().to_string();
    let format = match format {
        FormatArg::Text => cli::Format::Text,
        FormatArg::Latex => cli::Format::Latex,
        FormatArg::Json => cli::Format::Json,
    };
    let options = engine::Options { units: !no_units };
    match cli::derive_keeping(&path, &source, format, options, full) {
        Ok((report, warnings, derivation)) => {
            eprint!("{warnings}");
            // The process ends here: freeing a large model's expressions one by one (a
            // tenth of the bicycle's run) would be work for nothing.
            std::mem::forget(derivation);
            write_or_print(out.as_ref(), &report)
        }
        Err(diagnostics) => {
            eprint!("{diagnostics}");
            ExitCode::from(2)
        }
    }
}

/// `lagrange check`: each file's report, then the count of `expect` lines that held and
/// failed; the worst exit code of the files.
fn check(files: &[PathBuf], no_units: bool) -> ExitCode {
    let mut worst = 0;
    let (mut held, mut failed) = (0, 0);
    for file in files {
        let Some(source) = read_or_report(file) else {
            worst = 2;
            continue;
        };
        let result = cli::check::check_file_with(
            &file.display().to_string(),
            &source,
            engine::Options { units: !no_units },
        );
        eprint!("{}", result.warnings);
        if result.exit_code == 2 {
            eprint!("{}", result.report);
        } else {
            emit(&result.report);
        }
        held += result.held;
        failed += result.failed;
        worst = worst.max(result.exit_code);
    }
    emit(&format!("{held} passed, {failed} failed\n"));
    ExitCode::from(worst as u8)
}

fn write_or_print(out: Option<&PathBuf>, text: &str) -> ExitCode {
    match out {
        Some(path) => match cli::write_atomically(path, text) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: cannot write {}: {e}", path.display());
                ExitCode::from(2)
            }
        },
        None => {
            emit(text);
            ExitCode::SUCCESS
        }
    }
}

/// `lagrange codegen --lang c`: NAME.h and NAME.c into the directory `out`.
fn codegen_c(
    path: &str,
    source: &str,
    options: engine::Options,
    out: Option<&std::path::Path>,
) -> ExitCode {
    let Some(dir) = out else {
        eprintln!("error: `codegen --lang c` writes two files: give the directory with --out DIR");
        return ExitCode::from(2);
    };
    let module = match export::codegen::c(path, source, options) {
        Ok(module) => module,
        Err(e) => return fail(path, &e),
    };
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!("error: cannot create {}: {e}", dir.display());
        return ExitCode::from(2);
    }
    for (ext, text) in [("h", &module.header), ("c", &module.source)] {
        let file = dir.join(format!("{}.{ext}", module.name));
        if let Err(e) = cli::write_atomically(&file, text) {
            eprintln!("error: cannot write {}: {e}", file.display());
            return ExitCode::from(2);
        }
    }
    ExitCode::SUCCESS
}

/// Writes to standard output. A reader that stops reading (`| head`) is not an error: the
/// rest of the output is dropped and the command ends with its own exit code, where `print!`
/// would panic.
fn emit(text: &str) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_all(text.as_bytes()).and_then(|()| stdout.flush()) {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("error: cannot write the output: {e}");
        }
    }
}

/// Says on stderr why the engine could not do what was asked; its exit code.
/// `lagrange export --fmu`: the FMU's contents from the engine, compiled and archived.
fn export(
    file: &std::path::Path,
    source: &str,
    options: &export::fmu::ExportOptions,
    out: &std::path::Path,
) -> ExitCode {
    let path = file.display().to_string();
    let fmu = match export::fmu::export(&path, source, options) {
        Ok(fmu) => fmu,
        Err(e) => return fail(&path, &e),
    };
    match cli::export::export(&fmu, &cli::export::compiler(), out) {
        Ok(()) => {
            eprintln!("wrote {} (FMI 2.0, Model Exchange and Co-Simulation)", out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn fail(path: &str, error: &engine::Error) -> ExitCode {
    let message = cli::diagnostics::error(path, error);
    eprint!("{}", if message.ends_with('\n') { message } else { format!("{message}\n") });
    ExitCode::from(error.exit_code())
}

/// The pictures `simulate` draws besides its table.
struct Figures {
    /// The recorded quantities against time, as SVG.
    plot: Option<PathBuf>,
    /// The motion, as an HTML page that plays it.
    animate: Option<PathBuf>,
    /// The contact events, as CSV.
    events: Option<PathBuf>,
}

fn simulate(
    file: &std::path::Path,
    source: &str,
    options: &simulation::Options,
    out: Option<PathBuf>,
    figures: Figures,
) -> ExitCode {
    let Figures { plot, animate, events } = figures;
    let path = file.display().to_string();
    for target in out.iter().chain(plot.iter()).chain(animate.iter()).chain(events.iter()) {
        let ext = target.extension().and_then(|e| e.to_str()).unwrap_or("");
        let allowed: &[&str] = if Some(target) == animate.as_ref() {
            &["html"]
        } else if Some(target) == events.as_ref() {
            &["csv"]
        } else if Some(target) == plot.as_ref() {
            &["svg"]
        } else {
            &["csv", "json"]
        };
        if !allowed.contains(&ext) {
            eprintln!(
                "error: cannot tell the format of {}: use .{}",
                target.display(),
                allowed.join(" or .")
            );
            return ExitCode::from(2);
        }
    }
    let json = out.as_ref().and_then(|o| o.extension()).and_then(|e| e.to_str()) == Some("json");
    if plot.is_none() && animate.is_none() {
        return simulate_streamed(&path, source, options, out.as_ref(), json, events.as_ref());
    }
    // The plot draws every row, and the animation plays every frame: the rows are kept.
    let outcome = match cli::simulate::simulate(source, options) {
        Ok(o) => o,
        Err(e) => return fail(&path, &e),
    };
    let table = if json { cli::simulate::json(&outcome) } else { cli::simulate::csv(&outcome) };
    let mut code = if outcome.run.fault.is_some() { ExitCode::from(1) } else { ExitCode::SUCCESS };
    if write_or_print(out.as_ref(), &table) != ExitCode::SUCCESS {
        code = ExitCode::from(2);
    }
    if let Some(plot) = plot {
        let times = &outcome.run.trajectory.times;
        let mut series: Vec<(String, Vec<f64>)> = (0..outcome.shown)
            .map(|c| {
                let v = outcome.run.trajectory.rows.iter().map(|r| r[c]).collect();
                (outcome.columns[c].clone(), v)
            })
            .collect();
        let energy = outcome.energy();
        let e0 = energy.first().copied().unwrap_or(0.0);
        series.push(("energy error E − E(0)".to_string(), energy.iter().map(|e| e - e0).collect()));
        let title = format!("{} ({})", path, outcome.method.name());
        if let Err(e) =
            cli::write_atomically(&plot, &cli::plot::time_series(&title, times, &series))
        {
            eprintln!("error: cannot write {}: {e}", plot.display());
            code = ExitCode::from(2);
        }
    }
    if write_events(events.as_ref(), &outcome) != ExitCode::SUCCESS {
        code = ExitCode::from(2);
    }
    if let (Some(target), Some(animation)) = (animate, &outcome.animation) {
        if let Err(e) = cli::write_atomically(&target, &cli::animate::page(animation, &path)) {
            eprintln!("error: cannot write {}: {e}", target.display());
            code = ExitCode::from(2);
        }
    }
    eprint!("{}", cli::simulate::summary(&outcome));
    code
}

/// `lagrange simulate` with no picture: the table written as the rows are made, to a file put
/// in place once the run is over (or not at all, where the run is refused) or to standard
/// output, so that no row is kept.
fn simulate_streamed(
    path: &str,
    source: &str,
    options: &simulation::Options,
    out: Option<&PathBuf>,
    json: bool,
    events: Option<&PathBuf>,
) -> ExitCode {
    let mut table = cli::simulate::Table::new(json, Destination::to(out));
    let outcome = match cli::simulate::simulate_into(source, options, &mut table) {
        Ok(o) => o,
        Err(e) => return fail(path, &e),
    };
    let mut code = if outcome.run.fault.is_some() { ExitCode::from(1) } else { ExitCode::SUCCESS };
    if Destination::report(table.finish(&outcome).and_then(Destination::finish), out)
        != ExitCode::SUCCESS
    {
        code = ExitCode::from(2);
    }
    if write_events(events, &outcome) != ExitCode::SUCCESS {
        code = ExitCode::from(2);
    }
    eprint!("{}", cli::simulate::summary(&outcome));
    code
}

/// Writes a run's contact events to `target` as CSV, where asked.
fn write_events(target: Option<&PathBuf>, outcome: &simulation::Outcome) -> ExitCode {
    let Some(target) = target else { return ExitCode::SUCCESS };
    match cli::write_atomically(target, &cli::simulate::contact_events_csv(outcome)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: cannot write {}: {e}", target.display());
            ExitCode::from(2)
        }
    }
}

/// Where a streamed table goes.
enum Destination {
    /// A file, put in place whole when the table is done.
    File(cli::AtomicFile),
    Stdout(std::io::BufWriter<std::io::Stdout>),
    /// A file that cannot be written: the rows are dropped, and the error said at the end.
    Unwritable(std::io::Error),
}

impl Destination {
    /// A file at `out`, put in place when the table is done, or standard output.
    fn to(out: Option<&PathBuf>) -> Destination {
        match out.map(|o| cli::AtomicFile::create(o)) {
            Some(Ok(file)) => Destination::File(file),
            // Said after the run, as a table that cannot be written always was.
            Some(Err(e)) => Destination::Unwritable(e),
            None => Destination::Stdout(std::io::BufWriter::new(std::io::stdout())),
        }
    }

    /// Says why the table could not be written, as [`write_or_print`] says it; its exit code.
    fn report(written: std::io::Result<()>, out: Option<&PathBuf>) -> ExitCode {
        match (written, out) {
            (Ok(()), _) => ExitCode::SUCCESS,
            (Err(e), Some(out)) => {
                eprintln!("error: cannot write {}: {e}", out.display());
                ExitCode::from(2)
            }
            // A reader that stops reading (`| head`) is not an error, as for `emit`.
            (Err(e), None) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
            (Err(e), None) => {
                eprintln!("error: cannot write the output: {e}");
                ExitCode::SUCCESS
            }
        }
    }

    fn finish(self) -> std::io::Result<()> {
        use std::io::Write;
        match self {
            Destination::File(file) => file.finish(),
            Destination::Stdout(mut out) => out.flush(),
            Destination::Unwritable(e) => Err(e),
        }
    }
}

impl std::io::Write for Destination {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        match self {
            Destination::File(file) => file.write(bytes),
            Destination::Stdout(out) => out.write(bytes),
            Destination::Unwritable(_) => Ok(bytes.len()),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Destination::File(file) => file.flush(),
            Destination::Stdout(out) => out.flush(),
            Destination::Unwritable(_) => Ok(()),
        }
    }
}

fn ensemble(
    file: &std::path::Path,
    source: &str,
    options: &::ensemble::Options,
    threads: Option<usize>,
    out: Option<PathBuf>,
    plot: Option<PathBuf>,
) -> ExitCode {
    let path = file.display().to_string();
    let formats = [(out.as_ref(), &["csv"][..]), (plot.as_ref(), &["svg", "png"][..])];
    for (target, allowed) in formats {
        let Some(target) = target else { continue };
        let ext = target.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !allowed.contains(&ext) {
            let wanted = allowed.join(" or .");
            eprintln!("error: cannot tell the format of {}: use .{wanted}", target.display());
            return ExitCode::from(2);
        }
    }
    if let Err(e) = plot.as_ref().map_or(Ok(()), |_| cli::plot::ensemble::check(&options.vary)) {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let threads = threads.unwrap_or_else(::ensemble::cores);
    let started = std::time::Instant::now();
    let ensemble = match ::ensemble::Ensemble::new(source, options) {
        Ok(ensemble) => ensemble,
        Err(e) => return fail(&path, &e),
    };
    // The rows are written as they come, chunk by chunk, and not kept.
    let header = ensemble.table();
    let mut outputs = cli::ensemble::Outputs {
        csv: cli::ensemble::Csv::new(&header, Destination::to(out.as_ref())),
        tally: cli::ensemble::Tally::default(),
        picture: plot.as_ref().map(|_| cli::plot::ensemble::Picture::new(&header)),
    };
    cli::ensemble::stream(&ensemble, threads, &mut outputs);
    let wall_seconds = started.elapsed().as_secs_f64();
    let cli::ensemble::Outputs { csv, tally, picture } = outputs;
    let mut code = Destination::report(csv.finish().and_then(Destination::finish), out.as_ref());
    if let (Some(plot), Some(picture)) = (plot, picture) {
        let title = format!("{path}: {}", header.columns.get(header.varied).map_or("", |c| c));
        if let Err(e) = cli::plot::ensemble::ensemble(&picture, &title, &plot) {
            eprintln!("error: {e}");
            code = ExitCode::from(2);
        }
    }
    eprint!("{}", cli::ensemble::summary_of(&tally, wall_seconds, threads));
    code
}

/// Whether a plot's path ends in `.svg`, the one format plots are written in; says so when not.
fn is_svg(p: &std::path::Path) -> bool {
    let svg = p.extension().and_then(|e| e.to_str()) == Some("svg");
    if !svg {
        eprintln!("error: cannot tell the format of {}: use .svg", p.display());
    }
    svg
}

fn linearize(
    file: &std::path::Path,
    source: &str,
    options: &engine::linearize::Options,
    format: LinearizeFormat,
    out: Option<PathBuf>,
    plot: Option<PathBuf>,
) -> ExitCode {
    let path = file.display().to_string();
    if let Some(p) = &plot {
        if !is_svg(p) {
            return ExitCode::from(2);
        }
        if options.sweep.is_none() {
            eprintln!("error: --plot draws a sweep: give --sweep p=a:b:n too");
            return ExitCode::from(2);
        }
    }
    let linearized = match engine::linearize::linearize(source, options) {
        Ok(l) => l,
        Err(e) => return fail(&path, &e),
    };
    let report = match format {
        LinearizeFormat::Text => cli::linearize::text(&linearized),
        LinearizeFormat::Json => cli::linearize::json(&linearized),
        LinearizeFormat::Csv => unreachable!("refused without --along"),
    };
    if let (Some(p), Some(sweep)) = (plot, &linearized.sweep) {
        let title = format!("Eigenvalues against {}: {path}", sweep.parameter);
        if let Err(e) = cli::write_atomically(&p, &cli::plot::sweep(&title, sweep)) {
            eprintln!("error: cannot write {}: {e}", p.display());
            return ExitCode::from(2);
        }
    }
    // The process ends here: freeing a large model's expressions one by one (a tenth of the
    // bicycle's run) would be work for nothing.
    std::mem::forget(linearized);
    write_or_print(out.as_ref(), &report)
}

/// What `linearize --along` is asked for.
struct AlongAsked {
    /// `run`, or the trajectory's path.
    along: String,
    run: AlongRun,
    set: Vec<Assignment>,
    no_units: bool,
}

fn linearize_along(
    file: &std::path::Path,
    source: &str,
    asked: AlongAsked,
    format: LinearizeFormat,
    out: Option<PathBuf>,
) -> ExitCode {
    let path = file.display().to_string();
    let AlongAsked { along, run, set, no_units } = asked;
    if along != "run" {
        if let Some(flag) = run.given().first() {
            eprintln!(
                "error: {flag} sets the run of --along run, and --along {along} reads the \
                 motion from a file"
            );
            return ExitCode::from(2);
        }
    }
    let (Some(until), Some(tolerance), Some(step)) = (
        time_option(engine::Setting::Until, run.until.as_deref()),
        ratio_option(engine::Setting::Tolerance, run.tolerance.as_deref()),
        time_option(engine::Setting::Step, run.step.as_deref()),
    ) else {
        return ExitCode::from(2);
    };
    let options = simulation::Options {
        until,
        method: run.method.map(|m| m.name().to_string()),
        tolerance,
        step,
        set,
        no_units,
        samples: run.samples.unwrap_or(200),
        ..Default::default()
    };
    let linearized = match cli::along::linearize(&path, source, &along, &options) {
        Ok(l) => l,
        Err((message, code)) => {
            eprint!("{}", if message.ends_with('\n') { message } else { format!("{message}\n") });
            return ExitCode::from(code);
        }
    };
    let what = if along == "run" { format!("a run of {path}") } else { along.clone() };
    let report = match format {
        LinearizeFormat::Text => cli::along::text(&what, &linearized),
        LinearizeFormat::Json => cli::along::json(&linearized),
        LinearizeFormat::Csv => cli::along::csv(&linearized),
    };
    write_or_print(out.as_ref(), &report)
}

fn inverse_dynamics(
    file: &std::path::Path,
    source: &str,
    trajectory: &std::path::Path,
    out: Option<PathBuf>,
    options: &engine::inverse::Options,
) -> ExitCode {
    let path = file.display().to_string();
    let mut inverse = match engine::inverse::inverse_dynamics(source, options) {
        Ok(inverse) => inverse,
        Err(e) => return fail(&path, &e),
    };
    let table = std::fs::read(trajectory)
        .map_err(|e| format!("error: cannot read {}: {e}", trajectory.display()))
        .and_then(|bytes| {
            let name = trajectory.display().to_string();
            let text =
                String::from_utf8(bytes).map_err(|_| format!("error: {name} is not UTF-8 text"))?;
            cli::inverse::read_trajectory(&name, &text, inverse.coordinates())
        });
    let table = match table {
        Ok(table) => table,
        Err(message) => {
            eprintln!("{message}");
            return ExitCode::from(2);
        }
    };
    let forces = match cli::inverse::torques_csv(&mut inverse, &table) {
        Ok(forces) => forces,
        Err(e) => return fail(&path, &e),
    };
    eprint!("{}", cli::inverse::note(&inverse));
    write_or_print(out.as_ref(), &forces)
}

fn bench(
    file: &std::path::Path,
    source: &str,
    options: &simulation::Options,
    repeats: usize,
    plot: Option<PathBuf>,
) -> ExitCode {
    let path = file.display().to_string();
    if plot.as_deref().is_some_and(|p| !is_svg(p)) {
        return ExitCode::from(2);
    }
    let report =
        match simulation::bench::bench(source, options, repeats, &mut cli::progress::Bar::new()) {
            Ok(r) => r,
            Err(e) => return fail(&path, &e),
        };
    emit(&format!(
        "{path}: error = largest difference of the final state from DOP853 at tol {:.0e} \
         (which differs from tol {:.0e} by {:.1e}); time: median of {repeats}, integration only\n",
        simulation::bench::REFERENCE_TOLERANCE,
        10.0 * simulation::bench::REFERENCE_TOLERANCE,
        report.reference_check
    ));
    emit(&simulation::bench::table(&report.trials, &report.inapplicable));
    for t in report.trials.iter().filter(|t| t.fault.is_some()) {
        eprintln!(
            "{} {}: {}",
            t.method.name(),
            t.setting.label(),
            t.fault.as_deref().unwrap_or("")
        );
    }
    if let Some(p) = plot {
        let title = format!("Work–precision: {path}");
        if let Err(e) = cli::write_atomically(
            &p,
            &cli::plot::work_precision(&title, &report.trials, &report.inapplicable),
        ) {
            eprintln!("error: cannot write {}: {e}", p.display());
            return ExitCode::from(2);
        }
    }
    ExitCode::SUCCESS
}
