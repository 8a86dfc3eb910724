//! What each hold of two framings really frames, measured on the flown reference: the mean
//! distance to each actor, for [`FramedAs::level_fix`], the size that brings a level camera's
//! two aim points to one height (the help of `compile::framing_off`).
//!
//! (Which side each actor is seen from needs no check here: the solve keeps each written
//! profile within its 45° sector, [`crate::framing`], and the stage's margin moves the
//! camera by less than the rest of that sector.)

use dronecine_grammar::script::{Script, ShotContent};
use dronecine_grammar::vocab::Size;

use crate::camera::Lens;
use crate::reference::ActorPose;
use dronecine_math as math;
use dronecine_profile::Gimbal;

/// Sizes apart (in `Size::ALL` order) from which a framed size is reported.
pub const SIZE_STEPS_OFF: usize = 2;

/// One actor's framing in a composition of several framings, and what the holds saw of it.
#[derive(Clone, Debug)]
struct Asked {
    actor: usize,
    size: Size,
    sum_distance_m: f64,
    n: u64,
}

/// The check over a whole compilation: fed each hold tick, then asked for its diagnostics.
pub struct FramedAs {
    /// By timeline index: the framings asked, empty for shots of one framing.
    shots: Vec<Vec<Asked>>,
    /// By timeline index: the actors as the hold of a shot of several framings last saw them
    /// (for [`FramedAs::level_fix`]'s re-solve).
    poses: Vec<Option<Vec<ActorPose>>>,
    /// The scene's actors' names and heights, by index.
    names: Vec<String>,
    heights_m: Vec<f64>,
}

impl FramedAs {
    pub fn new(script: &Script) -> FramedAs {
        let actors = script.scene.as_ref().map_or(&[][..], |s| &s.actors[..]);
        let names: Vec<String> = actors.iter().map(|a| a.name.clone()).collect();
        let heights_m = actors.iter().map(|a| a.height_m).collect();
        let shots: Vec<Vec<Asked>> = script
            .timeline
            .iter()
            .map(|shot| match &shot.content {
                ShotContent::Composition(c) if c.framings.len() >= 2 => c
                    .framings
                    .iter()
                    .flat_map(|f| f.subjects.iter().map(move |s| (f.size, s)))
                    .filter_map(|(size, s)| {
                        Some(Asked {
                            actor: names.iter().position(|n| *n == s.actor)?,
                            size,
                            sum_distance_m: 0.0,
                            n: 0,
                        })
                    })
                    .collect(),
                _ => Vec::new(),
            })
            .collect();
        let poses = vec![None; shots.len()];
        FramedAs {
            shots,
            poses,
            names,
            heights_m,
        }
    }

    /// One tick of the hold of `shot`, the camera at `camera_m`.
    pub fn see(&mut self, shot: usize, camera_m: &[f64; 3], actors: &[ActorPose]) {
        let Some(asked) = self.shots.get_mut(shot) else {
            return;
        };
        if asked.is_empty() {
            return;
        }
        match &mut self.poses[shot] {
            Some(kept) => {
                kept.clear();
                kept.extend_from_slice(actors);
            }
            none => *none = Some(actors.to_vec()),
        }
        for a in asked {
            let Some(pose) = actors.get(a.actor) else {
                continue;
            };
            let (dx, dy) = (
                camera_m[0] - pose.position_m[0],
                camera_m[1] - pose.position_m[1],
            );
            a.sum_distance_m += dronecine_math::norm_xy(dx, dy);
            a.n += 1;
        }
    }
}

/// A size for `actor` in the two-framing hold of `shot` that brings its aim point to about
/// the height of the other actor's (a level camera sees both at their screen heights only
/// then): within a size of what the camera frames of the actor there (so that the fix does not
/// itself frame the actor off its size), and with which the composition still solves against
/// the actors as the hold last saw them. Heights in metres above the floor.
pub struct LevelFix {
    pub size: Size,
    pub centre_m: f64,
    pub other: usize,
    pub other_centre_m: f64,
}

impl FramedAs {
    /// Whether the composition of `shot` still solves, against the actors as its hold last
    /// saw them, with `actor` framed as `size`: a size the help suggests is one that frames.
    fn solves_with(
        &self,
        script: &Script,
        shot: usize,
        actor: usize,
        size: Size,
        lens: &Lens,
        gimbal: &Gimbal,
    ) -> bool {
        let (Some(Some(poses)), Some(shot), Some(name)) = (
            self.poses.get(shot),
            script.timeline.get(shot),
            self.names.get(actor),
        ) else {
            return false;
        };
        let ShotContent::Composition(comp) = &shot.content else {
            return false;
        };
        let mut fixed = comp.clone();
        for f in &mut fixed.framings {
            if f.subjects.iter().any(|s| s.actor == *name) {
                f.size = size;
            }
        }
        crate::framing::solve(&fixed, &self.names, poses, lens, gimbal).is_ok()
    }

    /// The [`LevelFix`] for `actor` in `shot`, if a size does better than the script's.
    pub fn level_fix(
        &self,
        script: &Script,
        shot: usize,
        actor: usize,
        lens: &Lens,
        gimbal: &Gimbal,
    ) -> Option<LevelFix> {
        let heights_m = &self.heights_m;
        let asked = self.shots.get(shot)?;
        let this = asked.iter().find(|a| a.actor == actor && a.n > 0)?;
        let other = asked.iter().find(|a| a.actor != actor)?;
        let centre = |size: Size, actor: usize| {
            let (b, t) = crate::size::band(size, *heights_m.get(actor)?);
            Some((b + t) / 2.0)
        };
        let other_centre_m = centre(other.size, other.actor)?;
        let gap =
            |size: Size| centre(size, actor).map_or(f64::INFINITY, |c| (c - other_centre_m).abs());
        let framed = framed_size(this, lens, heights_m)? as usize;
        let mut candidates: Vec<Size> = Size::ALL
            .into_iter()
            .filter(|s| {
                *s != this.size && (*s as usize).abs_diff(framed) <= 1 && gap(*s) < gap(this.size)
            })
            .collect();
        candidates.sort_by(|x, y| gap(*x).total_cmp(&gap(*y)));
        let size = candidates
            .into_iter()
            .find(|&size| self.solves_with(script, shot, actor, size, lens, gimbal))?;
        Some(LevelFix {
            size,
            centre_m: centre(size, actor)?,
            other: other.actor,
            other_centre_m,
        })
    }
}

/// The size a camera frames at the hold's mean distance: the nearest (in the ratio of framed
/// heights) of the table, for an actor of the scene's height.
fn framed_size(a: &Asked, lens: &Lens, heights_m: &[f64]) -> Option<Size> {
    let h = *heights_m.get(a.actor)?;
    let distance_m = a.sum_distance_m / a.n as f64;
    // d = W·Sy/2 (size.rs): the framed height this distance shows over the frame height.
    let shown_m = 2.0 * distance_m / lens.sy();
    if !(shown_m > 0.0 && h > 0.0) {
        return None;
    }
    Size::ALL.into_iter().min_by(|x, y| {
        let off = |s: Size| (math::ln(shown_m / crate::size::framed_height_m(s, h))).abs();
        off(*x).total_cmp(&off(*y))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_size_is_the_one_whose_distance_is_nearest() {
        let lens = Lens::new(92f64.to_radians(), 16.0 / 9.0);
        for size in Size::ALL {
            let d = crate::size::centred_distance_m(crate::size::framed_height_m(size, 1.8), &lens);
            let a = Asked {
                actor: 0,
                size,
                sum_distance_m: 3.0 * d,
                n: 3,
            };
            assert_eq!(
                framed_size(&a, &lens, &[1.8]),
                Some(size),
                "{size:?} at {d} m"
            );
        }
    }
}
