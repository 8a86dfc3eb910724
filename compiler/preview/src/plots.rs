//! The time series: speed, acceleration, tilt, heading and altitude over time, with the
//! profile's limits drawn and the shots marked.
//!
//! Tilt follows the servo's plant model (control.md §2–3): per horizontal body axis
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

fn panels(input: &PreviewInput) -> Vec<Panel> {
    let s = input.samples;
    let l = input.limits;
    let deg = f64::to_degrees;
    let col = |f: &dyn Fn(&Sample) -> f64| s.iter().map(f).collect::<Vec<f64>>();
    let tilts: Vec<[f64; 2]> = s
        .iter()
        .map(|x| tilt_commands_rad(x, input.model))
        .collect();
    let pm = |v: f64, unit: &str| {
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
    };
    vec![
        Panel {
            title: "Horizontal speed",
            unit: "m/s",
            series: vec![Series {
                name: "|v_xy|",
                color: "#1f77b4",
                width: 2.0,
                values: col(&|x| horizontal(x.velocity_mps)),
                checked: true,
            }],
            limits: vec![LimitLine {
                value: l.speed_max_mps,
                label: format!("speed_max {} m/s", num(l.speed_max_mps)),
            }],
            range: None,
            break_jump: None,
            ticks: None,
        },
        Panel {
            title: "Vertical speed",
            unit: "m/s",
            series: vec![Series {
                name: "v_z",
                color: "#2ca02c",
                width: 2.0,
                values: col(&|x| x.velocity_mps[2]),
                checked: true,
            }],
            limits: pm(l.vz_max_mps, "m/s (vz_max)"),
            range: None,
            break_jump: None,
            ticks: None,
        },
        Panel {
            title: "Horizontal acceleration",
            unit: "m/s²",
            series: vec![Series {
                name: "|a_xy|",
                color: "#9467bd",
                width: 2.0,
                values: col(&|x| horizontal(x.acceleration_mps2)),
                checked: true,
            }],
            limits: vec![LimitLine {
                value: l.accel_max_mps2,
                label: format!("accel_max {} m/s²", num(l.accel_max_mps2)),
            }],
            range: None,
            break_jump: None,
            ticks: None,
        },
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
            limits: pm(deg(l.tilt_max_rad), "deg (tilt_max)"),
            range: None,
            break_jump: None,
            ticks: None,
        },
        Panel {
            title: "Heading",
            unit: "deg",
            series: vec![Series {
                name: "ψ",
                color: "#8c564b",
                width: 2.0,
                values: col(&|x| deg(x.heading_rad)),
                checked: true,
            }],
            limits: Vec::new(),
            range: Some([-180.0, 180.0]),
            break_jump: Some(180.0),
            ticks: Some(vec![-180.0, -90.0, 0.0, 90.0, 180.0]),
        },
        Panel {
            title: "Heading rate",
            unit: "deg/s",
            series: vec![Series {
                name: "dψ/dt",
                color: "#e377c2",
                width: 2.0,
                values: col(&|x| deg(x.heading_rate_radps)),
                checked: true,
            }],
            limits: pm(deg(l.yaw_rate_max_radps), "deg/s (yaw_rate_max)"),
            range: None,
            break_jump: None,
            ticks: None,
        },
        Panel {
            title: "Altitude",
            unit: "m",
            series: vec![Series {
                name: "z",
                color: "#1f77b4",
                width: 2.0,
                values: col(&|x| x.position_m[2]),
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
        },
    ]
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

/// The time-series figure.
pub fn time_series(input: &PreviewInput) -> Svg {
    let panels = panels(input);
    let samples = input.samples;
    let t_of = |s: &Sample| s.t_s;
    let finite_t = samples.iter().map(t_of).filter(|t| t.is_finite());
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
    let tx = |t: f64| LEFT + (t - t0) / (t1 - t0) * PLOT_W;
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

    // The shot strip: one coloured band per shot entry, named.
    let names = shot_names(input.shots);
    let strip_y = 48.0;
    for (i, s) in input.shots.iter().enumerate() {
        let (a, b) = (tx(s.start_s.max(t0)), tx(s.end_s.min(t1)));
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

    let plot_bottom_all = TOP + panels.len() as f64 * (PANEL_H + PANEL_GAP) - PANEL_GAP;
    let t_ticks = nice_ticks(t0, t1, 12);
    for (p_i, panel) in panels.iter().enumerate() {
        let top = TOP + p_i as f64 * (PANEL_H + PANEL_GAP);
        let [lo, hi] = y_range(panel);
        let py = |v: f64| top + (hi - v) / (hi - lo) * PANEL_H;
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
            let (a, b) = (tx(s.start_s.max(t0)), tx(s.end_s.min(t1)));
            svg.rect(a, top, (b - a).max(0.0), PANEL_H, &Style::fill("#efefef"));
        }
        let grid = Style::stroke(GRID, 1.0);
        for &t in &t_ticks {
            svg.line(tx(t), top, tx(t), top + PANEL_H, &grid);
        }
        let y_ticks = panel.ticks.clone().unwrap_or_else(|| nice_ticks(lo, hi, 4));
        for v in y_ticks {
            svg.line(LEFT, py(v), LEFT + PLOT_W, py(v), &grid);
            svg.text(
                LEFT - 8.0,
                py(v) + 4.0,
                12.0,
                Anchor::End,
                MUTED,
                &num(v).replace('-', "−"),
            );
        }
        for s in input.shots.iter().skip(1) {
            svg.line(
                tx(s.start_s),
                top,
                tx(s.start_s),
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
        // Limits.
        for l in &panel.limits {
            if l.value.is_finite() && l.value >= lo && l.value <= hi {
                svg.line(
                    LEFT,
                    py(l.value),
                    LEFT + PLOT_W,
                    py(l.value),
                    &Style::stroke(LIMIT, 1.5).dashed("7 4"),
                );
            }
        }
        // Data, clipped to the panel.
        let clip = svg.clip_rect(LEFT, top - 1.0, PLOT_W, PANEL_H + 2.0);
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
                pts.push([tx(s.t_s), py(v)]);
                prev = Some(v);
            }
            svg.polyline(&pts, &Style::stroke(series.color, series.width));
        }
        svg.end_group();
        // Legend at the right: the series with their peaks, then the limits.
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
        // Time labels under every panel.
        for &t in &t_ticks {
            svg.text(
                tx(t),
                top + PANEL_H + 15.0,
                11.0,
                Anchor::Middle,
                MUTED,
                &num(t),
            );
        }
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
