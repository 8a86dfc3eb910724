//! The MCAP and CSV writers, read back: every channel, schema, message, the metadata record
//! and the attachment are there and say what was written; the files appear atomically; bad
//! paths are errors.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use dronecine_compiler::camera::Lens;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_grammar::script::Stage;
use dronecine_mcap::output::foxglove;
use dronecine_mcap::output::mcap::{
    actors_schema, decode_actors, decode_reference, reference_schema,
};
use dronecine_mcap::output::{CsvWriter, McapWriter, RunInfo, CSV_COLUMNS};
use serde_json::Value;
use sha2::{Digest, Sha256};

const MAGIC: &[u8] = b"\x89MCAP0\r\n";
const RATE_HZ: f64 = 100.0;
const SCRIPT: &str = "stage 8m x 6m x 3m\nactor A height 1.80m at (0, 0) facing 0deg\n";

fn names() -> Vec<String> {
    // A quote in a name exercises the JSON escaping.
    vec!["A".to_string(), "Bo \"B\"".to_string()]
}

fn info(names: &[String]) -> RunInfo<'_> {
    RunInfo {
        script_name: "scene.psl",
        script_text: SCRIPT,
        profile_name: "ardrone2",
        rate_hz: RATE_HZ,
        lens: Lens::new(84f64.to_radians(), 16.0 / 9.0),
        stage: Stage {
            size_m: [8.0, 6.0, 3.0],
        },
        actor_names: names,
    }
}

/// When actor B starts walking (it stands still before).
const B_WALKS_S: f64 = 1.5;

/// 2.5 s at 100 Hz over two shots, with full-precision values (including tiny and negative
/// ones, and halves of the resolution) so that reading back checks the quantisation; a fixed
/// camera pitch, actor A always walking, actor B still until [`B_WALKS_S`].
fn reference() -> Vec<(Sample, Vec<ActorPose>)> {
    (0..250)
        .map(|i| {
            let t = i as f64 / RATE_HZ;
            let sample = Sample {
                t_s: t,
                position_m: [t.sin() * 2.0, -1.0 / 3.0 + t, 1.5 + 1e-9 * t],
                velocity_mps: [t.cos() * 2.0, 1.0, 1e-9],
                acceleration_mps2: [-t.sin() * 2.0, 0.0, -1e-12],
                heading_rad: (0.3 * t).sin() * 3.0,
                heading_rate_radps: 0.9 * (0.3 * t).cos() + 5e-7,
                camera_pitch_rad: -0.25,
                shot: if t < 1.2 { 0 } else { 1 },
            };
            let actors = vec![
                ActorPose {
                    position_m: [0.1 * t, 0.0, 0.0],
                    velocity_mps: [0.1, 0.0, 0.0],
                    facing_rad: 0.0,
                    facing_rate_radps: 0.0,
                    height_m: 1.8,
                },
                {
                    let walk_s = (t - B_WALKS_S).max(0.0);
                    ActorPose {
                        position_m: [2.5, -0.7 * walk_s, 0.0],
                        velocity_mps: [0.0, -0.7, 0.0],
                        facing_rad: std::f64::consts::PI - 0.2 * walk_s,
                        facing_rate_radps: -0.2,
                        height_m: 1.65,
                    }
                },
            ];
            (sample, actors)
        })
        .collect()
}

fn write_mcap(path: &Path, reference: &[(Sample, Vec<ActorPose>)]) {
    let names = names();
    let mut w = McapWriter::create(path, &info(&names)).unwrap();
    for (s, a) in reference {
        w.write(s, a).unwrap();
    }
    w.finish().unwrap();
}

fn ns(t_s: f64) -> u64 {
    (t_s * 1e9).round() as u64
}

/// The documented resolution of `/reference`, `/actors` and `/camera`.
const RESOLUTION: f64 = 1e-6;

/// `read` is `value` rounded to the resolution: within half a unit (and a hair for the
/// decimal-to-binary conversion of both).
fn quantised(read: f64, value: f64) -> bool {
    (read - value).abs() <= RESOLUTION / 2.0 * (1.0 + 1e-9) + value.abs() * 1e-15
}

/// Every number in a message's text is plain decimal with at most six decimals (the keys
/// and the actor names of these tests contain no digits, so every digit run is a number).
fn assert_at_most_six_decimals(text: &str, topic: &str) {
    let is_num = |c: char| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E');
    for token in text
        .split(|c: char| !is_num(c))
        .filter(|t| t.chars().any(|c| c.is_ascii_digit()))
    {
        assert!(
            !token.contains(['e', 'E']),
            "{topic}: {token} has an exponent"
        );
        let decimals = token.split_once('.').map_or(0, |(_, d)| d.len());
        assert!(
            decimals <= 6,
            "{topic}: {token} has {decimals} decimals in {text}"
        );
    }
}

/// Every key of every object in `value` is a property of the matching (sub)schema, and
/// every required property is present.
fn check_keys(value: &Value, schema: &Value, at: &str) {
    match value {
        Value::Object(map) => {
            let props = schema["properties"]
                .as_object()
                .unwrap_or_else(|| panic!("{at}: object without schema properties"));
            for (k, v) in map {
                let sub = props
                    .get(k)
                    .unwrap_or_else(|| panic!("{at}: key {k:?} not in the schema"));
                check_keys(v, sub, &format!("{at}.{k}"));
            }
            if let Some(required) = schema["required"].as_array() {
                for r in required {
                    assert!(map.contains_key(r.as_str().unwrap()), "{at}: {r} missing");
                }
            }
        }
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                check_keys(item, &schema["items"], &format!("{at}[{i}]"));
            }
        }
        _ => {}
    }
}

fn files_in(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn mcap_holds_the_reference_actors_scene_metadata_and_script() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.mcap");
    let reference = reference();
    write_mcap(&path, &reference);
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(MAGIC) && bytes.ends_with(MAGIC));

    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let topics: BTreeMap<&str, (&str, &str, &str, u64)> = summary
        .channels
        .values()
        .map(|c| {
            let s = c.schema.as_ref().expect("every channel has a schema");
            let count = summary.stats.as_ref().unwrap().channel_message_counts[&c.id];
            (
                c.topic.as_str(),
                (
                    s.name.as_str(),
                    s.encoding.as_str(),
                    c.message_encoding.as_str(),
                    count,
                ),
            )
        })
        .collect();
    let n = reference.len() as u64;
    // The per-sample topics in CDR with ros2msg schemas.
    assert_eq!(
        topics.get("/reference"),
        Some(&("dronecine/msg/Reference", "ros2msg", "cdr", n))
    );
    assert_eq!(
        topics.get("/actors"),
        Some(&("dronecine/msg/Actors", "ros2msg", "cdr", n))
    );
    let expected = [
        ("/camera", "dronecine.Camera", 1),
        ("/scene/stage", "foxglove.SceneUpdate", 1),
        ("/scene/drone", "foxglove.SceneUpdate", 1),
        ("/scene/actors", "foxglove.SceneUpdate", 1),
        ("/scene/path", "foxglove.SceneUpdate", 1),
        ("/camera_calibration", "foxglove.CameraCalibration", 1),
    ];
    for (topic, schema, count) in expected {
        assert_eq!(
            topics.get(topic),
            Some(&(schema, "jsonschema", "json", count)),
            "{topic}"
        );
    }
    // One transform topic per frame (their counts are checked below).
    let tf_topics = [
        "/tf/drone",
        "/tf/camera",
        "/tf/actor/A",
        "/tf/actor/Bo \"B\"",
    ];
    for topic in tf_topics {
        assert_eq!(
            topics.get(topic).map(|t| (t.0, t.1, t.2)),
            Some(("foxglove_msgs/msg/FrameTransforms", "ros2msg", "cdr")),
            "{topic} in {topics:?}"
        );
    }
    assert_eq!(topics.len(), 2 + expected.len() + tf_topics.len());

    // Metadata record and attachment.
    assert_eq!(summary.metadata_indexes.len(), 1);
    let meta = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).unwrap();
    assert_eq!(meta.name, "dronecine");
    let sha: String = Sha256::digest(SCRIPT.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(meta.metadata["source_sha256"], sha);
    assert_eq!(meta.metadata["profile"], "ardrone2");
    assert_eq!(meta.metadata["compiler_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(meta.metadata["rate_hz"].parse::<f64>().unwrap(), RATE_HZ);
    assert_eq!(meta.metadata["script_name"], "scene.psl");
    assert_eq!(summary.attachment_indexes.len(), 1);
    let att = mcap::read::attachment(&bytes, &summary.attachment_indexes[0]).unwrap();
    assert_eq!(
        (att.name.as_str(), att.media_type.as_str()),
        ("scene.psl", "text/plain")
    );
    assert_eq!(&*att.data, SCRIPT.as_bytes());

    // Every message: valid JSON whose keys the schema declares; log and publish time agree.
    let mut reference_msgs = Vec::new();
    let mut actor_msgs = Vec::new();
    let mut by_topic: BTreeMap<String, Vec<(u64, Value)>> = BTreeMap::new();
    let mut tf_by_topic: BTreeMap<String, Vec<(u64, Vec<foxglove::FrameTransform>)>> =
        BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.log_time, m.publish_time);
        let schema = &m.channel.schema.as_ref().unwrap().data;
        match m.channel.topic.as_str() {
            "/reference" => {
                assert_eq!(std::str::from_utf8(schema).unwrap(), reference_schema());
                reference_msgs.push((m.log_time, decode_reference(&m.data).unwrap()));
                continue;
            }
            "/actors" => {
                assert_eq!(std::str::from_utf8(schema).unwrap(), actors_schema());
                actor_msgs.push((m.log_time, decode_actors(&m.data).unwrap()));
                continue;
            }
            _ => {}
        }
        if m.channel.message_encoding == "cdr" {
            // The transforms.
            assert_eq!(
                std::str::from_utf8(schema).unwrap(),
                foxglove::frame_transforms_schema()
            );
            let transforms = foxglove::decode_frame_transforms(&m.data).unwrap();
            tf_by_topic
                .entry(m.channel.topic.clone())
                .or_default()
                .push((m.log_time, transforms));
            continue;
        }
        let value: Value = serde_json::from_slice(&m.data).unwrap_or_else(|e| {
            panic!(
                "{}: {e}: {}",
                m.channel.topic,
                String::from_utf8_lossy(&m.data)
            )
        });
        let schema: Value =
            serde_json::from_slice(&m.channel.schema.as_ref().unwrap().data).unwrap();
        check_keys(&value, &schema, &m.channel.topic);
        if m.channel.topic == "/camera" {
            assert_at_most_six_decimals(std::str::from_utf8(&m.data).unwrap(), &m.channel.topic);
            // Our own schema: the keys are exactly the properties.
            let keys: BTreeSet<&String> = value.as_object().unwrap().keys().collect();
            let props: BTreeSet<&String> =
                schema["properties"].as_object().unwrap().keys().collect();
            assert_eq!(keys, props, "{}", m.channel.topic);
        }
        by_topic
            .entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, value));
    }

    // The samples and the actors, every number exact (CDR keeps the bits).
    assert_eq!(reference_msgs.len(), reference.len());
    assert_eq!(actor_msgs.len(), reference.len());
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    for ((log_time, read), (s, _)) in reference_msgs.iter().zip(&reference) {
        assert_eq!(*log_time, ns(s.t_s));
        assert_eq!(read, s);
        assert_eq!(bits(&read.position_m), bits(&s.position_m));
    }
    let names = names();
    for ((log_time, (t_s, read)), (s, actors)) in actor_msgs.iter().zip(&reference) {
        assert_eq!(*log_time, ns(s.t_s));
        assert_eq!(t_s.to_bits(), s.t_s.to_bits());
        assert_eq!(read.len(), actors.len());
        for ((a, pose), name) in read.iter().zip(actors).zip(&names) {
            assert_eq!(&a.name, name);
            assert_eq!(
                bits(&[
                    a.position_m[0],
                    a.position_m[1],
                    a.position_m[2],
                    a.facing_rad,
                    a.height_m
                ]),
                bits(&[
                    pose.position_m[0],
                    pose.position_m[1],
                    pose.position_m[2],
                    pose.facing_rad,
                    pose.height_m
                ])
            );
        }
    }

    let camera = &by_topic["/camera"][0].1;
    assert!(quantised(
        camera["fov_x_rad"].as_f64().unwrap(),
        84f64.to_radians()
    ));
    assert!(quantised(camera["aspect"].as_f64().unwrap(), 16.0 / 9.0));

    // The transforms: the drone (always moving) at every 30 Hz tick, actor A (walking) too,
    // the fixed camera once at the first tick, actor B once at the first tick and then at
    // every tick from when it walks. Each transform follows the samples to the millimetre
    // and is stamped at its message's time, but for the one that holds B still until the
    // tick before it starts walking.
    let sample_at = |ns_: u64| {
        reference
            .iter()
            .find(|(s, _)| ns(s.t_s) == ns_)
            .unwrap_or_else(|| panic!("no sample at {ns_} ns"))
    };
    let mm = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() <= 5e-4);
    let ticks: Vec<u64> = tf_by_topic["/tf/drone"].iter().map(|(t, _)| *t).collect();
    assert!((74..=76).contains(&ticks.len()), "{} ticks", ticks.len());
    assert!(ticks.windows(2).all(|w| {
        let dt = (w[1] - w[0]) as f64 / 1e9;
        (0.03..=0.04).contains(&dt)
    }));
    assert_eq!(ticks[0], 0);
    let log_times =
        |topic: &str| -> Vec<u64> { tf_by_topic[topic].iter().map(|(t, _)| *t).collect() };
    assert_eq!(log_times("/tf/actor/A"), ticks);
    assert_eq!(log_times("/tf/camera"), [ticks[0]]);
    let b_ticks: Vec<u64> = std::iter::once(ticks[0])
        .chain(
            ticks
                .iter()
                .copied()
                .filter(|&t| t as f64 / 1e9 > B_WALKS_S + 1e-9),
        )
        .collect();
    assert_eq!(log_times("/tf/actor/Bo \"B\""), b_ticks);
    for (topic, parent, child, index) in [
        ("/tf/drone", "world", "drone", None),
        ("/tf/camera", "drone", "camera", None),
        ("/tf/actor/A", "world", "actor/A", Some(0)),
        ("/tf/actor/Bo \"B\"", "world", "actor/Bo \"B\"", Some(1)),
    ] {
        for (log_time, transforms) in &tf_by_topic[topic] {
            let (s, actors) = sample_at(*log_time);
            let last = transforms.last().unwrap();
            assert_eq!(last.timestamp_ns, *log_time);
            let expected = match index {
                None if child == "drone" => s.position_m,
                None => [0.0; 3],
                Some(i) => actors[i].position_m,
            };
            assert!(mm(last.translation, expected), "{topic} at {log_time}");
            for t in transforms {
                assert_eq!(
                    (t.parent_frame_id.as_str(), t.child_frame_id.as_str()),
                    (parent, child)
                );
            }
            // B's first step: held still at the previous tick, then where it is.
            let held = *log_time == b_ticks[1] && index == Some(1);
            assert_eq!(transforms.len(), if held { 2 } else { 1 }, "{topic}");
            if held {
                let previous = ticks[ticks.iter().position(|t| t == log_time).unwrap() - 1];
                assert_eq!(transforms[0].timestamp_ns, previous);
                assert!(mm(transforms[0].translation, [2.5, 0.0, 0.0]));
            }
        }
    }

    // The path: one strip per shot, from the first position to the last, joined.
    let path = &by_topic["/scene/path"][0].1;
    let lines = path["entities"][0]["lines"].as_array().unwrap();
    assert_eq!(lines.len(), 2);
    let point = |p: &Value| {
        [
            p["x"].as_f64().unwrap(),
            p["y"].as_f64().unwrap(),
            p["z"].as_f64().unwrap(),
        ]
    };
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() <= 5e-4);
    let first = point(&lines[0]["points"][0]);
    let last_strip = lines[1]["points"].as_array().unwrap();
    assert!(close(first, reference[0].0.position_m));
    assert!(close(
        point(last_strip.last().unwrap()),
        reference.last().unwrap().0.position_m
    ));
    let end_of_first = lines[0]["points"].as_array().unwrap().last().unwrap();
    assert_eq!(point(end_of_first), point(&last_strip[0]), "strips join");

    // Actor entities ride their frames.
    let actors = &by_topic["/scene/actors"][0].1["entities"];
    assert_eq!(actors[1]["frame_id"], "actor/Bo \"B\"");
    assert_eq!(actors[1]["frame_locked"], true);
    let calib = &by_topic["/camera_calibration"][0].1;
    assert_eq!(calib["frame_id"], "camera");
}

#[test]
fn files_appear_only_on_finish_and_vanish_when_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let reference = reference();
    let mcap_path = dir.path().join("out.mcap");
    let csv_path = dir.path().join("out.csv");

    let mut m = McapWriter::create(&mcap_path, &info(&names)).unwrap();
    let mut c = CsvWriter::create(&csv_path).unwrap();
    for (s, a) in &reference {
        m.write(s, a).unwrap();
        c.write(s).unwrap();
    }
    let during = files_in(dir.path());
    assert_eq!(during.len(), 2);
    assert!(
        during
            .iter()
            .all(|f| f.starts_with('.') && f.ends_with(".tmp")),
        "{during:?}"
    );
    m.finish().unwrap();
    c.finish().unwrap();
    assert_eq!(
        files_in(dir.path()),
        BTreeSet::from(["out.csv".to_string(), "out.mcap".to_string()])
    );

    // Unfinished writers leave nothing behind, and never touch the destination.
    let before = std::fs::read(&mcap_path).unwrap();
    let mut m = McapWriter::create(&mcap_path, &info(&names)).unwrap();
    let mut c = CsvWriter::create(&csv_path).unwrap();
    for (s, a) in &reference[..10] {
        m.write(s, a).unwrap();
        c.write(s).unwrap();
    }
    drop(m);
    drop(c);
    assert_eq!(
        files_in(dir.path()),
        BTreeSet::from(["out.csv".to_string(), "out.mcap".to_string()])
    );
    assert_eq!(std::fs::read(&mcap_path).unwrap(), before);
}

#[test]
fn unwritable_paths_are_errors_that_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let missing = dir.path().join("no such dir").join("out.mcap");
    let e = McapWriter::create(&missing, &info(&names))
        .err()
        .expect("an error");
    assert_eq!(e.kind(), std::io::ErrorKind::NotFound);
    assert!(
        e.to_string().contains(&missing.display().to_string()),
        "{e}"
    );
    let missing_csv = dir.path().join("no such dir").join("out.csv");
    let e = CsvWriter::create(&missing_csv).err().expect("an error");
    assert!(
        e.to_string().contains(&missing_csv.display().to_string()),
        "{e}"
    );
    // A path that names no file.
    let e = McapWriter::create(Path::new("/"), &info(&names))
        .err()
        .expect("an error");
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    assert!(files_in(dir.path()).is_empty());
}

#[test]
fn a_wrong_number_of_actors_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let names = names();
    let mut m = McapWriter::create(&dir.path().join("out.mcap"), &info(&names)).unwrap();
    let (s, a) = &reference()[0];
    let e = m.write(s, &a[..1]).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
}

#[test]
fn non_finite_values_are_kept_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.mcap");
    let mut reference = reference();
    reference[3].0.velocity_mps[1] = f64::NAN;
    reference[4].0.heading_rad = f64::INFINITY;
    reference[5].1[0].facing_rad = f64::NEG_INFINITY;
    write_mcap(&path, &reference);
    let bytes = std::fs::read(&path).unwrap();
    let (mut samples, mut actors) = (Vec::new(), Vec::new());
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        // Every message, /tf included, still reads.
        match m.channel.topic.as_str() {
            "/reference" => samples.push(decode_reference(&m.data).unwrap()),
            "/actors" => actors.push(decode_actors(&m.data).unwrap().1),
            _ if m.channel.message_encoding == "cdr" => {
                foxglove::decode_frame_transforms(&m.data).unwrap();
            }
            _ => {
                serde_json::from_slice::<Value>(&m.data).unwrap();
            }
        }
    }
    assert_eq!(
        samples[3].velocity_mps[1].to_bits(),
        f64::NAN.to_bits(),
        "the NaN's own bits"
    );
    assert_eq!(samples[4].heading_rad, f64::INFINITY);
    assert_eq!(actors[5][0].facing_rad, f64::NEG_INFINITY);
    let non_finite = samples
        .iter()
        .flat_map(|s| {
            [
                s.t_s,
                s.heading_rad,
                s.heading_rate_radps,
                s.camera_pitch_rad,
            ]
            .into_iter()
            .chain(s.position_m)
            .chain(s.velocity_mps)
            .chain(s.acceleration_mps2)
        })
        .chain(
            actors
                .iter()
                .flatten()
                .flat_map(|a| [a.facing_rad, a.height_m].into_iter().chain(a.position_m)),
        )
        .filter(|x| !x.is_finite())
        .count();
    assert_eq!(non_finite, 3);
}

#[test]
fn csv_rows_parse_back_to_the_samples() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.csv");
    let mut reference = reference();
    reference[7].0.acceleration_mps2[2] = f64::NAN;
    let mut w = CsvWriter::create(&path).unwrap();
    for (s, _) in &reference {
        w.write(s).unwrap();
    }
    w.finish().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap().split(',').collect::<Vec<_>>(),
        CSV_COLUMNS
    );
    let mut rows = 0;
    for (line, (s, _)) in lines.zip(&reference) {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        assert_eq!(f.len(), CSV_COLUMNS.len());
        let back = Sample {
            t_s: f[0],
            position_m: [f[1], f[2], f[3]],
            velocity_mps: [f[4], f[5], f[6]],
            acceleration_mps2: [f[7], f[8], f[9]],
            heading_rad: f[10],
            heading_rate_radps: f[11],
            camera_pitch_rad: f[12],
            shot: f[13] as usize,
        };
        if s.acceleration_mps2[2].is_nan() {
            assert!(back.acceleration_mps2[2].is_nan());
            assert_eq!(back.position_m, s.position_m);
        } else {
            assert_eq!(&back, s);
        }
        rows += 1;
    }
    assert_eq!(rows, reference.len());
}
