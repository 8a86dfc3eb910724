//! What the checks read of each shot, filled tick by tick: where the camera and the actors
//! were when the shot started, at its middle and when it ended, and when a framed actor was
//! out of the frame; and the checks themselves, run when a shot's findings are asked.

use dronecine_compiler::camera::{Lens, Vec3};
use dronecine_compiler::director::Watch;
use dronecine_compiler::line::{self, Pair};
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_compiler::size;
use dronecine_diag::{Diagnostic, Span};
use dronecine_grammar::script::{Scene, Script, ShotContent, Transition};
use dronecine_grammar::vocab::{Profile, Size};
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;
use dronecine_profile::Gimbal;

use crate::code::FilmCode;
use crate::frame::{self, Kept, Out};

use dronecine_compiler::line::{JUMP_ANGLE_RAD, JUMP_SIZE_STEPS};
/// An actor walks at least this fast…
pub const WALKING_MPS: f64 = 0.2;
/// …and across the screen at least this fast (along the camera's right), for the walk to
/// have a screen direction.
pub const ACROSS_MPS: f64 = 0.1;

/// One shot as the checks need it.
#[derive(Clone, Debug)]
struct ShotInfo {
    span: Span,
    /// Reached by a cut or a dissolve, not by a camera move.
    cut: bool,
    duration_s: f64,
    /// The pair of actors whose line of action the shot stands by ([`line::shot_pairs`]).
    pair: Option<Pair>,
    /// The actors it frames, by index, in order.
    subjects: Vec<usize>,
    /// The actors that must stay in frame, and the band of each that must.
    kept: [Option<Kept>; 2],
    /// The size of its main framing (the background's of an over-the-shoulder).
    size: Option<Size>,
    /// Its subjects' profiles, in order.
    profiles: Vec<Option<Profile>>,
    /// A path's altitude range, for a path `looking at` an actor.
    path_altitude_m: Option<(f64, f64)>,
}

/// The camera and the actors the checks follow, at one tick.
#[derive(Clone, Copy, Debug)]
struct Snap {
    camera_m: Vec3,
    heading_rad: f64,
    /// The poses of the shot's tracked actors ([`Film::tracked`]).
    poses: [Option<ActorPose>; 2],
}

/// What the ticks of one shot left.
#[derive(Clone, Debug, Default)]
struct Seen {
    start_s: Option<f64>,
    first: Option<Snap>,
    mid: Option<Snap>,
    last: Option<Snap>,
    out: Out,
}

/// The film checks over a script's flight ([`Watch`]).
#[derive(Clone, Debug)]
pub(crate) struct Film {
    shots: Vec<ShotInfo>,
    seen: Vec<Seen>,
    names: Vec<String>,
    lens: Lens,
    gimbal: Gimbal,
}

impl Film {
    pub(crate) fn new(script: &Script, scene: &Scene, lens: Lens, gimbal: Gimbal) -> Film {
        let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
        let heights: Vec<f64> = scene.actors.iter().map(|a| a.height_m).collect();
        let pairs = line::shot_pairs(script, &names);
        let index = |n: &str| names.iter().position(|x| x == n);
        let shots = script
            .timeline
            .iter()
            .zip(pairs)
            .map(|(shot, pair)| {
                let mut info = ShotInfo {
                    span: shot.span,
                    cut: !matches!(shot.transition, Transition::Move { .. }),
                    duration_s: shot.end_s - shot.start_s,
                    pair,
                    subjects: Vec::new(),
                    kept: [None, None],
                    size: None,
                    profiles: Vec::new(),
                    path_altitude_m: None,
                };
                match (shot.content.framed(), &shot.content) {
                    (Some(c), _) => {
                        for f in &c.framings {
                            for s in &f.subjects {
                                if let Some(i) = index(&s.actor) {
                                    info.subjects.push(i);
                                    info.profiles.push(s.profile);
                                }
                            }
                        }
                        info.size = c.framings.last().map(|f| f.size);
                        info.kept = frame::kept(&c, &names, &heights);
                    }
                    (None, ShotContent::Path(p)) => {
                        if let Some(i) = p.looking_at.as_deref().and_then(index) {
                            info.subjects.push(i);
                            let (b, t) = size::band(Size::MS, heights[i]);
                            info.kept[0] = Some(Kept {
                                actor: i,
                                band_m: [b, t],
                            });
                            info.path_altitude_m = frame::path_altitude_m(&p.shape);
                        }
                    }
                    (None, _) => {}
                }
                info
            })
            .collect::<Vec<_>>();
        Film {
            seen: vec![Seen::default(); shots.len()],
            shots,
            names,
            lens,
            gimbal,
        }
    }

    /// The actors a shot's snapshots keep: its pair's, else its subject's.
    fn tracked(info: &ShotInfo) -> [Option<usize>; 2] {
        match info.pair {
            Some((a, b)) => [Some(a), Some(b)],
            None => [info.subjects.first().copied(), None],
        }
    }

    fn name(&self, i: usize) -> &str {
        self.names.get(i).map_or("an actor", String::as_str)
    }
}

impl Snap {
    fn of(sample: &Sample, actors: &[ActorPose], tracked: [Option<usize>; 2]) -> Snap {
        Snap {
            camera_m: Vec3::from(sample.position_m),
            heading_rad: sample.heading_rad,
            poses: tracked.map(|i| i.and_then(|i| actors.get(i).copied())),
        }
    }

    /// The pose of actor `actor` if tracked, given what was tracked.
    fn pose(&self, tracked: [Option<usize>; 2], actor: usize) -> Option<ActorPose> {
        (0..2).find_map(|k| {
            (tracked[k] == Some(actor))
                .then_some(self.poses[k])
                .flatten()
        })
    }

    /// The side of the line of the tracked pair the camera stood on.
    fn side(&self) -> Option<dronecine_compiler::framing::Side> {
        let [Some(a), Some(b)] = self.poses else {
            return None;
        };
        line::side_of((0, 1), &[a, b], &self.camera_m)
    }
}

impl Watch for Film {
    fn tick(&mut self, sample: &Sample, actors: &[ActorPose], flying: Option<usize>) {
        let Some(i) = flying else {
            return;
        };
        let (Some(info), Some(seen)) = (self.shots.get(i), self.seen.get_mut(i)) else {
            return;
        };
        let snap = Snap::of(sample, actors, Film::tracked(info));
        let start = *seen.start_s.get_or_insert(sample.t_s);
        seen.first.get_or_insert(snap);
        if seen.mid.is_none() && sample.t_s >= start + info.duration_s / 2.0 {
            seen.mid = Some(snap);
        }
        seen.last = Some(snap);
        frame::see(
            &mut seen.out,
            &info.kept,
            sample,
            start,
            actors,
            (&self.lens, &self.gimbal),
        );
    }

    fn findings(&self, index: usize, out: &mut Vec<Diagnostic>) {
        if index >= self.shots.len() {
            return;
        }
        out.extend(self.crossing(index));
        if index > 0 && self.shots[index].cut {
            out.extend(self.jump(index));
            out.extend(self.screen_direction(index));
        }
        out.extend(self.out_of_frame(index));
    }

    fn clone_box(&self) -> Box<dyn Watch> {
        Box::new(self.clone())
    }
}

impl Film {
    /// `film::crosses_line` for a cut into shot `index`: the line of action's side walked
    /// from the first shot, each shot of a pair judged at its middle; a move re-establishes
    /// the side it ends on, and a shot on the line clears it.
    fn crossing(&self, index: usize) -> Option<Diagnostic> {
        // The side each pair's line was last seen from, and by which shot: on the stack (this
        // runs at every shot's end, on the flight's tick); pairs past the first few are not
        // followed.
        let mut established = Established::default();
        for j in 0..=index {
            let (info, seen) = (&self.shots[j], &self.seen[j]);
            let Some(pair) = info.pair else {
                continue;
            };
            let judged = if info.cut { seen.mid } else { seen.last };
            let Some(snap) = judged.or(seen.last) else {
                continue;
            };
            match (snap.side(), established.get(pair)) {
                (None, _) => established.clear(pair),
                (Some(s), Some((before, by))) if j == index && s != before && info.cut => {
                    return Some(self.crosses_line(index, pair, by));
                }
                (Some(s), _) => established.set(pair, s, j),
            }
        }
        None
    }

    fn crosses_line(&self, index: usize, pair: Pair, by: usize) -> Diagnostic {
        let info = &self.shots[index];
        let (a, b) = (self.name(pair.0), self.name(pair.1));
        let mirrored: Vec<String> = info
            .subjects
            .iter()
            .zip(&info.profiles)
            .filter_map(|(&i, p)| {
                let p = (*p)?;
                let m = mirror(p);
                (m != p).then(|| format!("{} {} → {}", self.name(i), p.as_str(), m.as_str()))
            })
            .collect();
        let fix = if mirrored.is_empty() {
            "frame it from the other side".to_string()
        } else {
            format!("mirror its profiles ({})", mirrored.join(", "))
        };
        Diagnostic::warning(
            FilmCode::CrossesLine,
            info.span,
            format!(
                "this cut crosses the line of action between {a} and {b}: the camera stands \
                 on the other side of it from the shot before, and the two swap sides of the \
                 screen"
            ),
        )
        .with_label("the camera across the line")
        .with_related(
            self.shots[by].span,
            "the camera's side of the line is set here",
        )
        .with_help(format!(
            "{fix} to keep the camera on the side set before, or reach this framing with a \
             camera move (`then … to`), which the audience sees cross, or cut to a shot on \
             the line between them first"
        ))
    }

    /// `film::jump_cut` for the cut into shot `index` from the shot before, when both frame
    /// the same actors.
    fn jump(&self, index: usize) -> Option<Diagnostic> {
        let (before, after) = (&self.shots[index - 1], &self.shots[index]);
        let (s0, s1) = (subject_set(&before.subjects), subject_set(&after.subjects));
        let s0 = match (s0, s1) {
            (Some(a), Some(b)) if a == b => a,
            _ => return None,
        };
        let s0: &[usize] = match &s0 {
            [a, b] if a == b => std::slice::from_ref(a),
            both => both,
        };
        let s1 = s0;
        let (size0, size1) = (before.size?, after.size?);
        let steps = (size0 as usize).abs_diff(size1 as usize);
        if steps >= JUMP_SIZE_STEPS {
            return None;
        }
        let last = self.seen[index - 1].last?;
        let first = self.seen[index].first?;
        let b0 = bearing_round(s0, Film::tracked(before), &last)?;
        let b1 = bearing_round(s1, Film::tracked(after), &first)?;
        let turn = wrap_angle_rad(b1 - b0).abs();
        if turn >= JUMP_ANGLE_RAD {
            return None;
        }
        let who = match s0 {
            [a] => self.name(*a).to_string(),
            [a, b] => format!("{} and {}", self.name(*a), self.name(*b)),
            _ => return None,
        };
        let sizes = if steps == 0 {
            format!("keeps its size ({})", size1.as_str())
        } else {
            format!(
                "changes its size by one step only ({} → {})",
                size0.as_str(),
                size1.as_str()
            )
        };
        let round = match s0 {
            [a] => self.name(*a).to_string(),
            _ => "the two".to_string(),
        };
        Some(
            Diagnostic::warning(
                FilmCode::JumpCut,
                after.span,
                format!(
                    "this cut to {who} turns the camera {:.0}° round {round} and {sizes}: it \
                     reads as a jump in the picture, not as a cut",
                    turn.to_degrees()
                ),
            )
            .with_label("a jump cut")
            .with_related(before.span, "the shot it cuts from")
            .with_help(format!(
                "turn the camera at least 30° round {round} (a profile one step or more away), \
                 change the size by two steps or more, or join the shots with a camera move \
                 (`then … to`)"
            )),
        )
    }

    /// `film::screen_direction` for the cut into shot `index`: an actor of both shots
    /// walking across the screen one way before it and the other way after.
    fn screen_direction(&self, index: usize) -> Option<Diagnostic> {
        let (before, after) = (&self.shots[index - 1], &self.shots[index]);
        let last = self.seen[index - 1].last?;
        let first = self.seen[index].first?;
        for &actor in &after.subjects {
            if !before.subjects.contains(&actor) {
                continue;
            }
            let across = |snap: &Snap, info: &ShotInfo| -> Option<f64> {
                let p = snap.pose(Film::tracked(info), actor)?;
                let v = Vec3::new(p.velocity_mps[0], p.velocity_mps[1], 0.0);
                if v.norm() < WALKING_MPS {
                    return None;
                }
                let (s, c) = math::sin_cos(snap.heading_rad);
                let right = Vec3::new(s, -c, 0.0);
                let x = v.dot(&right);
                (x.abs() >= ACROSS_MPS).then_some(x)
            };
            let (Some(x0), Some(x1)) = (across(&last, before), across(&first, after)) else {
                continue;
            };
            if (x0 > 0.0) == (x1 > 0.0) {
                continue;
            }
            let way = |x: f64| {
                if x > 0.0 {
                    "left to right"
                } else {
                    "right to left"
                }
            };
            let who = self.name(actor);
            return Some(
                Diagnostic::warning(
                    FilmCode::ScreenDirection,
                    after.span,
                    format!(
                        "{who} walks {} across the screen before this cut and {} after it: \
                         the walk reverses on the cut",
                        way(x0),
                        way(x1)
                    ),
                )
                .with_label(format!("{who} walks {}", way(x1)))
                .with_related(before.span, format!("{who} walks {}", way(x0)))
                .with_help(format!(
                    "film both shots from the same side of {who}'s walk, or put a shot \
                     between them that looks along it (the camera ahead of {who} or behind)"
                )),
            );
        }
        None
    }

    /// `film::out_of_frame` for shot `index`, if an actor it frames left the frame.
    fn out_of_frame(&self, index: usize) -> Option<Diagnostic> {
        let info = &self.shots[index];
        let seen = &self.seen[index];
        let start = seen.start_s?;
        frame::diagnostic(
            &seen.out,
            frame::Context {
                span: info.span,
                start_s: start,
                duration_s: info.duration_s,
                names: &self.names,
                lens: &self.lens,
                gimbal: &self.gimbal,
                path_altitude_m: info.path_altitude_m,
            },
        )
    }
}

/// A shot's subjects as a sorted pair (one actor twice), `None` for none or more than two.
fn subject_set(subjects: &[usize]) -> Option<[usize; 2]> {
    match subjects {
        [a] => Some([*a, *a]),
        [a, b] => Some([*a.min(b), *a.max(b)]),
        _ => None,
    }
}

/// The side of the line of action each pair of actors was last seen from, and by which
/// shot, for the first [`PAIRS_FOLLOWED`] pairs a timeline frames.
#[derive(Default)]
struct Established {
    slots: [Option<(Pair, dronecine_compiler::framing::Side, usize)>; PAIRS_FOLLOWED],
}

/// How many pairs of actors the line-of-action check follows.
const PAIRS_FOLLOWED: usize = 8;

impl Established {
    fn get(&self, pair: Pair) -> Option<(dronecine_compiler::framing::Side, usize)> {
        self.slots
            .iter()
            .flatten()
            .find(|e| e.0 == pair)
            .map(|e| (e.1, e.2))
    }

    fn clear(&mut self, pair: Pair) {
        for slot in &mut self.slots {
            if slot.is_some_and(|e| e.0 == pair) {
                *slot = None;
            }
        }
    }

    fn set(&mut self, pair: Pair, side: dronecine_compiler::framing::Side, by: usize) {
        let at = (self
            .slots
            .iter()
            .position(|e| e.is_some_and(|e| e.0 == pair)))
        .or_else(|| self.slots.iter().position(Option::is_none));
        if let Some(k) = at {
            self.slots[k] = Some((pair, side, by));
        }
    }
}

/// The camera's bearing round the subject: round one actor from their facing, round a pair
/// from the line between them.
fn bearing_round(subjects: &[usize], tracked: [Option<usize>; 2], snap: &Snap) -> Option<f64> {
    let c = snap.camera_m;
    match subjects {
        [a] => {
            let p = snap.pose(tracked, *a)?;
            let b = math::atan2(c.y - p.position_m[1], c.x - p.position_m[0]);
            Some(wrap_angle_rad(b - p.facing_rad))
        }
        [a, b] => {
            let (pa, pb) = (snap.pose(tracked, *a)?, snap.pose(tracked, *b)?);
            let m = [
                (pa.position_m[0] + pb.position_m[0]) / 2.0,
                (pa.position_m[1] + pb.position_m[1]) / 2.0,
            ];
            let line = math::atan2(
                pb.position_m[1] - pa.position_m[1],
                pb.position_m[0] - pa.position_m[0],
            );
            let b = math::atan2(c.y - m[1], c.x - m[0]);
            Some(wrap_angle_rad(b - line))
        }
        _ => None,
    }
}

/// The profile that sees the actor from the other side of the line they face along.
fn mirror(p: Profile) -> Profile {
    match p {
        Profile::ThreeQuarterLeft => Profile::ThreeQuarterRight,
        Profile::ThreeQuarterRight => Profile::ThreeQuarterLeft,
        Profile::Left => Profile::Right,
        Profile::Right => Profile::Left,
        Profile::ThreeQuarterBackLeft => Profile::ThreeQuarterBackRight,
        Profile::ThreeQuarterBackRight => Profile::ThreeQuarterBackLeft,
        Profile::Front | Profile::Back => p,
    }
}
