//! Pictures of the shadow-map ground truth: what the sampled map shows on screen and how it
//! behaves along the camera path.
//!
//! - [`shadow_png`] (`shadow.png`): the camera view (the visibility pass's sampled grid, enlarged
//!   with nearest-neighbour) shaded lit or shadowed as the map says, acne and leaks in colours of
//!   their own, with a legend of counts and shares; snapped and unsnapped side by side.
//! - [`flicker_png`] (`flicker.png`): each receiver pixel coloured by how often the map's answer
//!   flipped between consecutive frames, with a colour bar.
//! - [`write_animation`] / [`ShadowAnimation`] (`shadow.apng`): an animated PNG of every k-th
//!   frame of the path, streamed frame by frame, under fixed caps ([`ANIMATION_CAPS`]).
//! - [`FlickerVsShimmer`] (`flicker_vs_shimmer.svg/png` of a sweep): S5 against S3 and S4 per
//!   configuration with the least-squares line and the correlations.
//!
//! Inputs are plain values ([`ShadeImage`], [`FlipImage`], [`ShimmerPoint`]); nothing here
//! computes a shadow. Panels carry their own titles ([`Panel::snapped`], [`Panel::unsnapped`]).
//!
//! # Wiring (where the ground-truth pass's data goes in)
//!
//! - `analyze`: add `("shadow.png", shadow_png(&panels)?)` and `("flicker.png",
//!   flicker_png(&panels)?)` to the rendered files, and `ShadowAnimation { plan:
//!   AnimationPlan::new(frames, cols, rows, &["snapped", "unsnapped"], &ANIMATION_CAPS)?,
//!   frames: || /* the path's per-frame [snapped, unsnapped] ShadeImages */ }` to the streamed
//!   files of `output::write_files_streamed` (it restarts the path itself and holds one frame).
//!   Only every `plan.every`-th frame is drawn: a producer may skip the others cheaply by
//!   implementing `Iterator::nth`.
//! - `sweep`: push [`flicker_vs_shimmer_figure`] (stem, caption, SVG) onto the figures of
//!   `report::sweep::render_figures`; its PNG and its place in `report.html` follow.
//! - `report.html`: `report::truth::section(label, &TruthPictures { .. })` after the camera
//!   view of the recommended configuration.

use std::fmt::Write as _;
use std::io::Write;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    colormap, draw_legend_below, draw_message, encode_png, house_mesh, legend_frame, legend_height, linear_axis,
    nice_ticks, series_color, short, svg_to_rgb, tick, Figure, Legend, PlotResult, FONT, LEGEND_FONT,
};
use crate::error::{PlotError, Result};
use crate::output::StreamedFile;
use csm_core::shade::{FlipImage, Shade, ShadeImage};

// ---------------------------------------------------------------------------------------------
// Colours and layout
// ---------------------------------------------------------------------------------------------

/// The colour of each shadow state, and of the flicker map's marks.
pub mod colours {
    /// No receiver (sky, a point no cascade serves, a receiver that left the view).
    pub const EMPTY: [u8; 3] = [236, 236, 236];
    /// A surface turned from the light: in shadow by its own orientation (a shade of its own,
    /// so a building's shadowed face never reads as a notch of sky).
    pub(crate) const AWAY: [u8; 3] = [118, 116, 136];
    /// Lit by the map, truly lit.
    pub(crate) const LIT: [u8; 3] = [246, 222, 140];
    /// Shadowed by the map, truly shadowed.
    pub(crate) const SHADOWED: [u8; 3] = [72, 84, 112];
    /// Shadowed by the map, truly lit, every texel read holding its own surface (acne).
    pub(crate) const ACNE: [u8; 3] = [213, 40, 120];
    /// Wrong because the texels read hold another surface (the blocky edge, either way).
    pub(crate) const EDGE: [u8; 3] = [240, 130, 20];
    /// Lit by the map only because of the bias, truly shadowed (peter-panning, light leaks).
    pub(crate) const LEAK: [u8; 3] = [0, 190, 220];
    /// The animation's progress bar.
    pub const PROGRESS: [u8; 3] = [213, 94, 0];
}

/// Every shadow state, in the order of the pictures' palette.
pub const SHADES: [Shade; 7] = [
    Shade::Empty,
    Shade::Lit,
    Shade::Shadowed,
    Shade::Acne,
    Shade::Edge,
    Shade::Leak,
    Shade::Away,
];

/// The colour of a state in `shadow.png` and `shadow.apng`.
pub(crate) fn shade_colour(s: Shade) -> [u8; 3] {
    match s {
        Shade::Empty => colours::EMPTY,
        Shade::Lit => colours::LIT,
        Shade::Shadowed => colours::SHADOWED,
        Shade::Acne => colours::ACNE,
        Shade::Edge => colours::EDGE,
        Shade::Leak => colours::LEAK,
        Shade::Away => colours::AWAY,
    }
}

/// The colour of flip rate `v` on a scale from 0 to `vmax` (viridis-like; 0 is the darkest).
pub(crate) fn flip_colour(v: f64, vmax: f64) -> [u8; 3] {
    let t = if vmax > 0.0 { v / vmax } else { 0.0 };
    let c = colormap(t);
    [c.0, c.1, c.2]
}

/// White space between two panels, in pixels.
pub(crate) const GAP: u32 = 16;
/// The band above the panels that holds their titles.
pub(crate) const TITLE_H: u32 = 30;
/// The widest `shadow.png` and `flicker.png`, in pixels.
pub(crate) const MAX_WIDTH: u32 = 1280;
/// The narrowest `shadow.png` and `flicker.png` (room for the legend), in pixels; narrower
/// panels are left-aligned on white.
pub(crate) const MIN_WIDTH: u32 = 960;
/// The narrowest animation (room for its legend), in pixels.
pub(crate) const MIN_ANIMATION_WIDTH: u32 = 520;
/// The tallest panel of `shadow.png` and `flicker.png`, in pixels.
pub(crate) const MAX_PANEL_HEIGHT: u32 = 900;

/// One image of a figure with its title.
#[derive(Debug, Clone, Copy)]
pub struct Panel<'a, T> {
    pub title: &'a str,
    pub image: &'a T,
}

impl<'a, T> Panel<'a, T> {
    pub fn snapped(image: &'a T) -> Self {
        Panel {
            title: "snapped",
            image,
        }
    }
    pub fn unsnapped(image: &'a T) -> Self {
        Panel {
            title: "unsnapped",
            image,
        }
    }
}

/// The size of a `cols × rows` grid drawn into at most `max_w × max_h` pixels: enlarged by the
/// largest whole factor that fits (pixels stay square and equal), or shrunk when the grid is
/// larger than the box.
pub(crate) fn panel_size(cols: u32, rows: u32, max_w: u32, max_h: u32) -> (u32, u32) {
    let (cols, rows) = (cols.max(1), rows.max(1));
    if cols <= max_w && rows <= max_h {
        let k = (max_w / cols).min(max_h / rows).max(1);
        (cols * k, rows * k)
    } else {
        let s = (max_w as f64 / cols as f64).min(max_h as f64 / rows as f64);
        (
            ((cols as f64 * s).floor() as u32).max(1),
            ((rows as f64 * s).floor() as u32).max(1),
        )
    }
}

/// Where panels go: `n` panels of `pw × ph` pixels, [`GAP`] apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    pub cols: u32,
    pub rows: u32,
    pub panels: u32,
    pub pw: u32,
    pub ph: u32,
    /// The picture is at least this wide (its legend's room), panels left-aligned.
    pub min_width: u32,
}

impl Layout {
    pub(crate) fn new(cols: u32, rows: u32, panels: u32, max_w: u32, max_h: u32) -> Layout {
        let panels = panels.max(1);
        let per = (max_w.saturating_sub(GAP * (panels - 1)) / panels).max(1);
        let (pw, ph) = panel_size(cols, rows, per, max_h);
        Layout {
            cols,
            rows,
            panels,
            pw,
            ph,
            min_width: 0,
        }
    }

    /// The layout with the picture at least `w` pixels wide.
    pub(crate) fn at_least(self, w: u32) -> Layout {
        Layout { min_width: w, ..self }
    }

    /// The width of the picture: all panels with their gaps, or [`Self::min_width`].
    pub(crate) fn width(&self) -> u32 {
        (self.panels * self.pw + GAP * (self.panels - 1)).max(self.min_width)
    }

    /// The left edge of panel `i`.
    pub(crate) fn panel_x(&self, i: u32) -> u32 {
        i * (self.pw + GAP)
    }

    /// The grid pixel (row-major index) shown at panel pixel (x, y).
    pub(crate) fn source(&self, x: u32, y: u32) -> usize {
        let c = (x as u64 * self.cols as u64 / self.pw as u64) as usize;
        let r = (y as u64 * self.rows as u64 / self.ph as u64) as usize;
        r * self.cols as usize + c
    }
}

/// An RGB8 picture being put together.
struct Canvas {
    w: u32,
    h: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(w: u32, h: u32) -> Canvas {
        Canvas {
            w,
            h,
            rgb: vec![255; w as usize * h as usize * 3],
        }
    }

    /// Panel `i` of `layout` at height `y0`, pixel colours from `colour(grid index)`.
    fn panel(&mut self, layout: &Layout, i: u32, y0: u32, colour: impl Fn(usize) -> [u8; 3]) {
        let x0 = layout.panel_x(i);
        for y in 0..layout.ph {
            for x in 0..layout.pw {
                let o = (((y0 + y) * self.w + x0 + x) * 3) as usize;
                self.rgb[o..o + 3].copy_from_slice(&colour(layout.source(x, y)));
            }
        }
    }

    /// An SVG strip (as wide as the canvas) rasterised at height `y0`; returns its height.
    fn svg(&mut self, y0: u32, svg: &str) -> Result<u32> {
        let (sw, sh, rgb) = svg_to_rgb(svg.as_bytes(), 1.0)?;
        for y in 0..sh.min(self.h.saturating_sub(y0)) {
            for x in 0..sw.min(self.w) {
                let i = ((y * sw + x) * 3) as usize;
                let o = (((y0 + y) * self.w + x) * 3) as usize;
                self.rgb[o..o + 3].copy_from_slice(&rgb[i..i + 3]);
            }
        }
        Ok(sh)
    }

    fn png(&self) -> Result<Vec<u8>> {
        encode_png(self.w, self.h, &self.rgb)
    }
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// An SVG strip `w × h` pixels in the figures' font, white behind `body`.
fn strip(w: u32, h: u32, body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"{FONT}\" font-size=\"13\">\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>{body}</svg>"
    )
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The titles strip: each panel's title centred over it, `extra` (markup) after.
fn titles_svg<T>(layout: &Layout, panels: &[Panel<'_, T>], extra: &str) -> String {
    let titles: Vec<&str> = panels.iter().map(|p| p.title).collect();
    titles_strip(layout, &titles, extra)
}

fn titles_strip(layout: &Layout, titles: &[&str], extra: &str) -> String {
    let mut body = String::new();
    for (i, t) in titles.iter().enumerate() {
        let cx = layout.panel_x(i as u32) as f64 + layout.pw as f64 / 2.0;
        let _ = write!(
            body,
            "<text x=\"{cx}\" y=\"21\" text-anchor=\"middle\" font-weight=\"bold\" font-size=\"15\">{}</text>",
            esc(t)
        );
    }
    body.push_str(extra);
    strip(layout.width(), TITLE_H, &body)
}

/// The glyphs of the animation's frame counter, each centred in a cell [`CELL_W`] pixels wide.
const GLYPHS: &str = "0123456789/";
/// A counter glyph's cell: a 13-pixel DejaVu Sans digit advances 8.3 pixels.
const CELL_W: u32 = 9;

fn glyph_strip() -> String {
    let mut body = String::new();
    for (i, ch) in GLYPHS.chars().enumerate() {
        let _ = write!(
            body,
            "<text x=\"{}\" y=\"21\" text-anchor=\"middle\" fill=\"#444\">{ch}</text>",
            CELL_W as f64 * (i as f64 + 0.5)
        );
    }
    strip(CELL_W * GLYPHS.len() as u32, TITLE_H, &body)
}

fn swatch(x: f64, y: f64, c: [u8; 3], label: &str) -> String {
    format!(
        "<rect x=\"{x}\" y=\"{}\" width=\"14\" height=\"14\" fill=\"{}\" stroke=\"#888\"/><text x=\"{}\" y=\"{y}\">{}</text>",
        y - 12.0,
        hex(c),
        x + 19.0,
        esc(label)
    )
}

/// A share in per cent with two decimals ("0.00 %" only when the count is 0).
fn percent(n: usize, of: usize) -> String {
    if of == 0 {
        return "-".to_string();
    }
    let p = 100.0 * n as f64 / of as f64;
    if n > 0 && p < 0.005 {
        "< 0.01 %".to_string()
    } else {
        format!("{p:.2} %")
    }
}

fn check_panels<T>(panels: &[Panel<'_, T>], dims: impl Fn(&T) -> (u32, u32, usize), what: &str) -> Result<(u32, u32)> {
    let first = panels
        .first()
        .ok_or_else(|| PlotError::Draw(format!("{what}: no image to draw")))?;
    let (cols, rows, _) = dims(first.image);
    for p in panels {
        let (c, r, n) = dims(p.image);
        if (c, r) != (cols, rows) || n != c as usize * r as usize || c == 0 || r == 0 {
            return Err(PlotError::Draw(format!(
                "{what}: panel '{}' is {c} × {r} with {n} pixels; every panel must be {cols} × {rows} with one value per pixel",
                p.title
            ))
            .into());
        }
    }
    if panels.len() > 2 {
        return Err(PlotError::Draw(format!(
            "{what}: at most two panels (snapped, unsnapped), got {}",
            panels.len()
        ))
        .into());
    }
    Ok((cols, rows))
}

// ---------------------------------------------------------------------------------------------
// shadow.png
// ---------------------------------------------------------------------------------------------

/// Pixels of each state in one image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct ShadeCounts {
    pub empty: usize,
    pub lit: usize,
    pub shadowed: usize,
    pub acne: usize,
    pub edge: usize,
    pub leak: usize,
    pub away: usize,
}

impl ShadeCounts {
    pub(crate) fn of(image: &ShadeImage) -> ShadeCounts {
        let mut c = ShadeCounts::default();
        for s in &image.pixels {
            match s {
                Shade::Empty => c.empty += 1,
                Shade::Lit => c.lit += 1,
                Shade::Shadowed => c.shadowed += 1,
                Shade::Acne => c.acne += 1,
                Shade::Edge => c.edge += 1,
                Shade::Leak => c.leak += 1,
                Shade::Away => c.away += 1,
            }
        }
        c
    }

    /// Pixels with a receiver.
    pub(crate) fn receivers(&self) -> usize {
        self.lit + self.shadowed + self.acne + self.edge + self.leak
    }
}

const SHADE_LEGEND_H: u32 = 96;

/// The states' legend: the swatches on one line, then three lines of counts under each panel.
fn shade_legend<T>(layout: &Layout, panels: &[Panel<'_, T>], counts: &[ShadeCounts]) -> String {
    let mut body = String::new();
    let mut x = 4.0;
    for (c, label) in [
        (colours::LIT, "lit"),
        (colours::SHADOWED, "shadowed"),
        (colours::ACNE, "acne (own surface)"),
        (colours::EDGE, "edge (another surface)"),
        (colours::LEAK, "leak (the bias)"),
        (colours::AWAY, "turned from the light"),
        (colours::EMPTY, "no receiver"),
    ] {
        body.push_str(&swatch(x, 22.0, c, label));
        x += 34.0 + 7.0 * label.chars().count() as f64;
    }
    for (i, (p, c)) in panels.iter().zip(counts).enumerate() {
        let x0 = layout.panel_x(i as u32) as f64 + 4.0;
        let n = c.receivers();
        let lines = [
            format!("{}: {} receiver pixels of {}", p.title, n, n + c.empty),
            format!(
                "lit {} ({}), shadowed {} ({})",
                c.lit,
                percent(c.lit, n),
                c.shadowed,
                percent(c.shadowed, n)
            ),
            format!(
                "acne {} ({}), edge {} ({}), leak {} ({})",
                c.acne,
                percent(c.acne, n),
                c.edge,
                percent(c.edge, n),
                c.leak,
                percent(c.leak, n)
            ),
        ];
        for (k, l) in lines.iter().enumerate() {
            let _ = write!(body, "<text x=\"{x0}\" y=\"{}\">{}</text>", 46 + 17 * k, esc(l));
        }
    }
    strip(layout.width(), SHADE_LEGEND_H, &body)
}

/// `shadow.png`: the panels (one or two images of the same grid) side by side under their
/// titles, each pixel in its state's colour ([`shade_colour`]), with the legend below. The grid
/// is enlarged by a whole factor (or shrunk) to at most [`MAX_WIDTH`] pixels in all.
pub fn shadow_png(panels: &[Panel<'_, ShadeImage>]) -> Result<Vec<u8>> {
    let (cols, rows) = check_panels(panels, |i| (i.cols, i.rows, i.pixels.len()), "shadow.png")?;
    let layout = Layout::new(cols, rows, panels.len() as u32, MAX_WIDTH, MAX_PANEL_HEIGHT).at_least(MIN_WIDTH);
    let counts: Vec<ShadeCounts> = panels.iter().map(|p| ShadeCounts::of(p.image)).collect();
    let mut c = Canvas::new(layout.width(), TITLE_H + layout.ph + SHADE_LEGEND_H);
    c.svg(0, &titles_svg(&layout, panels, ""))?;
    for (i, p) in panels.iter().enumerate() {
        c.panel(&layout, i as u32, TITLE_H, |k| shade_colour(p.image.pixels[k]));
    }
    c.svg(TITLE_H + layout.ph, &shade_legend(&layout, panels, &counts))?;
    c.png()
}

// ---------------------------------------------------------------------------------------------
// flicker.png
// ---------------------------------------------------------------------------------------------

/// What a flip image holds: receivers, how many flipped at all, the mean and largest rate.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct FlipStats {
    pub receivers: usize,
    pub flipped: usize,
    pub mean: f64,
    pub max: f64,
}

impl FlipStats {
    pub(crate) fn of(image: &FlipImage) -> FlipStats {
        let mut s = FlipStats::default();
        let mut sum = 0.0;
        for v in image.flips.iter().flatten() {
            s.receivers += 1;
            if *v > 0.0 {
                s.flipped += 1;
            }
            sum += v;
            s.max = s.max.max(*v);
        }
        if s.receivers > 0 {
            s.mean = sum / s.receivers as f64;
        }
        s
    }
}

const FLICKER_LEGEND_H: u32 = 110;
/// The colour bar's left edge and length, in pixels.
const BAR_X: f64 = 10.0;
const BAR_LEN: f64 = 360.0;

/// The largest value of the flicker colour scale: the largest rate, rounded up to a tick.
pub fn flip_scale_max(max: f64) -> f64 {
    if max <= 0.0 {
        return 0.0;
    }
    let step = {
        let t = nice_ticks(0.0, max, false);
        if t.len() >= 2 {
            t[1] - t[0]
        } else {
            max
        }
    };
    // Rounded to 12 decimals so that 3 steps of 0.1 are 0.3, the tick's own value.
    let top = ((max / step).ceil() * step * 1e12).round() / 1e12;
    top.min(1.0).max(max)
}

fn flicker_legend<T>(layout: &Layout, panels: &[Panel<'_, T>], stats: &[FlipStats], vmax: f64) -> String {
    let mut body = String::new();
    let receivers: usize = stats.iter().map(|s| s.receivers).sum();
    if receivers == 0 {
        body.push_str("<text x=\"10\" y=\"26\" font-size=\"16\" font-weight=\"bold\">No receiver pixel in view: nothing to show (nothing can flicker).</text>");
    } else if vmax <= 0.0 {
        body.push_str("<text x=\"10\" y=\"26\" font-size=\"16\" font-weight=\"bold\">No receiver pixel flipped between lit and shadowed along the path: nothing flickers.</text>");
    } else {
        let steps = 90;
        for i in 0..steps {
            let c = flip_colour((i as f64 + 0.5) / steps as f64 * vmax, vmax);
            let _ = write!(
                body,
                "<rect x=\"{}\" y=\"8\" width=\"4\" height=\"14\" fill=\"{}\"/>",
                BAR_X + 4.0 * i as f64,
                hex(c)
            );
        }
        let mut ticks = nice_ticks(0.0, vmax, false);
        ticks.retain(|t| *t <= vmax * (1.0 + 1e-12));
        for t in ticks {
            let x = BAR_X + BAR_LEN * t / vmax;
            let _ = write!(
                body,
                "<line x1=\"{x}\" y1=\"6\" x2=\"{x}\" y2=\"26\" stroke=\"black\"/><text x=\"{x}\" y=\"40\" text-anchor=\"middle\">{}</text>",
                tick(t)
            );
        }
        let _ = write!(
            body,
            "<text x=\"{}\" y=\"19\">flip rate (share of frame pairs with a changed answer)</text>",
            BAR_X + BAR_LEN + 16.0
        );
    }
    for (i, (p, s)) in panels.iter().zip(stats).enumerate() {
        let x0 = layout.panel_x(i as u32) as f64 + 4.0;
        let lines = [
            format!("{}: {} receiver pixels", p.title, s.receivers),
            format!(
                "flipped at least once: {} ({})",
                s.flipped,
                percent(s.flipped, s.receivers)
            ),
            format!("mean flip rate {}, max {}", short(s.mean), short(s.max)),
        ];
        for (k, l) in lines.iter().enumerate() {
            let _ = write!(body, "<text x=\"{x0}\" y=\"{}\">{}</text>", 62 + 17 * k, esc(l));
        }
    }
    let _ = write!(
        body,
        "<rect x=\"{}\" y=\"{}\" width=\"14\" height=\"14\" fill=\"{}\" stroke=\"#888\"/>",
        layout.width().saturating_sub(110),
        8,
        hex(colours::EMPTY)
    );
    let _ = write!(
        body,
        "<text x=\"{}\" y=\"20\">no receiver</text>",
        layout.width().saturating_sub(91)
    );
    strip(layout.width(), FLICKER_LEGEND_H, &body)
}

/// `flicker.png`: each receiver pixel coloured by its flip rate ([`flip_colour`], one scale for
/// all panels from 0 to [`flip_scale_max`]), pixels without a receiver in [`colours::EMPTY`],
/// with a titled colour bar and per-panel counts below. With no receiver, or no flip anywhere,
/// the legend says so in place of the colour bar.
pub fn flicker_png(panels: &[Panel<'_, FlipImage>]) -> Result<Vec<u8>> {
    let (cols, rows) = check_panels(panels, |i| (i.cols, i.rows, i.flips.len()), "flicker.png")?;
    for p in panels {
        if let Some(v) = p.image.flips.iter().flatten().find(|v| !(0.0..=1.0).contains(*v)) {
            return Err(PlotError::Draw(format!(
                "flicker.png: panel '{}' has the flip rate {v}; a rate lies in [0, 1]",
                p.title
            ))
            .into());
        }
    }
    let layout = Layout::new(cols, rows, panels.len() as u32, MAX_WIDTH, MAX_PANEL_HEIGHT).at_least(MIN_WIDTH);
    let stats: Vec<FlipStats> = panels.iter().map(|p| FlipStats::of(p.image)).collect();
    let vmax = flip_scale_max(stats.iter().map(|s| s.max).fold(0.0, f64::max));
    let mut c = Canvas::new(layout.width(), TITLE_H + layout.ph + FLICKER_LEGEND_H);
    c.svg(0, &titles_svg(&layout, panels, ""))?;
    for (i, p) in panels.iter().enumerate() {
        c.panel(&layout, i as u32, TITLE_H, |k| match p.image.flips[k] {
            None => colours::EMPTY,
            Some(v) => flip_colour(v, vmax),
        });
    }
    c.svg(TITLE_H + layout.ph, &flicker_legend(&layout, panels, &stats, vmax))?;
    c.png()
}

// ---------------------------------------------------------------------------------------------
// shadow.apng
// ---------------------------------------------------------------------------------------------

/// The file name of the animation.
pub(crate) const SHADOW_APNG: &str = "shadow.apng";

/// What bounds the animation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnimationCaps {
    /// Frames shown at most (every k-th frame of the path, k chosen to fit).
    pub max_frames: usize,
    /// Width and height of the animation at most, in pixels.
    pub max_width: u32,
    pub max_height: u32,
    /// Bytes of the file at most: guaranteed by construction (see [`AnimationPlan::byte_bound`]).
    pub max_bytes: u64,
    /// Path frames per second of playback: a shown frame standing for k path frames is held
    /// k / `path_fps` seconds (clamped to 40..500 ms).
    pub path_fps: f64,
}

/// The caps of `shadow.apng`: 48 frames, 1000 × 540 pixels, 16 MiB, played at 30 path frames per
/// second. The default grid (240 × 135) is shown at twice its size, two panels in 976 pixels.
pub const ANIMATION_CAPS: AnimationCaps = AnimationCaps {
    max_frames: 48,
    max_width: 1000,
    max_height: 540,
    max_bytes: 16 << 20,
    path_fps: 30.0,
};

const PROGRESS_H: u32 = 6;
const ANIM_LEGEND_H: u32 = 26;
/// Bytes of the file besides its frames (signature, IHDR, acTL, PLTE, IEND), at most.
const HEADER_BOUND: u64 = 1024;
/// Palette: 16 greys (white to black) for the text, then the states and the progress bar.
const GREYS: usize = 16;
const PAL_STATE: usize = GREYS;
const PAL_PROGRESS: usize = GREYS + 7;

fn palette_rgb() -> Vec<[u8; 3]> {
    let mut p: Vec<[u8; 3]> = (0..GREYS)
        .map(|i| {
            let v = (255.0 * (1.0 - i as f64 / (GREYS - 1) as f64)).round() as u8;
            [v, v, v]
        })
        .collect();
    for s in SHADES {
        p.push(shade_colour(s));
    }
    p.push(colours::PROGRESS);
    p
}

fn state_index(s: Shade) -> u8 {
    (PAL_STATE
        + match s {
            Shade::Empty => 0,
            Shade::Lit => 1,
            Shade::Shadowed => 2,
            Shade::Acne => 3,
            Shade::Edge => 4,
            Shade::Leak => 5,
            Shade::Away => 6,
        }) as u8
}

/// The nearest palette entry of an RGB colour (rasterised text and swatches).
fn nearest(pal: &[[u8; 3]], c: &[u8]) -> u8 {
    let d = |p: &[u8; 3]| -> i32 { (0..3).map(|k| (p[k] as i32 - c[k] as i32).pow(2)).sum() };
    (0..pal.len()).min_by_key(|&i| (d(&pal[i]), i)).unwrap_or(0) as u8
}

/// How a path becomes the animation: its size, which frames are shown and for how long.
#[derive(Debug, Clone, PartialEq)]
pub struct AnimationPlan {
    /// Frames of the path.
    pub path_frames: usize,
    /// Every `every`-th path frame is shown, from frame 0.
    pub every: usize,
    /// Frames in the animation: `ceil(path_frames / every)`.
    pub shown: usize,
    /// How long each frame is held, in milliseconds.
    pub delay_ms: u16,
    pub layout: Layout,
    /// The titles of the panels, left to right.
    pub titles: Vec<String>,
}

impl AnimationPlan {
    /// The plan for a path of `path_frames` frames of a `cols × rows` grid with one panel per
    /// title (one or two), under `caps`.
    pub fn new(path_frames: usize, cols: u32, rows: u32, titles: &[&str], caps: &AnimationCaps) -> Result<Self> {
        if path_frames == 0 || cols == 0 || rows == 0 || titles.is_empty() || titles.len() > 2 {
            return Err(PlotError::Draw(format!(
                "shadow animation: needs a path with frames, a grid and one or two panels (got {path_frames} frames, {cols} × {rows}, {} panels)",
                titles.len()
            ))
            .into());
        }
        let fixed = TITLE_H + PROGRESS_H + ANIM_LEGEND_H;
        let layout = Layout::new(
            cols,
            rows,
            titles.len() as u32,
            caps.max_width,
            caps.max_height.saturating_sub(fixed).max(1),
        )
        .at_least(MIN_ANIMATION_WIDTH.min(caps.max_width));
        let mut plan = AnimationPlan {
            path_frames,
            every: 1,
            shown: path_frames,
            delay_ms: 0,
            layout,
            titles: titles.iter().map(|t| t.to_string()).collect(),
        };
        let by_bytes = ((caps.max_bytes.saturating_sub(HEADER_BOUND)) / plan.frame_bound()).max(1) as usize;
        let max_shown = caps.max_frames.min(by_bytes).max(1);
        plan.every = path_frames.div_ceil(max_shown);
        plan.shown = path_frames.div_ceil(plan.every);
        plan.delay_ms = (1000.0 * plan.every as f64 / caps.path_fps).round().clamp(40.0, 500.0) as u16;
        Ok(plan)
    }

    pub(crate) fn width(&self) -> u32 {
        self.layout.width()
    }

    pub(crate) fn height(&self) -> u32 {
        TITLE_H + PROGRESS_H + self.layout.ph + ANIM_LEGEND_H
    }

    /// The path frames shown, in order.
    pub fn frames(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.path_frames).step_by(self.every)
    }

    /// The most bytes one frame can take whatever it shows: the raw indexed rows (one filter
    /// byte each) stored without compression, plus deflate's and the chunks' framing.
    pub(crate) fn frame_bound(&self) -> u64 {
        let raw = self.height() as u64 * (self.width() as u64 + 1);
        raw + raw / 1024 + 256
    }

    /// The most bytes the file can take: [`HEADER_BOUND`] plus [`Self::frame_bound`] per frame.
    pub fn byte_bound(&self) -> u64 {
        HEADER_BOUND + self.shown as u64 * self.frame_bound()
    }
}

/// Counts the bytes written through it.
struct Counting<'a> {
    inner: &'a mut dyn Write,
    n: u64,
}

impl Write for Counting<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let k = self.inner.write(buf)?;
        self.n += k as u64;
        Ok(k)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

fn png_err(e: png::EncodingError) -> crate::error::Error {
    PlotError::Png(e.to_string()).into()
}

/// Writes the animation of a path to `out`: `frames` yields every path frame's images (one per
/// panel of `plan`, in the titles' order), and every `plan.every`-th is drawn from frame 0; one
/// frame is held at a time. The file is an 8-bit indexed APNG that loops forever. Each frame
/// shows the panels under their titles and the path frame number, a progress bar along the
/// path, and the states' legend. Returns the bytes written, at most [`AnimationPlan::byte_bound`].
pub fn write_animation(
    plan: &AnimationPlan,
    frames: impl Iterator<Item = Vec<ShadeImage>>,
    out: &mut dyn Write,
) -> Result<u64> {
    let (w, h, l) = (plan.width(), plan.height(), plan.layout);
    let pal = palette_rgb();
    let quantise = |svg: &str| -> Result<Vec<u8>> {
        let (_, _, rgb) = svg_to_rgb(svg.as_bytes(), 1.0)?;
        Ok(rgb.chunks_exact(3).map(|c| nearest(&pal, c)).collect())
    };
    // The legend is the same in every frame.
    let mut legend_body = String::new();
    let mut x = 4.0;
    for (s, label) in [
        (Shade::Lit, "lit"),
        (Shade::Shadowed, "shadowed"),
        (Shade::Acne, "acne"),
        (Shade::Edge, "edge"),
        (Shade::Leak, "leak"),
        (Shade::Away, "away"),
        (Shade::Empty, "no receiver"),
    ] {
        legend_body.push_str(&swatch(x, 19.0, shade_colour(s), label));
        x += 34.0 + 7.0 * label.chars().count() as f64;
    }
    let legend = quantise(&strip(w, ANIM_LEGEND_H, &legend_body))?;
    // The titles and the word "frame" are the same in every frame; the counter ("12/240") is put
    // together from glyph cells rendered once (DejaVu Sans digits share one advance), so no
    // frame lays out text.
    let counter_len = format!("{0}/{0}", plan.path_frames).len() as u32;
    let counter_x = w.saturating_sub(6 + CELL_W * counter_len);
    let label = format!(
        "<text x=\"{}\" y=\"21\" text-anchor=\"end\" fill=\"#444\">frame</text>",
        counter_x.saturating_sub(4)
    );
    let titles: Vec<&str> = plan.titles.iter().map(|t| t.as_str()).collect();
    let header = quantise(&titles_strip(&l, &titles, &label))?;
    let glyphs = quantise(&glyph_strip())?;
    let glyph_w = CELL_W * GLYPHS.len() as u32;
    let mut sink = Counting { inner: out, n: 0 };
    {
        let mut enc = png::Encoder::new(&mut sink, w, h);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(pal.concat());
        enc.set_animated(plan.shown as u32, 0).map_err(png_err)?;
        enc.set_frame_delay(plan.delay_ms, 1000).map_err(png_err)?;
        let mut writer = enc.write_header().map_err(png_err)?;
        let mut index = vec![0u8; w as usize * h as usize];
        let mut drawn = 0usize;
        for (f, images) in plan.frames().zip(frames.step_by(plan.every)) {
            if images.len() != plan.titles.len() {
                return Err(PlotError::Draw(format!(
                    "shadow animation: frame {f} has {} images for {} panels",
                    images.len(),
                    plan.titles.len()
                ))
                .into());
            }
            for im in &images {
                if (im.cols, im.rows) != (l.cols, l.rows) || im.pixels.len() != l.cols as usize * l.rows as usize {
                    return Err(PlotError::Draw(format!(
                        "shadow animation: frame {f} has a {} × {} image; the plan is for {} × {}",
                        im.cols, im.rows, l.cols, l.rows
                    ))
                    .into());
                }
            }
            index[..header.len()].copy_from_slice(&header);
            for (k, ch) in format!("{}/{}", f + 1, plan.path_frames).chars().enumerate() {
                let g = GLYPHS.find(ch).unwrap_or(0) as u32;
                let x0 = counter_x + CELL_W * k as u32;
                for y in 0..TITLE_H {
                    for x in 0..CELL_W.min(w.saturating_sub(x0)) {
                        index[(y * w + x0 + x) as usize] = glyphs[(y * glyph_w + g * CELL_W + x) as usize];
                    }
                }
            }
            // The progress bar: how far along the path this frame is.
            let filled = ((f + 1) as u64 * w as u64 / plan.path_frames as u64) as u32;
            for y in TITLE_H..TITLE_H + PROGRESS_H {
                for x in 0..w {
                    index[(y * w + x) as usize] = if x < filled { PAL_PROGRESS as u8 } else { 2 };
                }
            }
            let y0 = TITLE_H + PROGRESS_H;
            for y in 0..l.ph {
                let row = &mut index[((y0 + y) * w) as usize..((y0 + y + 1) * w) as usize];
                row.fill(0);
                for (i, im) in images.iter().enumerate() {
                    let x0 = l.panel_x(i as u32);
                    for x in 0..l.pw {
                        row[(x0 + x) as usize] = state_index(im.pixels[l.source(x, y)]);
                    }
                }
            }
            let o = ((y0 + l.ph) * w) as usize;
            index[o..].copy_from_slice(&legend);
            writer.write_image_data(&index).map_err(png_err)?;
            drawn += 1;
        }
        if drawn != plan.shown {
            return Err(PlotError::Draw(format!(
                "shadow animation: the path gave {drawn} of the {} frames to draw (a path of {} frames was planned)",
                plan.shown, plan.path_frames
            ))
            .into());
        }
        writer.finish().map_err(png_err)?;
    }
    Ok(sink.n)
}

/// `shadow.apng` as a streamed file of an output set: `frames()` starts the path over and
/// yields each frame's images (one per panel of the plan); only one frame is held at a time.
pub struct ShadowAnimation<F> {
    pub plan: AnimationPlan,
    pub frames: F,
}

impl<F, I> StreamedFile for ShadowAnimation<F>
where
    F: Fn() -> I + Sync,
    I: Iterator<Item = Vec<ShadeImage>>,
{
    fn file_name(&self) -> &str {
        SHADOW_APNG
    }

    fn write_to(&self, out: &mut dyn Write) -> Result<()> {
        write_animation(&self.plan, (self.frames)(), out).map(|_| ())
    }
}

// ---------------------------------------------------------------------------------------------
// flicker_vs_shimmer
// ---------------------------------------------------------------------------------------------

/// One configuration of a sweep in the S5-against-proxies scatter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShimmerPoint {
    /// Sub-texel drift per frame (texels, RMS).
    pub s3: f64,
    /// Share of probes whose texel changes per frame.
    pub s4: f64,
    /// Share of receivers whose shadow state changes per frame (flicker).
    pub s5: f64,
    /// Snapped windows (else unsnapped).
    pub snapped: bool,
}

/// The stem of the scatter's files (`.svg`, `.png`).
pub(crate) const FLICKER_VS_SHIMMER: &str = "flicker_vs_shimmer";

/// The scatter's caption in a report: what to look for.
pub(crate) const FLICKER_VS_SHIMMER_CAPTION: &str = "Flicker S5 against the shimmer proxies S3 and S4, one point per configuration: points close to the fitted line (|r| near 1) mean the proxy predicts the flicker a player sees. The snapped configurations sit at the origin and pull the line; the unsnapped points alone (the report's sentences) say whether the proxy ranks the configurations that flicker.";

/// The ordinary least-squares line `y = a + b x` through points and how well it fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    pub n: usize,
    /// Intercept and slope; None with fewer than two points or constant x.
    pub line: Option<(f64, f64)>,
    /// Pearson's r; None when x or y is constant.
    pub pearson: Option<f64>,
    /// Spearman's ρ (Pearson's r of the ranks, ties averaged); None when x or y is constant.
    pub spearman: Option<f64>,
}

fn centred_sums(x: &[f64], y: &[f64]) -> (f64, f64, f64, f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
        sxy += (a - mx) * (b - my);
    }
    (mx, my, sxx, syy, sxy)
}

fn pearson(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() < 2 {
        return None;
    }
    let (_, _, sxx, syy, sxy) = centred_sums(x, y);
    (sxx > 0.0 && syy > 0.0).then(|| (sxy / (sxx * syy).sqrt()).clamp(-1.0, 1.0))
}

/// Ranks from 1, ties given the mean of their ranks.
pub fn ranks(v: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]).then(a.cmp(&b)));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && v[order[j + 1]] == v[order[i]] {
            j += 1;
        }
        let mean = (i + j) as f64 / 2.0 + 1.0;
        for &k in &order[i..=j] {
            r[k] = mean;
        }
        i = j + 1;
    }
    r
}

/// The least-squares line of y on x, Pearson's r and Spearman's ρ, over finite pairs only.
pub fn fit(x: &[f64], y: &[f64]) -> Fit {
    let (x, y): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip();
    let n = x.len();
    let line = (n >= 2)
        .then(|| centred_sums(&x, &y))
        .filter(|s| s.2 > 0.0)
        .map(|(mx, my, sxx, _, sxy)| {
            let b = sxy / sxx;
            (my - b * mx, b)
        });
    Fit {
        n,
        line,
        pearson: pearson(&x, &y),
        spearman: pearson(&ranks(&x), &ranks(&y)),
    }
}

/// `flicker_vs_shimmer`: S5 against S3 (left) and S4 (right), snapped configurations as filled
/// circles and unsnapped as triangles, each panel with its least-squares line over all points
/// and Pearson's r and Spearman's ρ printed in it.
pub struct FlickerVsShimmer<'a> {
    /// The sweep's config name, for the title.
    pub name: &'a str,
    pub points: &'a [ShimmerPoint],
}

const SCATTER_LEGEND_LINES: usize = 3;
/// The band above each scatter panel with its title and the fit's two lines.
const FIT_TEXT_H: u32 = 70;

impl FlickerVsShimmer<'_> {
    /// The fit of S5 on S3 and on S4.
    pub fn fits(&self) -> (Fit, Fit) {
        let s5: Vec<f64> = self.points.iter().map(|p| p.s5).collect();
        let s3: Vec<f64> = self.points.iter().map(|p| p.s3).collect();
        let s4: Vec<f64> = self.points.iter().map(|p| p.s4).collect();
        (fit(&s3, &s5), fit(&s4, &s5))
    }

    /// The fit's text as the figure prints it.
    pub(crate) fn fit_text(proxy: &str, f: &Fit) -> [String; 2] {
        let line = match f.line {
            Some((a, b)) => format!("least squares: S5 = {} + {} · {proxy}", short(a), short(b)),
            None => format!("no line: fewer than two points or {proxy} constant"),
        };
        let r = |v: Option<f64>| v.map_or("undefined (a constant)".to_string(), |v| format!("{v:.3}"));
        [
            line,
            format!(
                "Pearson r = {}, Spearman ρ = {}, n = {}",
                r(f.pearson),
                r(f.spearman),
                f.n
            ),
        ]
    }

    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        proxy: &str,
        x_desc: &str,
        x_of: fn(&ShimmerPoint) -> f64,
        f: &Fit,
        legend: Option<&mut Legend<DB>>,
    ) -> PlotResult {
        let pts: Vec<(f64, f64, bool)> = self
            .points
            .iter()
            .filter(|p| x_of(p).is_finite() && p.s5.is_finite())
            .map(|p| (x_of(p), p.s5, p.snapped))
            .collect();
        // Both axes start at 0 (or below, for a negative value) and end a little past the data.
        let span = |v: &mut dyn Iterator<Item = f64>| {
            let (lo, hi) = v.fold((0.0f64, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
            let pad = if hi > lo { 0.06 * (hi - lo) } else { 1e-3 };
            (if lo < 0.0 { lo - pad } else { 0.0 }, hi + pad)
        };
        let (x0, x1) = span(&mut pts.iter().map(|p| p.0));
        let (y0, y1) = span(&mut pts.iter().map(|p| p.1));
        // The panel's title and the fit's numbers above the chart, never over a point.
        let (head, body) = area.split_vertically(FIT_TEXT_H);
        head.draw(&Text::new(
            format!("S5 against {proxy}"),
            (84, 4),
            (FONT, 18).into_font().style(FontStyle::Bold),
        ))?;
        for (k, t) in Self::fit_text(proxy, f).iter().enumerate() {
            head.draw(&Text::new(t.clone(), (84, 30 + 18 * k as i32), (FONT, 14).into_font()))?;
        }
        let mut chart = legend_frame(&body, "", 1, 70, SCATTER_LEGEND_LINES, LEGEND_FONT)
            .build_cartesian_2d(linear_axis(x0, x1), linear_axis(y0, y1))?;
        house_mesh(&mut chart, x_desc, "S5 flicker (share of receivers flipping per frame)")
            .max_light_lines(3)
            .axis_desc_style((FONT, 14))
            .label_style((FONT, 12))
            .draw()?;
        let (snap, free) = (series_color(0), series_color(1));
        chart.draw_series(
            pts.iter()
                .filter(|p| p.2)
                .map(|p| Circle::new((p.0, p.1), 4, snap.filled())),
        )?;
        chart.draw_series(
            pts.iter()
                .filter(|p| !p.2)
                .map(|p| TriangleMarker::new((p.0, p.1), 6, free.filled())),
        )?;
        let fit_style = BLACK.stroke_width(2);
        if let Some((a, b)) = f.line {
            chart.draw_series(LineSeries::new(vec![(x0, a + b * x0), (x1, a + b * x1)], fit_style))?;
        }
        if let Some(legend) = legend {
            legend.add("snapped configuration", move |(x, y)| {
                Circle::new((x + 8, y), 4, snap.filled())
            });
            legend.add("unsnapped configuration", move |(x, y)| {
                TriangleMarker::new((x + 8, y), 6, free.filled())
            });
            legend.add("least-squares line over all points", move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], fit_style)
            });
        }
        Ok(())
    }
}

impl Figure for FlickerVsShimmer<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 580 + legend_height(SCATTER_LEGEND_LINES, LEGEND_FONT))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let title = format!("Does shimmer predict flicker? S5 against S3 and S4: {}", self.name);
        if !self
            .points
            .iter()
            .any(|p| p.s3.is_finite() && p.s4.is_finite() && p.s5.is_finite())
        {
            return draw_message(root, &title, "No configuration with a measured flicker S5.");
        }
        let root_t = root.titled(&title, (FONT, 20))?;
        let halves = root_t.split_evenly((1, 2));
        let (f3, f4) = self.fits();
        let mut legend = Legend::default();
        self.panel(
            &halves[0],
            "S3",
            "S3 sub-texel drift (texels per frame, RMS)",
            |p| p.s3,
            &f3,
            Some(&mut legend),
        )?;
        self.panel(
            &halves[1],
            "S4",
            "S4 cell flips (share of probes changing texel per frame)",
            |p| p.s4,
            &f4,
            None,
        )?;
        let (_, below) = halves[0].split_vertically(FIT_TEXT_H);
        draw_legend_below(&below, legend, SCATTER_LEGEND_LINES)
    }
}

/// The scatter as a sweep figure: (stem, caption, SVG), the form `report::sweep` renders to SVG,
/// PNG and the report's plots.
pub fn flicker_vs_shimmer_figure(name: &str, points: &[ShimmerPoint]) -> Result<(&'static str, String, Vec<u8>)> {
    let svg = FlickerVsShimmer { name, points }.to_svg()?;
    Ok((FLICKER_VS_SHIMMER, FLICKER_VS_SHIMMER_CAPTION.to_string(), svg))
}
