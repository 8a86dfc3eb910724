//! The canonical form of a script (`dronecine fmt`).
//!
//! One statement per line, single spaces, `on` after every size, `cut to` before every shot
//! that starts a new shot after the first, actor attributes and path parameters in their
//! documented order, `looking at` last. Numbers, names and comments are kept exactly as
//! written; runs of blank lines shrink to one. Formatting never changes what a script means
//! (`tests/it/fmt.rs` checks that the resolved script is the same) and is idempotent.

use std::fmt::Write as _;

use crate::ast::*;
use crate::script::{self, Script, ShotContent};
use crate::vocab::ScreenThird;

/// Format a parsed file. The caller ensures it parsed without syntax errors.
pub fn format_file(file: &File<'_>) -> String {
    // Each output line: its statement text and its comment, blank lines already collapsed.
    let mut rows: Vec<Option<(String, Option<&str>)>> = Vec::new();
    let mut seen_shot = false;
    for line in &file.lines {
        if line.statement.is_none() && line.comment.is_none() {
            if matches!(rows.last(), Some(Some(_))) {
                rows.push(None);
            }
            continue;
        }
        let mut text = String::new();
        if let Some(st) = &line.statement {
            statement(&mut text, st, &mut seen_shot);
        }
        rows.push(Some((text, line.comment.map(|c| c.text.trim_end()))));
    }
    while matches!(rows.last(), Some(None)) {
        rows.pop();
    }

    // Trailing comments on consecutive lines line up, two spaces after the longest statement
    // of the run (statements longer than ALIGN_MAX are left out of the alignment).
    const ALIGN_MAX: usize = 72;
    let trailing =
        |r: &Option<(String, Option<&str>)>| matches!(r, Some((t, Some(_))) if !t.is_empty());
    let mut out = String::new();
    let mut i = 0;
    while i < rows.len() {
        let mut j = i;
        while j < rows.len() && trailing(&rows[j]) {
            j += 1;
        }
        let run = if j > i { &rows[i..j] } else { &rows[i..=i] };
        let column = run
            .iter()
            .filter_map(|r| r.as_ref().map(|(t, _)| t.chars().count()))
            .filter(|w| *w <= ALIGN_MAX)
            .max()
            .unwrap_or(0);
        for row in run {
            match row {
                None => {}
                Some((text, comment)) => {
                    out.push_str(text);
                    if let Some(c) = comment {
                        if !text.is_empty() {
                            let pad = column.saturating_sub(text.chars().count()) + 2;
                            out.extend(std::iter::repeat_n(' ', pad));
                        }
                        out.push_str(c);
                    }
                }
            }
            out.push('\n');
        }
        i += run.len();
    }
    out
}

fn statement(out: &mut String, st: &Statement<'_>, seen_shot: &mut bool) {
    match st {
        Statement::Stage(s) => {
            let _ = write!(out, "stage {} x {} x {}", q(&s.x), q(&s.y), q(&s.z));
        }
        Statement::Lens(l) => {
            let _ = write!(out, "lens {}", q(&l.fov));
            if let Some(a) = &l.aspect {
                let _ = write!(out, " {}", a.text);
            }
        }
        Statement::Drone(d) => match &d.target {
            DroneTarget::Builtin(n) => {
                let _ = write!(out, "drone {}", n.text);
            }
            DroneTarget::File(f) => {
                let _ = write!(out, "drone \"{}\"", f.text);
            }
        },
        Statement::Actor(a) => {
            let _ = write!(out, "actor {}", a.name.text);
            let mut attrs: Vec<&ActorAttr<'_>> = a.attrs.iter().collect();
            attrs.sort_by_key(|x| match x {
                ActorAttr::Height(..) => 0,
                ActorAttr::At(..) => 1,
                ActorAttr::Facing(..) => 2,
            });
            for attr in attrs {
                match attr {
                    ActorAttr::Height(_, h) => {
                        let _ = write!(out, " height {}", q(h));
                    }
                    ActorAttr::At(_, p) => {
                        let _ = write!(out, " at {}", point(p));
                    }
                    ActorAttr::Facing(_, f) => {
                        let _ = write!(out, " facing {}", q(f));
                    }
                }
            }
        }
        Statement::Blocking(b) => {
            let _ = write!(out, "at {} {} ", q(&b.at), b.actor.text);
            match &b.action {
                Action::Walk(_, p) => {
                    let _ = write!(out, "walks to {}", point(p));
                }
                Action::Turn(_, a) => {
                    let _ = write!(out, "turns to {}", q(a));
                }
            }
            duration(out, b.duration.as_ref());
        }
        Statement::Shot(s) => {
            if let Some(p) = &s.pin {
                let _ = write!(out, "at {} ", q(p));
            }
            body(out, &s.body, *seen_shot);
            *seen_shot = true;
        }
        Statement::Timed(t) => {
            let _ = write!(out, "{} {} --> {} ", t.index.text, t.start.text, t.end.text);
            body(out, &t.body, false);
        }
    }
}

fn body(out: &mut String, b: &ShotBody<'_>, after_first: bool) {
    match b {
        ShotBody::Framed(f) => {
            match &f.transition {
                Some(t) => transition(out, t),
                None if after_first => out.push_str("cut to "),
                None => {}
            }
            composition(out, &f.composition);
            duration(out, f.duration.as_ref());
        }
        ShotBody::Hold(h) => {
            out.push_str("then ");
            if let Some(e) = &h.event {
                event(out, e);
            }
            out.push_str("hold");
            duration(out, h.duration.as_ref());
        }
        ShotBody::Coverage(c) => {
            match &c.transition {
                Some(t) => transition(out, t),
                None if after_first => out.push_str("cut to "),
                None => {}
            }
            out.push_str("coverage ");
            if let Some((_, size)) = c.size {
                let _ = write!(out, "{} on ", size.as_str());
            }
            let _ = write!(out, "{} and {}", c.a.text, c.b.text);
            duration(out, c.duration.as_ref());
        }
        ShotBody::Path(p) => {
            if let Some(t) = &p.transition {
                transition(out, t);
            }
            out.push_str("path ");
            match &p.kind.1 {
                PathKind::Waypoints(f) => {
                    let _ = write!(out, "waypoints \"{}\"", f.text);
                }
                k => out.push_str(k.name()),
            }
            let mut params: Vec<&PathParam<'_>> = p.params.iter().collect();
            params.sort_by_key(|x| rank(&x.value));
            let mut looking = Vec::new();
            for param in params {
                match &param.value {
                    PathValue::LookingAt(n) => looking.push(n.text),
                    v => {
                        out.push(' ');
                        path_value(out, v);
                    }
                }
            }
            duration(out, p.duration.as_ref());
            for n in looking {
                let _ = write!(out, " looking at {n}");
            }
        }
    }
}

fn rank(v: &PathValue<'_>) -> u8 {
    match v {
        PathValue::Around(_) => 0,
        PathValue::Side(_) => 1,
        PathValue::Radius(_) => 2,
        PathValue::Center(_) => 3,
        PathValue::Altitude(_) => 4,
        PathValue::FromTo(..) => 5,
        PathValue::Turns(_) => 6,
        PathValue::Clockwise(_) => 7,
        PathValue::LookingAt(_) => 8,
    }
}

fn path_value(out: &mut String, v: &PathValue<'_>) {
    let _ = match v {
        PathValue::Side(x) => write!(out, "side {}", q(x)),
        PathValue::Center(p) => write!(out, "center {}", point(p)),
        PathValue::Altitude(x) => write!(out, "altitude {}", q(x)),
        PathValue::Radius(x) => write!(out, "radius {}", q(x)),
        PathValue::FromTo(a, b) => write!(out, "from {} to {}", q(a), q(b)),
        PathValue::Turns(x) => write!(out, "turns {}", q(x)),
        PathValue::Around(n) => write!(out, "around {}", n.text),
        PathValue::Clockwise(true) => write!(out, "clockwise"),
        PathValue::Clockwise(false) => write!(out, "counterclockwise"),
        PathValue::LookingAt(n) => write!(out, "looking at {}", n.text),
    };
}

fn transition(out: &mut String, t: &Transition<'_>) {
    match &t.kind {
        TransitionKind::Cut => out.push_str("cut to "),
        TransitionKind::Dissolve => out.push_str("dissolve to "),
        TransitionKind::Move {
            event: ev,
            kind,
            follow,
        } => {
            out.push_str("then ");
            if let Some(e) = ev {
                event(out, e);
            }
            out.push_str(kind.as_str());
            if let Some(f) = follow {
                let _ = write!(out, " {}", f.text);
            }
            out.push_str(" to ");
        }
    }
}

fn event(out: &mut String, e: &Event<'_>) {
    if e.quoted {
        let _ = write!(out, "as \"{}\" ", e.text);
    } else {
        let words: Vec<&str> = e.text.split_whitespace().collect();
        let _ = write!(out, "as {} ", words.join(" "));
    }
}

fn composition(out: &mut String, c: &Composition<'_>) {
    if let Some((_, a)) = c.angle {
        out.push_str(a.as_str());
        out.push(' ');
    }
    for (i, f) in c.framings.iter().enumerate() {
        if i > 0 {
            out.push(' ');
        }
        let _ = write!(out, "{} on ", f.size.1.as_str());
        for (j, s) in f.subjects.iter().enumerate() {
            if j > 0 {
                out.push_str(" and ");
            }
            out.push_str(s.actor.text);
            if let Some((_, p)) = s.profile {
                let _ = write!(out, " {}", p.as_str());
            }
            if let Some(sc) = &s.screen {
                let _ = match &sc.position {
                    ScreenPosition::Third(t) => write!(out, " screen {}", ScreenThird::as_str(*t)),
                    ScreenPosition::Point(x, y) => write!(out, " screen ({}, {})", q(x), q(y)),
                };
            }
        }
    }
}

fn duration(out: &mut String, d: Option<&Duration<'_>>) {
    if let Some(d) = d {
        let _ = write!(out, " {} {}", d.keyword.as_str(), q(&d.value));
    }
}

fn q(x: &Quantity<'_>) -> String {
    match x.unit {
        Some(u) => format!("{}{}", x.number, u.text),
        None => x.number.to_string(),
    }
}

fn point(p: &Point<'_>) -> String {
    format!("({}, {})", q(&p.x), q(&p.y))
}

/// The text of script `src` with each coverage line replaced by the shots of `expanded`
/// (the script with its coverages expanded, each part carrying its coverage's span), as PSL
/// in canonical form: a comment naming the coverage, then its parts, back to back, each
/// with a comment saying what it frames. Written back, it resolves to the shots of
/// `expanded` (the parts' holds are whole milliseconds). The syntax errors of `src`, if any.
pub fn expanded_text(
    src: &str,
    expanded: &Script,
) -> Result<String, Vec<dronecine_diag::Diagnostic>> {
    let (file, diagnostics) = crate::parser::parse(src);
    if diagnostics.iter().any(dronecine_diag::Diagnostic::is_error) {
        return Err(diagnostics);
    }
    let mut text = String::with_capacity(src.len() * 2);
    for line in &file.lines {
        let raw = src.get(line.span.start..line.span.end).unwrap_or("");
        let covered = matches!(
            &line.statement,
            Some(Statement::Shot(Shot {
                body: ShotBody::Coverage(_),
                ..
            }))
        );
        let parts: Vec<&script::Shot> = expanded
            .timeline
            .iter()
            .filter(|s| {
                s.coverage.is_some()
                    && line.span.start <= s.span.start
                    && s.span.end <= line.span.end
            })
            .collect();
        if !covered || parts.is_empty() {
            text.push_str(raw);
            text.push('\n');
            continue;
        }
        let statement = line
            .statement
            .as_ref()
            .map_or("", |s| src.get(s.span().start..s.span().end).unwrap_or(""));
        let _ = write!(text, "# {statement}: expanded into {} shots", parts.len());
        if let Some(c) = line.comment {
            let _ = write!(text, " {}", c.text.trim_start_matches('#').trim_start());
        }
        text.push('\n');
        for part in parts {
            shot_line(&mut text, part);
        }
    }
    let (file, diagnostics) = crate::parser::parse(&text);
    if diagnostics.iter().any(dronecine_diag::Diagnostic::is_error) {
        return Err(diagnostics);
    }
    Ok(format_file(&file))
}

/// A part of an expanded coverage as a PSL line: its pin, its dissolve (a cut goes without
/// saying), its composition and its hold, with a comment saying what it frames.
fn shot_line(out: &mut String, shot: &script::Shot) {
    let ShotContent::Composition(comp) = &shot.content else {
        return;
    };
    if shot.pinned {
        let _ = write!(out, "at {}s ", seconds(shot.start_s));
    }
    if shot.transition == script::Transition::Dissolve {
        out.push_str("dissolve to ");
    }
    let _ = write!(out, "{comp} for {}s", seconds(shot.end_s - shot.start_s));
    let what = match comp.framings.as_slice() {
        [f] if f.subjects.len() == 2 => "establishing two-shot".to_string(),
        [fg, bg] => match (fg.subjects.first(), bg.subjects.first()) {
            (Some(a), Some(b)) => format!("over {}'s shoulder, on {}", a.actor, b.actor),
            _ => String::new(),
        },
        [f] => f
            .subjects
            .first()
            .map_or(String::new(), |s| format!("single on {}", s.actor)),
        _ => String::new(),
    };
    match &shot.coverage {
        Some(part) => {
            let _ = writeln!(out, "  # {}/{}: {what}", part.part, part.parts);
        }
        None => out.push('\n'),
    }
}

/// Seconds as a script writes them: to the microsecond, without trailing zeros.
fn seconds(s: f64) -> String {
    let text = format!("{s:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_string()
    } else {
        text.to_string()
    }
}
