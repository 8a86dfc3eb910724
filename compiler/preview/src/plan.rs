//! The plan views: the stage from above (`top`) and two elevations (`side`), with the camera
//! path coloured by shot, the camera's looking direction every second, and the actors.

use dronecine_math as math;
use dronecine_math::wrap_angle_rad;

use super::figure::{HEAD_CENTRE, HEAD_RADIUS, SHOULDER};
use super::plots::nice_ticks;
use super::svg::{num, truncate, Anchor, Style, Svg};
use super::{actor_color, shot_at, shot_color, shot_names, PreviewInput, ShotKind};

/// Length of the camera heading ticks, metres.
const TICK_M: f64 = 0.35;
/// Length of the actors' facing arrows, metres.
const FACING_M: f64 = 0.55;
const TEXT: &str = "#222222";
const MUTED: &str = "#666666";
const GRID: &str = "#e4e4e4";
const STAGE_FILL: &str = "#f6f3ec";
const STAGE_STROKE: &str = "#555555";

/// A world-to-pixel mapping of one panel: `x` right, `y` (world second axis) up.
#[derive(Clone, Copy)]
struct Frame {
    left: f64,
    top: f64,
    scale: f64,
    min: [f64; 2],
    max: [f64; 2],
}

impl Frame {
    fn px(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.left + (p[0] - self.min[0]) * self.scale,
            self.top + (self.max[1] - p[1]) * self.scale,
        ]
    }

    fn width(&self) -> f64 {
        (self.max[0] - self.min[0]) * self.scale
    }

    fn height(&self) -> f64 {
        (self.max[1] - self.min[1]) * self.scale
    }

    /// Grid lines and tick labels in metres, with axis names.
    fn axes(&self, svg: &mut Svg, x_name: &str, y_name: &str) {
        let grid = Style::stroke(GRID, 1.0);
        for x in nice_ticks(self.min[0], self.max[0], 10) {
            let p = self.px([x, self.min[1]]);
            svg.line(p[0], self.top, p[0], self.top + self.height(), &grid);
            svg.text(p[0], p[1] + 16.0, 12.0, Anchor::Middle, MUTED, &fmt_tick(x));
        }
        for y in nice_ticks(self.min[1], self.max[1], 8) {
            let p = self.px([self.min[0], y]);
            svg.line(self.left, p[1], self.left + self.width(), p[1], &grid);
            svg.text(
                p[0] - 6.0,
                p[1] + 4.0,
                12.0,
                Anchor::End,
                MUTED,
                &fmt_tick(y),
            );
        }
        svg.rect(
            self.left,
            self.top,
            self.width(),
            self.height(),
            &Style::stroke("#bbbbbb", 1.0),
        );
        svg.text(
            self.left + self.width() / 2.0,
            self.top + self.height() + 36.0,
            13.0,
            Anchor::Middle,
            TEXT,
            x_name,
        );
        svg.text_styled(
            self.left - 40.0,
            self.top + self.height() / 2.0,
            13.0,
            Anchor::Middle,
            TEXT,
            false,
            -90.0,
            None,
            y_name,
        );
    }
}

fn fmt_tick(v: f64) -> String {
    let s = num(v);
    s.replace('-', "−")
}

/// Bounds of the stage and of everything drawn, on two world axes, padded.
fn bounds(input: &PreviewInput, axes: [usize; 2], pad_m: f64) -> ([f64; 2], [f64; 2]) {
    let (lo, hi) = (input.stage.min_m(), input.stage.max_m());
    let mut min = [lo[axes[0]], lo[axes[1]]];
    let mut max = [hi[axes[0]], hi[axes[1]]];
    let mut grow = |p: [f64; 3]| {
        for (j, &a) in axes.iter().enumerate() {
            if p[a].is_finite() {
                min[j] = min[j].min(p[a]);
                max[j] = max[j].max(p[a]);
            }
        }
    };
    for s in input.samples {
        grow(s.position_m);
    }
    for poses in input.actors {
        for a in poses {
            grow(a.position_m);
            let mut top = a.position_m;
            top[2] += a.height_m.max(0.0);
            grow(top);
        }
    }
    for j in 0..2 {
        if !(max[j] - min[j]).is_finite() || max[j] - min[j] < 1.0 {
            let c = if (min[j] + max[j]).is_finite() {
                (min[j] + max[j]) / 2.0
            } else {
                0.0
            };
            min[j] = c - 0.5;
            max[j] = c + 0.5;
        }
        min[j] -= pad_m;
        max[j] += pad_m;
    }
    (min, max)
}

/// An arrow from `a` to `b` (pixels).
fn arrow(svg: &mut Svg, a: [f64; 2], b: [f64; 2], color: &str, width: f64) {
    svg.line(a[0], a[1], b[0], b[1], &Style::stroke(color, width));
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = math::hypot(dx, dy);
    if len < 1e-6 {
        return;
    }
    let (ux, uy) = (dx / len, dy / len);
    let head = (3.0 * width + 4.0).min(len * 0.6);
    let base = [b[0] - ux * head, b[1] - uy * head];
    let half = head * 0.55;
    svg.polygon(
        &[
            b,
            [base[0] - uy * half, base[1] + ux * half],
            [base[0] + uy * half, base[1] - ux * half],
        ],
        &Style::fill(color),
    );
}

/// The camera path on a panel, split into one polyline per shot entry.
fn draw_path(svg: &mut Svg, input: &PreviewInput, frame: &Frame, axes: [usize; 2]) {
    let samples = input.samples;
    let mut start = 0;
    while start < samples.len() {
        let shot = shot_at(input.shots, samples[start].t_s);
        let mut end = start + 1;
        while end < samples.len() && shot_at(input.shots, samples[end].t_s) == shot {
            end += 1;
        }
        // Reach into the next piece's first sample so the pieces join.
        let last = end.min(samples.len() - 1);
        let pts: Vec<[f64; 2]> = samples[start..=last]
            .iter()
            .map(|s| frame.px([s.position_m[axes[0]], s.position_m[axes[1]]]))
            .collect();
        let color = shot.map_or(super::REPOSITION_COLOR, |i| shot_color(input.shots, i));
        let mut style = Style::stroke(color, 3.0);
        if shot.is_none_or(|i| input.shots[i].kind == ShotKind::Reposition) {
            style = style.dashed("8 5");
        }
        svg.polyline(&pts, &style);
        start = end;
    }
    // Start and end markers.
    let first = samples[0].position_m;
    let p = frame.px([first[axes[0]], first[axes[1]]]);
    svg.circle(
        p[0],
        p[1],
        6.0,
        &Style::stroke(TEXT, 2.0).with_fill("#ffffff"),
    );
    let last = samples[samples.len() - 1].position_m;
    let q = frame.px([last[axes[0]], last[axes[1]]]);
    svg.rect(q[0] - 5.0, q[1] - 5.0, 10.0, 10.0, &Style::fill(TEXT));
}

/// Indices of the first sample at or after each whole second.
fn every_second(input: &PreviewInput) -> Vec<usize> {
    let mut out = Vec::new();
    let mut next = f64::NEG_INFINITY;
    for (i, s) in input.samples.iter().enumerate() {
        if !s.t_s.is_finite() {
            continue;
        }
        if s.t_s >= next - 1e-9 {
            out.push(i);
            next = s.t_s.floor() + 1.0;
        }
    }
    out
}

/// The shot entries' legend: colour, name, kind, times and (when `psl`) the PSL text.
fn shot_legend(
    svg: &mut Svg,
    input: &PreviewInput,
    x: f64,
    mut y: f64,
    width: f64,
    psl: bool,
) -> f64 {
    let names = shot_names(input.shots);
    svg.text_bold(x, y, 14.0, Anchor::Start, TEXT, "Shots");
    y += 20.0;
    for (i, s) in input.shots.iter().enumerate() {
        let color = shot_color(input.shots, i);
        let mut style = Style::stroke(color, 4.0);
        if s.kind == ShotKind::Reposition {
            style = style.dashed("6 4");
        }
        svg.line(x, y - 4.0, x + 24.0, y - 4.0, &style);
        let head = format!(
            "{}  {}  {:.1}–{:.1} s",
            names[i],
            s.kind.as_str(),
            s.start_s,
            s.end_s
        );
        svg.text(x + 32.0, y, 12.0, Anchor::Start, TEXT, &head);
        y += 16.0;
        if psl && !s.label.is_empty() {
            let text = truncate(&s.label, 11.0, width - 32.0);
            svg.text(x + 32.0, y, 11.0, Anchor::Start, MUTED, &text);
            y += 18.0;
        } else {
            y += 4.0;
        }
    }
    y
}

/// The symbols' legend, one line per (symbol drawer, text).
fn symbol_legend(svg: &mut Svg, input: &PreviewInput, x: f64, mut y: f64, top_view: bool) -> f64 {
    svg.text_bold(x, y, 14.0, Anchor::Start, TEXT, "Symbols");
    y += 22.0;
    svg.circle(
        x + 12.0,
        y - 4.0,
        6.0,
        &Style::stroke(TEXT, 2.0).with_fill("#ffffff"),
    );
    svg.text(x + 32.0, y, 12.0, Anchor::Start, TEXT, "camera path start");
    y += 20.0;
    svg.rect(x + 7.0, y - 9.0, 10.0, 10.0, &Style::fill(TEXT));
    svg.text(x + 32.0, y, 12.0, Anchor::Start, TEXT, "camera path end");
    y += 20.0;
    svg.circle(x + 4.0, y - 4.0, 2.5, &Style::fill(TEXT));
    if top_view {
        svg.line(
            x + 4.0,
            y - 4.0,
            x + 24.0,
            y - 4.0,
            &Style::stroke(TEXT, 1.5),
        );
        svg.text(
            x + 32.0,
            y,
            12.0,
            Anchor::Start,
            TEXT,
            "camera heading, every 1 s",
        );
    } else {
        svg.line(
            x + 4.0,
            y - 4.0,
            x + 22.0,
            y - 10.0,
            &Style::stroke(TEXT, 1.5),
        );
        svg.text(
            x + 32.0,
            y,
            12.0,
            Anchor::Start,
            TEXT,
            "camera looking direction, every 1 s",
        );
    }
    y += 20.0;
    svg.line(
        x,
        y - 4.0,
        x + 24.0,
        y - 4.0,
        &Style::stroke(MUTED, 3.0).dashed("8 5"),
    );
    svg.text(
        x + 32.0,
        y,
        12.0,
        Anchor::Start,
        TEXT,
        "repositioning flight",
    );
    y += 24.0;
    for (k, name) in input.actor_names.iter().enumerate() {
        let c = actor_color(k);
        if top_view {
            svg.circle(x + 6.0, y - 4.0, 6.0, &Style::fill(c));
            arrow(svg, [x + 6.0, y - 4.0], [x + 26.0, y - 4.0], c, 2.0);
            svg.text(
                x + 32.0,
                y,
                12.0,
                Anchor::Start,
                TEXT,
                &format!("{name}: start, facing arrow; dashed: walk; ring: end"),
            );
        } else {
            svg.line(x + 10.0, y + 2.0, x + 10.0, y - 8.0, &Style::stroke(c, 4.0));
            svg.circle(x + 10.0, y - 11.0, 3.5, &Style::fill(c));
            svg.text(
                x + 32.0,
                y,
                12.0,
                Anchor::Start,
                TEXT,
                &format!("{name} at start (faded: at end)"),
            );
        }
        y += 22.0;
    }
    y
}

fn stage_caption(input: &PreviewInput) -> String {
    let s = input.stage.size_m;
    format!("stage {} × {} × {} m", num(s[0]), num(s[1]), num(s[2]))
}

/// Top view: x right, y up, the floor seen from above.
pub fn top_view(input: &PreviewInput) -> Svg {
    let (min, max) = bounds(input, [0, 1], 0.4);
    let (wx, wy) = (max[0] - min[0], max[1] - min[1]);
    let scale = (820.0 / wx).min(640.0 / wy);
    let frame = Frame {
        left: 70.0,
        top: 60.0,
        scale,
        min,
        max,
    };
    let legend_x = frame.left + frame.width() + 40.0;
    let legend_w = 380.0;
    let legend_h =
        60.0 + input.shots.len() as f64 * 38.0 + 130.0 + input.actor_names.len() as f64 * 22.0;
    let height = (frame.top + frame.height() + 60.0).max(legend_h + 40.0);
    let mut svg = Svg::new(legend_x + legend_w, height);
    svg.comment("dronecine preview: top view");
    svg.text_bold(
        frame.left,
        32.0,
        18.0,
        Anchor::Start,
        TEXT,
        "Top view (x–y, seen from above)",
    );

    // Stage and grid.
    let (lo, hi) = (input.stage.min_m(), input.stage.max_m());
    let a = frame.px([lo[0], hi[1]]);
    let b = frame.px([hi[0], lo[1]]);
    svg.rect(
        a[0],
        a[1],
        b[0] - a[0],
        b[1] - a[1],
        &Style::fill(STAGE_FILL),
    );
    frame.axes(&mut svg, "x (m)", "y (m)");
    svg.rect(
        a[0],
        a[1],
        b[0] - a[0],
        b[1] - a[1],
        &Style::stroke(STAGE_STROKE, 2.0),
    );
    svg.text(
        a[0] + 6.0,
        a[1] + 16.0,
        12.0,
        Anchor::Start,
        MUTED,
        &stage_caption(input),
    );

    // Actors: trajectories, then start and end markers.
    for (k, name) in input.actor_names.iter().enumerate() {
        let c = actor_color(k);
        let pts: Vec<[f64; 2]> = (0..input.actors.len())
            .filter_map(|i| input.actor(i, k))
            .map(|p| frame.px([p.position_m[0], p.position_m[1]]))
            .collect();
        svg.polyline(&pts, &Style::stroke(c, 2.0).dashed("5 4").opacity(0.8));
        let (Some(first), Some(last)) = (
            input.actor(0, k),
            input.actor(input.actors.len().wrapping_sub(1), k),
        ) else {
            continue;
        };
        let r = (0.18 * scale).max(6.0);
        let facing = |p: &dronecine_compiler::reference::ActorPose| {
            let o = frame.px([p.position_m[0], p.position_m[1]]);
            let (s, c) = math::sin_cos(p.facing_rad);
            let tip = frame.px([
                p.position_m[0] + c * FACING_M,
                p.position_m[1] + s * FACING_M,
            ]);
            (o, tip)
        };
        let moved = math::hypot(
            first.position_m[0] - last.position_m[0],
            first.position_m[1] - last.position_m[1],
        ) > 0.05
            || wrap_angle_rad(first.facing_rad - last.facing_rad).abs() > 0.05;
        if moved {
            let (o, tip) = facing(last);
            svg.circle(o[0], o[1], r, &Style::stroke(c, 2.0).with_fill("#ffffff"));
            arrow(&mut svg, o, tip, c, 2.0);
        }
        let (o, tip) = facing(first);
        svg.circle(o[0], o[1], r, &Style::fill(c));
        arrow(&mut svg, o, tip, c, 2.5);
        svg.text_halo(o[0] + r + 4.0, o[1] - r - 2.0, 14.0, Anchor::Start, c, name);
    }

    // Camera path, heading ticks, shot labels.
    draw_path(&mut svg, input, &frame, [0, 1]);
    for i in every_second(input) {
        let s = &input.samples[i];
        let o = frame.px([s.position_m[0], s.position_m[1]]);
        let (sn, cs) = math::sin_cos(s.heading_rad);
        let tip = frame.px([s.position_m[0] + cs * TICK_M, s.position_m[1] + sn * TICK_M]);
        svg.circle(o[0], o[1], 2.5, &Style::fill(TEXT));
        svg.line(o[0], o[1], tip[0], tip[1], &Style::stroke(TEXT, 1.5));
    }
    shot_labels(&mut svg, input, &frame, [0, 1]);

    let y = shot_legend(&mut svg, input, legend_x, frame.top, legend_w - 20.0, true);
    symbol_legend(&mut svg, input, legend_x, y + 16.0, true);
    svg
}

/// The shot names at the first sample of each shot entry.
fn shot_labels(svg: &mut Svg, input: &PreviewInput, frame: &Frame, axes: [usize; 2]) {
    let names = shot_names(input.shots);
    let mut seen = vec![false; input.shots.len()];
    for s in input.samples {
        if let Some(i) = shot_at(input.shots, s.t_s) {
            if !seen[i] {
                seen[i] = true;
                let p = frame.px([s.position_m[axes[0]], s.position_m[axes[1]]]);
                let color = shot_color(input.shots, i);
                svg.text_halo(
                    p[0] + 8.0,
                    p[1] + 17.0,
                    13.0,
                    Anchor::Start,
                    color,
                    &names[i],
                );
            }
        }
    }
}

/// Side view: two elevations, x–z seen from −y and y–z seen from +x, at one scale.
pub fn side_view(input: &PreviewInput) -> Svg {
    let (bx_min, bx_max) = bounds(input, [0, 2], 0.3);
    let (by_min, by_max) = bounds(input, [1, 2], 0.3);
    let z_min = bx_min[1].min(by_min[1]).min(-0.1);
    let z_max = bx_max[1].max(by_max[1]);
    let wide = (bx_max[0] - bx_min[0]).max(by_max[0] - by_min[0]);
    let scale = (820.0 / wide).min(280.0 / (z_max - z_min));
    let first = Frame {
        left: 70.0,
        top: 70.0,
        scale,
        min: [bx_min[0], z_min],
        max: [bx_max[0], z_max],
    };
    let second = Frame {
        left: 70.0,
        top: first.top + first.height() + 100.0,
        scale,
        min: [by_min[0], z_min],
        max: [by_max[0], z_max],
    };
    let legend_x = first.left + wide * scale + 40.0;
    let legend_w = 330.0;
    let legend_h =
        60.0 + input.shots.len() as f64 * 20.0 + 130.0 + input.actor_names.len() as f64 * 22.0;
    let height = (second.top + second.height() + 60.0).max(legend_h + 40.0);
    let mut svg = Svg::new(legend_x + legend_w, height);
    svg.comment("dronecine preview: side views");
    for (frame, axes, title, axis_name) in [
        (
            &first,
            [0usize, 2usize],
            "Side view (x–z, seen from −y)",
            "x (m)",
        ),
        (&second, [1, 2], "Side view (y–z, seen from +x)", "y (m)"),
    ] {
        svg.text_bold(
            frame.left,
            frame.top - 16.0,
            18.0,
            Anchor::Start,
            TEXT,
            title,
        );
        let (lo, hi) = (input.stage.min_m(), input.stage.max_m());
        let a = frame.px([lo[axes[0]], hi[2]]);
        let b = frame.px([hi[axes[0]], lo[2]]);
        svg.rect(
            a[0],
            a[1],
            b[0] - a[0],
            b[1] - a[1],
            &Style::fill(STAGE_FILL),
        );
        frame.axes(&mut svg, axis_name, "z (m)");
        svg.rect(
            a[0],
            a[1],
            b[0] - a[0],
            b[1] - a[1],
            &Style::stroke(STAGE_STROKE, 2.0),
        );
        svg.line(a[0], b[1], b[0], b[1], &Style::stroke(STAGE_STROKE, 3.0));
        svg.text(
            a[0] + 6.0,
            a[1] + 16.0,
            12.0,
            Anchor::Start,
            MUTED,
            &stage_caption(input),
        );

        // Actors standing at their start (and, faded, end) positions.
        for (k, name) in input.actor_names.iter().enumerate() {
            let c = actor_color(k);
            let last_i = input.actors.len().wrapping_sub(1);
            for (i, opacity) in [(last_i, 0.35), (0, 1.0)] {
                let Some(p) = input.actor(i, k) else { continue };
                if i == last_i && i != 0 {
                    let f = input.actor(0, k);
                    if f.is_some_and(|f| {
                        (f.position_m[axes[0]] - p.position_m[axes[0]]).abs() < 0.05
                    }) {
                        continue;
                    }
                }
                let h = p.height_m;
                let u = p.position_m[axes[0]];
                let feet = frame.px([u, p.position_m[2]]);
                let shoulder = frame.px([u, p.position_m[2] + SHOULDER * h]);
                let head = frame.px([u, p.position_m[2] + HEAD_CENTRE * h]);
                let w = (0.12 * h * scale).max(3.0);
                svg.line(
                    feet[0],
                    feet[1],
                    shoulder[0],
                    shoulder[1],
                    &Style::stroke(c, w).opacity(opacity),
                );
                svg.circle(
                    head[0],
                    head[1],
                    HEAD_RADIUS * h * scale,
                    &Style::fill(c).opacity(opacity),
                );
                if i == 0 {
                    let top = frame.px([u, p.position_m[2] + h]);
                    svg.text_halo(top[0], top[1] - 6.0, 13.0, Anchor::Middle, c, name);
                }
            }
        }

        draw_path(&mut svg, input, frame, axes);
        for i in every_second(input) {
            let s = &input.samples[i];
            let o = frame.px([s.position_m[axes[0]], s.position_m[2]]);
            let (st, ct) = math::sin_cos(s.camera_pitch_rad);
            let (sp, cp) = math::sin_cos(s.heading_rad);
            let fwd = [ct * cp, ct * sp, st];
            let tip = frame.px([
                s.position_m[axes[0]] + fwd[axes[0]] * TICK_M,
                s.position_m[2] + fwd[2] * TICK_M,
            ]);
            svg.circle(o[0], o[1], 2.5, &Style::fill(TEXT));
            svg.line(o[0], o[1], tip[0], tip[1], &Style::stroke(TEXT, 1.5));
        }
        shot_labels(&mut svg, input, frame, [axes[0], 2]);
    }
    let y = shot_legend(&mut svg, input, legend_x, first.top, legend_w - 20.0, false);
    symbol_legend(&mut svg, input, legend_x, y + 16.0, false);
    svg
}
