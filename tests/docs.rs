//! The manual cannot go stale: every scene in README.md and docs/*.md derives (or is refused,
//! where the page shows a mistake), every `lagrange` command in a `sh` block runs on the
//! bundled examples through the library, every `text,output` block is what its command prints,
//! and every path, link and picture a page names exists. docs/README.md describes the tags.

use std::path::{Path, PathBuf};

use engine::input::{Assignment, SweepRange};

/// The pages, relative to the repository; `every_page_is_tested` keeps the list whole.
const PAGES: [&str; 19] = [
    "README.md",
    "docs/README.md",
    "docs/language.md",
    "docs/commands.md",
    "docs/simulating.md",
    "docs/linearizing.md",
    "docs/bicycle.md",
    "docs/python.md",
    "docs/fmu.md",
    "docs/benchmarks.md",
    "docs/examples.md",
    "docs/testing.md",
    "docs/control.md",
    "docs/ensembles.md",
    "docs/c.md",
    "docs/contacts.md",
    "docs/friction.md",
    "docs/orbits.md",
    "docs/fitting.md",
];

/// The name a refused scene's diagnostic gives its file.
const BAD_SCENE: &str = "bad.lag";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A fenced code block: its tag (the info string), its lines without the fence's indentation,
/// and the line of its opening fence.
struct Block {
    tag: String,
    text: String,
    line: usize,
}

/// The page's fenced blocks, and its text outside them.
fn blocks(page: &str) -> (Vec<Block>, String) {
    let mut out = Vec::new();
    let mut prose = String::new();
    let mut open: Option<(usize, String, usize, String)> = None;
    for (i, line) in page.lines().enumerate() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        if let Some(fence) = trimmed.strip_prefix("```") {
            match open.take() {
                None => open = Some((indent, fence.trim().to_string(), i + 1, String::new())),
                Some((_, tag, start, text)) => out.push(Block { tag, text, line: start }),
            }
            continue;
        }
        match &mut open {
            Some((indent, _, _, text)) => {
                let strip = line.len() - line.trim_start().len();
                text.push_str(&line[strip.min(*indent)..]);
                text.push('\n');
            }
            None => {
                prose.push_str(line);
                prose.push('\n');
            }
        }
    }
    assert!(open.is_none(), "a code block is not closed");
    (out, prose)
}

/// Words of a shell line: whitespace-separated, with '…' and "…" quoting, up to a `#` comment.
fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word: Option<String> = None;
    let mut quote: Option<char> = None;
    for c in line.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => word.get_or_insert_with(String::new).push(c),
            None if c == '\'' || c == '"' => {
                quote = Some(c);
                word.get_or_insert_with(String::new);
            }
            None if c == '#' && word.is_none() => break,
            None if c.is_whitespace() => out.extend(word.take()),
            None => word.get_or_insert_with(String::new).push(c),
        }
    }
    out.extend(word);
    out
}

/// The `--flag value` and `--flag=value` options of a command, and its other arguments.
struct Args {
    flags: Vec<(String, Option<String>)>,
    positional: Vec<String>,
}

impl Args {
    /// `switches` take no value.
    fn parse(words: &[String], switches: &[&str]) -> Args {
        let mut args = Args { flags: Vec::new(), positional: Vec::new() };
        let mut rest = words.iter();
        while let Some(w) = rest.next() {
            if let Some(flag) = w.strip_prefix("--") {
                if let Some((name, value)) = flag.split_once('=') {
                    args.flags.push((name.to_string(), Some(value.to_string())));
                } else if switches.contains(&flag) {
                    args.flags.push((flag.to_string(), None));
                } else {
                    let value = rest.next().unwrap_or_else(|| panic!("--{flag} needs a value"));
                    args.flags.push((flag.to_string(), Some(value.clone())));
                }
            } else {
                args.positional.push(w.clone());
            }
        }
        args
    }

    /// Every value of a flag, in order.
    fn all(&self, name: &str) -> Vec<String> {
        self.flags.iter().filter(|(n, _)| n == name).filter_map(|(_, v)| v.clone()).collect()
    }

    fn last(&self, name: &str) -> Option<String> {
        self.all(name).pop()
    }

    fn has(&self, name: &str) -> bool {
        self.flags.iter().any(|(n, _)| n == name)
    }

    /// Every value of a flag, read as the command's value parser reads it.
    fn parsed<T: std::str::FromStr<Err: std::fmt::Display>>(
        &self,
        name: &str,
    ) -> Result<Vec<T>, String> {
        let read = |v: String| v.parse().map_err(|e| format!("--{name} {v}: {e}"));
        self.all(name).into_iter().map(read).collect()
    }

    fn number<T: std::str::FromStr>(&self, name: &str) -> Result<Option<T>, String> {
        self.last(name)
            .map(|v| v.parse().map_err(|_| format!("--{name} {v}: not a number")))
            .transpose()
    }

    /// Refuses a flag the command does not take (or this test does not know).
    fn only(&self, known: &[&str]) -> Result<(), String> {
        match self.flags.iter().find(|(n, _)| !known.contains(&n.as_str())) {
            Some((n, _)) => Err(format!("--{n} is not an option tests/docs.rs knows here")),
            None => Ok(()),
        }
    }
}

fn extension(path: &str) -> &str {
    Path::new(path).extension().and_then(|e| e.to_str()).unwrap_or("")
}

fn read(file: &str) -> Result<String, String> {
    cli::read_scene(&root().join(file))
}

/// Runs one `lagrange` command through the library, as the command would, writing nothing;
/// what it would show on a terminal (standard output, then standard error), or why it would
/// not exit with status 0.
fn run(words: &[String]) -> Result<String, String> {
    let (command, rest) = words.split_first().ok_or("no command")?;
    match command.as_str() {
        "derive" => derive(rest),
        "check" => check(rest),
        "simulate" => simulate(rest),
        "linearize" => linearize(rest),
        "ensemble" => ensemble(rest),
        "orbit" => orbit(rest),
        "fit" => fit(rest),
        other => Err(format!("`lagrange {other}` is not run by tests/docs.rs")),
    }
}

/// The checks a command's `--no-units` leaves.
fn units(args: &Args) -> engine::Options {
    engine::Options { units: !args.has("no-units") }
}

/// `lagrange derive`: the report, or nothing with `--out`, then the warnings.
fn derive(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units", "full"]);
    args.only(&["format", "out", "no-units", "full"])?;
    let [file] = &args.positional[..] else { return Err("one file".into()) };
    let format = match args.last("format").as_deref() {
        None | Some("text") => cli::Format::Text,
        Some("latex") => cli::Format::Latex,
        Some("json") => cli::Format::Json,
        Some(other) => return Err(format!("no format {other}")),
    };
    let source = read(file)?;
    let (report, warnings) =
        cli::derive_report_with(file, &source, format, units(&args), args.has("full"))?;
    let shown = if args.has("out") { String::new() } else { report };
    Ok(shown + &warnings)
}

/// `lagrange check`: each file's report, the count, then the warnings.
fn check(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units"]);
    args.only(&["no-units"])?;
    let (mut shown, mut warned, mut held, mut failed) = (String::new(), String::new(), 0, 0);
    for file in &args.positional {
        let result = cli::check::check_file_with(file, &read(file)?, units(&args));
        if result.exit_code != 0 {
            return Err(format!("exit {}:\n{}", result.exit_code, result.report));
        }
        shown += &result.report;
        warned += &result.warnings;
        held += result.held;
        failed += result.failed;
    }
    Ok(format!("{shown}{held} passed, {failed} failed\n{warned}"))
}

/// Refuses a file whose extension the command refuses for its flag.
fn formats(args: &Args, allowed: &[(&str, &[&str])]) -> Result<(), String> {
    for (flag, extensions) in allowed {
        if let Some(target) = args.last(flag) {
            if !extensions.contains(&extension(&target)) {
                return Err(format!("--{flag} {target}: the command refuses the format"));
            }
        }
    }
    Ok(())
}

/// The flags of [`run_settings`].
const RUN_FLAGS: [&str; 10] = [
    "until",
    "method",
    "tolerance",
    "step",
    "set",
    "input",
    "hold",
    "stop-when",
    "event",
    "no-units",
];

/// The settings of a run that `simulate` and `ensemble` share.
fn run_settings(args: &Args) -> Result<simulation::Options, String> {
    Ok(simulation::Options {
        until: args.number("until")?,
        method: args.last("method"),
        tolerance: args.number("tolerance")?,
        step: args.number("step")?,
        set: args.parsed("set")?,
        input: args.parsed("input")?,
        hold: args.number("hold")?,
        stop_when: args.all("stop-when"),
        events: args.all("event"),
        no_units: args.has("no-units"),
        ..Default::default()
    })
}

/// `lagrange simulate`: the CSV (unless `--out`) and the summary; the files it would write made in memory.
fn simulate(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units"]);
    args.only(
        &[&RUN_FLAGS[..], &["output", "samples", "out", "plot", "animate", "events"]].concat(),
    )?;
    let [file] = &args.positional[..] else { return Err("one file".into()) };
    formats(
        &args,
        &[
            ("out", &["csv", "json"]),
            ("plot", &["svg"]),
            ("animate", &["html"]),
            ("events", &["csv"]),
        ],
    )?;
    let animate = args.has("animate");
    let options = simulation::Options {
        output: args.all("output"),
        samples: args.number("samples")?.unwrap_or(if animate { 1000 } else { 200 }),
        animate,
        ..run_settings(&args)?
    };
    let outcome = cli::simulate::simulate(&read(file)?, &options)
        .map_err(|e| cli::diagnostics::error(file, &e))?;
    if let Some(fault) = &outcome.run.fault {
        return Err(format!("a numeric fault (exit 1): {fault:?}"));
    }
    if animate {
        let animation = outcome.animation.as_ref().ok_or("no animation")?;
        assert!(cli::animate::page(animation, file).contains("<canvas"));
    }
    let table = match args.last("out") {
        Some(_) => String::new(),
        None => cli::simulate::csv(&outcome),
    };
    Ok(table + &cli::simulate::summary(&outcome))
}

/// `lagrange ensemble`: the CSV (unless `--out`) and the summary; `--plot` checked as the
/// command checks it, and not drawn.
fn ensemble(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units"]);
    let own = ["vary", "runs", "seed", "record", "out", "plot", "threads"];
    args.only(&[&RUN_FLAGS[..], &own].concat())?;
    let [file] = &args.positional[..] else { return Err("one file".into()) };
    formats(&args, &[("out", &["csv"]), ("plot", &["svg", "png"])])?;
    let mut vary = Vec::new();
    for text in args.all("vary") {
        let parsed = engine::input::Vary::parse(&text);
        vary.push(parsed.map_err(|d| cli::diagnostics::render("--vary", &text, &[d]))?);
    }
    if args.has("plot") {
        cli::plot::ensemble::check(&vary)?;
    }
    let options = ::ensemble::Options {
        simulate: run_settings(&args)?,
        vary,
        runs: args.number("runs")?,
        seed: args.number("seed")?.unwrap_or(0),
        record: args.all("record"),
    };
    let threads: Option<usize> = args.number("threads")?;
    let table = cli::ensemble::ensemble(&read(file)?, &options, threads)
        .map_err(|e| cli::diagnostics::error(file, &e))?;
    let shown = if args.has("out") { String::new() } else { cli::ensemble::csv(&table) };
    let threads = threads.unwrap_or_else(::ensemble::cores);
    Ok(shown + &cli::ensemble::summary(&table, 0.0, threads))
}

/// `lagrange linearize`: the report (unless `--out`); a sweep's plot made in memory.
fn linearize(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units", "drop-cyclic"]);
    let along = ["along", "until", "method", "tolerance", "step", "samples"];
    let known = ["about", "set", "sweep", "plot", "format", "out", "no-units", "drop-cyclic"];
    args.only(&[&known[..], &along[..]].concat())?;
    let [file] = &args.positional[..] else { return Err("one file".into()) };
    if let Some(motion) = args.last("along") {
        return linearize_along(file, &motion, &args);
    }
    if let Some(flag) = along.iter().find(|flag| args.has(flag)) {
        return Err(format!("--{flag} without --along: the command refuses it"));
    }
    if let Some(plot) = args.last("plot") {
        if extension(&plot) != "svg" || !args.has("sweep") {
            return Err(format!("--plot {plot}: the command refuses it"));
        }
    }
    let options = engine::linearize::Options {
        about: args.last("about"),
        // Read as the command's value parsers read them, passed on as text.
        set: args.parsed::<Assignment>("set")?.iter().map(Assignment::to_string).collect(),
        sweep: args.parsed::<SweepRange>("sweep")?.pop().map(|s| s.to_string()),
        no_units: args.has("no-units"),
        drop_cyclic: args.has("drop-cyclic"),
    };
    let linearized = engine::linearize::linearize(&read(file)?, &options)
        .map_err(|e| cli::diagnostics::error(file, &e))?;
    let report = match args.last("format").as_deref() {
        None | Some("text") => cli::linearize::text(&linearized),
        Some("json") => cli::linearize::json(&linearized),
        Some(other) => return Err(format!("no format {other}")),
    };
    if let (Some(_), Some(sweep)) = (args.last("plot"), &linearized.sweep) {
        assert!(cli::plot::sweep(file, sweep).starts_with("<svg"));
    }
    Ok(if args.has("out") { String::new() } else { report })
}

/// `lagrange linearize --along`: the report along a run or a trajectory's file, as the command
/// refuses the flags of a linearization about an equilibrium beside it.
fn linearize_along(file: &str, motion: &str, args: &Args) -> Result<String, String> {
    if let Some(flag) = ["about", "sweep", "plot", "drop-cyclic"].iter().find(|f| args.has(f)) {
        return Err(format!("--{flag} with --along: the command refuses it"));
    }
    let options = simulation::Options {
        until: args.number("until")?,
        method: args.last("method"),
        tolerance: args.number("tolerance")?,
        step: args.number("step")?,
        samples: args.number("samples")?.unwrap_or(200),
        set: args.parsed("set")?,
        no_units: args.has("no-units"),
        ..Default::default()
    };
    let l = cli::along::linearize(file, &read(file)?, motion, &options).map_err(|(e, _)| e)?;
    let what = if motion == "run" { format!("a run of {file}") } else { motion.to_string() };
    let report = match args.last("format").as_deref() {
        None | Some("text") => cli::along::text(&what, &l),
        Some("json") => cli::along::json(&l),
        Some("csv") => cli::along::csv(&l),
        Some(other) => return Err(format!("no format {other}")),
    };
    Ok(if args.has("out") { String::new() } else { report })
}

/// `lagrange orbit`: the report, text or JSON.
fn orbit(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units", "json"]);
    let own = [
        "section",
        "direction",
        "period",
        "shift",
        "swap",
        "ignore",
        "iterations",
        "json",
        "sweep",
    ];
    args.only(&[&["until", "method", "tolerance", "step", "set", "no-units"][..], &own].concat())?;
    let [file] = &args.positional[..] else { return Err("one file".into()) };
    let rising = match args.last("direction").as_deref() {
        None | Some("rising") => true,
        Some("falling") => false,
        Some(other) => return Err(format!("no direction {other}")),
    };
    let section = match (args.last("section"), args.last("period")) {
        (None, Some(period)) => orbit::Section::Period(period),
        (Some(text), None) => orbit::Section::parse(&text, rising),
        _ => return Err("one of --section and --period".into()),
    };
    let words = section.words();
    let options = orbit::Options {
        run: simulation::Options {
            until: args.number("until")?,
            method: args.last("method"),
            tolerance: args.number("tolerance")?,
            step: args.number("step")?,
            set: args.parsed("set")?,
            no_units: args.has("no-units"),
            ..Default::default()
        },
        section,
        swaps: args.parsed("swap")?,
        shifts: args.parsed("shift")?,
        ignore: args.all("ignore"),
        iterations: args.number("iterations")?.unwrap_or(30),
    };
    if let Some(range) = args.parsed::<SweepRange>("sweep")?.pop() {
        let swept = orbit::sweep::sweep(&read(file)?, &options, &range)
            .map_err(|e| cli::diagnostics::error(file, &e))?;
        return Ok(if args.has("json") {
            cli::orbit::sweep_json(file, &swept, &words)
        } else {
            cli::orbit::sweep_text(file, &swept, &words)
        });
    }
    let found =
        orbit::orbit(&read(file)?, &options).map_err(|e| cli::diagnostics::error(file, &e))?;
    Ok(if args.has("json") {
        cli::orbit::json(file, &found, &words)
    } else {
        cli::orbit::text(file, &found, &words)
    })
}

/// `lagrange fit`: the report, text or JSON; the files it would write are not written.
fn fit(rest: &[String]) -> Result<String, String> {
    let args = Args::parse(rest, &["no-units", "json"]);
    let own = ["data", "free", "bound", "noise", "shots", "iterations", "json", "plot", "fitted"];
    args.only(&[&["method", "tolerance", "step", "set", "input", "no-units"][..], &own].concat())?;
    let [file] = &args.positional[..] else { return Err("one file".into()) };
    let data = args.last("data").ok_or("--data")?;
    let mut series = Vec::new();
    for input in args.parsed::<Assignment>("input")? {
        let read = cli::series::read(&root().join(&input.value))?;
        series.push((input.name, read));
    }
    let run = simulation::Options {
        method: args.last("method"),
        tolerance: args.number("tolerance")?,
        step: args.number("step")?,
        set: args.parsed("set")?,
        input_series: series,
        no_units: args.has("no-units"),
        ..Default::default()
    };
    let request = cli::fit::Request {
        free: args.all("free"),
        bound: args.all("bound"),
        noise: args.parsed("noise")?,
        shots: args.number("shots")?.unwrap_or(1),
        iterations: args.number("iterations")?.unwrap_or(100),
        json: args.has("json"),
    };
    let (_, found) = cli::fit::from_files(&root().join(file), &root().join(&data), run, &request)
        .map_err(|(message, _)| message)?;
    Ok(if request.json {
        cli::fit::json(file, &data, &found)
    } else {
        cli::fit::text_report(file, &data, &found)
    })
}

/// The `lagrange` command of a shell line, if it is one that is run: `lagrange derive …` or
/// `cargo run -- derive …` (with `--release` or not).
fn command(line: &str) -> Option<Vec<String>> {
    let words = words(line);
    let rest = match words.first().map(String::as_str) {
        Some("lagrange") => &words[1..],
        Some("cargo") => {
            let dashes = words.iter().position(|w| w == "--")?;
            (words[1] == "run").then_some(&words[dashes + 1..])?
        }
        _ => return None,
    };
    let run = ["derive", "check", "simulate", "linearize", "ensemble", "orbit", "fit"];
    run.contains(&rest.first()?.as_str()).then(|| rest.to_vec())
}

/// Whether `shown` (with `…` lines standing for lines left out) is what `printed` says.
fn shows(shown: &str, printed: &str) -> bool {
    let printed: Vec<&str> = printed.trim_end().lines().map(str::trim_end).collect();
    let lines: Vec<&str> = shown.trim_end().lines().map(str::trim_end).collect();
    let chunks: Vec<&[&str]> = lines.split(|l| *l == "…").collect();
    let mut at = 0;
    for (i, chunk) in chunks.iter().enumerate() {
        let first = i == 0;
        let last = i + 1 == chunks.len();
        if chunk.is_empty() {
            continue;
        }
        let found = if first {
            printed.starts_with(chunk).then_some(0)
        } else if last {
            printed.ends_with(chunk).then(|| printed.len() - chunk.len()).filter(|&s| s >= at)
        } else {
            (at..=printed.len().saturating_sub(chunk.len()))
                .find(|&s| printed[s..].starts_with(chunk))
        };
        let Some(start) = found else { return false };
        at = start + chunk.len();
        if last && at != printed.len() {
            return false;
        }
    }
    true
}

/// The anchors GitHub gives a page's headings.
fn anchors(page: &str) -> Vec<String> {
    let (_, prose) = blocks(page);
    prose
        .lines()
        .filter(|l| l.starts_with('#'))
        .map(|l| {
            l.trim_start_matches('#')
                .trim()
                .to_lowercase()
                .chars()
                .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
                .map(|c| if c == ' ' { '-' } else { c })
                .collect()
        })
        .collect()
}

/// What is wrong with a page, one message each.
fn problems(name: &str) -> Vec<String> {
    let path = root().join(name);
    let page = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (blocks, prose) = blocks(&page);
    let mut problems = Vec::new();
    // What the last block that runs something printed, for a `text,output` block after it.
    let mut printed: Option<(usize, String)> = None;
    for block in &blocks {
        let at = format!("{name}:{}", block.line);
        match block.tag.as_str() {
            "lagrange" => match cli::derive("scene.lag", &block.text, cli::Format::Text) {
                Ok(report) => printed = Some((block.line, report)),
                Err(e) => problems.push(format!("{at}: the scene is refused:\n{e}")),
            },
            "lagrange,error" => match cli::derive(BAD_SCENE, &block.text, cli::Format::Text) {
                Ok(_) => problems.push(format!("{at}: the scene shown as a mistake derives")),
                Err(e) => printed = Some((block.line, e)),
            },
            "sh" => {
                for line in block.text.lines() {
                    if let Some(words) = command(line) {
                        match run(&words) {
                            Ok(out) => printed = Some((block.line, out)),
                            Err(e) => problems.push(format!("{at}: `{line}`: {e}")),
                        }
                    }
                }
            }
            "text,output" => match printed.take() {
                None => problems.push(format!("{at}: no command or scene before this output")),
                Some((from, out)) if !shows(&block.text, &out) => problems.push(format!(
                    "{at}: the block of line {from} prints something else now:\n{out}"
                )),
                Some(_) => {}
            },
            // C is compiled and run by tests/codegen_c.rs.
            "text" | "python" | "c" => {}
            "" => problems.push(format!("{at}: an untagged block (see docs/README.md)")),
            other => problems.push(format!("{at}: an unknown tag `{other}`")),
        }
    }
    // Paths under examples/, tests/ and crates/ named anywhere on the page.
    let whole = page.as_str();
    for prefix in ["examples/", "tests/", "crates/"] {
        for (i, _) in whole.match_indices(prefix) {
            let before = whole[..i].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || "./_-".contains(c)) {
                continue;
            }
            let end = whole[i..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || "./_-".contains(c)))
                .map_or(whole.len(), |e| i + e);
            let named = whole[i..end].trim_end_matches(['.', ',']);
            if !root().join(named).exists() {
                problems.push(format!("{name}: `{named}` does not exist"));
            }
        }
    }
    // Relative links and pictures, with the heading an anchor names.
    let dir = path.parent().expect("a folder");
    for (i, _) in prose.match_indices("](") {
        let rest = &prose[i + 2..];
        let target = &rest[..rest.find(')').unwrap_or(rest.len())];
        if target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
        let linked = if file.is_empty() { path.clone() } else { dir.join(file) };
        if !linked.exists() {
            problems.push(format!("{name}: the link `{target}` leads nowhere"));
        } else if !anchor.is_empty() {
            let text = std::fs::read_to_string(&linked).unwrap_or_default();
            if !anchors(&text).iter().any(|a| a == anchor) {
                problems.push(format!("{name}: `{target}` names no heading there"));
            }
        }
    }
    problems
}

fn assert_honest(name: &str) {
    let problems = problems(name);
    assert!(problems.is_empty(), "{} problems:\n\n{}", problems.len(), problems.join("\n\n"));
}

#[test]
fn every_page_is_tested() {
    let mut found: Vec<String> = std::fs::read_dir(root().join("docs"))
        .expect("docs/")
        .flatten()
        .map(|e| format!("docs/{}", e.file_name().to_string_lossy()))
        .filter(|n| n.ends_with(".md"))
        .collect();
    found.push("README.md".into());
    found.sort();
    let mut listed: Vec<String> = PAGES.iter().map(|p| p.to_string()).collect();
    listed.sort();
    assert_eq!(found, listed, "list every page in PAGES, and a test for it below");
    // Each page by name: tests that indexed PAGES had drifted to other pages' entries, and
    // two pages were never read.
    let this = include_str!("docs.rs");
    for page in PAGES {
        let call = format!("assert_honest(\"{page}\")");
        assert!(this.contains(&call), "no test calls {call}");
    }
}

#[test]
fn readme() {
    assert_honest("README.md");
}

#[test]
fn docs_index() {
    assert_honest("docs/README.md");
}

#[test]
fn language() {
    assert_honest("docs/language.md");
}

#[test]
fn commands() {
    assert_honest("docs/commands.md");
}

#[test]
fn ensembles() {
    assert_honest("docs/ensembles.md");
}

#[test]
fn contacts() {
    assert_honest("docs/contacts.md");
}

#[test]
fn friction() {
    assert_honest("docs/friction.md");
}

#[test]
fn simulating() {
    assert_honest("docs/simulating.md");
}

#[test]
fn linearizing() {
    assert_honest("docs/linearizing.md");
}

#[test]
fn bicycle() {
    assert_honest("docs/bicycle.md");
}

#[test]
fn python() {
    assert_honest("docs/python.md");
}

#[test]
fn benchmarks() {
    assert_honest("docs/benchmarks.md");
}

#[test]
fn examples() {
    assert_honest("docs/examples.md");
}

#[test]
fn testing() {
    assert_honest("docs/testing.md");
}

#[test]
fn control() {
    assert_honest("docs/control.md");
}

#[test]
fn fmu() {
    assert_honest("docs/fmu.md");
}

#[test]
fn orbits() {
    assert_honest("docs/orbits.md");
}

#[test]
fn fitting() {
    assert_honest("docs/fitting.md");
}

#[test]
fn c_page() {
    assert_honest("docs/c.md");
}

/// Which methods a list on a page names, in the table's order.
type Listed = fn(sim::Method) -> bool;

/// The lists of methods the pages (and the Python package's docstrings) write out, each
/// against `sim`'s method table: the file, the words the list follows, the words that end it,
/// and which methods it names.
const METHOD_LISTS: [(&str, &str, &str, Listed); 8] = [
    ("docs/commands.md", "[--method ", "]", |_| true),
    ("docs/commands.md", "the adaptive methods (", ")", sim::Method::is_adaptive),
    ("docs/commands.md", "the fixed-step ones (", ")", |m| !m.is_adaptive()),
    ("docs/simulating.md", "The methods: ", "The implicit methods", |_| true),
    (
        "docs/simulating.md",
        "with a multiplier are taken by ",
        ":",
        sim::Method::handles_multipliers,
    ),
    ("docs/simulating.md", "whichever adaptive method takes it: ", ".", sim::Method::is_adaptive),
    ("docs/ensembles.md", "with the explicit methods (", ")", sim::Method::is_explicit),
    ("crates/python/python/lagrange/__init__.py", "``method``: one of ", ";", |_| true),
];

/// The methods `text` names between the first `from` and the next `to` after it, each once,
/// where it is first named (an alias counts as its method); whitespace runs are one space.
fn methods_named(text: &str, from: &str, to: &str) -> Result<Vec<sim::Method>, String> {
    let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let start = text.find(from).ok_or(format!("no `{from}`"))? + from.len();
    let end = text[start..].find(to).ok_or(format!("no `{to}` after `{from}`"))? + start;
    let mut named = Vec::new();
    for word in text[start..end].split(|c: char| !c.is_ascii_alphanumeric()) {
        match sim::Method::from_name(word) {
            Some(m) if !named.contains(&m) => named.push(m),
            _ => {}
        }
    }
    Ok(named)
}

#[test]
fn the_lists_of_methods_are_the_tables() {
    for (file, from, to, listed) in METHOD_LISTS {
        let text = read(file).expect(file);
        let named = methods_named(&text, from, to).unwrap_or_else(|e| panic!("{file}: {e}"));
        let names =
            |methods: &[sim::Method]| -> Vec<&str> { methods.iter().map(|m| m.name()).collect() };
        let table: Vec<sim::Method> = sim::Method::all().filter(|m| listed(*m)).collect();
        assert_eq!(names(&named), names(&table), "{file}, the list after `{from}`");
    }
    // The check sees a list that lost a method.
    let short = methods_named("[--method rk4|rk45|dop853]", "[--method ", "]");
    assert_eq!(short, Ok(vec![sim::Method::Rk4, sim::Method::Dopri5, sim::Method::Dop853]));
}

/// The tests' own helpers: elided output, shell words, and that a wrong page is caught.
#[test]
fn the_checks_catch_what_they_should() {
    assert!(shows("a\nb\n", "a\nb\n"));
    assert!(shows("…\nc\n", "a\nb\nc\n"));
    assert!(shows("a\n…\nc\n", "a\nb\nc\n"));
    assert!(!shows("a\n…\nb\n", "a\nb\nc\n"));
    assert!(!shows("b\n", "a\nb\n"));
    assert_eq!(
        words("lagrange linearize f.lag --about 'theta=0' --set \"phi'=5\"   # why"),
        ["lagrange", "linearize", "f.lag", "--about", "theta=0", "--set", "phi'=5"]
    );
    assert!(command("cargo test --workspace").is_none());
    assert!(command("cargo run -- derive examples/ps5/falling_rod.lag").is_some());
    assert!(command("cargo run --release -- derive examples/ps5/falling_rod.lag").is_some());
    assert!(run(&words("simulate examples/ps5/falling_rod.lag --nonsense 1")).is_err());
    assert!(run(&words("derive examples/ps5/no_such_scene.lag")).is_err());
    assert!(run(&words("linearize examples/classics/simple_pendulum.lag --about theta=1")).is_err());
    assert_eq!(
        anchors("# See it move\n```sh\n# not a heading\n```\n## Work–precision\n"),
        ["see-it-move", "workprecision"]
    );
}
