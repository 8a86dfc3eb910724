//! The parser: runs the pest grammar line by line and builds the typed AST.
//!
//! Invariant: `parse` never panics and always returns a `File` with one `Line` per source
//! line; a line that does not parse is kept with `error: true` and one diagnostic, and the
//! next lines are parsed as usual. The tree-building code below relies on the grammar's
//! shape; `expect_*` helpers turn a mismatch into an internal-error diagnostic rather than a
//! panic.

use pest::iterators::Pair;
use pest::Parser as _;

use dronecine_diag::{Diagnostic, Span};

use crate::ast::*;
use crate::code;
use crate::rules::{PslParser, Rule};
use crate::syntax;
use crate::vocab::{CameraAngle, MoveKind, Profile, ScreenThird, Size};

/// Parse a whole script. Returns the tree and the syntax diagnostics, all lines considered.
pub fn parse(src: &str) -> (File<'_>, Vec<Diagnostic>) {
    let mut lines = Vec::with_capacity(src.bytes().filter(|&b| b == b'\n').count() + 1);
    let mut diagnostics = Vec::new();
    let mut offset = 0;
    for (i, raw) in src.split('\n').enumerate() {
        let mut start = offset;
        let mut text = raw.strip_suffix('\r').unwrap_or(raw);
        if i == 0 {
            if let Some(rest) = text.strip_prefix('\u{feff}') {
                start += '\u{feff}'.len_utf8();
                text = rest;
            }
        }
        lines.push(parse_line(text, start, i + 1, &mut diagnostics));
        offset += raw.len() + 1;
    }
    // A trailing newline does not open a new line.
    if src.ends_with('\n') {
        lines.pop();
    }
    (File { source: src, lines }, diagnostics)
}

fn parse_line<'a>(
    text: &'a str,
    offset: usize,
    number: usize,
    diagnostics: &mut Vec<Diagnostic>,
) -> Line<'a> {
    let span = Span::new(offset, offset + text.len());
    let mut line = Line {
        number,
        span,
        statement: None,
        comment: None,
        error: false,
    };
    let trimmed = text.trim_start_matches([' ', '\t']);
    if trimmed.is_empty() {
        return line;
    }
    if trimmed.starts_with('#') {
        let start = offset + (text.len() - trimmed.len());
        let t = trimmed.trim_end();
        line.comment = Some(Text {
            text: t,
            span: Span::new(start, start + t.len()),
        });
        return line;
    }
    let pairs = match PslParser::parse(Rule::line, text) {
        Ok(pairs) => pairs,
        Err(err) => {
            diagnostics.push(syntax::diagnostic(&err, text, offset));
            line.error = true;
            return line;
        }
    };
    let b = Builder { offset };
    if let Some(pair) = pairs.into_iter().next() {
        for child in pair.into_inner() {
            match child.as_rule() {
                Rule::comment => {
                    let t = child.as_str().trim_end();
                    let s = b.span(&child);
                    line.comment = Some(Text {
                        text: t,
                        span: Span::new(s.start, s.start + t.len()),
                    });
                }
                Rule::EOI => {}
                _ => match b.statement(child) {
                    Ok(st) => line.statement = Some(st),
                    Err(d) => {
                        diagnostics.push(*d);
                        line.error = true;
                    }
                },
            }
        }
    }
    line
}

/// What the tree builder returns: the node, or the one diagnostic of its line, boxed so that
/// the node's result stays small.
type Result<T> = std::result::Result<T, Box<Diagnostic>>;

/// [`code::internal`], boxed for the tree builder's [`Result`].
fn internal(span: Span, what: String) -> Box<Diagnostic> {
    Box::new(code::internal(span, what))
}

struct Builder {
    offset: usize,
}

impl Builder {
    fn span(&self, p: &Pair<'_, Rule>) -> Span {
        let s = p.as_span();
        Span::new(self.offset + s.start(), self.offset + s.end())
    }

    fn text<'a>(&self, p: &Pair<'a, Rule>) -> Text<'a> {
        Text {
            text: p.as_str(),
            span: self.span(p),
        }
    }

    fn bug(&self, p: &Pair<'_, Rule>, what: &str) -> Box<Diagnostic> {
        internal(
            self.span(p),
            format!("the parser met {:?} where it expected {what}", p.as_rule()),
        )
    }

    fn statement<'a>(&self, p: Pair<'a, Rule>) -> Result<Statement<'a>> {
        Ok(match p.as_rule() {
            Rule::stage => Statement::Stage(self.stage(p)?),
            Rule::lens => Statement::Lens(self.lens(p)?),
            Rule::drone => Statement::Drone(self.drone(p)?),
            Rule::actor_decl => Statement::Actor(self.actor(p)?),
            Rule::blocking => Statement::Blocking(self.blocking(p)?),
            Rule::shot => Statement::Shot(self.shot(p)?),
            Rule::timed_entry => Statement::Timed(self.timed(p)?),
            _ => return Err(self.bug(&p, "a statement")),
        })
    }

    fn quantity<'a>(&self, p: Pair<'a, Rule>) -> Result<Quantity<'a>> {
        let span = self.span(&p);
        let mut number = None;
        let mut unit = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::number => number = Some(c.as_str()),
                Rule::unit => unit = Some(self.text(&c)),
                _ => return Err(self.bug(&c, "a number")),
            }
        }
        let number = number.ok_or_else(|| internal(span, "a quantity without number".into()))?;
        // The grammar admits only digits, one dot and a sign, so this parse cannot fail; a
        // literal too large for f64 becomes infinite and is rejected by the semantic pass.
        let value = number.parse::<f64>().unwrap_or(f64::NAN);
        Ok(Quantity {
            value,
            number,
            unit,
            span,
        })
    }

    fn point<'a>(&self, p: Pair<'a, Rule>) -> Result<Point<'a>> {
        let span = self.span(&p);
        let mut it = p.into_inner();
        let x = self.next_quantity(&mut it, span)?;
        let y = self.next_quantity(&mut it, span)?;
        Ok(Point { x, y, span })
    }

    fn next_quantity<'a>(
        &self,
        it: &mut pest::iterators::Pairs<'a, Rule>,
        span: Span,
    ) -> Result<Quantity<'a>> {
        match it.next() {
            Some(q) => self.quantity(q),
            None => Err(internal(span, "a missing number".into())),
        }
    }

    fn string<'a>(&self, p: Pair<'a, Rule>) -> Text<'a> {
        // string = ${ "\"" ~ string_inner ~ "\"" }
        match p.into_inner().next() {
            Some(inner) => self.text(&inner),
            None => Text {
                text: "",
                span: Span::default(),
            },
        }
    }

    fn stage<'a>(&self, p: Pair<'a, Rule>) -> Result<Stage<'a>> {
        let span = self.span(&p);
        let mut qs = p.into_inner().filter(|c| c.as_rule() == Rule::quantity);
        let mut next = || match qs.next() {
            Some(q) => self.quantity(q),
            None => Err(internal(span, "stage needs three sizes".into())),
        };
        Ok(Stage {
            span,
            x: next()?,
            y: next()?,
            z: next()?,
        })
    }

    fn lens<'a>(&self, p: Pair<'a, Rule>) -> Result<Lens<'a>> {
        let span = self.span(&p);
        let mut fov = None;
        let mut aspect = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::quantity => fov = Some(self.quantity(c)?),
                Rule::aspect => aspect = Some(self.text(&c)),
                _ => {}
            }
        }
        let fov = fov.ok_or_else(|| internal(span, "lens without angle".into()))?;
        Ok(Lens { span, fov, aspect })
    }

    fn drone<'a>(&self, p: Pair<'a, Rule>) -> Result<Drone<'a>> {
        let span = self.span(&p);
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::string => {
                    return Ok(Drone {
                        span,
                        target: DroneTarget::File(self.string(c)),
                    })
                }
                Rule::profile_name => {
                    return Ok(Drone {
                        span,
                        target: DroneTarget::Builtin(self.text(&c)),
                    })
                }
                _ => {}
            }
        }
        Err(internal(span, "drone without profile".into()))
    }

    fn actor<'a>(&self, p: Pair<'a, Rule>) -> Result<ActorDecl<'a>> {
        let span = self.span(&p);
        let mut name = None;
        let mut attrs = Vec::new();
        for c in p.into_inner() {
            let cs = self.span(&c);
            match c.as_rule() {
                Rule::name => name = Some(self.text(&c)),
                Rule::actor_height => attrs.push(ActorAttr::Height(cs, self.last_quantity(c)?)),
                Rule::actor_facing => attrs.push(ActorAttr::Facing(cs, self.last_quantity(c)?)),
                Rule::actor_at => {
                    let pt = c
                        .into_inner()
                        .find(|x| x.as_rule() == Rule::point)
                        .ok_or_else(|| internal(cs, "`at` without point".into()))?;
                    attrs.push(ActorAttr::At(cs, self.point(pt)?));
                }
                _ => {}
            }
        }
        let name = name.ok_or_else(|| internal(span, "actor without name".into()))?;
        Ok(ActorDecl { span, name, attrs })
    }

    /// The last `quantity` or `count` child of a pair.
    fn last_quantity<'a>(&self, p: Pair<'a, Rule>) -> Result<Quantity<'a>> {
        let span = self.span(&p);
        match p
            .into_inner()
            .filter(|c| matches!(c.as_rule(), Rule::quantity | Rule::count))
            .last()
        {
            Some(q) => self.quantity(q),
            None => Err(internal(span, "a missing number".into())),
        }
    }

    fn duration<'a>(&self, p: Pair<'a, Rule>) -> Result<Duration<'a>> {
        let span = self.span(&p);
        let mut keyword = DurationKeyword::For;
        let mut value = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::kw_for => keyword = DurationKeyword::For,
                Rule::kw_over => keyword = DurationKeyword::Over,
                Rule::quantity => value = Some(self.quantity(c)?),
                _ => {}
            }
        }
        let value = value.ok_or_else(|| internal(span, "duration without value".into()))?;
        Ok(Duration {
            span,
            keyword,
            value,
        })
    }

    fn blocking<'a>(&self, p: Pair<'a, Rule>) -> Result<Blocking<'a>> {
        let span = self.span(&p);
        let mut at = None;
        let mut actor = None;
        let mut action = None;
        let mut duration = None;
        for c in p.into_inner() {
            let cs = self.span(&c);
            match c.as_rule() {
                Rule::quantity => at = Some(self.quantity(c)?),
                Rule::name => actor = Some(self.text(&c)),
                Rule::walk => {
                    let pt = c
                        .into_inner()
                        .find(|x| x.as_rule() == Rule::point)
                        .ok_or_else(|| internal(cs, "walk without point".into()))?;
                    action = Some(Action::Walk(cs, self.point(pt)?));
                }
                Rule::turn => action = Some(Action::Turn(cs, self.last_quantity(c)?)),
                Rule::duration => duration = Some(self.duration(c)?),
                _ => {}
            }
        }
        match (at, actor, action) {
            (Some(at), Some(actor), Some(action)) => Ok(Blocking {
                span,
                at,
                actor,
                action,
                duration,
            }),
            _ => Err(internal(span, "incomplete movement".into())),
        }
    }

    fn shot<'a>(&self, p: Pair<'a, Rule>) -> Result<Shot<'a>> {
        let span = self.span(&p);
        let mut pin = None;
        let mut body = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::pin => pin = Some(self.last_quantity(c)?),
                _ => body = Some(self.shot_body(c)?),
            }
        }
        let body = body.ok_or_else(|| internal(span, "empty shot".into()))?;
        Ok(Shot { span, pin, body })
    }

    fn shot_body<'a>(&self, p: Pair<'a, Rule>) -> Result<ShotBody<'a>> {
        Ok(match p.as_rule() {
            Rule::framed_shot => ShotBody::Framed(self.framed(p)?),
            Rule::hold_shot => ShotBody::Hold(self.hold(p)?),
            Rule::path_shot => ShotBody::Path(self.path(p)?),
            Rule::coverage_shot => ShotBody::Coverage(self.coverage(p)?),
            _ => return Err(self.bug(&p, "a shot")),
        })
    }

    fn framed<'a>(&self, p: Pair<'a, Rule>) -> Result<FramedShot<'a>> {
        let span = self.span(&p);
        let mut transition = None;
        let mut composition = None;
        let mut duration = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::transition => transition = Some(self.transition(c)?),
                Rule::composition => composition = Some(self.composition(c)?),
                Rule::duration => duration = Some(self.duration(c)?),
                _ => return Err(self.bug(&c, "a part of a shot")),
            }
        }
        let composition =
            composition.ok_or_else(|| internal(span, "shot without composition".into()))?;
        Ok(FramedShot {
            span,
            transition,
            composition,
            duration,
        })
    }

    fn coverage<'a>(&self, p: Pair<'a, Rule>) -> Result<CoverageShot<'a>> {
        let span = self.span(&p);
        let mut transition = None;
        let mut size = None;
        let mut names = Vec::with_capacity(2);
        let mut duration = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::transition => transition = Some(self.transition(c)?),
                Rule::size => {
                    let s = Size::parse(c.as_str()).ok_or_else(|| self.bug(&c, "a size"))?;
                    size = Some((self.span(&c), s));
                }
                Rule::name => names.push(self.text(&c)),
                Rule::duration => duration = Some(self.duration(c)?),
                _ => {}
            }
        }
        match names.as_slice() {
            [a, b] => Ok(CoverageShot {
                span,
                transition,
                size,
                a: *a,
                b: *b,
                duration,
            }),
            _ => Err(internal(span, "a coverage without its two actors".into())),
        }
    }

    fn hold<'a>(&self, p: Pair<'a, Rule>) -> Result<HoldShot<'a>> {
        let span = self.span(&p);
        let mut event = None;
        let mut duration = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::event => event = Some(self.event(c)),
                Rule::duration => duration = Some(self.duration(c)?),
                _ => {}
            }
        }
        Ok(HoldShot {
            span,
            event,
            duration,
        })
    }

    fn event<'a>(&self, p: Pair<'a, Rule>) -> Event<'a> {
        let span = self.span(&p);
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::string => {
                    let t = self.string(c);
                    return Event {
                        span,
                        text: t.text,
                        quoted: true,
                    };
                }
                Rule::event_text => {
                    return Event {
                        span,
                        text: c.as_str(),
                        quoted: false,
                    }
                }
                _ => {}
            }
        }
        Event {
            span,
            text: "",
            quoted: true,
        }
    }

    fn transition<'a>(&self, p: Pair<'a, Rule>) -> Result<Transition<'a>> {
        let span = self.span(&p);
        let inner = p
            .into_inner()
            .next()
            .ok_or_else(|| internal(span, "empty transition".into()))?;
        let kind = match inner.as_rule() {
            Rule::cut_to => TransitionKind::Cut,
            Rule::dissolve_to => TransitionKind::Dissolve,
            Rule::then_move => {
                let mut event = None;
                let mut kind = MoveKind::Hold;
                let mut follow = None;
                for c in inner.into_inner() {
                    match c.as_rule() {
                        Rule::event => event = Some(self.event(c)),
                        Rule::camera_move => {
                            let m = c
                                .into_inner()
                                .next()
                                .ok_or_else(|| internal(span, "empty move".into()))?;
                            if m.as_rule() == Rule::follow {
                                kind = MoveKind::Follow;
                                follow = m
                                    .into_inner()
                                    .find(|x| x.as_rule() == Rule::name)
                                    .map(|n| self.text(&n));
                            } else {
                                kind = MoveKind::parse(m.as_str())
                                    .ok_or_else(|| self.bug(&m, "a camera move"))?;
                            }
                        }
                        _ => {}
                    }
                }
                TransitionKind::Move {
                    event,
                    kind,
                    follow,
                }
            }
            _ => return Err(self.bug(&inner, "a transition")),
        };
        Ok(Transition { span, kind })
    }

    fn composition<'a>(&self, p: Pair<'a, Rule>) -> Result<Composition<'a>> {
        let span = self.span(&p);
        let mut angle = None;
        let mut framings = Vec::new();
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::camera_angle => {
                    let cs = self.span(&c);
                    let a = match c.into_inner().next().map(|x| x.as_rule()) {
                        Some(Rule::high_angle) => CameraAngle::High,
                        Some(Rule::low_angle) => CameraAngle::Low,
                        _ => CameraAngle::EyeLevel,
                    };
                    angle = Some((cs, a));
                }
                Rule::framing => framings.push(self.framing(c)?),
                _ => return Err(self.bug(&c, "a framing")),
            }
        }
        Ok(Composition {
            span,
            angle,
            framings,
        })
    }

    fn framing<'a>(&self, p: Pair<'a, Rule>) -> Result<Framing<'a>> {
        let span = self.span(&p);
        let mut size = None;
        let mut subjects = Vec::new();
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::size => {
                    let s = Size::parse(c.as_str()).ok_or_else(|| self.bug(&c, "a size"))?;
                    size = Some((self.span(&c), s));
                }
                Rule::subject => subjects.push(self.subject(c)?),
                _ => {}
            }
        }
        let size = size.ok_or_else(|| internal(span, "framing without size".into()))?;
        Ok(Framing {
            span,
            size,
            subjects,
        })
    }

    fn subject<'a>(&self, p: Pair<'a, Rule>) -> Result<Subject<'a>> {
        let span = self.span(&p);
        let mut actor = None;
        let mut profile = None;
        let mut screen = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::name => actor = Some(self.text(&c)),
                Rule::profile => {
                    let pr = Profile::parse(c.as_str()).ok_or_else(|| self.bug(&c, "a profile"))?;
                    profile = Some((self.span(&c), pr));
                }
                Rule::screen => screen = Some(self.screen(c)?),
                _ => {}
            }
        }
        let actor = actor.ok_or_else(|| internal(span, "subject without actor".into()))?;
        Ok(Subject {
            span,
            actor,
            profile,
            screen,
        })
    }

    fn screen<'a>(&self, p: Pair<'a, Rule>) -> Result<Screen<'a>> {
        let span = self.span(&p);
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::screen_third => {
                    let t =
                        ScreenThird::parse(c.as_str()).ok_or_else(|| self.bug(&c, "a third"))?;
                    return Ok(Screen {
                        span,
                        position: ScreenPosition::Third(t),
                    });
                }
                Rule::screen_point => {
                    let cs = self.span(&c);
                    let mut it = c.into_inner();
                    let x = self.next_quantity(&mut it, cs)?;
                    let y = self.next_quantity(&mut it, cs)?;
                    return Ok(Screen {
                        span,
                        position: ScreenPosition::Point(x, y),
                    });
                }
                _ => {}
            }
        }
        Err(internal(span, "screen without position".into()))
    }

    fn path<'a>(&self, p: Pair<'a, Rule>) -> Result<PathShot<'a>> {
        let span = self.span(&p);
        let mut transition = None;
        let mut kind = None;
        let mut params = Vec::new();
        let mut duration = None;
        for c in p.into_inner() {
            let cs = self.span(&c);
            let value = match c.as_rule() {
                Rule::transition => {
                    transition = Some(self.transition(c)?);
                    continue;
                }
                Rule::kw_path => continue,
                Rule::path_kind => {
                    let k = c
                        .into_inner()
                        .next()
                        .ok_or_else(|| internal(cs, "empty path kind".into()))?;
                    let pk = match k.as_rule() {
                        Rule::kw_square => PathKind::Square,
                        Rule::kw_helix => PathKind::Helix,
                        Rule::kw_orbit => PathKind::Orbit,
                        Rule::waypoints => {
                            let file = k
                                .into_inner()
                                .find(|x| x.as_rule() == Rule::string)
                                .map(|s| self.string(s))
                                .ok_or_else(|| internal(cs, "waypoints without file".into()))?;
                            PathKind::Waypoints(file)
                        }
                        _ => return Err(self.bug(&k, "a path kind")),
                    };
                    kind = Some((cs, pk));
                    continue;
                }
                Rule::duration => {
                    duration = Some(self.duration(c)?);
                    continue;
                }
                Rule::p_side => PathValue::Side(self.last_quantity(c)?),
                Rule::p_altitude => PathValue::Altitude(self.last_quantity(c)?),
                Rule::p_radius => PathValue::Radius(self.last_quantity(c)?),
                Rule::p_turns => PathValue::Turns(self.last_quantity(c)?),
                Rule::p_center => {
                    let pt = c
                        .into_inner()
                        .find(|x| x.as_rule() == Rule::point)
                        .ok_or_else(|| internal(cs, "center without point".into()))?;
                    PathValue::Center(self.point(pt)?)
                }
                Rule::p_from_to => {
                    let mut qs = c.into_inner().filter(|x| x.as_rule() == Rule::quantity);
                    match (qs.next(), qs.next()) {
                        (Some(a), Some(b)) => {
                            PathValue::FromTo(self.quantity(a)?, self.quantity(b)?)
                        }
                        _ => return Err(internal(cs, "from without to".into())),
                    }
                }
                Rule::p_around | Rule::looking_at => {
                    let is_around = c.as_rule() == Rule::p_around;
                    let n = c
                        .into_inner()
                        .find(|x| x.as_rule() == Rule::name)
                        .map(|n| self.text(&n))
                        .ok_or_else(|| internal(cs, "missing actor".into()))?;
                    if is_around {
                        PathValue::Around(n)
                    } else {
                        PathValue::LookingAt(n)
                    }
                }
                Rule::p_direction => PathValue::Clockwise(c.as_str() == "clockwise"),
                _ => return Err(self.bug(&c, "a path parameter")),
            };
            params.push(PathParam { span: cs, value });
        }
        let kind = kind.ok_or_else(|| internal(span, "path without kind".into()))?;
        Ok(PathShot {
            span,
            transition,
            kind,
            params,
            duration,
        })
    }

    fn timed<'a>(&self, p: Pair<'a, Rule>) -> Result<TimedEntry<'a>> {
        let span = self.span(&p);
        let mut index = None;
        let mut codes = Vec::with_capacity(2);
        let mut body = None;
        for c in p.into_inner() {
            match c.as_rule() {
                Rule::entry_index => index = Some(self.text(&c)),
                Rule::timecode => codes.push(self.text(&c)),
                Rule::arrow => {}
                _ => body = Some(self.shot_body(c)?),
            }
        }
        match (index, codes.as_slice(), body) {
            (Some(index), [start, end], Some(body)) => Ok(TimedEntry {
                span,
                index,
                start: *start,
                end: *end,
                body,
            }),
            _ => Err(internal(span, "incomplete timed entry".into())),
        }
    }
}
