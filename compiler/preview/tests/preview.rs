//! The previews of `dronecine compile --preview`: every file is written, the SVGs parse, the
//! PNGs decode at the SVG's size and show something, text renders from the embedded font, the
//! output is deterministic, bad input is an error; and the storyboard's figures sit where the
//! projection puts them, at the size the shot size asks for, with a profile that reads.

use std::f64::consts::{FRAC_PI_2, PI};
use std::fs;
use std::path::{Path, PathBuf};

use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_grammar::script::Stage;
use dronecine_math::wrap_angle_rad;
use dronecine_preview::figure::{figure, Figure};
use dronecine_preview::{
    svg_to_png, tilt_commands_rad, write_previews, PreviewInput, ShotInfo, ShotKind,
};
use dronecine_profile::Profile;

fn actor(x: f64, y: f64, facing_rad: f64, height_m: f64) -> ActorPose {
    ActorPose {
        position_m: [x, y, 0.0],
        velocity_mps: [0.0; 3],
        facing_rad,
        facing_rate_radps: 0.0,
        height_m,
    }
}

fn shot(start_s: f64, end_s: f64, label: &str, kind: ShotKind) -> ShotInfo {
    ShotInfo {
        start_s,
        end_s,
        label: label.to_string(),
        kind,
        framing: Default::default(),
    }
}

fn lens_84() -> Lens {
    Lens::new(84f64.to_radians(), 16.0 / 9.0)
}

/// A scene to preview (owned, borrowed by `PreviewInput`).
struct Scene {
    samples: Vec<Sample>,
    actors: Vec<Vec<ActorPose>>,
    names: Vec<String>,
    shots: Vec<ShotInfo>,
    profile: Profile,
}

impl Scene {
    fn input(&self) -> PreviewInput<'_> {
        PreviewInput {
            samples: &self.samples,
            actors: &self.actors,
            actor_names: &self.names,
            stage: Stage {
                size_m: [8.0, 6.0, 3.0],
            },
            lens: lens_84(),
            limits: &self.profile.limits,
            model: &self.profile.model,
            shots: &self.shots,
        }
    }
}

/// The camera circling one actor (radius 2.5 m, one turn in 20 s) at 10 Hz, looking at them.
fn circling() -> Scene {
    let (r, w, z) = (2.5, 2.0 * PI / 20.0, 1.5);
    let mut samples = Vec::new();
    for i in 0..=200 {
        let t = i as f64 * 0.1;
        let (s, c) = (w * t).sin_cos();
        samples.push(Sample {
            t_s: t,
            position_m: [r * c, r * s, z],
            velocity_mps: [-r * w * s, r * w * c, 0.0],
            acceleration_mps2: [-r * w * w * c, -r * w * w * s, 0.0],
            heading_rad: wrap_angle_rad(w * t + PI),
            heading_rate_radps: w,
            camera_pitch_rad: 0.0,
            shot: usize::from(t >= 10.0),
        });
    }
    let actors = vec![vec![actor(0.0, 0.0, 0.0, 1.8)]; samples.len()];
    Scene {
        samples,
        actors,
        names: vec!["A".to_string()],
        shots: vec![
            shot(0.0, 10.0, "MS on A front for 10s", ShotKind::Hold),
            shot(
                10.0,
                20.0,
                "then track to MS on A back over 10s",
                ShotKind::Transition,
            ),
        ],
        profile: Profile::builtin("ardrone2").unwrap(),
    }
}

/// Two actors facing each other, B walking away from 5 s to 10 s; the camera flies a line
/// looking +y, with a repositioning between two shots. 5 Hz (a decimated reference).
fn two_actors() -> Scene {
    let mut samples = Vec::new();
    let mut actors = Vec::new();
    for i in 0..=60 {
        let t = i as f64 * 0.2;
        let u = t / 12.0;
        samples.push(Sample {
            t_s: t,
            position_m: [-0.5 + 2.0 * u, -3.0, 1.6 - 0.4 * u],
            velocity_mps: [2.0 / 12.0, 0.0, -0.4 / 12.0],
            acceleration_mps2: [0.0; 3],
            heading_rad: FRAC_PI_2,
            heading_rate_radps: 0.0,
            camera_pitch_rad: 0.0,
            shot: usize::from(t >= 5.0),
        });
        let walk = ((t - 5.0) / 5.0).clamp(0.0, 1.0);
        actors.push(vec![
            actor(-1.0, 0.0, 0.0, 1.8),
            actor(1.5, 1.5 * walk, PI, 1.65),
        ]);
    }
    Scene {
        samples,
        actors,
        names: vec!["A".to_string(), "Bob".to_string()],
        shots: vec![
            shot(0.0, 5.0, "MS on A and Bob for 5s", ShotKind::Hold),
            shot(5.0, 7.0, "repositioning to shot 2", ShotKind::Reposition),
            shot(
                7.0,
                12.0,
                "cut to MLS Bob 34right screen right for 5s",
                ShotKind::Hold,
            ),
        ],
        profile: Profile::builtin("ardrone2").unwrap(),
    }
}

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("preview")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    dir
}

/// The `width`/`height` attributes of an SVG's root.
fn svg_size(svg: &str) -> (u32, u32) {
    let attr = |name: &str| {
        let key = format!(" {name}=\"");
        let start = svg.find(&key).unwrap() + key.len();
        let end = start + svg[start..].find('"').unwrap();
        svg[start..end].parse::<f64>().unwrap() as u32
    };
    (attr("width"), attr("height"))
}

/// Decodes a PNG to (width, height, RGBA pixels).
fn decode_png(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba, "RGBA expected");
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

fn non_white_fraction(rgba: &[u8]) -> f64 {
    let px = rgba.len() / 4;
    let n = rgba
        .chunks_exact(4)
        .filter(|p| p[0] < 245 || p[1] < 245 || p[2] < 245)
        .count();
    n as f64 / px as f64
}

const NAMES: [&str; 8] = [
    "top.svg",
    "top.png",
    "side.svg",
    "side.png",
    "timeseries.svg",
    "timeseries.png",
    "storyboard.svg",
    "storyboard.png",
];

fn check_outputs(dir: &Path, written: &[PathBuf]) {
    let expected: Vec<PathBuf> = NAMES.iter().map(|n| dir.join(n)).collect();
    assert_eq!(written, expected.as_slice());
    for pair in NAMES.chunks(2) {
        let svg = fs::read_to_string(dir.join(pair[0])).unwrap();
        // Parses as SVG (strict XML underneath).
        let tree = resvg::usvg::Tree::from_str(&svg, &resvg::usvg::Options::default())
            .unwrap_or_else(|e| panic!("{}: {e}", pair[0]));
        let (w, h) = svg_size(&svg);
        assert_eq!(
            (tree.size().width() as u32, tree.size().height() as u32),
            (w, h)
        );
        let (pw, ph, rgba) = decode_png(&fs::read(dir.join(pair[1])).unwrap());
        assert_eq!((pw, ph), (w, h), "{}", pair[1]);
        let ink = non_white_fraction(&rgba);
        assert!(ink > 0.03, "{} is nearly blank: {ink}", pair[1]);
    }
    // No temporary file left behind.
    let leftovers: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !NAMES.contains(&n.as_str()))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn circling_one_actor_writes_every_preview() {
    let scene = circling();
    let dir = out_dir("circling");
    let written = write_previews(&dir, &scene.input()).unwrap();
    check_outputs(&dir, &written);
    let story = fs::read_to_string(dir.join("storyboard.svg")).unwrap();
    assert!(story.contains("MS on A front for 10s"));
    assert!(story.contains("then track to MS on A back over 10s"));
    // The limits are drawn and named.
    let ts = fs::read_to_string(dir.join("timeseries.svg")).unwrap();
    for limit in [
        "speed_max",
        "accel_max",
        "tilt_max",
        "vz_max",
        "yaw_rate_max",
    ] {
        assert!(ts.contains(limit), "{limit} missing");
    }
    assert!(
        !ts.contains("OVER LIMIT"),
        "0.79 m/s and 0.25 m/s² are within the limits"
    );
}

#[test]
fn tilt_follows_the_servo_model() {
    // Circling at r = 2.5 m, ω = 2π/20 rad/s, looking at the centre: the acceleration
    // rω² = 0.246740 m/s² points forward, the velocity rω = 0.785398 m/s to the camera's
    // right. With K = 17.5 m/s/rad and τ = 1.7 s: pitch = 1.7·0.246740/17.5 = 0.0239691 rad,
    // roll = 0.785398/17.5 = 0.0448799 rad.
    let scene = circling();
    for s in [&scene.samples[0], &scene.samples[37], &scene.samples[150]] {
        let [pitch, roll] = tilt_commands_rad(s, &scene.profile.model);
        assert!((pitch - 0.023_969_1).abs() < 1e-6, "{pitch}");
        assert!((roll - 0.044_879_9).abs() < 1e-6, "{roll}");
    }
}

#[test]
fn a_reference_over_the_limits_is_flagged() {
    let mut scene = two_actors();
    let vmax = scene.profile.limits.speed_max_mps;
    for s in &mut scene.samples[10..20] {
        s.velocity_mps = [1.5 * vmax, 0.0, 0.0];
    }
    let dir = out_dir("over");
    write_previews(&dir, &scene.input()).unwrap();
    let ts = fs::read_to_string(dir.join("timeseries.svg")).unwrap();
    assert!(
        ts.contains("|v_xy|  (peak 2.76 m/s)  OVER LIMIT"),
        "speed over the limit not flagged"
    );
}

#[test]
fn two_actors_and_a_repositioning_write_every_preview() {
    let scene = two_actors();
    let dir = out_dir("two_actors");
    let written = write_previews(&dir, &scene.input()).unwrap();
    check_outputs(&dir, &written);
    let story = fs::read_to_string(dir.join("storyboard.svg")).unwrap();
    assert!(story.contains("R→2 · repositioning flight"));
    assert!(story.contains("cut to MLS Bob 34right screen right for 5s"));
    assert!(story.contains(">Bob</text>"));
}

#[test]
fn output_is_deterministic() {
    let scene = two_actors();
    let (a, b) = (out_dir("det_a"), out_dir("det_b"));
    write_previews(&a, &scene.input()).unwrap();
    write_previews(&b, &scene.input()).unwrap();
    for name in NAMES {
        assert!(
            fs::read(a.join(name)).unwrap() == fs::read(b.join(name)).unwrap(),
            "{name} differs between two runs"
        );
    }
}

#[test]
fn text_renders_from_the_embedded_font() {
    // resvg is built without system fonts: ink here comes from the embedded DejaVu Sans.
    let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="40" font-family="DejaVu Sans"><text x="4" y="30" font-size="24" fill="#000">MS on A</text></svg>"##;
    let (w, h, rgba) = decode_png(&svg_to_png(svg).unwrap());
    assert_eq!((w, h), (200, 40));
    assert!(non_white_fraction(&rgba) > 0.05);
    let bold = svg.replace("<text ", "<text font-weight=\"bold\" ");
    let (_, _, rgba_bold) = decode_png(&svg_to_png(&bold).unwrap());
    assert!(
        non_white_fraction(&rgba_bold) > non_white_fraction(&rgba) * 1.15,
        "bold is a separate, heavier face"
    );
}

#[test]
fn mismatched_input_is_an_error_and_writes_nothing() {
    let mut scene = two_actors();
    scene.actors.pop();
    let dir = out_dir("bad");
    let err = write_previews(&dir, &scene.input()).unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
    assert!(!dir.exists());

    let mut scene = two_actors();
    scene.actors[3].pop();
    assert!(write_previews(&dir, &scene.input()).is_err());

    let mut scene = two_actors();
    scene.samples.clear();
    scene.actors.clear();
    assert!(write_previews(&dir, &scene.input()).is_err());
}

#[test]
fn non_finite_samples_still_give_valid_files() {
    let mut scene = circling();
    scene.samples[50].position_m[0] = f64::NAN;
    scene.samples[60].velocity_mps[1] = f64::INFINITY;
    let dir = out_dir("nan");
    let written = write_previews(&dir, &scene.input()).unwrap();
    check_outputs(&dir, &written);
}

// ---- storyboard geometry ----

fn pose_looking_at(from: Vec3, heading_rad: f64) -> CameraPose {
    CameraPose {
        position_m: from,
        heading_rad,
        pitch_rad: 0.0,
    }
}

#[test]
fn head_lands_where_the_projection_puts_it() {
    // fovX 90°: Sx = 1, Sy = 16/9. Actor 1.80 m at (0, 0.5) facing +x; camera 3 m in front at
    // (3, 0, 1.6), looking −x (its right is +y). Head centre at 0.935·1.80 = 1.683 m:
    // x = 0.5·1/3 = 0.166667, y = (1.683 − 1.6)·(16/9)/3 = 0.0491852; radius 0.065·1.80 = 0.117 m
    // → 0.117·(16/9)/3 = 0.0693333.
    let lens = Lens::new(FRAC_PI_2, 16.0 / 9.0);
    let pose = pose_looking_at(Vec3::new(3.0, 0.0, 1.6), PI);
    let f = figure(&pose, &lens, &actor(0.0, 0.5, 0.0, 1.8)).unwrap();
    assert!(
        (f.head_centre[0] - 0.166_666_7).abs() < 1e-6,
        "{:?}",
        f.head_centre
    );
    assert!(
        (f.head_centre[1] - 0.049_185_2).abs() < 1e-6,
        "{:?}",
        f.head_centre
    );
    assert!(
        (f.head_radius - 0.069_333_3).abs() < 1e-6,
        "{}",
        f.head_radius
    );
    // Twice as far, half the size.
    let far = pose_looking_at(Vec3::new(6.0, 0.0, 1.6), PI);
    let g = figure(&far, &lens, &actor(0.0, 0.5, 0.0, 1.8)).unwrap();
    assert!((f.head_radius / g.head_radius - 2.0).abs() < 1e-9);
    // The feet: 1.6 m below the camera, 3 m ahead → y = −1.6·(16/9)/3 = −0.948148.
    let feet = f.feet.unwrap();
    assert!((feet[1] + 0.948_148_1).abs() < 1e-6, "{feet:?}");
    // Behind the camera: no figure.
    let behind = pose_looking_at(Vec3::new(3.0, 0.0, 1.6), 0.0);
    assert!(figure(&behind, &lens, &actor(0.0, 0.5, 0.0, 1.8)).is_none());
}

fn screen_extent(outline: &[[f64; 2]], axis: usize) -> (f64, f64) {
    outline
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[axis]), hi.max(p[axis]))
        })
}

#[test]
fn a_medium_shot_is_cut_at_the_waist() {
    // MS: band 0.60–1.05 H, W = 0.45 H. H = 1.80, lens 84° 16:9:
    // tan(fovY/2) = tan 42° / (16/9) = 0.506477, d = 0.81 / (2·0.506477) = 0.799641 m, camera
    // at the band centre 0.825·1.80 = 1.485 m. The crown (1.80 m) is at
    // y = 0.315 / (d·tan(fovY/2)) = 0.315 / 0.405 = 0.777778 and the hips are below the frame.
    let lens = lens_84();
    let d = 0.81 / (2.0 * 0.506_477);
    let pose = pose_looking_at(Vec3::new(d, 0.0, 1.485), PI);
    let f = figure(&pose, &lens, &actor(0.0, 0.0, 0.0, 1.8)).unwrap();
    let crown = f.crown.unwrap();
    assert!(crown[0].abs() < 1e-9);
    assert!((crown[1] - 0.777_778).abs() < 2e-4, "{crown:?}");
    let (torso_lo, torso_hi) = screen_extent(f.torso.as_ref().unwrap(), 1);
    assert!(torso_lo < -1.0, "the frame cuts the torso: {torso_lo}");
    assert!(
        (-0.1..0.0).contains(&torso_hi),
        "shoulders near the centre: {torso_hi}"
    );
    let (_, legs_hi) = screen_extent(f.legs.as_ref().unwrap(), 1);
    assert!(legs_hi < -1.0, "no legs in an MS: {legs_hi}");
}

/// The figure seen from azimuth `theta` around the actor (as a script's angles are: from the
/// facing, counter-clockwise), 3 m away at head height, the camera looking at the head.
fn seen_from(theta: f64) -> Figure {
    let h = 1.8;
    let z = 0.935 * h;
    let pose = pose_looking_at(
        Vec3::new(3.0 * theta.cos(), 3.0 * theta.sin(), z),
        theta + PI,
    );
    figure(&pose, &lens_84(), &actor(0.0, 0.0, 0.0, h)).unwrap()
}

fn nose_dx(f: &Figure) -> f64 {
    let [_, tip] = f.nose.unwrap();
    tip[0] - f.head_centre[0]
}

#[test]
fn the_profile_reads_from_eyes_nose_and_width() {
    let deg = f64::to_radians;
    let front = seen_from(0.0);
    let three_quarter_left = seen_from(deg(45.0));
    let left = seen_from(deg(90.0));
    let back = seen_from(deg(180.0));
    let right = seen_from(deg(-90.0));

    assert_eq!(front.eyes.len(), 2);
    assert!(front.nose_in_front);
    assert!(nose_dx(&front).abs() < 0.1 * front.head_radius);

    // From 34left the actor faces toward screen left.
    assert_eq!(three_quarter_left.eyes.len(), 2);
    assert!(nose_dx(&three_quarter_left) < -0.5 * three_quarter_left.head_radius / 1.7778);

    assert_eq!(left.eyes.len(), 1);
    assert!(nose_dx(&left) < 0.0);
    assert!(nose_dx(&left).abs() > nose_dx(&three_quarter_left).abs());
    assert!(nose_dx(&right) > 0.0);
    assert_eq!(right.eyes.len(), 1);

    assert!(back.eyes.is_empty());
    assert!(!back.nose_in_front);

    // Shoulders are wide from the front and narrow from the side.
    let width = |f: &Figure| {
        let (lo, hi) = screen_extent(f.torso.as_ref().unwrap(), 0);
        hi - lo
    };
    assert!(
        width(&front) > 1.6 * width(&left),
        "{} vs {}",
        width(&front),
        width(&left)
    );
    assert!((width(&front) - width(&back)).abs() < 1e-9);
}

/// The hair's share of the head's disk, seen from azimuth `theta` (as [`seen_from`]).
fn hair_seen_from(theta: f64) -> (f64, Figure) {
    let f = seen_from(theta);
    (f.hair.share(f.head_centre, f.head_radius, 16.0 / 9.0), f)
}

#[test]
fn a_head_seen_from_behind_is_hair_and_from_the_front_a_face() {
    let deg = f64::to_radians;
    let (back, b) = hair_seen_from(deg(180.0));
    assert!(back > 0.9, "from behind, hair over {back:.2} of the head");
    assert!(b.eyes.is_empty() && !b.nose_in_front);
    let (back34, b34) = hair_seen_from(deg(135.0));
    assert!(
        back34 > 0.8 && b34.eyes.is_empty(),
        "34backleft: {back34:.2}"
    );
    let (side, s) = hair_seen_from(deg(90.0));
    assert!(
        (0.4..0.8).contains(&side) && s.eyes.len() == 1,
        "left: {side:.2}"
    );
    let (front, f) = hair_seen_from(0.0);
    assert!(
        front < 0.3 && f.eyes.len() == 2,
        "front: {front:.2} of the head is hair"
    );
    let (front34, _) = hair_seen_from(deg(-45.0));
    assert!(front34 < 0.45, "34right: {front34:.2}");
    // From behind and above: all hair; from in front and below: no hair at all.
    let h = 1.8;
    let lens = lens_84();
    let above = CameraPose {
        position_m: Vec3::new(-1.0, 0.0, 3.0),
        heading_rad: 0.0,
        pitch_rad: -0.9,
    };
    let f = figure(&above, &lens, &actor(0.0, 0.0, 0.0, h)).unwrap();
    assert!(
        f.hair.share(f.head_centre, f.head_radius, 16.0 / 9.0) > 0.97,
        "{:?}",
        f.hair
    );
    let below = CameraPose {
        position_m: Vec3::new(0.8, 0.0, 0.8),
        heading_rad: PI,
        pitch_rad: 0.8,
    };
    let f = figure(&below, &lens, &actor(0.0, 0.0, 0.0, h)).unwrap();
    assert!(
        f.hair.share(f.head_centre, f.head_radius, 16.0 / 9.0) < 0.05,
        "{:?}",
        f.hair
    );
}
