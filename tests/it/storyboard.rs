//! The storyboard `compile --preview` draws, read back from its SVG with the text laid out as
//! the PNG sets it: in every frame of every shipped shot, and of scenes that crowd actors
//! together, each actor's name lies inside its frame and clear of every figure and every other
//! name; each frame's caption names the shot type.

use std::collections::BTreeMap;
use std::path::Path;

use dronecine_preview::usvg::{self, Node};

use crate::common::{dronecine, stderr, temp_dir};

/// A box, px: `[left, top, right, bottom]`.
type Rect = [f32; 4];

fn rect(r: usvg::Rect) -> Rect {
    [r.left(), r.top(), r.right(), r.bottom()]
}

fn overlap(a: &Rect, b: &Rect) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// What a storyboard's frame holds: its border, the boxes of its figures' shapes (by actor)
/// and of its names (by actor).
#[derive(Default)]
struct Frame {
    border: Option<Rect>,
    markers: Vec<(String, Rect)>,
    labels: Vec<(String, Rect)>,
}

/// Every shape's box under `g` (strokes included).
fn shapes(g: &usvg::Group, out: &mut Vec<Rect>) {
    for n in g.children() {
        match n {
            Node::Group(c) => shapes(c, out),
            Node::Path(p) => out.push(rect(p.abs_stroke_bounding_box())),
            Node::Text(t) => out.push(rect(t.abs_stroke_bounding_box())),
            Node::Image(i) => out.push(rect(i.abs_bounding_box())),
        }
    }
}

/// The frames of a storyboard, by `R-F`, from the groups it names.
fn frames(g: &usvg::Group, out: &mut BTreeMap<String, Frame>) {
    for n in g.children() {
        let Node::Group(c) = n else { continue };
        let id = c.id();
        let mut parts = id.splitn(2, '-');
        let (kind, rest) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
        let (frame, actor) = match rest.rsplit_once('-') {
            Some((f, a)) if kind != "frame" => (f.to_string(), a.to_string()),
            _ => (rest.to_string(), String::new()),
        };
        let mut boxes = Vec::new();
        shapes(c, &mut boxes);
        match kind {
            "frame" => {
                out.entry(frame).or_default().border = Some(rect(c.abs_stroke_bounding_box()))
            }
            "figure" => (out.entry(frame).or_default().markers)
                .extend(boxes.into_iter().map(|b| (actor.clone(), b))),
            "label" => (out.entry(frame).or_default().labels)
                .extend(boxes.into_iter().map(|b| (actor.clone(), b))),
            _ => frames(c, out),
        }
    }
}

/// The names in `svg` that leave their frame or overlap a figure or another name; and how
/// many frames and names there are.
fn collisions(svg: &str) -> (Vec<String>, usize, usize) {
    let tree = dronecine_preview::Rasteriser::new()
        .parse(svg)
        .expect("the SVG parses");
    let mut all = BTreeMap::new();
    frames(tree.root(), &mut all);
    let mut bad = Vec::new();
    let names: usize = all.values().map(|f| f.labels.len()).sum();
    for (id, f) in &all {
        let border = f
            .border
            .unwrap_or_else(|| panic!("frame {id} has no border"));
        for (i, (who, l)) in f.labels.iter().enumerate() {
            let inside =
                l[0] >= border[0] && l[1] >= border[1] && l[2] <= border[2] && l[3] <= border[3];
            if !inside {
                bad.push(format!(
                    "frame {id}: {who}'s name {l:?} leaves the frame {border:?}"
                ));
            }
            for (whose, m) in f.markers.iter().filter(|(_, m)| overlap(l, m)) {
                bad.push(format!(
                    "frame {id}: {who}'s name {l:?} covers {whose}'s figure {m:?}"
                ));
            }
            for (other, o) in f.labels[i + 1..].iter().filter(|(_, o)| overlap(l, o)) {
                bad.push(format!(
                    "frame {id}: {who}'s name {l:?} covers {other}'s {o:?}"
                ));
            }
        }
    }
    (bad, all.len(), names)
}

/// `dronecine compile SCRIPT --preview` into a scratch folder: the storyboard's SVG.
fn storyboard(script: &Path, name: &str) -> String {
    let dir = temp_dir(name);
    let out = dir.join("x.mcap");
    let previews = dir.join("previews");
    let o = dronecine(&[
        "compile",
        script.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--preview",
        previews.to_str().unwrap(),
        "--allow-infeasible",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read_to_string(previews.join("storyboard.svg")).unwrap()
}

/// The storyboards of the shipped shots, by name, compiled once for the tests that read them.
fn shipped() -> &'static [(String, String)] {
    static SHIPPED: std::sync::OnceLock<Vec<(String, String)>> = std::sync::OnceLock::new();
    SHIPPED.get_or_init(|| {
        (crate::common::scripts("shots").into_iter())
            .map(|p| (p.file_stem().unwrap().to_string_lossy().into_owned(), p))
            // A film annotation is not flown: nothing to draw.
            .filter(|(name, _)| name != "annotation")
            .map(|(name, p)| {
                let svg = storyboard(&p, &name);
                (name, svg)
            })
            .collect()
    })
}

#[test]
fn names_never_cover_a_figure_in_the_shipped_shots() {
    let mut checked = (0, 0);
    for (name, svg) in shipped() {
        let (bad, frames, names) = collisions(svg);
        assert!(bad.is_empty(), "{name}:\n{}", bad.join("\n"));
        checked = (checked.0 + frames, checked.1 + names);
    }
    assert!(
        checked.0 >= 60 && checked.1 >= 60,
        "{checked:?} frames and names"
    );
}

/// Actors crowded together, seen from everywhere: two a head apart in a two-shot and an
/// over-the-shoulder, a third just behind them, the camera swinging round them close.
#[test]
fn names_never_cover_a_figure_of_actors_crowded_together() {
    let dir = temp_dir("crowded");
    let scripts = [
        "stage 8m x 6m x 3m\nactor A height 1.80m at (0, 0) facing 0deg\n\
         actor B height 1.65m at (0.35, 0.1) facing 180deg\n\
         actor C height 1.90m at (0.2, 0.45) facing -90deg\n\
         MS on A and B for 2s\nthen dolly to MS on A and B screen left over 4s\n\
         cut to MCU on A 34left for 2s\ncut to MS on B back MS on A front screen right for 2s\n\
         cut to FS on C 34backright for 2s\n\
         cut to path orbit around A radius 1.2m altitude 1.6m turns 1 for 12s looking at A\n",
        "stage 6m x 6m x 3m\nactor Alexandra height 1.70m at (-0.2, 0) facing 90deg\n\
         actor Bartholomew height 1.75m at (0.2, 0) facing 90deg\n\
         actor C height 1.60m at (0, 0.4) facing -90deg\n\
         LS on Alexandra and Bartholomew for 2s\ncut to MCU on Bartholomew front for 2s\n\
         then pan to MCU on Bartholomew back over 4s\n\
         cut to high angle MLS on C and Alexandra for 2s\n",
    ];
    for (i, text) in scripts.iter().enumerate() {
        let script = dir.join(format!("crowded{i}.psl"));
        std::fs::write(&script, text).unwrap();
        let (bad, frames, names) = collisions(&storyboard(&script, &format!("crowded{i}")));
        assert!(bad.is_empty(), "crowded{i}:\n{}", bad.join("\n"));
        assert!(
            frames >= 15 && names >= 15,
            "{frames} frames, {names} names"
        );
    }
}

/// Each frame's caption starts with where it is in the shot and what the shot is.
#[test]
fn each_caption_names_the_shot_type() {
    let svg = &shipped()
        .iter()
        .find(|(n, _)| n == "scene")
        .expect("scene.psl")
        .1;
    for caption in [
        ">start · t 0.00 s · single on Bob<",
        " s · flying to single on Alice<",
        " s · OTS over Bob (on Alice)<",
        " s · OTS over Alice (on Bob)<",
        " s · two-shot of Alice and Bob<",
        " s · orbit around Alice<",
        " s · path looking at Bob<",
    ] {
        assert!(svg.contains(caption), "no caption `{caption}`");
    }
    // Every frame has one: three per row.
    let rows = svg.matches("<g id=\"frame-").count();
    let captions = svg.matches(" s · ").count();
    assert!(
        captions >= rows && rows >= 60,
        "{captions} captions, {rows} frames"
    );
}

/// The scan sees a name over a figure, over another name, and out of its frame.
#[test]
fn the_scan_finds_a_covered_figure() {
    let svg = |label_x: f64, other_x: f64| {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400\" height=\"200\" \
             font-family=\"DejaVu Sans\"><g id=\"figure-0-0-1\"><circle cx=\"100\" cy=\"100\" \
             r=\"20\" fill=\"#000\"/></g><g id=\"label-0-0-1\"><text x=\"{label_x}\" y=\"105\" \
             font-size=\"13\">Ann</text></g><g id=\"label-0-0-2\"><text x=\"{other_x}\" \
             y=\"105\" font-size=\"13\">Ben</text></g><g id=\"frame-0-0\"><rect x=\"0\" \
             y=\"0\" width=\"300\" height=\"200\" fill=\"none\" stroke=\"#000\"/></g></svg>"
        )
    };
    assert_eq!(collisions(&svg(200.0, 250.0)), (vec![], 1, 2));
    let (bad, _, _) = collisions(&svg(95.0, 250.0));
    assert!(
        bad.len() == 1 && bad[0].contains("covers 1's figure"),
        "{bad:?}"
    );
    let (bad, _, _) = collisions(&svg(200.0, 205.0));
    assert!(bad.len() == 1 && bad[0].contains("covers 2's"), "{bad:?}");
    let (bad, _, _) = collisions(&svg(200.0, 295.0));
    assert!(
        bad.len() == 1 && bad[0].contains("leaves the frame"),
        "{bad:?}"
    );
}
