//! Runs of filled rectangles (the heat map's cells and colour-bar steps) written into the SVG
//! as plotters writes them, without plotters' per-element machinery.
//!
//! plotters draws a `Rectangle` by mapping its two corners through the chart's coordinates,
//! clamping them to the drawing area, ordering them, and formatting the `SVGBackend`'s line
//! `<rect x=".." y=".." width=".." height=".." opacity="1" fill="#RRGGBB" stroke="none"/>`
//! through half a dozen `format!` calls: 10,000 instructions a cell, a quarter of writing all
//! the sweep's SVGs. [`draw_filled`] maps and writes the same lines itself into a string held
//! aside, and leaves in their place one marker element (a pixel at `x = i32::MIN`, outside any
//! canvas); [`splice`] puts the lines in the marker's place once the document is written. The
//! bytes are plotters' (tests compare them on random charts).

use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Mutex, OnceLock};

use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::ranged1d::Ranged;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::{BackendColor, BackendCoord, DrawingErrorKind};

/// The lines held aside, by marker id, until [`splice`] puts them in place.
fn held() -> &'static Mutex<HashMap<u32, String>> {
    static HELD: OnceLock<Mutex<HashMap<u32, String>>> = OnceLock::new();
    HELD.get_or_init(Default::default)
}

/// The x of a marker pixel: no chart draws there.
const MARKER_X: i32 = i32::MIN;

/// The line plotters' SVG backend writes for the marker pixel of id `id` (its `draw_pixel`).
fn marker_line(id: u32) -> String {
    format!(
        "<rect x=\"{MARKER_X}\" y=\"{id}\" width=\"1\" height=\"1\" stroke=\"none\" opacity=\"1\" fill=\"#000000\"/>\n"
    )
}

/// The element that leaves a marker: one pixel at ([`MARKER_X`], id), black, opaque.
struct Marker(u32);

impl<'a, C: 'a> PointCollection<'a, C> for &'a Marker {
    type Point = &'a C;
    type IntoIter = std::iter::Empty<&'a C>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::empty()
    }
}

impl<DB: DrawingBackend> Drawable<DB> for Marker {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        _: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let black = BackendColor {
            alpha: 1.0,
            rgb: (0, 0, 0),
        };
        backend.draw_pixel((MARKER_X, self.0 as i32), black)
    }
}

/// Appends `v` in decimal (as `format!("{v}")`).
fn push_int(out: &mut String, v: i32) {
    let mut buf = [0u8; 11];
    let mut i = buf.len();
    let mut n = v.unsigned_abs();
    loop {
        i -= 1;
        buf[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    if v < 0 {
        out.push('-');
    }
    out.extend(buf[i..].iter().map(|&b| char::from(b)));
}

/// The line plotters' SVG backend writes for a rectangle from `a` to `b` (backend pixels,
/// ordered) filled opaquely with `c`.
fn push_rect(out: &mut String, a: BackendCoord, b: BackendCoord, c: RGBColor) {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    out.push_str("<rect x=\"");
    push_int(out, a.0);
    out.push_str("\" y=\"");
    push_int(out, a.1);
    out.push_str("\" width=\"");
    push_int(out, b.0 - a.0);
    out.push_str("\" height=\"");
    push_int(out, b.1 - a.1);
    out.push_str("\" opacity=\"1\" fill=\"#");
    for v in [c.0, c.1, c.2] {
        out.push(char::from(HEX[usize::from(v >> 4)]));
        out.push(char::from(HEX[usize::from(v & 15)]));
    }
    out.push_str("\" stroke=\"none\"/>\n");
}

/// Draws opaque filled rectangles (each two opposite corners in the chart's coordinates and
/// its colour) on `chart`, in order: what `chart.draw_series` of `Rectangle`s filled with
/// those colours draws, written into the SVG by [`splice`]. Only for a document that
/// [`super::Figure::to_svg`] writes (the one backend the figures are drawn on).
pub(crate) fn draw_filled<DB, X, Y>(
    chart: &ChartContext<'_, DB, Cartesian2d<X, Y>>,
    rects: impl IntoIterator<Item = ((X::ValueType, Y::ValueType), (X::ValueType, Y::ValueType), RGBColor)>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend,
    X: Ranged,
    Y: Ranged,
{
    let area = chart.plotting_area();
    let (xr, yr) = area.get_pixel_range();
    // The clamp plotters applies to every mapped point (the drawing area's `Rect::truncate`).
    let clamp = |p: BackendCoord| (p.0.min(xr.end).max(xr.start), p.1.min(yr.end).max(yr.start));
    let mut lines = String::new();
    for (p, q, c) in rects {
        let (p, q) = (clamp(chart.backend_coord(&p)), clamp(chart.backend_coord(&q)));
        push_rect(
            &mut lines,
            (p.0.min(q.0), p.1.min(q.1)),
            (p.0.max(q.0), p.1.max(q.1)),
            c,
        );
    }
    if lines.is_empty() {
        return Ok(());
    }
    static NEXT: AtomicU32 = AtomicU32::new(0);
    // Ids stay below 2³¹ (the marker's y is an i32): they wrap long before a process could
    // hold two live documents with the same one.
    let id = NEXT.fetch_add(1, Ordering::Relaxed) & (i32::MAX as u32);
    held().lock().unwrap_or_else(|e| e.into_inner()).insert(id, lines);
    area.draw(&Marker(id))
}

/// `svg` with every marker of [`draw_filled`] replaced by the lines held for it.
pub(crate) fn splice(svg: String) -> String {
    const PREFIX: &str = "<rect x=\"-2147483648\" y=\"";
    if !svg.contains(PREFIX) {
        return svg;
    }
    let mut held = held().lock().unwrap_or_else(|e| e.into_inner());
    let mut out = String::with_capacity(svg.len());
    let mut rest = svg.as_str();
    while let Some(at) = rest.find(PREFIX) {
        out.push_str(&rest[..at]);
        rest = &rest[at..];
        let line_end = rest.find('\n').map_or(rest.len(), |e| e + 1);
        let line = &rest[..line_end];
        let id = line[PREFIX.len()..]
            .split_once('"')
            .and_then(|(id, _)| id.parse::<u32>().ok());
        match id.filter(|&id| line == marker_line(id)).and_then(|id| held.remove(&id)) {
            Some(lines) => out.push_str(&lines),
            None => out.push_str(line),
        }
        rest = &rest[line_end..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::{log_axis, ticked_axis};
    use proptest::prelude::*;

    /// A rectangle's two corners (chart coordinates) and its colour.
    type Filled = ((f64, f64), (f64, f64), RGBColor);

    /// A chart's SVG with `rects` drawn by plotters (`draw_series`) or by [`draw_filled`]
    /// and spliced, between two plotters elements.
    fn chart_svg(size: (u32, u32), log: bool, rects: &[Filled], direct: bool) -> String {
        let mut s = String::new();
        {
            let root = SVGBackend::with_string(&mut s, size).into_drawing_area();
            root.fill(&WHITE).unwrap();
            let builder = |root| {
                let mut b = ChartBuilder::on(root);
                b.margin(7).x_label_area_size(30).y_label_area_size(25);
                b
            };
            let ticks = vec![0.5, 1.5, 2.5];
            if log {
                let mut chart = builder(&root)
                    .build_cartesian_2d(ticked_axis(0.0, 3.0, ticks), log_axis(0.1, 100.0))
                    .unwrap();
                let rects = rects
                    .iter()
                    .map(|&((x0, y0), (x1, y1), c)| ((x0, 0.1 + y0.abs()), (x1, 0.1 + y1.abs()), c));
                if direct {
                    draw_filled(&chart, rects).unwrap();
                } else {
                    chart
                        .draw_series(rects.map(|(p, q, c)| Rectangle::new([p, q], c.filled())))
                        .unwrap();
                }
                chart.plotting_area().draw(&Circle::new((1.0, 1.0), 3, RED)).unwrap();
            } else {
                let mut chart = builder(&root)
                    .build_cartesian_2d(ticked_axis(0.0, 3.0, ticks.clone()), ticked_axis(-1.0, 4.0, ticks))
                    .unwrap();
                if direct {
                    draw_filled(&chart, rects.iter().copied()).unwrap();
                } else {
                    chart
                        .draw_series(rects.iter().map(|&(p, q, c)| Rectangle::new([p, q], c.filled())))
                        .unwrap();
                }
                chart.plotting_area().draw(&Circle::new((1.0, 1.0), 3, RED)).unwrap();
            }
            root.present().unwrap();
        }
        splice(s)
    }

    fn rect() -> impl Strategy<Value = Filled> {
        // Corners inside, on and outside the axes' ranges (clamped), in either order.
        (
            -2.0..6.0f64,
            -3.0..7.0f64,
            -2.0..6.0f64,
            -3.0..7.0f64,
            any::<(u8, u8, u8)>(),
        )
            .prop_map(|(x0, y0, x1, y1, (r, g, b))| ((x0, y0), (x1, y1), RGBColor(r, g, b)))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn filled_rectangles_are_written_as_plotters_writes_them(
            w in 60u32..900,
            h in 60u32..700,
            log in any::<bool>(),
            rects in proptest::collection::vec(rect(), 0..40),
        ) {
            let theirs = chart_svg((w, h), log, &rects, false);
            let ours = chart_svg((w, h), log, &rects, true);
            prop_assert_eq!(ours, theirs);
        }
    }

    #[test]
    fn integers_are_written_as_format_writes_them() {
        for v in [0, 1, -1, 9, 10, -10, 99, 12345, i32::MAX, i32::MIN, -2147483647] {
            let mut s = String::new();
            push_int(&mut s, v);
            assert_eq!(s, v.to_string());
        }
    }

    #[test]
    fn a_marker_without_lines_held_is_left_as_it_is() {
        let svg = format!("<svg>\n{}</svg>\n", marker_line(i32::MAX as u32));
        assert_eq!(splice(svg.clone()), svg);
    }
}
