//! The fast path of the parser: a hand-written, allocation-light recogniser of one line that
//! builds exactly the `ast` nodes `parser.rs` builds through pest (same spans, same borrowed
//! text), or gives up.
//!
//! Invariant: `parse_line` returns `Some(line)` only for a line the pest grammar accepts, and
//! then `line` equals what the pest path builds. It returns `None` for every line it does not
//! accept and whenever it is not sure; `parser::parse` then runs pest on that line, so every
//! diagnostic still comes from the pest path.
//!
//! How it keeps that invariant: each function below is one rule of `psl.pest`, written with
//! pest's PEG semantics (ordered choice that commits, greedy repetition, no backtracking into
//! a rule that matched). Implicit whitespace follows pest's generated code exactly: in a
//! non-atomic sequence `a ~ b`, whitespace is skipped before `b` and stays consumed when `b`
//! matches, even empty (`b?`, `b*`), so a rule ending in an absent optional part ends after
//! the trailing blanks; inside a repetition the skip before a failed repetition is undone.
//! Non-ASCII text is handled where the grammar matches `ANY` (strings, events, comments);
//! where the grammar asks `XID_START`/`XID_CONTINUE` of a non-ASCII character (names, the
//! `boundary` after a keyword), the parser "poisons" the line and gives up, because it has no
//! Unicode tables. `grammar/tests/fast.rs` and `fuzz/fuzz_targets/differential.rs` compare
//! this path with the pest path.

use crate::ast::*;
use crate::span::Span;
use crate::vocab::{CameraAngle, MoveKind, Profile, ScreenThird, Size};

/// The `size` words in the grammar's order.
const SIZES: &[(&str, Size)] = &[
    ("ECU", Size::ECU),
    ("BCU", Size::BCU),
    ("CU", Size::CU),
    ("MCU", Size::MCU),
    ("MS", Size::MS),
    ("MLS", Size::MLS),
    ("FS", Size::FS),
    ("LS", Size::LS),
    ("ELS", Size::ELS),
];

/// The `profile` words in the grammar's order.
const PROFILES: &[(&str, Profile)] = &[
    ("34backleft", Profile::ThreeQuarterBackLeft),
    ("34backright", Profile::ThreeQuarterBackRight),
    ("34left", Profile::ThreeQuarterLeft),
    ("34right", Profile::ThreeQuarterRight),
    ("front", Profile::Front),
    ("back", Profile::Back),
    ("left", Profile::Left),
    ("right", Profile::Right),
];

/// The `screen_third` words in the grammar's order.
const THIRDS: &[(&str, ScreenThird)] = &[
    ("left", ScreenThird::Left),
    ("center", ScreenThird::Center),
    ("centre", ScreenThird::Center),
    ("right", ScreenThird::Right),
];

/// The camera moves of `camera_move` (without `follow`), in the grammar's order.
const MOVES: &[(&str, MoveKind)] = &[
    ("hold", MoveKind::Hold),
    ("pan", MoveKind::Pan),
    ("dolly", MoveKind::Dolly),
    ("crane", MoveKind::Crane),
    ("track", MoveKind::Track),
];

/// The words of `move_word` (what ends a free event text).
const MOVE_WORDS: &[(&str, ())] = &[
    ("hold", ()),
    ("pan", ()),
    ("dolly", ()),
    ("crane", ()),
    ("track", ()),
    ("follow", ()),
];

const CENTER: &[(&str, ())] = &[("center", ()), ("centre", ())];
const DIRECTIONS: &[(&str, bool)] = &[("counterclockwise", false), ("clockwise", true)];

/// Parse one source line (without its line break) that starts at byte `offset` of the file
/// and is line `number` (1-based). `Some` only when pest accepts the line, with the same
/// `Line` the pest path builds; `None` means "ask pest".
pub fn parse_line(text: &str, offset: usize, number: usize) -> Option<Line<'_>> {
    let mut line = Line {
        number,
        span: Span::new(offset, offset + text.len()),
        statement: None,
        comment: None,
        error: false,
    };
    // Blank and comment-only lines: the same shortcut as the pest path takes.
    let trimmed = text.trim_start_matches([' ', '\t']);
    if trimmed.is_empty() {
        return Some(line);
    }
    let start = text.len() - trimmed.len();
    if trimmed.starts_with('#') {
        let t = trimmed.trim_end();
        line.comment = Some(Text {
            text: t,
            span: Span::new(offset + start, offset + start + t.len()),
        });
        return Some(line);
    }

    // line = { SOI ~ statement? ~ comment? ~ EOI }. The first non-blank character is not
    // `#`, so the line is accepted only if a statement matches here.
    let mut p = P {
        s: text,
        b: text.as_bytes(),
        off: offset,
        poisoned: false,
    };
    let statement = p.statement(start);
    if p.poisoned {
        return None;
    }
    let (statement, end) = statement?;
    let mut i = p.ws(end);
    if p.peek(i) == Some(b'#') {
        // comment = @{ "#" ~ (!NEWLINE ~ ANY)* }: it stops at a carriage return, and then
        // EOI fails.
        let rest = &text[i..];
        if rest.contains('\r') {
            return None;
        }
        let t = rest.trim_end();
        line.comment = Some(Text {
            text: t,
            span: Span::new(offset + i, offset + i + t.len()),
        });
        i = text.len();
    }
    if i != text.len() {
        return None;
    }
    line.statement = Some(statement);
    Some(line)
}

/// Is `w` a word of the `keyword` rule? (Byte patterns grouped by length; a unit test checks
/// this against `vocab::KEYWORDS`, which a test of its own checks against `psl.pest`.)
fn is_keyword(w: &[u8]) -> bool {
    match w.len() {
        1 => w == b"x",
        2 => matches!(
            w,
            b"CU" | b"MS" | b"FS" | b"LS" | b"on" | b"as" | b"to" | b"at"
        ),
        3 => matches!(
            w,
            b"ECU"
                | b"BCU"
                | b"MCU"
                | b"MLS"
                | b"ELS"
                | b"and"
                | b"cut"
                | b"for"
                | b"pan"
                | b"low"
                | b"eye"
        ),
        4 => matches!(
            w,
            b"back"
                | b"left"
                | b"then"
                | b"over"
                | b"hold"
                | b"high"
                | b"lens"
                | b"path"
                | b"side"
                | b"from"
        ),
        5 => matches!(
            w,
            b"front"
                | b"right"
                | b"dolly"
                | b"crane"
                | b"track"
                | b"level"
                | b"angle"
                | b"stage"
                | b"drone"
                | b"actor"
                | b"walks"
                | b"turns"
                | b"helix"
                | b"orbit"
        ),
        6 => matches!(
            w,
            b"34left"
                | b"follow"
                | b"screen"
                | b"center"
                | b"centre"
                | b"height"
                | b"facing"
                | b"square"
                | b"radius"
                | b"around"
        ),
        7 => matches!(w, b"34right" | b"looking"),
        8 => matches!(w, b"dissolve" | b"altitude"),
        9 => matches!(w, b"waypoints" | b"clockwise"),
        10 => w == b"34backleft",
        11 => w == b"34backright",
        16 => w == b"counterclockwise",
        _ => false,
    }
}

/// ASCII part of `XID_CONTINUE`.
fn is_word_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The state of one line's parse: positions are byte offsets into the line.
struct P<'a> {
    s: &'a str,
    b: &'a [u8],
    /// Offset of the line in the file, added to every span.
    off: usize,
    /// A question the parser cannot answer exactly came up (a Unicode class of a non-ASCII
    /// character): the result is void, whatever it is.
    poisoned: bool,
}

type R<T> = Option<(T, usize)>;

impl<'a> P<'a> {
    fn peek(&self, i: usize) -> Option<u8> {
        self.b.get(i).copied()
    }

    fn is(&self, i: usize, c: u8) -> bool {
        self.b.get(i) == Some(&c)
    }

    fn digits(&self, mut i: usize) -> usize {
        while self.peek(i).is_some_and(|c| c.is_ascii_digit()) {
            i += 1;
        }
        i
    }

    /// Implicit whitespace: `WHITESPACE*`.
    fn ws(&self, mut i: usize) -> usize {
        while matches!(self.peek(i), Some(b' ' | b'\t')) {
            i += 1;
        }
        i
    }

    fn span(&self, a: usize, b: usize) -> Span {
        Span::new(self.off + a, self.off + b)
    }

    fn text(&self, a: usize, b: usize) -> Text<'a> {
        Text {
            text: &self.s[a..b],
            span: self.span(a, b),
        }
    }

    /// `boundary = _{ !(XID_CONTINUE | "-") }` at `i`.
    fn boundary(&mut self, i: usize) -> bool {
        match self.peek(i) {
            None => true,
            Some(c) if c < 0x80 => !(is_word_byte(c) || c == b'-'),
            Some(_) => {
                self.poisoned = true;
                false
            }
        }
    }

    /// `@{ "k" ~ boundary }`
    fn kw(&mut self, i: usize, k: &str) -> Option<usize> {
        let e = i + k.len();
        if self.b[i..].starts_with(k.as_bytes()) && self.boundary(e) {
            Some(e)
        } else {
            None
        }
    }

    /// `@{ ("w1" | "w2" | …) ~ boundary }`: the first word that is a prefix is the choice
    /// (PEG commits to it), then the boundary decides.
    fn one_of<T: Copy>(&mut self, i: usize, words: &[(&str, T)]) -> R<T> {
        let rest = &self.b[i..];
        for (w, v) in words {
            if rest.starts_with(w.as_bytes()) {
                let e = i + w.len();
                return if self.boundary(e) {
                    Some((*v, e))
                } else {
                    None
                };
            }
        }
        None
    }

    /// `name = @{ !keyword ~ XID_START ~ XID_CONTINUE* }`
    fn name(&mut self, i: usize) -> R<Text<'a>> {
        let c = self.peek(i)?;
        if c >= 0x80 {
            self.poisoned = true;
            return None;
        }
        if !c.is_ascii_alphabetic() {
            return None;
        }
        let mut j = i + 1;
        while self.peek(j).is_some_and(is_word_byte) {
            j += 1;
        }
        if self.peek(j).is_some_and(|c| c >= 0x80) {
            self.poisoned = true;
            return None;
        }
        // No keyword is a prefix of another (tested), so `keyword` matches here exactly when
        // the whole word is one and the boundary after it holds.
        if is_keyword(&self.b[i..j]) && !self.is(j, b'-') {
            return None;
        }
        Some((self.text(i, j), j))
    }

    /// `number = @{ "-"? ~ (ASCII_DIGIT+ ~ ("." ~ ASCII_DIGIT*)? | "." ~ ASCII_DIGIT+) }`
    fn number(&self, i: usize) -> Option<usize> {
        let mut j = i;
        if self.is(j, b'-') {
            j += 1;
        }
        let d = self.digits(j);
        if d > j {
            if self.is(d, b'.') {
                Some(self.digits(d + 1))
            } else {
                Some(d)
            }
        } else if self.is(j, b'.') {
            let e = self.digits(j + 1);
            (e > j + 1).then_some(e)
        } else {
            None
        }
    }

    /// `quantity = ${ number ~ unit? }` (and `count`, built the same way).
    fn quantity(&self, i: usize) -> R<Quantity<'a>> {
        let ne = self.number(i)?;
        let mut j = ne;
        while self.peek(j).is_some_and(|c| c.is_ascii_alphabetic()) {
            j += 1;
        }
        let number = &self.s[i..ne];
        let unit = (j > ne).then(|| self.text(ne, j));
        Some((
            Quantity {
                // As in the pest path: the grammar admits only what f64 parses.
                value: number.parse::<f64>().unwrap_or(f64::NAN),
                number,
                unit,
                span: self.span(i, j),
            },
            j,
        ))
    }

    /// `"(" ~ quantity ~ "," ~ quantity ~ ")"`: the two quantities and the end.
    fn pair(&self, i: usize) -> R<(Quantity<'a>, Quantity<'a>)> {
        if !self.is(i, b'(') {
            return None;
        }
        let (x, e) = self.quantity(self.ws(i + 1))?;
        let j = self.ws(e);
        if !self.is(j, b',') {
            return None;
        }
        let (y, e) = self.quantity(self.ws(j + 1))?;
        let j = self.ws(e);
        if !self.is(j, b')') {
            return None;
        }
        Some(((x, y), j + 1))
    }

    /// `point = { "(" ~ quantity ~ "," ~ quantity ~ ")" }`
    fn point(&self, i: usize) -> R<Point<'a>> {
        let ((x, y), e) = self.pair(i)?;
        Some((
            Point {
                x,
                y,
                span: self.span(i, e),
            },
            e,
        ))
    }

    /// `string = ${ "\"" ~ string_inner ~ "\"" }`: the inner text.
    fn string(&self, i: usize) -> R<Text<'a>> {
        if !self.is(i, b'"') {
            return None;
        }
        let len = self.b[i + 1..].iter().position(|&c| c == b'"')?;
        let e = i + 1 + len;
        Some((self.text(i + 1, e), e + 1))
    }

    /// `statement = _{ shot | blocking | stage | lens | drone | actor_decl | timed_entry }`
    fn statement(&mut self, i: usize) -> R<Statement<'a>> {
        if let Some((s, e)) = self.shot(i) {
            return Some((Statement::Shot(s), e));
        }
        if self.poisoned {
            return None;
        }
        if let Some((s, e)) = self.blocking(i) {
            return Some((Statement::Blocking(s), e));
        }
        if let Some((s, e)) = self.stage(i) {
            return Some((Statement::Stage(s), e));
        }
        if let Some((s, e)) = self.lens(i) {
            return Some((Statement::Lens(s), e));
        }
        if let Some((s, e)) = self.drone(i) {
            return Some((Statement::Drone(s), e));
        }
        if let Some((s, e)) = self.actor(i) {
            return Some((Statement::Actor(s), e));
        }
        if let Some((s, e)) = self.timed(i) {
            return Some((Statement::Timed(s), e));
        }
        None
    }

    /// `stage = { kw_stage ~ quantity ~ kw_x ~ quantity ~ kw_x ~ quantity }`
    fn stage(&mut self, i: usize) -> R<Stage<'a>> {
        let e = self.kw(i, "stage")?;
        let (x, e) = self.quantity(self.ws(e))?;
        let e = self.kw(self.ws(e), "x")?;
        let (y, e) = self.quantity(self.ws(e))?;
        let e = self.kw(self.ws(e), "x")?;
        let (z, e) = self.quantity(self.ws(e))?;
        Some((
            Stage {
                span: self.span(i, e),
                x,
                y,
                z,
            },
            e,
        ))
    }

    /// `lens = { kw_lens ~ quantity ~ aspect? }`
    fn lens(&mut self, i: usize) -> R<Lens<'a>> {
        let e = self.kw(i, "lens")?;
        let (fov, e) = self.quantity(self.ws(e))?;
        let j = self.ws(e);
        let (aspect, end) = match self.aspect(j) {
            Some(e) => (Some(self.text(j, e)), e),
            None => (None, j),
        };
        Some((
            Lens {
                span: self.span(i, end),
                fov,
                aspect,
            },
            end,
        ))
    }

    /// `aspect = @{ D+ ~ ("." ~ D+)? ~ ":" ~ D+ ~ ("." ~ D+)? }`
    fn aspect(&self, i: usize) -> Option<usize> {
        let e = self.digits_with_fraction(i)?;
        if !self.is(e, b':') {
            return None;
        }
        self.digits_with_fraction(e + 1)
    }

    /// `D+ ~ ("." ~ D+)?`
    fn digits_with_fraction(&self, i: usize) -> Option<usize> {
        let e = self.digits(i);
        if e == i {
            return None;
        }
        if self.is(e, b'.') {
            let f = self.digits(e + 1);
            if f > e + 1 {
                return Some(f);
            }
        }
        Some(e)
    }

    /// `drone = { kw_drone ~ (string | profile_name) }`
    fn drone(&mut self, i: usize) -> R<Drone<'a>> {
        let e = self.kw(i, "drone")?;
        let j = self.ws(e);
        let (target, end) = if let Some((t, e)) = self.string(j) {
            (DroneTarget::File(t), e)
        } else {
            // profile_name = @{ (ASCII_ALPHANUMERIC | "-" | "_" | ".")+ }
            let mut e = j;
            while self
                .peek(e)
                .is_some_and(|c| c.is_ascii_alphanumeric() || matches!(c, b'-' | b'_' | b'.'))
            {
                e += 1;
            }
            if e == j {
                return None;
            }
            (DroneTarget::Builtin(self.text(j, e)), e)
        };
        Some((
            Drone {
                span: self.span(i, end),
                target,
            },
            end,
        ))
    }

    /// `actor_decl = { kw_actor ~ name ~ actor_attr* }`
    fn actor(&mut self, i: usize) -> R<ActorDecl<'a>> {
        let e = self.kw(i, "actor")?;
        let (name, e) = self.name(self.ws(e))?;
        let mut end = self.ws(e);
        let mut attrs = Vec::new();
        while let Some((a, e)) = self.actor_attr(self.ws(end)) {
            attrs.push(a);
            end = e;
        }
        Some((
            ActorDecl {
                span: self.span(i, end),
                name,
                attrs,
            },
            end,
        ))
    }

    /// `actor_attr = _{ actor_height | actor_at | actor_facing }`
    fn actor_attr(&mut self, i: usize) -> R<ActorAttr<'a>> {
        if let Some(e) = self.kw(i, "height") {
            if let Some((q, e)) = self.quantity(self.ws(e)) {
                return Some((ActorAttr::Height(self.span(i, e), q), e));
            }
        }
        if let Some(e) = self.kw(i, "at") {
            if let Some((p, e)) = self.point(self.ws(e)) {
                return Some((ActorAttr::At(self.span(i, e), p), e));
            }
        }
        if let Some(e) = self.kw(i, "facing") {
            if let Some((q, e)) = self.quantity(self.ws(e)) {
                return Some((ActorAttr::Facing(self.span(i, e), q), e));
            }
        }
        None
    }

    /// `blocking = { kw_at ~ quantity ~ name ~ (walk | turn) ~ duration? }`
    fn blocking(&mut self, i: usize) -> R<Blocking<'a>> {
        let e = self.kw(i, "at")?;
        let (at, e) = self.quantity(self.ws(e))?;
        let (actor, e) = self.name(self.ws(e))?;
        let j = self.ws(e);
        let (action, e) = self.walk_or_turn(j)?;
        let (duration, end) = self.opt_duration(self.ws(e));
        Some((
            Blocking {
                span: self.span(i, end),
                at,
                actor,
                action,
                duration,
            },
            end,
        ))
    }

    /// `walk = { kw_walks ~ kw_to ~ point }`, `turn = { kw_turns ~ kw_to ~ quantity }`
    fn walk_or_turn(&mut self, i: usize) -> R<Action<'a>> {
        if let Some(e) = self.kw(i, "walks") {
            if let Some(e) = self.kw(self.ws(e), "to") {
                if let Some((p, e)) = self.point(self.ws(e)) {
                    return Some((Action::Walk(self.span(i, e), p), e));
                }
            }
        }
        if let Some(e) = self.kw(i, "turns") {
            if let Some(e) = self.kw(self.ws(e), "to") {
                if let Some((q, e)) = self.quantity(self.ws(e)) {
                    return Some((Action::Turn(self.span(i, e), q), e));
                }
            }
        }
        None
    }

    /// `duration = { (kw_for | kw_over) ~ quantity }`
    fn duration(&mut self, i: usize) -> R<Duration<'a>> {
        let (keyword, e) = if let Some(e) = self.kw(i, "for") {
            (DurationKeyword::For, e)
        } else {
            (DurationKeyword::Over, self.kw(i, "over")?)
        };
        let (value, e) = self.quantity(self.ws(e))?;
        Some((
            Duration {
                span: self.span(i, e),
                keyword,
                value,
            },
            e,
        ))
    }

    /// `duration?` at `i`: the duration and where the optional part ends.
    fn opt_duration(&mut self, i: usize) -> (Option<Duration<'a>>, usize) {
        match self.duration(i) {
            Some((d, e)) => (Some(d), e),
            None => (None, i),
        }
    }

    /// `shot = { pin? ~ (framed_shot | hold_shot | path_shot) }`, `pin = { kw_at ~ quantity }`
    fn shot(&mut self, i: usize) -> R<Shot<'a>> {
        let mut pin = None;
        let mut j = i;
        if let Some(e) = self.kw(i, "at") {
            if let Some((q, e)) = self.quantity(self.ws(e)) {
                pin = Some(q);
                j = e;
            }
        }
        let (body, end) = self.shot_body(self.ws(j), true)?;
        Some((
            Shot {
                span: self.span(i, end),
                pin,
                body,
            },
            end,
        ))
    }

    /// `framed_shot | hold_shot | path_shot` (without `path_shot` in a timed entry).
    fn shot_body(&mut self, i: usize, with_path: bool) -> R<ShotBody<'a>> {
        if let Some((f, e)) = self.framed(i) {
            return Some((ShotBody::Framed(f), e));
        }
        if let Some((h, e)) = self.hold(i) {
            return Some((ShotBody::Hold(h), e));
        }
        if with_path {
            if let Some((p, e)) = self.path(i) {
                return Some((ShotBody::Path(p), e));
            }
        }
        None
    }

    /// `transition?` at `i`: the transition and where the optional part ends.
    fn opt_transition(&mut self, i: usize) -> (Option<Transition<'a>>, usize) {
        match self.transition(i) {
            Some((t, e)) => (Some(t), e),
            None => (None, i),
        }
    }

    /// `framed_shot = { transition? ~ composition ~ duration? }`
    fn framed(&mut self, i: usize) -> R<FramedShot<'a>> {
        let (transition, e) = self.opt_transition(i);
        let (composition, e) = self.composition(self.ws(e))?;
        let (duration, end) = self.opt_duration(self.ws(e));
        Some((
            FramedShot {
                span: self.span(i, end),
                transition,
                composition,
                duration,
            },
            end,
        ))
    }

    /// `hold_shot = { kw_then ~ event? ~ kw_hold ~ duration? }`
    fn hold(&mut self, i: usize) -> R<HoldShot<'a>> {
        let e = self.kw(i, "then")?;
        let (event, e) = self.opt_event(self.ws(e));
        let e = self.kw(self.ws(e), "hold")?;
        let (duration, end) = self.opt_duration(self.ws(e));
        Some((
            HoldShot {
                span: self.span(i, end),
                event,
                duration,
            },
            end,
        ))
    }

    /// `transition = { cut_to | dissolve_to | then_move }`
    fn transition(&mut self, i: usize) -> R<Transition<'a>> {
        let cut_or_dissolve = |p: &mut Self, word: &str| {
            let e = p.kw(i, word)?;
            p.kw(p.ws(e), "to")
        };
        let (kind, e) = if let Some(e) = cut_or_dissolve(self, "cut") {
            (TransitionKind::Cut, e)
        } else if let Some(e) = cut_or_dissolve(self, "dissolve") {
            (TransitionKind::Dissolve, e)
        } else {
            self.then_move(i)?
        };
        Some((
            Transition {
                span: self.span(i, e),
                kind,
            },
            e,
        ))
    }

    /// `then_move = { kw_then ~ event? ~ camera_move ~ kw_to }`
    fn then_move(&mut self, i: usize) -> R<TransitionKind<'a>> {
        let e = self.kw(i, "then")?;
        let (event, e) = self.opt_event(self.ws(e));
        let j = self.ws(e);
        // camera_move = { kw_hold | kw_pan | kw_dolly | kw_crane | kw_track | follow }
        let (kind, follow, e) = if let Some((k, e)) = self.one_of(j, MOVES) {
            (k, None, e)
        } else {
            let e = self.kw(j, "follow")?;
            let (n, e) = self.name(self.ws(e))?;
            (MoveKind::Follow, Some(n), e)
        };
        let e = self.kw(self.ws(e), "to")?;
        Some((
            TransitionKind::Move {
                event,
                kind,
                follow,
            },
            e,
        ))
    }

    /// `event?` at `i`.
    fn opt_event(&mut self, i: usize) -> (Option<Event<'a>>, usize) {
        match self.event(i) {
            Some((ev, e)) => (Some(ev), e),
            None => (None, i),
        }
    }

    /// `event = { kw_as ~ (string | event_text) }`
    fn event(&mut self, i: usize) -> R<Event<'a>> {
        let e = self.kw(i, "as")?;
        let j = self.ws(e);
        if let Some((t, e)) = self.string(j) {
            return Some((
                Event {
                    span: self.span(i, e),
                    text: t.text,
                    quoted: true,
                },
                e,
            ));
        }
        let e = self.event_text(j)?;
        Some((
            Event {
                span: self.span(i, e),
                text: &self.s[j..e],
                quoted: false,
            },
            e,
        ))
    }

    /// `event_text = @{ event_word ~ ((" " | "\t")+ ~ !move_word ~ event_word)* }`
    fn event_text(&mut self, i: usize) -> Option<usize> {
        let mut e = self.event_word(i)?;
        loop {
            let j = self.ws(e);
            if j == e || self.one_of(j, MOVE_WORDS).is_some() {
                return Some(e);
            }
            match self.event_word(j) {
                Some(k) => e = k,
                None => return Some(e),
            }
        }
    }

    /// `event_word = _{ (!(" " | "\t" | "#") ~ ANY)+ }`
    fn event_word(&self, i: usize) -> Option<usize> {
        let n = self.b[i..]
            .iter()
            .position(|&c| matches!(c, b' ' | b'\t' | b'#'))
            .unwrap_or(self.b.len() - i);
        (n > 0).then_some(i + n)
    }

    /// `composition = { camera_angle? ~ framing+ }`
    fn composition(&mut self, i: usize) -> R<Composition<'a>> {
        let (angle, e) = match self.camera_angle(i) {
            Some((a, e)) => (Some((self.span(i, e), a)), e),
            None => (None, i),
        };
        let (first, e) = self.framing(self.ws(e))?;
        let mut framings = vec![first];
        let mut end = self.ws(e);
        while let Some((f, e)) = self.framing(self.ws(end)) {
            framings.push(f);
            end = e;
        }
        Some((
            Composition {
                span: self.span(i, end),
                angle,
                framings,
            },
            end,
        ))
    }

    /// `camera_angle = { high_angle | low_angle | eye_level }`, each
    /// `${ "high" ~ WHITESPACE+ ~ "angle" ~ boundary }` and the like.
    fn camera_angle(&mut self, i: usize) -> R<CameraAngle> {
        for (first, second, angle) in [
            ("high", "angle", CameraAngle::High),
            ("low", "angle", CameraAngle::Low),
            ("eye", "level", CameraAngle::EyeLevel),
        ] {
            if !self.b[i..].starts_with(first.as_bytes()) {
                continue;
            }
            let j = i + first.len();
            let k = self.ws(j);
            if k > j {
                if let Some(e) = self.kw(k, second) {
                    return Some((angle, e));
                }
            }
        }
        None
    }

    /// `framing = { size ~ kw_on? ~ subject ~ (kw_and ~ subject)* }`
    fn framing(&mut self, i: usize) -> R<Framing<'a>> {
        let (size, e) = self.one_of(i, SIZES)?;
        let size = (self.span(i, e), size);
        let mut j = self.ws(e);
        if let Some(e) = self.kw(j, "on") {
            j = e;
        }
        let (first, e) = self.subject(self.ws(j))?;
        let mut subjects = vec![first];
        let mut end = self.ws(e);
        // (kw_and ~ subject)*: the element is a sequence, all or nothing.
        while let Some((s, e)) = self
            .kw(self.ws(end), "and")
            .and_then(|a| self.subject(self.ws(a)))
        {
            subjects.push(s);
            end = e;
        }
        Some((
            Framing {
                span: self.span(i, end),
                size,
                subjects,
            },
            end,
        ))
    }

    /// `subject = { name ~ profile? ~ screen? }`
    fn subject(&mut self, i: usize) -> R<Subject<'a>> {
        let (actor, e) = self.name(i)?;
        let mut j = self.ws(e);
        let profile = match self.one_of(j, PROFILES) {
            Some((p, e)) => {
                let r = (self.span(j, e), p);
                j = e;
                Some(r)
            }
            None => None,
        };
        j = self.ws(j);
        let screen = match self.screen(j) {
            Some((s, e)) => {
                j = e;
                Some(s)
            }
            None => None,
        };
        Some((
            Subject {
                span: self.span(i, j),
                actor,
                profile,
                screen,
            },
            j,
        ))
    }

    /// `screen = { kw_screen ~ (screen_third | screen_point) }`
    fn screen(&mut self, i: usize) -> R<Screen<'a>> {
        let e = self.kw(i, "screen")?;
        let j = self.ws(e);
        let (position, e) = if let Some((t, e)) = self.one_of(j, THIRDS) {
            (ScreenPosition::Third(t), e)
        } else {
            // screen_point = { "(" ~ count ~ "," ~ count ~ ")" }
            let ((x, y), e) = self.pair(j)?;
            (ScreenPosition::Point(x, y), e)
        };
        Some((
            Screen {
                span: self.span(i, e),
                position,
            },
            e,
        ))
    }

    /// `path_shot = { transition? ~ kw_path ~ path_kind ~ path_param* ~ duration? ~ looking_at? }`
    fn path(&mut self, i: usize) -> R<PathShot<'a>> {
        let (transition, e) = self.opt_transition(i);
        let e = self.kw(self.ws(e), "path")?;
        let j = self.ws(e);
        let (kind, e) = self.path_kind(j)?;
        let kind = (self.span(j, e), kind);
        let mut end = self.ws(e);
        let mut params = Vec::new();
        while let Some((p, e)) = self.path_param(self.ws(end)) {
            params.push(p);
            end = e;
        }
        let (duration, e) = self.opt_duration(self.ws(end));
        end = self.ws(e);
        if let Some((p, e)) = self.looking_at(end) {
            params.push(p);
            end = e;
        }
        Some((
            PathShot {
                span: self.span(i, end),
                transition,
                kind,
                params,
                duration,
            },
            end,
        ))
    }

    /// `path_kind = { kw_square | kw_helix | kw_orbit | waypoints }`
    fn path_kind(&mut self, i: usize) -> R<PathKind<'a>> {
        for (w, k) in [
            ("square", PathKind::Square),
            ("helix", PathKind::Helix),
            ("orbit", PathKind::Orbit),
        ] {
            if let Some(e) = self.kw(i, w) {
                return Some((k, e));
            }
        }
        // waypoints = { kw_waypoints ~ string }
        let e = self.kw(i, "waypoints")?;
        let (file, e) = self.string(self.ws(e))?;
        Some((PathKind::Waypoints(file), e))
    }

    /// `path_param = _{ p_side | p_center | p_altitude | p_radius | p_from_to | p_turns |
    /// p_around | p_direction | looking_at }`
    fn path_param(&mut self, i: usize) -> R<PathParam<'a>> {
        let (value, e) = self.path_value(i)?;
        Some((
            PathParam {
                span: self.span(i, e),
                value,
            },
            e,
        ))
    }

    fn path_value(&mut self, i: usize) -> R<PathValue<'a>> {
        let quantity_after = |p: &mut Self, word: &str| {
            let e = p.kw(i, word)?;
            p.quantity(p.ws(e))
        };
        if let Some((q, e)) = quantity_after(self, "side") {
            return Some((PathValue::Side(q), e));
        }
        if let Some((_, e)) = self.one_of(i, CENTER) {
            if let Some((p, e)) = self.point(self.ws(e)) {
                return Some((PathValue::Center(p), e));
            }
        }
        if let Some((q, e)) = quantity_after(self, "altitude") {
            return Some((PathValue::Altitude(q), e));
        }
        if let Some((q, e)) = quantity_after(self, "radius") {
            return Some((PathValue::Radius(q), e));
        }
        if let Some((a, e)) = quantity_after(self, "from") {
            if let Some(e) = self.kw(self.ws(e), "to") {
                if let Some((b, e)) = self.quantity(self.ws(e)) {
                    return Some((PathValue::FromTo(a, b), e));
                }
            }
        }
        if let Some((q, e)) = quantity_after(self, "turns") {
            return Some((PathValue::Turns(q), e));
        }
        if let Some(e) = self.kw(i, "around") {
            if let Some((n, e)) = self.name(self.ws(e)) {
                return Some((PathValue::Around(n), e));
            }
        }
        if let Some((cw, e)) = self.one_of(i, DIRECTIONS) {
            return Some((PathValue::Clockwise(cw), e));
        }
        let (p, e) = self.looking_at(i)?;
        Some((p.value, e))
    }

    /// `looking_at = { kw_looking ~ kw_at ~ name }`
    fn looking_at(&mut self, i: usize) -> R<PathParam<'a>> {
        let e = self.kw(i, "looking")?;
        let e = self.kw(self.ws(e), "at")?;
        let (n, e) = self.name(self.ws(e))?;
        Some((
            PathParam {
                span: self.span(i, e),
                value: PathValue::LookingAt(n),
            },
            e,
        ))
    }

    /// `timed_entry = { entry_index ~ timecode ~ arrow ~ timecode ~ (framed_shot | hold_shot) }`
    fn timed(&mut self, i: usize) -> R<TimedEntry<'a>> {
        // entry_index = @{ ASCII_DIGIT+ ~ boundary }
        let e = self.digits(i);
        if e == i || !self.boundary(e) {
            return None;
        }
        let index = self.text(i, e);
        let j = self.ws(e);
        let e = self.timecode(j)?;
        let start = self.text(j, e);
        let j = self.ws(e);
        if !self.b[j..].starts_with(b"-->") {
            return None;
        }
        let j = self.ws(j + 3);
        let e = self.timecode(j)?;
        let end_code = self.text(j, e);
        let (body, end) = self.shot_body(self.ws(e), false)?;
        Some((
            TimedEntry {
                span: self.span(i, end),
                index,
                start,
                end: end_code,
                body,
            },
            end,
        ))
    }

    /// `timecode = @{ D+ ~ ":" ~ D+ ~ (":" ~ D+)? ~ (("," | ".") ~ D+)? }`
    fn timecode(&self, i: usize) -> Option<usize> {
        let e = self.digits(i);
        if e == i || !self.is(e, b':') {
            return None;
        }
        let mut e2 = self.digits(e + 1);
        if e2 == e + 1 {
            return None;
        }
        if self.is(e2, b':') {
            let f = self.digits(e2 + 1);
            if f > e2 + 1 {
                e2 = f;
            }
        }
        if matches!(self.peek(e2), Some(b',' | b'.')) {
            let f = self.digits(e2 + 1);
            if f > e2 + 1 {
                e2 = f;
            }
        }
        Some(e2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::{is_keyword as vocab_keyword, KEYWORDS};

    #[test]
    fn keyword_table_is_the_vocabulary() {
        for k in KEYWORDS {
            assert!(is_keyword(k.as_bytes()), "{k} missing");
        }
        let mut count = 0;
        for len in 1..=16 {
            // Every keyword of each length is found, and nothing else of that length.
            for k in KEYWORDS.iter().filter(|k| k.len() == len) {
                let mut other = k.as_bytes().to_vec();
                other[0] ^= 0x20; // flip case of the first letter (digits become other bytes)
                assert_eq!(
                    is_keyword(&other),
                    vocab_keyword(&String::from_utf8_lossy(&other))
                );
                count += 1;
            }
        }
        assert_eq!(count, KEYWORDS.len());
        assert!(!is_keyword(b"onward") && !is_keyword(b"A") && !is_keyword(b""));
    }

    #[test]
    fn no_keyword_is_a_prefix_of_another() {
        // `name` relies on this: then `keyword` matches a word exactly when the word is one.
        for a in KEYWORDS {
            for b in KEYWORDS {
                assert!(a == b || !b.starts_with(a), "{a} is a prefix of {b}");
            }
        }
    }

    #[test]
    fn word_tables_follow_the_vocabulary() {
        for (w, s) in SIZES {
            assert_eq!(Size::parse(w), Some(*s));
        }
        assert_eq!(SIZES.len(), Size::ALL.len());
        for (w, p) in PROFILES {
            assert_eq!(Profile::parse(w), Some(*p));
        }
        assert_eq!(PROFILES.len(), Profile::ALL.len());
        for (w, t) in THIRDS {
            assert_eq!(ScreenThird::parse(w), Some(*t));
        }
        for (w, m) in MOVES {
            assert_eq!(MoveKind::parse(w), Some(*m));
        }
    }
}
