//! SVG to PNG with `resvg`, text set in the embedded DejaVu Sans (regular and bold subsets,
//! `compiler/assets/`, licence next to them): no system font is read, so a fresh machine
//! renders the same pixels, and the PNG bytes are deterministic.

use std::io;

use resvg::{tiny_skia, usvg};

use super::svg::{Anchor, Svg, FONT_FAMILY};

const REGULAR: &[u8] = include_bytes!("../assets/DejaVuSans-subset.ttf");
const BOLD: &[u8] = include_bytes!("../assets/DejaVuSans-Bold-subset.ttf");

/// Largest PNG side drawn, in pixels (a very long script makes a tall storyboard; beyond this
/// the PNG is scaled down, the SVG keeps everything).
const MAX_SIDE_PX: f64 = 16_000.0;

/// The PNG of an SVG document (one pixel per SVG unit, on white), text set in the embedded
/// fonts. For one document; [`super::write_previews`] loads the fonts once for all four.
pub fn svg_to_png(svg: &str) -> io::Result<Vec<u8>> {
    Rasteriser::new().png(svg)
}

/// Parsing options with the embedded fonts loaded once.
pub struct Rasteriser {
    options: usvg::Options<'static>,
}

impl Default for Rasteriser {
    fn default() -> Rasteriser {
        Rasteriser::new()
    }
}

impl Rasteriser {
    pub fn new() -> Rasteriser {
        let mut options = usvg::Options {
            font_family: FONT_FAMILY.to_string(),
            ..usvg::Options::default()
        };
        let db = options.fontdb_mut();
        db.load_font_data(REGULAR.to_vec());
        db.load_font_data(BOLD.to_vec());
        db.set_sans_serif_family(FONT_FAMILY);
        db.set_serif_family(FONT_FAMILY);
        db.set_monospace_family(FONT_FAMILY);
        Rasteriser { options }
    }

    /// An SVG document parsed with the embedded fonts: its text laid out as the PNG sets it.
    pub fn parse(&self, svg: &str) -> io::Result<usvg::Tree> {
        usvg::Tree::from_str(svg, &self.options)
            .map_err(|e| io::Error::other(format!("preview: SVG not rasterised: {e}")))
    }

    /// The box `[left, top, right, bottom]` `text` takes set at `size` px about its anchor
    /// (the middle of its baseline), as [`Svg::text_styled`] sets it (bold or not, with a
    /// white halo or none): its glyphs (and halo) as the PNG draws them. `None` for text with
    /// no glyph.
    pub fn text_box(&self, text: &str, size: f64, bold: bool, halo: bool) -> Option<[f64; 4]> {
        // Far enough from the page's edges for any line to fit.
        let (x, y) = (4000.0, 400.0);
        let mut svg = Svg::new(2.0 * x, 2.0 * y);
        let halo = halo.then_some("#ffffff");
        svg.text_styled(x, y, size, Anchor::Middle, "#000000", bold, 0.0, halo, text);
        let tree = self.parse(&svg.finish()).ok()?;
        tree.root().children().iter().find_map(|n| match n {
            usvg::Node::Text(t) => {
                let b = t.abs_stroke_bounding_box();
                let f = |v: f32| f64::from(v);
                Some([
                    f(b.left()) - x,
                    f(b.top()) - y,
                    f(b.right()) - x,
                    f(b.bottom()) - y,
                ])
            }
            _ => None,
        })
    }

    /// The PNG of an SVG document, at one pixel per SVG unit, on white.
    pub fn png(&self, svg: &str) -> io::Result<Vec<u8>> {
        let tree = self.parse(svg)?;
        let size = tree.size();
        let (w, h) = (size.width() as f64, size.height() as f64);
        let scale = (MAX_SIDE_PX / w.max(h)).min(1.0);
        let (pw, ph) = (
            (w * scale).ceil().max(1.0) as u32,
            (h * scale).ceil().max(1.0) as u32,
        );
        let mut pixmap = tiny_skia::Pixmap::new(pw, ph)
            .ok_or_else(|| io::Error::other(format!("preview: no {pw}×{ph} pixmap")))?;
        pixmap.fill(tiny_skia::Color::WHITE);
        resvg::render(
            &tree,
            tiny_skia::Transform::from_scale(scale as f32, scale as f32),
            &mut pixmap.as_mut(),
        );
        pixmap
            .encode_png()
            .map_err(|e| io::Error::other(format!("preview: PNG not encoded: {e}")))
    }
}
