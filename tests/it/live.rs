//! The live view against a client no one here wrote: Foxglove's WebSocket protocol client
//! (`@foxglove/ws-protocol`, on Node) subscribes to every channel `shoot --live` advertises
//! during a `--realtime` flight, and Foxglove's ROS 2 reader decodes every CDR message
//! against the schema text advertised with it (`tests/live/client.cjs`). What it received is
//! the flight log's: the same topics under the same schemas, and message for message the
//! same bytes. `replay --live` plays a log to the same client: every message of the log.
//!
//! Node is `DRONECINE_NODE` (default `node`); the npm packages are in `DRONECINE_NODE_MODULES`
//! (default `target/ci-node/node_modules`, where `.ci/run` installs them). Without them the
//! tests say so and pass, except under CI (`CI` set), where they fail.

use std::collections::{BTreeMap, BTreeSet};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::common::workspace;

/// A short shot: the flight is mostly its take-off and landing (about 19 s in real time).
const SCRIPT: &str = "stage 8m x 6m x 3m\ndrone ardrone2\n\
                      actor A height 1.75m at (0, 0) facing 0deg\n\n\
                      MS on A front for 2s\n";

/// Node and the folder of its packages, or `None` (after saying why) to skip.
fn node(test: &str) -> Option<(String, PathBuf)> {
    let node = std::env::var("DRONECINE_NODE").unwrap_or_else(|_| "node".into());
    let modules = std::env::var_os("DRONECINE_NODE_MODULES")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target/ci-node/node_modules"));
    let probe = Command::new(&node)
        .env("NODE_PATH", &modules)
        .args([
            "-e",
            "for (const m of ['@foxglove/ws-protocol', '@foxglove/rosmsg', \
                      '@foxglove/rosmsg2-serialization', 'ws']) require(m)",
        ])
        .output();
    let why = match probe {
        Ok(o) if o.status.success() => return Some((node, modules)),
        Ok(o) => format!(
            "the npm packages are not in {}: {}",
            modules.display(),
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .next()
                .unwrap_or("")
        ),
        Err(e) => format!("cannot run `{node}`: {e}"),
    };
    if std::env::var_os("CI").is_some() {
        panic!("{test}: Node and the Foxglove npm packages are needed under CI: {why}");
    }
    eprintln!(
        "{test}: skipped: {why} (`npm install --prefix target/ci-node @foxglove/ws-protocol \
         @foxglove/rosmsg @foxglove/rosmsg2-serialization ws`, as .ci/run does)"
    );
    None
}

/// A folder with the short script; the script's and the log's paths (the log not written
/// yet), and where the client writes.
fn files() -> (tempfile::TempDir, String, String, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("short.psl");
    std::fs::write(&script, SCRIPT).unwrap();
    let log = dir.path().join("short.mcap").display().to_string();
    let out = dir.path().join("client.json");
    (dir, script.display().to_string(), log, out)
}

/// The script flown on the simulator as fast as it goes, logged at `log`.
fn shoot_fast(script: &str, log: &str) {
    let shot = crate::common::dronecine(&["shoot", script, "--quiet", "--log", log]);
    let said = String::from_utf8_lossy(&shot.stderr);
    assert!(shot.status.success(), "{said}");
}

/// `dronecine ARGS…` with its stderr read line by line on a thread: the `ws://` address it
/// serves as soon as it says it, then every line once it exits.
fn spawn_serving(args: &[&str]) -> (Child, String, mpsc::Receiver<Vec<String>>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dronecine"))
        .args(args)
        .current_dir(workspace())
        .env("NO_COLOR", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("dronecine runs");
    let stderr = child.stderr.take().expect("piped");
    let (url_tx, url_rx) = mpsc::channel();
    let (lines_tx, lines_rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut lines = Vec::new();
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Some(url) = line.split_whitespace().find(|w| w.starts_with("ws://")) {
                let _ = url_tx.send(url.to_string());
            }
            lines.push(line);
        }
        let _ = lines_tx.send(lines);
    });
    let url = match url_rx.recv_timeout(Duration::from_secs(120)) {
        Ok(url) => url,
        Err(_) => {
            let _ = child.kill();
            let said = lines_rx.recv().unwrap_or_default().join("\n");
            panic!("dronecine {args:?} never said where it serves:\n{said}");
        }
    };
    (child, url, lines_rx)
}

/// The client on `url`, writing what it received to `out` once the server closes the
/// connection, or after `timeout_s`.
fn client(node: &(String, PathBuf), url: &str, out: &Path, timeout_s: &str) -> Child {
    Command::new(&node.0)
        .env("NODE_PATH", &node.1)
        .arg(workspace().join("tests/live/client.cjs"))
        .args([url, &out.display().to_string(), timeout_s])
        .spawn()
        .expect("node runs")
}

/// A log's channels (topic → message encoding, schema name, schema encoding, schema text)
/// and its messages per topic (log time, SHA-256), in file order.
type Channels = BTreeMap<String, [String; 4]>;
type Messages = BTreeMap<String, Vec<(u64, String)>>;

fn read_log(path: &Path) -> (Channels, Messages) {
    let bytes = std::fs::read(path).unwrap();
    let (mut channels, mut messages) = (Channels::new(), Messages::new());
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let c = &m.channel;
        let s = c.schema.as_ref().expect("every topic has a schema");
        let schema = String::from_utf8(s.data.to_vec()).unwrap();
        let desc = [
            c.message_encoding.clone(),
            s.name.clone(),
            s.encoding.clone(),
            schema,
        ];
        channels.insert(c.topic.clone(), desc);
        let sha = format!("{:x}", Sha256::digest(&m.data));
        messages
            .entry(c.topic.clone())
            .or_default()
            .push((m.log_time, sha));
    }
    (channels, messages)
}

/// What the client received: its channels as advertised, its messages per topic, and each
/// message's record (decoded fields).
fn read_client(path: &Path) -> (Channels, Messages, Vec<Value>) {
    let v: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    assert_eq!(
        v["errors"],
        serde_json::json!([]),
        "the client's decoder failed"
    );
    assert_eq!(v["reason"], "closed by the server");
    let mut channels = Channels::new();
    for c in v["channels"].as_array().unwrap() {
        let s = |k: &str| c[k].as_str().unwrap_or_default().to_string();
        let desc = [
            s("encoding"),
            s("schemaName"),
            s("schemaEncoding"),
            s("schema"),
        ];
        channels.insert(s("topic"), desc);
    }
    let records = v["messages"].as_array().unwrap().clone();
    let mut messages = Messages::new();
    for m in &records {
        let t: u64 = m["log_time"].as_str().unwrap().parse().unwrap();
        let sha = m["sha256"].as_str().unwrap().to_string();
        let topic = m["topic"].as_str().unwrap().to_string();
        messages.entry(topic).or_default().push((t, sha));
    }
    (channels, messages, records)
}

/// The decoded values are a flight's: each topic's `t_s` in order (strictly on
/// `/servo/tick`), a tick's `t_s` its log time, the reference inside the 8 × 6 × 3 m stage.
fn assert_sane(records: &[Value]) {
    let mut last: BTreeMap<&str, f64> = BTreeMap::new();
    for m in records {
        let topic = m["topic"].as_str().unwrap();
        let Some(t_s) = m["t_s"].as_f64() else {
            continue;
        };
        let log_ns: f64 = m["log_time"].as_str().unwrap().parse().unwrap();
        if topic != "/measurement" {
            assert!(
                (t_s * 1e9 - log_ns).abs() < 1.0,
                "{topic}: t_s {t_s} at {log_ns} ns"
            );
        }
        if let Some(&before) = last.get(topic) {
            let ordered = if topic == "/servo/tick" {
                t_s > before
            } else {
                t_s >= before
            };
            assert!(ordered, "{topic}: t_s {t_s} after {before}");
        }
        last.insert(topic, t_s);
        if topic == "/reference" {
            let p: Vec<f64> = serde_json::from_value(m["position_m"].clone()).unwrap();
            let inside = p[0].abs() <= 4.0 && p[1].abs() <= 3.0 && (0.0..=3.0).contains(&p[2]);
            assert!(inside, "the reference {p:?} is outside the stage");
        }
    }
    assert!(last.contains_key("/servo/tick") && last.contains_key("/reference"));
}

/// `shoot --realtime --live`: the client connects as the drone takes off and receives the
/// flight as the log records it, byte for byte, on the log's topics and schemas.
#[test]
fn a_live_client_receives_the_flight_as_the_log_records_it() {
    let Some(node) = node("a_live_client_receives_the_flight_as_the_log_records_it") else {
        return;
    };
    let (_dir, script_arg, log_arg, out) = files();
    let log = Path::new(&log_arg);
    let args = ["shoot", &script_arg, "--realtime", "--log", &log_arg];
    let (mut shoot, url, said) = spawn_serving(&[&args[..], &["--live", "127.0.0.1:0"]].concat());
    assert!(url.starts_with("ws://127.0.0.1:"), "{url}");
    let mut client = client(&node, &url, &out, "180");
    let status = shoot.wait().unwrap();
    let said = said.recv().unwrap().join("\n");
    assert!(status.success(), "{said}");
    assert!(client.wait().unwrap().success());

    let summary = said
        .lines()
        .find(|l| l.starts_with("live view:") && l.contains("served"))
        .unwrap_or_else(|| panic!("no live summary in:\n{said}"));
    assert!(summary.contains("(1 client)"), "{summary}");
    assert!(
        summary.contains("with a client connected: p99"),
        "{summary}"
    );
    let dropped = summary.contains(" 0 dropped");

    let (log_channels, log_messages) = read_log(log);
    let (live_channels, live_messages, records) = read_client(&out);
    assert_eq!(
        live_channels.keys().collect::<Vec<_>>(),
        log_channels.keys().collect::<Vec<_>>(),
        "the log's topics"
    );
    assert_eq!(
        live_channels, log_channels,
        "the log's encodings and schemas"
    );
    assert!(live_channels.len() >= 18, "{:?}", live_channels.keys());
    for (topic, live) in &live_messages {
        let logged = &log_messages[topic];
        // From the client's first message on, the log's messages (all of them unless the
        // loop dropped ticks for the live view).
        let from = logged.iter().position(|m| *m == live[0]);
        let from = from.unwrap_or_else(|| panic!("{topic}: {:?} is not in the log", live[0]));
        if !dropped {
            assert_eq!(live, &logged[from..].to_vec(), "{topic}");
        } else {
            let all: BTreeSet<_> = logged.iter().collect();
            assert!(live.iter().all(|m| all.contains(m)), "{topic}");
        }
    }
    // The scene and the lens reach a client that connects after they were written; the ticks
    // from the approach on (the client subscribed during the take-off).
    for topic in [
        "/scene/stage",
        "/scene/drone",
        "/scene/actors",
        "/camera",
        "/servo/tick",
    ] {
        if dropped && topic == "/servo/tick" {
            continue;
        }
        assert_eq!(live_messages[topic], log_messages[topic], "{topic}");
    }
    assert!(records.iter().any(|m| m["kind"] == "flight_end"));
    assert_sane(&records);
}

/// `replay --live`: every message of the log, once a client subscribes, paced (here at 20×).
#[test]
fn replay_live_plays_every_message_of_the_log() {
    let Some(node) = node("replay_live_plays_every_message_of_the_log") else {
        return;
    };
    let (_dir, script_arg, log_arg, out) = files();
    let log = Path::new(&log_arg);
    shoot_fast(&script_arg, &log_arg);

    let args = ["replay", &log_arg, "--live", "127.0.0.1:0", "--speed", "20"];
    let (mut replay, url, said) = spawn_serving(&args);
    let mut client = client(&node, &url, &out, "180");
    let status = replay.wait().unwrap();
    let said = said.recv().unwrap().join("\n");
    assert!(status.success(), "{said}");
    assert!(said.contains("at 20× once a client subscribes"), "{said}");
    assert!(client.wait().unwrap().success());

    let (log_channels, log_messages) = read_log(log);
    let (live_channels, live_messages, records) = read_client(&out);
    assert_eq!(live_channels, log_channels);
    assert_eq!(live_messages, log_messages);
    assert_sane(&records);
}

/// An address that cannot be served is refused before anything flies, with a fix; and
/// `--speed` needs `--live` and a speed that is one.
#[test]
fn a_live_address_in_use_is_refused_before_take_off() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("f.mcap").display().to_string();
    let o =
        crate::common::dronecine(&["shoot", "shots/square.psl", "--log", &log, "--live", &addr]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains(&format!("cannot serve the live view on {addr}")),
        "{err}"
    );
    assert!(err.contains("help: give --live another ADDR:PORT"), "{err}");
    assert!(
        !Path::new(&log).exists(),
        "nothing was flown, no log written"
    );

    let o = crate::common::dronecine(&["replay", "x.mcap", "--speed", "2"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--live"));
    let o =
        crate::common::dronecine(&["replay", "x.mcap", "--live", "127.0.0.1:0", "--speed", "-1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("--speed -1 is outside 0.01–1000"), "{err}");
}

/// `emulate --live`: the simulator's world, the actors walking where they truly are, on the
/// log's topics (every one advertised, with the log's schemas), decoded by the same client.
#[test]
fn emulate_live_serves_the_simulators_world() {
    let Some(node) = node("emulate_live_serves_the_simulators_world") else {
        return;
    };
    let (_dir, script_arg, log_arg, out) = files();
    let log = Path::new(&log_arg);
    shoot_fast(&script_arg, &log_arg);

    let args = [
        "emulate",
        "ardrone",
        "--at-port",
        "0",
        "--navdata-port",
        "0",
        "--no-natnet",
        "--script",
        &script_arg,
        "--live",
        "127.0.0.1:0",
    ];
    let (mut emulate, url, _) = spawn_serving(&args);
    let mut client = client(&node, &url, &out, "3");
    let status = client.wait().unwrap();
    let _ = emulate.kill();
    let _ = emulate.wait();
    assert!(status.success());

    let v: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(v["errors"], serde_json::json!([]));
    let (log_channels, _) = read_log(log);
    let advertised: BTreeSet<&str> = v["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["topic"].as_str().unwrap())
        .collect();
    assert_eq!(
        advertised,
        log_channels.keys().map(String::as_str).collect()
    );
    let count = |topic: &str| {
        let all = v["messages"].as_array().unwrap();
        all.iter().filter(|m| m["topic"] == topic).count()
    };
    // Two seconds or so at 30 Hz; the drone, landed, once (its last pose, as it has not
    // moved); the scene once.
    assert!(count("/actors") >= 20, "{}", count("/actors"));
    assert!(count("/tf/actor/A") >= 1 && count("/tf/drone") == 1);
    assert_eq!((count("/scene/stage"), count("/camera")), (1, 1));
    let records = v["messages"].as_array().unwrap();
    let times: Vec<f64> = records
        .iter()
        .filter(|m| m["topic"] == "/actors")
        .map(|m| m["t_s"].as_f64().unwrap())
        .collect();
    assert!(times.windows(2).all(|w| w[1] > w[0]), "{times:?}");
}
