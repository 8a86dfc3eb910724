//! The storyboard contact sheet: one row per shot entry, the camera's view at its start,
//! middle and end, labelled with the shot's number, kind, times and PSL text.
//!
//! Each frame has the lens aspect and shows the horizon, the stage floor (outline and a 1 m
//! grid) and the stage's corner posts, the actors as figures ([`super::figure`]) drawn far to
//! near, each named, and faint thirds lines. An actor out of frame is named at the frame edge
//! with an arrow toward it.

use dronecine_math as math;
use dronecine_math::wrap_angle_rad;

use super::figure::{figure, project_segment, Figure};
use super::svg::{num, truncate, Anchor, Style, Svg};
use super::{actor_color, shot_color, shot_names, PreviewInput, ShotInfo, ShotKind};
use dronecine_compiler::camera::{CameraPose, Vec3};
use dronecine_compiler::reference::Sample;

const TEXT: &str = "#222222";
const MUTED: &str = "#666666";
const SKY: &str = "#e3eaf1";
const FLOOR: &str = "#ebe5d8";
const FLOOR_LINE: &str = "#b9ae98";
const SKIN: &str = "#f2d6b8";

const MARGIN: f64 = 24.0;
const FRAME_W: f64 = 384.0;
const GAP: f64 = 18.0;
const HEADER_H: f64 = 50.0;
const CAPTION_H: f64 = 44.0;
const ROW_GAP: f64 = 18.0;
const TITLE_H: f64 = 64.0;

/// The samples shown for a shot entry: the first at or after its start, the one nearest its
/// middle, and the last at or before its end (within the entry); the samples nearest those
/// times when none falls inside. `samples` must be non-empty and in time order.
pub fn frame_sample_indices(samples: &[Sample], shot: &ShotInfo) -> [usize; 3] {
    let eps = 1e-6;
    let nearest = |t: f64| {
        samples
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1.t_s - t).abs().total_cmp(&(b.1.t_s - t).abs()))
            .map_or(0, |(i, _)| i)
    };
    let inside: Vec<usize> = (0..samples.len())
        .filter(|&i| {
            let t = samples[i].t_s;
            t >= shot.start_s - eps && t <= shot.end_s + eps
        })
        .collect();
    match (inside.first(), inside.last()) {
        (Some(&first), Some(&last)) => {
            let mid_t = (shot.start_s + shot.end_s) / 2.0;
            let mid = *inside
                .iter()
                .min_by(|&&a, &&b| {
                    (samples[a].t_s - mid_t)
                        .abs()
                        .total_cmp(&(samples[b].t_s - mid_t).abs())
                })
                .unwrap_or(&first);
            [first, mid, last]
        }
        _ => [
            nearest(shot.start_s),
            nearest((shot.start_s + shot.end_s) / 2.0),
            nearest(shot.end_s),
        ],
    }
}

fn camera_pose(s: &Sample) -> CameraPose {
    CameraPose {
        position_m: Vec3::new(s.position_m[0], s.position_m[1], s.position_m[2]),
        heading_rad: s.heading_rad,
        pitch_rad: s.camera_pitch_rad,
    }
}

/// A frame's placement on the sheet, mapping screen coordinates to pixels.
#[derive(Clone, Copy)]
struct Slot {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

impl Slot {
    fn px(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.x + (p[0] + 1.0) / 2.0 * self.w,
            self.y + (1.0 - p[1]) / 2.0 * self.h,
        ]
    }

    fn len(&self, screen_y: f64) -> f64 {
        screen_y * self.h / 2.0
    }
}

fn darker(color: &str) -> String {
    // `#rrggbb` at 70 %.
    let c = color.trim_start_matches('#');
    if c.len() != 6 {
        return color.to_string();
    }
    let mut out = String::from("#");
    for i in 0..3 {
        let v = u8::from_str_radix(&c[2 * i..2 * i + 2], 16).unwrap_or(0);
        out.push_str(&format!("{:02x}", (f64::from(v) * 0.7).round() as u8));
    }
    out
}

fn draw_figure(svg: &mut Svg, slot: &Slot, fig: &Figure, color: &str) {
    let outline = darker(color);
    let px = |pts: &Vec<[f64; 2]>| pts.iter().map(|p| slot.px(*p)).collect::<Vec<_>>();
    if let Some(legs) = &fig.legs {
        svg.polygon(&px(legs), &Style::stroke(&outline, 1.2).with_fill(&outline));
    }
    if let Some(neck) = &fig.neck {
        svg.polygon(&px(neck), &Style::stroke(&outline, 1.0).with_fill(SKIN));
    }
    if let Some(torso) = &fig.torso {
        svg.polygon(&px(torso), &Style::stroke(&outline, 1.2).with_fill(color));
    }
    let head = slot.px(fig.head_centre);
    let r = slot.len(fig.head_radius);
    let nose = fig.nose.map(|[a, b]| (slot.px(a), slot.px(b)));
    let nose_w = (r * 0.35).max(1.0);
    if let (Some((a, b)), false) = (nose, fig.nose_in_front) {
        svg.line(a[0], a[1], b[0], b[1], &Style::stroke(TEXT, nose_w));
    }
    svg.circle(
        head[0],
        head[1],
        r,
        &Style::stroke(&outline, (r * 0.12).clamp(0.8, 2.0)).with_fill(SKIN),
    );
    for e in &fig.eyes {
        let p = slot.px(*e);
        svg.circle(
            p[0],
            p[1],
            slot.len(fig.eye_radius).max(0.8),
            &Style::fill(TEXT),
        );
    }
    if let (Some((a, b)), true) = (nose, fig.nose_in_front) {
        svg.line(a[0], a[1], b[0], b[1], &Style::stroke(TEXT, nose_w));
    }
}

/// The floor, grid, stage posts and horizon of one frame.
fn draw_scene(svg: &mut Svg, slot: &Slot, input: &PreviewInput, pose: &CameraPose) {
    // Horizon: a level direction ahead projects to y = −tan(pitch)·Sy.
    let pitch = pose.pitch_rad.clamp(-1.55, 1.55);
    let horizon =
        slot.px([0.0, -math::tan(pitch) * input.lens.sy()])[1].clamp(slot.y, slot.y + slot.h);
    svg.rect(slot.x, slot.y, slot.w, horizon - slot.y, &Style::fill(SKY));
    svg.rect(
        slot.x,
        horizon,
        slot.w,
        slot.y + slot.h - horizon,
        &Style::fill(FLOOR),
    );
    let (lo, hi) = (input.stage.min_m(), input.stage.max_m());
    let seg = |svg: &mut Svg, a: Vec3, b: Vec3, style: &Style| {
        if let Some([p, q]) = project_segment(pose, &input.lens, &a, &b) {
            let (p, q) = (slot.px(p), slot.px(q));
            svg.line(p[0], p[1], q[0], q[1], style);
        }
    };
    let grid = Style::stroke(FLOOR_LINE, 0.7).opacity(0.8);
    let first = |v: f64| v.ceil();
    let mut x = first(lo[0]);
    while x <= hi[0] && x.is_finite() {
        seg(
            svg,
            Vec3::new(x, lo[1], 0.0),
            Vec3::new(x, hi[1], 0.0),
            &grid,
        );
        x += 1.0;
    }
    let mut y = first(lo[1]);
    while y <= hi[1] && y.is_finite() {
        seg(
            svg,
            Vec3::new(lo[0], y, 0.0),
            Vec3::new(hi[0], y, 0.0),
            &grid,
        );
        y += 1.0;
    }
    let edge = Style::stroke("#8d826c", 1.4);
    let corners = [
        [lo[0], lo[1]],
        [hi[0], lo[1]],
        [hi[0], hi[1]],
        [lo[0], hi[1]],
    ];
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        seg(
            svg,
            Vec3::new(a[0], a[1], 0.0),
            Vec3::new(b[0], b[1], 0.0),
            &edge,
        );
        seg(
            svg,
            Vec3::new(a[0], a[1], 0.0),
            Vec3::new(a[0], a[1], hi[2]),
            &Style::stroke("#9aa5b1", 1.0).dashed("4 3"),
        );
    }
}

/// One frame: the view from sample `i`.
fn draw_frame(svg: &mut Svg, slot: &Slot, input: &PreviewInput, i: usize) {
    let sample = &input.samples[i];
    let pose = camera_pose(sample);
    let clip = svg.clip_rect(slot.x, slot.y, slot.w, slot.h);
    svg.begin_group(Some(&clip));
    draw_scene(svg, slot, input, &pose);
    let mut figures: Vec<(usize, Figure)> = (0..input.actor_names.len())
        .filter_map(|k| {
            let a = input.actor(i, k)?;
            figure(&pose, &input.lens, a).map(|f| (k, f))
        })
        .collect();
    figures.sort_by(|a, b| b.1.depth_m.total_cmp(&a.1.depth_m).then(a.0.cmp(&b.0)));
    for (k, fig) in &figures {
        draw_figure(svg, slot, fig, actor_color(*k));
    }
    // Thirds.
    let thirds = Style::stroke("#ffffff", 1.0).opacity(0.9);
    let thirds_dark = Style::stroke("#000000", 0.6).opacity(0.25);
    for f in [1.0 / 3.0, 2.0 / 3.0] {
        let x = slot.x + f * slot.w;
        let y = slot.y + f * slot.h;
        for st in [&thirds, &thirds_dark] {
            svg.line(x, slot.y, x, slot.y + slot.h, st);
            svg.line(slot.x, y, slot.x + slot.w, y, st);
        }
    }
    // Names: above the head, kept inside the frame, with an arrow when the actor is out of it.
    for (k, fig) in &figures {
        let name = &input.actor_names[*k];
        let top = fig.crown.unwrap_or(fig.head_centre);
        let p = slot.px(top);
        let (mut x, mut y) = (p[0], p[1] - 6.0);
        let mut label = name.clone();
        let c = fig.head_centre;
        if c[0] < -1.0 {
            label = format!("◀ {name}");
        } else if c[0] > 1.0 {
            label = format!("{name} ▶");
        } else if c[1] > 1.0 {
            label = format!("▲ {name}");
        } else if c[1] < -1.0 {
            label = format!("▼ {name}");
        }
        let half = super::svg::text_width(&label, 13.0) / 2.0 + 3.0;
        x = x.clamp(slot.x + half, slot.x + slot.w - half);
        y = y.clamp(slot.y + 16.0, slot.y + slot.h - 6.0);
        svg.text_halo(x, y, 13.0, Anchor::Middle, actor_color(*k), &label);
    }
    // Actors behind the camera, listed at the bottom.
    let behind: Vec<&str> = (0..input.actor_names.len())
        .filter(|k| input.actor(i, *k).is_some() && !figures.iter().any(|(j, _)| j == k))
        .map(|k| input.actor_names[k].as_str())
        .collect();
    if !behind.is_empty() {
        svg.text(
            slot.x + 6.0,
            slot.y + slot.h - 6.0,
            11.0,
            Anchor::Start,
            MUTED,
            &format!("behind the camera: {}", behind.join(", ")),
        );
    }
    svg.end_group();
    svg.rect(
        slot.x,
        slot.y,
        slot.w,
        slot.h,
        &Style::stroke("#333333", 1.5),
    );
}

/// A caption line about the camera: height, heading, pitch and distance to each actor.
fn camera_caption(input: &PreviewInput, i: usize) -> String {
    let s = &input.samples[i];
    let mut out = format!(
        "z {} m · ψ {}° · τ {}°",
        fmt1(s.position_m[2]),
        fmt0(wrap_angle_rad(s.heading_rad).to_degrees()),
        fmt0(s.camera_pitch_rad.to_degrees())
    );
    for (k, name) in input.actor_names.iter().enumerate() {
        if let Some(a) = input.actor(i, k) {
            let d = math::hypot(
                a.position_m[0] - s.position_m[0],
                a.position_m[1] - s.position_m[1],
            );
            out.push_str(&format!(" · {name} {} m", fmt1(d)));
        }
    }
    out
}

fn fmt1(v: f64) -> String {
    format!("{v:.1}").replace('-', "−")
}

fn fmt0(v: f64) -> String {
    let r = v.round();
    let r = if r == 0.0 { 0.0 } else { r };
    format!("{r:.0}").replace('-', "−")
}

/// The contact sheet.
pub fn storyboard(input: &PreviewInput) -> Svg {
    let aspect = input.lens.aspect().clamp(0.5, 3.0);
    let frame_h = (FRAME_W / aspect).round();
    let row_h = HEADER_H + frame_h + CAPTION_H + ROW_GAP;
    let width = 2.0 * MARGIN + 3.0 * FRAME_W + 2.0 * GAP;
    let rows = input.shots.len().max(1);
    let mut svg = Svg::new(width, TITLE_H + rows as f64 * row_h + MARGIN);
    svg.comment("dronecine preview: storyboard");
    svg.text_bold(
        MARGIN,
        32.0,
        18.0,
        Anchor::Start,
        TEXT,
        "Storyboard: the camera's view at the start, middle and end of every shot",
    );
    svg.text(
        MARGIN,
        52.0,
        12.0,
        Anchor::Start,
        MUTED,
        &format!(
            "lens {}° horizontal, {}:1 · faint lines: thirds · ψ heading, τ camera pitch · distances on the floor",
            fmt0(input.lens.fov_x_rad().to_degrees()),
            num(input.lens.aspect())
        ),
    );
    let names = shot_names(input.shots);
    let fallback;
    let shots: &[ShotInfo] = if input.shots.is_empty() {
        fallback = [ShotInfo {
            start_s: input.samples[0].t_s,
            end_s: input.samples[input.samples.len() - 1].t_s,
            label: "(no shots given: the whole reference)".to_string(),
            kind: ShotKind::Path,
        }];
        &fallback
    } else {
        input.shots
    };
    for (r, shot) in shots.iter().enumerate() {
        let y0 = TITLE_H + r as f64 * row_h;
        let color = if input.shots.is_empty() {
            TEXT
        } else {
            shot_color(input.shots, r)
        };
        let name = names.get(r).cloned().unwrap_or_else(|| "1".to_string());
        svg.rect(MARGIN, y0 + 6.0, 8.0, 40.0, &Style::fill(color));
        let head = if shot.kind == ShotKind::Reposition {
            format!(
                "{name} · repositioning flight · {:.2}–{:.2} s",
                shot.start_s, shot.end_s
            )
        } else {
            format!(
                "Shot {name} · {} · {:.2}–{:.2} s ({:.2} s)",
                shot.kind.as_str(),
                shot.start_s,
                shot.end_s,
                shot.end_s - shot.start_s
            )
        };
        svg.text_bold(MARGIN + 16.0, y0 + 22.0, 15.0, Anchor::Start, TEXT, &head);
        let psl = truncate(&shot.label, 14.0, width - 2.0 * MARGIN - 16.0);
        svg.text(
            MARGIN + 16.0,
            y0 + 42.0,
            14.0,
            Anchor::Start,
            "#0b4f8a",
            &psl,
        );
        let idx = frame_sample_indices(input.samples, shot);
        for (j, (&i, which)) in idx.iter().zip(["start", "middle", "end"]).enumerate() {
            let slot = Slot {
                x: MARGIN + j as f64 * (FRAME_W + GAP),
                y: y0 + HEADER_H,
                w: FRAME_W,
                h: frame_h,
            };
            draw_frame(&mut svg, &slot, input, i);
            let cy = slot.y + slot.h + 17.0;
            svg.text_bold(
                slot.x,
                cy,
                12.0,
                Anchor::Start,
                TEXT,
                &format!("{which} · t {:.2} s", input.samples[i].t_s),
            );
            let cap = truncate(&camera_caption(input, i), 11.0, FRAME_W);
            svg.text(slot.x, cy + 16.0, 11.0, Anchor::Start, MUTED, &cap);
        }
    }
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t_s: f64) -> Sample {
        Sample {
            t_s,
            ..Sample::default()
        }
    }

    #[test]
    fn frames_are_picked_inside_the_shot_at_any_rate() {
        // 4 Hz samples over 0..10 s; a shot from 2.1 to 6.9 s.
        let samples: Vec<Sample> = (0..=40).map(|i| sample(i as f64 * 0.25)).collect();
        let shot = ShotInfo {
            start_s: 2.1,
            end_s: 6.9,
            label: String::new(),
            kind: ShotKind::Hold,
        };
        let [a, m, b] = frame_sample_indices(&samples, &shot);
        assert_eq!(samples[a].t_s, 2.25);
        assert_eq!(samples[m].t_s, 4.5);
        assert_eq!(samples[b].t_s, 6.75);
        // A shot between two samples falls back to the nearest ones.
        let short = ShotInfo {
            start_s: 3.3,
            end_s: 3.4,
            ..shot
        };
        let [a, _, b] = frame_sample_indices(&samples, &short);
        assert_eq!((samples[a].t_s, samples[b].t_s), (3.25, 3.5));
    }

    #[test]
    fn darker_scales_each_channel() {
        assert_eq!(darker("#64c8ff"), "#468cb3");
        assert_eq!(darker("red"), "red");
    }
}
