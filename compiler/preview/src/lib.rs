//! Previews of a compiled reference, for `dronecine compile … --preview DIR`: what a director
//! checks before anything flies.
//!
//! [`write_previews`] writes four images, each as SVG and PNG:
//! - `top.svg`/`.png`: the stage seen from above (x–y), the camera path coloured by shot, the
//!   camera heading as a tick every second, the actors' start positions, trajectories and
//!   facing arrows;
//! - `side.svg`/`.png`: two elevations (x–z seen from −y, y–z seen from +x) with the stage, the
//!   path, the camera's looking direction every second and the actors standing at their start
//!   (and end) positions;
//! - `timeseries.svg`/`.png`: horizontal speed, vertical speed, horizontal acceleration, tilt,
//!   heading, heading rate and altitude over time, with the profile's limits drawn and the
//!   shot boundaries marked;
//! - `storyboard.svg`/`.png`: a contact sheet, one row per shot, the camera's view at the
//!   start, middle and end of the shot with the actors drawn as simple figures (see
//!   [`figure`]: a face, or the back of a head in hair), each named clear of every figure,
//!   labelled with the shot's PSL text and each frame captioned with its shot type
//!   ([`shot_type`]).
//!
//! The SVGs are written by hand ([`svg`]); the PNGs are the same SVGs rasterised by `resvg`
//! with an embedded font (DejaVu Sans, a subset: `assets/DejaVuSans-subset.ttf`), so the
//! output needs no system font and is byte-for-byte deterministic. Each file is written to a
//! temporary name in the directory and renamed into place.
//!
//! The samples may be decimated (any rate): every quantity is read from the samples, none is
//! differentiated from an assumed rate.

pub mod figure;
mod labels;
mod plan;
mod plots;
mod raster;
mod storyboard;
pub mod svg;

use std::fs;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

use dronecine_grammar::script::{OrbitCenter, PathShape, ShotContent, Stage};

use dronecine_compiler::camera::Lens;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_profile::{Limits, Model};

pub use plots::tilt_commands_rad;
pub use raster::{svg_to_png, Rasteriser};
pub use resvg::usvg;
pub use storyboard::frame_sample_indices;

/// What kind of stretch of the timeline a shot entry is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShotKind {
    /// `for Ns`: a composition held.
    Hold,
    /// `then <move> to …`: a camera move within a shot.
    Transition,
    /// `path …`: a hand-crafted path.
    Path,
    /// A repositioning flight the compiler inserted before a cut (it belongs to the shot it
    /// flies to).
    Reposition,
}

impl ShotKind {
    pub fn as_str(self) -> &'static str {
        match self {
            ShotKind::Hold => "hold",
            ShotKind::Transition => "transition",
            ShotKind::Path => "path",
            ShotKind::Reposition => "reposition",
        }
    }
}

/// One stretch of the timeline, in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct ShotInfo {
    pub start_s: f64,
    pub end_s: f64,
    /// The PSL line (or a description of the repositioning).
    pub label: String,
    pub kind: ShotKind,
    /// What the camera frames at the entry's start and at its end, named by shot type
    /// ([`shot_type`]): the same twice for a hold or a path, the two compositions of a camera
    /// move, the shot flown to for a repositioning.
    pub framing: [String; 2],
}

/// A shot's type, from its composition: one framing of one actor is a single ("single on
/// A"), of two a two-shot ("two-shot of A and B"); two framings are an over-the-shoulder shot
/// over the first framing's actor, the foreground ("OTS over A (on B)"); a path is named by
/// its kind and what the camera looks at ("orbit around A", "path looking at B"; an orbit
/// around an actor that does not look at them is "looking ahead").
pub fn shot_type(content: &ShotContent) -> String {
    let path = match content {
        ShotContent::Composition(c) => {
            let actors = |i: usize| -> Vec<&str> {
                c.framings.get(i).map_or(Vec::new(), |f| {
                    f.subjects.iter().map(|s| s.actor.as_str()).collect()
                })
            };
            return match (actors(0).as_slice(), actors(1).as_slice()) {
                ([a], []) => format!("single on {a}"),
                ([a, b], []) => format!("two-shot of {a} and {b}"),
                ([a], [b]) => format!("OTS over {a} (on {b})"),
                _ => format!("{} actors", c.actors().count()),
            };
        }
        ShotContent::Coverage(c) => return format!("coverage of {} and {}", c.a, c.b),
        ShotContent::Path(p) => p,
    };
    let around = match &path.shape {
        PathShape::Orbit {
            center: OrbitCenter::Actor { name },
            ..
        } => Some(name.as_str()),
        _ => None,
    };
    let kind = match &path.shape {
        PathShape::Square { .. } => "square path".to_string(),
        PathShape::Helix { .. } => "helix".to_string(),
        PathShape::Orbit { .. } => match around {
            Some(a) => format!("orbit around {a}"),
            None => "orbit".to_string(),
        },
        PathShape::Waypoints { .. } => "path".to_string(),
    };
    // An orbit around an actor looks at them unless it says otherwise.
    match (path.looking_at.as_deref(), around) {
        (Some(b), _) if Some(b) != around => format!("{kind} looking at {b}"),
        (None, Some(_)) => format!("{kind} looking ahead"),
        _ => kind,
    }
}

/// Everything the previews draw.
#[derive(Clone, Copy, Debug)]
pub struct PreviewInput<'a> {
    /// The reference, in time order (any rate).
    pub samples: &'a [Sample],
    /// The actors at each sample: `actors[i][k]` is actor `k` (named `actor_names[k]`) at
    /// `samples[i].t_s`. Either empty (no actors) or as long as `samples`, each entry as long
    /// as `actor_names`.
    pub actors: &'a [Vec<ActorPose>],
    pub actor_names: &'a [String],
    pub stage: Stage,
    pub lens: Lens,
    pub limits: &'a Limits,
    pub model: &'a Model,
    /// The shots and repositionings, in time order.
    pub shots: &'a [ShotInfo],
}

impl PreviewInput<'_> {
    /// Checks the shapes the drawing code relies on.
    fn validate(&self) -> io::Result<()> {
        let bad = |msg: String| Err(io::Error::new(io::ErrorKind::InvalidInput, msg));
        if self.samples.is_empty() {
            return bad("preview: no samples to draw".into());
        }
        if !self.actors.is_empty() && self.actors.len() != self.samples.len() {
            return bad(format!(
                "preview: {} actor entries for {} samples",
                self.actors.len(),
                self.samples.len()
            ));
        }
        if let Some((i, a)) = self
            .actors
            .iter()
            .enumerate()
            .find(|(_, a)| a.len() != self.actor_names.len())
        {
            return bad(format!(
                "preview: sample {i} has {} actors, {} names given",
                a.len(),
                self.actor_names.len()
            ));
        }
        if !(self.lens.fov_x_rad().is_finite()
            && self.lens.fov_x_rad() > 0.0
            && self.lens.fov_x_rad() < std::f64::consts::PI
            && self.lens.aspect().is_finite()
            && self.lens.aspect() > 0.0)
        {
            return bad(format!("preview: unusable lens {:?}", self.lens));
        }
        Ok(())
    }

    /// Actor `k` at sample `i`, if the input has actors.
    fn actor(&self, i: usize, k: usize) -> Option<&ActorPose> {
        self.actors.get(i).and_then(|a| a.get(k))
    }
}

/// Colours of the shots (cycled), chosen to stay apart from each other and from the grey of
/// repositionings.
const SHOT_COLORS: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2",
];
/// Colour of repositioning flights and of samples outside every shot.
const REPOSITION_COLOR: &str = "#8a8a8a";
/// Colours of the actors (cycled).
const ACTOR_COLORS: [&str; 6] = [
    "#3b5ba5", "#b5443a", "#3f8f4f", "#8a5aa8", "#c07a1a", "#2a8a8a",
];

fn actor_color(k: usize) -> &'static str {
    ACTOR_COLORS[k % ACTOR_COLORS.len()]
}

/// Colour of shot entry `index`.
fn shot_color(shots: &[ShotInfo], index: usize) -> &'static str {
    match shots.get(index) {
        Some(s) if s.kind == ShotKind::Reposition => REPOSITION_COLOR,
        Some(_) => {
            let n = shots[..index]
                .iter()
                .filter(|s| s.kind != ShotKind::Reposition)
                .count();
            SHOT_COLORS[n % SHOT_COLORS.len()]
        }
        None => REPOSITION_COLOR,
    }
}

/// Short names of the shot entries: the shots numbered from 1 in order, a repositioning
/// named after the shot it flies to (`R→3`).
fn shot_names(shots: &[ShotInfo]) -> Vec<String> {
    let mut n = 0;
    let mut names = Vec::with_capacity(shots.len());
    for s in shots {
        if s.kind == ShotKind::Reposition {
            names.push(String::new());
        } else {
            n += 1;
            names.push(n.to_string());
        }
    }
    for i in 0..shots.len() {
        if shots[i].kind == ShotKind::Reposition {
            let next = shots[i + 1..]
                .iter()
                .filter(|s| s.kind != ShotKind::Reposition)
                .count();
            names[i] = if next > 0 {
                format!("R→{}", n - next + 1)
            } else {
                "R".to_string()
            };
        }
    }
    names
}

/// Index of the shot entry that holds time `t_s` (a boundary belongs to the later entry, the
/// end of the last entry to the last).
fn shot_at(shots: &[ShotInfo], t_s: f64) -> Option<usize> {
    let eps = 1e-9;
    shots
        .iter()
        .rposition(|s| t_s >= s.start_s - eps && t_s < s.end_s - eps)
        .or_else(|| {
            shots
                .iter()
                .rposition(|s| (t_s - s.end_s).abs() <= 1e-6 && s.start_s <= t_s)
        })
}

/// Writes `name` in `dir` atomically: a temporary file in the same directory, flushed, then
/// renamed over the target.
fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> io::Result<PathBuf> {
    let target = dir.join(name);
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, &target)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map(|_| target)
}

/// Writes the previews into `dir` (created if missing): `top`, `side`, `timeseries` and
/// `storyboard`, each as `.svg` and `.png`. Returns the paths written, in that order.
///
/// Errors: `InvalidInput` when the input's shapes disagree (see [`PreviewInput`]) or the
/// lens is unusable; I/O errors from writing; `Other` if an SVG cannot be rasterised.
pub fn write_previews(dir: &Path, input: &PreviewInput) -> io::Result<Vec<PathBuf>> {
    input.validate()?;
    fs::create_dir_all(dir)?;
    let rasteriser = raster::Rasteriser::new();
    let images = [
        ("top", plan::top_view(input)),
        ("side", plan::side_view(input)),
        ("timeseries", plots::time_series(input)),
        ("storyboard", storyboard::storyboard(input, &rasteriser)),
    ];
    let mut written = Vec::with_capacity(images.len() * 2);
    for (name, svg) in images {
        let text = svg.finish();
        written.push(write_atomic(dir, &format!("{name}.svg"), text.as_bytes())?);
        let png = rasteriser.png(&text)?;
        written.push(write_atomic(dir, &format!("{name}.png"), &png)?);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shot(start_s: f64, end_s: f64, kind: ShotKind) -> ShotInfo {
        ShotInfo {
            start_s,
            end_s,
            label: String::new(),
            kind,
            framing: Default::default(),
        }
    }

    #[test]
    fn a_shot_is_named_by_its_type() {
        let src =
            "stage 8m x 6m x 3m\nactor A height 1.8m at (-1, 0)\nactor B height 1.7m at (1, 0)\n\
                   MS on A front for 2s\ncut to MS on B and A for 2s\n\
                   cut to MS on A 34backright MS on B 34left for 2s\n\
                   cut to path orbit around A radius 2m altitude 1.5m for 5s looking at A\n\
                   cut to path orbit around A radius 2m altitude 1.5m for 5s looking at B\n\
                   cut to path orbit around A radius 2m altitude 1.5m for 5s\n\
                   cut to path square side 2m altitude 1.5m for 5s\n\
                   cut to path helix radius 1m from 1m to 2m for 5s looking at B\n";
        let checked = dronecine_grammar::check(src, &dronecine_grammar::Options::default());
        let script = checked.script.expect("the script checks");
        let types: Vec<String> = script
            .timeline
            .iter()
            .map(|s| shot_type(&s.content))
            .collect();
        assert_eq!(
            types,
            [
                "single on A",
                "two-shot of B and A",
                "OTS over A (on B)",
                "orbit around A",
                "orbit around A looking at B",
                "orbit around A looking ahead",
                "square path",
                "helix looking at B",
            ]
        );
    }

    #[test]
    fn repositionings_are_named_after_the_shot_they_fly_to() {
        let shots = [
            shot(0.0, 4.0, ShotKind::Hold),
            shot(4.0, 6.0, ShotKind::Reposition),
            shot(6.0, 9.0, ShotKind::Hold),
            shot(9.0, 12.0, ShotKind::Transition),
        ];
        assert_eq!(shot_names(&shots), ["1", "R→2", "2", "3"]);
        assert_eq!(shot_color(&shots, 1), REPOSITION_COLOR);
        assert_eq!(shot_color(&shots, 2), SHOT_COLORS[1]);
        assert_eq!(shot_at(&shots, 4.0), Some(1));
        assert_eq!(shot_at(&shots, 3.99), Some(0));
        assert_eq!(shot_at(&shots, 12.0), Some(3));
        assert_eq!(shot_at(&shots, 12.5), None);
    }
}
