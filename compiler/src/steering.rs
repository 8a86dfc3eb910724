//! Steering behaviours: the camera is a point mass pushed toward its manifold target, within
//! the profile's limits, kept inside the stage and away from the actors.
//!
//! The state is position, velocity and acceleration; each tick chooses a jerk (bounded) and
//! integrates it exactly, so velocity and acceleration are the derivatives of position by
//! construction and the reference is C² with bounded jerk. The behaviour is arrival with
//! feed-forward: `v_des = v_T + truncate(k_p·(p_T − p'))` capped at the speed limit, `p'`
//! where the camera is at the step's end if it keeps its acceleration (the desired speed falls
//! with the distance to the target, so the camera arrives without overshoot), `a_des = a_T +
//! k_v·(v_des − v')` plus separation from the actors' bodies and stage containment,
//! capped at the acceleration limit; `v'` is the velocity the camera reaches when its
//! acceleration is taken to the target's trend at full jerk, which keeps a jerk-limited camera
//! from overshooting and, on a target that speeds up or slows down, on it. Near the stage's
//! walls (less its margin) the speed toward each wall is capped at what the camera can brake from
//! before it, and the target's acceleration toward it is dropped ([`brake_for_walls`]). The
//! actors' bodies are kept clear as hard as the walls: the goal is held outside their
//! safety distance ([`kept_clear`]), a camera inside it moves out, and one whose course
//! would take it in brakes from its jerk-limited stopping distance. When the camera sits on
//! a smooth, feasible target the feed-forward terms keep it there exactly.
//!
//! Heading is steered the same way one order down (rate and rate-of-rate limits), with the
//! error wrapped to (−π, π] so the camera never turns the long way round.

use dronecine_math::wrap_angle_rad;

use crate::camera::Vec3;

/// Limits of the reference, from the drone profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteerLimits {
    pub speed_h_mps: f64,
    pub speed_v_mps: f64,
    pub accel_h_mps2: f64,
    pub accel_v_mps2: f64,
    pub jerk_mps3: f64,
    pub yaw_rate_radps: f64,
    pub yaw_accel_radps2: f64,
}

/// Gains of the arrival behaviour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteerGains {
    /// Position error → desired velocity, 1/s.
    pub k_p: f64,
    /// Velocity error → desired acceleration, 1/s.
    pub k_v: f64,
    /// Heading error → desired yaw rate, 1/s.
    pub k_heading: f64,
    /// Yaw-rate error → yaw acceleration, 1/s.
    pub k_heading_rate: f64,
}

impl Default for SteerGains {
    fn default() -> SteerGains {
        // Unsaturated, the loop is p̈ = k_v·(k_p·e − ṗ): ω² = k_p·k_v, ζ = √(k_v/k_p)/2 ≈ 1.2.
        // With these, under the ardrone2 limits and the jerk limit on, steps from 0.3 m to
        // 6 m arrive without overshoot.
        SteerGains {
            k_p: 1.0,
            k_v: 6.0,
            k_heading: 3.0,
            k_heading_rate: 12.0,
        }
    }
}

/// Position, velocity and acceleration of the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kinematics {
    pub p: Vec3,
    pub v: Vec3,
    pub a: Vec3,
}

/// An actor's body as the steering keeps clear of it: the feet-to-head segment, moving.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Body {
    pub feet_m: Vec3,
    pub height_m: f64,
    pub velocity_mps: Vec3,
}

impl Body {
    /// The point of the body's axis nearest `p`.
    pub fn nearest_m(&self, p: &Vec3) -> Vec3 {
        let z = (p.z - self.feet_m.z).clamp(0.0, self.height_m.max(0.0));
        self.feet_m + Vec3::new(0.0, 0.0, z)
    }

    /// Distance from `p` to the body's axis: the one measure of an actor's distance
    /// ([`crate::framing::body_axis_distance_m`] is this for an actor's pose).
    pub fn distance_m(&self, p: &Vec3) -> f64 {
        (p - self.nearest_m(p)).norm()
    }
}

impl From<&crate::reference::ActorPose> for Body {
    fn from(a: &crate::reference::ActorPose) -> Body {
        Body {
            feet_m: Vec3::from(a.position_m),
            height_m: a.height_m,
            velocity_mps: Vec3::from(a.velocity_mps),
        }
    }
}

/// The actors' bodies and the distance the camera keeps from each one's axis.
#[derive(Clone, Copy, Debug)]
pub struct Bodies<'a> {
    pub axes: &'a [Body],
    pub clear_m: f64,
}

impl Bodies<'_> {
    /// No actors.
    pub const NONE: Bodies<'static> = Bodies {
        axes: &[],
        clear_m: 0.0,
    };
}

/// `goal` held at least `bodies.clear_m` from every body's axis (an actor's safety
/// distance, measured as [`crate::framing::body_axis_distance_m`] measures it): a position
/// inside is put on that distance along the line from the nearest point of the axis, and
/// the velocity that would carry it further in than the body moves, and the acceleration
/// inward, are dropped. Bodies are taken in turn, twice, so that a goal between two actors
/// standing close settles outside both where it can.
pub fn kept_clear(mut goal: Kinematics, bodies: Bodies) -> Kinematics {
    for _ in 0..CLEAR_PASSES {
        let mut moved = false;
        for b in bodies.axes {
            let axis = b.nearest_m(&goal.p);
            let out = goal.p - axis;
            if !(out.norm_squared() < bodies.clear_m * bodies.clear_m) {
                continue;
            }
            let d = out.norm();
            // On the axis itself (a framing with no way out that is better than another):
            // out along x, which keeps the goal where it was from tick to tick.
            let n = if d > 1e-9 { out / d } else { Vec3::x() };
            goal.p = axis + n * bodies.clear_m;
            let inward_mps = (goal.v - b.velocity_mps).dot(&n);
            if inward_mps < 0.0 {
                goal.v -= n * inward_mps;
            }
            let inward_mps2 = goal.a.dot(&n);
            if inward_mps2 < 0.0 {
                goal.a -= n * inward_mps2;
            }
            moved = true;
        }
        if !moved {
            break;
        }
    }
    goal
}

/// How many times [`kept_clear`] takes the bodies in turn: a goal pushed out of one actor's
/// distance into another's is pushed out of that one on the second pass.
const CLEAR_PASSES: usize = 2;

/// Heading and its rate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeadingState {
    pub heading_rad: f64,
    pub rate_radps: f64,
}

/// Scale the horizontal part of `v` to at most `h` and the vertical part to at most `z`.
pub fn truncate_hv(v: Vec3, h: f64, z: f64) -> Vec3 {
    let n = dronecine_math::norm_xy(v.x, v.y);
    let s = if n > h && n > 0.0 { h / n } else { 1.0 };
    Vec3::new(v.x * s, v.y * s, v.z.clamp(-z, z))
}

/// Scale a vector to at most `max` in length.
pub fn truncate(v: Vec3, max: f64) -> Vec3 {
    let n = v.norm();
    if n > max && n > 0.0 {
        v * (max / n)
    } else {
        v
    }
}

/// The longest step the behaviours are integrated over at once. Each step holds its jerk
/// (and its separation and containment pushes) constant, so a coarser step is a different
/// camera: at 10 Hz the velocity loop's `k_v·Δ` is 0.6, and an actor's push held for a
/// whole step. A tick longer than this is integrated in [`substeps`] equal steps, so the
/// camera does not depend on the rate it is sampled at; at 100 Hz and faster, one step.
pub const MAX_STEP_S: f64 = 0.01;

/// The most sub-steps one tick is cut into (a tick of more than 10 s is steered in steps
/// longer than [`MAX_STEP_S`]).
const MAX_SUBSTEPS: usize = 1000;

/// The share by which a tick may exceed a whole number of [`MAX_STEP_S`] and still take no
/// more steps: a rate's period rounded to a float is a little longer than its true value.
const PERIOD_ALLOWANCE: f64 = 1e-6;

/// How many equal steps of at most [`MAX_STEP_S`] integrate a tick of `dt_s` (1 for a tick
/// of 10 ms or less, with a part-per-million allowance for a rate's rounded period, and for
/// a time step that is not a positive number).
pub fn substeps(dt_s: f64) -> usize {
    let n = (dt_s / MAX_STEP_S * (1.0 - PERIOD_ALLOWANCE)).ceil();
    if n.is_finite() && n > 1.0 {
        (n as usize).min(MAX_SUBSTEPS)
    } else {
        1
    }
}

impl Kinematics {
    /// Where a target moving with this state stood `back_s` earlier (its acceleration held):
    /// the goal of a sub-step that ends before the tick does.
    pub fn earlier(&self, back_s: f64) -> Kinematics {
        Kinematics {
            p: self.p - self.v * back_s + self.a * (back_s * back_s / 2.0),
            v: self.v - self.a * back_s,
            a: self.a,
        }
    }
}

/// One tick of the arrival behaviour toward `target` (its position, velocity and
/// acceleration, fed forward), with `extra` accelerations (separation, containment) added
/// before the limits. `trend_a` is the acceleration the target keeps up (its acceleration
/// low-passed; `target.a` for a smooth target), which the camera predicts its velocity
/// against. Integrates the chosen jerk exactly over `dt_s`.
#[allow(clippy::too_many_arguments)]
pub fn step(
    state: &Kinematics,
    target: &Kinematics,
    trend_a: &Vec3,
    extra: Vec3,
    walls: (&Vec3, &Vec3),
    bodies: Bodies,
    limits: &SteerLimits,
    gains: &SteerGains,
    dt_s: f64,
) -> Kinematics {
    // Arrival: the closing speed falls linearly near the target and never exceeds what
    // the camera can still brake from (√(2·a·d), with a margin for the jerk ramp).
    // The target is where the camera should be at the end of the step: compared with where
    // the camera is then if it keeps its acceleration (compared with where it is now, the
    // camera would be held one step's travel ahead of a moving target).
    let (dt2, dt3) = (dt_s * dt_s, dt_s * dt_s * dt_s);
    let e = target.p - (state.p + state.v * dt_s + state.a * (dt2 / 2.0));
    let d = e.norm();
    let brake = (2.0 * BRAKE_SHARE * limits.accel_h_mps2.min(limits.accel_v_mps2) * d).sqrt();
    let closing = truncate(gains.k_p * e, brake);
    let v_want = target.v + closing;
    let v_des = truncate_hv(v_want, limits.speed_h_mps, limits.speed_v_mps);
    let mut trend = *trend_a;
    let a_ff = at_speed_limit(&v_want, &v_des, target.a, &mut trend);
    let (v_des, a_ff, capped) = brake_for_walls(v_des, a_ff, &state.p, walls, limits);
    let (v_des, a_ff) = out_of_bodies(v_des, a_ff, &state.p, bodies, gains);
    // The velocity the camera reaches if its acceleration is taken to the target's at full
    // jerk: steering on it instead of on v keeps a jerk-limited camera from overshooting.
    // Relative to the target's acceleration, so that a camera on a target that speeds up or
    // slows down is steered on its own velocity, and stays on the target: predicted to zero
    // acceleration, it would be held a·|a|/(2·jerk·k_p) behind a target speeding up and as
    // far ahead of one slowing down, enough to take a flight to a close-up past its framing,
    // into the actor's distance.
    // The target's acceleration is taken as it trends (against live actors, the tick's own
    // is mostly their motion capture's noise differentiated twice, which the prediction's
    // square would rectify, the more so at rates where some ticks have no new frame),
    // toward a wall as the walls allow, and as far as the camera can follow it (a target
    // that jumps or sweeps faster than the drone can fly must not make the camera predict
    // itself tens of metres a second slow).
    for i in 0..3 {
        if capped[i] {
            trend[i] = a_ff[i];
        }
    }
    let lead = state.a - truncate_hv(trend, limits.accel_h_mps2, limits.accel_v_mps2);
    let v_pred = state.v + state.a * dt_s + lead * (lead.norm() / (2.0 * limits.jerk_mps3));
    let a_des = a_ff + gains.k_v * (v_des - v_pred) + extra;
    // The walls: the camera's own velocity once it stops accelerating.
    let v_stop = state.v + state.a * (state.a.norm() / (2.0 * limits.jerk_mps3));
    let (a_des, capped) = stop_before_walls(a_des, capped, &state.p, &v_stop, walls, limits);
    let a_des = truncate_accel(a_des, capped, limits);
    let a_des = stop_before_bodies(a_des, state, bodies, limits);
    let jerk = truncate((a_des - state.a) / dt_s, limits.jerk_mps3);
    Kinematics {
        p: state.p + state.v * dt_s + state.a * (dt2 / 2.0) + jerk * (dt3 / 6.0),
        v: state.v + state.a * dt_s + jerk * (dt2 / 2.0),
        a: state.a + jerk * dt_s,
    }
}

/// The target's acceleration `a` to feed forward, and its trend (in place), where the
/// desired velocity `want` was capped at the speed limits (to `des`): without the part that
/// would speed the camera up beyond them, along the capped horizontal velocity and on a capped
/// vertical one. The velocity loop balances a fed-forward acceleration with a velocity error
/// of `a/k_v`: a camera chasing a target that speeds up past the limit (a repositioning
/// flight re-planned against live actors) would run over the limit by that much. The rest
/// of the acceleration (the turn of a curving target) is kept.
pub fn at_speed_limit(want: &Vec3, des: &Vec3, mut a: Vec3, trend: &mut Vec3) -> Vec3 {
    let (h_want, h_des) = (
        dronecine_math::norm_xy(want.x, want.y),
        dronecine_math::norm_xy(des.x, des.y),
    );
    if h_want > h_des && h_des > 0.0 {
        let (ux, uy) = (des.x / h_des, des.y / h_des);
        for v in [&mut a, trend] {
            let along = v.x * ux + v.y * uy;
            if along > 0.0 {
                v.x -= along * ux;
                v.y -= along * uy;
            }
        }
    }
    if want.z.abs() > des.z.abs() {
        for v in [&mut a, trend] {
            if v.z * des.z > 0.0 {
                v.z = 0.0;
            }
        }
    }
    a
}

/// The share of the acceleration limit that arrival and the walls' speed cap plan to brake
/// with (`√(2·BRAKE_SHARE·a·d)` from `d` away); the rest is left for the jerk ramp and the
/// other axes.
const BRAKE_SHARE: f64 = 0.4;

/// The acceleration limit on axis `i` (x, y, z): the vertical one on z.
fn axis_accel_mps2(limits: &SteerLimits, i: usize) -> f64 {
    if i == 2 {
        limits.accel_v_mps2
    } else {
        limits.accel_h_mps2
    }
}

/// The desired velocity `v` and the target's acceleration `a` (the feed-forward) near the
/// faces of the box `walls` (`[lo, hi]`): the speed toward each face is capped at what the
/// camera can still brake from before it (the arrival law's `√(2·BRAKE_SHARE·a·d)`, `d` the
/// distance to that face; zero on or beyond it), and where the cap binds, the target's
/// acceleration toward that face is dropped; the third value marks the axes where it binds.
/// Arrival brakes on the distance to the target, which along a wall can be metres while the
/// wall is centimetres away, and follows the target's acceleration wherever it goes: a camera
/// chasing a target that slides toward the stage's margin and stops there would reach the
/// margin at speed and coast out of the stage.
pub fn brake_for_walls(
    mut v: Vec3,
    mut a: Vec3,
    p: &Vec3,
    walls: (&Vec3, &Vec3),
    limits: &SteerLimits,
) -> (Vec3, Vec3, [bool; 3]) {
    let (lo, hi) = walls;
    let mut capped = [false; 3];
    for i in 0..3 {
        let accel = axis_accel_mps2(limits, i);
        let allowed = |room: f64| (2.0 * BRAKE_SHARE * accel * room.max(0.0)).sqrt();
        if v[i] >= 0.0 {
            let cap = allowed(hi[i] - p[i]);
            if v[i] >= cap {
                v[i] = cap;
                a[i] = a[i].min(0.0);
                capped[i] = true;
            }
        }
        if v[i] <= 0.0 {
            let cap = allowed(p[i] - lo[i]);
            if v[i] <= -cap {
                v[i] = -cap;
                a[i] = a[i].max(0.0);
                capped[i] = true;
            }
        }
    }
    (v, a, capped)
}

/// The acceleration `a` with, on each axis where the camera (its velocity `v`) comes at a
/// face of the box `walls` faster than [`brake_for_walls`]'s cap allows (late: a target that
/// rushed at the face, or the camera's own momentum), at least the deceleration that stops it
/// before the face, the jerk ramp's distance allowed for; those axes are marked braking. The
/// cap's law alone brakes in proportion to how far over the cap the camera is, which near
/// the face is little: a camera coming fast at the margin (a repositioning flight whose end
/// the director holds on the margin) would run into it, and the drone, a few centimetres
/// behind its reference, out of the stage.
fn stop_before_walls(
    mut a: Vec3,
    mut capped: [bool; 3],
    p: &Vec3,
    v: &Vec3,
    walls: (&Vec3, &Vec3),
    limits: &SteerLimits,
) -> (Vec3, [bool; 3]) {
    let (lo, hi) = walls;
    for i in 0..3 {
        let accel = axis_accel_mps2(limits, i);
        // Toward the face ahead: its room, and the speed toward it.
        let (room, speed, sign) = if v[i] > 0.0 {
            (hi[i] - p[i], v[i], 1.0)
        } else {
            (p[i] - lo[i], -v[i], -1.0)
        };
        if speed.is_nan() || speed <= 0.0 {
            continue;
        }
        // While the deceleration ramps up at the jerk limit, the camera goes on at about its
        // speed for half the ramp.
        let ramp_m = speed * accel / (2.0 * limits.jerk_mps3);
        let need = speed * speed / (2.0 * (room - ramp_m).max(MIN_ROOM_M));
        if need > BRAKE_SHARE * accel {
            a[i] = if sign > 0.0 {
                a[i].min(-need)
            } else {
                a[i].max(need)
            };
            capped[i] = true;
        }
    }
    (a, capped)
}

/// The least room a camera is taken to have before a wall when it brakes: on the face or past
/// it, the deceleration asked is large but finite.
const MIN_ROOM_M: f64 = 1e-3;

/// The most acceleration the camera has along the unit vector `n` within its horizontal
/// and vertical limits.
fn accel_along_mps2(n: &Vec3, limits: &SteerLimits) -> f64 {
    let h = dronecine_math::norm_xy(n.x, n.y);
    let by_h = if h > 0.0 {
        limits.accel_h_mps2 / h
    } else {
        f64::INFINITY
    };
    let by_v = if n.z != 0.0 {
        limits.accel_v_mps2 / n.z.abs()
    } else {
        f64::INFINITY
    };
    by_h.min(by_v)
}

/// The desired velocity `v` and the target's acceleration `a` for a camera inside an
/// actor's distance (`bodies.clear_m` from the body's axis): relative to the body, it
/// moves out at `k_p` times its depth at least, and the target's acceleration inward is
/// dropped; along the body it goes on as the arrival law wants. A camera whose goal lies
/// across an actor would otherwise sit where the separation's push balances the arrival's
/// pull, inside the distance.
fn out_of_bodies(
    mut v: Vec3,
    mut a: Vec3,
    p: &Vec3,
    bodies: Bodies,
    gains: &SteerGains,
) -> (Vec3, Vec3) {
    for b in bodies.axes {
        let out = p - b.nearest_m(p);
        if !(out.norm_squared() < bodies.clear_m * bodies.clear_m) {
            continue;
        }
        let d = out.norm();
        if !(d > 1e-9) {
            continue;
        }
        let n = out / d;
        let want_mps = gains.k_p * (bodies.clear_m - d);
        let outward_mps = (v - b.velocity_mps).dot(&n);
        if outward_mps < want_mps {
            v += n * (want_mps - outward_mps);
        }
        let inward = a.dot(&n);
        if inward < 0.0 {
            a -= n * inward;
        }
    }
    (v, a)
}

/// The acceleration `a` braking for the actors' bodies ([`stop_before_walls`] for a body).
/// A camera (`state`, relative to the body's motion) brakes for a body when, braking at
/// [`BRAKE_SHARE`] of its limit along the line from the body, reached from the acceleration
/// it has now at its jerk limit ([`stopping_m`]), it would come within `bodies.clear_m`, and
/// its course with `a` does come within it; it then brakes with the deceleration that stops
/// it at that distance (its limit if none does). The brakes of every body it brakes for are
/// summed and come first, within the limit; what `a` did across them keeps the room left.
/// Called on an acceleration already within the limits.
///
/// The course matters: judged on the straight line, or braking without an exact stopping
/// distance, a camera following a framing that curves away or slows by itself (one that
/// heads for an actor and stops short of them, a crane swinging past an actor) would be held
/// back behind it. The director holds its goal outside the distance; without this the
/// camera, a jerk-limited point mass chasing a framing that stops where an actor's distance
/// holds it, would run on past the goal, into the actor's distance.
fn stop_before_bodies(a: Vec3, state: &Kinematics, bodies: Bodies, limits: &SteerLimits) -> Vec3 {
    let jerk = limits.jerk_mps3;
    // The most the camera can brake with along any line (for the quick test below).
    let most = limits.accel_h_mps2.max(limits.accel_v_mps2);
    let least_brake = BRAKE_SHARE * limits.accel_h_mps2.min(limits.accel_v_mps2);
    // Each body's brake, outward, summed: a camera squeezed between two actors brakes for
    // both (braking for the second alone would undo the first's, and the camera would go on
    // between them).
    let mut brakes = Vec3::zeros();
    for b in bodies.axes {
        let out = state.p - b.nearest_m(&state.p);
        let rel = state.v - b.velocity_mps;
        // Not closing: nothing to brake for (tested before any square root).
        if !(rel.dot(&out) < 0.0) {
            continue;
        }
        let d = out.norm();
        let n = out / d;
        let speed = -rel.dot(&n);
        let room_m = d - bodies.clear_m;
        // Far enough that it stops whatever it does: its speed held over the longest ramp
        // to the brake, then the brake (a bound on `stopping_m`).
        let speeding_up = -state.a.dot(&n);
        let ramp_s = (speeding_up.max(0.0) + most) / jerk;
        let fast_mps = speed + speeding_up.max(0.0) * ramp_s;
        if room_m > fast_mps * ramp_s + fast_mps * fast_mps / (2.0 * least_brake) {
            continue;
        }
        let accel = accel_along_mps2(&n, limits);
        let brake = BRAKE_SHARE * accel;
        if stopping_m(speed, speeding_up, brake, jerk) < room_m {
            continue;
        }
        // The course the camera is on with the acceleration it is given, until braking at
        // that share would have stopped it closing: does it come within the distance?
        let horizon_s = speed / brake;
        // (Relative to the body: its axis stands where it is now, the camera moves at `rel`.)
        let enters = (1..=COURSE_POINTS).any(|k| {
            let t = horizon_s * k as f64 / COURSE_POINTS as f64;
            b.distance_m(&(state.p + rel * t + a * (t * t / 2.0))) < bodies.clear_m
        });
        if !enters {
            continue;
        }
        // The deceleration that stops it at the distance, between that share and the limit.
        let need = if stopping_m(speed, speeding_up, accel, jerk) >= room_m {
            accel
        } else {
            let (mut lo, mut hi) = (brake, accel);
            for _ in 0..BRAKE_BISECTIONS {
                let mid = (lo + hi) / 2.0;
                if stopping_m(speed, speeding_up, mid, jerk) >= room_m {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            hi
        };
        if a.dot(&n) < need {
            brakes += n * need;
        }
    }
    let size = brakes.norm();
    if !(size > 0.0) {
        return a;
    }
    // The brakes first, within the limit along them; what `a` did across them keeps the
    // room left.
    let way = brakes / size;
    let accel = accel_along_mps2(&way, limits);
    let brake = way * size.min(accel);
    let across = a - way * a.dot(&way);
    let left = (accel * accel - brake.norm_squared()).max(0.0).sqrt();
    brake + truncate(across, left)
}

/// How far a point closing at `speed` (m/s, positive), speeding up at `speeding_up` (m/s²,
/// negative while it slows), goes before it stops when it brakes at `brake` (m/s²) reached
/// at `jerk` (m/s³): the ramp from its acceleration to the brake, then the brake.
fn stopping_m(speed: f64, speeding_up: f64, brake: f64, jerk: f64) -> f64 {
    let c0 = speeding_up.max(-brake);
    let ramp_s = (c0 + brake) / jerk;
    // Its speed during the ramp: speed + c0·t − jerk·t²/2; stopped within the ramp?
    let stop_s = (c0 + (c0 * c0 + 2.0 * jerk * speed).sqrt()) / jerk;
    let gone = |t: f64| speed * t + c0 * t * t / 2.0 - jerk * t * t * t / 6.0;
    if stop_s <= ramp_s {
        return gone(stop_s);
    }
    let left = speed + c0 * ramp_s - jerk * ramp_s * ramp_s / 2.0;
    gone(ramp_s) + left * left / (2.0 * brake)
}

/// How many points of its course [`stop_before_bodies`] checks against a body.
const COURSE_POINTS: usize = 8;

/// How many halvings [`stop_before_bodies`] searches the deceleration that stops a camera at
/// an actor's distance in: to a 4096th of the range between its share of the limit and the
/// limit.
const BRAKE_BISECTIONS: usize = 12;

/// [`truncate_hv`] for an acceleration, except that when exactly one horizontal axis is
/// braking for a wall (`capped`, from [`brake_for_walls`]) that axis has the first call on
/// the horizontal limit and the other gets what is left. Scaling both alike would let a
/// camera speeding up along a wall brake from it at a fraction of its limit.
fn truncate_accel(a: Vec3, capped: [bool; 3], limits: &SteerLimits) -> Vec3 {
    let h = limits.accel_h_mps2;
    let z = a.z.clamp(-limits.accel_v_mps2, limits.accel_v_mps2);
    let (first, other) = match (capped[0], capped[1]) {
        (true, false) => (0, 1),
        (false, true) => (1, 0),
        _ => return truncate_hv(a, h, limits.accel_v_mps2),
    };
    let mut out = Vec3::new(0.0, 0.0, z);
    out[first] = a[first].clamp(-h, h);
    let left = (h * h - out[first] * out[first]).max(0.0).sqrt();
    out[other] = a[other].clamp(-left, left);
    out
}

/// The sub-steps of a tick of `dt_s` ([`substeps`]): each one's length, and how long before
/// the tick's end it ends.
fn schedule(dt_s: f64) -> impl Iterator<Item = (f64, f64)> {
    let n = substeps(dt_s);
    let h = dt_s / n as f64;
    (0..n).map(move |k| (h, (n - 1 - k) as f64 * h))
}

/// `one(state, h, back_s)` over the [`schedule`] of a tick of `dt_s`, each sub-step from the
/// state the one before left.
fn substepped<S: Copy>(state: &S, dt_s: f64, one: impl Fn(&S, f64, f64) -> S) -> S {
    let mut s = *state;
    for (h, back_s) in schedule(dt_s) {
        s = one(&s, h, back_s);
    }
    s
}

/// A tick of `dt_s` of [`step`] toward `goal`, in [`substeps`] equal steps each toward the
/// goal as it stood at that step's end ([`Kinematics::earlier`]), with `extra(p)` the
/// separation and containment pushes at the camera's position `p`. One step, toward `goal`
/// itself, for a tick of 10 ms or less.
#[allow(clippy::too_many_arguments)]
pub fn advance(
    state: &Kinematics,
    goal: &Kinematics,
    trend_a: &Vec3,
    extra: impl Fn(&Vec3) -> Vec3,
    walls: (&Vec3, &Vec3),
    bodies: Bodies,
    limits: &SteerLimits,
    gains: &SteerGains,
    dt_s: f64,
) -> Kinematics {
    substepped(state, dt_s, |s, h, back_s| {
        let goal_then = if back_s > 0.0 {
            goal.earlier(back_s)
        } else {
            *goal
        };
        step(
            s,
            &goal_then,
            trend_a,
            extra(&s.p),
            walls,
            bodies,
            limits,
            gains,
            h,
        )
    })
}

/// [`advance`] for the heading: [`step_heading`] in [`substeps`] equal steps, each toward the
/// target as it stood at that step's end.
pub fn advance_heading(
    state: &HeadingState,
    target_rad: f64,
    target_rate_radps: f64,
    limits: &SteerLimits,
    gains: &SteerGains,
    dt_s: f64,
) -> HeadingState {
    substepped(state, dt_s, |s, h, back_s| {
        let target_then = if back_s > 0.0 {
            target_rad - target_rate_radps * back_s
        } else {
            target_rad
        };
        step_heading(s, target_then, target_rate_radps, limits, gains, h)
    })
}

/// One tick of heading steering toward `target_rad` turning at `target_rate_radps`.
pub fn step_heading(
    state: &HeadingState,
    target_rad: f64,
    target_rate_radps: f64,
    limits: &SteerLimits,
    gains: &SteerGains,
    dt_s: f64,
) -> HeadingState {
    // As for the position: against the heading at the step's end (against the one at its
    // start, a turning target would be led by one step's turn).
    let err = wrap_angle_rad(target_rad - (state.heading_rad + state.rate_radps * dt_s));
    let rate_des = (target_rate_radps + gains.k_heading * err)
        .clamp(-limits.yaw_rate_radps, limits.yaw_rate_radps);
    let acc = (gains.k_heading_rate * (rate_des - state.rate_radps))
        .clamp(-limits.yaw_accel_radps2, limits.yaw_accel_radps2);
    HeadingState {
        heading_rad: wrap_angle_rad(
            state.heading_rad + state.rate_radps * dt_s + acc * dt_s * dt_s / 2.0,
        ),
        rate_radps: state.rate_radps + acc * dt_s,
    }
}

/// Separation from actors: a push away from each actor's body axis (the
/// segment from their feet to the top of their head, [`Body::nearest_m`]) when the camera
/// is closer than `radius_m` to it, growing as `gain·(radius − d)/d` (m/s²; `gain` at
/// d = radius/2). Beside the body it pushes level; above the head, up and out.
pub fn separation(p: &Vec3, axes: &[Body], radius_m: f64, gain: f64) -> Vec3 {
    let mut f = Vec3::zeros();
    for body in axes {
        let d = p - body.nearest_m(p);
        let n = d.norm();
        if n < radius_m && n > 1e-6 {
            f += d / n * (gain * (radius_m - n) / n);
        }
    }
    f
}

/// Containment: a spring pushing back inside the box `[lo, hi]` when the camera is outside.
pub fn containment(p: &Vec3, lo: &Vec3, hi: &Vec3, stiffness: f64) -> Vec3 {
    let mut f = Vec3::zeros();
    for i in 0..3 {
        if p[i] < lo[i] {
            f[i] = stiffness * (lo[i] - p[i]);
        } else if p[i] > hi[i] {
            f[i] = stiffness * (hi[i] - p[i]);
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No walls within reach.
    const OPEN: (&Vec3, &Vec3) = (&Vec3::new(-1e9, -1e9, -1e9), &Vec3::new(1e9, 1e9, 1e9));

    fn body(feet_m: Vec3, height_m: f64) -> Body {
        Body {
            feet_m,
            height_m,
            velocity_mps: Vec3::zeros(),
        }
    }

    /// One step toward `target`, its acceleration fed forward as it is, with no pushes, no
    /// walls within reach and no actors.
    fn open_step(
        s: &Kinematics,
        target: &Kinematics,
        lim: &SteerLimits,
        gains: &SteerGains,
        dt: f64,
    ) -> Kinematics {
        step(
            s,
            target,
            &target.a,
            Vec3::zeros(),
            OPEN,
            Bodies::NONE,
            lim,
            gains,
            dt,
        )
    }

    fn limits() -> SteerLimits {
        SteerLimits {
            speed_h_mps: 1.8,
            speed_v_mps: 0.7,
            accel_h_mps2: 1.0,
            accel_v_mps2: 1.0,
            jerk_mps3: 2.0,
            yaw_rate_radps: 1.5,
            yaw_accel_radps2: 3.0,
        }
    }

    #[test]
    fn a_long_tick_is_cut_into_steps_of_at_most_ten_milliseconds() {
        // 100 Hz and faster: one step, whatever the period's rounding.
        for dt in [0.01, 0.01 + 1e-15, 1.0 / 100.0, 0.002, 1e-9] {
            assert_eq!(substeps(dt), 1, "{dt}");
        }
        assert_eq!(substeps(0.02), 2);
        assert_eq!(substeps(1.0 / 30.0), 4);
        assert_eq!(substeps(0.1), 10);
        // Not a positive number: one step (the caller does not steer it anyway).
        for dt in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            assert_eq!(substeps(dt), 1, "{dt}");
        }
        assert_eq!(substeps(1e6), MAX_SUBSTEPS);
        // Each step within the limit, up to 10 s.
        for k in 1..=1000 {
            let dt = k as f64 * 0.0137;
            let n = substeps(dt);
            assert!(
                dt / n as f64 <= MAX_STEP_S * (1.0 + 1e-9) || n == MAX_SUBSTEPS,
                "{dt}"
            );
            assert!(
                n == 1 || dt / (n - 1) as f64 > MAX_STEP_S,
                "{dt}: {n} is more than needed"
            );
        }
    }

    #[test]
    fn ten_hertz_in_substeps_follows_a_moving_target_as_a_hundred_hertz_does() {
        // A camera catching up with a target that accelerates along x past an actor: at
        // 10 Hz in one step (the actor's push held for the whole step) it is more than 1.2 cm
        // off the camera stepped at 100 Hz; in sub-steps, within 6 mm (the target's
        // acceleration steps at 2 s, which the sub-steps' goals do not see coming).
        let lim = limits();
        let gains = SteerGains::default();
        let target_at = |t: f64| {
            let a = if t < 2.0 { 0.3 } else { 0.0 };
            let tt = t.min(2.0);
            let (p, v) = (0.15 * tt * tt + 0.6 * (t - tt), 0.3 * tt);
            Kinematics {
                p: Vec3::new(p, 0.0, 1.0),
                v: Vec3::new(v, 0.0, 0.0),
                a: Vec3::new(a, 0.0, 0.0),
            }
        };
        let fly = |dt: f64, sub: bool| {
            let mut s = Kinematics {
                p: Vec3::new(-0.5, 0.0, 1.0),
                ..Default::default()
            };
            let mut out = Vec::new();
            let ticks = (6.0 / dt).round() as usize;
            for k in 1..=ticks {
                let t = k as f64 * dt;
                let goal = target_at(t);
                // An actor beside the way, whose separation pushes the camera past them.
                let axes = [body(Vec3::new(0.6, 0.3, 0.0), 1.8)];
                let bodies = Bodies {
                    axes: &axes,
                    clear_m: 0.5,
                };
                let push = |p: &Vec3| separation(p, &axes, 0.5, 3.0);
                s = if sub {
                    advance(&s, &goal, &goal.a, push, OPEN, bodies, &lim, &gains, dt)
                } else {
                    step(
                        &s,
                        &goal,
                        &goal.a,
                        push(&s.p),
                        OPEN,
                        bodies,
                        &lim,
                        &gains,
                        dt,
                    )
                };
                out.push((t, s.p));
            }
            out
        };
        let fine = fly(0.01, false);
        let at = |t: f64| fine[(t * 100.0).round() as usize - 1].1;
        let worst = |path: &[(f64, Vec3)]| {
            path.iter()
                .map(|(t, p)| (p - at(*t)).norm())
                .fold(0.0, f64::max)
        };
        let (one_step, sub_stepped) = (worst(&fly(0.1, false)), worst(&fly(0.1, true)));
        assert!(one_step > 0.012, "{one_step}");
        assert!(sub_stepped < 0.006, "{sub_stepped} (one step: {one_step})");
    }

    #[test]
    fn a_target_that_outruns_the_speed_limit_is_chased_at_the_limit() {
        // A target speeding up at 0.7 m/s² along a gentle curve, past the 1.8 m/s limit (a
        // repositioning flight re-planned against live actors). Its acceleration fed forward
        // whole would hold the camera over the limit; only the part across its velocity is,
        // the curve's turn.
        let lim = limits();
        let gains = SteerGains::default();
        let (dt, acc, w) = (0.01, 0.7, 0.05);
        let at = |t: f64| {
            // Its speed 0.7·t, its heading turning at w.
            let (speed, th) = (acc * t, w * t);
            let (s, c) = th.sin_cos();
            let tangent = Vec3::new(c, s, 0.0);
            let normal = Vec3::new(-s, c, 0.0);
            Kinematics {
                // Its position is not used for the speed; the camera chases its velocity.
                p: Vec3::new(0.0, 0.0, 1.0),
                v: tangent * speed,
                a: tangent * acc + normal * (speed * w),
            }
        };
        let mut s = Kinematics {
            p: Vec3::new(0.0, 0.0, 1.0),
            ..Default::default()
        };
        let mut top = 0.0f64;
        for k in 1..=800 {
            let mut target = at(k as f64 * dt);
            // A goal that keeps ahead of the camera: where the camera would be at its speed.
            target.p = s.p + target.v * 0.5;
            s = open_step(&s, &target, &lim, &gains, dt);
            top = top.max(s.v.x.hypot(s.v.y));
        }
        assert!(
            top <= lim.speed_h_mps * 1.005,
            "{top} against {}",
            lim.speed_h_mps
        );
        // It got there, and kept turning with the target.
        assert!(top >= lim.speed_h_mps * 0.99, "{top}");
        let heading = s.v.y.atan2(s.v.x);
        assert!((heading - w * 8.0).abs() < 0.05, "{heading}");
    }

    #[test]
    fn arrives_without_overshoot_and_within_limits() {
        let lim = limits();
        let gains = SteerGains::default();
        let target = Kinematics {
            p: Vec3::new(3.0, 0.0, 0.5),
            ..Default::default()
        };
        let mut s = Kinematics::default();
        let dt = 0.01;
        let mut prev = s;
        for k in 0..2000 {
            s = open_step(&s, &target, &lim, &gains, dt);
            assert!(
                s.v.x.hypot(s.v.y) <= lim.speed_h_mps + 1e-9,
                "tick {k}: {:?}",
                s.v
            );
            assert!(s.a.x.hypot(s.a.y) <= lim.accel_h_mps2 + 1e-9);
            assert!(((s.a - prev.a) / dt).norm() <= lim.jerk_mps3 + 1e-9);
            assert!(
                s.p.x <= 3.0 + 1e-3 && s.p.z <= 0.5 + 1e-3,
                "overshoot {}",
                s.p.x
            );
            // v and a are the derivatives of p: the exact integration makes the mean
            // velocity over the tick equal to the position increment.
            let mean_v = (s.p - prev.p) / dt;
            assert!((mean_v - (prev.v + s.v) / 2.0).norm() < 1e-3);
            prev = s;
        }
        assert!((s.p - target.p).norm() < 1e-3, "{:?}", s.p);
    }

    #[test]
    fn a_tracked_smooth_target_is_held_exactly() {
        let lim = limits();
        let gains = SteerGains::default();
        let dt = 0.01;
        let w = 0.3;
        let at = |t: f64| Kinematics {
            p: Vec3::new((w * t).cos(), (w * t).sin(), 1.0),
            v: Vec3::new(-w * (w * t).sin(), w * (w * t).cos(), 0.0),
            a: Vec3::new(-w * w * (w * t).cos(), -w * w * (w * t).sin(), 0.0),
        };
        let mut s = at(0.0);
        let mut worst: f64 = 0.0;
        for k in 1..3000 {
            let goal = at(k as f64 * dt);
            s = step(
                &s,
                &goal,
                &goal.a,
                Vec3::zeros(),
                OPEN,
                Bodies::NONE,
                &lim,
                &gains,
                dt,
            );
            worst = worst.max((s.p - at(k as f64 * dt).p).norm());
        }
        assert!(worst < 1e-3, "{worst}");
    }

    /// The furthest past the face y = `face` that a camera gets, with `lim` the drone's
    /// limits and `walls` the box it brakes for, chasing the target `at(t)` for 8 s at 100 Hz.
    fn furthest_past(
        face: f64,
        walls: (&Vec3, &Vec3),
        lim: &SteerLimits,
        at: impl Fn(f64) -> Kinematics,
    ) -> f64 {
        let gains = SteerGains::default();
        let dt = 0.01;
        let mut s = at(0.0);
        let mut furthest = f64::NEG_INFINITY;
        for k in 1..800 {
            let goal = at(k as f64 * dt);
            s = step(
                &s,
                &goal,
                &goal.a,
                Vec3::zeros(),
                walls,
                Bodies::NONE,
                lim,
                &gains,
                dt,
            );
            furthest = furthest.max(s.p.y - face);
        }
        furthest
    }

    /// The furthest past the face y = `face` that a camera gets when it chases a target
    /// sliding toward that face at 0.7 m/s (and along it at 0.5 m/s, speeding up), held on
    /// the face once it gets there, as the director keeps its target inside the stage less
    /// its margin.
    fn overshoot_past(face: f64, walls: (&Vec3, &Vec3)) -> f64 {
        furthest_past(face, walls, &limits(), |t| {
            let y = 1.0 + 0.7 * t;
            let on_face = y >= face;
            Kinematics {
                p: Vec3::new(0.5 * t + 0.15 * t * t, y.min(face), 1.0),
                v: Vec3::new(0.5 + 0.3 * t, if on_face { 0.0 } else { 0.7 }, 0.0),
                a: Vec3::new(0.3, 0.0, 0.0),
            }
        })
    }

    /// The furthest past the face y = `face` a camera gets chasing a target that comes at the
    /// face at `speed_mps` from 3 m (a repositioning flight's route whose end the director
    /// holds on the face) while turning along it (`ax` the target's acceleration along the
    /// face), with `lim` the drone's limits.
    fn overshoot_fast(face: f64, speed_mps: f64, ax: f64, lim: &SteerLimits) -> f64 {
        let (lo, hi) = (Vec3::new(-50.0, -50.0, 0.0), Vec3::new(50.0, face, 3.0));
        furthest_past(face, (&lo, &hi), lim, |t| {
            let y = face - 3.0 + speed_mps * t;
            let on_face = y >= face;
            Kinematics {
                p: Vec3::new(0.6 * t + ax * t * t / 2.0, y.min(face), 1.0),
                v: Vec3::new(0.6 + ax * t, if on_face { 0.0 } else { speed_mps }, 0.0),
                a: Vec3::new(ax, 0.0, 0.0),
            }
        })
    }

    /// A camera that comes at the face fast (a repositioning flight's route whose end the
    /// director holds on the margin) stops before it, with the outdoor AR.Drone's limits,
    /// while the target turns along the face: the cap's law alone would let it run past.
    #[test]
    fn a_camera_that_comes_at_a_wall_fast_stops_before_it() {
        let outdoor = SteerLimits {
            speed_h_mps: 3.06,
            speed_v_mps: 1.0,
            accel_h_mps2: 1.8,
            accel_v_mps2: 1.8,
            jerk_mps3: 5.0,
            yaw_rate_radps: 3.5,
            yaw_accel_radps2: 3.0,
        };
        for speed in [0.7, 1.0, 1.5, 1.9, 2.5] {
            for ax in [0.0, -1.3, 1.3] {
                let past = overshoot_fast(2.7, speed, ax, &outdoor);
                assert!(
                    past < 0.035,
                    "{speed} m/s, along {ax} m/s²: {past:.3} m past"
                );
            }
        }
        // At full speed with 3 m to go (2.5 m to stop, and the jerk ramp) it cannot stop in
        // time, but it brakes at once.
        assert!(overshoot_fast(2.7, 3.0, -1.3, &outdoor) < 0.2);
    }

    #[test]
    fn a_camera_brakes_for_a_wall_its_target_slides_against() {
        let face = 2.7;
        let (lo, hi) = (Vec3::new(-50.0, -50.0, 0.0), Vec3::new(50.0, face, 3.0));
        let braked = overshoot_past(face, (&lo, &hi));
        let free = overshoot_past(face, OPEN);
        // 5 cm with these limits (a jerk of 2 m/s³; 2 cm at the AR.Drone's 5 m/s³)…
        assert!(braked < 0.06, "{braked}");
        // …where braking on the distance to the target alone (metres ahead along the wall)
        // runs more than 0.3 m on.
        assert!(free > 0.3, "{free}");
        // Away from the walls nothing changes.
        let v = Vec3::new(0.9, -0.4, 0.2);
        let a = Vec3::new(0.1, 0.2, -0.3);
        assert_eq!(
            brake_for_walls(v, a, &Vec3::new(0.0, 0.0, 1.0), (&lo, &hi), &limits()),
            (v, a, [false; 3])
        );
        // On a face, nothing more toward it; away from it, anything.
        let on = Vec3::new(0.0, face, 1.0);
        let (v_on, a_on, capped) = brake_for_walls(v, -a, &on, (&lo, &hi), &limits());
        assert_eq!((v_on.y, capped), (-0.4, [false; 3]));
        assert_eq!(a_on, -a);
        let (v_on, a_on, capped) = brake_for_walls(-v, a, &on, (&lo, &hi), &limits());
        assert_eq!((v_on.y, a_on.y, capped), (0.0, 0.0, [false, true, false]));
    }

    #[test]
    fn heading_turns_the_short_way() {
        let lim = limits();
        let gains = SteerGains::default();
        let mut h = HeadingState {
            heading_rad: 170f64.to_radians(),
            rate_radps: 0.0,
        };
        let target = (-170f64).to_radians();
        for _ in 0..300 {
            h = step_heading(&h, target, 0.0, &lim, &gains, 0.01);
            assert!(
                h.rate_radps >= -1e-9,
                "turned the long way: {}",
                h.rate_radps
            );
            assert!(h.rate_radps <= lim.yaw_rate_radps + 1e-9);
        }
        assert!(wrap_angle_rad(h.heading_rad - target).abs() < 1e-3);
    }

    /// A target turning at a steady 0.8 rad/s across ±π: the camera's heading, started on
    /// it, stays on it (compared with the heading at the step's start, it would be held one
    /// step's turn ahead).
    #[test]
    fn a_heading_on_a_steadily_turning_target_stays_on_it() {
        let lim = limits();
        let gains = SteerGains::default();
        let rate = 0.8;
        let at = |t: f64| wrap_angle_rad(3.0 + rate * t);
        let mut h = HeadingState {
            heading_rad: at(0.0),
            rate_radps: rate,
        };
        let mut worst: f64 = 0.0;
        for k in 1..=800 {
            let t = k as f64 * 0.01;
            h = step_heading(&h, at(t), rate, &lim, &gains, 0.01);
            worst = worst.max(wrap_angle_rad(h.heading_rad - at(t)).abs());
        }
        assert!(worst < 1e-6, "{worst} rad");
    }

    #[test]
    fn separation_pushes_away_and_containment_pushes_in() {
        let axes = [body(Vec3::new(0.0, 0.0, 0.0), 1.8)];
        let f = separation(&Vec3::new(0.3, 0.0, 1.5), &axes, 0.5, 1.0);
        assert!(f.x > 0.0 && f.y.abs() < 1e-12);
        assert_eq!(
            separation(&Vec3::new(0.6, 0.0, 1.5), &axes, 0.5, 1.0),
            Vec3::zeros()
        );
        let c = containment(
            &Vec3::new(4.2, 0.0, -0.1),
            &Vec3::new(-4.0, -3.0, 0.3),
            &Vec3::new(4.0, 3.0, 2.7),
            2.0,
        );
        assert!(c.x < 0.0 && c.z > 0.0 && c.y == 0.0);
    }

    /// The closest a camera comes to the body's axis of `axes[0]`, flown `seconds` at
    /// 100 Hz from `start` toward the goal `goal_at(t)` held clear of the bodies (as the
    /// director holds it), with the separation push and, when `keep` is set, the bodies
    /// kept clear by the steering itself; and where it ends.
    fn closest_flown(
        start: Kinematics,
        goal_at: impl Fn(f64) -> Kinematics,
        axes: &[Body],
        keep: bool,
        seconds: f64,
    ) -> (f64, Kinematics) {
        let (lim, gains) = (limits(), SteerGains::default());
        let bodies = Bodies { axes, clear_m: 0.5 };
        let mut s = start;
        let mut closest = f64::INFINITY;
        let dt = 0.01;
        for k in 1..=(seconds / dt).round() as usize {
            let goal = kept_clear(goal_at(k as f64 * dt), bodies);
            let push = separation(&s.p, axes, 0.5, 3.0);
            let kept = if keep { bodies } else { Bodies::NONE };
            s = step(&s, &goal, &goal.a, push, OPEN, kept, &lim, &gains, dt);
            closest = closest.min((s.p - axes[0].nearest_m(&s.p)).norm());
        }
        (closest, s)
    }

    #[test]
    fn a_goal_inside_an_actors_distance_is_held_on_it() {
        let walking = Body {
            velocity_mps: Vec3::new(0.4, 0.0, 0.0),
            ..body(Vec3::zeros(), 1.8)
        };
        let bodies = Bodies {
            axes: std::slice::from_ref(&walking),
            clear_m: 0.5,
        };
        // Beside the body, coming in at 1 m/s and along it at 0.3 m/s: out to 0.5 m on the
        // same line, moving out as fast as the actor walks at it, along as before.
        let held = kept_clear(
            Kinematics {
                p: Vec3::new(0.3, 0.0, 1.0),
                v: Vec3::new(-1.0, 0.3, 0.0),
                a: Vec3::new(-2.0, 0.5, 0.0),
            },
            bodies,
        );
        assert!(
            (held.p - Vec3::new(0.5, 0.0, 1.0)).norm() < 1e-12,
            "{:?}",
            held.p
        );
        assert!(
            (held.v - Vec3::new(0.4, 0.3, 0.0)).norm() < 1e-12,
            "{:?}",
            held.v
        );
        assert!(
            (held.a - Vec3::new(0.0, 0.5, 0.0)).norm() < 1e-12,
            "{:?}",
            held.a
        );
        // Over the head: up, to 0.5 m above it.
        let over = kept_clear(
            Kinematics {
                p: Vec3::new(0.0, 0.0, 2.0),
                ..Default::default()
            },
            bodies,
        );
        assert!(
            (over.p - Vec3::new(0.0, 0.0, 2.3)).norm() < 1e-12,
            "{:?}",
            over.p
        );
        // Outside: the same bits.
        let clear = Kinematics {
            p: Vec3::new(0.0, 0.51, 1.0),
            v: Vec3::new(0.0, -1.0, 0.0),
            a: Vec3::new(0.0, -1.0, 0.0),
        };
        assert_eq!(kept_clear(clear, bodies), clear);
    }

    /// A framing that comes at an actor at 0.6 m/s and stops 0.3 m from them is held on
    /// their distance, where it stops at once, and so does the camera; without braking for the
    /// body, the camera, a jerk-limited point mass on its heels, runs on past it into the
    /// distance.
    #[test]
    fn a_camera_whose_goal_stops_at_an_actors_distance_stops_there_too() {
        let axes = [body(Vec3::zeros(), 1.8)];
        let goal_at = |t: f64| {
            let x = 2.0 - 0.6 * t;
            Kinematics {
                p: Vec3::new(x.max(0.3), 0.05, 1.2),
                v: Vec3::new(if x > 0.3 { -0.6 } else { 0.0 }, 0.0, 0.0),
                a: Vec3::zeros(),
            }
        };
        let start = goal_at(0.0);
        let (free, _) = closest_flown(start, goal_at, &axes, false, 6.0);
        let (kept, end) = closest_flown(start, goal_at, &axes, true, 6.0);
        assert!(free < 0.48, "{free} m without the bodies");
        assert!(kept > 0.495, "{kept} m (without the bodies: {free} m)");
        // Where the goal is held: 0.5 m out along the line through (0.3, 0.05).
        let held = Vec3::new(0.3, 0.05, 0.0).normalize() * 0.5 + Vec3::new(0.0, 0.0, 1.2);
        assert!((end.p - held).norm() < 0.01, "{:?} against {held:?}", end.p);
    }

    /// A camera that passes an actor 0.7 m off at 1.5 m/s, closing on them fast, is not
    /// braked: its course does not come within their distance.
    #[test]
    fn a_camera_passing_an_actor_wide_is_not_braked() {
        let axes = [body(Vec3::zeros(), 1.8)];
        let goal_at = |t: f64| Kinematics {
            p: Vec3::new(-3.0 + 1.5 * t, 0.7, 1.2),
            v: Vec3::new(1.5, 0.0, 0.0),
            a: Vec3::zeros(),
        };
        let start = goal_at(0.0);
        let (free, a) = closest_flown(start, goal_at, &axes, false, 4.0);
        let (kept, b) = closest_flown(start, goal_at, &axes, true, 4.0);
        assert_eq!((free, a), (kept, b));
        assert!((kept - 0.7).abs() < 1e-6, "{kept}");
    }

    /// A camera that starts inside an actor's distance with its goal across them moves out
    /// and round them to the goal. With the separation's push alone it sits inside, where
    /// that push balances the arrival's pull through the actor.
    #[test]
    fn a_camera_inside_an_actors_distance_goes_out_and_round() {
        let axes = [body(Vec3::zeros(), 1.8)];
        let goal = Kinematics {
            p: Vec3::new(1.2, 0.1, 1.2),
            ..Default::default()
        };
        let start = Kinematics {
            p: Vec3::new(-0.42, 0.0, 1.2),
            ..Default::default()
        };
        let (_, free) = closest_flown(start, |_| goal, &axes, false, 1.0);
        let (_, kept) = closest_flown(start, |_| goal, &axes, true, 1.0);
        let from_axis = |k: &Kinematics| dronecine_math::norm_xy(k.p.x, k.p.y);
        assert!(from_axis(&free) < 0.45, "{:?}", free.p);
        assert!(from_axis(&kept) > 0.49, "{:?}", kept.p);
        let (_, end) = closest_flown(start, |_| goal, &axes, true, 15.0);
        assert!((end.p - goal.p).norm() < 0.01, "{:?}", end.p);
    }
}
