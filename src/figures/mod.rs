//! Charts. A [`Figure`] draws itself on any plotters backend, so the same code yields the SVG
//! (for reports, the README and docs/) and the PNG (for slides). Text is laid out with an embedded
//! DejaVu Sans font, so nothing depends on the fonts installed on the machine.
//!
//! This module holds what every figure shares: the font, SVG and PNG encoding, the palette,
//! axes and legend helpers. Each command's figures live in their own submodule.

pub mod analyze;
pub(crate) mod bench;
pub(crate) mod compare;
pub(crate) mod plan;
pub(crate) mod raster;
pub(crate) mod rects;
pub(crate) mod screen;
pub(crate) mod sun;
pub(crate) mod sweep;
pub(crate) mod text;
pub mod truth;
pub(crate) mod views;

use std::sync::Once;

use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::combinators::{BindKeyPoints, LogCoord, WithKeyPoints};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::{DynElement, IntoDynElement};

/// A pixel position on a backend.
type BackendCoord = (i32, i32);
use plotters::prelude::*;

use crate::error::{PlotError, Result};

pub(crate) const FONT: &str = "sans-serif";

/// The width a report page shows a figure at, in pixels: a figure wider than this is scaled
/// down by the browser, so its text is drawn larger by [`legible_scale`].
pub(crate) const PAGE_WIDTH: u32 = 1280;

/// How much larger than its nominal size a figure `width` pixels wide draws its text, so that
/// the text is as legible at [`PAGE_WIDTH`] as a figure of that width's (1 up to that width).
pub(crate) fn legible_scale(width: u32) -> f64 {
    (f64::from(width) / f64::from(PAGE_WIDTH)).max(1.0)
}

/// `size` scaled by `k` ([`legible_scale`]), in whole pixels (rounded up, so the text is never
/// smaller than its nominal size at the page's width).
pub(crate) fn scaled(size: u32, k: f64) -> u32 {
    (f64::from(size) * k).ceil() as u32
}

/// The font size of every legend.
pub(crate) const LEGEND_FONT: u32 = 13;

/// Registers the embedded font with plotters (once per process).
pub(crate) fn init_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// A drawing error from any backend, as text.
#[derive(Debug)]
pub struct DrawError(pub String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        DrawError(e.to_string())
    }
}

pub(crate) type PlotResult = std::result::Result<(), DrawError>;

/// Something that can be drawn.
pub trait Figure {
    fn size(&self) -> (u32, u32) {
        (960, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult;

    fn to_svg(&self) -> Result<Vec<u8>> {
        init_fonts();
        let mut s = String::new();
        {
            let root = SVGBackend::with_string(&mut s, self.size()).into_drawing_area();
            root.fill(&WHITE).map_err(|e| PlotError::Draw(e.to_string()))?;
            self.draw(&root).map_err(|e| PlotError::Draw(e.0))?;
            root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
        }
        Ok(rects::splice(s).into_bytes())
    }

    /// The SVG rasterised at the size a report page shows it ([`png_scale`]). Going through
    /// the SVG keeps one drawing path, so the PNG shows exactly what the SVG shows.
    fn to_png(&self) -> Result<Vec<u8>> {
        let tree = ParsedSvg::parse(&self.to_svg()?)?;
        tree.png(png_scale(tree.size()))
    }
}

/// The most pixels a figure's PNG file has (give or take a row and a column of rounding): 8
/// million (32 MB while it is rasterised, RGBA). Only a figure both wider than a page and very
/// tall reaches it.
pub(crate) const MAX_PNG_PIXELS: f32 = 8.0e6;

/// PNG pixels per SVG unit for a figure of `size` (SVG units): the size a report page shows it
/// at, i.e. its own size (1), or [`PAGE_WIDTH`] pixels wide when it is wider (figures that
/// wide draw their text larger for that, [`legible_scale`]), and less if that would pass
/// [`MAX_PNG_PIXELS`]. One raster then serves both the PNG file and a page's inlined copy, and
/// the memory of rasterising a figure stays bounded at any grid size.
pub(crate) fn png_scale(size: (f32, f32)) -> f32 {
    let page = (PAGE_WIDTH as f32 / size.0).min(1.0);
    let area = size.0 * size.1 * page * page;
    if area <= MAX_PNG_PIXELS {
        page
    } else {
        page * (MAX_PNG_PIXELS / area).sqrt()
    }
}

/// The font database resvg lays text out with: the embedded DejaVu faces, also answering
/// for the generic `sans-serif` family that the SVGs name.
fn font_db() -> std::sync::Arc<resvg::usvg::fontdb::Database> {
    static DB: std::sync::OnceLock<std::sync::Arc<resvg::usvg::fontdb::Database>> = std::sync::OnceLock::new();
    DB.get_or_init(|| {
        let mut db = resvg::usvg::fontdb::Database::new();
        db.load_font_data(dejavu::sans::regular().to_vec());
        db.load_font_data(dejavu::sans::bold().to_vec());
        db.set_sans_serif_family("DejaVu Sans");
        std::sync::Arc::new(db)
    })
    .clone()
}

/// The options resvg parses an SVG with: the embedded fonts.
fn usvg_options() -> resvg::usvg::Options<'static> {
    resvg::usvg::Options {
        font_family: "DejaVu Sans".to_string(),
        fontdb: font_db(),
        ..Default::default()
    }
}

/// An SVG document ready to rasterise. plotters' SVG (one element per line) is read by
/// csm-lab and drawn directly ([`raster::Shape`], [`text::TextLine`]): parsing it with usvg,
/// laying out every text again and parsing the font per glyph, was a third of rasterising a
/// chart. A line csm-lab does not read, and any other document (the screen pictures'
/// legends), is parsed by usvg and drawn by resvg, in document order between the shapes.
pub(crate) struct ParsedSvg {
    /// The document's size in its own units.
    size: (f32, f32),
    parts: Vec<SvgPart>,
}

/// A piece of a [`ParsedSvg`], drawn in order.
enum SvgPart {
    /// Elements parsed by usvg (the document's header and its own elements).
    Tree(Box<resvg::usvg::Tree>),
    /// Elements drawn directly.
    Shapes(Vec<raster::Shape>),
}

/// The size plotters writes in its header line,
/// `<svg width="W" height="H" viewBox="0 0 W H" xmlns="http://www.w3.org/2000/svg">`.
fn plotters_header_size(header: &str) -> Option<(f32, f32)> {
    let rest = header.strip_prefix("<svg width=\"")?;
    let (w, rest) = rest.split_once("\" height=\"")?;
    let (h, rest) = rest.split_once('"')?;
    if rest != format!(" viewBox=\"0 0 {w} {h}\" xmlns=\"http://www.w3.org/2000/svg\">") {
        return None;
    }
    let (w, h): (u32, u32) = (w.parse().ok()?, h.parse().ok()?);
    (w > 0 && h > 0).then_some((w as f32, h as f32))
}

/// A piece of plotters' SVG in document order: lines to parse (a document of the header, the
/// lines and the closing tag) or shapes read directly.
enum Piece {
    Svg(String),
    Shapes(Vec<raster::Shape>),
}

/// Splits plotters' SVG into the shapes csm-lab reads ([`raster::Shape::from_lines`]) and
/// documents of the lines it does not, in order: (size, pieces). None when the document is not
/// laid out as plotters writes it (its header line, one element per line, the closing tag), to
/// be parsed whole.
fn split_parts(svg: &str) -> Option<((f32, f32), Vec<Piece>)> {
    let (header, body) = svg.split_once('\n')?;
    let size = plotters_header_size(header)?;
    let body = body.trim_end().strip_suffix("</svg>")?;
    let lines: Vec<&str> = body.lines().collect();
    let mut parts = Vec::new();
    let mut shapes = Vec::new();
    let mut doc = String::new();
    let mut i = 0;
    let mut in_text = false;
    while i < lines.len() {
        let read = if in_text {
            None
        } else {
            raster::Shape::from_lines(lines[i], &lines[i + 1..])
        };
        match read {
            Some((shape, n)) => {
                if !doc.is_empty() {
                    doc.push_str("</svg>\n");
                    parts.push(Piece::Svg(std::mem::take(&mut doc)));
                }
                shapes.extend(shape);
                i += n;
            }
            None => {
                let line = lines[i];
                if line.starts_with("<text") {
                    in_text = true;
                }
                if in_text && line.ends_with("</text>") {
                    in_text = false;
                }
                if !shapes.is_empty() {
                    parts.push(Piece::Shapes(std::mem::take(&mut shapes)));
                }
                if doc.is_empty() {
                    doc.push_str(header);
                    doc.push('\n');
                }
                doc.push_str(line);
                doc.push('\n');
                i += 1;
            }
        }
    }
    if !doc.is_empty() {
        doc.push_str("</svg>\n");
        parts.push(Piece::Svg(doc));
    }
    if !shapes.is_empty() {
        parts.push(Piece::Shapes(shapes));
    }
    Some((size, parts))
}

impl ParsedSvg {
    pub(crate) fn parse(svg: &[u8]) -> Result<Self> {
        let tree = |bytes: &[u8]| {
            resvg::usvg::Tree::from_data(bytes, &usvg_options())
                .map_err(|e| crate::error::Error::from(PlotError::Rasterise(e.to_string())))
        };
        match std::str::from_utf8(svg).ok().and_then(split_parts) {
            Some((size, parts)) => Ok(ParsedSvg {
                size,
                parts: parts
                    .into_iter()
                    .map(|p| match p {
                        Piece::Svg(text) => tree(text.as_bytes()).map(|t| SvgPart::Tree(Box::new(t))),
                        Piece::Shapes(shapes) => Ok(SvgPart::Shapes(shapes)),
                    })
                    .collect::<Result<Vec<_>>>()?,
            }),
            None => {
                let t = tree(svg)?;
                Ok(ParsedSvg {
                    size: (t.size().width(), t.size().height()),
                    parts: vec![SvgPart::Tree(Box::new(t))],
                })
            }
        }
    }

    /// The document's size in its own units (pixels): (width, height).
    pub(crate) fn size(&self) -> (f32, f32) {
        self.size
    }

    /// Draws the document onto `pixmap` with `transform`, a scale equal on both axes: the
    /// shapes directly, the parsed parts with `resvg::render`.
    pub(crate) fn render(&self, transform: resvg::tiny_skia::Transform, pixmap: &mut resvg::tiny_skia::PixmapMut) {
        for part in &self.parts {
            match part {
                SvgPart::Tree(t) => resvg::render(t, transform, pixmap),
                SvgPart::Shapes(shapes) => shapes.iter().for_each(|s| s.draw(transform, pixmap)),
            }
        }
    }

    /// RGB8 pixels on a white background, `scale` pixels per SVG unit: (width, height, pixels).
    pub(crate) fn rgb(&self, scale: f32) -> Result<(u32, u32, Vec<u8>)> {
        let pixmap = self.pixmap(scale)?;
        Ok((pixmap.width(), pixmap.height(), opaque_rgb(pixmap)))
    }

    /// The document drawn on a white background, `scale` pixels per SVG unit (opaque).
    pub(crate) fn pixmap(&self, scale: f32) -> Result<resvg::tiny_skia::Pixmap> {
        use resvg::tiny_skia;
        let (sw, sh) = self.size();
        let (w, h) = ((sw * scale).ceil() as u32, (sh * scale).ceil() as u32);
        let mut pixmap =
            tiny_skia::Pixmap::new(w, h).ok_or_else(|| PlotError::Rasterise(format!("bad size {w}x{h}")))?;
        let transform = tiny_skia::Transform::from_scale(scale, scale);
        // A chart's first element is its opaque background over the whole canvas: the white
        // underneath would be overwritten.
        let covered = match self.parts.first() {
            Some(SvgPart::Shapes(shapes)) => shapes.first().is_some_and(|s| s.covers(transform, w, h)),
            _ => false,
        };
        if !covered {
            pixmap.fill(tiny_skia::Color::WHITE);
        }
        self.render(transform, &mut pixmap.as_mut());
        Ok(pixmap)
    }

    /// A PNG `scale` pixels per SVG unit (the figures' encoding, [`encode_figure_png`]).
    pub(crate) fn png(&self, scale: f32) -> Result<Vec<u8>> {
        encode_figure_pixmap(&self.pixmap(scale)?)
    }
}

/// Rasterises SVG bytes to RGB8 pixels on a white background: (width, height, pixels).
pub(crate) fn svg_to_rgb(svg: &[u8], scale: f32) -> Result<(u32, u32, Vec<u8>)> {
    ParsedSvg::parse(svg)?.rgb(scale)
}

/// An opaque pixmap's pixels as RGB8. Opaque, so premultiplied RGBA equals straight RGBA: the
/// alpha is dropped, in place: pixel i's RGB moves from 4i to 3i (never past a pixel not yet
/// read), which saves allocating and faulting in a second image-sized buffer.
pub(crate) fn opaque_rgb(pixmap: resvg::tiny_skia::Pixmap) -> Vec<u8> {
    // Four pixels at a time (16 bytes read before 12 are written, never past the next four),
    // then the rest one by one.
    let mut rgb = pixmap.take();
    let n = rgb.len() / 4;
    let blocks = n / 4;
    for b in 0..blocks {
        let mut px = [0u8; 16];
        px.copy_from_slice(&rgb[16 * b..16 * b + 16]);
        let out = &mut rgb[12 * b..12 * b + 12];
        for p in 0..4 {
            out[3 * p..3 * p + 3].copy_from_slice(&px[4 * p..4 * p + 3]);
        }
    }
    for i in 4 * blocks..n {
        let (s, d) = (4 * i, 3 * i);
        rgb.copy_within(s..s + 3, d);
    }
    rgb.truncate(3 * n);
    rgb
}

/// RGB8 pixels to PNG bytes (fast deflate, each row predicted from its left neighbour).
pub(crate) fn encode_png(w: u32, h: u32, rgb: &[u8]) -> Result<Vec<u8>> {
    encode_png_as(w, h, rgb, png::FilterType::Sub)
}

/// A figure's RGB8 pixels (a chart rasterised from its SVG, the plan) to PNG bytes: fast
/// deflate after the Paeth predictor, which suits flat colour areas, lines and text; half the
/// size of [`encode_png`]'s rows for the same time (on the default sweep's figures: 2 ms and
/// 250 KB for the heat map instead of 480 KB), small enough for a page to inline the file itself.
///
/// The figures are encoded from their pixmaps by [`encode_figure_pixmap`], to the same bytes;
/// this is what its tests compare with.
#[cfg(test)]
pub(crate) fn encode_figure_png(w: u32, h: u32, rgb: &[u8]) -> Result<Vec<u8>> {
    encode_png_as(w, h, rgb, png::FilterType::Paeth)
}

/// [`encode_figure_png`] of an opaque pixmap's pixels, the same bytes, without converting the
/// whole image to RGB first or predicting the rows' unchanged runs.
///
/// The PNG is what the `png` crate writes for [`encode_figure_png`]: its header, then the zlib
/// stream fast deflate (`fdeflate`, which the crate uses) makes of the rows, each given to the
/// compressor as the crate gives it (the filter type byte, then the row after the Paeth
/// predictor), stored instead when that is smaller, in IDAT chunks of the crate's largest
/// size, then the end chunk. Each row is made RGB on its own ([`rgba_row_to_rgb`]), a row
/// equal to the row above is all zero residuals without being converted, and wherever a run of
/// 32 bytes and the pixel before it equal the row above, its Paeth residuals are zero
/// ([`paeth_row`]): most of a chart is rows and runs that repeat.
pub(crate) fn encode_figure_pixmap(pixmap: &resvg::tiny_skia::Pixmap) -> Result<Vec<u8>> {
    let png_err = |e: &dyn std::fmt::Display| crate::error::Error::from(PlotError::Png(e.to_string()));
    let (w, h) = (pixmap.width(), pixmap.height());
    let row = 3 * w as usize;
    let rgba = pixmap.data();
    let rows = || rgba.chunks_exact(4 * w as usize);
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_filter(png::FilterType::Paeth);
        let mut writer = enc.write_header().map_err(|e| png_err(&e))?;
        let mut deflate = fdeflate::Compressor::new(std::io::Cursor::new(Vec::new())).map_err(|e| png_err(&e))?;
        let (mut prev, mut cur) = (vec![0u8; row], vec![0u8; row]);
        let mut filtered = vec![0u8; row + 1];
        filtered[0] = png::FilterType::Paeth as u8;
        // A row equal to the row above predicts itself exactly: all its residuals are zero.
        let mut repeated = vec![0u8; row + 1];
        repeated[0] = png::FilterType::Paeth as u8;
        let mut above: Option<&[u8]> = None;
        for src in rows() {
            if above == Some(src) {
                deflate.write_data(&repeated).map_err(|e| png_err(&e))?;
                continue;
            }
            rgba_row_to_rgb(src, &mut cur);
            paeth_row(&prev, &cur, &mut filtered[1..]);
            deflate.write_data(&filtered).map_err(|e| png_err(&e))?;
            std::mem::swap(&mut prev, &mut cur);
            above = Some(src);
        }
        let mut zlib = deflate.finish().map_err(|e| png_err(&e))?.into_inner();
        if zlib.len() > fdeflate::StoredOnlyCompressor::<()>::compressed_size((row + 1) * h as usize) {
            // Stored rows without a filter, as the crate falls back to.
            let mut stored =
                fdeflate::StoredOnlyCompressor::new(std::io::Cursor::new(Vec::new())).map_err(|e| png_err(&e))?;
            for src in rows() {
                rgba_row_to_rgb(src, &mut cur);
                stored.write_data(&[0]).map_err(|e| png_err(&e))?;
                stored.write_data(&cur).map_err(|e| png_err(&e))?;
            }
            zlib = stored.finish().map_err(|e| png_err(&e))?.into_inner();
        }
        for chunk in zlib.chunks((u32::MAX >> 1) as usize) {
            writer.write_chunk(png::chunk::IDAT, chunk).map_err(|e| png_err(&e))?;
        }
        writer.finish().map_err(|e| png_err(&e))?;
    }
    Ok(out)
}

/// An opaque premultiplied RGBA row as RGB (`dst` is three quarters of `src`'s length).
fn rgba_row_to_rgb(src: &[u8], dst: &mut [u8]) {
    // Four pixels at a time: two 8-byte words to 12 bytes.
    let (blocks, rest) = (src.len() / 16, src.len() % 16);
    let three = |v: u64| (v & 0xff_ffff) | ((v >> 8) & 0xffff_ff00_0000);
    for (s, d) in src.chunks_exact(16).zip(dst.chunks_exact_mut(12)) {
        let a = three(u64::from_le_bytes(s[..8].try_into().unwrap_or_default()));
        let b = three(u64::from_le_bytes(s[8..].try_into().unwrap_or_default()));
        d[..8].copy_from_slice(&(a | (b << 48)).to_le_bytes());
        d[8..].copy_from_slice(&((b >> 16) as u32).to_le_bytes());
    }
    for (s, d) in src[16 * blocks..][..rest]
        .chunks_exact(4)
        .zip(dst[12 * blocks..].chunks_exact_mut(3))
    {
        d.copy_from_slice(&s[..3]);
    }
}

/// The PNG Paeth predictor of `a` (left), `b` (above), `c` (above left): of the three, the one
/// nearest `a + b - c`, ties to `a`, then `b`. In bytes only (`|p - a| = |b - c|`,
/// `|p - b| = |a - c|`, and `|p - c|`, needed only when `c` lies between `a` and `b`, is the
/// difference of those two), which the compiler makes many lanes wide.
#[inline(always)]
fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let pa = b.max(c) - b.min(c);
    let pb = a.max(c) - a.min(c);
    // When c is below or above both, p is farther from c than from a and from b.
    let between = (a <= c) != (b <= c) || a == c || b == c;
    let pc = if between { pa.max(pb) - pa.min(pb) } else { 255 };
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}

/// RGB row `cur` after the Paeth predictor, given the row above (`prev`, zeros above the
/// first row), into `out` (the same length). A run of 32 bytes that, with the pixel before it,
/// equals the row above has zero residuals (each byte's predictor is the byte above), so it is
/// written without computing them.
fn paeth_row(prev: &[u8], cur: &[u8], out: &mut [u8]) {
    const BPP: usize = 3;
    const RUN: usize = 32;
    let n = cur.len().min(BPP);
    for i in 0..n {
        out[i] = cur[i].wrapping_sub(paeth(0, prev[i], 0));
    }
    let mut i = BPP;
    while i + RUN <= cur.len() {
        let out = &mut out[i..i + RUN];
        if cur[i - BPP..i + RUN] == prev[i - BPP..i + RUN] {
            out.fill(0);
        } else {
            let (x, a) = (&cur[i..i + RUN], &cur[i - BPP..i - BPP + RUN]);
            let (b, c) = (&prev[i..i + RUN], &prev[i - BPP..i - BPP + RUN]);
            for k in 0..RUN {
                out[k] = x[k].wrapping_sub(paeth(a[k], b[k], c[k]));
            }
        }
        i += RUN;
    }
    while i < cur.len() {
        out[i] = cur[i].wrapping_sub(paeth(cur[i - BPP], prev[i], prev[i - BPP]));
        i += 1;
    }
}

fn encode_png_as(w: u32, h: u32, rgb: &[u8], filter: png::FilterType) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_filter(filter);
        let mut writer = enc.write_header().map_err(|e| PlotError::Png(e.to_string()))?;
        writer
            .write_image_data(rgb)
            .map_err(|e| PlotError::Png(e.to_string()))?;
    }
    Ok(out)
}

/// An axis tick label: the shortest decimal that names the tick ("10", "0.2", "2.5e-5"), never
/// trailing zeros. Ticks come from [`nice_ticks`], so 4 significant digits always suffice.
pub(crate) fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".to_string();
    }
    crate::output::four_digits(v, 1e-4)
}

/// Round tick values for an axis over `lo..hi` (log or linear), at least three when the range
/// allows, each with a distinct [`tick`] label. Log axes take 1-2-5 steps per decade (every
/// decade when the range spans many), falling back to a linear 1-2-5 step on narrow ranges, so
/// an axis never goes unlabelled.
pub(crate) fn nice_ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    // The largest 1-2-5 step that still gives `min_count` ticks.
    let linear = |min_count: usize| -> Vec<f64> {
        let mag = 10f64.powf((hi - lo).log10().floor());
        let at = |step: f64| -> Vec<f64> {
            let first = (lo / step).ceil() as i64;
            let last = (hi / step).floor() as i64;
            (first..=last).map(|k| k as f64 * step).collect()
        };
        [5.0, 2.0, 1.0, 0.5, 0.2, 0.1, 0.05]
            .iter()
            .map(|m| at(m * mag))
            .find(|t| t.len() >= min_count)
            .unwrap_or_else(|| at(0.05 * mag))
    };
    let mut out = if log && lo > 0.0 {
        let decades = (hi / lo).log10();
        let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let mantissas: &[f64] = if decades > 6.0 {
            &[1.0]
        } else if decades > 2.5 {
            &[1.0, 3.0]
        } else if decades > 1.0 {
            &[1.0, 2.0, 5.0]
        } else {
            &[1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0]
        };
        let stride = if decades > 12.0 {
            (decades / 6.0).ceil() as i32
        } else {
            1
        };
        let mut v = Vec::new();
        for d in (d0..=d1).filter(|d| (d - d0) % stride == 0) {
            for m in mantissas {
                let x = m * 10f64.powi(d);
                if x >= lo && x <= hi {
                    v.push(x);
                }
            }
        }
        if v.len() < 3 {
            linear(3).into_iter().filter(|x| *x > 0.0).collect()
        } else {
            v
        }
    } else {
        linear(4)
    };
    out.dedup_by(|a, b| tick(*a) == tick(*b));
    if out.is_empty() {
        out.push(lo);
    }
    out
}

/// Value labels in figures use the reports' number format.
pub use crate::output::short_number as short;

// ---------------------------------------------------------------------------------------------
// Palette: every colour a figure uses
// ---------------------------------------------------------------------------------------------

/// Every colour a figure uses: named single marks and the categorical lists.
pub(crate) mod palette {
    use plotters::style::RGBColor;

    /// A heatmap cell without a value (no cascades needed), or a view of the plan without one
    /// (it sees no receiver).
    pub(crate) const NO_DATA: RGBColor = RGBColor(220, 220, 220);
    /// The outline of the recommended heatmap cell.
    pub(crate) const MARKED: RGBColor = RGBColor(255, 0, 0);
    /// The recommended point of a scatter plot.
    pub(crate) const RECOMMENDED: RGBColor = RGBColor(200, 0, 0);
    /// Scatter points that are not singled out.
    pub(crate) const POINT: RGBColor = RGBColor(170, 170, 170);
    /// Split depths drawn across a chart.
    pub(crate) const SPLIT: RGBColor = RGBColor(150, 150, 150);
    /// A limit such as the memory budget.
    pub(crate) const LIMIT: RGBColor = RGBColor(120, 120, 120);
    /// Coverage misses.
    pub(crate) const MISS: RGBColor = RGBColor(214, 39, 40);
    /// View depths where nothing visible lies (shaded in the depth charts).
    pub(crate) const NOT_VISIBLE: RGBColor = RGBColor(160, 160, 160);

    /// Colours written as 0xRRGGBB, the way palettes are usually published.
    const fn from_hex<const N: usize>(hex: [u32; N]) -> [RGBColor; N] {
        let mut out = [RGBColor(0, 0, 0); N];
        let mut i = 0;
        while i < N {
            let h = hex[i];
            out[i] = RGBColor((h >> 16) as u8, (h >> 8) as u8, h as u8);
            i += 1;
        }
        out
    }

    /// Series of a chart, in order.
    pub(crate) const SERIES: [RGBColor; 8] = from_hex([
        0x0072B2, 0xD55E00, 0x009E73, 0xCC79A7, 0xE69F00, 0x56B4E9, 0x787878, 0xA02828,
    ]);

    /// Presets of a comparison, in order.
    pub(crate) const PRESETS: [RGBColor; 11] = from_hex([
        0x1F77B4, 0xFF7F0E, 0x2CA02C, 0xD62728, 0x9467BD, 0x8C564B, 0xE377C2, 0x7F7F7F, 0xBCBD22, 0x17BECF, 0x000080,
    ]);
}

/// Distinct, colour-blind-friendly-ish colours for series.
pub(crate) fn series_color(i: usize) -> RGBColor {
    palette::SERIES[i % palette::SERIES.len()]
}

/// One colour per preset (eleven, distinguishable).
pub(crate) fn preset_color(i: usize) -> RGBColor {
    palette::PRESETS[i % palette::PRESETS.len()]
}

/// The colour map's stops, evenly spaced in t (viridis-like).
const STOPS: [(f64, f64, f64); 5] = [
    (68.0, 1.0, 84.0),
    (59.0, 82.0, 139.0),
    (33.0, 145.0, 140.0),
    (94.0, 201.0, 98.0),
    (253.0, 231.0, 37.0),
];

/// Sequential colour map (viridis-like stops), t in [0, 1].
pub(crate) fn colormap(t: f64) -> RGBColor {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let x = t * 4.0;
    // x is in [0, 4]: truncation is its floor (no libm call, which baseline x86-64 makes).
    let i = (x as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let lerp = |p: f64, q: f64| round_byte(p + (q - p) * f);
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// `v.round() as u8` for `v` in [0, 255] (a colour channel): the whole part, plus one when the
/// rest is at least 1/2 (half away from zero, as `f64::round`). The rest `v - trunc(v)` is
/// exact, so the result is `f64::round`'s to the bit, without its libm call.
#[inline]
fn round_byte(v: f64) -> u8 {
    let whole = v as u8;
    whole.saturating_add(u8::from(v - whole as f64 >= 0.5))
}

/// A chart that only says why there is nothing to show.
pub(crate) fn draw_message<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    message: &str,
) -> PlotResult {
    let (w, h) = root.dim_in_pixel();
    root.draw(&Text::new(
        title.to_string(),
        (20, 20),
        (FONT, 24).into_font().style(FontStyle::Bold),
    ))?;
    root.draw(&Text::new(
        message.to_string(),
        (20, (h / 2) as i32),
        (FONT, 18).into_font(),
    ))?;
    let _ = w;
    Ok(())
}

/// The house chart frame: a caption, 14-pixel margins, and room for the axis labels (50 pixels
/// below, `y_labels` pixels left).
pub(crate) fn chart_frame<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    caption_size: u32,
    y_labels: u32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(root);
    b.caption(title, (FONT, caption_size))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(y_labels);
    b
}

/// The house mesh of a chart with numeric axes: [`tick`] labels on both, the axis descriptions
/// in 15-pixel text and the labels in 13-pixel text. The caller adds what its chart changes
/// (light lines, label sizes) and draws it.
pub(crate) fn house_mesh<'a, 'b, X, Y, DB>(
    chart: &'b mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    x_desc: impl Into<String>,
    y_desc: impl Into<String>,
) -> plotters::chart::MeshStyle<'a, 'b, X, Y, DB>
where
    X: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    DB: DrawingBackend,
{
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(&tick_label)
        .y_label_formatter(&tick_label)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13));
    mesh
}

/// [`tick`] as a label formatter.
fn tick_label(v: &f64) -> String {
    tick(*v)
}

/// Log-axis range that covers `lo..hi` with a margin and never collapses.
pub(crate) fn log_range(lo: f64, hi: f64) -> (f64, f64) {
    let lo = lo.max(1e-300);
    let hi = hi.max(lo * 1.0001);
    (lo / 1.3, hi * 1.3)
}

/// The chart type of the log-log "texels per pixel against view depth" figures.
pub(crate) type DepthChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogAxis, LogAxis>>;

/// A log axis labelled at [`nice_ticks`].
pub(crate) type LogAxis = WithKeyPoints<LogCoord<f64>>;

/// A log axis over `lo..hi` with round, distinct tick labels.
pub(crate) fn log_axis(lo: f64, hi: f64) -> LogAxis {
    (lo..hi).log_scale().with_key_points(nice_ticks(lo, hi, true))
}

/// A log axis over `lo..hi` labelled at `ticks`.
pub(crate) fn log_axis_with(lo: f64, hi: f64, ticks: Vec<f64>) -> LogAxis {
    (lo..hi).log_scale().with_key_points(ticks)
}

/// A linear axis over `lo..hi` with round, distinct tick labels.
pub(crate) fn linear_axis(lo: f64, hi: f64) -> TickedAxis {
    TickedAxis {
        inner: (lo..hi).into(),
        ticks: nice_ticks(lo, hi, false),
    }
}

/// A linear axis over `lo..hi` labelled at the given ticks (e.g. the centres of categories).
pub(crate) fn ticked_axis(lo: f64, hi: f64, ticks: Vec<f64>) -> TickedAxis {
    TickedAxis {
        inner: (lo..hi).into(),
        ticks,
    }
}

/// A linear f64 axis with chosen tick positions, labelled by the chart's label formatter.
pub(crate) struct TickedAxis {
    inner: RangedCoordf64,
    ticks: Vec<f64>,
}

impl Ranged for TickedAxis {
    type ValueType = f64;
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;

    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }
}

/// The view depths of the visible geometry (`visible_z_lo`, `visible_z_hi` of the screen
/// metrics), when the scene has geometry and some of it is visible: what the depth charts shade
/// outside of.
pub(crate) fn visible_depths(s: &crate::analysis::Summary) -> Option<(f64, f64)> {
    s.screen
        .as_ref()
        .map(|x| (x.visible_z_lo, x.visible_z_hi))
        .filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && *lo > 0.0 && lo < hi)
}

/// The legend entries [`texels_per_pixel_chart`] adds: the ideal line, and the shaded depths
/// without visible geometry when `visible` is known.
pub(crate) fn depth_chart_legend_lines(visible: Option<(f64, f64)>) -> usize {
    1 + usize::from(visible.is_some())
}

/// A log-log chart of texels per pixel against view depth over `depth` with its axes, labels and
/// the dashed "ideal: 1 texel per pixel" line already drawn; the y range covers `texels_per_pixel`
/// and 1. With `visible` (the depths of the visible geometry, [`visible_depths`]) the depths
/// outside it are shaded: no pixel on screen lies there, so the density there is what no one
/// sees. Shared by `analyze`'s density figure, `sweep`'s λ figure and `compare`'s overlay.
#[allow(clippy::too_many_arguments)]
pub(crate) fn texels_per_pixel_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    caption_size: u32,
    depth: (f64, f64),
    texels_per_pixel: impl Iterator<Item = f64>,
    legend_lines: usize,
    legend: &mut Legend<DB>,
    visible: Option<(f64, f64)>,
) -> Result<(DepthChart<'a, DB>, (f64, f64)), DrawError> {
    let (ymin, ymax) = texels_per_pixel.fold((1.0f64, 1.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (y0, y1) = log_range(ymin, ymax);
    let (x0, x1) = depth;
    let mut chart = legend_frame(root, title, caption_size, 70, legend_lines, LEGEND_FONT)
        .build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1))?;
    house_mesh(
        &mut chart,
        "view depth (world units, log)",
        "texels per pixel (log; above 1 = sharper than the screen)",
    )
    .draw()?;
    if let Some((lo, hi)) = visible {
        let shade = palette::NOT_VISIBLE.mix(0.35).filled();
        for (a, b) in [(x0, lo.min(x1)), (hi.max(x0), x1)] {
            if b > a {
                chart.draw_series(std::iter::once(Rectangle::new([(a, y0), (b, y1)], shade)))?;
            }
        }
        legend.add(
            format!(
                "shaded: no visible geometry (what the camera sees lies at depths {} to {})",
                tick(lo),
                tick(hi)
            ),
            move |(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], shade),
        );
    }
    let ideal = BLACK.stroke_width(2);
    chart.draw_series(DashedLineSeries::new(vec![(x0, 1.0), (x1, 1.0)], 8, 5, ideal))?;
    legend.add("ideal: 1 texel per pixel", move |(x, y)| {
        PathElement::new(vec![(x, y), (x + 18, y)], ideal)
    });
    Ok((chart, (y0, y1)))
}

/// The height of a legend of `lines` entries in `font_size` text, in pixels: what
/// [`legend_frame`] reserves below a chart and [`draw_legend_below`] fills.
pub(crate) fn legend_height(lines: usize, font_size: u32) -> u32 {
    lines as u32 * (font_size * 5).div_ceil(4) + 24
}

/// The size of a house chart with its legend below: 960 × 540 pixels of chart and the band of
/// [`legend_height`] for `lines` entries.
pub(crate) fn size_with_legend(lines: usize) -> (u32, u32) {
    (960, 540 + legend_height(lines, LEGEND_FONT))
}

/// [`chart_frame`] with a band of [`legend_height`] pixels reserved under the x-axis labels, where
/// [`draw_legend_below`] puts the legend: outside the plotting area, so it never covers data.
pub(crate) fn legend_frame<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    caption_size: u32,
    y_labels: u32,
    legend_lines: usize,
    font_size: u32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = chart_frame(root, title, caption_size, y_labels);
    b.margin_bottom(14 + legend_height(legend_lines, font_size));
    b
}

/// A figure's legend entries (label and swatch), drawn by [`draw_legend_below`] in a band of its
/// own under the chart, so the legend box never covers data.
pub(crate) struct Legend<DB: DrawingBackend> {
    entries: Vec<LegendEntry<DB>>,
}

type LegendEntry<DB> = (
    String,
    Box<dyn Fn(BackendCoord) -> DynElement<'static, DB, BackendCoord>>,
);

impl<DB: DrawingBackend> Default for Legend<DB> {
    fn default() -> Self {
        Legend { entries: Vec::new() }
    }
}

impl<DB: DrawingBackend> Legend<DB> {
    /// An entry: `label` beside the swatch `f` draws at the given pixel.
    pub(crate) fn add<E, F>(&mut self, label: impl Into<String>, f: F)
    where
        E: IntoDynElement<'static, DB, BackendCoord>,
        F: Fn(BackendCoord) -> E + 'static,
    {
        self.entries.push((label.into(), Box::new(move |p| f(p).into_dyn())));
    }

    pub(crate) fn len(&self) -> usize {
        self.entries.len()
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// Draws `legend` in the house style (white, framed box) in the band of [`legend_height`] pixels
/// for `reserved_lines` entries that [`legend_frame`] left at the bottom of `root`, left-aligned
/// with the plotting area.
pub(crate) fn draw_legend_below<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    legend: Legend<DB>,
    reserved_lines: usize,
) -> PlotResult {
    if legend.is_empty() {
        return Ok(());
    }
    let (w, h) = root.dim_in_pixel();
    let band_h = legend_height(reserved_lines.max(legend.len()), LEGEND_FONT).min(h);
    let left = 84.min(w.saturating_sub(1));
    let band = root.clone().shrink((left, h - band_h), (w - left, band_h));
    let mut chart = ChartBuilder::on(&band).build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
    for (label, f) in legend.entries {
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label(label)
            .legend(f);
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, LEGEND_FONT)
}

/// Draws the series legend in the house style (white, framed box) at `position`.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> PlotResult {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, font_size))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_byte_is_f64_round_as_u8() {
        // Every half and its neighbours, below, inside and above the channel range.
        let mut xs = vec![-1.0, -0.5, -0.0, 0.0, 255.0, 255.5, 256.0, 300.0];
        for k in -2..=600 {
            let h = k as f64 * 0.5;
            xs.extend([h, h.next_up(), h.next_down()]);
        }
        let mut rng = csm_core::rng::SplitMix64::new(7);
        xs.extend((0..100_000).map(|_| rng.unit() * 256.0));
        for x in xs {
            assert_eq!(round_byte(x), x.round() as u8, "{x:e}");
        }
        // And the map itself against the plain formula with f64::floor and f64::round.
        for k in 0..=10_000 {
            let t = k as f64 / 10_000.0;
            let x = t * 4.0;
            let i = (x.floor() as usize).min(3);
            let f = x - i as f64;
            let (a, b) = (STOPS[i], STOPS[i + 1]);
            let lerp = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
            let want = RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2));
            assert_eq!(colormap(t), want, "{t}");
        }
    }

    #[test]
    fn tick_labels_are_the_shortest_decimal() {
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(0.2), "0.2");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(6.0 * 0.1), "0.6");
        assert_eq!(tick(1500.0), "1500");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(-2.5), "-2.5");
        assert_eq!(tick(2.5e-5), "2.5e-5");
        assert_eq!(tick(3e7), "3e7");
    }

    fn labels(lo: f64, hi: f64, log: bool) -> Vec<String> {
        nice_ticks(lo, hi, log).into_iter().map(tick).collect()
    }

    #[test]
    fn log_ticks_take_1_2_5_steps_per_decade_and_every_decade_on_wide_ranges() {
        assert_eq!(labels(0.8, 120.0, true), ["1", "2", "5", "10", "20", "50", "100"]);
        assert_eq!(
            labels(0.9, 1.1e4, true),
            ["1", "3", "10", "30", "100", "300", "1000", "3000", "10000"]
        );
        assert_eq!(
            labels(1e-3, 1e5, true),
            ["0.001", "0.01", "0.1", "1", "10", "100", "1000", "10000", "100000"]
        );
    }

    #[test]
    fn narrow_ranges_get_at_least_three_distinct_labels() {
        // top_down's max aliasing at 4096²: inside one decade, no 1-2-5 value but 0.6 and 0.8.
        assert_eq!(labels(0.580319, 0.986597, true), ["0.6", "0.7", "0.8", "0.9"]);
        assert_eq!(labels(1.16, 1.97, true), ["1.2", "1.4", "1.6", "1.8"]);
        for (lo, hi) in [(0.5, 0.52), (1234.0, 1240.0), (3.0e-5, 3.3e-5), (99.0, 101.0)] {
            let l = labels(lo, hi, true);
            assert!(l.len() >= 3, "{lo}..{hi}: {l:?}");
            let mut d = l.clone();
            d.dedup();
            assert_eq!(d, l, "{lo}..{hi}: duplicated labels");
            let slack = 1e-9 * hi;
            for v in nice_ticks(lo, hi, true) {
                assert!(v >= lo - slack && v <= hi + slack, "{v} outside {lo}..{hi}");
            }
        }
    }

    #[test]
    fn linear_ticks_are_round_and_cover_the_range() {
        assert_eq!(labels(0.0, 0.6048, false), ["0", "0.2", "0.4", "0.6"]);
        assert_eq!(labels(0.0, 239.0, false), ["0", "50", "100", "150", "200"]);
        assert_eq!(labels(-12.0, 12.0, false), ["-10", "-5", "0", "5", "10"]);
    }

    #[test]
    fn the_byte_paeth_predictor_is_the_textbook_one() {
        // Every (a, b, c): nearest to a + b - c, ties to a, then b (the PNG specification).
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                for c in 0..=255u8 {
                    let p = i32::from(a) + i32::from(b) - i32::from(c);
                    let (pa, pb, pc) = (
                        (p - i32::from(a)).abs(),
                        (p - i32::from(b)).abs(),
                        (p - i32::from(c)).abs(),
                    );
                    let want = if pa <= pb && pa <= pc {
                        a
                    } else if pb <= pc {
                        b
                    } else {
                        c
                    };
                    assert_eq!(paeth(a, b, c), want, "{a} {b} {c}");
                }
            }
        }
    }

    #[test]
    fn a_pixmaps_png_is_the_png_of_its_rgb_pixels() {
        use resvg::tiny_skia::Pixmap;
        // Opaque pixmaps of every width from 1 to 40 (rows shorter and longer than a run, and
        // not a multiple of one) and larger ones: flat with repeated rows and a few marks
        // (runs equal to the row above, and not), smooth gradients, and noise (whose fast
        // deflate is larger than stored rows: the stored fallback).
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut sizes: Vec<(u32, u32)> = (1..=40).map(|w| (w, 1 + w % 7)).collect();
        sizes.extend([(300, 40), (961, 17), (64, 64)]);
        for (w, h) in sizes {
            for kind in 0..3 {
                let mut pm = Pixmap::new(w, h).unwrap();
                for (k, px) in pm.data_mut().chunks_exact_mut(4).enumerate() {
                    let (x, y) = (k as u32 % w, k as u32 / w);
                    let r = next();
                    let rgb = match kind {
                        0 if r % 97 == 0 => [(r >> 8) as u8, (r >> 16) as u8, (r >> 24) as u8],
                        0 if y % 5 == 3 && x % 11 == 0 => [0, 0, 0],
                        0 => [255, 255, 250],
                        1 => [(x * 7 + y) as u8, (x + y * 3) as u8, (x * y) as u8],
                        _ => [r as u8, (r >> 8) as u8, (r >> 16) as u8],
                    };
                    px.copy_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
                }
                let want = encode_figure_png(w, h, &opaque_rgb(pm.clone())).unwrap();
                assert_eq!(encode_figure_pixmap(&pm).unwrap(), want, "{w} x {h}, kind {kind}");
            }
        }
    }

    #[test]
    fn a_png_is_drawn_at_the_size_a_page_shows_it() {
        // No wider than the page: its own size.
        assert_eq!(png_scale((960.0, 600.0)), 1.0);
        assert_eq!(png_scale((1280.0, 900.0)), 1.0);
        // Wider: the page's width, the height in proportion.
        let s = png_scale((1640.0, 1010.0));
        assert_eq!(s, 1280.0 / 1640.0);
        assert_eq!((1640.0 * s).ceil() as u32, 1280);
        // Wide and very tall: at most MAX_PNG_PIXELS (give or take a row and a column).
        let (w, h) = (2440.0f32, 40_000.0f32);
        let s = png_scale((w, h));
        assert!(s < 1280.0 / w);
        let (pw, ph) = ((w * s).ceil(), (h * s).ceil());
        assert!(pw * ph <= MAX_PNG_PIXELS + pw + ph, "{pw} x {ph}");
        assert!(pw * ph > 0.99 * MAX_PNG_PIXELS, "{pw} x {ph}");
    }

    /// Rasterises `svg` whole with usvg and resvg (nothing read directly), RGB.
    fn resvg_whole(svg: &str, scale: f32) -> Vec<u8> {
        let tree = resvg::usvg::Tree::from_data(svg.as_bytes(), &usvg_options()).unwrap();
        let (w, h) = (
            (tree.size().width() * scale).ceil() as u32,
            (tree.size().height() * scale).ceil() as u32,
        );
        let mut pixmap = resvg::tiny_skia::Pixmap::new(w, h).unwrap();
        pixmap.fill(resvg::tiny_skia::Color::WHITE);
        resvg::render(
            &tree,
            resvg::tiny_skia::Transform::from_scale(scale, scale),
            &mut pixmap.as_mut(),
        );
        opaque_rgb(pixmap)
    }

    #[test]
    fn plotters_shapes_draw_what_usvg_draws_in_order_up_to_the_shade_of_edge_pixels() {
        // A 24 x 10 grid of cells (overlapping their right neighbour by a unit, as a heat map's
        // do), a translucent band, dots, outlined circles and rectangles, polylines, a line and
        // a polygon as plotters writes them; an ellipse (a line csm-lab does not read, left to
        // usvg) drawn between the cells and the ring over them.
        let (cols, rows, cw, ch, x0, y0) = (24, 10, 11, 17, 40, 60);
        let colour = |i: i32, j: i32| RGBColor((i * 10) as u8, (j * 25) as u8, ((i + j) * 7) as u8);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (400, 300)).into_drawing_area();
            root.fill(&WHITE).unwrap();
            for j in 0..rows {
                for i in 0..cols {
                    let (x, y) = (x0 + i * (cw - 1), y0 + j * ch);
                    root.draw(&Rectangle::new([(x, y), (x + cw, y + ch)], colour(i, j).filled()))
                        .unwrap();
                }
            }
            root.draw(&Rectangle::new([(10, 10), (390, 40)], BLUE.mix(0.4).filled()))
                .unwrap();
            root.draw(&Circle::new((150, 120), 12, RED.filled())).unwrap();
            root.draw(&Circle::new((330, 200), 9, BLACK.stroke_width(2))).unwrap();
            root.draw(&Rectangle::new([(300, 60), (380, 100)], BLACK.stroke_width(1)))
                .unwrap();
            root.draw(&PathElement::new(
                vec![(10, 290), (100, 250), (200, 280)],
                GREEN.stroke_width(2),
            ))
            .unwrap();
            root.draw(&Polygon::new(
                vec![(250, 295), (290, 255), (330, 295)],
                MAGENTA.mix(0.5).filled(),
            ))
            .unwrap();
            for k in 0..40 {
                root.draw(&Circle::new((20 + 9 * k, 245), 3, BLACK.filled())).unwrap();
            }
        }
        // The ellipse goes after the cells, before the ring.
        let at = svg.find("<rect x=\"10\" y=\"10\"").unwrap();
        svg.insert_str(
            at,
            "<ellipse cx=\"100\" cy=\"100\" rx=\"30\" ry=\"10\" fill=\"#00FF00\"/>\n",
        );
        let parsed = ParsedSvg::parse(svg.as_bytes()).unwrap();
        let kinds: Vec<_> = parsed
            .parts
            .iter()
            .map(|p| match p {
                SvgPart::Tree(_) => "tree".to_string(),
                SvgPart::Shapes(s) => format!("{} shapes", s.len()),
            })
            .collect();
        // The background and the cells; the ellipse; the rest (the empty line of plotters'
        // own none).
        assert_eq!(kinds, ["241 shapes", "tree", "46 shapes"]);
        assert_eq!(parsed.size(), (400.0, 300.0));
        for scale in [1.0f32, 0.78] {
            let (w, _, ours) = parsed.rgb(scale).unwrap();
            let theirs = resvg_whole(&svg, scale);
            assert_eq!(ours.len(), theirs.len());
            let at = |v: &[u8], x: u32, y: u32| {
                let i = 3 * (y * w + x) as usize;
                [v[i], v[i + 1], v[i + 2]]
            };
            // Every pixel within an edge pixel's shade of usvg's, and 95 % within 2 of it.
            let mut same = 0;
            for (a, b) in ours.iter().zip(&theirs) {
                assert!(a.abs_diff(*b) <= 80, "{a} vs {b} at scale {scale}");
                same += usize::from(a.abs_diff(*b) <= 2);
            }
            assert!(same as f64 > 0.95 * ours.len() as f64, "{same} of {}", ours.len());
            // A pixel wholly inside one cell's visible part (not under the ring, the ellipse
            // or the band) is that cell's colour in both.
            let mut inside = 0;
            for j in 0..rows {
                for i in 0..cols {
                    let left = (x0 + i * (cw - 1)) as f32 * scale;
                    let right = (x0 + i * (cw - 1) + cw - 1) as f32 * scale;
                    let (top, bottom) = ((y0 + j * ch) as f32 * scale, (y0 + (j + 1) * ch) as f32 * scale);
                    for y in (top.ceil() as u32)..(bottom.floor() as u32) {
                        for x in (left.ceil() as u32)..(right.floor() as u32) {
                            let (sx, sy) = ((x as f32 + 0.5) / scale, (y as f32 + 0.5) / scale);
                            let ellipse = ((sx - 100.0) / 32.0).powi(2) + ((sy - 100.0) / 12.0).powi(2) < 1.0;
                            if (sx - 150.0).hypot(sy - 120.0) < 16.0 || ellipse {
                                continue;
                            }
                            let c = colour(i, j);
                            assert_eq!(at(&ours, x, y), [c.0, c.1, c.2], "cell {i},{j} at {x},{y}");
                            assert_eq!(at(&theirs, x, y), [c.0, c.1, c.2]);
                            inside += 1;
                        }
                    }
                }
            }
            assert!(inside > 15_000, "{inside}");
            // The ellipse over the cells, the ring over both, as in the document.
            let px = |x: f32, y: f32| at(&ours, (x * scale) as u32, (y * scale) as u32);
            assert_eq!(px(100.0, 100.0), [0, 255, 0]);
            assert_eq!(px(150.0, 120.0), [255, 0, 0]);
        }
    }

    #[test]
    fn a_legend_reserves_one_line_per_entry() {
        assert_eq!(legend_height(0, 13), 24);
        assert_eq!(legend_height(4, 13), 4 * 17 + 24);
    }
}
