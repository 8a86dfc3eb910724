//! `dronecine`: the command line. It only wires the crates together: the language front end
//! (`dronecine-grammar`), the compiler and the runtime. Each subcommand lives in its own
//! module.
//!
//! Everything printed goes through `out.rs`'s macros, never `println!` (which panics when
//! the output cannot be written).
#![warn(clippy::print_stdout, clippy::print_stderr)]

#[macro_use]
mod out;
mod realtime;

mod calibrate;
mod check;
mod compile;
mod emulate;
mod explain;
mod files;
mod fmt;
mod gains;
mod hardware;
mod live;
mod replay;
mod report;
mod shoot;
mod signals;
mod status;

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
    ///
    /// With --expand, print one script with each `coverage` line replaced by the shots the
    /// compiler flies for it, timed to its drone's repositioning flights, as PSL that
    /// compiles to the same flight; the file is not changed.
    Fmt {
        /// Scripts or directories of scripts.
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
        /// Change nothing; exit 1 if any file would be rewritten.
        #[arg(long, conflicts_with = "expand")]
        check: bool,
        /// Print the script (one FILE) with its coverages expanded, instead of rewriting it.
        #[arg(long)]
        expand: bool,
    },
    /// What a word of the shot language or a diagnostic code means, with an example.
    ///
    /// A word: a shot size (`MS`), a profile (`34left`), a camera move (`dolly`), a camera
    /// angle (`high angle`), a transition (`cut`) or any other keyword; a code:
    /// `psl::unknown_actor` (or `unknown_actor`). Without one, lists them all.
    Explain {
        /// The word or code (several words are one term: `high angle`).
        #[arg(value_name = "TERM")]
        term: Vec<String>,
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
        #[arg(
            long,
            value_name = "HZ",
            default_value_t = 100.0,
            allow_negative_numbers = true
        )]
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
    /// Measure the servo's model: fly small doublets and steps on each input around hover (on the
    /// embedded simulator by default, or a real drone with --drone/--mocap), and fit K and τ
    /// per axis (roll, pitch, vertical speed) by prediction error through a Kalman filter, and
    /// K_ψ by least squares.
    ///
    /// Prints each fitted value with its 95 % interval, the fit's R² and the previous
    /// profile's value; writes the profile only when every fit is good, else exits 1 naming
    /// the test to repeat.
    Calibrate(calibrate::CalibrateArgs),
    /// Fit the servo's model (as `calibrate`) from a flight log.
    Identify(calibrate::IdentifyArgs),
    /// Fly a script: on the embedded AR.Drone simulator (the default) or a real drone, with
    /// the LQG servo (or `--controller pid`).
    ///
    /// Checks and compiles the script first (a script the drone cannot fly is refused), then
    /// takes off, flies to the first framing, flies the shots with the director re-framing the
    /// live actors every tick, and lands. Logs the flight to MCAP and prints a report.
    Shoot {
        /// The script.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        /// The flight log to write, a new file (a recording is never overwritten), or a folder
        /// to write the time-stamped one in (by default `flights/<script>-<UTC time>.mcap`).
        #[arg(long, value_name = "FILE|DIR")]
        log: Option<PathBuf>,
        /// The simulator's seed (noise, wind, radio loss, the actors' deviations) [default: 1].
        #[arg(long, value_name = "N")]
        seed: Option<u64>,
        /// The controller: the paper's LQG servo, or per-axis PID loops (tum_ardrone gains).
        #[arg(long, value_enum, default_value_t = ControllerKind::Lqg)]
        controller: ControllerKind,
        /// Fly the paper's pre-filter exactly, without the acceleration feed-forward.
        #[arg(long)]
        paper_prefilter: bool,
        /// Solve the full DARE at every tick instead of rotating the body-frame gains.
        #[arg(long)]
        per_tick_solve: bool,
        /// Keep to the wall clock (by default a simulated flight runs as fast as it can).
        #[arg(long)]
        realtime: bool,
        /// Force the log to the disk as it is written (fsync), as for a real or --realtime
        /// flight. A simulated flight's log is otherwise left for the OS to write back: the
        /// flight is reproducible from its script and seed.
        #[arg(long)]
        sync_log: bool,
        /// Control rate, Hz, from 10 to 1000 (the simulator's mocap sends 100 frames a second:
        /// a faster loop predicts between them).
        #[arg(
            long,
            value_name = "HZ",
            default_value_t = 100.0,
            allow_negative_numbers = true
        )]
        rate: f64,
        /// How to print the report.
        #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
        report: ReportFormat,
        #[command(flatten)]
        effects: SimEffects,
        /// Fly a real drone. An AR.Drone 2.0 (or `dronecine emulate ardrone`):
        /// `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]`; an ArduPilot Copter:
        /// `mavlink://udp:HOST:PORT`, `mavlink://tcp:HOST:PORT` or
        /// `mavlink:///dev/PORT?baud=N`; a Crazyflie: `crazyflie+radio://N/CHANNEL/RATE/ADDRESS`
        /// (a Crazyradio) or `crazyflie+udp://HOST:PORT` (or `dronecine emulate crazyflie`).
        /// Needs --mocap.
        #[arg(long, value_name = "URL")]
        drone: Option<String>,
        /// Its positions from OptiTrack NatNet:
        /// `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`; or `sitl`: the
        /// truth of ArduPilot's simulator (SIM_STATE), the actors walking their blocking.
        #[arg(long, value_name = "URL")]
        mocap: Option<String>,
        /// Rigid-body ids of the drone and the actors (TOML) [default: drone 1, actors 2, 3, …].
        #[arg(long, value_name = "FILE")]
        rig: Option<PathBuf>,
        /// With an ArduPilot drone or a Crazyflie: do not send it the motion capture
        /// (VISION_POSITION_ESTIMATE; the external pose); its estimator then navigates on its
        /// own sensors.
        #[arg(long)]
        no_forward_mocap: bool,
        /// With a real drone: do not ask for real-time scheduling (SCHED_FIFO) and locked
        /// memory, which a flight on a real drone asks for when the user may have them.
        #[arg(long)]
        normal_priority: bool,
        /// No progress display; of the events, only the errors (a failsafe's reason, why a
        /// flight ended early).
        #[arg(short, long)]
        quiet: bool,
        /// Serve the flight as it happens to Foxglove (its WebSocket protocol), on ADDR:PORT
        /// [default: 127.0.0.1:8765]: the flight log's topics, live. Give it after FILE.
        #[arg(long, value_name = "ADDR:PORT", num_args = 0..=1, default_missing_value = LIVE_ADDR)]
        live: Option<std::net::SocketAddr>,
    },
    /// Re-run the controller of a flight log on its logged inputs, check that it gives the
    /// logged commands bit for bit, and print the report again.
    Replay {
        /// The flight log (`dronecine shoot --log`).
        #[arg(value_name = "LOG.mcap")]
        file: PathBuf,
        /// How to print the report.
        #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
        report: ReportFormat,
        /// Then play the logged flight to Foxglove (its WebSocket protocol) on ADDR:PORT
        /// [default: 127.0.0.1:8765], paced as it was flown, once a client subscribes.
        #[arg(long, value_name = "ADDR:PORT", num_args = 0..=1, default_missing_value = LIVE_ADDR)]
        live: Option<std::net::SocketAddr>,
        /// With --live: times real time (0.01 to 1000).
        #[arg(
            long,
            value_name = "X",
            default_value_t = 1.0,
            requires = "live",
            allow_negative_numbers = true
        )]
        speed: f64,
    },
    /// Connect to a drone and print its state: what to check before a flight.
    ///
    /// Starts the drone's navdata and prints the control state, battery, angles, altitude,
    /// velocities and the set state flags, once or continuously. Only reads: writes no
    /// limits and sends no take-off or landing command.
    Status {
        /// The drone: `ardrone://HOST[:AT_PORT[:NAVDATA_PORT]]` (its Wi-Fi: ardrone://192.168.1.1),
        /// or an ArduPilot Copter: `mavlink://udp:HOST:PORT`, `mavlink://tcp:HOST:PORT`,
        /// `mavlink:///dev/PORT?baud=N` (mode, arming, battery, EKF and motion-capture
        /// navigation, pre-arm checks, the parameters that matter, limits, gimbal), or a
        /// Crazyflie: `crazyflie+radio://N/CHANNEL/RATE/ADDRESS`, `crazyflie+udp://HOST:PORT`
        /// (protocol version, battery, supervisor, estimate, attitude).
        #[arg(long, value_name = "URL")]
        drone: String,
        /// Keep printing (every --interval) until interrupted.
        #[arg(long)]
        watch: bool,
        /// One JSON object per line (keys ctrl_state, battery_percent, theta_deg, phi_deg,
        /// psi_deg, altitude_m, velocity_mps, flags, navdata_rejected, implausible, problems, …).
        #[arg(long)]
        json: bool,
        /// Seconds to wait for the drone's first valid navdata packet before giving up.
        #[arg(
            long,
            value_name = "SECONDS",
            default_value_t = 3.0,
            allow_negative_numbers = true
        )]
        timeout: f64,
        /// Seconds between two prints with --watch.
        #[arg(
            long,
            value_name = "SECONDS",
            default_value_t = 0.5,
            allow_negative_numbers = true
        )]
        interval: f64,
    },
    /// Emulate a drone and its motion capture over the network, on the embedded simulator.
    Emulate {
        #[command(subcommand)]
        kind: EmulateKind,
    },
    /// Print a shell completion script.
    Completions {
        /// The shell to complete for.
        shell: clap_complete::Shell,
    },
}

/// Where `--live` serves unless told: Foxglove's default, on this machine only.
const LIVE_ADDR: &str = "127.0.0.1:8765";

#[derive(Subcommand, Debug)]
enum EmulateKind {
    /// An AR.Drone 2.0 (AT commands in, navdata out) and OptiTrack Motive (NatNet frames of
    /// the drone and the actors), the simulator running in real time until Ctrl-C.
    ///
    /// Navdata goes to the sender of the trigger packet, from the navdata port. NatNet rigid
    /// bodies: 1 = the drone, 2, 3, … = the script's actors in order.
    Ardrone {
        /// Address to listen on.
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
        host: std::net::IpAddr,
        /// AT command port (UDP).
        #[arg(long, value_name = "P", default_value_t = 5556)]
        at_port: u16,
        /// Navdata port (UDP).
        #[arg(long, value_name = "P", default_value_t = 5554)]
        navdata_port: u16,
        #[command(flatten)]
        world: EmulatedWorld,
    },
    /// A Crazyflie (CRTP over UDP, one packet per datagram, as cflib's UDP driver speaks it)
    /// and OptiTrack Motive (NatNet frames of the drone and the actors), the simulator
    /// running in real time until Ctrl-C; fly it with `--drone crazyflie+udp://HOST:PORT`.
    ///
    /// The answers and log samples go to the sender of the last packet. NatNet rigid
    /// bodies: 1 = the drone, 2, 3, … = the script's actors in order. The script's drone line
    /// gives the profile the simulator flies (`drone crazyflie21`).
    Crazyflie {
        /// Address to listen on.
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
        host: std::net::IpAddr,
        /// CRTP port (UDP).
        #[arg(long, value_name = "P", default_value_t = 19850)]
        port: u16,
        /// The CRTP protocol version to announce (4 to 12; from 9 the altHold yaw rate is
        /// counter-clockwise positive).
        #[arg(long, value_name = "N", default_value_t = 12, value_parser = clap::value_parser!(u8).range(4..=12))]
        protocol: u8,
        #[command(flatten)]
        world: EmulatedWorld,
    },
}

/// What an emulator streams and simulates besides its drone's own protocol.
#[derive(Clone, Debug, clap::Args)]
struct EmulatedWorld {
    /// Where NatNet frames go: a unicast address, or a multicast group.
    #[arg(long, value_name = "ADDR:PORT", default_value = "239.255.42.99:1511")]
    natnet: std::net::SocketAddr,
    /// NatNet command port (UDP), answering the connect request with the server info.
    #[arg(long, value_name = "P", default_value_t = 1510)]
    natnet_command_port: u16,
    /// NatNet version to announce and stream (3.0 to 4.1).
    #[arg(long, value_name = "X.Y", default_value = "4.1")]
    natnet_version: String,
    /// Stream Z-up (Motive's default is Y-up).
    #[arg(long)]
    z_up: bool,
    /// No NatNet at all.
    #[arg(long, conflicts_with_all = ["natnet", "natnet_command_port", "natnet_version", "z_up"])]
    no_natnet: bool,
    /// The simulator's seed (noise, wind, radio loss, the actors' deviations).
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// A script whose scene gives the actors (and the drone profile); none without it.
    #[arg(long, value_name = "FILE.psl")]
    script: Option<PathBuf>,
    #[command(flatten)]
    effects: SimEffects,
    /// Serve the simulator's world (the drone and the actors where they truly are) to
    /// Foxglove (its WebSocket protocol) on ADDR:PORT [default: 127.0.0.1:8765].
    #[arg(long, value_name = "ADDR:PORT", num_args = 0..=1, default_missing_value = LIVE_ADDR)]
    live: Option<std::net::SocketAddr>,
}

/// Which simulator effects a simulated flight has (`shoot`, `emulate`).
#[derive(Clone, Debug, clap::Args)]
struct SimEffects {
    /// Simulate the servo's own model only: no lag, drag, latency, noise, wind or loss.
    #[arg(long)]
    ideal: bool,
    /// Switch simulator effects off (comma-separated): attitude-lag, tilt-saturation, drag,
    /// asymmetric-vz, yaw-lag, latency, radio-loss, mocap-noise, mocap-dropouts, wind,
    /// actor-deviation, battery.
    #[arg(
        long,
        value_name = "EFFECT,…",
        value_delimiter = ',',
        conflicts_with = "ideal"
    )]
    sim_off: Vec<String>,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
enum Format {
    Human,
    Json,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
enum ControllerKind {
    Lqg,
    Pid,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
enum ReportFormat {
    Text,
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
    let code = run(Cli::parse());
    // Output that did not reach stdout (not a closed pipe: a full disk behind `>`) is not a
    // success, whatever the command did. What is still buffered is written first.
    out::stdout_result(std::io::Write::flush(&mut std::io::stdout()));
    match out::stdout_failure() {
        Some(e) => {
            errln!("error: cannot write the output: {e}");
            ExitCode::FAILURE
        }
        None => code,
    }
}

fn run(cli: Cli) -> ExitCode {
    let color = cli.color.enabled();
    match cli.command {
        Command::Check { files, format } => check::run(&files, format == Format::Json, color),
        Command::Fmt {
            files,
            check,
            expand: true,
        } if !check => fmt::expand(&files, color),
        Command::Fmt { files, check, .. } => fmt::run(&files, check, color),
        Command::Explain { term } => explain::run(&term),
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
        Command::Calibrate(args) => calibrate::run_calibrate(&args, color),
        Command::Identify(args) => calibrate::run_identify(&args, color),
        Command::Shoot {
            file,
            log,
            seed,
            controller,
            paper_prefilter,
            per_tick_solve,
            realtime,
            sync_log,
            rate,
            report,
            effects,
            quiet,
            drone,
            mocap,
            rig,
            no_forward_mocap,
            normal_priority,
            live,
        } => shoot::run(&shoot::Args {
            file: &file,
            log: log.as_deref(),
            seed,
            controller: match controller {
                ControllerKind::Lqg => "lqg",
                ControllerKind::Pid => "pid",
            },
            paper_prefilter,
            per_tick_solve,
            realtime,
            sync_log,
            rate_hz: rate,
            json: report == ReportFormat::Json,
            quiet,
            ideal: effects.ideal,
            sim_off: &effects.sim_off,
            drone: drone.as_deref(),
            mocap: mocap.as_deref(),
            no_forward_mocap,
            normal_priority,
            rig: rig.as_deref(),
            color,
            live,
        }),
        Command::Emulate { kind } => {
            let (drone, host, w) = match kind {
                EmulateKind::Ardrone {
                    host,
                    at_port,
                    navdata_port,
                    world,
                } => (
                    emulate::Emulated::ArDrone {
                        at_port,
                        navdata_port,
                    },
                    host,
                    world,
                ),
                EmulateKind::Crazyflie {
                    host,
                    port,
                    protocol,
                    world,
                } => (emulate::Emulated::Crazyflie { port, protocol }, host, world),
            };
            emulate::run(&emulate::Args {
                drone,
                host,
                natnet: w.natnet,
                natnet_command_port: w.natnet_command_port,
                natnet_version: &w.natnet_version,
                z_up: w.z_up,
                no_natnet: w.no_natnet,
                seed: w.seed,
                script: w.script.as_deref(),
                ideal: w.effects.ideal,
                sim_off: &w.effects.sim_off,
                color,
                live: w.live,
            })
        }
        Command::Replay {
            file,
            report,
            live,
            speed,
        } => replay::run(
            &file,
            report == ReportFormat::Json,
            live.map(|a| (a, speed)),
        ),
        Command::Status {
            drone,
            watch,
            json,
            timeout,
            interval,
        } => status::run(&status::Args {
            drone: &drone,
            watch,
            json,
            timeout_s: timeout,
            interval_s: interval,
        }),
        Command::Completions { shell } => {
            // Into memory first: clap_complete panics when its writer fails.
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "dronecine", &mut script);
            out!("{}", String::from_utf8_lossy(&script));
            ExitCode::SUCCESS
        }
    }
}
