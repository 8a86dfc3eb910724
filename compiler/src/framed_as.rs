//! Whether each over-the-shoulder hold frames its actors at the sizes and from the sides the
//! script names (`compile::size_off`, `compile::profile_off`).
//!
//! A composition of two framings (`MS on Bob 34backright LS on Alice 34left`) asks for two
//! sizes and up to two profiles, but once the screen positions fix the angle between the actors
//! the toric solve can meet only one of them: the background's size, or a profile; the rest
//! follows from where the actors stand. Usually it follows closely enough. When it does not,
//! the shot is not the one written and nothing else says so:
//! `MS on Bob 34backright MS on Alice 34left`, actors 2 m apart, puts the camera at Alice's
//! MS distance (0.7 m) with Bob 2.5 m away, seen from the front: over Alice's shoulder, not
//! Bob's, with both actors on their screen points.
//!
//! Measured over each hold from the reference's camera, as [`crate::compile`]'s screen check
//! is: the mean horizontal distance to each framed actor gives the size the camera really
//! frames (the nearest of the size table, `size.rs`, for that distance and lens), the mean
//! bearing from the actor the profile. Reported when the size is two or more sizes off, or the
//! profile more than one and a half profile steps (67.5°).

use crate::code::CompileCode;
use dronecine_diag::Diagnostic;
use dronecine_grammar::script::{Script, ShotContent};
use dronecine_grammar::vocab::{Profile, Size};
use dronecine_math::wrap_angle_rad;

use crate::camera::Lens;
use crate::reference::ActorPose;
use dronecine_math as math;
use dronecine_profile::Gimbal;

/// Sizes apart (in `Size::ALL` order) from which a framed size is reported.
pub const SIZE_STEPS_OFF: usize = 2;
/// Angle from the requested profile beyond which the side an actor is seen from is reported:
/// one and a half steps of the eight profiles.
pub const PROFILE_OFF_RAD: f64 = 1.5 * std::f64::consts::FRAC_PI_4;

/// One actor's framing in a composition of several framings, and what the holds saw of it.
#[derive(Clone, Debug)]
struct Asked {
    actor: usize,
    size: Size,
    profile: Option<Profile>,
    sum_distance_m: f64,
    /// Sum of the unit vectors of the camera's bearing from the actor, relative to its facing.
    sum_cos: f64,
    sum_sin: f64,
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
                            profile: s.profile,
                            sum_distance_m: 0.0,
                            sum_cos: 0.0,
                            sum_sin: 0.0,
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

    /// Actor `i`'s name, or `or`.
    fn name<'a>(&'a self, i: usize, or: &'a str) -> &'a str {
        self.names.get(i).map_or(or, String::as_str)
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
            let (s, c) = math::sin_cos(math::atan2(dy, dx) - pose.facing_rad);
            a.sum_cos += c;
            a.sum_sin += s;
            a.n += 1;
        }
    }

    /// A warning for each actor of each hold framed two sizes or more off, or seen from a
    /// side more than [`PROFILE_OFF_RAD`] from its profile; none on a shot that already has
    /// an error (`skip`).
    pub fn diagnostics(
        &self,
        script: &Script,
        lens: &Lens,
        gimbal: &Gimbal,
        skip: impl Fn(usize) -> bool,
    ) -> Vec<Diagnostic> {
        let heights_m = &self.heights_m;
        let mut out = Vec::new();
        for (index, (asked, shot)) in self.shots.iter().zip(&script.timeline).enumerate() {
            if skip(index) {
                continue;
            }
            // The actor whose size the camera keeps, for the help.
            let kept = asked
                .iter()
                .filter(|a| a.n > 0)
                .find(|a| framed_size(a, lens, heights_m) == Some(a.size));
            for a in asked.iter().filter(|a| a.n > 0) {
                let who = self.name(a.actor, "an actor");
                let distance_m = a.sum_distance_m / a.n as f64;
                if let Some(got) = framed_size(a, lens, heights_m) {
                    if (got as usize).abs_diff(a.size as usize) >= SIZE_STEPS_OFF {
                        let asked_m = heights_m.get(a.actor).map_or(f64::NAN, |&h| {
                            crate::size::centred_distance_m(
                                crate::size::framed_height_m(a.size, h),
                                lens,
                            )
                        });
                        let rule = match kept {
                            Some(k) => format!(
                                "the camera keeps {}'s {}, and ",
                                self.name(k.actor, "the other actor"),
                                k.size.as_str()
                            ),
                            None => String::new(),
                        };
                        let write = if self.solves_with(script, index, a.actor, got, lens, gimbal) {
                            format!("write {who}'s size as {}, or ", got.as_str())
                        } else {
                            String::new()
                        };
                        out.push(
                            Diagnostic::warning(
                                CompileCode::SizeOff,
                                shot.span,
                                format!(
                                    "{who} is framed as {} {} ({distance_m:.1} m away), not as \
                                     the {} this shot asks ({asked_m:.1} m)",
                                    article(got),
                                    got.as_str(),
                                    a.size.as_str()
                                ),
                            )
                            .with_label(format!("{who} framed as {}", got.as_str()))
                            .with_help(format!(
                                "two framings fix the angle between the actors on screen; \
                                 then {rule}the other's size follows from where they stand: \
                                 {write}block the actors so that their distances to the camera \
                                 differ as the sizes do"
                            )),
                        );
                    }
                }
                if let Some(p) = a.profile {
                    let seen_rad = math::atan2(a.sum_sin, a.sum_cos);
                    let off_rad = wrap_angle_rad(seen_rad - p.azimuth_rad()).abs();
                    if off_rad > PROFILE_OFF_RAD && math::hypot(a.sum_sin, a.sum_cos) > 0.0 {
                        let seen = nearest_profile(seen_rad);
                        out.push(
                            Diagnostic::warning(
                                CompileCode::ProfileOff,
                                shot.span,
                                format!(
                                    "{who} is seen from the {} side ({}), {:.0}° from the {} \
                                     this shot asks",
                                    side(seen),
                                    seen.as_str(),
                                    off_rad.to_degrees(),
                                    p.as_str()
                                ),
                            )
                            .with_label(format!("{who} seen {}", seen.as_str()))
                            .with_help(
                                "two framings fix the angle between the actors on screen and \
                                 keep one actor's size or profile; the other's side follows \
                                 from where they stand: drop this profile, write the one the \
                                 camera gets, or block the actors so that the camera can be on \
                                 the side each profile names"
                                    .to_string(),
                            ),
                        );
                    }
                }
            }
        }
        out
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

/// The profile nearest a bearing from the actor (relative to its facing).
fn nearest_profile(bearing_rad: f64) -> Profile {
    Profile::ALL
        .into_iter()
        .min_by(|x, y| {
            let off = |p: Profile| wrap_angle_rad(bearing_rad - p.azimuth_rad()).abs();
            off(*x).total_cmp(&off(*y))
        })
        .expect("eight profiles")
}

/// In words, which of the actor's sides a profile sees.
fn side(p: Profile) -> &'static str {
    match p {
        Profile::Front => "front",
        Profile::ThreeQuarterLeft => "front-left",
        Profile::Left => "left",
        Profile::ThreeQuarterBackLeft => "back-left",
        Profile::Back => "back",
        Profile::ThreeQuarterBackRight => "back-right",
        Profile::Right => "right",
        Profile::ThreeQuarterRight => "front-right",
    }
}

fn article(s: Size) -> &'static str {
    match s {
        Size::ECU | Size::MCU | Size::MS | Size::MLS | Size::FS | Size::LS | Size::ELS => "an",
        Size::BCU | Size::CU => "a",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_name_the_side_they_see() {
        for p in Profile::ALL {
            assert_eq!(nearest_profile(p.azimuth_rad()), p);
            assert_eq!(nearest_profile(p.azimuth_rad() + 0.3), p);
        }
        assert_eq!(side(nearest_profile(0.0)), "front");
    }

    #[test]
    fn a_size_is_the_one_whose_distance_is_nearest() {
        let lens = Lens::new(92f64.to_radians(), 16.0 / 9.0);
        for size in Size::ALL {
            let d = crate::size::centred_distance_m(crate::size::framed_height_m(size, 1.8), &lens);
            let a = Asked {
                actor: 0,
                size,
                profile: None,
                sum_distance_m: 3.0 * d,
                sum_cos: 0.0,
                sum_sin: 0.0,
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
