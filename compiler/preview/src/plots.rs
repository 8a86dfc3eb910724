//! The time series: speed, acceleration, tilt, heading and altitude over time, with the
//! profile's limits drawn and the shots marked.
//!
//! Tilt follows the servo's plant model (the profile's `model`): per horizontal body axis
//! `v̇ = (K·u − v)/τ`, so the command that flies the reference is `u = (τ·a + v)/K`, read on
//! the body's longitudinal axis (pitch: gain and τ of pitch, positive to accelerate forward)
//! and lateral axis (roll: positive to accelerate to the right). The total is the length of
//! (pitch, roll); `tilt_max` bounds each command.

use super::svg::{num, Anchor, Style, Svg};
use super::{shot_color, shot_names, PreviewInput, ShotKind};
use dronecine_compiler::reference::Sample;
use dronecine_math as math;
use dronecine_profile::Model;

const TEXT: &str = "#222222";
const MUTED: &str = "#666666";
const GRID: &str = "#e8e8e8";
const LIMIT: &str = "#d62728";

/// Values near `lo..hi` at "nice" steps (1, 2, 5 × 10ⁿ), about `target` of them.
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo || target == 0 {
        return Vec::new();
    }
    let raw = (hi - lo) / target as f64;
    let mag = math::powf(10f64, math::log10(raw).floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= 0.75 * raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// One line of a panel.
struct Series {
    name: &'static str,
    color: &'static str,
    width: f64,
    values: Vec<f64>,
    /// Whether the panel's limits bound this series (the total tilt is drawn, not bounded).
    checked: bool,
}

/// A horizontal limit line.
struct LimitLine {
    value: f64,
    label: String,
}

struct Panel {
    title: &'static str,
    unit: &'static str,
    series: Vec<Series>,
    limits: Vec<LimitLine>,
    /// Fixed y range (heading), else fitted to data and limits.
    range: Option<[f64; 2]>,
    /// Break the line where consecutive values jump more than this (wrapped angles).
    break_jump: Option<f64>,
    /// Fixed y ticks (heading), else nice ones.
    ticks: Option<Vec<f64>>,
}

fn horizontal(v: [f64; 3]) -> f64 {
    math::hypot(v[0], v[1])
}

/// Pitch and roll commands (rad) that fly sample `s` under the plant model `m`: per body axis
/// `u = (τ·a + v)/K`, pitch on the longitudinal axis (positive to accelerate forward), roll
/// on the lateral axis (positive to accelerate to the right).
pub fn tilt_commands_rad(s: &Sample, m: &Model) -> [f64; 2] {
    let (sn, cs) = math::sin_cos(s.heading_rad);
    let fwd = |v: [f64; 3]| v[0] * cs + v[1] * sn;
    let right = |v: [f64; 3]| v[0] * sn - v[1] * cs;
    let pitch =
        (m.tau_pitch_s * fwd(s.acceleration_mps2) + fwd(s.velocity_mps)) / m.gain_pitch_mps_per_rad;
    let roll = (m.tau_roll_s * right(s.acceleration_mps2) + right(s.velocity_mps))
        / m.gain_roll_mps_per_rad;
    [pitch, roll]
}

/// The panels of the time series, top to bottom.
fn panels(input: &PreviewInput) -> Vec<Panel> {
    vec![
        horizontal_speed_panel(input),
        vertical_speed_panel(input),
        horizontal_acceleration_panel(input),
        tilt_panel(input),
        heading_panel(input),
        heading_rate_panel(input),
        altitude_panel(input),
    ]
}

/// One value of every sample, in time order.
fn column(samples: &[Sample], f: &dyn Fn(&Sample) -> f64) -> Vec<f64> {
    samples.iter().map(f).collect::<Vec<f64>>()
}

/// A symmetric pair of limit lines at `+v` and `−v`, labelled with `unit`.
fn plus_minus(v: f64, unit: &str) -> Vec<LimitLine> {
    vec![
        LimitLine {
            value: v,
            label: format!("+{} {unit}", num(v)),
        },
        LimitLine {
            value: -v,
            label: format!("−{} {unit}", num(v)),
        },
    ]
}

/// The horizontal speed, under the profile's speed limit.
fn horizontal_speed_panel(input: &PreviewInput) -> Panel {
    let l = input.limits;
    Panel {
        title: "Horizontal speed",
        unit: "m/s",
        series: vec![Series {
            name: "|v_xy|",
            color: "#1f77b4",
            width: 2.0,
            values: column(input.samples, &|x| horizontal(x.velocity_mps)),
            checked: true,
        }],
        limits: vec![LimitLine {
            value: l.speed_max_mps,
            label: format!("speed_max {} m/s", num(l.speed_max_mps)),
        }],
        range: None,
        break_jump: None,
        ticks: None,
    }
}

/// The vertical speed, between the profile's climb and descent limits.
fn vertical_speed_panel(input: &PreviewInput) -> Panel {
    let l = input.limits;
    Panel {
        title: "Vertical speed",
        unit: "m/s",
        series: vec![Series {
            name: "v_z",
            color: "#2ca02c",
            width: 2.0,
            values: column(input.samples, &|x| x.velocity_mps[2]),
            checked: true,
        }],
        limits: plus_minus(l.vz_max_mps, "m/s (vz_max)"),
        range: None,
        break_jump: None,
        ticks: None,
    }
}

/// The horizontal acceleration, under the profile's acceleration limit.
fn horizontal_acceleration_panel(input: &PreviewInput) -> Panel {
    let l = input.limits;
    Panel {
        title: "Horizontal acceleration",
        unit: "m/s²",
        series: vec![Series {
            name: "|a_xy|",
            color: "#9467bd",
            width: 2.0,
            values: column(input.samples, &|x| horizontal(x.acceleration_mps2)),
            checked: true,
        }],
        limits: vec![LimitLine {
            value: l.accel_max_mps2,
            label: format!("accel_max {} m/s²", num(l.accel_max_mps2)),
        }],
        range: None,
        break_jump: None,
        ticks: None,
    }
}

/// The tilt commands (total, pitch and roll), pitch and roll within the profile's tilt limit.
fn tilt_panel(input: &PreviewInput) -> Panel {
    let l = input.limits;
    let deg = f64::to_degrees;
    let tilts: Vec<[f64; 2]> = input
        .samples
        .iter()
        .map(|x| tilt_commands_rad(x, input.model))
        .collect();
    Panel {
        title: "Tilt command (τ·a + v)/K",
        unit: "deg",
        series: vec![
            Series {
                name: "total",
                color: "#222222",
                width: 2.2,
                values: tilts.iter().map(|t| deg(math::hypot(t[0], t[1]))).collect(),
                checked: false,
            },
            Series {
                name: "pitch (+ forward)",
                color: "#ff7f0e",
                width: 1.4,
                values: tilts.iter().map(|t| deg(t[0])).collect(),
                checked: true,
            },
            Series {
                name: "roll (+ right)",
                color: "#17becf",
                width: 1.4,
                values: tilts.iter().map(|t| deg(t[1])).collect(),
                checked: true,
            },
        ],
        limits: plus_minus(deg(l.tilt_max_rad), "deg (tilt_max)"),
        range: None,
        break_jump: None,
        ticks: None,
    }
}

/// The heading, on a fixed ±180° range, its line broken where it wraps.
fn heading_panel(input: &PreviewInput) -> Panel {
    let deg = f64::to_degrees;
    Panel {
        title: "Heading",
        unit: "deg",
        series: vec![Series {
            name: "ψ",
            color: "#8c564b",
            width: 2.0,
            values: column(input.samples, &|x| deg(x.heading_rad)),
            checked: true,
        }],
        limits: Vec::new(),
        range: Some([-180.0, 180.0]),
        break_jump: Some(180.0),
        ticks: Some(vec![-180.0, -90.0, 0.0, 90.0, 180.0]),
    }
}

/// The heading rate, within the profile's yaw-rate limit.
fn heading_rate_panel(input: &PreviewInput) -> Panel {
    let l = input.limits;
    let deg = f64::to_degrees;
    Panel {
        title: "Heading rate",
        unit: "deg/s",
        series: vec![Series {
            name: "dψ/dt",
            color: "#e377c2",
            width: 2.0,
            values: column(input.samples, &|x| deg(x.heading_rate_radps)),
            checked: true,
        }],
        limits: plus_minus(deg(l.yaw_rate_max_radps), "deg/s (yaw_rate_max)"),
        range: None,
        break_jump: None,
        ticks: None,
    }
}

/// The altitude, between the floor and the stage's ceiling.
fn altitude_panel(input: &PreviewInput) -> Panel {
    Panel {
        title: "Altitude",
        unit: "m",
        series: vec![Series {
            name: "z",
            color: "#1f77b4",
            width: 2.0,
            values: column(input.samples, &|x| x.position_m[2]),
            checked: true,
        }],
        limits: vec![
            LimitLine {
                value: input.stage.size_m[2],
                label: format!("stage ceiling {} m", num(input.stage.size_m[2])),
            },
            LimitLine {
                value: 0.0,
                label: "floor".to_string(),
            },
        ],
        range: None,
        break_jump: None,
        ticks: None,
    }
}

/// Whether a value leaves the band the limits draw (below the lowest or above the highest;
/// a single limit bounds from above).
fn exceeds(values: &[f64], limits: &[LimitLine]) -> bool {
    let finite = limits.iter().map(|l| l.value).filter(|v| v.is_finite());
    let hi = finite.clone().fold(f64::NEG_INFINITY, f64::max);
    let lo = if limits.len() > 1 {
        finite.fold(f64::INFINITY, f64::min)
    } else {
        f64::NEG_INFINITY
    };
    hi.is_finite() && values.iter().any(|&v| v > hi + 1e-9 || v < lo - 1e-9)
}

/// The y range of a panel: data and limits, padded.
fn y_range(panel: &Panel) -> [f64; 2] {
    if let Some(r) = panel.range {
        return r;
    }
    let mut lo = 0.0f64;
    let mut hi = 0.0f64;
    for v in panel
        .series
        .iter()
        .flat_map(|s| s.values.iter().copied())
        .chain(panel.limits.iter().map(|l| l.value))
        .filter(|v| v.is_finite())
    {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi - lo < 1e-6 {
        hi = lo + 1.0;
    }
    let pad = 0.08 * (hi - lo);
    [if lo < 0.0 { lo - pad } else { lo }, hi + pad]
}

const WIDTH: f64 = 1280.0;
const LEFT: f64 = 90.0;
const PLOT_W: f64 = 880.0;
const PANEL_H: f64 = 130.0;
const PANEL_GAP: f64 = 46.0;
const TOP: f64 = 96.0;

/// The time axis shared by every panel: from `t0` to `t1` across the plot's width.
#[derive(Clone, Copy)]
struct TimeAxis {
    t0: f64,
    t1: f64,
}

impl TimeAxis {
    /// The span of the samples and of the shots, at least a second where they have none.
    fn of(input: &PreviewInput) -> TimeAxis {
        let t_of = |s: &Sample| s.t_s;
        let finite_t = input.samples.iter().map(t_of).filter(|t| t.is_finite());
        let mut t0 = finite_t.clone().fold(f64::INFINITY, f64::min);
        let mut t1 = finite_t.fold(f64::NEG_INFINITY, f64::max);
        for s in input.shots {
            if s.start_s.is_finite() && s.end_s.is_finite() {
                t0 = t0.min(s.start_s);
                t1 = t1.max(s.end_s);
            }
        }
        if !(t0.is_finite() && t1.is_finite()) || t1 - t0 < 1e-6 {
            t0 = if t0.is_finite() { t0 } else { 0.0 };
            t1 = t0 + 1.0;
        }
        TimeAxis { t0, t1 }
    }

    /// The x coordinate of time `t`.
    fn x(&self, t: f64) -> f64 {
        LEFT + (t - self.t0) / (self.t1 - self.t0) * PLOT_W
    }
}

/// Where a panel is drawn: its top edge and the y range it spans.
#[derive(Clone, Copy)]
struct PanelBox {
    top: f64,
    lo: f64,
    hi: f64,
}

impl PanelBox {
    /// The y coordinate of value `v`.
    fn y(&self, v: f64) -> f64 {
        self.top + (self.hi - v) / (self.hi - self.lo) * PANEL_H
    }
}

/// The time-series figure.
pub fn time_series(input: &PreviewInput) -> Svg {
    let panels = panels(input);
    let axis = TimeAxis::of(input);
    let height = TOP + panels.len() as f64 * (PANEL_H + PANEL_GAP) + 30.0;
    let mut svg = Svg::new(WIDTH, height);
    svg.comment("dronecine preview: time series");
    svg.text_bold(
        LEFT,
        30.0,
        18.0,
        Anchor::Start,
        TEXT,
        "Reference over time, with the drone profile's limits",
    );
    draw_shot_strip(&mut svg, input, &axis);
    let plot_bottom_all = TOP + panels.len() as f64 * (PANEL_H + PANEL_GAP) - PANEL_GAP;
    let t_ticks = nice_ticks(axis.t0, axis.t1, 12);
    for (p_i, panel) in panels.iter().enumerate() {
        let top = TOP + p_i as f64 * (PANEL_H + PANEL_GAP);
        let [lo, hi] = y_range(panel);
        let frame = PanelBox { top, lo, hi };
        draw_panel_frame(&mut svg, input, panel, &axis, &frame, &t_ticks);
        draw_limit_lines(&mut svg, panel, &frame);
        draw_series(&mut svg, input, panel, &axis, &frame);
        draw_legend(&mut svg, panel, top);
        draw_time_labels(&mut svg, &axis, top, &t_ticks);
    }
    svg.text(
        LEFT + PLOT_W / 2.0,
        plot_bottom_all + 40.0,
        13.0,
        Anchor::Middle,
        TEXT,
        "time (s); dashed verticals: shot boundaries; grey: repositioning",
    );
    svg
}

/// The shot strip: one coloured band per shot entry, named.
fn draw_shot_strip(svg: &mut Svg, input: &PreviewInput, axis: &TimeAxis) {
    let (t0, t1) = (axis.t0, axis.t1);
    let names = shot_names(input.shots);
    let strip_y = 48.0;
    for (i, s) in input.shots.iter().enumerate() {
        let (a, b) = (axis.x(s.start_s.max(t0)), axis.x(s.end_s.min(t1)));
        let color = shot_color(input.shots, i);
        let mut style = Style::fill(color).opacity(0.85);
        if s.kind == ShotKind::Reposition {
            style = Style::fill(color).opacity(0.45);
        }
        svg.rect(a, strip_y, (b - a).max(0.0), 20.0, &style);
        if b - a > 18.0 {
            svg.text_bold(
                (a + b) / 2.0,
                strip_y + 15.0,
                12.0,
                Anchor::Middle,
                "#ffffff",
                &names[i],
            );
        }
    }
    svg.text(LEFT - 8.0, strip_y + 15.0, 12.0, Anchor::End, TEXT, "shot");
}

/// A panel's title, its repositionings shaded, its grid with the y ticks labelled, the shot
/// boundaries, its border and its unit.
fn draw_panel_frame(
    svg: &mut Svg,
    input: &PreviewInput,
    panel: &Panel,
    axis: &TimeAxis,
    frame: &PanelBox,
    t_ticks: &[f64],
) {
    let (t0, t1) = (axis.t0, axis.t1);
    let PanelBox { top, lo, hi } = *frame;
    svg.text_bold(
        LEFT,
        top - 8.0,
        14.0,
        Anchor::Start,
        TEXT,
        &format!("{} ({})", panel.title, panel.unit),
    );
    // Repositionings shaded, grid, shot boundaries.
    for s in input
        .shots
        .iter()
        .filter(|s| s.kind == ShotKind::Reposition)
    {
        let (a, b) = (axis.x(s.start_s.max(t0)), axis.x(s.end_s.min(t1)));
        svg.rect(a, top, (b - a).max(0.0), PANEL_H, &Style::fill("#efefef"));
    }
    let grid = Style::stroke(GRID, 1.0);
    for &t in t_ticks {
        svg.line(axis.x(t), top, axis.x(t), top + PANEL_H, &grid);
    }
    let y_ticks = panel.ticks.clone().unwrap_or_else(|| nice_ticks(lo, hi, 4));
    for v in y_ticks {
        svg.line(LEFT, frame.y(v), LEFT + PLOT_W, frame.y(v), &grid);
        svg.text(
            LEFT - 8.0,
            frame.y(v) + 4.0,
            12.0,
            Anchor::End,
            MUTED,
            &num(v).replace('-', "−"),
        );
    }
    for s in input.shots.iter().skip(1) {
        svg.line(
            axis.x(s.start_s),
            top,
            axis.x(s.start_s),
            top + PANEL_H,
            &Style::stroke("#999999", 1.0).dashed("4 3"),
        );
    }
    svg.rect(LEFT, top, PLOT_W, PANEL_H, &Style::stroke("#bbbbbb", 1.0));
    svg.text_styled(
        LEFT - 54.0,
        top + PANEL_H / 2.0,
        12.0,
        Anchor::Middle,
        TEXT,
        false,
        -90.0,
        None,
        panel.unit,
    );
}

/// The panel's limits that fall within its range, as dashed lines.
fn draw_limit_lines(svg: &mut Svg, panel: &Panel, frame: &PanelBox) {
    let PanelBox { lo, hi, .. } = *frame;
    for l in &panel.limits {
        if l.value.is_finite() && l.value >= lo && l.value <= hi {
            svg.line(
                LEFT,
                frame.y(l.value),
                LEFT + PLOT_W,
                frame.y(l.value),
                &Style::stroke(LIMIT, 1.5).dashed("7 4"),
            );
        }
    }
}

/// The panel's series as lines, clipped to the panel, broken where a wrapped value jumps.
fn draw_series(
    svg: &mut Svg,
    input: &PreviewInput,
    panel: &Panel,
    axis: &TimeAxis,
    frame: &PanelBox,
) {
    let samples = input.samples;
    let clip = svg.clip_rect(LEFT, frame.top - 1.0, PLOT_W, PANEL_H + 2.0);
    svg.begin_group(Some(&clip));
    for series in &panel.series {
        let mut pts = Vec::with_capacity(samples.len());
        let mut prev: Option<f64> = None;
        for (s, &v) in samples.iter().zip(&series.values) {
            if let (Some(jump), Some(p)) = (panel.break_jump, prev) {
                if (v - p).abs() > jump {
                    pts.push([f64::NAN, f64::NAN]);
                }
            }
            pts.push([axis.x(s.t_s), frame.y(v)]);
            prev = Some(v);
        }
        svg.polyline(&pts, &Style::stroke(series.color, series.width));
    }
    svg.end_group();
}

/// The legend at the right of a panel whose top is at `top`: the series with their peaks,
/// then the limits.
fn draw_legend(svg: &mut Svg, panel: &Panel, top: f64) {
    let lx = LEFT + PLOT_W + 20.0;
    let mut ly = top + 12.0;
    for series in &panel.series {
        svg.line(
            lx,
            ly - 4.0,
            lx + 22.0,
            ly - 4.0,
            &Style::stroke(series.color, series.width + 1.0),
        );
        let peak = series
            .values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| if v.abs() > m.abs() { v } else { m });
        let over = series.checked && exceeds(&series.values, &panel.limits);
        let mut text = if panel.range.is_some() {
            series.name.to_string()
        } else {
            format!(
                "{}  (peak {} {})",
                series.name,
                num(peak).replace('-', "−"),
                panel.unit
            )
        };
        if over {
            text.push_str("  OVER LIMIT");
        }
        svg.text_styled(
            lx + 30.0,
            ly,
            12.0,
            Anchor::Start,
            if over { LIMIT } else { TEXT },
            over,
            0.0,
            None,
            &text,
        );
        ly += 18.0;
    }
    for (shown, l) in panel.limits.iter().enumerate() {
        if shown == 0 {
            svg.line(
                lx,
                ly - 4.0,
                lx + 22.0,
                ly - 4.0,
                &Style::stroke(LIMIT, 1.5).dashed("7 4"),
            );
        }
        svg.text(lx + 30.0, ly, 12.0, Anchor::Start, LIMIT, &l.label);
        ly += 16.0;
    }
}

/// The time labels under a panel whose top is at `top`.
fn draw_time_labels(svg: &mut Svg, axis: &TimeAxis, top: f64, t_ticks: &[f64]) {
    for &t in t_ticks {
        svg.text(
            axis.x(t),
            top + PANEL_H + 15.0,
            11.0,
            Anchor::Middle,
            MUTED,
            &num(t),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_nice_and_inside() {
        assert_eq!(
            nice_ticks(0.0, 10.0, 5),
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
        );
        let t = nice_ticks(-0.37, 1.9, 4);
        assert!(t.iter().all(|v| (-0.37..=1.9).contains(v)));
        assert_eq!(t, vec![0.0, 0.5, 1.0, 1.5]);
        assert!(nice_ticks(1.0, 1.0, 4).is_empty());
        assert!(nice_ticks(0.0, f64::NAN, 4).is_empty());
    }
}
