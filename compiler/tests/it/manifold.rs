//! Properties of the framing math: placed cameras reproject the actors
//! where the composition asks, sizes hold, mirror profiles mirror, the toric formulas agree
//! with the triangle they describe, velocities are derivatives, interpolation ends at its
//! inputs.

use dronecine_compiler::camera::{CameraPose, Lens, Vec3};
use dronecine_compiler::framing::{
    self, body_axis_distance_m, interpolate, place, screen_targets, solve, FramingError, Placement,
    Visual,
};
use dronecine_compiler::reference::ActorPose;
use dronecine_compiler::toric::{self, Toric};
use dronecine_compiler::{size, sphere};
use dronecine_grammar::script::{Composition, Framing, Subject};
use dronecine_grammar::vocab::{CameraAngle, Profile, Size};
use dronecine_math::wrap_angle_rad;
use dronecine_profile::Gimbal;
use proptest::prelude::*;
use std::f64::consts::PI;

const NAMES: [&str; 3] = ["A", "B", "C"];

fn lens(fov_deg: f64) -> Lens {
    Lens::new(fov_deg.to_radians(), 16.0 / 9.0)
}

fn gimbal() -> Gimbal {
    Gimbal::Pitch {
        min_rad: -PI / 2.0,
        max_rad: PI / 2.0,
        rate_radps: PI,
    }
}

fn actor(x: f64, y: f64, facing_deg: f64, height_m: f64) -> ActorPose {
    ActorPose {
        position_m: [x, y, 0.0],
        velocity_mps: [0.0; 3],
        facing_rad: wrap_angle_rad(facing_deg.to_radians()),
        facing_rate_radps: 0.0,
        height_m,
    }
}

fn subject(actor: &str, profile: Option<Profile>, x: Option<f64>, y: Option<f64>) -> Subject {
    Subject {
        actor: actor.to_string(),
        profile,
        screen_x: x,
        screen_y: y,
    }
}

fn comp(angle: CameraAngle, framings: Vec<(Size, Vec<Subject>)>) -> Composition {
    Composition {
        camera_angle: angle,
        framings: framings
            .into_iter()
            .map(|(size, subjects)| Framing { size, subjects })
            .collect(),
    }
}

/// A two-shot of A and B, placed by the size alone.
fn two_shot(angle: CameraAngle, size: Size) -> Composition {
    comp(
        angle,
        vec![(
            size,
            vec![
                subject("A", None, None, None),
                subject("B", None, None, None),
            ],
        )],
    )
}

fn pose(p: &Placement) -> CameraPose {
    CameraPose {
        position_m: p.position_m,
        heading_rad: p.heading_rad,
        pitch_rad: p.pitch_rad,
    }
}

fn head(a: &ActorPose, h: f64) -> Vec3 {
    Vec3::new(a.position_m[0], a.position_m[1], h)
}

fn size_strategy() -> impl Strategy<Value = Size> {
    prop::sample::select(Size::ALL.to_vec())
}

fn profile_strategy() -> impl Strategy<Value = Profile> {
    prop::sample::select(Profile::ALL.to_vec())
}

fn angle_strategy() -> impl Strategy<Value = CameraAngle> {
    prop::sample::select(vec![
        CameraAngle::EyeLevel,
        CameraAngle::High,
        CameraAngle::Low,
    ])
}

/// Largest screen error over the visual's targets for a placed camera.
fn screen_error(v: &Visual, actors: &[ActorPose], l: &Lens, g: &Gimbal, p: &Placement) -> f64 {
    let cam = pose(p);
    screen_targets(v, actors, l, g, &p.position_m)
        .iter()
        .map(|t| match cam.project(l, &t.point_m) {
            Some(s) => (s[0] - t.screen[0]).abs().max((s[1] - t.screen[1]).abs()),
            None => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// One actor, gimbal camera: the aim point lands exactly where asked, and with the band
    /// centred horizontally its ends land on y ± 1 (the size holds) at any camera angle.
    #[test]
    fn one_actor_reprojects_and_frames_the_band(
        x in -3.0..3.0f64, y in -3.0..3.0f64, facing in -180.0..180.0f64,
        height in 1.2..2.0f64, size_ in size_strategy(), profile in profile_strategy(),
        angle in angle_strategy(), sx in -0.6..0.6f64, sy in -0.4..0.4f64,
        centred in any::<bool>(), fov in 40.0..100.0f64,
    ) {
        let l = lens(fov);
        let g = gimbal();
        let actors = [actor(x, y, facing, height)];
        let sx = if centred { 0.0 } else { sx };
        let c = comp(angle, vec![(size_, vec![subject("A", Some(profile), Some(sx), Some(sy))])]);
        let v = solve(&c, &NAMES[..1], &actors, &l, &g).unwrap();
        let p = place(&v, &actors, &l, &g);
        prop_assert!(!p.flags.any(), "{:?}", p.flags);
        prop_assert!(screen_error(&v, &actors, &l, &g, &p) < 1e-6);
        let (bottom, top) = size::band(size_, height);
        let cam = pose(&p);
        let t = cam.project(&l, &head(&actors[0], top)).unwrap();
        let b = cam.project(&l, &head(&actors[0], bottom)).unwrap();
        if centred {
            prop_assert!((t[1] - (sy + 1.0)).abs() < 1e-6 && (b[1] - (sy - 1.0)).abs() < 1e-6,
                "top {t:?} bottom {b:?}");
        } else {
            // Off-centre, a pitched camera sees the vertical band slanted (vertical lines
            // converge): the band's height still matches the size.
            prop_assert!(((t[1] - b[1]) - 2.0).abs() < 0.05, "top {t:?} bottom {b:?}");
        }
    }

    /// One actor, fixed-pitch camera (AR.Drone): level, the band spans [y − 1, y + 1] at x
    /// exactly; a non-level camera angle is flagged, never silently dropped.
    #[test]
    fn one_actor_fixed_pitch_frames_with_altitude(
        x in -3.0..3.0f64, y in -3.0..3.0f64, facing in -180.0..180.0f64,
        height in 1.2..2.0f64, size_ in size_strategy(), profile in profile_strategy(),
        angle in angle_strategy(), sx in -0.6..0.6f64, sy in -0.4..0.4f64,
    ) {
        let l = lens(84.0);
        let g = Gimbal::None;
        let actors = [actor(x, y, facing, height)];
        let c = comp(angle, vec![(size_, vec![subject("A", Some(profile), Some(sx), Some(sy))])]);
        let v = solve(&c, &NAMES[..1], &actors, &l, &g).unwrap();
        let p = place(&v, &actors, &l, &g);
        prop_assert_eq!(p.pitch_rad, 0.0);
        prop_assert_eq!(p.flags.angle_not_rendered, angle != CameraAngle::EyeLevel);
        prop_assert!(screen_error(&v, &actors, &l, &g, &p) < 1e-9);
        let (bottom, top) = size::band(size_, height);
        let cam = pose(&p);
        let t = cam.project(&l, &head(&actors[0], top)).unwrap();
        let b = cam.project(&l, &head(&actors[0], bottom)).unwrap();
        prop_assert!((t[1] - (sy + 1.0)).abs() < 1e-9 && (b[1] - (sy - 1.0)).abs() < 1e-9);
        prop_assert!((t[0] - sx).abs() < 1e-9 && (b[0] - sx).abs() < 1e-9);
    }

    /// Mirror profiles give positions mirrored across the actor's facing axis (and mirrored
    /// headings), for every camera angle.
    #[test]
    fn mirror_profiles_mirror_the_camera(
        x in -3.0..3.0f64, y in -3.0..3.0f64, facing in -180.0..180.0f64,
        size_ in size_strategy(), angle in angle_strategy(), which in 0usize..4,
        sx in -0.5..0.5f64, fixed in any::<bool>(),
    ) {
        let (left, right) = [
            (Profile::ThreeQuarterLeft, Profile::ThreeQuarterRight),
            (Profile::Left, Profile::Right),
            (Profile::ThreeQuarterBackLeft, Profile::ThreeQuarterBackRight),
            (Profile::Front, Profile::Front),
        ][which];
        let l = lens(84.0);
        let g = if fixed { Gimbal::None } else { gimbal() };
        let actors = [actor(x, y, facing, 1.75)];
        let place_for = |p: Profile, sx: f64| {
            let c = comp(angle, vec![(size_, vec![subject("A", Some(p), Some(sx), None)])]);
            place(&solve(&c, &NAMES[..1], &actors, &l, &g).unwrap(), &actors, &l, &g)
        };
        // The mirror image of "screen x" is "screen −x".
        let pl = place_for(left, sx);
        let pr = place_for(right, -sx);
        let h = actors[0].facing_rad;
        let f = Vec3::new(h.cos(), h.sin(), 0.0);
        let feet = Vec3::new(x, y, 0.0);
        let mirror = |c: &Vec3| {
            let d = c - feet;
            let along = f * d.dot(&f);
            let across = d.xy() - along.xy();
            feet + Vec3::new(along.x - across.x, along.y - across.y, d.z)
        };
        prop_assert!((mirror(&pl.position_m) - pr.position_m).norm() < 1e-9,
            "{:?} vs {:?}", pl.position_m, pr.position_m);
        prop_assert!(wrap_angle_rad(pl.heading_rad + pr.heading_rad - 2.0 * h).abs() < 1e-9);
        prop_assert!((pl.pitch_rad - pr.pitch_rad).abs() < 1e-9);
        if left != right {
            // 34left and left put the camera on the actor's left.
            let side = (pl.position_m - feet).dot(&Vec3::z().cross(&f));
            prop_assert!(side > 0.0);
        }
    }

    /// Two equal-height actors, eye level, in one framing with written screen positions: both
    /// land exactly there (the positions outrank the size), the camera stands as far from
    /// both (a two-shot), and the band each shows is the size's scaled by how far the
    /// camera stands from the size's distance (the ratio the size warning reads).
    #[test]
    fn two_actors_eye_level_are_exact(
        ax in -3.0..3.0f64, ay in -3.0..3.0f64, dist in 0.5..4.0f64, dir in -180.0..180.0f64,
        fa in -180.0..180.0f64, fb in -180.0..180.0f64, height in 1.5..1.9f64,
        size_ in prop::sample::select(vec![Size::CU, Size::MCU, Size::MS, Size::MLS, Size::FS]),
        xa in -0.7..-0.1f64, xb in 0.1..0.7f64, swap in any::<bool>(), fixed in any::<bool>(),
    ) {
        let l = lens(84.0);
        let g = if fixed { Gimbal::None } else { gimbal() };
        let (bx, by) = (ax + dist * dir.to_radians().cos(), ay + dist * dir.to_radians().sin());
        let actors = [actor(ax, ay, fa, height), actor(bx, by, fb, height)];
        let (xa, xb) = if swap { (xb, xa) } else { (xa, xb) };
        let c = comp(CameraAngle::EyeLevel, vec![(size_, vec![
            subject("A", None, Some(xa), None), subject("B", None, Some(xb), None)])]);
        let v = solve(&c, &NAMES[..2], &actors, &l, &g).unwrap();
        let p = place(&v, &actors, &l, &g);
        prop_assert!(!p.flags.any(), "{:?}", p.flags);
        prop_assert!(screen_error(&v, &actors, &l, &g, &p) < 1e-6);
        let Visual::Two(t) = &v else { panic!("{v:?}") };
        let m = |a: &ActorPose| head(a, 0.5 * (size::band(size_, height).0 + size::band(size_, height).1));
        let (da, db) = ((p.position_m - m(&actors[0])).norm(), (p.position_m - m(&actors[1])).norm());
        prop_assert!((da - db).abs() < 1e-6 * da, "{da} {db}");
        // Each band shows the size at the distance its screen point asks; the camera, as far
        // from both, frames their mean at the ratio.
        let cam = pose(&p);
        let (bottom, top) = size::band(size_, height);
        let shown: Vec<f64> = actors.iter().map(|a| {
            cam.project(&l, &head(a, top)).unwrap()[1] - cam.project(&l, &head(a, bottom)).unwrap()[1]
        }).collect();
        let mean = (shown[0] + shown[1]) / 2.0;
        prop_assert!((mean * t.distance_ratio - 2.0).abs() < 1e-3, "{shown:?} ratio {}", t.distance_ratio);
    }

    /// Toric position: the law of sines holds, ∠ACB = α, and the inverse returns (α, θ, φ).
    #[test]
    fn toric_position_and_inverse(
        ax in -3.0..3.0f64, ay in -3.0..3.0f64, az in 0.5..2.0f64,
        bx in -3.0..3.0f64, by in -3.0..3.0f64, bz in 0.5..2.0f64,
        alpha in 0.05..3.0f64, frac in 0.01..0.99f64, phi in -3.1..3.1f64,
    ) {
        let a = Vec3::new(ax, ay, az);
        let b = Vec3::new(bx, by, bz);
        prop_assume!((b - a).xy().norm() > 0.1);
        let v = Toric { alpha_rad: alpha, theta_rad: frac * 2.0 * (PI - alpha), phi_rad: phi };
        let c = toric::position(&a, &b, &v).unwrap();
        let (ab, ac, bc) = ((b - a).norm(), (c - a).norm(), (c - b).norm());
        let at_a = (b - a).angle(&(c - a));
        let at_b = (a - b).angle(&(c - b));
        let at_c = (a - c).angle(&(b - c));
        prop_assert!((at_c - alpha).abs() < 1e-9, "∠ACB {at_c} vs α {alpha}");
        prop_assert!((at_a - v.theta_rad / 2.0).abs() < 1e-9);
        prop_assert!((ac / at_b.sin() - ab / alpha.sin()).abs() < 1e-7 * ab / alpha.sin());
        prop_assert!((bc / at_a.sin() - ab / alpha.sin()).abs() < 1e-7 * ab / alpha.sin());
        let back = toric::inverse(&a, &b, &c).unwrap();
        prop_assert!((back.alpha_rad - alpha).abs() < 1e-9);
        prop_assert!((back.theta_rad - v.theta_rad).abs() < 1e-9);
        prop_assert!(wrap_angle_rad(back.phi_rad - phi).abs() < 1e-7);
    }

    /// θ from a distance constraint gives that distance, and every root is in range.
    #[test]
    fn toric_distance_constraints(
        ab in 0.5..5.0f64, alpha in 0.05..3.0f64, d in 0.05..12.0f64, phi in -3.0..3.0f64,
    ) {
        let a = Vec3::new(0.0, 0.0, 1.5);
        let b = Vec3::new(ab * 0.6, ab * 0.8, 1.5);
        let r = toric::radius_m(ab, alpha);
        let max_a = if alpha < PI / 2.0 { 2.0 * r } else { ab };
        let ra = toric::theta_for_distance_to_a(alpha, ab, d);
        let rb = toric::theta_for_distance_to_b(alpha, ab, d);
        for (roots, x) in [(&ra, a), (&rb, b)] {
            for &th in roots.iter() {
                prop_assert!(th > 0.0 && th < 2.0 * (PI - alpha));
                let c = toric::position(&a, &b, &Toric { alpha_rad: alpha, theta_rad: th, phi_rad: phi }).unwrap();
                prop_assert!(((c - x).norm() - d).abs() < 1e-7 * d.max(1.0), "θ {th}");
            }
        }
        // A solution exists below the largest distance on the torus, none above it.
        if d < max_a * 0.999 { prop_assert!(!ra.is_empty()); }
        if d > max_a * 1.001 { prop_assert!(ra.is_empty()); }
        if d < max_a * 0.999 { prop_assert!(!rb.is_empty()); }
        if d > max_a * 1.001 { prop_assert!(rb.is_empty()); }
    }

    /// The vantage formula puts C along u from A, on the torus of α.
    #[test]
    fn toric_vantage(alpha in 0.1..2.5f64, yaw in -3.1..3.1f64, el in -0.5..0.5f64) {
        let a = Vec3::new(0.0, 0.0, 1.6);
        let b = Vec3::new(2.0, 0.5, 1.5);
        let u = Vec3::new(el.cos() * yaw.cos(), el.cos() * yaw.sin(), el.sin());
        match toric::vantage_position(&a, &b, alpha, &u) {
            Some(c) => {
                prop_assert!(((c - a).normalize() - u).norm() < 1e-9);
                prop_assert!(((a - c).angle(&(b - c)) - alpha).abs() < 1e-9);
            }
            None => prop_assert!((b - a).angle(&u) >= PI - alpha),
        }
    }

    /// The sphere velocity formula is the derivative of the sphere position for a walking,
    /// turning actor while d, θ, φ change.
    #[test]
    fn sphere_velocity_is_the_derivative(
        vx in -1.5..1.5f64, vy in -1.5..1.5f64, h0 in -3.0..3.0f64, hdot in -1.0..1.0f64,
        d0 in 0.5..5.0f64, ddot in -0.5..0.5f64, th0 in -3.0..3.0f64, thdot in -0.5..0.5f64,
        ph0 in -0.5..0.5f64, phdot in -0.3..0.3f64,
    ) {
        let p0 = Vec3::new(0.3, -0.2, 1.2);
        let vel = Vec3::new(vx, vy, 0.0);
        let at = |t: f64| sphere::position(&(p0 + vel * t), h0 + hdot * t, &sphere::Spherical {
            distance_m: d0 + ddot * t, azimuth_rad: th0 + thdot * t, elevation_rad: ph0 + phdot * t,
        });
        let dt = 1e-5;
        let numeric = (at(dt) - at(-dt)) / (2.0 * dt);
        let analytic = sphere::velocity(h0, &sphere::Spherical {
            distance_m: d0, azimuth_rad: th0, elevation_rad: ph0,
        }, &sphere::Rates {
            aim_velocity_mps: vel, facing_rate_radps: hdot, distance_rate_mps: ddot,
            azimuth_rate_radps: thdot, elevation_rate_radps: phdot,
        });
        prop_assert!((numeric - analytic).norm() < 1e-6, "{numeric:?} vs {analytic:?}");
    }
}

/// A walking, turning actor: the framing velocity is the derivative of the placement.
#[test]
fn feed_forward_velocity_matches_placement_derivative() {
    let l = lens(84.0);
    for g in [gimbal(), Gimbal::None] {
        let moving = |t: f64| {
            let mut a = actor(0.5 + 0.8 * t, -0.3 + 0.4 * t, 30.0, 1.8);
            a.velocity_mps = [0.8, 0.4, 0.0];
            a.facing_rad = wrap_angle_rad(30f64.to_radians() + 0.6 * t);
            a.facing_rate_radps = 0.6;
            let mut b = actor(2.5 - 0.2 * t, 1.0, 200.0, 1.65);
            b.velocity_mps = [-0.2, 0.0, 0.0];
            [a, b]
        };
        let actors = moving(0.0);
        let comps = [
            comp(
                CameraAngle::High,
                vec![(
                    Size::MS,
                    vec![subject("A", Some(Profile::ThreeQuarterLeft), None, None)],
                )],
            ),
            two_shot(CameraAngle::EyeLevel, Size::MS),
        ];
        for c in &comps {
            let v = solve(c, &NAMES[..2], &actors, &l, &g).unwrap();
            let dt = 1e-4;
            let numeric = (place(&v, &moving(dt), &l, &g).position_m
                - place(&v, &moving(-dt), &l, &g).position_m)
                / (2.0 * dt);
            let ff = framing::velocity_mps(&v, &actors, &l, &g);
            assert!((numeric - ff).norm() < 1e-4, "{numeric:?} vs {ff:?}");
        }
    }
}

fn two_shot_scene() -> [ActorPose; 3] {
    [
        actor(0.0, 0.0, 0.0, 1.8),
        actor(2.5, 0.0, 180.0, 1.65),
        actor(1.0, 2.0, -90.0, 1.7),
    ]
}

/// `SIZE on A and B`: the camera as far from both (within a tenth), A screen-left of B,
/// both in frame; the size holds while the actors fit in one frame at it, and beyond that
/// they sit at the widest spread and the size gives way (the ratio the warning reads).
#[test]
fn a_two_shot_is_symmetric_and_sized_alike() {
    let l = lens(84.0);
    let g = Gimbal::None;
    for (apart_m, size_, holds) in [
        (2.5, Size::LS, true),
        (1.0, Size::MS, true),
        (2.5, Size::MS, false),
    ] {
        let actors = [actor(0.0, 0.0, 0.0, 1.8), actor(apart_m, 0.0, 180.0, 1.65)];
        let c = two_shot(CameraAngle::EyeLevel, size_);
        let v = solve(&c, &NAMES[..2], &actors, &l, &g).unwrap();
        let Visual::Two(t) = &v else { panic!("{v:?}") };
        let p = place(&v, &actors, &l, &g);
        let cam = pose(&p);
        let band = |a: &ActorPose| size::band(size_, a.height_m);
        let centre = |a: &ActorPose| head(a, (band(a).0 + band(a).1) / 2.0);
        let (da, db) = (
            (p.position_m - centre(&actors[0])).norm(),
            (p.position_m - centre(&actors[1])).norm(),
        );
        assert!(
            (da - db).abs() <= 0.1 * (da + db) / 2.0,
            "{apart_m} m {size_:?}: {da} {db}"
        );
        let (sa, sb) = (
            cam.project(&l, &centre(&actors[0])).unwrap(),
            cam.project(&l, &centre(&actors[1])).unwrap(),
        );
        assert!(sa[0] < 0.0 && 0.0 < sb[0], "{sa:?} {sb:?}");
        for s in [sa, sb] {
            assert!(
                s[0].abs() <= framing::TWO_SHOT_SCREEN_MAX + 1e-9 && s[1].abs() < 1.0,
                "{s:?}"
            );
        }
        assert_eq!(
            size::holds_at_ratio(t.distance_ratio),
            holds,
            "{apart_m} m {size_:?}: {t:?}"
        );
        if holds {
            // The band of each fills the frame's height within the size's slack.
            for a in &actors {
                let top = cam.project(&l, &head(a, band(a).1)).unwrap();
                let bottom = cam.project(&l, &head(a, band(a).0)).unwrap();
                let shown = top[1] - bottom[1];
                assert!((shown / 2.0).ln().abs() < size::SIZE_SLACK.ln(), "{shown}");
            }
        } else {
            // At the widest spread (within the blend of the two distances).
            assert!(
                (sb[0] - framing::TWO_SHOT_SCREEN_MAX).abs() < 0.02,
                "{sb:?}"
            );
            assert!(t.distance_ratio > 1.4, "{t:?}");
        }
    }
}

/// `SIZE on A and B PROFILE`: the profile is honoured, seen from the actor it is written on
/// (`MS on A and B right` is not the plain two-shot), the size kept on that actor while both
/// fit in frame.
#[test]
fn a_profile_on_a_two_shot_is_honoured_on_either_actor() {
    let l = lens(84.0);
    let g = Gimbal::None;
    let actors = [actor(-1.0, 0.0, 0.0, 1.8), actor(1.0, 0.0, 180.0, 1.65)];
    let plain = two_shot(CameraAngle::EyeLevel, Size::MLS);
    let p0 = place(
        &solve(&plain, &NAMES[..2], &actors, &l, &g).unwrap(),
        &actors,
        &l,
        &g,
    );
    for (who, profile) in [
        (0usize, Profile::ThreeQuarterLeft),
        (1, Profile::Right),
        (1, Profile::ThreeQuarterRight),
    ] {
        let subjects = if who == 0 {
            vec![
                subject("A", Some(profile), None, None),
                subject("B", None, None, None),
            ]
        } else {
            vec![
                subject("A", None, None, None),
                subject("B", Some(profile), None, None),
            ]
        };
        let c = comp(CameraAngle::EyeLevel, vec![(Size::MLS, subjects)]);
        let v = solve(&c, &NAMES[..2], &actors, &l, &g).unwrap();
        let p = place(&v, &actors, &l, &g);
        assert!(
            (p.position_m - p0.position_m).norm() > 0.3,
            "{profile:?} on {who}: the plain two-shot"
        );
        let x = &actors[who];
        let bearing = (p.position_m.y - x.position_m[1]).atan2(p.position_m.x - x.position_m[0]);
        let off = wrap_angle_rad(bearing - x.facing_rad - profile.azimuth_rad()).abs();
        assert!(
            off < 1e-6,
            "{profile:?} on {who}: {}° off",
            off.to_degrees()
        );
        // Both in frame.
        let cam = pose(&p);
        for a in &actors {
            let s = cam.project(&l, &head(a, 0.6 * a.height_m)).unwrap();
            assert!(
                s[0].abs() <= framing::TWO_SHOT_SCREEN_MAX + 1e-6,
                "{profile:?}: {s:?}"
            );
        }
    }
}

/// `MS B 34backright <background> A 34left screen right`: B in the foreground, A in the
/// background at `background` size.
fn over_b_shoulder(background: Size) -> Composition {
    comp(
        CameraAngle::EyeLevel,
        vec![
            (
                Size::MS,
                vec![subject(
                    "B",
                    Some(Profile::ThreeQuarterBackRight),
                    None,
                    None,
                )],
            ),
            (
                background,
                vec![subject(
                    "A",
                    Some(Profile::ThreeQuarterLeft),
                    Some(1.0 / 3.0),
                    None,
                )],
            ),
        ],
    )
}

/// The camera's bearing from an actor, from their facing, against a profile's angle.
fn profile_off_rad(camera_m: &Vec3, a: &ActorPose, p: Profile) -> f64 {
    let bearing = (camera_m.y - a.position_m[1]).atan2(camera_m.x - a.position_m[0]);
    wrap_angle_rad(bearing - a.facing_rad - p.azimuth_rad()).abs()
}

/// Over the shoulder, as film grammar checks it: the camera within 22.5° of each written
/// profile's side (B's, the foreground; A's, the background), A (background) exactly at its
/// screen point, B on the other half of the frame, and A at its size where the camera can
/// stand at its distance — else from as near as the profiles allow, the ratio telling how
/// far.
#[test]
fn over_the_shoulder() {
    let l = lens(84.0);
    for g in [gimbal(), Gimbal::None] {
        for apart_m in [1.2, 2.0, 3.0] {
            let mut actors = two_shot_scene();
            actors[1].position_m = [apart_m, 0.0, 0.0];
            for background in [Size::MS, Size::MLS, Size::LS] {
                let c = over_b_shoulder(background);
                let v = solve(&c, &NAMES, &actors, &l, &g).unwrap();
                let Visual::Two(t) = &v else { panic!("{v:?}") };
                assert!(t.over_shoulder && t.a == 1 && t.b == 0);
                let p = place(&v, &actors, &l, &g);
                let off_fg =
                    profile_off_rad(&p.position_m, &actors[1], Profile::ThreeQuarterBackRight);
                let off_bg = profile_off_rad(&p.position_m, &actors[0], Profile::ThreeQuarterLeft);
                assert!(
                    off_fg.to_degrees() <= 22.5 && off_bg.to_degrees() <= 22.5,
                    "{apart_m} m {background:?}: {:.1}° {:.1}°",
                    off_fg.to_degrees(),
                    off_bg.to_degrees()
                );
                let cam = pose(&p);
                let (bottom, top) = size::band(background, 1.8);
                let a_centre = head(&actors[0], (bottom + top) / 2.0);
                let sa = cam.project(&l, &a_centre).unwrap();
                assert!(
                    (sa[0] - 1.0 / 3.0).abs() < 1e-6 && sa[1].abs() < 1e-6,
                    "{sa:?}"
                );
                let (b_bottom, b_top) = size::band(Size::MS, 1.65);
                let sb = cam
                    .project(&l, &head(&actors[1], (b_bottom + b_top) / 2.0))
                    .unwrap();
                assert!(
                    sb[0] < 0.0 && sb[0] >= -1.0,
                    "{apart_m} m {background:?}: B at {sb:?}"
                );
                assert!(t.distance_ratio >= 1.0 - 1e-9, "{t:?}");
                // The band shows the size at the ratio's distance.
                let shown = cam.project(&l, &head(&actors[0], top)).unwrap()[1]
                    - cam.project(&l, &head(&actors[0], bottom)).unwrap()[1];
                assert!(
                    (shown * t.distance_ratio - 2.0).abs() < 0.03,
                    "{shown} at {}",
                    t.distance_ratio
                );
            }
        }
    }
}

/// Over the shoulder with profiles on opposite sides of the line between the actors: no
/// camera stands in both sectors, and the error names both profiles.
#[test]
fn over_the_shoulder_profiles_on_opposite_sides_are_refused() {
    let l = lens(84.0);
    let actors = [actor(0.0, 0.0, 0.0, 1.8), actor(2.0, 0.0, 180.0, 1.65)];
    let c = comp(
        CameraAngle::EyeLevel,
        vec![
            (
                Size::MS,
                vec![subject(
                    "B",
                    Some(Profile::ThreeQuarterBackLeft),
                    None,
                    None,
                )],
            ),
            (
                Size::MS,
                vec![subject("A", Some(Profile::ThreeQuarterLeft), None, None)],
            ),
        ],
    );
    let e = solve(&c, &NAMES[..2], &actors, &l, &Gimbal::None).unwrap_err();
    assert_eq!(
        e,
        FramingError::ProfilesConflict {
            foreground: Some(Profile::ThreeQuarterBackLeft),
            background: Some(Profile::ThreeQuarterLeft)
        }
    );
    let text = e.to_string();
    assert!(
        text.contains("34backleft") && text.contains("34left"),
        "{text}"
    );
}

/// A pitch gimbal with a narrow range: the pitch is clamped and flagged, the aim point still
/// lands at its x.
#[test]
fn pitch_is_clamped_and_flagged() {
    let l = lens(84.0);
    let g = Gimbal::Pitch {
        min_rad: -0.1,
        max_rad: 0.1,
        rate_radps: PI,
    };
    let actors = [actor(0.0, 0.0, 0.0, 1.8)];
    let c = comp(
        CameraAngle::High,
        vec![(Size::CU, vec![subject("A", None, Some(1.0 / 3.0), None)])],
    );
    let v = solve(&c, &NAMES[..1], &actors, &l, &g).unwrap();
    let p = place(&v, &actors, &l, &g);
    assert!(p.flags.pitch_clamped && p.pitch_rad == -0.1);
    let target = screen_targets(&v, &actors, &l, &g, &p.position_m)[0];
    let s = pose(&p).project(&l, &target.point_m).unwrap();
    assert!((s[0] - 1.0 / 3.0).abs() < 1e-9);
}

#[test]
fn solve_reports_bad_compositions() {
    let l = lens(84.0);
    let g = gimbal();
    let actors = two_shot_scene();
    let one = |a: &str| subject(a, None, None, None);
    let err = |c: Composition| solve(&c, &NAMES, &actors, &l, &g).unwrap_err();
    assert_eq!(
        err(comp(
            CameraAngle::EyeLevel,
            vec![(Size::MS, vec![one("Z")])]
        )),
        FramingError::UnknownActor("Z".into())
    );
    assert_eq!(
        err(comp(
            CameraAngle::EyeLevel,
            vec![(Size::MS, vec![one("A"), one("A")])]
        )),
        FramingError::SameActor("A".into())
    );
    assert!(matches!(
        err(comp(
            CameraAngle::EyeLevel,
            vec![(Size::MS, vec![one("A"), one("B"), one("C")])]
        )),
        FramingError::Unsupported { .. }
    ));
    assert!(matches!(
        err(comp(CameraAngle::EyeLevel, vec![])),
        FramingError::Unsupported { .. }
    ));
    let same_place = [actor(1.0, 1.0, 0.0, 1.8), actor(1.0, 1.0, 90.0, 1.8)];
    assert_eq!(
        solve(
            &comp(
                CameraAngle::EyeLevel,
                vec![(Size::MS, vec![one("A"), one("B")])]
            ),
            &NAMES[..2],
            &same_place,
            &l,
            &g
        )
        .unwrap_err(),
        FramingError::ActorsCoincide
    );
    assert_eq!(
        err(comp(
            CameraAngle::EyeLevel,
            vec![(
                Size::MS,
                vec![
                    subject("A", None, Some(0.2), None),
                    subject("B", None, Some(0.2), None)
                ]
            )]
        )),
        FramingError::ScreensCoincide
    );
    // Profile behind A when A faces B: the camera would look along the line through them.
    assert_eq!(
        err(comp(
            CameraAngle::EyeLevel,
            vec![(
                Size::MS,
                vec![subject("A", Some(Profile::Back), None, None), one("B")]
            )]
        )),
        FramingError::ProfileBlocked {
            profile: Profile::Back
        }
    );
    // A profile on both actors of one framing: a two-shot has one vantage.
    assert_eq!(
        err(comp(
            CameraAngle::EyeLevel,
            vec![(
                Size::MS,
                vec![
                    subject("A", Some(Profile::ThreeQuarterLeft), None, None),
                    subject("B", Some(Profile::ThreeQuarterRight), None, None)
                ]
            )]
        )),
        FramingError::TwoProfiles
    );
}

fn visuals() -> (Vec<ActorPose>, Vec<Visual>) {
    let l = lens(84.0);
    let g = gimbal();
    let actors = two_shot_scene().to_vec();
    let cs = [
        comp(
            CameraAngle::EyeLevel,
            vec![(
                Size::MS,
                vec![subject("A", Some(Profile::ThreeQuarterLeft), None, None)],
            )],
        ),
        comp(
            CameraAngle::High,
            vec![(
                Size::CU,
                vec![subject("A", Some(Profile::Right), Some(-1.0 / 3.0), None)],
            )],
        ),
        two_shot(CameraAngle::EyeLevel, Size::MS),
        comp(
            CameraAngle::High,
            vec![(
                Size::MLS,
                vec![
                    subject("B", None, None, None),
                    subject("A", None, None, None),
                ],
            )],
        ),
        comp(
            CameraAngle::EyeLevel,
            vec![
                (
                    Size::MS,
                    vec![subject(
                        "B",
                        Some(Profile::ThreeQuarterBackRight),
                        None,
                        None,
                    )],
                ),
                (
                    Size::MLS,
                    vec![subject("A", Some(Profile::ThreeQuarterLeft), None, None)],
                ),
            ],
        ),
        comp(
            CameraAngle::Low,
            vec![(
                Size::FS,
                vec![subject("C", Some(Profile::Front), None, None)],
            )],
        ),
        // Over A's shoulder, A on the left as in the two-shot (no line crossing).
        comp(
            CameraAngle::EyeLevel,
            vec![
                (
                    Size::MS,
                    vec![subject(
                        "A",
                        Some(Profile::ThreeQuarterBackRight),
                        None,
                        None,
                    )],
                ),
                (
                    Size::MS,
                    vec![subject("B", Some(Profile::ThreeQuarterLeft), None, None)],
                ),
            ],
        ),
    ];
    let vs = cs
        .iter()
        .map(|c| solve(c, &NAMES, &actors, &l, &g).unwrap())
        .collect();
    (actors, vs)
}

/// Whether a move between two visuals flips the screen order of a pair of actors.
fn crosses_line(a: &Visual, b: &Visual, actors: &[ActorPose]) -> bool {
    let l = lens(84.0);
    let g = gimbal();
    let xs = |v: &Visual| -> Vec<(usize, f64)> {
        let p = place(v, actors, &l, &g);
        screen_targets(v, actors, &l, &g, &p.position_m)
            .iter()
            .map(|t| (t.actor, t.screen[0]))
            .collect()
    };
    let (xa, xb) = (xs(a), xs(b));
    xa.iter().any(|(i, x)| {
        xa.iter().any(|(j, y)| {
            let order = |v: &Vec<(usize, f64)>| {
                let p = v.iter().find(|t| t.0 == *i)?.1;
                let q = v.iter().find(|t| t.0 == *j)?.1;
                Some(p < q)
            };
            i != j && x != y && order(&xb).is_some_and(|o| o != order(&xa).unwrap())
        })
    })
}

/// Interpolation ends at its inputs, for every pair of visuals, and is continuous in between.
#[test]
fn interpolation_endpoints_and_continuity() {
    let l = lens(84.0);
    let g = gimbal();
    let (actors, vs) = visuals();
    for a in &vs {
        for b in &vs {
            assert_eq!(&interpolate(a, b, 0.0), a);
            assert_eq!(&interpolate(a, b, 1.0), b);
            let pa = place(a, &actors, &l, &g);
            let pb = place(b, &actors, &l, &g);
            let near0 = place(&interpolate(a, b, 1e-9), &actors, &l, &g);
            let near1 = place(&interpolate(a, b, 1.0 - 1e-9), &actors, &l, &g);
            assert!((near0.position_m - pa.position_m).norm() < 1e-6);
            assert!((near1.position_m - pb.position_m).norm() < 1e-6);
            assert!(wrap_angle_rad(near0.heading_rad - pa.heading_rad).abs() < 1e-6);
            assert!(wrap_angle_rad(near1.heading_rad - pb.heading_rad).abs() < 1e-6);
            // No jumps: 200 steps, each moving at most a few times the mean step. Moves that
            // cross the line of action between two actors (the pair's screen order flips) pass
            // between them and are left out: the view swings round there by construction.
            if crosses_line(a, b, &actors) {
                continue;
            }
            let span = (pb.position_m - pa.position_m).norm().max(0.5);
            let mut prev = pa;
            for k in 1..=200 {
                let p = place(&interpolate(a, b, k as f64 / 200.0), &actors, &l, &g);
                let step = (p.position_m - prev.position_m).norm();
                assert!(step < 0.1 * span, "{a:?} → {b:?} at {k}: step {step}");
                // The view direction does not jump (heading alone is ill-conditioned when
                // the camera looks steeply down), except where the aim passes straight below
                // the camera, which is flagged (a move crossing the line of action between
                // actors 2.5 m apart passes over them).
                let df = (pose(&p).forward() - pose(&prev).forward()).norm();
                let flagged = p.flags.orientation_clamped || prev.flags.orientation_clamped;
                // Passing an actor at arm's length, the view turns fast by construction (the
                // director's steering keeps the drone clear of them).
                let grazing = actors
                    .iter()
                    .any(|x| body_axis_distance_m(&p.position_m, x) < 0.3);
                assert!(
                    df < 0.2 || flagged || grazing,
                    "{a:?} → {b:?} at {k}: view step {df} {p:?}"
                );
                prev = p;
            }
        }
    }
}

/// The toric blend keeps both actors framed through a two-shot → over-the-shoulder move: each
/// stays close to its interpolated screen point.
#[test]
fn toric_blend_keeps_both_actors_on_screen() {
    let l = lens(84.0);
    let g = gimbal();
    let (actors, vs) = visuals();
    let (a, b) = (&vs[2], &vs[6]);
    let mut worst: f64 = 0.0;
    for k in 0..=20 {
        let v = interpolate(a, b, k as f64 / 20.0);
        let p = place(&v, &actors, &l, &g);
        let cam = pose(&p);
        for t in screen_targets(&v, &actors, &l, &g, &p.position_m) {
            let s = cam.project(&l, &t.point_m).unwrap();
            worst = worst.max((s[0] - t.screen[0]).hypot(s[1] - t.screen[1]));
        }
    }
    // The two-shot end is symmetric: its actors of different heights (1.80 and 1.65 m) share
    // its roll-free error (0.07 in screen y at the start), and the move carries it over.
    assert!(worst < 0.2, "worst screen error {worst}");
}

/// Body axis distance: to the segment feet → head.
#[test]
fn body_axis_distance_is_to_the_segment() {
    let a = actor(1.0, 2.0, 0.0, 1.8);
    assert!((body_axis_distance_m(&Vec3::new(1.0, 2.5, 1.0), &a) - 0.5).abs() < 1e-12);
    assert!((body_axis_distance_m(&Vec3::new(1.0, 2.0, 2.3), &a) - 0.5).abs() < 1e-12);
    assert!(
        (body_axis_distance_m(&Vec3::new(1.3, 2.4, -1.0), &a) - 0.5f64.hypot(1.0)).abs() < 1e-12
    );
}

/// `high angle MLS on B 34left MLS on A 34backright`, the actors written across each other.
fn ots_written_across() -> Composition {
    comp(
        CameraAngle::High,
        vec![
            (
                Size::MLS,
                vec![subject("B", Some(Profile::ThreeQuarterLeft), None, None)],
            ),
            (
                Size::MLS,
                vec![subject(
                    "A",
                    Some(Profile::ThreeQuarterBackRight),
                    None,
                    None,
                )],
            ),
        ],
    )
}

/// [`ots_written_across`] prepared, with its lens (84°) and a level camera.
fn ots_written_across_prepared() -> (Lens, Gimbal, Composition, framing::Prepared) {
    let l = lens(84.0);
    let c = ots_written_across();
    let prepared = framing::Prepared::new(&c, &NAMES, &l);
    (l, Gimbal::None, c, prepared)
}

/// The largest step of the camera from one tick to the next, with the actors at `at(k)` on
/// ticks `k` in `0..=ticks`: solved afresh each tick, and held (`solve_near` with the last
/// solve, as the director does). `each` sees every tick's actors, fresh solve and held solve.
fn plain_and_held_steps_m(
    prepared: &framing::Prepared,
    c: &Composition,
    (l, g): (&Lens, &Gimbal),
    ticks: usize,
    at: impl Fn(usize) -> [ActorPose; 2],
    mut each: impl FnMut(usize, &[ActorPose], &Visual, &Visual),
) -> (f64, f64) {
    let (mut plain_m, mut held_m) = (0.0f64, 0.0f64);
    let mut prev: Option<(Vec3, Visual, Vec3)> = None;
    for k in 0..=ticks {
        let actors = at(k);
        let plain = prepared.solve(c, &actors, l, g).unwrap();
        let held = prepared
            .solve_near(c, &actors, l, g, prev.as_ref().map(|(_, v, _)| v), 0.0)
            .unwrap();
        let (p, q) = (
            framing::position_m(&plain, &actors, l, g),
            framing::position_m(&held, &actors, l, g),
        );
        if let Some((p0, _, q0)) = &prev {
            plain_m = plain_m.max((p - p0).norm());
            held_m = held_m.max((q - q0).norm());
        }
        each(k, &actors, &plain, &held);
        prev = Some((p, held, q));
    }
    (plain_m, held_m)
}

/// An over-the-shoulder held tick after tick while the foreground actor walks toward the
/// other, 1 cm a tick: its camera moves a few centimetres a tick at most, fresh or held
/// (`solve_near`, as the director does), within each profile's sector throughout.
#[test]
fn a_held_over_the_shoulder_moves_smoothly_as_an_actor_walks() {
    let (l, g, c, prepared) = ots_written_across_prepared();
    let at = |k: usize| {
        let s = k as f64 * 0.01;
        [
            actor(-1.04, 0.21, 19.0, 1.82),
            actor(0.5 - 0.98 * s, -0.3 - 0.2 * s, -168.0, 1.82),
        ]
    };
    let (plain_jump_m, held_jump_m) =
        plain_and_held_steps_m(&prepared, &c, (&l, &g), 80, at, |k, actors, _, held| {
            let p = framing::position_m(held, actors, &l, &g);
            let (fg, bg) = (&actors[1], &actors[0]);
            let (o_fg, o_bg) = (
                profile_off_rad(&p, fg, Profile::ThreeQuarterLeft),
                profile_off_rad(&p, bg, Profile::ThreeQuarterBackRight),
            );
            assert!(
                o_fg.to_degrees() <= 22.5 && o_bg.to_degrees() <= 22.5,
                "{k}: {o_fg} {o_bg}"
            );
        });
    assert!(plain_jump_m < 0.05, "fresh: {plain_jump_m:.3} m in a tick");
    assert!(held_jump_m < 0.05, "held: {held_jump_m:.3} m in a tick");
}

/// An over-the-shoulder's camera keeps `clear_m` from both actors' body axes, the
/// foreground actor walked up close to the other.
#[test]
fn an_over_the_shoulder_camera_keeps_clear_of_both_actors() {
    let (l, g, c, prepared) = ots_written_across_prepared();
    let actors = [
        actor(-1.06, 0.32, 19.0, 1.82),
        actor(-0.10, -0.40, -168.0, 1.82),
    ];
    let nearest_m = |v: &Visual| {
        let p = framing::position_m(v, &actors, &l, &g);
        actors
            .iter()
            .map(|a| body_axis_distance_m(&p, a))
            .fold(f64::INFINITY, f64::min)
    };
    for clear_m in [0.5, 0.8, 1.0] {
        let kept = prepared
            .solve_near(&c, &actors, &l, &g, None, clear_m)
            .unwrap();
        assert!(
            nearest_m(&kept) >= clear_m - 1e-6,
            "{clear_m}: {}",
            nearest_m(&kept)
        );
    }
}

/// A move between two framings while an actor turns round, one tick at a time: the largest
/// step of the camera target, short way round on every tick (`position_between_m`), with the
/// way carried from tick to tick as the director does (`position_between_way_m`), and of
/// either of the move's two ends. Ticks where an end does not solve restart the count.
fn move_steps_while_turning(from: &Composition, to: &Composition, s: f64) -> [f64; 3] {
    let l = lens(84.0);
    let g = Gimbal::None;
    // A turns round twice, 1° a tick; B stands.
    let at = |k: usize| {
        [
            actor(-2.71, 0.47, -118.0 + k as f64, 1.98),
            actor(1.39, 0.16, -7.0, 2.01),
        ]
    };
    let mut steps_m = [0.0f64; 3];
    let mut way = framing::BlendWay::default();
    let mut prev: Option<[Vec3; 4]> = None;
    for k in 0..=720 {
        let actors = at(k);
        let (Ok(a), Ok(b)) = (
            solve(from, &NAMES, &actors, &l, &g),
            solve(to, &NAMES, &actors, &l, &g),
        ) else {
            prev = None;
            continue;
        };
        let short = framing::position_between_m(&a, &b, s, &actors, &l, &g);
        let (kept, next) = framing::position_between_way_m(&a, &b, s, &actors, &l, &g, &way);
        // With the way of its first tick, the same position, bit for bit.
        if way == framing::BlendWay::default() {
            assert_eq!(short, kept);
        }
        way = next;
        let now = [
            short,
            kept,
            framing::position_m(&a, &actors, &l, &g),
            framing::position_m(&b, &actors, &l, &g),
        ];
        if let Some(before) = prev {
            for i in 0..4 {
                steps_m[i.min(2)] = steps_m[i.min(2)].max((now[i] - before[i]).norm());
            }
        }
        prev = Some(now);
    }
    steps_m
}

/// A move from one actor's framing to another's (cylindrical blend about the actors): with
/// A turning round, its end swings through the far side of the centroid, and the short way
/// round would flip the camera across the actors in one tick (`tests/it/compile.rs` flies
/// such a script). Carried from tick to tick, the way round keeps going: the target moves a
/// few centimetres a tick, as A's end does.
#[test]
fn a_move_between_actors_keeps_its_way_round_while_one_turns() {
    let from = comp(
        CameraAngle::EyeLevel,
        vec![(
            Size::MS,
            vec![subject("A", Some(Profile::ThreeQuarterRight), None, None)],
        )],
    );
    let to = comp(
        CameraAngle::EyeLevel,
        vec![(Size::LS, vec![subject("B", None, None, None)])],
    );
    let [short_m, kept_m, ends_m] = move_steps_while_turning(&from, &to, 0.3);
    assert!(
        short_m > 1.0,
        "the case flips the short way: {short_m:.3} m"
    );
    assert!(
        kept_m < 0.05,
        "kept: {kept_m:.3} m in a tick, the ends {ends_m:.3} m"
    );
}

/// The same for a move between two framings of the same pair (the toric blend, which
/// interpolates the camera's yaw about each actor): with one end circling A (A turning round
/// with a profile written on them), the short way flipped the blend across the actors where
/// the end passed opposite the other end; the kept way follows it round.
#[test]
fn the_toric_blend_keeps_its_way_round_while_one_end_circles() {
    let a = Vec3::new(0.0, 0.0, 1.5);
    let b = Vec3::new(2.0, 0.0, 1.5);
    let c1 = Vec3::new(1.0, -4.0, 1.6);
    let alpha = 0.5;
    let mut turns = [None, None];
    let (mut short_m, mut kept_m, mut end_m) = (0.0f64, 0.0f64, 0.0f64);
    let mut prev: Option<(Vec3, Vec3, Vec3)> = None;
    // c0 circles A at 5 m, 1° a tick, twice round.
    for k in 0..=720 {
        let phi = (k as f64).to_radians();
        let c0 = a + Vec3::new(5.0 * phi.cos(), 5.0 * phi.sin(), 0.1);
        let (short, _) = toric::interpolate(&a, &b, &c0, &c1, alpha, alpha, 0.5, [None, None]);
        let (kept, next) = toric::interpolate(&a, &b, &c0, &c1, alpha, alpha, 0.5, turns);
        if k == 0 {
            assert_eq!(short, kept);
        }
        turns = next.map(Some);
        if let Some((s0, k0, e0)) = prev {
            short_m = short_m.max((short - s0).norm());
            kept_m = kept_m.max((kept - k0).norm());
            end_m = end_m.max((c0 - e0).norm());
        }
        prev = Some((short, kept, c0));
    }
    assert!(
        short_m > 1.0,
        "the case flips the short way: {short_m:.3} m"
    );
    assert!(
        kept_m < 1.5 * end_m,
        "kept: {kept_m:.3} m in a tick, the end {end_m:.3} m"
    );
}

/// A two-shot of two actors walking apart: the camera follows them on their bisector, a few
/// millimetres a tick, fresh or held, both actors on their screen points throughout.
#[test]
fn a_two_shot_follows_walking_actors_smoothly() {
    let l = lens(84.0);
    let g = Gimbal::None;
    let c = two_shot(CameraAngle::Low, Size::LS);
    let prepared = framing::Prepared::new(&c, &NAMES, &l);
    let at = |k: usize| {
        let t = k as f64 * 0.01;
        [
            actor(-0.16 - 0.45 * t, -1.77 - 0.45 * t, 0.0, 1.69),
            actor(-1.78 - 0.12 * t, 0.96 + 0.10 * t, 172.0, 1.72),
        ]
    };
    let (plain_jump_m, held_jump_m) = plain_and_held_steps_m(
        &prepared,
        &c,
        (&l, &g),
        400,
        at,
        |k, actors, plain, held| {
            if k == 0 {
                assert_eq!(held, plain);
            }
            let placed = place(held, actors, &l, &g);
            let cam = pose(&placed);
            for t in screen_targets(held, actors, &l, &g, &placed.position_m) {
                let s = cam.project(&l, &t.point_m).unwrap();
                assert!(
                    (s[0] - t.screen[0]).hypot(s[1] - t.screen[1]) < 0.05,
                    "{k}: {s:?}"
                );
            }
        },
    );
    assert!(plain_jump_m < 0.05, "fresh: {plain_jump_m:.3} m in a tick");
    assert!(held_jump_m < 0.05, "held: {held_jump_m:.3} m in a tick");
}

/// Two actors of different heights in one two-shot, eye level: from equal distances no
/// roll-free camera puts their band centres on one screen line, so the two-shot frames them
/// where a camera aimed between them sees them, the taller higher in the frame: exactly, with
/// a level camera as with a gimbal. Screen points written on one line split the error
/// evenly between the two (equal and opposite in y).
#[test]
fn a_two_shot_of_two_heights_frames_them_as_they_stand() {
    let l = lens(84.0);
    for g in [gimbal(), Gimbal::None] {
        for (xb, yb, hb) in [(2.0, 0.0, 1.65), (1.5, 1.0, 1.50), (2.5, -0.5, 1.95)] {
            let actors = [actor(0.0, 0.0, 0.0, 1.8), actor(xb, yb, 180.0, hb)];
            let c = two_shot(CameraAngle::EyeLevel, Size::FS);
            let v = solve(&c, &NAMES[..2], &actors, &l, &g).unwrap();
            let p = place(&v, &actors, &l, &g);
            let e = screen_error(&v, &actors, &l, &g, &p);
            assert!(e < 1e-6, "B at ({xb}, {yb}), {hb} m: screen error {e}");
            let Visual::Two(t) = &v else { panic!("{v:?}") };
            let taller_higher = (t.screen_a[1] > t.screen_b[1]) == (1.8 > hb);
            assert!(taller_higher, "{t:?}");
        }
        let actors = [actor(0.0, 0.0, 0.0, 1.8), actor(1.2, 0.0, 180.0, 1.65)];
        let third = 1.0 / 3.0;
        let c = comp(
            CameraAngle::EyeLevel,
            vec![(
                Size::MLS,
                vec![
                    subject("A", None, Some(-third), Some(0.0)),
                    subject("B", None, Some(third), Some(0.0)),
                ],
            )],
        );
        let v = solve(&c, &NAMES[..2], &actors, &l, &g).unwrap();
        let p = place(&v, &actors, &l, &g);
        let cam = pose(&p);
        let ys: Vec<f64> = screen_targets(&v, &actors, &l, &g, &p.position_m)
            .iter()
            .map(|t| cam.project(&l, &t.point_m).unwrap()[1] - t.screen[1])
            .collect();
        assert!((ys[0] + ys[1]).abs() < 1e-6 && ys[0].abs() > 1e-3, "{ys:?}");
    }
}

/// A pitch gimbal that barely tilts: a high angle's pitch is out of its reach and flagged.
#[test]
fn a_narrow_gimbal_flags_the_pitch_it_cannot_hold() {
    let l = lens(84.0);
    let narrow = Gimbal::Pitch {
        min_rad: -1e-4,
        max_rad: 1e-4,
        rate_radps: PI,
    };
    let actors = [actor(0.0, 0.0, 0.0, 1.8), actor(2.0, 0.0, 180.0, 1.65)];
    let c = two_shot(CameraAngle::High, Size::FS);
    let v = solve(&c, &NAMES[..2], &actors, &l, &narrow).unwrap();
    let p = place(&v, &actors, &l, &narrow);
    assert!(p.flags.pitch_clamped, "{p:?}");
    assert!(screen_error(&v, &actors, &l, &narrow, &p) > 0.01);
}
