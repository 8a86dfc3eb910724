//! Whether each two-actor framing gets the size the script writes (`compile::size_off`), and
//! the way out when it cannot: one warning per shot, at its worst tick, that names the size
//! the shot gets, the size to write instead and what else would give the written one.
//!
//! The framing solve says how far it had to stand from the size's distance
//! ([`TwoVisual::distance_ratio`]): a two-shot whose actors stand too far apart for the size
//! in one frame, or written screen positions that fix the camera's distance; an
//! over-the-shoulder whose background actor is out of the size's reach from behind the
//! foreground actor. A ratio within [`size::SIZE_SLACK`] still frames the size.

use crate::camera::{Lens, Vec3};
use crate::code::CompileCode;
use crate::framing::TwoVisual;
use crate::reference::ActorPose;
use crate::size;
use dronecine_diag::{Diagnostic, Span};
use dronecine_grammar::script::Composition;
use dronecine_grammar::vocab::Size;
use dronecine_math as math;
use dronecine_profile::Gimbal;

/// What a two-actor framing is, for the words of its warning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A two-shot whose actors' screen points follow the size.
    TwoShot,
    /// A two-shot whose written screen points fix the camera's distance.
    Screens,
    /// A two-shot seen from one actor's profile.
    Profiled,
    /// An over-the-shoulder; the size is the background actor's.
    OverShoulder,
}

/// A shot's worst tick: the farthest the camera stood from the size's distance.
#[derive(Clone, Debug)]
struct Worst {
    kind: Kind,
    asked: Size,
    ratio: f64,
    /// The sized actor (the background one of an over-the-shoulder; A of a two-shot) and
    /// the other, by index.
    sized: usize,
    other: usize,
    /// The actors' separation on the floor, and the camera's distance from the sized
    /// actor's band centre, at that tick.
    apart_m: f64,
    distance_m: f64,
    /// The angle between the two band centres seen from the camera, at that tick.
    apart_on_screen_rad: f64,
    /// The visual's A and B (by index) and their poses at that tick, for checking the advice.
    pair: [usize; 2],
    poses: [ActorPose; 2],
}

/// The watch over a compilation or a flight: fed each tick's two-actor visual, asked for
/// each shot's warning.
#[derive(Clone, Debug)]
pub struct SizeWatch {
    worst: Vec<Option<Worst>>,
}

impl SizeWatch {
    pub fn new(shots: usize) -> SizeWatch {
        SizeWatch {
            worst: vec![None; shots],
        }
    }

    /// A tick of shot `index` framing `comp` as `v`.
    pub fn see(&mut self, index: usize, comp: &Composition, v: &TwoVisual, actors: &[ActorPose]) {
        let Some(slot) = self.worst.get_mut(index) else {
            return;
        };
        let ratio = v.distance_ratio;
        if !ratio.is_finite()
            || slot
                .as_ref()
                .is_some_and(|w| math::ln(w.ratio).abs() >= math::ln(ratio).abs())
        {
            return;
        }
        let (Some(pa), Some(pb)) = (actors.get(v.a), actors.get(v.b)) else {
            return;
        };
        let written_x = comp
            .framings
            .iter()
            .flat_map(|f| &f.subjects)
            .any(|s| s.screen_x.is_some());
        let profiled = comp.framings.len() == 1
            && comp.framings[0]
                .subjects
                .iter()
                .any(|s| s.profile.is_some());
        let kind = match (v.over_shoulder, written_x, profiled) {
            (true, _, _) => Kind::OverShoulder,
            (false, _, true) => Kind::Profiled,
            (false, true, false) => Kind::Screens,
            (false, false, false) => Kind::TwoShot,
        };
        let profiled_b = kind == Kind::Profiled && comp.framings[0].subjects[0].profile.is_none();
        let (sized, other, band, sized_pose) = if v.over_shoulder || profiled_b {
            (v.b, v.a, v.band_b_m, pb)
        } else {
            (v.a, v.b, v.band_a_m, pa)
        };
        // The background framing of an over-the-shoulder is the last; a two-shot has one.
        let asked = comp.framings.last().map_or(Size::MS, |f| f.size);
        let centre_m = crate::framing::band_centre(sized_pose, band);
        let camera = crate::toric::position(
            &crate::framing::band_centre(pa, v.band_a_m),
            &crate::framing::band_centre(pb, v.band_b_m),
            &v.toric,
        );
        *slot = Some(Worst {
            kind,
            asked,
            ratio,
            sized,
            other,
            apart_m: math::norm_xy(
                pa.position_m[0] - pb.position_m[0],
                pa.position_m[1] - pb.position_m[1],
            ),
            distance_m: camera.map_or(f64::NAN, |c| (c - centre_m).norm()),
            apart_on_screen_rad: v.toric.alpha_rad,
            pair: [v.a, v.b],
            poses: [*pa, *pb],
        });
    }

    /// The warning of shot `index` (on `span`, framing `comp`), if its worst tick missed the
    /// size. Its advice is checked: the size to write and the lens it names frame the size
    /// against the actors as they stood at that tick.
    #[allow(clippy::too_many_arguments)]
    pub fn diagnostic(
        &self,
        index: usize,
        span: Span,
        comp: &Composition,
        names: &[String],
        lens: &Lens,
        gimbal: &Gimbal,
        stage: (&Vec3, &Vec3),
    ) -> Option<Diagnostic> {
        let w = self.worst.get(index)?.as_ref()?;
        if size::holds_at_ratio(w.ratio) {
            return None;
        }
        let check = Check {
            worst: w,
            comp,
            names,
            gimbal,
            stage,
        };
        let name = |i: usize| names.get(i).map_or("an actor", String::as_str);
        let (who, other) = (name(w.sized), name(w.other));
        let got = size::framed_at_ratio(w.asked, w.ratio);
        let write = check.size_that_holds(lens);
        let asked = w.asked.as_str();
        let larger = w.ratio < 1.0;
        // "framed as an LS", or, when the nearest size is still the one asked, how much off.
        let framed = if got == w.asked {
            let pct = ((1.0 / w.ratio - 1.0).abs() * 100.0).round();
            let way = if larger { "larger" } else { "smaller" };
            format!("framed {pct:.0}% {way} than the {asked} this shot asks")
        } else {
            format!(
                "framed as {} {}, not as the {asked} this shot asks",
                article(got),
                got.as_str()
            )
        };
        // The camera's distance scales with the actors' separation (the angles fixed).
        let apart_for_size = w.apart_m / w.ratio;
        let (message, help) = match w.kind {
            Kind::TwoShot => (
                format!(
                    "{who} and {other} are {framed}: \
                     {:.2} m apart, they fit in one frame only from {:.2} m away",
                    w.apart_m, w.distance_m
                ),
                format!(
                    "write {} (the tightest that fits), or block them at most {:.2} m apart for \
                     {asked}; a lens does not help: two actors side by side fill the same share \
                     of a {}:{} frame whatever its focal length",
                    write.as_str(),
                    apart_for_size,
                    aspect_words(lens).0,
                    aspect_words(lens).1
                ),
            ),
            Kind::Screens => (
                format!(
                    "{who} and {other} are {framed}: \
                     their written screen positions put the camera {:.2} m from them",
                    w.distance_m
                ),
                format!(
                    "write {}, or write their screen positions {} so that {asked} fits",
                    write.as_str(),
                    if larger {
                        "closer together"
                    } else {
                        "farther apart"
                    }
                ),
            ),
            Kind::Profiled => (
                format!(
                    "{who} is {framed} ({:.2} m away): \
                     from this side the camera stands back to keep {other} in frame",
                    w.distance_m
                ),
                format!(
                    "write {}, or block them at most {:.2} m apart for {asked}",
                    write.as_str(),
                    apart_for_size
                ),
            ),
            Kind::OverShoulder => {
                let lens_way = match check.lens_that_holds(lens) {
                    Some(fov) => format!(
                        ", or `lens {fov:.0}deg {}:{}`, which frames {who} as {asked} over \
                         {other}'s shoulder",
                        aspect_words(lens).0,
                        aspect_words(lens).1
                    ),
                    None => format!(
                        "; no lens gives {asked} here: where the two profiles' sides meet, \
                         {other} stands {:.0}° from {who} as the camera sees them, and a lens \
                         narrow enough for {asked} at {:.2} m leaves {other} out of the frame \
                         (profiles nearer the line between them, or the actors closer, let the \
                         camera come nearer)",
                        w.apart_on_screen_rad.to_degrees(),
                        w.distance_m
                    ),
                };
                (
                    format!(
                        "{who} is {framed} ({:.2} m away): over {other}'s shoulder the camera \
                         stands {} {:.2} m from {who}",
                        w.distance_m,
                        if larger { "at most" } else { "at least" },
                        w.distance_m
                    ),
                    format!("write {}{lens_way}", write.as_str()),
                )
            }
        };
        // An over-the-shoulder's background actor framed larger: the profiles keep the
        // camera nearer than the size's distance.
        let code = if w.kind == Kind::OverShoulder && larger {
            CompileCode::BeyondReach
        } else {
            CompileCode::SizeOff
        };
        Some(
            Diagnostic::warning(code, span, message)
                .with_label(format!("framed as {}", got.as_str()))
                .with_help(help),
        )
    }
}

/// The advice of a warning, checked against the actors as they stood at the worst tick.
struct Check<'a> {
    worst: &'a Worst,
    comp: &'a Composition,
    names: &'a [String],
    gimbal: &'a Gimbal,
    /// The box the director keeps its target in: advice whose camera leaves it is not given.
    stage: (&'a Vec3, &'a Vec3),
}

/// The lenses advised, horizontal field of view in degrees: what drone cameras carry.
const LENS_RANGE_DEG: (f64, f64) = (20.0, 120.0);

/// How many lenses [`Check::lens_that_holds`] tries, each from the last one's miss.
const LENS_TRIES: usize = 6;

impl Check<'_> {
    /// The distance ratio of `comp` solved with `lens` against the worst tick's actors.
    fn ratio(&self, comp: &Composition, lens: &Lens) -> Option<f64> {
        let w = self.worst;
        let mut actors = vec![w.poses[0]; self.names.len()];
        *actors.get_mut(w.pair[0])? = w.poses[0];
        *actors.get_mut(w.pair[1])? = w.poses[1];
        let v = crate::framing::solve(comp, self.names, &actors, lens, self.gimbal).ok()?;
        let c = crate::framing::place(&v, &actors, lens, self.gimbal).position_m;
        let (lo, hi) = self.stage;
        let inside = (0..3).all(|i| c[i] >= lo[i] - 1e-9 && c[i] <= hi[i] + 1e-9);
        match v {
            crate::framing::Visual::Two(t) if inside => Some(t.distance_ratio),
            _ => None,
        }
    }

    /// The tightest size, from the one [`size::size_to_write`] names looser, with which the
    /// composition frames its size.
    fn size_that_holds(&self, lens: &Lens) -> Size {
        let w = self.worst;
        let first = size::size_to_write(w.asked, w.ratio);
        let sizes: Vec<Size> = if w.ratio >= 1.0 {
            Size::ALL
                .into_iter()
                .filter(|s| *s as usize >= first as usize)
                .collect()
        } else {
            Size::ALL
                .into_iter()
                .rev()
                .filter(|s| *s as usize <= first as usize)
                .collect()
        };
        sizes
            .into_iter()
            .find(|s| {
                let mut c = self.comp.clone();
                if let Some(f) = c.framings.last_mut() {
                    f.size = *s;
                }
                self.ratio(&c, lens).is_some_and(size::holds_at_ratio)
            })
            .unwrap_or(first)
    }

    /// A lens (horizontal field of view in whole degrees, the same aspect) with which an
    /// over-the-shoulder frames its background actor at the written size: from the field
    /// that frames at the worst ratio's distance what this one frames at the size's, again
    /// from each try's own miss; `None` when none of [`LENS_TRIES`] holds.
    fn lens_that_holds(&self, lens: &Lens) -> Option<f64> {
        let mut ratio = self.worst.ratio;
        let mut current = *lens;
        for _ in 0..LENS_TRIES {
            let tan_y = 1.0 / current.sy() / ratio;
            let deg = (2.0 * math::atan(tan_y * current.aspect())).to_degrees();
            let deg = if ratio >= 1.0 {
                deg.floor()
            } else {
                deg.ceil()
            };
            if !(deg >= LENS_RANGE_DEG.0 && deg <= LENS_RANGE_DEG.1) {
                return None;
            }
            current = Lens::new(deg.to_radians(), lens.aspect());
            ratio = self.ratio(self.comp, &current)?;
            if size::holds_at_ratio(ratio) {
                return Some(deg);
            }
        }
        None
    }
}

/// The lens's aspect in the words a script writes it (16:9, 4:3), or as a ratio.
fn aspect_words(lens: &Lens) -> (String, String) {
    for (w, h) in [(16.0, 9.0), (4.0, 3.0), (3.0, 2.0), (1.0, 1.0), (21.0, 9.0)] {
        if (lens.aspect() - w / h).abs() < 1e-6 {
            return (format!("{w}"), format!("{h}"));
        }
    }
    (format!("{:.2}", lens.aspect()), "1".to_string())
}

fn article(s: Size) -> &'static str {
    match s {
        Size::ECU | Size::MCU | Size::MS | Size::MLS | Size::FS | Size::LS | Size::ELS => "an",
        Size::BCU | Size::CU => "a",
    }
}
