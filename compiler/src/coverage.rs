//! `coverage A and B for Ns`: the classic coverage of a pair of actors, expanded for one
//! drone into ordinary shots before the script is flown ([`expand`]).
//!
//! A coverage becomes [`COVERAGE_PARTS`] cuts, each carrying the coverage line's span:
//! an establishing two-shot, the over-the-shoulder over A's shoulder (on B), the one over B's
//! shoulder (on A), a single on A and a single on B. The two-shot comes first, the other four
//! in the order whose cameras stand nearest each other in turn (the least flying; [`ORDER`]
//! on a tie). All five stand on one side of the line between A and B ([`crate::line`]): the
//! side the pair's nearest shot before the coverage fixes, else the nearest after it, else
//! the side the actors face (the camera sees their faces) if the cameras fit inside the
//! stage less its margin there, else the other if they fit there, else the right side (the
//! camera right of A→B).
//!
//! Each part's profiles come from where the actors stand and face when it is flown: for
//! the side S, film grammar's wanted direction of the camera from each actor (over A's
//! shoulder: A's back three-quarter on S, B's front three-quarter on S, as if each faced the
//! other), and of the eight profiles the one nearest that direction from the actor's
//! facing. Each part's size is the tightest that holds against the blocking over its
//! time (the framing's [`crate::framing::TwoVisual::distance_ratio`] within
//! [`size::SIZE_SLACK`], with [`SIZE_MARGIN`] to spare), with its camera inside the stage
//! less its margin, on S, and clear of every actor by the on-set distance
//! ([`dronecine_profile::Safety::on_set_m`]); the two-shot stands back where the cut to the
//! over-the-shoulder after it would read as a jump (`film::jump_cut`).
//!
//! Timing: the parts' holds and the repositioning flights the director inserts between
//! them fill the coverage's duration. The holds are split in [`SHARES`] of what the flights
//! leave, the director is run over the expanded script to measure the flights, and the holds
//! are split again, until the coverage lasts its duration within [`TIMING_TOLERANCE_S`]
//! (holds in whole milliseconds, so that the expansion written as PSL text reads back to the
//! same shots). Where the flights leave less than [`COVERAGE_MIN_HOLD_S`] a part, each part
//! is held that long and the coverage runs longer (`compile::coverage_overruns`).
//!
//! The expansion is deterministic: the same script and profile give the same shots, bit for
//! bit (a flight log's replay rebuilds them from the script it records).

use dronecine_diag::{Diagnostic, Span};
use dronecine_grammar::script::{
    Composition, Coverage, CoveragePart, Framing, Scene, Script, Shot, ShotContent, Subject,
    Transition, COVERAGE_MIN_HOLD_S, COVERAGE_PARTS,
};
use dronecine_grammar::vocab::{CameraAngle, Profile as Angle, ScreenThird, Size};
use dronecine_math as math;
use dronecine_math::wrap_angle_rad;
use dronecine_profile::{Gimbal, Profile};

use crate::blocking::Blocking;
use crate::camera::{Lens, Vec3};
use crate::code::CompileCode;
use crate::director::{scene_lens, Director};
use crate::framing::{self, Side, Visual};
use crate::line;
use crate::reference::{ActorPose, ShotTiming};
use crate::size;

/// What a part of a coverage frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `SIZE on A and B`, symmetric.
    TwoShot,
    /// Over A's shoulder, on B (A in the foreground).
    OverA,
    /// Over B's shoulder, on A.
    OverB,
    /// `SIZE on A PROFILE screen …`.
    SingleA,
    SingleB,
}

impl Kind {
    /// The part's name in a comment or a caption.
    pub fn describe(self, a: &str, b: &str) -> String {
        match self {
            Kind::TwoShot => "establishing two-shot".into(),
            Kind::OverA => format!("over {a}'s shoulder, on {b}"),
            Kind::OverB => format!("over {b}'s shoulder, on {a}"),
            Kind::SingleA => format!("single on {a}"),
            Kind::SingleB => format!("single on {b}"),
        }
    }
}

/// The classic order of the parts. A coverage flies its establishing two-shot first and the
/// other four in the order of these that flies the least: of the 24 orders, the one whose
/// cameras are the nearest each other in turn.
pub const ORDER: [Kind; COVERAGE_PARTS] = [
    Kind::TwoShot,
    Kind::OverA,
    Kind::OverB,
    Kind::SingleA,
    Kind::SingleB,
];

/// Each part's share of the holds, in the order flown: the establishing two-shot the longest.
pub const SHARES: [f64; COVERAGE_PARTS] = [0.3, 0.2, 0.2, 0.15, 0.15];

/// How close to its duration the expanded coverage lasts, flights included.
pub const TIMING_TOLERANCE_S: f64 = 0.005;

/// The repositioning flight assumed between two parts before one is measured.
const FLIGHT_GUESS_S: f64 = 2.0;

/// Rounds of measuring the flights and splitting the holds again; the parts' framings are
/// chosen again in the first [`DESIGN_ROUNDS`] only, so that the timing settles.
const TIMING_ROUNDS: usize = 5;
const DESIGN_ROUNDS: usize = 2;

/// A part's size holds with this much to spare (its camera's distance this much nearer the
/// end of [`size::SIZE_SLACK`]): on set the actors stand a few centimetres off their marks,
/// and a size designed to the slack's end would not hold there.
pub const SIZE_MARGIN: f64 = 1.05;

/// The times a part's framing is checked at over its hold: its start, middle and end.
const CHECKS: usize = 3;

/// The expanded script: every coverage replaced by its parts (the rest as it is, the script's
/// length the end of its last shot), and the expansion's own warnings
/// (`compile::coverage_overruns`). A script without a coverage, or without a scene, comes
/// back as it is.
pub fn expand(script: &Script, profile: &Profile) -> (Script, Vec<Diagnostic>) {
    let Some(scene) = &script.scene else {
        return (script.clone(), Vec::new());
    };
    let ctx = Context::new(scene, profile);
    let mut plans: Vec<Plan> = Vec::new();
    for index in 0..script.timeline.len() {
        let partial = build(script, &plans);
        plans.extend(Plan::first(&ctx, &partial, script, index, plans.len()));
    }
    if plans.is_empty() {
        return (script.clone(), Vec::new());
    }
    let mut built = build(script, &plans);
    let mut timings = fly(&built, scene, profile, &plans);
    for round in 0..TIMING_ROUNDS {
        let mut settled = true;
        for plan in &mut plans {
            settled &= plan.retime(&ctx, &timings, round < DESIGN_ROUNDS);
        }
        if settled {
            break;
        }
        built = build(script, &plans);
        timings = fly(&built, scene, profile, &plans);
    }
    let diagnostics = plans.iter().filter_map(|p| p.overrun(&timings)).collect();
    (built, diagnostics)
}

/// One coverage's parts: their framings, holds and side.
#[derive(Clone, Debug)]
struct Plan {
    coverage: Coverage,
    span: Span,
    /// The coverage's actors, by index in the scene.
    a: usize,
    b: usize,
    /// The side of the line from A to B every part stands on.
    side: Side,
    /// The parts in the order flown.
    order: [Kind; COVERAGE_PARTS],
    /// Where its first part is in the expanded script.
    first: usize,
    duration_s: f64,
    compositions: Vec<Composition>,
    holds_s: [f64; COVERAGE_PARTS],
    /// When each part is held, as last measured (before the first measure, estimated).
    windows: [(f64, f64); COVERAGE_PARTS],
}

impl Plan {
    /// The plan of shot `index` of `script` if it is a coverage (the `earlier`-th), framed
    /// against the blocking at its written times with guessed flights; `partial` is the
    /// script with the coverages before it expanded, whose shots before it fix the side.
    fn first(
        ctx: &Context,
        partial: &Script,
        script: &Script,
        index: usize,
        earlier: usize,
    ) -> Option<Plan> {
        let shot = script.timeline.get(index)?;
        let ShotContent::Coverage(coverage) = &shot.content else {
            return None;
        };
        let (a, b) = (ctx.index(&coverage.a)?, ctx.index(&coverage.b)?);
        let duration_s = shot.end_s - shot.start_s;
        let holds_s = split(duration_s - FLIGHT_GUESS_S * (COVERAGE_PARTS - 1) as f64);
        let first = index + earlier * (COVERAGE_PARTS - 1);
        let mut plan = Plan {
            coverage: coverage.clone(),
            span: shot.span,
            a,
            b,
            side: Side::Right,
            order: ORDER,
            first,
            duration_s,
            compositions: Vec::new(),
            holds_s,
            windows: windows_from(shot.start_s, &holds_s, FLIGHT_GUESS_S),
        };
        // The side the pair's nearest shot before fixes, else the nearest after, else the
        // one that fits.
        let (lens, gimbal) = (&ctx.lens, &ctx.gimbal);
        let pair = (a.min(b), a.max(b));
        let near = |later| line::side_near(partial, ctx.scene, (lens, gimbal), first, pair, later);
        plan.side = match near(false).or_else(|| near(true)) {
            Some(s) if a <= b => s,
            Some(s) => s.swapped(),
            None => ctx.side_that_fits(&plan),
        };
        plan.order = ctx.shortest_order(&plan);
        plan.compositions = ctx.design(&plan, plan.side).0;
        Some(plan)
    }

    /// The holds split again from the flights measured in `timings` (and, with `design`,
    /// the framings chosen again at the parts' new times). Whether the coverage already
    /// lasted its duration.
    fn retime(&mut self, ctx: &Context, timings: &[ShotTiming], design: bool) -> bool {
        let Some(flown) = self.flown(timings) else {
            return true;
        };
        let length_s = flown[COVERAGE_PARTS - 1].1 - flown[0].0;
        if (length_s - self.duration_s).abs() <= TIMING_TOLERANCE_S {
            return true;
        }
        let held_s: f64 = self.holds_s.iter().sum();
        self.holds_s = split(self.duration_s - (length_s - held_s));
        let mut t = flown[0].0;
        for p in 0..COVERAGE_PARTS {
            if p > 0 {
                t += flown[p].0 - flown[p - 1].1;
            }
            self.windows[p] = (t, t + self.holds_s[p]);
            t += self.holds_s[p];
        }
        if design {
            self.compositions = ctx.design(self, self.side).0;
        }
        false
    }

    /// Each part's hold as the director flew it, if it flew them all.
    fn flown(&self, timings: &[ShotTiming]) -> Option<[(f64, f64); COVERAGE_PARTS]> {
        let mut out = [(0.0, 0.0); COVERAGE_PARTS];
        for (p, slot) in out.iter_mut().enumerate() {
            let t = timings.iter().find(|t| t.index == self.first + p)?;
            *slot = (t.start_s, t.end_s);
        }
        Some(out)
    }

    /// `compile::coverage_overruns` when the coverage, as flown in `timings`, lasts longer or
    /// shorter than written by more than [`OVERRUN_TOLD_S`].
    fn overrun(&self, timings: &[ShotTiming]) -> Option<Diagnostic> {
        let flown = self.flown(timings)?;
        let length_s = flown[COVERAGE_PARTS - 1].1 - flown[0].0;
        if (length_s - self.duration_s).abs() <= OVERRUN_TOLD_S {
            return None;
        }
        let held_s: f64 = self.holds_s.iter().sum();
        let flights_s = length_s - held_s;
        let needed_s = (flights_s + COVERAGE_PARTS as f64 * COVERAGE_MIN_HOLD_S).max(length_s);
        let (a, b) = (&self.coverage.a, &self.coverage.b);
        Some(
            Diagnostic::warning(
                CompileCode::CoverageOverruns,
                self.span,
                format!(
                    "the coverage of {a} and {b} lasts {length_s:.1} s, not the {:.1} s \
                     written: the drone's {} repositioning flights between its shots take \
                     {flights_s:.1} s, and each of its {COVERAGE_PARTS} shots is held at least \
                     {COVERAGE_MIN_HOLD_S} s",
                    self.duration_s,
                    COVERAGE_PARTS - 1
                ),
            )
            .with_label(format!("lasts {length_s:.1} s"))
            .with_help(format!(
                "give it at least `for {}s`, or block {a} and {b} nearer each other: the \
                 cameras round them stand nearer each other then, and the flights are shorter",
                needed_s.ceil()
            )),
        )
    }

    /// Part `p` of the expanded script: the coverage's transition and pin on the first.
    fn part(&self, shot: &Shot, p: usize, start_s: f64) -> Shot {
        let composition = self
            .compositions
            .get(p)
            .cloned()
            .unwrap_or_else(|| self.coverage.unexpanded());
        Shot {
            start_s,
            end_s: start_s + self.holds_s[p],
            pinned: p == 0 && shot.pinned,
            transition: if p == 0 {
                shot.transition.clone()
            } else {
                Transition::Cut
            },
            content: ShotContent::Composition(composition),
            span: shot.span,
            coverage: Some(CoveragePart {
                part: p + 1,
                parts: COVERAGE_PARTS,
                a: self.coverage.a.clone(),
                b: self.coverage.b.clone(),
            }),
        }
    }
}

/// A coverage told as lasting other than written past this (the timing settles to
/// [`TIMING_TOLERANCE_S`] where the flights leave the holds their minimum).
const OVERRUN_TOLD_S: f64 = 0.05;

/// `script` with the coverages `plans` cover replaced by their parts, back to back from the
/// coverage's written start (the others as they are).
fn build(script: &Script, plans: &[Plan]) -> Script {
    let mut timeline = Vec::with_capacity(script.timeline.len() + plans.len() * COVERAGE_PARTS);
    let mut plans = plans.iter().peekable();
    for shot in &script.timeline {
        let plan = plans
            .next_if(|p| p.span == shot.span && matches!(shot.content, ShotContent::Coverage(_)));
        let Some(plan) = plan else {
            timeline.push(shot.clone());
            continue;
        };
        let mut start_s = shot.start_s;
        for p in 0..COVERAGE_PARTS {
            let part = plan.part(shot, p, start_s);
            start_s = part.end_s;
            timeline.push(part);
        }
    }
    let duration_s = timeline.last().map_or(0.0, |s| s.end_s);
    Script {
        scene: script.scene.clone(),
        cast: script.cast.clone(),
        timeline,
        duration_s,
    }
}

/// The timeline as the director flies `script` against its blocking at the default rate, up
/// to the last part of the last of `plans`.
fn fly(script: &Script, scene: &Scene, profile: &Profile, plans: &[Plan]) -> Vec<ShotTiming> {
    let until = plans.iter().map(|p| p.first + COVERAGE_PARTS - 1).max();
    let mut director = Director::new(script, scene, profile);
    let blocking = Blocking::new(scene);
    let mut poses = blocking.poses(0.0);
    let rate_hz = crate::compile::DEFAULT_RATE_HZ;
    // A timeline always ends: this only guards the loop (as `compile` does).
    let limit = ((script.duration_s * 4.0 + 3600.0) * rate_hz) as u64;
    for k in 0..=limit {
        let t_s = k as f64 / rate_hz;
        blocking.poses_into(t_s, &mut poses);
        director.step(t_s, &poses);
        let reached = until.is_some_and(|u| director.timings().iter().any(|x| x.index >= u));
        if director.finished() || reached {
            break;
        }
    }
    director.timings().to_vec()
}

/// `total_s` of holds split in [`SHARES`], each at least [`COVERAGE_MIN_HOLD_S`] (all of them
/// that long when `total_s` is less than their sum), in whole milliseconds (the first part
/// takes the rounding).
fn split(total_s: f64) -> [f64; COVERAGE_PARTS] {
    let min_s = COVERAGE_MIN_HOLD_S;
    let mut holds = [min_s; COVERAGE_PARTS];
    if !(total_s > min_s * COVERAGE_PARTS as f64) {
        return holds;
    }
    // The parts whose share would fall below the minimum are held the minimum, and the
    // others share the rest.
    let mut free = [true; COVERAGE_PARTS];
    loop {
        let fixed = free.iter().filter(|f| !**f).count() as f64 * min_s;
        let weight: f64 = (0..COVERAGE_PARTS)
            .filter(|&p| free[p])
            .map(|p| SHARES[p])
            .sum();
        let rest = total_s - fixed;
        let short: Vec<usize> = (0..COVERAGE_PARTS)
            .filter(|&p| free[p] && rest * SHARES[p] / weight < min_s)
            .collect();
        if short.is_empty() {
            for p in (0..COVERAGE_PARTS).filter(|&p| free[p]) {
                holds[p] = rest * SHARES[p] / weight;
            }
            break;
        }
        for p in short {
            free[p] = false;
        }
    }
    let ms = |x: f64| (x * 1000.0).round() / 1000.0;
    for h in holds.iter_mut().skip(1) {
        *h = ms(*h);
    }
    let others: f64 = holds[1..].iter().sum();
    holds[0] = ms(total_s - others).max(min_s);
    holds
}

/// The holds `holds_s` from `start_s`, a flight of `flight_s` between two.
fn windows_from(
    start_s: f64,
    holds_s: &[f64; COVERAGE_PARTS],
    flight_s: f64,
) -> [(f64, f64); COVERAGE_PARTS] {
    let mut out = [(0.0, 0.0); COVERAGE_PARTS];
    let mut t = start_s;
    for (p, slot) in out.iter_mut().enumerate() {
        if p > 0 {
            t += flight_s;
        }
        *slot = (t, t + holds_s[p]);
        t += holds_s[p];
    }
    out
}

/// What the design of the parts reads: the scene, its blocking, the lens, and where a
/// camera may stand.
struct Context<'a> {
    scene: &'a Scene,
    names: Vec<String>,
    blocking: Blocking,
    lens: Lens,
    gimbal: Gimbal,
    /// The stage less the profile's margin.
    lo: Vec3,
    hi: Vec3,
    /// How far from every actor's body a camera stands: the on-set distance.
    clear_m: f64,
}

impl<'a> Context<'a> {
    fn new(scene: &'a Scene, profile: &Profile) -> Context<'a> {
        let (lo, hi) = crate::route::stage_less_margin(&scene.stage, profile.safety.stage_margin_m);
        Context {
            scene,
            names: scene.actors.iter().map(|a| a.name.clone()).collect(),
            blocking: Blocking::new(scene),
            lens: scene_lens(scene, profile),
            gimbal: profile.camera.gimbal,
            lo,
            hi,
            clear_m: profile.safety.on_set_m(),
        }
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The actors at the start, middle and end of a hold.
    fn poses(&self, window: (f64, f64)) -> Vec<Vec<ActorPose>> {
        (0..CHECKS)
            .map(|k| {
                let s = k as f64 / (CHECKS - 1) as f64;
                self.blocking.poses(window.0 + (window.1 - window.0) * s)
            })
            .collect()
    }

    /// The side of the line from A to B the actors face more (the camera sees their faces
    /// there), if every part's camera fits inside the stage there, else the other if they
    /// fit there; the right side when they face neither more.
    fn side_that_fits(&self, plan: &Plan) -> Side {
        let actors = self.blocking.poses(plan.windows[0].0);
        let (pa, pb) = (&actors[plan.a].position_m, &actors[plan.b].position_m);
        let (ux, uy) = (pb[0] - pa[0], pb[1] - pa[1]);
        // The actors' facings against the right side's normal, (uy, −ux).
        let facing_right: f64 = [plan.a, plan.b]
            .iter()
            .map(|&i| {
                let (s, c) = math::sin_cos(actors[i].facing_rad);
                c * uy - s * ux
            })
            .sum::<f64>()
            / math::hypot(ux, uy).max(1e-9);
        let first = if facing_right < -FACED_SIDE {
            Side::Left
        } else {
            Side::Right
        };
        [first, first.swapped()]
            .into_iter()
            .find(|side| self.design(plan, *side).1)
            .unwrap_or(first)
    }

    /// Part `kind`'s composition on `side` against the actors over `window`, and whether it
    /// found a size that holds (else a fallback the compiler then warns about).
    fn compose(
        &self,
        plan: &Plan,
        side: Side,
        kind: Kind,
        window: (f64, f64),
    ) -> (Composition, bool) {
        let poses = self.poses(window);
        match kind {
            Kind::TwoShot => self.two_shot(plan, side, &poses, None),
            Kind::OverA => self.over(plan, side, &poses, plan.a, plan.b),
            Kind::OverB => self.over(plan, side, &poses, plan.b, plan.a),
            Kind::SingleA => self.single(plan, side, &poses, plan.a, plan.b),
            Kind::SingleB => self.single(plan, side, &poses, plan.b, plan.a),
        }
    }

    /// The order of the parts that flies the least, the establishing two-shot first: of the
    /// orders of the other four, the one whose cameras (framed against the actors at the
    /// coverage's middle) are the nearest each other in turn, counting each flight by the
    /// square root of its length (a short flight's time at the drone's acceleration), the
    /// classic order on a tie.
    fn shortest_order(&self, plan: &Plan) -> [Kind; COVERAGE_PARTS] {
        let mid_s = (plan.windows[0].0 + plan.windows[COVERAGE_PARTS - 1].1) / 2.0;
        let actors = self.blocking.poses(mid_s);
        let camera = |kind: Kind| {
            let (comp, _) = self.compose(plan, plan.side, kind, (mid_s, mid_s));
            let prepared = framing::Prepared::new(&comp, &self.names, &self.lens)
                .on_side((kind == Kind::TwoShot).then_some(plan.side));
            let v = prepared
                .solve(&comp, &actors, &self.lens, &self.gimbal)
                .ok()?;
            Some(framing::position_m(&v, &actors, &self.lens, &self.gimbal))
        };
        let cameras: Option<Vec<Vec3>> = ORDER.iter().map(|k| camera(*k)).collect();
        let Some(cameras) = cameras else {
            return ORDER;
        };
        let at = |k: Kind| ORDER.iter().position(|x| *x == k).unwrap_or(0);
        let cost = |order: &[Kind; COVERAGE_PARTS]| -> f64 {
            (order.windows(2))
                .map(|w| (cameras[at(w[1])] - cameras[at(w[0])]).norm().sqrt())
                .sum()
        };
        let mut best = (cost(&ORDER), ORDER);
        for order in orders() {
            let c = cost(&order);
            if c < best.0 - 1e-9 {
                best = (c, order);
            }
        }
        best.1
    }

    /// The parts' compositions on `side`, in the plan's order, and whether each found a
    /// size that holds.
    fn design(&self, plan: &Plan, side: Side) -> (Vec<Composition>, bool) {
        let mut all = true;
        let mut out = Vec::with_capacity(COVERAGE_PARTS);
        for (p, kind) in plan.order.into_iter().enumerate() {
            let (comp, holds) = self.compose(plan, side, kind, plan.windows[p]);
            all &= holds;
            out.push(comp);
        }
        // The establishing two-shot and the over-the-shoulder after it frame the same two
        // actors: a size apart at most and from nearly the same side, the cut reads as a jump
        // (`film::jump_cut`). The two-shot stands back then, as far as it holds.
        let two_actors = matches!(plan.order[1], Kind::OverA | Kind::OverB);
        if plan.coverage.size.is_none() && two_actors && self.jumps(plan, side, &out) {
            let after = framed_size(&out[1]) as usize + line::JUMP_SIZE_STEPS;
            let poses = self.poses(plan.windows[0]);
            let (comp, holds) = self.two_shot(plan, side, &poses, Size::ALL.get(after).copied());
            if holds {
                out[0] = comp;
            }
        }
        (out, all)
    }

    /// The establishing two-shot: its written size, else the tightest that holds (from
    /// `at_least`, if given).
    fn two_shot(
        &self,
        plan: &Plan,
        side: Side,
        poses: &[Vec<ActorPose>],
        at_least: Option<Size>,
    ) -> (Composition, bool) {
        let cov = &plan.coverage;
        let sizes: Vec<Size> = match cov.size {
            Some(s) => vec![s],
            None => {
                let from = at_least.map_or(0, |s| s as usize);
                Size::ALL[from.min(Size::ALL.len() - 1)..].to_vec()
            }
        };
        for s in &sizes {
            let comp = cov.two_shot(*s);
            if self.frames(&comp, plan, side, poses, true) {
                return (comp, true);
            }
        }
        (cov.unexpanded(), false)
    }

    /// The over-the-shoulder over `fg`'s shoulder on `bg`: the profiles nearest film
    /// grammar's directions (the nearest pair first, then their neighbours), the background
    /// size the tightest that holds with them, the foreground's the size whose band centres
    /// at the height of the background's (a level camera lands both at their screen heights
    /// then).
    fn over(
        &self,
        plan: &Plan,
        side: Side,
        poses: &[Vec<ActorPose>],
        fg: usize,
        bg: usize,
    ) -> (Composition, bool) {
        let (mid, dir) = self.wanted(plan, side, poses, fg, bg, Away);
        let mut combos: Vec<(f64, Angle, Angle)> = Vec::with_capacity(9);
        for (pf, df) in nearest_profiles(&mid[fg], dir) {
            for (pb, db) in nearest_profiles(&mid[bg], dir) {
                combos.push((df + db, pf, pb));
            }
        }
        combos.sort_by(|x, y| x.0.total_cmp(&y.0));
        let heights = (
            self.scene.actors[fg].height_m,
            self.scene.actors[bg].height_m,
        );
        let ots = |pf: Angle, pb: Angle, bg_size: Size| {
            let fg_size = matched_size(bg_size, heights.1, heights.0);
            Composition {
                camera_angle: CameraAngle::EyeLevel,
                framings: vec![
                    framing(fg_size, subject(&self.names[fg], pf, None)),
                    framing(bg_size, subject(&self.names[bg], pb, None)),
                ],
            }
        };
        for (_, pf, pb) in &combos {
            for s in Size::ALL {
                let comp = ots(*pf, *pb, s);
                if self.frames(&comp, plan, side, poses, false) {
                    return (comp, true);
                }
            }
        }
        let (_, pf, pb) = combos[0];
        (ots(pf, pb, Size::FS), false)
    }

    /// The single on `who`: from their front three-quarter on the side (the nearest profile
    /// that keeps the camera on it), on the third of the frame the two-shot shows them on,
    /// the tightest size that holds.
    fn single(
        &self,
        plan: &Plan,
        side: Side,
        poses: &[Vec<ActorPose>],
        who: usize,
        other: usize,
    ) -> (Composition, bool) {
        let (mid, dir) = self.wanted(plan, side, poses, who, other, Toward);
        // From the right side of A→B a roll-free camera shows A left of B.
        let left = (who == plan.a) == (side == Side::Right);
        let third = if left {
            ScreenThird::Left
        } else {
            ScreenThird::Right
        };
        let single = |p: Angle, s: Size| Composition {
            camera_angle: CameraAngle::EyeLevel,
            framings: vec![framing(
                s,
                subject(&self.names[who], p, Some(third.screen_x())),
            )],
        };
        let profiles = nearest_profiles(&mid[who], dir);
        for (p, _) in &profiles {
            for s in Size::ALL {
                let comp = single(*p, s);
                if self.frames(&comp, plan, side, poses, false) {
                    return (comp, true);
                }
            }
        }
        (single(profiles[0].0, Size::MS), false)
    }

    /// Film grammar's direction of the camera from `from` (floor, unit) against the actors
    /// in the middle of `poses`: the side's normal to the line from A to B, turned 45° toward
    /// `other` or away from them; with those actors.
    fn wanted<'p>(
        &self,
        plan: &Plan,
        side: Side,
        poses: &'p [Vec<ActorPose>],
        from: usize,
        other: usize,
        way: Way,
    ) -> (&'p [ActorPose], [f64; 2]) {
        let poses = &poses[CHECKS / 2][..];
        let xy = |i: usize| [poses[i].position_m[0], poses[i].position_m[1]];
        let unit = |v: [f64; 2]| {
            let n = math::hypot(v[0], v[1]);
            if n > 0.0 {
                [v[0] / n, v[1] / n]
            } else {
                [1.0, 0.0]
            }
        };
        let (pa, pb) = (xy(plan.a), xy(plan.b));
        let u = unit([pb[0] - pa[0], pb[1] - pa[1]]);
        let n = match side {
            Side::Right => [u[1], -u[0]],
            Side::Left => [-u[1], u[0]],
        };
        let (pf, po) = (xy(from), xy(other));
        let mut to = unit([po[0] - pf[0], po[1] - pf[1]]);
        if way == Away {
            to = [-to[0], -to[1]];
        }
        (poses, unit([to[0] + n[0], to[1] + n[1]]))
    }

    /// Whether `comp` frames as it says against each of `poses`: it solves (a two-shot on
    /// `side`), a two-actor framing holds its size (and an over-the-shoulder keeps its
    /// foreground actor in the frame, on the other half from the background one), and the
    /// camera is inside the stage less its margin, [`Context::clear_m`] from every actor and
    /// on `side` of the line from A to B.
    fn frames(
        &self,
        comp: &Composition,
        plan: &Plan,
        side: Side,
        poses: &[Vec<ActorPose>],
        two_shot: bool,
    ) -> bool {
        let (lens, gimbal) = (&self.lens, &self.gimbal);
        let prepared =
            framing::Prepared::new(comp, &self.names, lens).on_side(two_shot.then_some(side));
        poses.iter().all(|actors| {
            let Ok(v) = prepared.solve(comp, actors, lens, gimbal) else {
                return false;
            };
            if let Visual::Two(t) = &v {
                let in_frame = !t.over_shoulder
                    || (t.screen_a[0].abs() <= 1.0 && t.screen_a[0] * t.screen_b[0] < 0.0);
                if !(size::holds_at_ratio(t.distance_ratio * SIZE_MARGIN) && in_frame) {
                    return false;
                }
            }
            let c = framing::position_m(&v, actors, lens, gimbal);
            let inside = (0..3).all(|i| c[i] >= self.lo[i] && c[i] <= self.hi[i]);
            let clear =
                (actors.iter()).all(|x| framing::body_axis_distance_m(&c, x) >= self.clear_m);
            // A single may stand on the line (seen from the other actor far away): it
            // crosses nothing.
            let on_side = match self.side_of(plan, actors, &c) {
                Some(s) => s == side,
                None => matches!(v, Visual::One(_)),
            };
            inside && clear && on_side
        })
    }

    /// The side of the line from A to B (in the coverage's order) a camera at `c` stands on,
    /// `None` on it ([`line::side_of`]).
    fn side_of(&self, plan: &Plan, actors: &[ActorPose], c: &Vec3) -> Option<Side> {
        let s = line::side_of((plan.a.min(plan.b), plan.a.max(plan.b)), actors, c)?;
        Some(if plan.a <= plan.b { s } else { s.swapped() })
    }

    /// Whether the cut from the establishing two-shot to the over-the-shoulder after it
    /// would read as a jump: a size apart at most, and the camera turned less than
    /// [`line::JUMP_ANGLE_RAD`] (and a margin) round the pair.
    fn jumps(&self, plan: &Plan, side: Side, parts: &[Composition]) -> bool {
        let steps = (framed_size(&parts[0]) as usize).abs_diff(framed_size(&parts[1]) as usize);
        if steps >= line::JUMP_SIZE_STEPS {
            return false;
        }
        let camera = |p: usize, at_s: f64| {
            let actors = self.blocking.poses(at_s);
            let prepared = framing::Prepared::new(&parts[p], &self.names, &self.lens)
                .on_side((p == 0).then_some(side));
            let v = prepared
                .solve(&parts[p], &actors, &self.lens, &self.gimbal)
                .ok()?;
            let c = framing::position_m(&v, &actors, &self.lens, &self.gimbal);
            let (pa, pb) = (&actors[plan.a].position_m, &actors[plan.b].position_m);
            let m = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
            let line = math::atan2(pb[1] - pa[1], pb[0] - pa[0]);
            Some(wrap_angle_rad(math::atan2(c.y - m[1], c.x - m[0]) - line))
        };
        match (camera(0, plan.windows[0].1), camera(1, plan.windows[1].0)) {
            (Some(b0), Some(b1)) => {
                wrap_angle_rad(b1 - b0).abs() < line::JUMP_ANGLE_RAD + JUMP_MARGIN_RAD
            }
            _ => false,
        }
    }
}

/// Every order of the parts with the establishing two-shot first, the classic one first.
fn orders() -> Vec<[Kind; COVERAGE_PARTS]> {
    let rest = &ORDER[1..];
    let mut out = Vec::with_capacity(24);
    for i in 0..4 {
        for j in (0..4).filter(|j| *j != i) {
            for k in (0..4).filter(|k| *k != i && *k != j) {
                let l = 6 - i - j - k;
                out.push([ORDER[0], rest[i], rest[j], rest[k], rest[l]]);
            }
        }
    }
    out
}

/// How much more the actors face one side of the line than the other (the sum of their
/// facings' cosines with its normal) for a coverage without an established side to take it.
const FACED_SIDE: f64 = 0.1;

/// How much more than [`line::JUMP_ANGLE_RAD`] the cut into the first over-the-shoulder
/// turns the camera, for it not to read as a jump against live actors.
const JUMP_MARGIN_RAD: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Which way from the other actor [`Context::wanted`] turns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Way {
    Toward,
    Away,
}
use Way::{Away, Toward};

/// The three profiles whose directions from `actor` are nearest `dir` (floor, unit), nearest
/// first, each with how far its direction is from it.
fn nearest_profiles(actor: &ActorPose, dir: [f64; 2]) -> Vec<(Angle, f64)> {
    let bearing = math::atan2(dir[1], dir[0]);
    let mut all: Vec<(Angle, f64)> = Angle::ALL
        .into_iter()
        .map(|p| {
            let off = wrap_angle_rad(bearing - actor.facing_rad - p.azimuth_rad()).abs();
            (p, off)
        })
        .collect();
    all.sort_by(|x, y| x.1.total_cmp(&y.1));
    all.truncate(3);
    all
}

/// The size of an actor `height_m` tall whose band centres nearest that of `asked` on an
/// actor `asked_height_m` tall (the same size for actors of one height).
fn matched_size(asked: Size, asked_height_m: f64, height_m: f64) -> Size {
    let centre = |s: Size, h: f64| {
        let (b, t) = size::band(s, h);
        (b + t) / 2.0
    };
    let want = centre(asked, asked_height_m);
    Size::ALL
        .into_iter()
        .min_by(|x, y| {
            let off = |s: Size| (centre(s, height_m) - want).abs();
            off(*x).total_cmp(&off(*y))
        })
        .unwrap_or(asked)
}

/// The size of a composition's main framing (the background's of an over-the-shoulder).
fn framed_size(comp: &Composition) -> Size {
    comp.framings.last().map_or(Size::MS, |f| f.size)
}

fn framing(size: Size, subject: Subject) -> Framing {
    Framing {
        size,
        subjects: vec![subject],
    }
}

fn subject(actor: &str, profile: Angle, screen_x: Option<f64>) -> Subject {
    Subject {
        actor: actor.to_string(),
        profile: Some(profile),
        screen_x,
        screen_y: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_split_in_shares_in_whole_milliseconds_and_never_below_the_minimum() {
        let h = split(20.0);
        let total: f64 = h.iter().sum();
        assert!((total - 20.0).abs() < 1e-9, "{h:?}");
        for (x, share) in h.iter().zip(SHARES) {
            assert!((x - 20.0 * share).abs() < 0.002, "{h:?}");
            assert_eq!((x * 1000.0).round() / 1000.0, *x, "{x}");
        }
        // 9 s: the singles' 15 % would be 1.35 s; held 1.5 s, the others share the rest.
        let h = split(9.0);
        assert_eq!(&h[3..], &[1.5, 1.5]);
        assert!((h.iter().sum::<f64>() - 9.0).abs() < 1e-9, "{h:?}");
        assert!(h[0] > h[1] && h[1] == h[2] && h[2] > 1.5, "{h:?}");
        // Less than five minimum holds: each the minimum.
        assert_eq!(split(6.0), [COVERAGE_MIN_HOLD_S; COVERAGE_PARTS]);
        assert_eq!(split(f64::NAN), [COVERAGE_MIN_HOLD_S; COVERAGE_PARTS]);
    }

    #[test]
    fn orders_are_every_order_of_the_four_after_the_two_shot_once() {
        let all = orders();
        assert_eq!(all.len(), 24);
        assert_eq!(all[0], ORDER);
        for (i, o) in all.iter().enumerate() {
            assert_eq!(o[0], Kind::TwoShot);
            for k in &ORDER {
                assert_eq!(o.iter().filter(|x| *x == k).count(), 1, "{o:?}");
            }
            assert!(!all[..i].contains(o));
        }
    }
}
