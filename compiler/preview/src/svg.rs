//! A small, deterministic SVG writer: the elements the previews need, with coordinates
//! rounded to 0.01 px, text escaped, and any element with a non-finite coordinate left out
//! (a NaN in the reference must not produce an unparsable file).

use std::fmt::Write as _;

/// The font every preview names; the rasteriser embeds it (`assets/DejaVuSans-subset.ttf`).
pub const FONT_FAMILY: &str = "DejaVu Sans";

/// A number for an SVG attribute: two decimals, trailing zeros trimmed, never `-0`.
pub fn num(v: f64) -> String {
    let r = (v * 100.0).round() / 100.0;
    let r = if r == 0.0 { 0.0 } else { r };
    let mut s = format!("{r:.2}");
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    s
}

/// Text content or attribute value with XML's special characters escaped. Control characters
/// (not allowed in XML 1.0) become spaces.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

fn finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// Text anchor (horizontal alignment of a text element).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    fn as_str(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// Stroke and fill of a shape, written as presentation attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    pub stroke: Option<String>,
    pub stroke_width: f64,
    pub fill: Option<String>,
    pub dash: Option<String>,
    pub opacity: f64,
}

impl Style {
    pub fn stroke(color: &str, width: f64) -> Style {
        Style {
            stroke: Some(color.to_string()),
            stroke_width: width,
            fill: None,
            dash: None,
            opacity: 1.0,
        }
    }

    pub fn fill(color: &str) -> Style {
        Style {
            stroke: None,
            stroke_width: 0.0,
            fill: Some(color.to_string()),
            dash: None,
            opacity: 1.0,
        }
    }

    pub fn with_fill(mut self, color: &str) -> Style {
        self.fill = Some(color.to_string());
        self
    }

    pub fn dashed(mut self, pattern: &str) -> Style {
        self.dash = Some(pattern.to_string());
        self
    }

    pub fn opacity(mut self, opacity: f64) -> Style {
        self.opacity = opacity;
        self
    }

    fn write(&self, out: &mut String) {
        match &self.fill {
            Some(f) => {
                let _ = write!(out, " fill=\"{}\"", escape(f));
            }
            None => out.push_str(" fill=\"none\""),
        }
        if let Some(s) = &self.stroke {
            let _ = write!(
                out,
                " stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\" stroke-linecap=\"round\"",
                escape(s),
                num(self.stroke_width)
            );
        }
        if let Some(d) = &self.dash {
            let _ = write!(out, " stroke-dasharray=\"{}\"", escape(d));
        }
        if self.opacity < 1.0 {
            let _ = write!(out, " opacity=\"{}\"", num(self.opacity));
        }
    }
}

/// An SVG document being written, `width × height` px, white background.
pub struct Svg {
    pub width: f64,
    pub height: f64,
    body: String,
    defs: String,
    next_id: usize,
}

impl Svg {
    pub fn new(width: f64, height: f64) -> Svg {
        Svg {
            width: width.max(1.0).round(),
            height: height.max(1.0).round(),
            body: String::new(),
            defs: String::new(),
            next_id: 0,
        }
    }

    /// The finished document.
    pub fn finish(&self) -> String {
        let mut out = String::with_capacity(self.body.len() + self.defs.len() + 512);
        let _ = write!(
            out,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" \
             width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"{FONT_FAMILY}\">\n",
            w = num(self.width),
            h = num(self.height)
        );
        if !self.defs.is_empty() {
            out.push_str("<defs>\n");
            out.push_str(&self.defs);
            out.push_str("</defs>\n");
        }
        let _ = writeln!(
            out,
            "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>",
            num(self.width),
            num(self.height)
        );
        out.push_str(&self.body);
        out.push_str("</svg>\n");
        out
    }

    /// A comment (for people reading the SVG), with `--` made harmless.
    pub fn comment(&mut self, text: &str) {
        let _ = writeln!(self.body, "<!-- {} -->", text.replace("--", "- -"));
    }

    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, style: &Style) {
        if !finite(&[x, y, w, h]) || w < 0.0 || h < 0.0 {
            return;
        }
        let _ = write!(
            self.body,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"",
            num(x),
            num(y),
            num(w),
            num(h)
        );
        style.write(&mut self.body);
        self.body.push_str("/>\n");
    }

    pub fn line(&mut self, x1: f64, y1: f64, x2: f64, y2: f64, style: &Style) {
        if !finite(&[x1, y1, x2, y2]) {
            return;
        }
        let _ = write!(
            self.body,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"",
            num(x1),
            num(y1),
            num(x2),
            num(y2)
        );
        style.write(&mut self.body);
        self.body.push_str("/>\n");
    }

    pub fn circle(&mut self, cx: f64, cy: f64, r: f64, style: &Style) {
        if !finite(&[cx, cy, r]) || r <= 0.0 {
            return;
        }
        let _ = write!(
            self.body,
            "<circle cx=\"{}\" cy=\"{}\" r=\"{}\"",
            num(cx),
            num(cy),
            num(r)
        );
        style.write(&mut self.body);
        self.body.push_str("/>\n");
    }

    /// An open polyline; non-finite points split it into separate pieces.
    pub fn polyline(&mut self, points: &[[f64; 2]], style: &Style) {
        for piece in points.split(|p| !finite(p)) {
            if piece.len() < 2 {
                continue;
            }
            self.body.push_str("<polyline points=\"");
            for (i, p) in piece.iter().enumerate() {
                if i > 0 {
                    self.body.push(' ');
                }
                let _ = write!(self.body, "{},{}", num(p[0]), num(p[1]));
            }
            self.body.push('"');
            style.write(&mut self.body);
            self.body.push_str("/>\n");
        }
    }

    /// A closed polygon; left out if any point is not finite.
    pub fn polygon(&mut self, points: &[[f64; 2]], style: &Style) {
        if points.len() < 3 || !points.iter().all(|p| finite(p)) {
            return;
        }
        self.body.push_str("<polygon points=\"");
        for (i, p) in points.iter().enumerate() {
            if i > 0 {
                self.body.push(' ');
            }
            let _ = write!(self.body, "{},{}", num(p[0]), num(p[1]));
        }
        self.body.push('"');
        style.write(&mut self.body);
        self.body.push_str("/>\n");
    }

    /// Text at (x, y) (the baseline), `size` px.
    pub fn text(&mut self, x: f64, y: f64, size: f64, anchor: Anchor, color: &str, text: &str) {
        self.text_styled(x, y, size, anchor, color, false, 0.0, None, text);
    }

    /// Bold text.
    pub fn text_bold(
        &mut self,
        x: f64,
        y: f64,
        size: f64,
        anchor: Anchor,
        color: &str,
        text: &str,
    ) {
        self.text_styled(x, y, size, anchor, color, true, 0.0, None, text);
    }

    /// Bold text with a white halo (an outline under the glyphs) that keeps it legible over
    /// lines.
    pub fn text_halo(
        &mut self,
        x: f64,
        y: f64,
        size: f64,
        anchor: Anchor,
        color: &str,
        text: &str,
    ) {
        self.text_styled(x, y, size, anchor, color, true, 0.0, Some("#ffffff"), text);
    }

    /// Text turned by `rotate_deg` about its anchor point (e.g. −90 for a vertical axis
    /// label), optionally with a halo.
    #[allow(clippy::too_many_arguments)]
    pub fn text_styled(
        &mut self,
        x: f64,
        y: f64,
        size: f64,
        anchor: Anchor,
        color: &str,
        bold: bool,
        rotate_deg: f64,
        halo: Option<&str>,
        text: &str,
    ) {
        if !finite(&[x, y, size, rotate_deg]) || text.is_empty() {
            return;
        }
        let _ = write!(
            self.body,
            "<text x=\"{}\" y=\"{}\" font-size=\"{}\" text-anchor=\"{}\" fill=\"{}\"",
            num(x),
            num(y),
            num(size),
            anchor.as_str(),
            escape(color)
        );
        if bold {
            self.body.push_str(" font-weight=\"bold\"");
        }
        if let Some(halo) = halo {
            let _ = write!(
                self.body,
                " stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\" paint-order=\"stroke\"",
                escape(halo),
                num(size * 0.25)
            );
        }
        if rotate_deg != 0.0 {
            let _ = write!(
                self.body,
                " transform=\"rotate({} {} {})\"",
                num(rotate_deg),
                num(x),
                num(y)
            );
        }
        let _ = writeln!(self.body, ">{}</text>", escape(text));
    }

    /// Defines a rectangular clip path and returns its id (for [`Svg::begin_group`]).
    pub fn clip_rect(&mut self, x: f64, y: f64, w: f64, h: f64) -> String {
        let (x, y, w, h) = (num(x), num(y), num(w.max(0.0)), num(h.max(0.0)));
        self.clip(&format!(
            "<rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\"/>"
        ))
    }

    /// Defines a circular clip path and returns its id (for [`Svg::begin_group`]).
    pub fn clip_circle(&mut self, cx: f64, cy: f64, r: f64) -> String {
        let (cx, cy, r) = (num(cx), num(cy), num(r.max(0.0)));
        self.clip(&format!("<circle cx=\"{cx}\" cy=\"{cy}\" r=\"{r}\"/>"))
    }

    /// Defines a clip path of `shape` (an SVG element) and returns its id.
    fn clip(&mut self, shape: &str) -> String {
        let id = format!("clip{}", self.next_id);
        self.next_id += 1;
        let _ = writeln!(self.defs, "<clipPath id=\"{id}\">{shape}</clipPath>");
        id
    }

    /// Opens a group named `id` (an id a reader of the SVG finds it by), clipped when `clip`
    /// names a clip path.
    pub fn begin_named_group(&mut self, id: &str, clip: Option<&str>) {
        let _ = write!(self.body, "<g id=\"{}\"", escape(id));
        if let Some(c) = clip {
            let _ = write!(self.body, " clip-path=\"url(#{c})\"");
        }
        self.body.push_str(">\n");
    }

    /// Opens a group, clipped when `clip` names a clip path.
    pub fn begin_group(&mut self, clip: Option<&str>) {
        match clip {
            Some(id) => {
                let _ = writeln!(self.body, "<g clip-path=\"url(#{id})\">");
            }
            None => self.body.push_str("<g>\n"),
        }
    }

    pub fn end_group(&mut self) {
        self.body.push_str("</g>\n");
    }
}

/// A rough width of `text` at `size` px in DejaVu Sans (average advance ≈ 0.6 em), for layout
/// and truncation (the exact glyph widths are the rasteriser's business).
pub fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * 0.6
}

/// `text` cut to fit `max_width` px at `size`, with an ellipsis when cut.
pub fn truncate(text: &str, size: f64, max_width: f64) -> String {
    let max_chars = (max_width / (size * 0.6)).floor().max(1.0) as usize;
    if text.chars().count() <= max_chars {
        return text.to_string();
    }
    let mut s: String = text.chars().take(max_chars.saturating_sub(1)).collect();
    s.push('…');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_never_negative_zero() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-0.001), "0");
        assert_eq!(num(2.345), "2.35");
        assert_eq!(num(-12.5), "-12.5");
    }

    #[test]
    fn text_is_escaped_and_non_finite_elements_dropped() {
        let mut svg = Svg::new(10.0, 10.0);
        svg.text(1.0, 2.0, 10.0, Anchor::Start, "#000", "a<b & \"c\"\u{1}");
        svg.line(0.0, f64::NAN, 1.0, 1.0, &Style::stroke("#000", 1.0));
        svg.polyline(
            &[
                [0.0, 0.0],
                [1.0, 1.0],
                [f64::NAN, 0.0],
                [2.0, 2.0],
                [3.0, 3.0],
            ],
            &Style::stroke("#000", 1.0),
        );
        let out = svg.finish();
        assert!(out.contains("a&lt;b &amp; &quot;c&quot; </text>"), "{out}");
        assert!(!out.contains("<line"));
        assert_eq!(out.matches("<polyline").count(), 2);
        assert!(!out.contains("NaN"));
    }

    #[test]
    fn truncation_keeps_short_text_and_marks_cuts() {
        assert_eq!(truncate("MS on A", 10.0, 1000.0), "MS on A");
        let cut = truncate("a very long line of PSL text", 10.0, 60.0);
        assert_eq!(cut.chars().count(), 10);
        assert!(cut.ends_with('…'));
    }
}
