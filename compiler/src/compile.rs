//! Batch compilation: the director driven by the script's own blocking, sample by sample,
//! into any sink (MCAP, CSV, previews, tests).

use crate::code::CompileCode;
use dronecine_diag::{Diagnostic, Span};
use dronecine_grammar::script::{Script, ShotContent, ACTORS_MIN_APART_M};
use dronecine_grammar::vocab::CameraAngle;
use dronecine_grammar::PslCode;

use crate::blocking::Blocking;
use crate::director::Director;
use crate::reference::{ActorPose, Sample, ShotTiming};
use dronecine_profile::{Gimbal, Profile};

/// Default sampling rate of the reference.
pub const DEFAULT_RATE_HZ: f64 = 100.0;

#[derive(Clone, Copy, Debug)]
pub struct Options {
    pub rate_hz: f64,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            rate_hz: DEFAULT_RATE_HZ,
        }
    }
}

/// What a compilation produced besides the samples.
#[derive(Clone, Debug)]
pub struct Compiled {
    pub timings: Vec<ShotTiming>,
    /// Errors and warnings on the script, in source order.
    pub diagnostics: Vec<Diagnostic>,
    pub samples: usize,
    pub duration_s: f64,
}

impl Compiled {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Compile `script` for `profile`, handing every sample (and the actors' poses at its time)
/// to `sink`. A sink error stops the compilation and is returned as is.
pub fn compile<E>(
    script: &Script,
    profile: &Profile,
    opts: &Options,
    sink: impl FnMut(&Sample, &[ActorPose]) -> Result<(), E>,
) -> Result<Compiled, E> {
    compile_watched(script, profile, opts, None, sink)
}

/// [`compile`] with the director `watch`ed ([`crate::director::Watch`]): its findings are
/// among the compilation's diagnostics.
pub fn compile_watched<E>(
    script: &Script,
    profile: &Profile,
    opts: &Options,
    watch: Option<Box<dyn crate::director::Watch>>,
    mut sink: impl FnMut(&Sample, &[ActorPose]) -> Result<(), E>,
) -> Result<Compiled, E> {
    let refused = unflyable(script);
    let (Some(scene), None) = (&script.scene, &refused) else {
        return Ok(Compiled {
            timings: Vec::new(),
            diagnostics: refused.into_iter().collect(),
            samples: 0,
            duration_s: 0.0,
        });
    };
    let mut diagnostics = static_warnings(script, profile);
    diagnostics.extend(no_camera(script, profile));
    diagnostics.extend(shorter_than_a_tick(script, opts.rate_hz));
    let blocking = Blocking::new(scene);
    diagnostics.extend(collisions(&blocking));
    let mut director = Director::new(script, scene, profile);
    if let Some(w) = watch {
        director = director.watched(w);
    }
    let mut poses = blocking.poses(0.0);
    let mut framing = FramingCheck::new(script.timeline.len());
    let mut framed_as = crate::framed_as::FramedAs::new(script);
    let mut k: u64 = 0;
    let mut last_t = 0.0;
    // Guard against a timeline that never ends (it always does: every phase has an end).
    let limit = ((script.duration_s * 4.0 + 3600.0) * opts.rate_hz) as u64;
    loop {
        let t = k as f64 / opts.rate_hz;
        blocking.poses_into(t, &mut poses);
        let sample = director.step(t, &poses);
        if director.finished() || k > limit {
            break;
        }
        if framing.see(&director, &sample, &poses) {
            framed_as.see(sample.shot, &sample.position_m, &poses);
        }
        sink(&sample, &poses)?;
        last_t = t;
        k += 1;
    }
    let lens = *director.lens();
    let (timings, mut flown) = director.finish();
    let gimbal = &profile.camera.gimbal;
    let off = framing.diagnostics(script, &flown, |shot, actor| {
        framed_as.level_fix(script, shot, actor, &lens, gimbal)
    });
    diagnostics.append(&mut flown);
    diagnostics.extend(off);
    diagnostics.sort_by_key(|d| (d.span.start, d.span.end, d.code));
    Ok(Compiled {
        timings,
        diagnostics,
        samples: k as usize,
        duration_s: last_t,
    })
}

/// Why `script` cannot be compiled or flown, if it cannot: a film annotation (no scene
/// set-up), an empty script, or a scene without shots.
pub fn unflyable(script: &Script) -> Option<Diagnostic> {
    match (&script.scene, script.timeline.first()) {
        (Some(_), Some(_)) => None,
        (None, Some(first)) => Some(
            Diagnostic::error(
                CompileCode::NoScene,
                first.span,
                "this script is a film annotation: it has no stage, actors or drone to fly",
            )
            .with_label("subtitle-timed annotation")
            .with_help(
                "add a scene set-up (`stage 8m x 6m x 3m`, `actor A height 1.80m at (0, 0) \
                 facing 0deg`) and write the shots with durations (`MS on A for 4s`)",
            ),
        ),
        (None, None) => Some(
            Diagnostic::error(PslCode::EmptyScript, Span::default(), "the script is empty")
                .with_label("nothing to fly")
                .with_help(
                    "write a scene set-up (`stage 8m x 6m x 3m`, `drone ardrone2`, `actor A \
                     height 1.80m at (0, 0) facing 0deg`) and a shot (`MS on A front for 4s`)",
                ),
        ),
        (Some(scene), None) => {
            let actor = scene.actors.first().map_or("A", |a| a.name.as_str());
            // Where the first shot would go: after the set-up's last line.
            let end = (scene.actors.iter().map(|a| a.span))
                .chain(scene.blocking.iter().map(|m| m.span))
                .map(|s| s.end)
                .max()
                .unwrap_or(0);
            Some(
                Diagnostic::error(
                    PslCode::EmptyScript,
                    Span::new(end, end),
                    "the script has no shots: there is nothing to fly",
                )
                .with_label("a scene set-up without shots")
                .with_help(format!("add a shot such as `MS on {actor} front for 4s`")),
            )
        }
    }
}

/// The blocking's walks that bring two actors within [`ACTORS_MIN_APART_M`] of each other
/// (one error per pair: its first encounter).
fn collisions(blocking: &Blocking) -> Vec<Diagnostic> {
    let names = blocking.names();
    blocking
        .contacts()
        .into_iter()
        .map(|c| {
            let (walker, other) = (&names[c.walker], &names[c.other]);
            let what = if c.other_walks {
                format!("`{walker}` and `{other}` walk into each other")
            } else {
                format!("`{walker}` walks into `{other}`")
            };
            Diagnostic::error(
                CompileCode::ActorsCollide,
                c.walk_span,
                format!(
                    "{what}: {:.2} m apart at {:.1} s, where two bodies cannot pass",
                    c.distance_m, c.t_s
                ),
            )
            .with_label(format!(
                "{:.2} m from `{other}` at {:.1} s",
                c.distance_m, c.t_s
            ))
            .with_related(
                c.other_span,
                if c.other_walks {
                    format!("`{other}` walks here at the same time")
                } else {
                    format!("`{other}` stands where this puts them")
                },
            )
            .with_help(format!(
                "end the walk elsewhere, or start it when `{other}` is out of the way: actors \
                 pass at least {ACTORS_MIN_APART_M} m apart (centre to centre)"
            ))
        })
        .collect()
}

/// The shots shorter than one control period at `rate_hz`: between two ticks, such a shot
/// is never flown (or flown for one tick, as if it were longer).
fn shorter_than_a_tick(script: &Script, rate_hz: f64) -> Vec<Diagnostic> {
    // Seconds as a person reads them: to the microsecond.
    let micro = |s: f64| (s * 1e6).round() / 1e6;
    let period_s = micro(1.0 / rate_hz);
    script
        .timeline
        .iter()
        .filter(|shot| (shot.end_s - shot.start_s) * rate_hz < 1.0 - 1e-9)
        .map(|shot| {
            let lasts_s = micro(shot.end_s - shot.start_s);
            // The rate that gives the shot a tick, where a command can fly at it.
            let needed_hz = (1.0 / lasts_s).ceil();
            let faster = if needed_hz <= MAX_RATE_HZ {
                format!(", or compile and shoot it at `--rate {needed_hz}` or faster")
            } else {
                String::new()
            };
            Diagnostic::error(
                CompileCode::TooShortForRate,
                shot.span,
                format!(
                    "this shot lasts {lasts_s} s, less than one control period at {rate_hz} Hz \
                     ({period_s} s): it has no tick of its own"
                ),
            )
            .with_label(format!("shorter than a tick at {rate_hz} Hz"))
            .with_help(format!("make it last at least {period_s}s{faster}"))
        })
        .collect()
}

/// The fastest control rate a command takes (`compile --rate`, `shoot --rate`).
const MAX_RATE_HZ: f64 = 1000.0;

/// Warnings that need no flight: camera angles a drone without a gimbal cannot render.
/// For a drone that carries no camera, one warning on the first shot: the framing is a
/// nominal camera's (the lens the shots are framed for), and nothing is filmed.
fn no_camera(script: &Script, profile: &Profile) -> Option<Diagnostic> {
    let first = script.timeline.first()?;
    if profile.camera.mounted {
        return None;
    }
    let fov_x_rad = (script.scene.as_ref())
        .and_then(|s| s.lens)
        .map_or(profile.camera.fov_x_rad, |l| l.fov_x_rad);
    Some(
        Diagnostic::warning(
            CompileCode::NoCamera,
            first.span,
            format!(
                "{} carries no camera: the shots are framed for a nominal lens ({:.0}° across), \
                 and nothing is filmed",
                profile.name,
                fov_x_rad.to_degrees()
            ),
        )
        .with_label("framed for a nominal camera")
        .with_help(
            "the path is the one a camera on the drone would fly, and the framing figures are \
             that camera's; fly a drone profile that carries a camera to film the shot",
        ),
    )
}

fn static_warnings(script: &Script, profile: &Profile) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    if profile.camera.gimbal != Gimbal::None {
        return out;
    }
    for shot in &script.timeline {
        if let ShotContent::Composition(c) = &shot.content {
            if c.camera_angle != CameraAngle::EyeLevel {
                out.push(
                    Diagnostic::warning(
                        CompileCode::AngleNotRendered,
                        shot.span,
                        format!(
                            "{} has a fixed level camera: a {} cannot be rendered, the shot is \
                             flown at eye level",
                            profile.name,
                            c.camera_angle.as_str()
                        ),
                    )
                    .with_label("no gimbal to tilt the camera")
                    .with_help(
                        "remove the camera angle, or fly a drone profile with a pitch gimbal \
                         (`drone \"profiles/mine.toml\"` with `gimbal = { pitch_min_deg = …, \
                         pitch_max_deg = …, rate_degps = … }`)",
                    ),
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Vec3;

    /// A drone without a camera is told once, on the first shot, with the lens the shots
    /// are framed for; a drone with one is not.
    #[test]
    fn a_drone_without_a_camera_is_told_its_framing_is_nominal() {
        let text = "stage 8m x 6m x 3m\ndrone crazyflie21\nactor A height 1.80m at (0, 0) \
                    facing 0deg\nMS on A front for 4s\nthen dolly to MS on A 34left over 4s\n";
        let s = script(text);
        let warned = |profile: &Profile| {
            let c = compile(&s, profile, &Options::default(), |_, _| Ok::<(), ()>(())).unwrap();
            (c.diagnostics.into_iter())
                .filter(|d| d.code == CompileCode::NoCamera.code())
                .collect::<Vec<_>>()
        };
        let crazyflie = Profile::builtin("crazyflie21").unwrap();
        let told = warned(&crazyflie);
        assert_eq!(told.len(), 1, "{told:?}");
        assert!(!told[0].is_error());
        assert_eq!(told[0].span, s.timeline[0].span);
        assert!(
            told[0].message.starts_with("crazyflie21 carries no camera: the shots are framed for a nominal lens (76° across)"),
            "{}",
            told[0].message
        );
        assert!(warned(&Profile::builtin("ardrone2").unwrap()).is_empty());
    }

    fn script(text: &str) -> Script {
        let opts = dronecine_grammar::Options {
            known_drones: dronecine_profile::BUILTIN_NAMES,
            base_dir: None,
        };
        let checked = dronecine_grammar::check(text, &opts);
        assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
        checked.script.expect("a script")
    }

    /// A scene without shots compiles to an error, not a panic; the director given one
    /// anyway is done at once.
    #[test]
    fn a_scene_without_shots_is_an_error_not_a_panic() {
        let s = script(
            "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.80m at (0, 0) facing 0deg\n",
        );
        let profile = Profile::builtin("ardrone2").unwrap();
        let mut samples = 0;
        let c = compile(&s, &profile, &Options::default(), |_, _| {
            samples += 1;
            Ok::<(), ()>(())
        })
        .unwrap();
        assert_eq!((samples, c.samples), (0, 0));
        assert!(c.has_errors());
        assert_eq!(c.diagnostics[0].code, PslCode::EmptyScript);
        assert!(
            c.diagnostics[0].message.contains("no shots"),
            "{:?}",
            c.diagnostics
        );

        let scene = s.scene.as_ref().unwrap();
        let mut director = Director::new(&s, scene, &profile);
        let poses = Blocking::new(scene).poses(0.0);
        let sample = director.step(0.0, &poses);
        assert!(director.finished());
        assert!(sample.position_m.iter().all(|x| x.is_finite()));
    }

    /// Compiles `text` at 100 Hz: the diagnostics, the timings, and for the last shot its
    /// first sample and the framing it asks for then (position and velocity, solved against
    /// the blocking at that time), at the first of its samples.
    fn last_shot_start(text: &str) -> (Compiled, Sample, Vec3, Vec3) {
        let s = script(text);
        let scene = s.scene.as_ref().unwrap();
        let profile = Profile::builtin("ardrone2").unwrap();
        let mut samples = Vec::new();
        let c = compile(&s, &profile, &Options::default(), |x, _| {
            samples.push(*x);
            Ok::<(), ()>(())
        })
        .unwrap();
        let last = c.timings.last().unwrap();
        let first = *samples
            .iter()
            .find(|x| x.t_s >= last.start_s - 1e-9)
            .unwrap();
        let ShotContent::Composition(comp) = &s.timeline[last.index].content else {
            panic!("a composition");
        };
        let lens = crate::camera::Lens::new(profile.camera.fov_x_rad, profile.camera.aspect);
        let gimbal = profile.camera.gimbal;
        let poses = Blocking::new(scene).poses(first.t_s);
        let names: Vec<&str> = scene.actors.iter().map(|a| a.name.as_str()).collect();
        let v = crate::framing::solve(comp, &names, &poses, &lens, &gimbal).unwrap();
        let p = crate::framing::position_m(&v, &poses, &lens, &gimbal);
        let vel = crate::framing::velocity_mps(&v, &poses, &lens, &gimbal);
        (c, first, p, vel)
    }

    /// A cut while the actor turns: the repositioning flight goes where the framing will be
    /// when it arrives, and the shot starts on it. Planned to where the framing is when the
    /// flight sets off, it would arrive mid-turn, metres from where it has to be, and the
    /// framing would swing round the turning actor faster than the drone follows.
    #[test]
    fn a_cut_while_the_actor_turns_starts_on_the_framing() {
        let (c, first, framing, _) = last_shot_start(
            "stage 10m x 12m x 4m\ndrone ardrone2\n\
             actor A height 1.80m at (-1.5, -2) facing 120deg\n\
             at 8s A turns to -75deg over 4s\n\
             MCU on A for 6s\n\
             cut to LS on A 34left for 8s\n",
        );
        assert!(!c.has_errors(), "{:#?}", c.diagnostics);
        let start = c.timings.last().unwrap().start_s;
        assert!(
            start >= 12.0,
            "the shot starts once the turn is done: {start}"
        );
        let off_m = (Vec3::from(first.position_m) - framing).norm();
        assert!(off_m < 0.05, "{off_m} m off the framing at the start");
    }

    /// A cut while the actor walks: the flight arrives on the framing moving with it (it
    /// merges), so the shot starts on its framing at its speed.
    #[test]
    fn a_cut_while_the_actor_walks_arrives_moving_with_the_framing() {
        let (c, first, framing, framing_v) = last_shot_start(
            "stage 12m x 10m x 3m\ndrone ardrone2\n\
             actor A height 1.80m at (-2, 0) facing 0deg\n\
             at 7s A walks to (1.5, 0) over 8s\n\
             MS on A front for 6s\n\
             cut to MS on A left for 10s\n",
        );
        assert!(!c.has_errors(), "{:#?}", c.diagnostics);
        let start = c.timings.last().unwrap().start_s;
        assert!(start < 15.0, "the shot starts while A walks: {start}");
        assert!(framing_v.norm() > 0.3, "A walks: {framing_v}");
        let off_m = (Vec3::from(first.position_m) - framing).norm();
        let off_mps = (Vec3::from(first.velocity_mps) - framing_v).norm();
        assert!(off_m < 0.05, "{off_m} m off the framing at the start");
        assert!(
            off_mps < 0.1,
            "{off_mps} m/s off the framing's velocity at the start"
        );
    }

    /// A cut to an actor seen from behind as they turn round: the flight's plans do not
    /// settle (the framing sweeps round with the turn), and it arrives at the first plan's
    /// time, but no sooner than the drone can fly its way at its limits: held to the first
    /// plan's time, it would fall behind the framing at the shot's start.
    #[test]
    fn a_flight_that_does_not_settle_is_no_faster_than_the_drone() {
        let (c, first, framing, _) = last_shot_start(
            "stage 10m x 12m x 4m\ndrone ardrone2\n\
             actor A height 1.56m at (-0.47, -2.03) facing 148deg\n\
             actor B height 1.77m at (-0.28, 0.85) facing -134deg\n\
             at 25.4s B turns to 138deg over 4s\n\
             at 1.3s A turns to -140deg over 4s\n\
             MS on A for 6s\n\
             then hold to high angle MS on A and B over 10s\n\
             then hold to MCU on A and B over 10s\n\
             cut to FS on B back screen right for 8s\n",
        );
        assert!(!c.has_errors(), "{:#?}", c.diagnostics);
        let off_m = (Vec3::from(first.position_m) - framing).norm();
        assert!(off_m < 0.05, "{off_m} m off the framing at the start");
    }

    /// A cut while an actor walks across the short way to the next framing: the flight
    /// keeps clear of where the actor is as it passes, and the profile's distance from them
    /// throughout. Planned against where they stand and where they stop, it would fly the
    /// short arc through their way, inside the profile's distance. The flight arrives after
    /// the actor has passed, sooner than the long way round them would.
    #[test]
    fn a_cut_keeps_clear_of_an_actor_who_walks_across_its_way() {
        let s = script(
            "stage 10m x 8m x 4m\ndrone ardrone2-outdoor\n\
             actor A height 1.6m at (-1.31, 0.35) facing 90deg\n\
             actor B height 1.91m at (-0.57, -1.02) facing 73deg\n\
             at 17.6s A walks to (-3.22, -1.21) over 4s\n\
             FS on A front for 16s\n\
             cut to MLS on B left for 12s\n",
        );
        let profile = Profile::builtin("ardrone2-outdoor").unwrap();
        let safety_m = profile.safety.actor_distance_m;
        let mut closest_m = f64::INFINITY;
        let c = compile(&s, &profile, &Options::default(), |x, actors| {
            let [px, py, pz] = x.position_m;
            for a in actors {
                let [ax, ay, az] = a.position_m;
                if pz <= az + a.height_m + safety_m {
                    closest_m = closest_m.min(dronecine_math::norm_xy(px - ax, py - ay));
                }
            }
            Ok::<(), ()>(())
        })
        .unwrap();
        assert!(!c.has_errors(), "{:#?}", c.diagnostics);
        let shot = c.timings.last().unwrap();
        let (start_s, end_s) = shot.reposition.unwrap();
        assert!(
            end_s - start_s > 4.5 && end_s - start_s < 8.0,
            "{start_s}..{end_s}"
        );
        assert!(end_s > 21.6, "A has passed: {end_s}");
        assert!(closest_m >= safety_m - 0.01, "{closest_m} m from an actor");
    }

    /// A film annotation and an empty script are refused, each for what it is.
    #[test]
    fn annotations_and_empty_scripts_are_refused_for_what_they_are() {
        let annotation = script("1 00:00:01 --> 00:00:05 LS on Rick 34left screen left\n");
        let d = unflyable(&annotation).unwrap();
        assert_eq!(d.code, CompileCode::NoScene);
        let empty = script("# nothing yet\n");
        let d = unflyable(&empty).unwrap();
        assert_eq!(d.code, PslCode::EmptyScript);
        assert!(d.message.contains("empty"), "{}", d.message);
        let flyable = script(
            "stage 8m x 6m x 3m\nactor A height 1.80m at (0, 0) facing 0deg\nMS on A for 2s\n",
        );
        assert!(unflyable(&flyable).is_none());
    }
}

/// Where each hold puts its actors on screen, against where the script puts them: the
/// reference's own camera (its position, heading and pitch) projecting each framed actor's
/// aim point, tick by tick, as `shoot` measures its framing error on set.
struct FramingCheck {
    shots: Vec<HoldFraming>,
    targets: Vec<crate::framing::ScreenTarget>,
}

#[derive(Clone, Debug, Default)]
struct HoldFraming {
    sum_sq: f64,
    n: u64,
    worst: Option<Miss>,
}

/// A hold's worst tick.
#[derive(Clone, Copy, Debug)]
struct Miss {
    /// Screen distance (infinite behind the camera).
    distance: f64,
    actor: usize,
    /// Where the actor landed on screen (`None`: behind the camera)…
    got: Option<[f64; 2]>,
    /// …and where the script puts it.
    want: [f64; 2],
    t_s: f64,
}

impl FramingCheck {
    fn new(shots: usize) -> FramingCheck {
        FramingCheck {
            shots: vec![HoldFraming::default(); shots],
            targets: Vec::new(),
        }
    }

    /// Measures a tick; true if it is a hold's (after its settling).
    fn see(&mut self, director: &Director, sample: &Sample, actors: &[ActorPose]) -> bool {
        let position_m = crate::camera::Vec3::from(sample.position_m);
        if !director.hold_targets(actors, &position_m, &mut self.targets) {
            return false;
        }
        // The camera's axes only in holds (a sine and a cosine each).
        let camera = crate::camera::CameraPose {
            position_m,
            heading_rad: sample.heading_rad,
            pitch_rad: sample.camera_pitch_rad,
        }
        .frame();
        let Some(hold) = self.shots.get_mut(sample.shot) else {
            return true;
        };
        for target in &self.targets {
            let got = camera.project(director.lens(), &target.point_m);
            let d = got.map_or(f64::INFINITY, |g| {
                (g[0] - target.screen[0]).hypot(g[1] - target.screen[1])
            });
            hold.sum_sq += framing_miss_sq(got, target.screen);
            hold.n += 1;
            if hold.worst.is_none_or(|w| d > w.distance) {
                hold.worst = Some(Miss {
                    distance: d,
                    actor: target.actor,
                    got,
                    want: target.screen,
                    t_s: sample.t_s,
                });
            }
        }
        true
    }

    /// A warning on each hold whose actors land, RMS over the hold, more than
    /// [`FRAMING_TOLERANCE`] from their screen points; none on a shot that already has an
    /// error (its framing's failure is that error's consequence).
    fn diagnostics(
        &self,
        script: &Script,
        flown: &[Diagnostic],
        level_fix: impl Fn(usize, usize) -> Option<crate::framed_as::LevelFix>,
    ) -> Vec<Diagnostic> {
        let names = script
            .scene
            .as_ref()
            .map(|s| s.actors.iter().map(|a| a.name.as_str()).collect::<Vec<_>>())
            .unwrap_or_default();
        let mut out = Vec::new();
        for (index, (hold, shot)) in self.shots.iter().zip(&script.timeline).enumerate() {
            let Some(Miss {
                distance: worst,
                actor,
                got,
                want,
                t_s,
            }) = hold.worst
            else {
                continue;
            };
            let rms = (hold.sum_sq / hold.n as f64).sqrt();
            let failed = flown.iter().any(|d| d.is_error() && d.span == shot.span);
            if !(rms > FRAMING_TOLERANCE) || failed {
                continue;
            }
            let who = names.get(actor).copied().unwrap_or("an actor");
            let message = match got {
                Some(g) => format!(
                    "{who} lands at ({:.2}, {:.2}) on screen, {worst:.2} from ({:.2}, {:.2}) \
                     where this shot puts them (at {t_s:.1} s; {rms:.2} RMS over the hold)",
                    g[0], g[1], want[0], want[1]
                ),
                None => format!(
                    "{who} is behind the camera at {t_s:.1} s, not at ({:.2}, {:.2}) on screen \
                     ({rms:.2} RMS over the hold)",
                    want[0], want[1]
                ),
            };
            let off_in_height =
                got.is_some_and(|g| (g[1] - want[1]).abs() > (g[0] - want[0]).abs());
            let help = if off_in_height {
                // Without roll, one actor's screen height is aimed exactly and
                // the other's follows from the geometry. (Writing the height it lands at
                // moves the solve's screen points and need not frame at all.) The same size
                // for both is no fix over a shoulder: the camera keeps the background's size,
                // so it would come as close to the background actor as to the foreground one
                // asked (`compile::size_off`).
                let why = "the camera has no roll: two actors land at their screen heights only \
                           when it sees their aim points (the centres of their framed bands) at \
                           the same elevation";
                match level_fix(index, actor) {
                    Some(fix) => format!(
                        "{why}; write {who}'s size as {}: its band centres at {:.2} m, near \
                         {}'s {:.2} m",
                        fix.size.as_str(),
                        fix.centre_m,
                        names.get(fix.other).copied().unwrap_or("the other actor"),
                        fix.other_centre_m
                    ),
                    None => format!(
                        "{why}; give the actors sizes whose bands centre at about the same \
                         height, or accept the offset"
                    ),
                }
            } else {
                "no camera position puts the actors at these screen points with these sizes and \
                 profiles: move the screen points, change a size, or choose profiles that agree \
                 (the camera must be on the side each profile names)"
                    .to_string()
            };
            out.push(
                Diagnostic::warning(CompileCode::FramingOff, shot.span, message)
                    .with_label(format!("{who} off their screen point"))
                    .with_help(help),
            );
        }
        out
    }
}

/// The RMS screen distance (the frame spans 2 in x and y; the thirds are 1/3 from the centre)
/// above which a hold's framing is reported as off. The shipped two-actor scenes hold 0.008
/// (`two-actors.psl`) and 0.067 (`two-heights.psl`: actors of different heights under a level
/// camera).
pub const FRAMING_TOLERANCE: f64 = 0.1;

/// The most one framed actor's miss counts, squared: the frame's diagonal (the frame spans 2
/// in x and y). An actor off the frame is off it however far its projection lands (near the
/// camera's plane it lands hundreds of frames away, and one such tick would outweigh a whole
/// flight's RMS), and an actor behind the camera counts as much.
pub const FRAMING_MISS_MAX_SQ: f64 = 8.0;

/// The squared screen distance that the framing error counts for an actor that lands at `got`
/// (`None`: behind the camera) where the script puts it at `want`, at most
/// [`FRAMING_MISS_MAX_SQ`]; NaN stays NaN (the caller leaves such a tick out). `compile`'s
/// check and `shoot`'s report both count misses with it.
pub fn framing_miss_sq(got: Option<[f64; 2]>, want: [f64; 2]) -> f64 {
    match got {
        Some(g) => {
            let sq = (g[0] - want[0]).powi(2) + (g[1] - want[1]).powi(2);
            if sq.is_nan() {
                sq
            } else {
                sq.min(FRAMING_MISS_MAX_SQ)
            }
        }
        None => FRAMING_MISS_MAX_SQ,
    }
}
