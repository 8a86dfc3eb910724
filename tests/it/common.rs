//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

use dronecine_grammar::{Checked, Options};

/// Check a script file the way `dronecine check` does: built-in profile names from the
/// compiler, relative files resolved against the script's folder.
pub fn check_path(path: &Path) -> (String, Checked) {
    let src = std::fs::read_to_string(path).expect("test script is UTF-8");
    // Relative to the workspace (the tests' working folder), so that messages naming files
    // read the same on every machine.
    let rel = path.strip_prefix(workspace()).unwrap_or(path);
    let base = rel.parent().expect("script has a folder").to_path_buf();
    let opts = Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: Some(&base),
    };
    let checked = dronecine_grammar::check(&src, &opts);
    (src, checked)
}

/// A serialised value with every `span` field removed, to compare scripts whose text moved.
pub fn without_spans(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Object(m) => Value::Object(
            m.into_iter()
                .filter(|(k, _)| k != "span")
                .map(|(k, v)| (k, without_spans(v)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.into_iter().map(without_spans).collect()),
        v => v,
    }
}

pub fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The `.psl` files of a folder of the workspace, sorted.
pub fn scripts(dir: &str) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(workspace().join(dir))
        .expect("folder exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "psl"))
        .collect();
    v.sort();
    v
}

/// Runs the `dronecine` binary in the workspace, without colour.
pub fn dronecine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(args)
        .current_dir(workspace())
        .env("NO_COLOR", "1")
        .output()
        .expect("runs")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// An empty scratch folder for one test, `dronecine-test-NAME-…` in the system's temporary
/// folder (a fresh name each time, so tests and test binaries never share one). Removed with
/// everything in it when dropped, unless the test is failing: then it is kept and its path
/// printed, to look at the logs and files the test wrote.
pub struct Scratch(Option<tempfile::TempDir>);

impl Scratch {
    pub fn path(&self) -> &Path {
        self.0.as_ref().expect("held until dropped").path()
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.path()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            if let Some(dir) = self.0.take() {
                eprintln!(
                    "the failing test's files are kept in {}",
                    dir.keep().display()
                );
            }
        }
    }
}

/// A new [`Scratch`] folder for the test `name`.
pub fn temp_dir(name: &str) -> Scratch {
    let dir = tempfile::Builder::new()
        .prefix(&format!("dronecine-test-{name}-"))
        .tempdir()
        .expect("a scratch folder in the temporary folder");
    Scratch(Some(dir))
}

/// A UDP port free on loopback now (for a child process to bind).
pub fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// `dronecine emulate ardrone` (or `crazyflie`) on free loopback ports, NatNet unicast to
/// this machine; killed when dropped.
pub struct Emulator {
    child: std::process::Child,
    /// `--drone` for it.
    pub drone_url: String,
    /// `--mocap` for it.
    pub mocap_url: String,
}

impl Emulator {
    /// `dronecine emulate ardrone` with `args` added (`--ideal`, `--seed N`, `--script FILE`).
    pub fn start(args: &[&str]) -> Emulator {
        Emulator::start_as("ardrone", args)
    }

    /// `dronecine emulate KIND` (`ardrone`, `crazyflie`) with `args` added, waited for until
    /// it listens. The ports are free when picked, not held: a test running beside this one
    /// can take one before the emulator binds it, and the emulator then exits; such a start
    /// is tried again on new ports, three times at most (then what it said is the panic).
    pub fn start_as(kind: &str, args: &[&str]) -> Emulator {
        let mut said = String::new();
        for _ in 0..3 {
            let (first, second, cmd, data) = (free_port(), free_port(), free_port(), free_port());
            let (ports, drone_url): (Vec<String>, String) = match kind {
                "crazyflie" => (
                    vec!["--port".into(), first.to_string()],
                    format!("crazyflie+udp://127.0.0.1:{first}"),
                ),
                _ => (
                    vec![
                        "--at-port".into(),
                        first.to_string(),
                        "--navdata-port".into(),
                        second.to_string(),
                    ],
                    format!("ardrone://127.0.0.1:{first}:{second}"),
                ),
            };
            // What it says goes to a file (a pipe nobody reads would block its writes).
            let mut told = tempfile::tempfile().expect("a temporary file");
            let mut child = Command::new(env!("CARGO_BIN_EXE_dronecine"))
                .args(["emulate", kind])
                .args(&ports)
                .args(["--natnet", &format!("127.0.0.1:{data}")])
                .args(["--natnet-command-port", &cmd.to_string()])
                .args(args)
                .stdout(std::process::Stdio::null())
                .stderr(told.try_clone().expect("the temporary file, again"))
                .spawn()
                .expect("the emulator starts");
            // Until it listens (a connect that fails too early would fail the test for
            // nothing), or exits.
            let started = std::time::Instant::now();
            while std::net::UdpSocket::bind(("127.0.0.1", first)).is_ok()
                && started.elapsed() < std::time::Duration::from_secs(5)
            {
                if child.try_wait().ok().flatten().is_some() {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(50));
            }
            if child.try_wait().ok().flatten().is_some() {
                use std::io::{Read, Seek};
                said.clear();
                let _ = told.rewind();
                let _ = told.read_to_string(&mut said);
                continue;
            }
            return Emulator {
                child,
                drone_url,
                mocap_url: format!("natnet://127.0.0.1:{cmd}?unicast&data_port={data}"),
            };
        }
        panic!("the emulator did not start: {said}");
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The chunks of the MCAP file at `path`: each one's file offset and length, from the
/// summary's chunk indexes (read by the `mcap` crate).
pub fn chunks(path: &Path) -> Vec<(u64, u64)> {
    let bytes = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    summary
        .chunk_indexes
        .iter()
        .map(|c| (c.chunk_start_offset, c.chunk_length))
        .collect()
}

/// Writes to `damaged` a copy of the MCAP file `log` with one bit flipped in the middle of its
/// middle chunk (whose CRC then fails); returns that chunk's offset, where a reader meets the
/// damage.
pub fn damage_middle_chunk(log: &Path, damaged: &Path) -> u64 {
    let chunks = chunks(log);
    let (start, len) = chunks[chunks.len() / 2];
    let mut bytes = std::fs::read(log).unwrap();
    bytes[(start + len / 2) as usize] ^= 0x04;
    std::fs::write(damaged, &bytes).unwrap();
    start
}
