//! The backends' test peers: a Python program on an implementation no one here wrote
//! (pymavlink, cflib), driven over its standard input and output, JSON lines.
//!
//! The Python is `DRONECINE_PYTHON` (default `python3`). Without the package a test needs,
//! the test says so and passes, except under CI (`CI` set), where it fails.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use serde_json::Value;

/// The Python that imports `module`, or `None` (after saying why) when the test is to be
/// skipped; under CI a panic instead.
pub fn python(test: &str, module: &str) -> Option<String> {
    let python = std::env::var("DRONECINE_PYTHON").unwrap_or_else(|_| "python3".into());
    let probe = Command::new(&python)
        .args(["-c", &format!("import {module}")])
        .output();
    let why = match probe {
        Ok(o) if o.status.success() => return Some(python),
        Ok(o) => format!(
            "`{python} -c 'import {module}'` failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ),
        Err(e) => format!("cannot run `{python}`: {e}"),
    };
    if std::env::var_os("CI").is_some() {
        panic!(
            "{test}: {module} is needed under CI: {why} (set DRONECINE_PYTHON to a Python \
             with {module})"
        );
    }
    eprintln!("{test}: skipped: {why} (set DRONECINE_PYTHON to a Python with {module} to run it)");
    None
}

/// A Python script, running, with its output lines as JSON.
pub struct Peer {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<Value>,
    /// Every line read so far.
    pub seen: Vec<Value>,
}

impl Peer {
    /// Starts the script at `path` with `args`.
    pub fn start(python: &str, path: &Path, args: &[&str]) -> Peer {
        let mut child = Command::new(python)
            .arg(path)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", path.display()));
        let stdout = child.stdout.take().expect("a piped stdout");
        let (tx, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                let value = serde_json::from_str(&line)
                    .unwrap_or_else(|e| panic!("the peer printed `{line}`, not JSON: {e}"));
                if tx.send(value).is_err() {
                    break;
                }
            }
        });
        let stdin = child.stdin.take();
        Peer {
            child,
            stdin,
            lines,
            seen: Vec::new(),
        }
    }

    /// Reads lines until one satisfies `want` (returned), failing after `timeout`.
    pub fn until(&mut self, timeout: Duration, mut want: impl FnMut(&Value) -> bool) -> Value {
        let deadline = Instant::now() + timeout;
        if let Some(v) = self.seen.iter().find(|v| want(v)) {
            return v.clone();
        }
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(v) => {
                    self.seen.push(v.clone());
                    if want(&v) {
                        return v;
                    }
                }
                Err(RecvTimeoutError::Timeout) => panic!(
                    "the peer printed nothing wanted within {timeout:?}; the last lines: {:?}",
                    &self.seen[self.seen.len().saturating_sub(5)..]
                ),
                Err(RecvTimeoutError::Disconnected) => {
                    panic!("the peer ended; its lines: {:?}", self.seen)
                }
            }
        }
    }

    /// Reads the lines printed so far without waiting.
    pub fn drain(&mut self) {
        while let Ok(v) = self.lines.try_recv() {
            self.seen.push(v);
        }
    }

    /// Writes one line to the peer's standard input.
    pub fn tell(&mut self, line: &str) {
        let stdin = self.stdin.as_mut().expect("the peer's stdin is open");
        writeln!(stdin, "{line}").expect("the peer reads its stdin");
        stdin.flush().expect("the peer reads its stdin");
    }

    /// The UDP port the peer listens on (its first line).
    pub fn port(&mut self) -> u16 {
        let v = self.until(Duration::from_secs(20), |v| v.get("port").is_some());
        v["port"].as_u64().expect("a port number") as u16
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        // Closing its stdin ends the peer; kill it if it does not end by itself.
        drop(self.stdin.take());
        let deadline = Instant::now() + Duration::from_secs(3);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A JSON number as f64 ("NaN" for a float that is not a number).
pub fn num(v: &Value) -> f64 {
    match v {
        Value::String(s) if s == "NaN" => f64::NAN,
        _ => v
            .as_f64()
            .unwrap_or_else(|| panic!("`{v}` is not a number")),
    }
}

/// `a` equals `b` to f32 precision (both NaN counts as equal).
pub fn close(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-6 * (1.0 + a.abs().max(b.abs()))
}

/// Runs the script at `path` once, `input` on its standard input: its standard output, one
/// JSON value.
pub fn run_json(python: &str, path: &Path, input: &str) -> Value {
    let mut child = Command::new(python)
        .arg(path)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {}: {e}", path.display()));
    let mut stdin = child.stdin.take().expect("a piped stdin");
    stdin
        .write_all(input.as_bytes())
        .expect("the script reads its stdin");
    drop(stdin);
    let out = child.wait_with_output().expect("the script ends");
    assert!(
        out.status.success(),
        "{} failed: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{} printed `{}`, not JSON: {e}",
            path.display(),
            String::from_utf8_lossy(&out.stdout)
        )
    })
}
