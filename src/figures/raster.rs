//! The figures' PNGs drawn straight from the lines of plotters' SVG, without usvg.
//!
//! plotters writes every element of a chart on a line of its own, in seven forms (filled or
//! outlined rectangles, filled or outlined circles, polylines, lines, polygons) besides texts
//! ([`super::text`]). [`Shape::from_line`] reads exactly those forms (a strict reader: any
//! other line is left to usvg) and [`Shape::draw`] draws them with tiny_skia the way resvg
//! draws the elements usvg makes of them: the same geometry, fills (non-zero rule,
//! anti-aliased) and strokes (butt caps, miter joins, the stroke width), with two differences
//! in how, not what: an element's `opacity` is its paint's alpha (resvg draws a translucent
//! element on a layer of its own and composites it: the same colour up to rounding), and a
//! filled circle is rasterised once per radius and quarter-pixel position and blended where
//! it lands (a scatter plot's hundreds of dots cost one fill each otherwise). Parsing the
//! document with usvg was a third of rasterising a chart.

use std::sync::{Arc, OnceLock};

use resvg::tiny_skia::{FillRule, Mask, Path, PathBuilder, PixmapMut, Rect, Stroke, Transform};

use super::text::{colour, memo, number, split_phase, Coverage, Memo, Rgba, TextLine, PHASES};

/// One element of plotters' SVG, in SVG units.
#[derive(Debug, Clone)]
pub(crate) enum Shape {
    /// A filled rectangle (no stroke).
    Rect { rect: Rect, paint: Rgba },
    /// A filled circle (no stroke).
    Dot { cx: f32, cy: f32, r: f32, paint: Rgba },
    /// A filled path (a polygon).
    Fill { path: Path, paint: Rgba },
    /// A stroked path (a polyline, a line, an outlined rectangle or circle).
    Stroke { path: Path, width: f32, paint: Rgba },
    /// A text.
    Text(TextLine),
}

/// The most attributes a line read by [`Shape::from_lines`] has (a circle's seven); a line with
/// more is none of its forms.
const MOST_ATTRS: usize = 8;

/// A line's attributes in order (at most [`MOST_ATTRS`]), without allocating.
struct Attrs<'a> {
    n: usize,
    at: [(&'a str, &'a str); MOST_ATTRS],
}

impl<'a> std::ops::Deref for Attrs<'a> {
    type Target = [(&'a str, &'a str)];
    fn deref(&self) -> &Self::Target {
        &self.at[..self.n]
    }
}

/// A line's tag and its attributes in order: `<tag a="v" b="v"/>`; None for any other line,
/// or one of more than [`MOST_ATTRS`] attributes.
fn element(line: &str) -> Option<(&str, Attrs<'_>)> {
    let body = line.strip_prefix('<')?.strip_suffix("/>")?;
    let (tag, mut rest) = body.split_once(' ')?;
    let mut attrs = Attrs {
        n: 0,
        at: [("", ""); MOST_ATTRS],
    };
    while !rest.is_empty() {
        // The first `="` (a byte search: a name holds no quote).
        let b = rest.as_bytes();
        let mut eq = 0;
        loop {
            eq += b[eq..].iter().position(|&c| c == b'=')?;
            if b.get(eq + 1) == Some(&b'"') {
                break;
            }
            eq += 1;
        }
        let (name, r) = (&rest[..eq], &rest[eq + 2..]);
        let (value, r) = r.split_once('"')?;
        if attrs.n == MOST_ATTRS {
            return None;
        }
        attrs.at[attrs.n] = (name, value);
        attrs.n += 1;
        rest = match r.strip_prefix(' ') {
            Some(r) => r,
            None if r.is_empty() => r,
            None => return None,
        };
    }
    Some((tag, attrs))
}

/// The attributes `names` exactly, in that order.
fn exactly<'a, const N: usize>(attrs: &[(&str, &'a str)], names: [&str; N]) -> Option<[&'a str; N]> {
    if attrs.len() != N || attrs.iter().zip(names).any(|((a, _), n)| *a != n) {
        return None;
    }
    let mut out = [""; N];
    for (o, (_, v)) in out.iter_mut().zip(attrs) {
        *o = v;
    }
    Some(out)
}

/// `x,y x,y …` as an open path (None for fewer than two points, which usvg does not draw).
fn points(s: &str, close: bool) -> Option<Option<Path>> {
    let mut b = PathBuilder::new();
    let mut n = 0;
    for p in s.split(' ').filter(|p| !p.is_empty()) {
        let (x, y) = p.split_once(',')?;
        let (x, y) = (number(x)?, number(y)?);
        if n == 0 {
            b.move_to(x, y);
        } else {
            b.line_to(x, y);
        }
        n += 1;
    }
    if n < 2 {
        return Some(None);
    }
    if close {
        b.close();
    }
    Some(b.finish())
}

/// A positive stroke width.
fn width(s: &str) -> Option<f32> {
    number(s).filter(|w| *w > 0.0)
}

impl Shape {
    /// The element of one line of plotters' SVG, or of a text's three lines (`next` are the
    /// lines after `line`): the shape and the number of lines read, or None (left to usvg).
    /// A shape usvg would not draw (an empty rectangle, a polyline of one point) is read as
    /// nothing: `Some((None, 1))`.
    pub(crate) fn from_lines(line: &str, next: &[&str]) -> Option<(Option<Shape>, usize)> {
        if line.starts_with("<text") {
            let t = TextLine::from_lines(line, next.first()?, next.get(1)?)?;
            return Some((Some(Shape::Text(t)), 3));
        }
        let (tag, attrs) = element(line)?;
        let shape = match tag {
            "rect" => {
                if let Some([x, y, w, h, o, fill, stroke]) =
                    exactly(&attrs, ["x", "y", "width", "height", "opacity", "fill", "stroke"])
                {
                    let (x, y, w, h) = (number(x)?, number(y)?, number(w)?, number(h)?);
                    // usvg draws no rectangle without an area.
                    if !(w > 0.0 && h > 0.0) {
                        return Some((None, 1));
                    }
                    if fill == "none" {
                        let paint = colour(stroke, o)?;
                        Rect::from_xywh(x, y, w, h).map(|r| Shape::Stroke {
                            path: PathBuilder::from_rect(r),
                            width: 1.0,
                            paint,
                        })
                    } else if stroke == "none" {
                        let paint = colour(fill, o)?;
                        Rect::from_xywh(x, y, w, h).map(|rect| Shape::Rect { rect, paint })
                    } else {
                        return None;
                    }
                } else {
                    return None;
                }
            }
            "circle" => {
                let [cx, cy, r, o, fill, stroke, sw] =
                    exactly(&attrs, ["cx", "cy", "r", "opacity", "fill", "stroke", "stroke-width"])?;
                let (cx, cy, r) = (number(cx)?, number(cy)?, number(r)?);
                if r <= 0.0 {
                    None
                } else if fill == "none" {
                    let paint = colour(stroke, o)?;
                    let width = width(sw)?;
                    PathBuilder::from_circle(cx, cy, r).map(|path| Shape::Stroke { path, width, paint })
                } else if stroke == "none" {
                    Some(Shape::Dot {
                        cx,
                        cy,
                        r,
                        paint: colour(fill, o)?,
                    })
                } else {
                    return None;
                }
            }
            "polyline" => {
                let [fill, o, stroke, sw, pts] =
                    exactly(&attrs, ["fill", "opacity", "stroke", "stroke-width", "points"])?;
                if fill != "none" {
                    return None;
                }
                let paint = colour(stroke, o)?;
                let w = width(sw)?;
                points(pts, false)?.and_then(|path| stroke_of(path, w, paint))
            }
            "line" => {
                let [o, stroke, sw, x1, y1, x2, y2] =
                    exactly(&attrs, ["opacity", "stroke", "stroke-width", "x1", "y1", "x2", "y2"])?;
                let paint = colour(stroke, o)?;
                let w = width(sw)?;
                let mut b = PathBuilder::new();
                b.move_to(number(x1)?, number(y1)?);
                b.line_to(number(x2)?, number(y2)?);
                b.finish().and_then(|path| stroke_of(path, w, paint))
            }
            "polygon" => {
                let [o, fill, pts] = exactly(&attrs, ["opacity", "fill", "points"])?;
                let paint = colour(fill, o)?;
                points(pts, true)?.map(|path| Shape::Fill { path, paint })
            }
            _ => return None,
        };
        Some((shape, 1))
    }

    /// Whether the shape, drawn with `transform`, paints every pixel of a `w` × `h` pixmap
    /// opaquely (a chart's background).
    pub(crate) fn covers(&self, transform: Transform, w: u32, h: u32) -> bool {
        match self {
            Shape::Rect { rect, paint } => {
                paint.opacity == 1.0
                    && rect.transform(transform).is_some_and(|r| {
                        r.left() <= 0.0 && r.top() <= 0.0 && r.right() >= w as f32 && r.bottom() >= h as f32
                    })
            }
            _ => false,
        }
    }

    /// Draws the shape onto `pixmap` with `transform` (a scale equal on both axes, and a shift).
    pub(crate) fn draw(&self, transform: Transform, pixmap: &mut PixmapMut) {
        match self {
            Shape::Rect { rect, paint } => {
                if let Some(r) = rect.transform(transform) {
                    fill_rect(r, *paint, pixmap);
                }
            }
            Shape::Dot { cx, cy, r, paint } => {
                let mut p = [resvg::tiny_skia::Point::from_xy(*cx, *cy)];
                transform.map_points(&mut p);
                let (fx, phx) = split_phase(p[0].x);
                let (fy, phy) = split_phase(p[0].y);
                if let Some(m) = dot((r * transform.sx).to_bits(), (phx, phy)) {
                    m.blend(fx, fy, paint.rgb, paint.opacity, pixmap);
                }
            }
            Shape::Fill { path, paint } => {
                pixmap.fill_path(path, &paint.paint(), FillRule::Winding, transform, None);
            }
            Shape::Stroke { path, width, paint } => {
                let stroke = Stroke {
                    width: *width,
                    ..Stroke::default()
                };
                pixmap.stroke_path(path, &paint.paint(), &stroke, transform, None);
            }
            Shape::Text(t) => t.draw(transform, pixmap),
        }
    }
}

/// A stroke of `path`: a rectangle when the path is one horizontal or vertical segment (a
/// tick, a grid line, an axis: with butt caps its stroke is exactly that rectangle), else the
/// path stroked. None when nothing is drawn (a segment of no length).
fn stroke_of(path: Path, width: f32, paint: Rgba) -> Option<Shape> {
    if let [a, b] = path.points() {
        let (x0, x1) = (a.x.min(b.x), a.x.max(b.x));
        let (y0, y1) = (a.y.min(b.y), a.y.max(b.y));
        let h = width / 2.0;
        let rect = if a.y == b.y {
            Rect::from_ltrb(x0, y0 - h, x1, y1 + h)
        } else if a.x == b.x {
            Rect::from_ltrb(x0 - h, y0, x1 + h, y1)
        } else {
            return Some(Shape::Stroke { path, width, paint });
        };
        return rect.map(|rect| Shape::Rect { rect, paint });
    }
    Some(Shape::Stroke { path, width, paint })
}

/// Fills `rect` (pixels) with `paint`, each pixel by the exact fraction of it the rectangle
/// covers (the shade tiny_skia's anti-aliased rectangle fill gives it), source-over. The rows
/// and columns wholly inside are copied (opaque) or blended at one alpha.
fn fill_rect(rect: Rect, paint: Rgba, pixmap: &mut PixmapMut) {
    let (pw, ph) = (pixmap.width() as f32, pixmap.height() as f32);
    let (l, t) = (rect.left().max(0.0), rect.top().max(0.0));
    let (r, b) = (rect.right().min(pw), rect.bottom().min(ph));
    if !(r > l && b > t) {
        return;
    }
    let (x0, x1) = (l.floor() as usize, r.ceil() as usize);
    let (y0, y1) = (t.floor() as usize, b.ceil() as usize);
    let opacity = paint.opacity * 255.0;
    let [cr, cg, cb] = paint.rgb;
    let solid = [cr, cg, cb, 255];
    // Each column's covered fraction; the rows' below.
    let cols: Vec<f32> = (x0..x1).map(|x| r.min(x as f32 + 1.0) - l.max(x as f32)).collect();
    // The run of whole columns from each column on (the same on every row).
    let mut whole = vec![0usize; cols.len() + 1];
    for i in (0..cols.len()).rev() {
        whole[i] = if cols[i] >= 1.0 { whole[i + 1] + 1 } else { 0 };
    }
    let span: Vec<u8> = solid.repeat(x1 - x0);
    let w = pixmap.width() as usize;
    let data = pixmap.data_mut();
    // The last pixel blended and what it became at that alpha: a translucent rectangle mostly
    // lies over runs of one colour.
    let mut last: Option<(u32, [u8; 4], [u8; 4])> = None;
    let mut blend = |px: &mut [u8], a: u32| {
        let before: [u8; 4] = [px[0], px[1], px[2], px[3]];
        if let Some((la, lb, after)) = last {
            if la == a && lb == before {
                px.copy_from_slice(&after);
                return;
            }
        }
        for (d, s) in px.iter_mut().zip(solid) {
            *d = super::text::div255(u32::from(s) * a + u32::from(*d) * (255 - a)) as u8;
        }
        last = Some((a, before, [px[0], px[1], px[2], px[3]]));
    };
    for y in y0..y1 {
        let cy = b.min(y as f32 + 1.0) - t.max(y as f32);
        let row = &mut data[4 * (y * w + x0)..4 * (y * w + x1)];
        let mut i = 0;
        while i < cols.len() {
            // A run of whole columns: one alpha for the run.
            let run = whole[i];
            if run > 0 {
                let a = (cy * opacity).round() as u32;
                let px = &mut row[4 * i..4 * (i + run)];
                if a >= 255 {
                    px.copy_from_slice(&span[..4 * run]);
                } else if a > 0 {
                    px.chunks_exact_mut(4).for_each(|p| blend(p, a));
                }
                i += run;
                continue;
            }
            let a = (cols[i] * cy * opacity).round() as u32;
            let px = &mut row[4 * i..4 * i + 4];
            if a >= 255 {
                px.copy_from_slice(&solid);
            } else if a > 0 {
                blend(px, a);
            }
            i += 1;
        }
    }
}

/// A filled circle of radius `r` (pixels, f32 bits) centred `phase` quarter pixels past a
/// whole pixel, rasterised once per process.
fn dot(r: u32, phase: (u8, u8)) -> Option<Arc<Coverage>> {
    /// A radius (f32 bits) and a phase.
    type DotKey = (u32, (u8, u8));
    static CACHE: Memo<DotKey, Option<Arc<Coverage>>> = OnceLock::new();
    memo(&CACHE, (r, phase), || {
        let radius = f32::from_bits(r);
        let reach = radius.ceil() as i32 + 1;
        let size = (2 * reach + 1) as u32;
        let (cx, cy) = (
            reach as f32 + f32::from(phase.0) / PHASES,
            reach as f32 + f32::from(phase.1) / PHASES,
        );
        let path = PathBuilder::from_circle(cx, cy, radius)?;
        let mut mask = Mask::new(size, size)?;
        mask.fill_path(&path, FillRule::Winding, true, Transform::identity());
        Some(Arc::new(Coverage {
            left: -reach,
            top: -reach,
            width: size,
            height: size,
            coverage: mask.data().to_vec(),
        }))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_as_rust_parses_them() {
        for s in [
            "0",
            "-0",
            "7",
            "-12",
            "1234567",
            "12345678",
            "12.903225806451614",
            "-0.5",
            "1e3",
        ] {
            let want = s.parse::<f64>().ok().filter(|v| v.abs() < 1e7).map(|v| v as f32);
            let want = if s.contains('e') { None } else { want };
            assert_eq!(number(s), want, "{s}");
        }
        for s in ["", "-", "1-2", "a", "1.2.3", "NaN", "inf"] {
            assert_eq!(number(s), None, "{s}");
        }
    }

    #[test]
    fn the_seven_element_forms_plotters_writes_are_read_and_others_left_to_usvg() {
        let read = |l: &str| Shape::from_lines(l, &[]);
        let rgba = |rgb, opacity| Rgba { rgb, opacity };
        match read(r##"<rect x="3" y="4" width="14" height="26" opacity="0.45" fill="#12ABEF" stroke="none"/>"##) {
            Some((Some(Shape::Rect { rect, paint }), 1)) => {
                assert_eq!(rect, Rect::from_xywh(3.0, 4.0, 14.0, 26.0).unwrap());
                assert_eq!(paint, rgba([0x12, 0xab, 0xef], 0.45));
            }
            other => panic!("{other:?}"),
        }
        match read(r##"<circle cx="117" cy="71" r="3" opacity="1" fill="#AAAAAA" stroke="none" stroke-width="1"/>"##) {
            Some((Some(Shape::Dot { cx, cy, r, paint }), 1)) => {
                assert_eq!((cx, cy, r), (117.0, 71.0, 3.0));
                assert_eq!(paint, rgba([0xaa; 3], 1.0));
            }
            other => panic!("{other:?}"),
        }
        match read(
            r##"<polyline fill="none" opacity="1" stroke="#000000" stroke-width="2" points="59,114 59,338 70.5,400 "/>"##,
        ) {
            Some((Some(Shape::Stroke { path, width, paint }), 1)) => {
                assert_eq!(path.points().len(), 3);
                assert_eq!(path.points()[2], resvg::tiny_skia::Point::from_xy(70.5, 400.0));
                assert_eq!((width, paint), (2.0, rgba([0; 3], 1.0)));
            }
            other => panic!("{other:?}"),
        }
        for line in [
            r##"<rect x="1" y="2" width="3" height="4" opacity="1" fill="none" stroke="#000000"/>"##,
            r##"<circle cx="1" cy="2" r="3" opacity="1" fill="none" stroke="#000000" stroke-width="1"/>"##,
            r##"<line opacity="1" stroke="#000000" stroke-width="1" x1="0" y1="0" x2="5" y2="5"/>"##,
        ] {
            assert!(matches!(read(line), Some((Some(Shape::Stroke { .. }), 1))), "{line}");
        }
        assert!(matches!(
            read(r##"<polygon opacity="0.3" fill="#000000" points="0,0 5,0 5,5 "/>"##),
            Some((Some(Shape::Fill { .. }), 1))
        ));
        // Nothing to draw, as usvg: an empty rectangle, a polyline of one point.
        for line in [
            r##"<rect x="904" y="455" width="43" height="0" opacity="0.45" fill="#0072B2" stroke="none"/>"##,
            r##"<polyline fill="none" opacity="1" stroke="#000000" stroke-width="1" points="59,114 "/>"##,
        ] {
            assert!(matches!(read(line), Some((None, 1))), "{line}");
        }
        for other in [
            r##"<rect x="3" y="4" width="14" height="26" rx="2" opacity="1" fill="#12ABEF" stroke="none"/>"##,
            r##"<rect x="3" y="4" width="14" height="26" opacity="1" fill="#12ABEF" stroke="#000000"/>"##,
            r##"<rect x="3" y="4" width="14" height="26" opacity="1.5" fill="#12ABEF" stroke="none"/>"##,
            r##"<rect x="3" y="4" width="14" height="26" opacity="1" fill="red" stroke="none"/>"##,
            r##"<circle cx="1" cy="2" r="3" fill="#000000"/>"##,
            r##"<path d="M0 0L5 5"/>"##,
            r##"<polyline fill="none" opacity="1" stroke="#000000" stroke-width="1" points="1,2 x,4 "/>"##,
            r##"<line opacity="1" stroke="#000000" stroke-width="0" x1="0" y1="0" x2="5" y2="5"/>"##,
            "<g>",
        ] {
            assert!(read(other).is_none(), "{other}");
        }
    }
}
