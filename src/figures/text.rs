//! Text of the figures' PNGs, drawn by csm-lab from glyphs rasterised once per process.
//!
//! The SVG files keep their `<text>` elements; only rasterising them changes. usvg lays out
//! every `<text>` element of every figure anew (it parses the font's tables again per glyph and
//! builds a shaper per text) and resvg fills each text's glyph outlines as one path: the text
//! of the default sweep's five figures cost 340 M instructions, 40 % of all their drawing. Here
//! a text is shaped once per distinct string (rustybuzz, the shaper usvg uses, so glyphs,
//! advances and kerning are usvg's), and each glyph is rasterised once per size, rotation and
//! quarter-pixel position into a coverage mask (tiny_skia's anti-aliased path fill, as resvg
//! fills text) that is then blended wherever that glyph lands. Every glyph sits within an
//! eighth of a pixel of where usvg puts it; where two glyphs of a text overlap, their
//! coverages are blended one after the other instead of filled as one path.
//!
//! Only the lines plotters writes for a text are read ([`TextLine::from_lines`], a strict
//! reader); any other `<text>` element is left to usvg. The readers of plotters' numbers and
//! colours live here too, for [`super::raster`]'s shapes (which draw texts through this module,
//! never the other way round).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use resvg::tiny_skia::{FillRule, Mask, Paint, PathBuilder, PixmapMut, Transform};
use rustybuzz::ttf_parser::{GlyphId, OutlineBuilder};

/// Sub-pixel positions a glyph is rasterised at, per pixel and axis.
pub(crate) const PHASES: f32 = 4.0;

/// Where a text's reference point sits vertically: plotters' `dy` values.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Dy {
    /// `0.76em`: the top of the text at the point.
    Top,
    /// `0.5ex`: centred.
    Center,
    /// `-0.5ex`: the bottom.
    Bottom,
}

impl Dy {
    /// The baseline's offset below the point, for `size`: an em is the font size, an ex half of
    /// it (as usvg resolves `ex`).
    fn offset(self, size: f32) -> f32 {
        match self {
            Dy::Top => 0.76 * size,
            Dy::Center => 0.5 * size / 2.0,
            Dy::Bottom => -0.5 * size / 2.0,
        }
    }
}

/// The horizontal anchor (`text-anchor`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Anchor {
    Start,
    Middle,
    End,
}

/// One text as plotters writes it, in SVG units.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TextLine {
    x: f32,
    y: f32,
    dy: Dy,
    anchor: Anchor,
    size: f32,
    opacity: f32,
    rgb: [u8; 3],
    bold: bool,
    /// Quarter turns clockwise about (x, y): plotters' `rotate(90|180|270, x, y)`.
    quarter_turns: u8,
    text: String,
}

/// The value of `name="…"` at the start of `s`, and the rest after the closing quote.
fn attr<'a>(s: &'a str, name: &str) -> Option<(&'a str, &'a str)> {
    let rest = s.strip_prefix(' ')?.strip_prefix(name)?.strip_prefix("=\"")?;
    rest.split_once('"')
}

/// A colour and its opacity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rgba {
    pub(crate) rgb: [u8; 3],
    pub(crate) opacity: f32,
}

impl Rgba {
    pub(crate) fn paint(self) -> Paint<'static> {
        let mut paint = Paint::default();
        let a = (self.opacity * 255.0).round() as u8;
        paint.set_color_rgba8(self.rgb[0], self.rgb[1], self.rgb[2], a);
        paint.anti_alias = true;
        paint
    }
}

/// A finite number as plotters writes one: an integer (a pixel position; read directly) or a
/// decimal.
pub(crate) fn number(s: &str) -> Option<f32> {
    let digits = s.strip_prefix('-').unwrap_or(s);
    if !digits.is_empty() && digits.len() <= 7 && digits.bytes().all(|b| b.is_ascii_digit()) {
        let v = digits.bytes().fold(0i32, |v, b| 10 * v + i32::from(b - b'0'));
        return Some(if digits.len() < s.len() { -v } else { v } as f32);
    }
    let ok = !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit() || b == b'.' || b == b'-');
    let v: f64 = if ok { s.parse().ok()? } else { return None };
    (v.is_finite() && v.abs() < 1e7).then_some(v as f32)
}

/// `#RRGGBB` and an opacity in [0, 1].
pub(crate) fn colour(hex: &str, opacity: &str) -> Option<Rgba> {
    let hex = hex.strip_prefix('#')?;
    if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    let opacity = number(opacity)?;
    (0.0..=1.0).contains(&opacity).then_some(Rgba {
        rgb: [byte(0)?, byte(2)?, byte(4)?],
        opacity,
    })
}

/// XML text with plotters' five escapes undone; None for any other `&` form.
fn unescape(s: &str) -> Option<String> {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find('&') {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        let (c, n) = [
            ("&lt;", '<'),
            ("&gt;", '>'),
            ("&amp;", '&'),
            ("&quot;", '"'),
            ("&apos;", '\''),
        ]
        .iter()
        .find(|(e, _)| tail.starts_with(e))
        .map(|(e, c)| (*c, e.len()))?;
        out.push(c);
        rest = &tail[n..];
    }
    out.push_str(rest);
    Some(out)
}

/// What usvg makes of a text's characters with the default `xml:space`: tabs as spaces,
/// runs of spaces as one, none at either end.
fn collapse_spaces(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for word in s.split([' ', '\t']).filter(|w| !w.is_empty()) {
        if !out.is_empty() {
            out.push(' ');
        }
        out.push_str(word);
    }
    out
}

impl TextLine {
    /// The text of plotters' three lines for one: `open` exactly
    /// `<text x="X" y="Y" dy="D" text-anchor="A" font-family="sans-serif" font-size="S"
    /// opacity="O" fill="#RRGGBB"[ font-weight="bold"][ transform="rotate(R, X, Y)"]>`, then its
    /// characters on one line, then `</text>`; None for anything else (left to usvg).
    pub(crate) fn from_lines(open: &str, content: &str, close: &str) -> Option<TextLine> {
        if close != "</text>" || content.contains('<') {
            return None;
        }
        let rest = open.strip_prefix("<text")?.strip_suffix('>')?;
        let (x, rest) = attr(rest, "x")?;
        let (y, rest) = attr(rest, "y")?;
        let (dy, rest) = attr(rest, "dy")?;
        let (anchor, rest) = attr(rest, "text-anchor")?;
        let (family, rest) = attr(rest, "font-family")?;
        let (size, rest) = attr(rest, "font-size")?;
        let (opacity, rest) = attr(rest, "opacity")?;
        let (fill, mut rest) = attr(rest, "fill")?;
        let mut bold = false;
        if let Some((w, r)) = attr(rest, "font-weight") {
            if w != "bold" {
                return None;
            }
            bold = true;
            rest = r;
        }
        let (x, y) = (number(x)?, number(y)?);
        let mut quarter_turns = 0;
        if let Some((t, r)) = attr(rest, "transform") {
            let args = t.strip_prefix("rotate(")?.strip_suffix(')')?;
            let mut it = args.split(", ");
            quarter_turns = match it.next()? {
                "90" => 1,
                "180" => 2,
                "270" => 3,
                _ => return None,
            };
            // The rotation is about the text's own point, as plotters writes it.
            if number(it.next()?)? != x || number(it.next()?)? != y || it.next().is_some() {
                return None;
            }
            rest = r;
        }
        if !rest.is_empty() || family != "sans-serif" {
            return None;
        }
        let dy = match dy {
            "0.76em" => Dy::Top,
            "0.5ex" => Dy::Center,
            "-0.5ex" => Dy::Bottom,
            _ => return None,
        };
        let anchor = match anchor {
            "start" => Anchor::Start,
            "middle" => Anchor::Middle,
            "end" => Anchor::End,
            _ => return None,
        };
        let size = number(size)?;
        if !(size > 0.0 && size < 1000.0) {
            return None;
        }
        let Rgba { rgb, opacity } = colour(fill, opacity)?;
        let text = collapse_spaces(&unescape(content)?);
        // Every glyph must be in the embedded font (usvg would look for a fallback font).
        let shaped = shaped(bold, &text);
        if shaped.glyphs.iter().any(|g| g.id == 0) {
            return None;
        }
        Some(TextLine {
            x,
            y,
            dy,
            anchor,
            size,
            opacity,
            rgb,
            bold,
            quarter_turns,
            text,
        })
    }

    /// Draws the text onto `pixmap` with `transform`, a scale equal on both axes (and a shift);
    /// its `sx` is the pixels per SVG unit.
    pub(crate) fn draw(&self, transform: Transform, pixmap: &mut PixmapMut) {
        let scale = transform.sx;
        let shaped = shaped(self.bold, &self.text);
        let font = font(self.bold);
        let k = self.size / f32::from(font.upem);
        let width = shaped.advance as f32 * k;
        let start = match self.anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => -width / 2.0,
            Anchor::End => -width,
        };
        let base = self.dy.offset(self.size);
        // (cos, sin) of the clockwise rotation on the page (y down).
        let (c, s) = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][usize::from(self.quarter_turns)];
        let px = scale * self.size;
        let mut pen = 0i32;
        for g in &shaped.glyphs {
            // The glyph's origin before the rotation, relative to (x, y).
            let u = start + (pen + g.dx) as f32 * k;
            let v = base - g.dy as f32 * k;
            pen += g.advance;
            let ox = transform.tx + scale * (self.x + u * c - v * s);
            let oy = transform.ty + scale * (self.y + u * s + v * c);
            let (fx, phx) = split_phase(ox);
            let (fy, phy) = split_phase(oy);
            let key = GlyphKey {
                bold: self.bold,
                id: g.id,
                px: px.to_bits(),
                quarter_turns: self.quarter_turns,
                phase: (phx, phy),
            };
            if let Some(m) = glyph_mask(key) {
                m.blend(fx, fy, self.rgb, self.opacity, pixmap);
            }
        }
    }
}

/// A position in pixels as its whole pixel and its nearest quarter (0 to 3) past it.
pub(crate) fn split_phase(v: f32) -> (i32, u8) {
    let q = (v * PHASES).round();
    let whole = (q / PHASES).floor();
    (whole as i32, (q - whole * PHASES) as u8)
}

/// A font's shaper and size.
struct Font {
    face: rustybuzz::Face<'static>,
    upem: u16,
}

fn font(bold: bool) -> &'static Font {
    static FONTS: OnceLock<[Font; 2]> = OnceLock::new();
    let fonts = FONTS.get_or_init(|| {
        let load = |data: &'static [u8]| {
            let face = rustybuzz::Face::from_slice(data, 0).expect("the embedded DejaVu font parses");
            let upem = face.units_per_em() as u16;
            Font { face, upem }
        };
        [load(dejavu::sans::regular()), load(dejavu::sans::bold())]
    });
    &fonts[usize::from(bold)]
}

/// One shaped glyph, in font units.
#[derive(Debug, Clone, Copy)]
struct ShapedGlyph {
    id: u16,
    advance: i32,
    dx: i32,
    dy: i32,
}

/// A text's glyphs and its whole advance, in font units.
#[derive(Debug)]
struct Shaped {
    glyphs: Vec<ShapedGlyph>,
    advance: i32,
}

/// `text` shaped with the regular or bold face (left to right, the font's default features,
/// as usvg shapes it), once per process.
fn shaped(bold: bool, text: &str) -> Arc<Shaped> {
    static CACHE: Memo<(bool, String), Arc<Shaped>> = OnceLock::new();
    memo(&CACHE, (bold, text.to_string()), || {
        let mut buffer = rustybuzz::UnicodeBuffer::new();
        buffer.push_str(text);
        buffer.set_direction(rustybuzz::Direction::LeftToRight);
        let out = rustybuzz::shape(&font(bold).face, &[], buffer);
        let glyphs: Vec<ShapedGlyph> = out
            .glyph_infos()
            .iter()
            .zip(out.glyph_positions())
            .map(|(i, p)| ShapedGlyph {
                id: i.glyph_id as u16,
                advance: p.x_advance,
                dx: p.x_offset,
                dy: p.y_offset,
            })
            .collect();
        let advance = glyphs.iter().map(|g| g.advance).sum();
        Arc::new(Shaped { glyphs, advance })
    })
}

/// A process-wide cache: values made once per key, shared by every thread.
pub(crate) type Memo<K, V> = OnceLock<Mutex<HashMap<K, V>>>;

/// The value of `key` in `cache`, made by `make` the first time. `make` runs outside the lock
/// (two threads may both make a value; the first stored is kept, and both are equal).
pub(crate) fn memo<K: std::hash::Hash + Eq, V: Clone>(
    cache: &'static Memo<K, V>,
    key: K,
    make: impl FnOnce() -> V,
) -> V {
    let cache = cache.get_or_init(Default::default);
    if let Some(v) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return v.clone();
    }
    let v = make();
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .entry(key)
        .or_insert(v)
        .clone()
}

/// What a glyph's coverage mask depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct GlyphKey {
    bold: bool,
    id: u16,
    /// The font size in pixels (f32 bits).
    px: u32,
    quarter_turns: u8,
    /// The origin's quarter-pixel position past the whole pixel, (x, y).
    phase: (u8, u8),
}

/// A glyph's (or a dot's) anti-aliased coverage, placed `left`, `top` pixels from its origin's
/// whole pixel.
#[derive(Debug)]
pub(crate) struct Coverage {
    pub(crate) left: i32,
    pub(crate) top: i32,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) coverage: Vec<u8>,
}

/// The glyph's outline as a tiny_skia path, in font units.
struct Outline(PathBuilder);

impl OutlineBuilder for Outline {
    fn move_to(&mut self, x: f32, y: f32) {
        self.0.move_to(x, y);
    }
    fn line_to(&mut self, x: f32, y: f32) {
        self.0.line_to(x, y);
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        self.0.quad_to(x1, y1, x, y);
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        self.0.cubic_to(x1, y1, x2, y2, x, y);
    }
    fn close(&mut self) {
        self.0.close();
    }
}

/// The glyph of `key` rasterised (once per process); None for a glyph with no outline (a space).
fn glyph_mask(key: GlyphKey) -> Option<Arc<Coverage>> {
    static CACHE: Memo<GlyphKey, Option<Arc<Coverage>>> = OnceLock::new();
    memo(&CACHE, key, || rasterise(key).map(Arc::new))
}

fn rasterise(key: GlyphKey) -> Option<Coverage> {
    let font = font(key.bold);
    let mut outline = Outline(PathBuilder::new());
    let bbox = font.face.outline_glyph(GlyphId(key.id), &mut outline)?;
    let path = outline.0.finish()?;
    let k = f32::from_bits(key.px) / f32::from(font.upem);
    let (c, s) = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][usize::from(key.quarter_turns)];
    let (phx, phy) = (f32::from(key.phase.0) / PHASES, f32::from(key.phase.1) / PHASES);
    // Font units (y up) to pixels relative to the origin's whole pixel: scale, flip, rotate
    // clockwise on the page, shift by the phase.
    let glyph = Transform::from_row(k * c, k * s, k * s, -k * c, phx, phy);
    let corners = [
        (bbox.x_min, bbox.y_min),
        (bbox.x_min, bbox.y_max),
        (bbox.x_max, bbox.y_min),
        (bbox.x_max, bbox.y_max),
    ]
    .map(|(x, y)| {
        let mut p = [resvg::tiny_skia::Point::from_xy(f32::from(x), f32::from(y))];
        glyph.map_points(&mut p);
        p[0]
    });
    let min_x = corners.iter().map(|p| p.x).fold(f32::INFINITY, f32::min);
    let max_x = corners.iter().map(|p| p.x).fold(f32::NEG_INFINITY, f32::max);
    let min_y = corners.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    let max_y = corners.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max);
    let (left, top) = (min_x.floor() as i32 - 1, min_y.floor() as i32 - 1);
    let (width, height) = (
        (max_x.ceil() as i32 + 1 - left) as u32,
        (max_y.ceil() as i32 + 1 - top) as u32,
    );
    let mut mask = Mask::new(width, height)?;
    mask.fill_path(
        &path,
        FillRule::Winding,
        true,
        glyph.post_translate(-left as f32, -top as f32),
    );
    Some(Coverage {
        left,
        top,
        width,
        height,
        coverage: mask.data().to_vec(),
    })
}

impl Coverage {
    /// Blends `rgb` at `opacity` through the coverage onto `pixmap` (premultiplied RGBA,
    /// source-over), the origin's whole pixel at (x, y).
    pub(crate) fn blend(&self, x: i32, y: i32, rgb: [u8; 3], opacity: f32, pixmap: &mut PixmapMut) {
        let (x0, y0) = (x + self.left, y + self.top);
        let (pw, ph) = (pixmap.width() as i32, pixmap.height() as i32);
        let data = pixmap.data_mut();
        let o = (opacity * 255.0).round() as u32;
        for j in 0..self.height as i32 {
            let y = y0 + j;
            if y < 0 || y >= ph {
                continue;
            }
            let row = &self.coverage[(j as usize) * self.width as usize..][..self.width as usize];
            for (i, &m) in row.iter().enumerate() {
                let x = x0 + i as i32;
                if m == 0 || x < 0 || x >= pw {
                    continue;
                }
                let a = div255(u32::from(m) * o);
                let p = 4 * (y as usize * pw as usize + x as usize);
                let px = &mut data[p..p + 4];
                for (d, s) in px.iter_mut().zip([rgb[0], rgb[1], rgb[2], 255]) {
                    *d = div255(u32::from(s) * a + u32::from(*d) * (255 - a)) as u8;
                }
            }
        }
    }
}

/// `v / 255` rounded, for `v` up to 255².
pub(crate) fn div255(v: u32) -> u32 {
    (v + 128 + ((v + 128) >> 8)) >> 8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div255_rounds_like_the_exact_quotient() {
        for v in 0..=255 * 255u32 {
            assert_eq!(div255(v), (f64::from(v) / 255.0).round() as u32, "{v}");
        }
    }

    #[test]
    fn plotters_text_lines_are_read_and_others_left_to_usvg() {
        let open = r##"<text x="140" y="96" dy="0.76em" text-anchor="middle" font-family="sans-serif" font-size="13.5" opacity="1" fill="#C80000" transform="rotate(270, 140, 96)">"##;
        let t = TextLine::from_lines(open, "a  &lt;b&gt; &amp; λ² ", "</text>").unwrap();
        assert_eq!(
            t,
            TextLine {
                x: 140.0,
                y: 96.0,
                dy: Dy::Top,
                anchor: Anchor::Middle,
                size: 13.5,
                opacity: 1.0,
                rgb: [0xC8, 0, 0],
                bold: false,
                quarter_turns: 3,
                text: "a <b> & λ²".to_string(),
            }
        );
        let plain = r##"<text x="1" y="2" dy="0.5ex" text-anchor="end" font-family="sans-serif" font-size="10" opacity="1" fill="#000000">"##;
        assert!(TextLine::from_lines(plain, "10", "</text>").is_some());
        for (open, content) in [
            // another family, a rotation about another point, an unknown dy, extra attributes
            (plain.replace("sans-serif", "serif"), "10"),
            (plain.replace("\">", "\" transform=\"rotate(90, 5, 2)\">"), "10"),
            (plain.replace("0.5ex", "1em"), "10"),
            (plain.replace("\">", "\" font-style=\"italic\">"), "10"),
            (plain.replace("fill=\"#000000\"", "fill=\"black\""), "10"),
            // an entity plotters never writes, a character DejaVu Sans lacks
            (plain.to_string(), "&#x41;"),
            (plain.to_string(), "漢字"),
        ] {
            assert_eq!(
                TextLine::from_lines(&open, content, "</text>"),
                None,
                "{open} {content}"
            );
        }
    }

    #[test]
    fn phases_split_a_position_into_its_pixel_and_nearest_quarter() {
        assert_eq!(split_phase(10.0), (10, 0));
        assert_eq!(split_phase(10.3), (10, 1));
        assert_eq!(split_phase(10.49), (10, 2));
        assert_eq!(split_phase(10.9), (11, 0));
        assert_eq!(split_phase(-0.3), (-1, 3));
    }

    /// The text drawn alone by usvg and resvg, RGBA.
    fn usvg_text(open: &str, text: &str, (w, h): (u32, u32)) -> Vec<u8> {
        let svg = format!(
            "<svg width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" xmlns=\"http://www.w3.org/2000/svg\">\n{open}\n{text}\n</text>\n</svg>\n"
        );
        let tree = resvg::usvg::Tree::from_data(svg.as_bytes(), &super::super::usvg_options()).unwrap();
        let mut pixmap = resvg::tiny_skia::Pixmap::new(w, h).unwrap();
        pixmap.fill(resvg::tiny_skia::Color::WHITE);
        resvg::render(&tree, Transform::identity(), &mut pixmap.as_mut());
        pixmap.take()
    }

    #[test]
    fn text_lands_where_usvg_draws_it_in_every_anchor_and_rotation() {
        // Ink (darkness) per text: its total, its centroid and the box of inked pixels, ours
        // against usvg's.
        let ink = |rgba: &[u8], w: u32| {
            let (mut sum, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
            let mut bx = [u32::MAX, u32::MAX, 0, 0];
            for (i, p) in rgba.chunks(4).enumerate() {
                let (x, y) = (i as u32 % w, i as u32 / w);
                let d = f64::from(255 - p[0]);
                if p[0] < 128 {
                    bx = [bx[0].min(x), bx[1].min(y), bx[2].max(x), bx[3].max(y)];
                }
                sum += d;
                sx += d * f64::from(x);
                sy += d * f64::from(y);
            }
            (sum, sx / sum, sy / sum, bx)
        };
        let (w, h) = (320u32, 320u32);
        for (dy, anchor, turn) in [
            ("0.76em", "middle", ""),
            ("0.5ex", "end", ""),
            ("-0.5ex", "start", ""),
            ("0.76em", "middle", " transform=\"rotate(270, 160, 150)\""),
            ("0.76em", "start", " transform=\"rotate(90, 160, 150)\""),
        ] {
            for text in ["Aliasing over λ × cascades: AVAWAY", "0.25"] {
                let open = format!(
                    "<text x=\"160\" y=\"150\" dy=\"{dy}\" text-anchor=\"{anchor}\" font-family=\"sans-serif\" font-size=\"12.903225806451614\" opacity=\"1\" fill=\"#000000\"{turn}>"
                );
                let line = TextLine::from_lines(&open, text, "</text>").unwrap();
                let mut ours = resvg::tiny_skia::Pixmap::new(w, h).unwrap();
                ours.fill(resvg::tiny_skia::Color::WHITE);
                line.draw(Transform::identity(), &mut ours.as_mut());
                let theirs = usvg_text(&open, text, (w, h));
                let (a, b) = (ink(ours.data(), w), ink(&theirs, w));
                let at = format!("{text} {dy} {anchor}{turn}: {a:?} vs {b:?}");
                assert!((a.0 / b.0 - 1.0).abs() < 0.03, "ink {at}");
                assert!((a.1 - b.1).abs() < 1.0 && (a.2 - b.2).abs() < 1.0, "centroid {at}");
                assert!(a.3.iter().zip(b.3).all(|(p, q)| p.abs_diff(q) <= 1), "box {at}");
            }
        }
    }
}
