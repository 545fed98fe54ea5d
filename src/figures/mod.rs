//! Charts. A [`Figure`] draws itself on any plotters backend, so the same code yields the SVG
//! (for reports and the README) and the PNG (for slides). Text is laid out with an embedded
//! DejaVu Sans font, so nothing depends on the fonts installed on the machine.

use std::sync::Once;

use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::combinators::LogCoord;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::analysis::Analysis;
use crate::cascades::{bounds_2d, LightPose};
use crate::error::{Error, Result};
use crate::output::Exporter;

pub const FONT: &str = "sans-serif";

/// Registers the embedded font with plotters (once per process).
pub fn init_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// A drawing error from any backend, as text.
#[derive(Debug)]
pub struct PlotError(pub String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        PlotError(e.to_string())
    }
}

pub type PlotResult = std::result::Result<(), PlotError>;

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
            root.fill(&WHITE).map_err(|e| Error::Other(format!("plot: {e}")))?;
            self.draw(&root).map_err(|e| Error::Other(format!("plot: {}", e.0)))?;
            root.present().map_err(|e| Error::Other(format!("plot: {e}")))?;
        }
        Ok(s.into_bytes())
    }

    /// The SVG rasterised at twice its size (crisp on slides and high-DPI screens). Going
    /// through the SVG keeps one drawing path, so the PNG shows exactly what the SVG shows.
    fn to_png(&self) -> Result<Vec<u8>> {
        svg_to_png(&self.to_svg()?, 2.0)
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

/// Rasterises SVG bytes to an opaque PNG on a white background, `scale` pixels per SVG unit.
pub fn svg_to_png(svg: &[u8], scale: f32) -> Result<Vec<u8>> {
    use resvg::tiny_skia;
    let opt = resvg::usvg::Options {
        font_family: "DejaVu Sans".to_string(),
        fontdb: font_db(),
        ..Default::default()
    };
    let tree = resvg::usvg::Tree::from_data(svg, &opt).map_err(|e| Error::Other(format!("SVG to PNG: {e}")))?;
    let size = tree.size();
    let (w, h) = (
        (size.width() * scale).ceil() as u32,
        (size.height() * scale).ceil() as u32,
    );
    let mut pixmap =
        tiny_skia::Pixmap::new(w, h).ok_or_else(|| Error::Other(format!("SVG to PNG: bad size {w}x{h}")))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    // Opaque background, so premultiplied RGBA equals straight RGBA: drop alpha.
    let rgb: Vec<u8> = pixmap.data().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    encode_png(w, h, &rgb)
}

/// RGB8 pixels to PNG bytes.
pub fn encode_png(w: u32, h: u32, rgb: &[u8]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc
            .write_header()
            .map_err(|e| Error::Other(format!("PNG encoding: {e}")))?;
        writer
            .write_image_data(rgb)
            .map_err(|e| Error::Other(format!("PNG encoding: {e}")))?;
    }
    Ok(out)
}

/// Distinct, colour-blind-friendly-ish colours for series.
pub fn series_color(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(120, 120, 120),
        RGBColor(160, 40, 40),
    ];
    C[i % C.len()]
}

/// A chart that only says why there is nothing to show.
pub fn draw_message<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &str, message: &str) -> PlotResult {
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

/// Log-axis range that covers `lo..hi` with a margin and never collapses.
pub fn log_range(lo: f64, hi: f64) -> (f64, f64) {
    let lo = lo.max(1e-300);
    let hi = hi.max(lo * 1.0001);
    (lo / 1.3, hi * 1.3)
}

/// The chart type of the log-log "texels per pixel against view depth" figures.
pub type DepthChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// A log-log chart of texels per pixel against view depth over `depth` with its axes, labels and
/// the dashed "ideal: 1 texel per pixel" line already drawn; the y range covers `texels_per_pixel`
/// and 1. Shared by `analyze`'s density figure, `sweep`'s λ figure and `compare`'s overlay.
pub fn texels_per_pixel_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    caption_size: u32,
    depth: (f64, f64),
    texels_per_pixel: impl Iterator<Item = f64>,
) -> Result<(DepthChart<'a, DB>, (f64, f64)), PlotError> {
    let (ymin, ymax) = texels_per_pixel.fold((1.0f64, 1.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (y0, y1) = log_range(ymin, ymax);
    let (x0, x1) = depth;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, caption_size))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("view depth (world units, log)")
        .y_desc("texels per pixel (log; above 1 = sharper than the screen)")
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .draw()?;
    let ideal = BLACK.stroke_width(2);
    chart
        .draw_series(DashedLineSeries::new(vec![(x0, 1.0), (x1, 1.0)], 8, 5, ideal))?
        .label("ideal: 1 texel per pixel")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], ideal));
    Ok((chart, (y0, y1)))
}

/// Draws the series legend in the house style (white, framed box) at `position`.
pub fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
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

// ---------------------------------------------------------------------------------------------
// analyze: density.svg, shimmer.svg, cascades.svg
// ---------------------------------------------------------------------------------------------

/// Texels per pixel against view depth, log-log, with split lines and the ideal 1.
pub struct DensityFigure<'a>(pub &'a Analysis);

impl Figure for DensityFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let a = self.0;
        let title = format!("Shadow texels per screen pixel vs depth: {}", a.config.name);
        let Some(rig) = a.rig() else {
            return draw_message(
                root,
                &title,
                "No cascades needed: the scene is not visible within the shadow distance.",
            );
        };
        let (mut chart, (y0, y1)) = texels_per_pixel_chart(
            root,
            &title,
            22,
            (a.summary.z_lo, a.summary.z_hi),
            a.density.iter().map(|d| d.texels_per_pixel),
        )?;
        for (i, s) in rig.splits[1..rig.splits.len() - 1].iter().enumerate() {
            let style = RGBColor(150, 150, 150).stroke_width(1);
            let series = chart.draw_series(DashedLineSeries::new(vec![(*s, y0), (*s, y1)], 5, 4, style))?;
            if i == 0 {
                series
                    .label("split depths")
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            }
        }
        for (i, c) in a.cascades.iter().enumerate() {
            let color = series_color(i);
            let pts: Vec<(f64, f64)> = a
                .density
                .iter()
                .filter(|d| d.cascade == i)
                .map(|d| (d.depth, d.texels_per_pixel))
                .collect();
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(3)))?
                .label(format!(
                    "cascade {i}: {:.3}..{:.3}, texel {:.4}",
                    c.near, c.far, c.texel_size
                ))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3)));
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, 13)?;
        Ok(())
    }
}

/// Per-frame RMS phase drift over all cascades, snapped vs unsnapped.
pub struct ShimmerFigure<'a>(pub &'a Analysis);

impl Figure for ShimmerFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let a = self.0;
        let title = format!(
            "Sub-texel drift per frame ({} path, {} fit): {}",
            a.config.motion.path.name(),
            a.config.shadow.fit,
            a.config.name
        );
        let (Some(sn), Some(un)) = (a.snapped(), a.unsnapped()) else {
            return draw_message(root, &title, "No cascades needed: nothing can shimmer.");
        };
        let frames = a.config.motion.frames;
        let per_frame = |p: &crate::shimmer::PathResult| -> Vec<(f64, f64)> {
            let m = a.cascades.len().max(1);
            let mut acc = vec![0.0; frames];
            for f in &p.frames {
                acc[f.frame] += f.phase_drift_rms * f.phase_drift_rms / m as f64;
            }
            (1..frames).map(|t| (t as f64, acc[t].sqrt())).collect()
        };
        let s_pts = per_frame(sn);
        let u_pts = per_frame(un);
        let ymax = u_pts.iter().chain(&s_pts).map(|p| p.1).fold(0.0f64, f64::max).max(0.05) * 1.15;
        let mut chart = ChartBuilder::on(root)
            .caption(&title, (FONT, 22))
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..(frames.max(2) - 1) as f64, 0.0..ymax)?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc("RMS phase drift over cascades (texels)")
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .draw()?;
        let red = series_color(1);
        let blue = series_color(0);
        chart
            .draw_series(LineSeries::new(u_pts, red.stroke_width(2)))?
            .label(format!("unsnapped (RMS {:.3e} texels)", un.stats.rms))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], red.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(s_pts, blue.stroke_width(4)))?
            .label(format!("snapped (RMS {:.3e} texels)", sn.stats.rms))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], blue.stroke_width(4)));
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
        Ok(())
    }
}

/// Andrew's monotone chain convex hull, counter-clockwise.
pub fn convex_hull(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Top-down view from the light: each slice's footprint and its window (frame 0).
pub struct CascadesFigure<'a>(pub &'a Analysis);

impl Figure for CascadesFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (860, 800)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let a = self.0;
        let title = format!("Slices and windows seen from the light: {}", a.config.name);
        let Some(rig) = a.rig() else {
            return draw_message(root, &title, "No cascades needed.");
        };
        let pose = a.config.camera.pose();
        let lp = LightPose::new(&rig.light, &pose);
        let mut all = Vec::new();
        let mut items = Vec::new();
        for i in 0..rig.cascade_count() {
            let w = rig.window(i, &lp, a.config.shadow.snap);
            let s = &rig.slices[i];
            // Windows are in each cascade's own basis (the same for all but a few presets).
            let lpi = LightPose::new(&rig.basis(i, &lp), &pose);
            let corners = lpi.corners(&rig.lens, s.near, s.far);
            let lo = w.min();
            let hi = lo + glam::DVec2::new(w.width(), w.height());
            all.extend_from_slice(&corners);
            all.push(lo);
            all.push(hi);
            items.push((corners, lo, hi));
        }
        all.push(lp.position);
        let (lo, hi) = bounds_2d(&all);
        // Equal scales on both axes so shapes are not distorted.
        let c = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo).max_element() * 1.06;
        let mut chart = ChartBuilder::on(root)
            .caption(&title, (FONT, 20))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d((c.x - half)..(c.x + half), (c.y - half)..(c.y + half))?;
        chart
            .configure_mesh()
            .x_desc("light-space x (world units)")
            .y_desc("light-space y (world units)")
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 12))
            .draw()?;
        for (i, (corners, wlo, whi)) in items.iter().enumerate().rev() {
            let color = series_color(i);
            let hull = convex_hull(corners.iter().map(|p| (p.x, p.y)).collect());
            chart.draw_series(std::iter::once(Polygon::new(hull.clone(), color.mix(0.25).filled())))?;
            let mut outline = hull.clone();
            outline.push(hull[0]);
            chart.draw_series(std::iter::once(PathElement::new(outline, color.stroke_width(1))))?;
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(wlo.x, wlo.y), (whi.x, whi.y)],
                    color.stroke_width(2),
                )))?
                .label(format!(
                    "cascade {i}: window {:.3} x {:.3}",
                    whi.x - wlo.x,
                    whi.y - wlo.y
                ))
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], color.mix(0.5).filled()));
        }
        chart
            .draw_series(std::iter::once(Circle::new(
                (lp.position.x, lp.position.y),
                5,
                BLACK.filled(),
            )))?
            .label("camera")
            .legend(|(x, y)| Circle::new((x + 8, y), 4, BLACK.filled()));
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, 13)?;
        Ok(())
    }
}

pub struct DensitySvg;
pub struct ShimmerSvg;
pub struct CascadesSvg;

impl Exporter<Analysis> for DensitySvg {
    fn file_name(&self) -> &'static str {
        "density.svg"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        DensityFigure(a).to_svg()
    }
}

impl Exporter<Analysis> for ShimmerSvg {
    fn file_name(&self) -> &'static str {
        "shimmer.svg"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        ShimmerFigure(a).to_svg()
    }
}

impl Exporter<Analysis> for CascadesSvg {
    fn file_name(&self) -> &'static str {
        "cascades.svg"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        CascadesFigure(a).to_svg()
    }
}
