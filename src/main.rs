//! `dronecine`: the command line. It only wires the crates together: the language front end
//! (`dronecine-grammar`), the compiler and the runtime. Each subcommand lives in its own
//! module.

mod check;
mod compile;
mod files;
mod fmt;
mod gains;

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand, ValueEnum};

/// Write a film shot in words; have a drone fly it.
#[derive(Parser, Debug)]
#[command(name = "dronecine", version, about, long_about = None, propagate_version = true)]
struct Cli {
    /// When to colour diagnostics.
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, global = true)]
    color: ColorChoice,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Check `.psl` scripts: parse, resolve, and report every mistake.
    ///
    /// Prints one summary line per valid file (actors, shots, total duration) and exits 0;
    /// on any error prints the diagnostics and exits 1. Directories are searched for `.psl`
    /// files.
    Check {
        /// Scripts or directories of scripts.
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
        /// Output format: human-readable text or JSON records.
        #[arg(long, value_enum, default_value_t = Format::Human)]
        format: Format,
    },
    /// Rewrite scripts in canonical form (idempotent; comments are kept).
    Fmt {
        /// Scripts or directories of scripts.
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
        /// Change nothing; exit 1 if any file would be rewritten.
        #[arg(long)]
        check: bool,
    },
    /// Compile a script into the timed 6D reference a drone flies (MCAP, CSV, previews).
    ///
    /// Each framing becomes a camera position around the actors, transitions interpolate the
    /// visual parameters, cuts get the repositioning flights they need, and every sample is
    /// checked against the drone profile, the stage and the actors' safety distance.
    Compile {
        /// The script.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        /// The MCAP file to write (opens in Foxglove).
        #[arg(short, long, value_name = "OUT.mcap")]
        output: PathBuf,
        /// Sample rate of the reference, Hz.
        #[arg(long, value_name = "HZ", default_value_t = 100.0)]
        rate: f64,
        /// Write previews (top and side views, plots, storyboard; SVG and PNG) to this folder.
        #[arg(long, value_name = "DIR")]
        preview: Option<PathBuf>,
        /// Also write the reference as CSV.
        #[arg(long, value_name = "FILE")]
        csv: Option<PathBuf>,
        /// Write the outputs even when the drone cannot fly the script (errors become warnings).
        #[arg(long)]
        allow_infeasible: bool,
    },
    /// Print the LQG servo's gains for a drone profile (P, K1, N1, poles, Kalman gain, k2).
    Gains(gains::Args),
    /// Print a shell completion script.
    Completions {
        /// The shell to complete for.
        shell: clap_complete::Shell,
    },
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
enum Format {
    Human,
    Json,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
enum ColorChoice {
    Auto,
    Always,
    Never,
}

impl ColorChoice {
    fn enabled(self) -> bool {
        match self {
            ColorChoice::Always => true,
            ColorChoice::Never => false,
            ColorChoice::Auto => {
                std::env::var_os("NO_COLOR").is_none() && std::io::stderr().is_terminal()
            }
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let color = cli.color.enabled();
    match cli.command {
        Command::Check { files, format } => check::run(&files, format == Format::Json, color),
        Command::Fmt { files, check } => fmt::run(&files, check, color),
        Command::Compile {
            file,
            output,
            rate,
            preview,
            csv,
            allow_infeasible,
        } => compile::run(&compile::Args {
            file: &file,
            out: &output,
            rate_hz: rate,
            preview: preview.as_deref(),
            csv: csv.as_deref(),
            allow_infeasible,
            color,
        }),
        Command::Gains(args) => gains::run(&args, color),
        Command::Completions { shell } => {
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "dronecine",
                &mut std::io::stdout(),
            );
            ExitCode::SUCCESS
        }
    }
}
