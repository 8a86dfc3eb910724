//! The storyboard contact sheet: one row per shot entry, the camera's view at its start,
//! middle and end, labelled with the shot's number, kind, times and PSL text.
//!
//! Each frame has the lens aspect and shows the horizon, the stage floor (outline and a 1 m
//! grid) and the stage's corner posts, the actors as figures ([`super::figure`]) drawn far to
//! near, each named, and faint thirds lines. A name goes at the free place nearest the top of
//! its actor's head, clear of every figure and every other name ([`super::labels`]); an actor
//! out of frame is named at the frame edge with an arrow toward it. Each frame's caption
//! names the shot type ([`super::shot_type`]), the camera's height, heading, pitch and
//! distances, and the actors behind the camera or with no room in the frame for their name.
//!
//! The SVG names what a reader checks: each frame's border `frame-R-F`, each figure
//! `figure-R-F-K` and each name `label-R-F-K` (row R, frame F of the row, actor K).

use std::collections::HashMap;

use dronecine_math as math;
use dronecine_math::wrap_angle_rad;

use super::figure::{figure, project_segment, Figure, Hair};
use super::labels::{bounds, grown, Placer, Rect};
use super::raster::Rasteriser;
use super::svg::{num, text_width, truncate, Anchor, Style, Svg};
use super::{actor_color, shot_color, shot_names, PreviewInput, ShotInfo, ShotKind};
use dronecine_compiler::camera::{CameraPose, Vec3};
use dronecine_compiler::reference::Sample;

const TEXT: &str = "#222222";
const MUTED: &str = "#666666";
const SKY: &str = "#e3eaf1";
const FLOOR: &str = "#ebe5d8";
const FLOOR_LINE: &str = "#b9ae98";
const SKIN: &str = "#f2d6b8";
const HAIR: &str = "#4a3426";
/// The actors' names, px.
const LABEL_SIZE: f64 = 13.0;

const MARGIN: f64 = 24.0;
const FRAME_W: f64 = 384.0;
const GAP: f64 = 18.0;
const HEADER_H: f64 = 50.0;
const CAPTION_H: f64 = 60.0;
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

/// Draws `fig` as the group `id` and returns the boxes of its shapes (px, strokes included).
fn draw_figure(svg: &mut Svg, slot: &Slot, fig: &Figure, color: &str, id: &str) -> Vec<Rect> {
    let outline = darker(color);
    let px = |pts: &[[f64; 2]]| pts.iter().map(|p| slot.px(*p)).collect::<Vec<_>>();
    let mut boxes = Vec::new();
    let shape = |boxes: &mut Vec<Rect>, pts: &[[f64; 2]], stroke: f64| {
        boxes.extend(bounds(pts).map(|b| grown(&b, stroke / 2.0)));
    };
    svg.begin_named_group(id, None);
    for (part, fill, width) in [
        (&fig.legs, outline.as_str(), 1.2),
        (&fig.neck, SKIN, 1.0),
        (&fig.torso, color, 1.2),
    ] {
        if let Some(p) = part {
            let p = px(p);
            svg.polygon(&p, &Style::stroke(&outline, width).with_fill(fill));
            shape(&mut boxes, &p, width);
        }
    }
    let head = slot.px(fig.head_centre);
    let r = slot.len(fig.head_radius);
    let nose = fig.nose.map(|[a, b]| [slot.px(a), slot.px(b)]);
    let nose_w = (r * 0.35).max(1.0);
    // Behind the head (only a tip sticking out shows) or over it.
    let draw_nose = |svg: &mut Svg, boxes: &mut Vec<Rect>, in_front: bool| {
        if let Some(n) = nose.filter(|_| fig.nose_in_front == in_front) {
            let style = Style::stroke(TEXT, nose_w);
            svg.line(n[0][0], n[0][1], n[1][0], n[1][1], &style);
            shape(boxes, &n, nose_w);
        }
    };
    draw_nose(svg, &mut boxes, false);
    draw_head(svg, slot, head, r, &fig.hair, &mut boxes);
    for e in &fig.eyes {
        let p = slot.px(*e);
        let er = slot.len(fig.eye_radius).max(0.8);
        svg.circle(p[0], p[1], er, &Style::fill(TEXT));
    }
    draw_nose(svg, &mut boxes, true);
    let ring = (r * 0.12).clamp(0.8, 2.0);
    svg.circle(head[0], head[1], r, &Style::stroke(&outline, ring));
    shape(
        &mut boxes,
        &[[head[0] - r, head[1] - r], [head[0] + r, head[1] + r]],
        ring,
    );
    svg.end_group();
    boxes
}

/// The head's disk: skin, and the hair over it, cut to the disk.
fn draw_head(svg: &mut Svg, slot: &Slot, c: [f64; 2], r: f64, hair: &Hair, boxes: &mut Vec<Rect>) {
    let px = |pts: &[[f64; 2]]| pts.iter().map(|p| slot.px(*p)).collect::<Vec<_>>();
    svg.circle(c[0], c[1], r, &Style::fill(SKIN));
    let clip = svg.clip_circle(c[0], c[1], r);
    svg.begin_group(Some(&clip));
    match hair {
        Hair::None => {}
        Hair::Inside(p) => {
            let p = px(p);
            svg.polygon(&p, &Style::fill(HAIR));
            boxes.extend(bounds(&p));
        }
        Hair::AllBut(p) => {
            svg.circle(c[0], c[1], r, &Style::fill(HAIR));
            svg.polygon(&px(p), &Style::fill(SKIN));
        }
        Hair::All => svg.circle(c[0], c[1], r, &Style::fill(HAIR)),
    }
    svg.end_group();
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

/// Names the actors of the frames: where each name goes, its box measured in the font the
/// PNG sets it in.
struct Labeller<'a> {
    placer: Placer,
    raster: &'a Rasteriser,
    measured: HashMap<String, Rect>,
}

impl Labeller<'_> {
    /// The box of `label` about its anchor (the middle of its baseline).
    fn label_box(&mut self, label: &str) -> Rect {
        if let Some(b) = self.measured.get(label) {
            return *b;
        }
        // Without a glyph to measure, a generous estimate (the halo and the widest glyphs).
        let b = self
            .raster
            .text_box(label, LABEL_SIZE, true, true)
            .unwrap_or_else(|| {
                let half = text_width(label, LABEL_SIZE) * 0.65 + 2.0;
                [-half, -LABEL_SIZE, half, 0.4 * LABEL_SIZE]
            });
        self.measured.insert(label.to_string(), b);
        b
    }

    /// `text` cut (with an ellipsis) to the longest start that, set at `size` px, is at
    /// most `width` px wide.
    fn fit(&self, text: &str, size: f64, bold: bool, width: f64) -> String {
        let wide = |t: &str| {
            (self.raster.text_box(t, size, bold, false))
                .map_or(text_width(t, size), |b| b[2] - b[0])
        };
        if wide(text) <= width {
            return text.to_string();
        }
        let chars: Vec<char> = text.chars().collect();
        let cut = |n: usize| chars[..n].iter().collect::<String>() + "…";
        let (mut lo, mut hi) = (0, chars.len());
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            match wide(&cut(mid)) <= width {
                true => lo = mid,
                false => hi = mid - 1,
            }
        }
        cut(lo)
    }
}

/// The name of an actor and where it is wanted: above the head, or, for an actor out of the
/// frame, at its edge with an arrow toward them.
fn wanted(slot: &Slot, name: &str, fig: &Figure) -> (String, [f64; 2]) {
    let p = slot.px(fig.crown.unwrap_or(fig.head_centre));
    let c = fig.head_centre;
    let label = if c[0] < -1.0 {
        format!("◀ {name}")
    } else if c[0] > 1.0 {
        format!("{name} ▶")
    } else if c[1] > 1.0 {
        format!("▲ {name}")
    } else if c[1] < -1.0 {
        format!("▼ {name}")
    } else {
        name.to_string()
    };
    (label, [p[0], p[1] - 6.0])
}

/// One frame: the view from sample `i`, its groups named `R-F` by `id`. Returns the actors
/// in the frame with no room for their name.
fn draw_frame(
    svg: &mut Svg,
    slot: &Slot,
    input: &PreviewInput,
    i: usize,
    id: &str,
    labeller: &mut Labeller,
) -> Vec<String> {
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
    let mut taken: Vec<Rect> = Vec::new();
    for (k, fig) in &figures {
        let boxes = draw_figure(svg, slot, fig, actor_color(*k), &format!("figure-{id}-{k}"));
        taken.extend(boxes);
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
    // Names, in the actors' order, each clear of the figures and of the names before it.
    let frame = [slot.x, slot.y, slot.x + slot.w, slot.y + slot.h];
    let mut unnamed = Vec::new();
    let mut by_actor: Vec<&(usize, Figure)> = figures.iter().collect();
    by_actor.sort_by_key(|(k, _)| *k);
    for (k, fig) in by_actor {
        let name = &input.actor_names[*k];
        let (label, want) = wanted(slot, name, fig);
        let b = labeller.label_box(&label);
        match labeller.placer.place(&frame, want, &b, &taken) {
            Some(at) => {
                svg.begin_named_group(&format!("label-{id}-{k}"), None);
                svg.text_halo(
                    at[0],
                    at[1],
                    LABEL_SIZE,
                    Anchor::Middle,
                    actor_color(*k),
                    &label,
                );
                svg.end_group();
                taken.push([b[0] + at[0], b[1] + at[1], b[2] + at[0], b[3] + at[1]]);
            }
            None => unnamed.push(name.clone()),
        }
    }
    svg.end_group();
    svg.begin_named_group(&format!("frame-{id}"), None);
    svg.rect(
        slot.x,
        slot.y,
        slot.w,
        slot.h,
        &Style::stroke("#333333", 1.5),
    );
    svg.end_group();
    unnamed
}

/// The actors behind the camera at sample `i`.
fn behind_camera<'a>(input: &'a PreviewInput, i: usize) -> Vec<&'a str> {
    let pose = camera_pose(&input.samples[i]);
    (0..input.actor_names.len())
        .filter(|&k| {
            input
                .actor(i, k)
                .is_some_and(|a| figure(&pose, &input.lens, a).is_none())
        })
        .map(|k| input.actor_names[k].as_str())
        .collect()
}

/// What a frame of `shot` shows, by shot type: `which` is 0, 1, 2 for its start, middle, end.
fn framing_caption(shot: &ShotInfo, which: usize) -> String {
    let [from, to] = &shot.framing;
    match (shot.kind, which) {
        (ShotKind::Reposition, _) => format!("flying to {to}"),
        (_, 0) => from.clone(),
        (_, 2) => to.clone(),
        _ if from == to => from.clone(),
        _ => format!("{from} → {to}"),
    }
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

/// The contact sheet; `raster` measures the names as the PNG sets them.
pub fn storyboard(input: &PreviewInput, raster: &Rasteriser) -> Svg {
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
            framing: [
                "the whole reference".to_string(),
                "the whole reference".to_string(),
            ],
        }];
        &fallback
    } else {
        input.shots
    };
    let mut labeller = Labeller {
        placer: Placer::new(FRAME_W, frame_h),
        raster,
        measured: HashMap::new(),
    };
    for (r, shot) in shots.iter().enumerate() {
        let y0 = TITLE_H + r as f64 * row_h;
        let color = if input.shots.is_empty() {
            TEXT
        } else {
            shot_color(input.shots, r)
        };
        let name = names.get(r).cloned().unwrap_or_else(|| "1".to_string());
        draw_row_header(&mut svg, shot, &name, color, y0, width);
        let idx = frame_sample_indices(input.samples, shot);
        for (j, (&i, which)) in idx.iter().zip(["start", "middle", "end"]).enumerate() {
            let slot = Slot {
                x: MARGIN + j as f64 * (FRAME_W + GAP),
                y: y0 + HEADER_H,
                w: FRAME_W,
                h: frame_h,
            };
            let unnamed = draw_frame(
                &mut svg,
                &slot,
                input,
                i,
                &format!("{r}-{j}"),
                &mut labeller,
            );
            let t = input.samples[i].t_s;
            let first = format!("{which} · t {t:.2} s · {}", framing_caption(shot, j));
            let mut third = Vec::new();
            let behind = behind_camera(input, i);
            if !behind.is_empty() {
                third.push(format!("behind the camera: {}", behind.join(", ")));
            }
            if !unnamed.is_empty() {
                third.push(format!(
                    "no room in the frame to name {}",
                    unnamed.join(", ")
                ));
            }
            let cy = slot.y + slot.h + 17.0;
            for (k, (text, size, bold)) in [
                (first, 12.0, true),
                (camera_caption(input, i), 11.0, false),
                (third.join(" · "), 11.0, false),
            ]
            .into_iter()
            .enumerate()
            {
                let (dy, color) = ([0.0, 16.0, 31.0][k], if bold { TEXT } else { MUTED });
                let text = labeller.fit(&text, size, bold, FRAME_W);
                svg.text_styled(
                    slot.x,
                    cy + dy,
                    size,
                    Anchor::Start,
                    color,
                    bold,
                    0.0,
                    None,
                    &text,
                );
            }
        }
    }
    svg
}

/// A row's heading: its colour mark, the shot's number, kind and times, and its PSL text.
fn draw_row_header(svg: &mut Svg, shot: &ShotInfo, name: &str, color: &str, y0: f64, width: f64) {
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
            framing: Default::default(),
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
