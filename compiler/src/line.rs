//! The line of action (film grammar's 180° rule), ahead of the flight: which pair of actors
//! each shot belongs to, which shots fix a side of the line between them, and the side a
//! shot that leaves it free takes — that of the nearest shot of the pair that fixes one, so
//! that a shot the director left open never causes a crossing.
//!
//! A side is [`Side::of`] the camera against the pair in a canonical order (the lower actor
//! index first); a shot's framing is told its side in its own order
//! ([`crate::framing::Prepared::on_side`]).

use std::borrow::Cow;

use crate::blocking::Blocking;
use crate::camera::{Lens, Vec3};
use crate::framing::{self, Side};
use crate::reference::ActorPose;
use dronecine_grammar::script::{Composition, Scene, Script};
use dronecine_profile::Gimbal;

/// Within this of the line through the two actors (seen from either), a camera stands on
/// the line itself: it fixes no side, and a cut to or from it crosses nothing.
pub const ON_LINE_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// A cut between two shots of the same actors turns the camera less than this round them…
pub const JUMP_ANGLE_RAD: f64 = 30.0 * std::f64::consts::PI / 180.0;
/// …and changes the size by fewer steps than this: it reads as a jump in the picture, not as
/// a cut (film grammar's 30° rule, `film::jump_cut`).
pub const JUMP_SIZE_STEPS: usize = 2;

/// A pair of actors by index, the lower first.
pub type Pair = (usize, usize);

/// The pair a composition frames, or, for a single, `None` (see [`pair_of_single`]).
pub fn pair_of(comp: &Composition, names: &[String]) -> Option<Pair> {
    let mut ids = comp
        .actors()
        .filter_map(|n| names.iter().position(|x| x == n));
    let (a, b) = (ids.next()?, ids.next()?);
    (a != b).then(|| (a.min(b), a.max(b)))
}

/// Whether a composition leaves the side of the line free: a two-actor framing with no
/// profile and no written screen x (a single with no profile is seen from the front, which
/// fixes its camera).
pub fn leaves_side_free(comp: &Composition) -> bool {
    let subjects: Vec<_> = comp.framings.iter().flat_map(|f| &f.subjects).collect();
    subjects.len() == 2
        && subjects
            .iter()
            .all(|s| s.profile.is_none() && s.screen_x.is_none())
}

/// The pair a single on `actor` belongs to: the one pair of the script's two-actor shots
/// that includes it, if exactly one does.
pub fn pair_of_single(actor: usize, pairs: &[Pair]) -> Option<Pair> {
    let mut with = pairs.iter().filter(|p| p.0 == actor || p.1 == actor);
    let first = *with.next()?;
    with.all(|p| *p == first).then_some(first)
}

/// The side of the line between `pair` that a camera at `c` stands on, `None` on the line
/// (within [`ON_LINE_RAD`] of it as seen from either actor).
pub fn side_of(pair: Pair, actors: &[ActorPose], c: &Vec3) -> Option<Side> {
    let (a, b) = (actors.get(pair.0)?, actors.get(pair.1)?);
    let pa = Vec3::new(a.position_m[0], a.position_m[1], 0.0);
    let pb = Vec3::new(b.position_m[0], b.position_m[1], 0.0);
    let c0 = Vec3::new(c.x, c.y, 0.0);
    let off = |from: &Vec3, to: &Vec3| {
        let (u, v) = (to - from, c0 - from);
        let angle = crate::camera::angle(&u, &v);
        angle.min(std::f64::consts::PI - angle)
    };
    if off(&pa, &pb) < ON_LINE_RAD || off(&pb, &pa) < ON_LINE_RAD {
        return None;
    }
    Side::of(&pa, &pb, &c0)
}

/// Each shot's composition (the one it holds, or the one a move goes to; an unexpanded
/// coverage's two-shot) and its time on the script's clock at its middle.
fn compositions(script: &Script) -> Vec<Option<(Cow<'_, Composition>, f64)>> {
    script
        .timeline
        .iter()
        .map(|shot| Some((shot.content.framed()?, (shot.start_s + shot.end_s) / 2.0)))
        .collect()
}

/// The pair of each shot: its own, a single's ([`pair_of_single`]), or none.
pub fn shot_pairs(script: &Script, names: &[String]) -> Vec<Option<Pair>> {
    let comps = compositions(script);
    let pairs: Vec<Pair> = comps
        .iter()
        .flatten()
        .filter_map(|(c, _)| pair_of(c, names))
        .collect();
    comps
        .iter()
        .map(|c| {
            let (comp, _) = c.as_ref()?;
            pair_of(comp, names).or_else(|| {
                let actor = comp.actors().next()?;
                let i = names.iter().position(|n| n == actor)?;
                pair_of_single(i, &pairs)
            })
        })
        .collect()
}

/// The side each shot that fixes one stands on (`None` for the others), as its framing
/// solves against the script's blocking at its middle, for its pair in canonical order.
fn fixed_sides(
    comps: &[Option<(Cow<'_, Composition>, f64)>],
    pairs: &[Option<Pair>],
    names: &[String],
    blocking: &Blocking,
    lens: &Lens,
    gimbal: &Gimbal,
) -> Vec<Option<Side>> {
    comps
        .iter()
        .zip(pairs)
        .map(|(c, pair)| {
            let ((comp, t), pair) = (c.as_ref()?, (*pair)?);
            if leaves_side_free(comp) {
                return None;
            }
            let poses = blocking.poses(*t);
            let v = framing::solve(comp, names, &poses, lens, gimbal).ok()?;
            let c = framing::place(&v, &poses, lens, gimbal).position_m;
            side_of(pair, &poses, &c)
        })
        .collect()
}

/// The side each shot that leaves it free takes, in its composition's own order (`None` for
/// the others, and when no shot of its pair fixes a side): the side of the nearest shot of
/// the pair that fixes one (the earlier on a tie), as that shot frames the script's
/// blocking at its middle.
pub fn established_sides(
    script: &Script,
    scene: &Scene,
    lens: &Lens,
    gimbal: &Gimbal,
) -> Vec<Option<Side>> {
    let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
    let blocking = Blocking::new(scene);
    let comps = compositions(script);
    let pairs = shot_pairs(script, &names);
    let fixed = fixed_sides(&comps, &pairs, &names, &blocking, lens, gimbal);
    comps
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (comp, _) = c.as_ref()?;
            let pair = pairs[i]?;
            if !leaves_side_free(comp) {
                return None;
            }
            let nearest = (0..comps.len())
                .filter(|&j| pairs[j] == Some(pair) && fixed[j].is_some())
                .min_by_key(|&j| (j.abs_diff(i), j))?;
            let side = fixed[nearest]?;
            // In the composition's own order: its first subject as A.
            let first = comp.actors().next()?;
            let first_is_lower = names.iter().position(|n| n == first) == Some(pair.0);
            Some(if first_is_lower { side } else { side.swapped() })
        })
        .collect()
}

/// The side of the line between `pair` (canonical order) that the nearest shot before shot
/// `index` fixing one stands on (`later`: after it), as [`established_sides`] reads each
/// shot; `None` when no such shot fixes one.
pub fn side_near(
    script: &Script,
    scene: &Scene,
    (lens, gimbal): (&Lens, &Gimbal),
    index: usize,
    pair: Pair,
    later: bool,
) -> Option<Side> {
    let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
    let blocking = Blocking::new(scene);
    let comps = compositions(script);
    let pairs = shot_pairs(script, &names);
    let n = comps.len();
    let range = if later {
        (index + 1).min(n)..n
    } else {
        0..index.min(n)
    };
    let fixed = fixed_sides(
        &comps[range.clone()],
        &pairs[range.clone()],
        &names,
        &blocking,
        lens,
        gimbal,
    );
    let found = |k: usize| pairs[range.start + k] == Some(pair) && fixed[k].is_some();
    let nearest = if later {
        (0..fixed.len()).find(|&k| found(k))
    } else {
        (0..fixed.len()).rev().find(|&k| found(k))
    };
    nearest.and_then(|k| fixed[k])
}
