//! `lagrange`: derive equations of motion from a scene file, and check them against
//! hand-derived results.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

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
        #[arg(value_parser = clap::builder::PossibleValuesParser::new(cli::generate::Family::NAMES))]
        family: String,
        /// The number of links.
        #[arg(value_parser = clap::value_parser!(u16).range(1..=500))]
        n: u16,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum FormatArg {
    Text,
    Latex,
    Json,
}

fn read(path: &PathBuf) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("error: cannot read {}: {e}", path.display()))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Derive { file, format, out, no_units } => {
            let source = match read(&file) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("{e}");
                    return ExitCode::from(2);
                }
            };
            let path = file.display().to_string();
            let format = match format {
                FormatArg::Text => cli::Format::Text,
                FormatArg::Latex => cli::Format::Latex,
                FormatArg::Json => cli::Format::Json,
            };
            match cli::derive_report(&path, &source, format, cli::Options { units: !no_units }) {
                Ok((report, warnings)) => {
                    eprint!("{warnings}");
                    match out {
                        Some(out) => match cli::write_atomically(&out, &report) {
                            Ok(()) => ExitCode::SUCCESS,
                            Err(e) => {
                                eprintln!("error: cannot write {}: {e}", out.display());
                                ExitCode::from(2)
                            }
                        },
                        None => {
                            print!("{report}");
                            ExitCode::SUCCESS
                        }
                    }
                }
                Err(diagnostics) => {
                    eprint!("{diagnostics}");
                    ExitCode::from(2)
                }
            }
        }
        Command::Generate { family, n } => {
            let family = cli::generate::Family::from_name(&family).expect("clap checked the name");
            print!("{}", cli::generate::n_link(family, n as usize));
            ExitCode::SUCCESS
        }
        Command::Check { files, no_units } => {
            let mut worst = 0;
            let (mut held, mut failed) = (0, 0);
            for file in &files {
                let source = match read(file) {
                    Ok(s) => s,
                    Err(e) => {
                        eprintln!("{e}");
                        worst = 2;
                        continue;
                    }
                };
                let result = cli::check::check_file_with(
                    &file.display().to_string(),
                    &source,
                    cli::Options { units: !no_units },
                );
                eprint!("{}", result.warnings);
                if result.exit_code == 2 {
                    eprint!("{}", result.report);
                } else {
                    print!("{}", result.report);
                }
                held += result.held;
                failed += result.failed;
                worst = worst.max(result.exit_code);
            }
            println!("{held} passed, {failed} failed");
            ExitCode::from(worst as u8)
        }
    }
}
