//! `dronecine compile`: script → checked → compiled reference → MCAP (+ CSV, previews).
//!
//! Everything is streamed: the director hands each sample to the MCAP and CSV writers as it
//! is made; previews get a decimated copy (10 Hz). Writers go through temporary files, so a
//! failed compilation (or a crash) never leaves an output that looks complete.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use dronecine_compiler::compile::{self, Compiled, Options};
use dronecine_compiler::reference::ShotTiming;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_diag as diag;
use dronecine_diag::Severity;
use dronecine_grammar::script::{DroneRef, Scene, Script, ShotContent};
use dronecine_mcap::output::{CsvWriter, McapWriter, RunInfo};
use dronecine_preview::{self as preview, PreviewInput, ShotInfo, ShotKind};
use dronecine_profile::{Profile, ProfileError, DEFAULT_NAME};

use crate::check;

pub struct Args<'a> {
    pub file: &'a Path,
    pub out: &'a Path,
    pub rate_hz: f64,
    pub preview: Option<&'a Path>,
    pub csv: Option<&'a Path>,
    pub allow_infeasible: bool,
    pub color: bool,
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    errln!("error: {msg}");
    ExitCode::FAILURE
}

/// Resolve the script's drone profile: a built-in name or a TOML file next to the script.
/// Errors are rendered here (against the TOML text when there is one).
pub fn load_profile(
    scene: &Scene,
    base: &Path,
    script_name: &str,
    script_text: &str,
    color: bool,
) -> Result<Profile, ExitCode> {
    match &scene.drone {
        None => Ok(Profile::builtin(DEFAULT_NAME).expect("the default profile is built in")),
        Some(DroneRef::Builtin { name }) => Profile::builtin(name)
            .ok_or_else(|| fail(format!("`{name}` is not a built-in drone profile"))),
        Some(DroneRef::File { path }) => {
            let full = base.join(path);
            match Profile::load(&full) {
                Ok((profile, source, warnings)) => {
                    if !warnings.is_empty() {
                        let name = full.display().to_string();
                        err!("{}", diag::render(&name, &source, &warnings, color, 100));
                    }
                    Ok(profile)
                }
                Err(e @ ProfileError::Unreadable { .. }) => {
                    let d = e.not_found(Default::default());
                    if let Some(d) = d {
                        err!(
                            "{}",
                            diag::render(script_name, script_text, &[d], color, 100)
                        );
                    }
                    Err(ExitCode::FAILURE)
                }
                Err(ProfileError::Invalid {
                    source,
                    diagnostics,
                }) => {
                    let name = full.display().to_string();
                    err!("{}", diag::render(&name, &source, &diagnostics, color, 100));
                    errln!("error: the drone profile `{name}` is not valid");
                    Err(ExitCode::FAILURE)
                }
            }
        }
    }
}

/// The profile named or pointed at by `option` (`--profile`, `--plant`), through the
/// compiler's loader (which renders profile errors as diagnostics). A name that is neither
/// built in nor a file is refused with the built-in names and the closest of them.
pub fn profile_arg(option: &str, arg: &str, color: bool) -> Result<Profile, ExitCode> {
    let builtin = Profile::builtin(arg).is_some();
    let is_file = !builtin && (arg.ends_with(".toml") || Path::new(arg).exists());
    if !builtin && !is_file {
        return Err(fail(unknown_profile(option, arg)));
    }
    let drone = if is_file {
        DroneRef::File {
            path: arg.to_string(),
        }
    } else {
        DroneRef::Builtin {
            name: arg.to_string(),
        }
    };
    let scene = Scene {
        stage: dronecine_grammar::script::Stage { size_m: [1.0; 3] },
        lens: None,
        drone: Some(drone),
        actors: Vec::new(),
        blocking: Vec::new(),
    };
    load_profile(&scene, Path::new(""), option, arg, color)
}

/// The message for `option NAME` that names no built-in profile and no file: the closest
/// built-in names, all of them, and how to give a file instead.
fn unknown_profile(option: &str, name: &str) -> String {
    use dronecine_diag::suggest;
    use dronecine_profile::BUILTIN_NAMES;
    let list = suggest::or_list(BUILTIN_NAMES);
    let help = match suggest::did_you_mean(name, BUILTIN_NAMES.iter().copied()) {
        Some(guess) => format!(
            "{guess} (built-in profiles: {list}; or give a profile's TOML file: \
             `{option} mine.toml`)"
        ),
        None => format!(
            "built-in profiles are {list}; for your own, give its TOML file: \
             `{option} profiles/mine.toml`"
        ),
    };
    format!(
        "{option} `{}` is not a built-in drone profile, nor a file\n  help: {help}",
        suggest::shorten(name)
    )
}

/// A script that checks clean, has a scene, and names a drone profile that loads: what
/// `compile`, `shoot` and `emulate` start from, its coverages expanded for the profile.
pub struct Loaded {
    pub file: check::FileResult,
    pub profile: Profile,
    /// The script as it is flown: each `coverage` line expanded into its shots
    /// ([`dronecine_compiler::coverage::expand`]).
    expanded: Script,
    /// What the expansion found (`compile::coverage_overruns`).
    expansion: Vec<diag::Diagnostic>,
}

impl Loaded {
    /// The script as it is flown, its coverages expanded.
    pub fn script(&self) -> &Script {
        &self.expanded
    }

    pub fn scene(&self) -> &Scene {
        self.expanded.scene.as_ref().expect("load_scene checked it")
    }

    /// The script check's warnings and the expansion's, to tell with the compiler's.
    pub fn script_warnings(&self) -> Vec<diag::Diagnostic> {
        let mut all = self.file.checked.diagnostics.clone();
        all.extend(self.expansion.iter().cloned());
        all
    }
}

/// The script check's warnings (it had no errors, or nothing is compiled) and the compiler's
/// diagnostics, in the order of the script's lines (stable: each side keeps its own order
/// where two share a place).
pub fn with_script_warnings(
    checked: &[diag::Diagnostic],
    compiled: &[diag::Diagnostic],
) -> Vec<diag::Diagnostic> {
    let mut all: Vec<diag::Diagnostic> = checked.iter().chain(compiled).cloned().collect();
    all.sort_by_key(|d| d.span.start);
    all
}

/// Checks `path`, requires a scene (and with `shots`, a shot), loads its profile; prints the
/// diagnostics otherwise and ends with "nothing was {what}". `emulate` takes a scene without
/// shots (its actors and their blocking); `compile` and `shoot` need shots.
pub fn load_scene(path: &Path, color: bool, what: &str, shots: bool) -> Result<Loaded, ExitCode> {
    let r = check::check_file(path);
    if r.checked.has_errors() || r.checked.script.is_none() {
        let lister = check::lister(&r.name);
        err!(
            "{}",
            diag::render_listed(
                &r.name,
                &r.text,
                &r.checked.diagnostics,
                color,
                100,
                Some(&lister)
            )
        );
        errln!("error: `{}` has errors; nothing was {what}", r.name);
        return Err(ExitCode::FAILURE);
    }
    let script = r.checked.script.as_ref().expect("checked above");
    let refused = match compile::unflyable(script) {
        Some(d) if shots => Some(d),
        // Without shots to fly, only the scene is needed: its help names no shot.
        Some(mut d) if script.scene.is_none() => {
            d.label = Some("no scene set-up".into());
            d.help = Some(
                "write a scene set-up (`stage 8m x 6m x 3m`, `drone ardrone2`, `actor A height \
                 1.80m at (0, 0) facing 0deg`); shots are not needed here"
                    .into(),
            );
            Some(d)
        }
        _ => None,
    };
    let (Some(scene), None) = (&script.scene, &refused) else {
        let d: Vec<_> = refused.into_iter().collect();
        err!("{}", diag::render(&r.name, &r.text, &d, color, 100));
        let has = if shots { "nothing to fly" } else { "no scene" };
        errln!("error: `{}` has {has}; nothing was {what}", r.name);
        return Err(ExitCode::FAILURE);
    };
    let base = crate::files::base_dir(path);
    let profile = load_profile(scene, &base, &r.name, &r.text, color)?;
    let (expanded, expansion) = dronecine_compiler::coverage::expand(script, &profile);
    Ok(Loaded {
        file: r,
        profile,
        expanded,
        expansion,
    })
}

pub fn run(a: &Args) -> ExitCode {
    if !(a.rate_hz.is_finite() && a.rate_hz >= 1.0 && a.rate_hz <= 1000.0) {
        return fail(format!(
            "--rate {} is outside 1–1000 Hz; the servo runs at 100 Hz (the default)",
            a.rate_hz
        ));
    }
    let loaded = match load_scene(a.file, a.color, "compiled", true) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let (r, profile) = (&loaded.file, loaded.profile.clone());
    let (script, scene) = (loaded.script(), loaded.scene());

    let script_name = a
        .file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| r.name.clone());
    let actor_names: Vec<String> = scene.actors.iter().map(|x| x.name.clone()).collect();
    let lens = match scene.lens {
        Some(l) => dronecine_compiler::camera::Lens::new(l.fov_x_rad, l.aspect),
        None => {
            dronecine_compiler::camera::Lens::new(profile.camera.fov_x_rad, profile.camera.aspect)
        }
    };
    let info = RunInfo {
        script_name: &script_name,
        script_text: &r.text,
        profile_name: &profile.name,
        rate_hz: a.rate_hz,
        lens,
        stage: scene.stage,
        actor_names: &actor_names,
    };
    // Every output's place first: a command that cannot write all its outputs writes none.
    let places = a
        .preview
        .map_or(Ok(()), |d| crate::files::prepare_folder(d, "--preview"))
        .and_then(|()| crate::files::prepare_output(a.out, "-o"))
        .and_then(|()| {
            a.csv
                .map_or(Ok(()), |c| crate::files::prepare_output(c, "--csv"))
        });
    if let Err(e) = places {
        return fail(e);
    }
    let mut mcap = match McapWriter::create(a.out, &info) {
        Ok(w) => w,
        Err(e) => return fail(e),
    };
    let mut csv = match a.csv.map(CsvWriter::create).transpose() {
        Ok(w) => w,
        Err(e) => return fail(e),
    };
    let every = ((a.rate_hz / 10.0).round() as usize).max(1);
    let mut kept: Vec<Sample> = Vec::new();
    let mut kept_actors: Vec<Vec<ActorPose>> = Vec::new();
    let mut n = 0usize;
    let opts = Options { rate_hz: a.rate_hz };
    let compiled = dronecine_film::compile(script, &profile, &opts, |s, actors| {
        mcap.write(s, actors)?;
        if let Some(c) = csv.as_mut() {
            c.write(s)?;
        }
        if a.preview.is_some() && n.is_multiple_of(every) {
            kept.push(*s);
            kept_actors.push(actors.to_vec());
        }
        n += 1;
        Ok::<(), std::io::Error>(())
    });
    let mut compiled = match compiled {
        Ok(c) => c,
        Err(e) => return fail(e),
    };
    let errors = compiled.has_errors();
    if errors && a.allow_infeasible {
        for d in &mut compiled.diagnostics {
            d.severity = Severity::Warning;
        }
    }
    // The language's warnings (a move timed with `for`, …) and the compiler's together, in
    // the script's order.
    let shown = with_script_warnings(&loaded.script_warnings(), &compiled.diagnostics);
    if !shown.is_empty() {
        err!("{}", diag::render(&r.name, &r.text, &shown, a.color, 100));
    }
    if errors && !a.allow_infeasible {
        errln!(
            "error: `{}` cannot be flown by {}; nothing was written (--allow-infeasible writes \
             it anyway)",
            r.name,
            profile.name
        );
        return ExitCode::FAILURE;
    }
    // The previews before the reference and the table are renamed into place: previews that
    // fail leave neither (a writer dropped unfinished removes its temporary file).
    let mut written: Vec<PathBuf> = vec![a.out.to_path_buf()];
    written.extend(a.csv.map(Path::to_path_buf));
    if let Some(dir) = a.preview {
        let shots = shot_infos(script, &r.text, &compiled.timings);
        let input = PreviewInput {
            samples: &kept,
            actors: &kept_actors,
            actor_names: &actor_names,
            stage: scene.stage,
            lens,
            limits: &profile.limits,
            model: &profile.model,
            shots: &shots,
        };
        match preview::write_previews(dir, &input) {
            Ok(paths) => written.extend(paths),
            Err(e) => return fail(format!("cannot write previews to `{}`: {e}", dir.display())),
        }
    }
    if let Err(e) = mcap.finish() {
        return fail(e);
    }
    if let Some(c) = csv {
        if let Err(e) = c.finish() {
            return fail(e);
        }
    }
    outln!(
        "{}",
        summary(&r.name, script, &profile, &compiled, a.rate_hz)
    );
    for p in written {
        let size = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        outln!("  wrote {} ({})", p.display(), human_bytes(size));
    }
    ExitCode::SUCCESS
}

fn summary(name: &str, script: &Script, profile: &Profile, c: &Compiled, rate_hz: f64) -> String {
    let flights: Vec<f64> = c
        .timings
        .iter()
        .filter_map(|t| t.reposition.map(|(a, b)| b - a))
        .collect();
    let shots = script.timeline.len();
    let repositioning = match flights.len() {
        0 => "no repositioning flight".to_string(),
        n => format!(
            "{n} repositioning {}, {:.1} s",
            if n == 1 { "flight" } else { "flights" },
            // Summed from +0.0 (an empty `sum()` of floats is −0.0).
            flights.iter().fold(0.0, |a, b| a + b)
        ),
    };
    format!(
        "{name}: {shots} {} for {}, {:.1} s of reference ({:.1} s as written; {repositioning}), \
         {} samples at {} Hz",
        if shots == 1 { "shot" } else { "shots" },
        profile.name,
        c.duration_s,
        script.duration_s,
        c.samples,
        rate_hz
    )
}

fn human_bytes(n: u64) -> String {
    if n >= 1 << 20 {
        format!("{:.1} MB", n as f64 / (1 << 20) as f64)
    } else {
        format!("{:.1} kB", n as f64 / 1024.0)
    }
}

/// The previews' list of shots and repositioning flights, labelled with the PSL text and
/// named by shot type.
fn shot_infos(script: &Script, src: &str, timings: &[ShotTiming]) -> Vec<ShotInfo> {
    let mut out = Vec::new();
    for t in timings {
        let shot = &script.timeline[t.index];
        let kind = match &shot.content {
            ShotContent::Path(_) => ShotKind::Path,
            _ if script.moves_camera(t.index) => ShotKind::Transition,
            _ => ShotKind::Hold,
        };
        let to = preview::shot_type(&shot.content);
        // A camera move starts on the composition before it.
        let from = match kind {
            ShotKind::Transition => t.index.checked_sub(1).map_or(to.clone(), |i| {
                preview::shot_type(&script.timeline[i].content)
            }),
            _ => to.clone(),
        };
        if let Some((a, b)) = t.reposition {
            out.push(ShotInfo {
                start_s: a,
                end_s: b,
                label: format!("repositioning flight to shot {}", t.index + 1),
                kind: ShotKind::Reposition,
                framing: [from.clone(), from.clone()],
            });
        }
        let label = shot.label(src);
        out.push(ShotInfo {
            start_s: t.start_s,
            end_s: t.end_s,
            label,
            kind,
            framing: [from, to],
        });
    }
    out
}
