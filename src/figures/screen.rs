//! The camera-view images of a scene with geometry: `screen_aliasing.png` (each sampled pixel
//! coloured by its per-pixel aliasing `m` on a log scale) and `screen_cascades.png` (each
//! pixel coloured by the cascade that serves it, with the split lines in black).
//!
//! Both are raster images of the sampled grid (`[analysis] screen_scale`), enlarged by a whole
//! factor to at least 960 pixels wide, with a legend drawn below as SVG and rasterised with the
//! same fonts as every other figure. Sky is neutral light grey, surfaces facing away from the
//! light are dimmed to dark grey, lit-facing pixels outside the split range mid grey. A set-up
//! that does not serve its receivers (an engine preset whose windows miss slice corners or whose
//! light depth range clips receivers, [`csm_core::truth::serve_faults`]) has those pixels drawn
//! in warning colours: red where the cascade's window misses the receiver, magenta where its
//! depth range clips it.

use std::fmt::Write as _;

use plotters::style::RGBColor;
use rayon::prelude::*;

use super::{colormap, encode_png, series_color, svg_to_rgb, FONT};
use crate::analysis::Analysis;
use crate::error::Result;
use crate::output::Exporter;
use csm_core::metrics::cascade_at;
use csm_core::truth::ServeFault;

pub(crate) const SKY: [u8; 3] = [236, 236, 236];
pub(crate) const SELF_SHADOWED: [u8; 3] = [70, 70, 70];
pub(crate) const UNSERVED: [u8; 3] = [170, 170, 170];
const SPLIT_LINE: [u8; 3] = [0, 0, 0];
/// A receiver outside the window of the cascade that reads it (a missed slice corner's area).
const MISSED: [u8; 3] = [214, 39, 40];
/// A receiver beyond the light depth range of the cascade that reads it (clipped).
const CLIPPED: [u8; 3] = [230, 0, 230];
/// The aliasing scale: log2 m from -3 (m = 1/8) to +6 (m = 64).
pub(crate) const LOG2_LO: f64 = -3.0;
pub(crate) const LOG2_HI: f64 = 6.0;

fn rgb(c: RGBColor) -> [u8; 3] {
    [c.0, c.1, c.2]
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Colour of aliasing `m` on the log scale.
pub(crate) fn aliasing_color(m: f64) -> [u8; 3] {
    rgb(colormap((m.log2() - LOG2_LO) / (LOG2_HI - LOG2_LO)))
}

/// What each sampled pixel shows: None (sky), or (lit, served cascade, whether the cascade
/// fails to serve it). 4 bytes: a full-HD picture holds two million (the aliasing `m` of a
/// served pixel is its cascade's texel size times the pass's factor, [`Pixels::m`]).
struct Pixel {
    cascade: Option<u8>,
    lit: bool,
    fault: Option<ServeFault>,
}

/// The sampled grid's pixels: columns, rows, each pixel row by row, and how many receiver
/// pixels each fault marks (counted once for both pictures and their captions).
struct Pixels {
    cols: u32,
    rows: u32,
    px: Vec<Option<Pixel>>,
    /// (missed, clipped).
    faults: (usize, usize),
    /// The pass the pixels come from.
    vis: std::sync::Arc<csm_core::visibility::Visibility>,
}

impl Pixels {
    /// The aliasing `m` of pixel `k` served by cascade `i`: `T_i g`.
    fn m(&self, a: &Analysis, k: usize, i: u8) -> f64 {
        let g = self.vis.samples.get(k).map_or(0.0, |s| s.factor);
        a.cascades[i as usize].texel_size * g
    }
}

fn pixels(a: &Analysis) -> Option<Pixels> {
    let setup = a.config.setup();
    let vis = setup.visibility()?;
    let rig = a.rig();
    let faults = rig.map(|r| {
        let slack = 1e-9 * (setup.bounds.max - setup.bounds.min).length().max(1.0);
        csm_core::truth::serve_faults(r, &vis, &setup.bounds, a.config.shadow.snap, slack)
    });
    let served = |d: f64| {
        let r = rig?;
        let m = r.cascade_count();
        (d >= r.splits[0] && d <= r.splits[m]).then(|| cascade_at(&r.splits, d))
    };
    let px: Vec<Option<Pixel>> = vis
        .samples
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(k, s)| {
            s.map(|s| {
                let cascade = served(s.depth);
                Pixel {
                    lit: s.lit,
                    cascade: cascade.map(|i| u8::try_from(i).expect("at most 255 cascades")),
                    fault: faults.as_ref().and_then(|f| f[k]),
                }
            })
        })
        .collect();
    let faults = fault_counts(&px);
    Some(Pixels {
        cols: vis.cols,
        rows: vis.rows,
        px,
        faults,
        vis,
    })
}

/// The image scaled up by a whole factor, with `legend` (SVG) below; PNG bytes.
fn compose(cols: u32, rows: u32, colour: &[[u8; 3]], legend: &str) -> Result<Vec<u8>> {
    let k = (960 / cols).max(1);
    let w = cols * k;
    let (lw, lh, lrgb) = svg_to_rgb(legend.replace("{W}", &w.to_string()).as_bytes(), 1.0)?;
    let h = rows * k + lh;
    let mut out = vec![255u8; (w * h * 3) as usize];
    // Each sampled row is enlarged once (every pixel k times) and copied to its k rows.
    let row = (w * 3) as usize;
    let (n, kk) = (cols as usize, k as usize);
    for (line, sampled) in out[..row * rows as usize * kk]
        .chunks_exact_mut(row * kk)
        .zip(colour.chunks_exact(n))
    {
        let (first, rest) = line.split_at_mut(row);
        if kk == 1 {
            first.copy_from_slice(sampled.as_flattened());
        } else {
            for (px, c) in first.chunks_exact_mut(3 * kk).zip(sampled) {
                for p in px.chunks_exact_mut(3) {
                    p.copy_from_slice(c);
                }
            }
        }
        for copy in rest.chunks_exact_mut(row) {
            copy.copy_from_slice(first);
        }
    }
    for y in 0..lh {
        for x in 0..lw.min(w) {
            let i = ((y * lw + x) * 3) as usize;
            let o = (((rows * k + y) * w + x) * 3) as usize;
            out[o..o + 3].copy_from_slice(&lrgb[i..i + 3]);
        }
    }
    encode_png(w, h, &out)
}

fn legend_svg(body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{{W}}\" height=\"64\" font-family=\"{FONT}\" font-size=\"13\">\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>{body}</svg>"
    )
}

fn swatch(x: f64, c: [u8; 3], label: &str) -> String {
    format!(
        "<rect x=\"{x}\" y=\"40\" width=\"14\" height=\"14\" fill=\"{}\" stroke=\"#888\"/>\
         <text x=\"{}\" y=\"52\">{label}</text>",
        hex(c),
        x + 19.0
    )
}

/// `screen_aliasing.png`.
pub(crate) fn aliasing_png(a: &Analysis) -> Result<Vec<u8>> {
    aliasing_of(a, &pixels(a).expect("written only with geometry"))
}

/// `screen_aliasing.png` from the analysis' [`pixels`].
fn aliasing_of(a: &Analysis, p: &Pixels) -> Result<Vec<u8>> {
    let (cols, rows, px) = (p.cols, p.rows, &p.px);
    let colour: Vec<[u8; 3]> = px
        .iter()
        .enumerate()
        .map(|(k, q)| match q {
            None => SKY,
            Some(q) if !q.lit => SELF_SHADOWED,
            Some(q) => match q.cascade {
                None => UNSERVED,
                Some(i) => fault_colour(q).unwrap_or_else(|| aliasing_color(p.m(a, k, i))),
            },
        })
        .collect();
    let mut body = String::new();
    let steps = 90;
    for i in 0..steps {
        let t = i as f64 / steps as f64;
        let c = rgb(colormap(t));
        let _ = write!(
            body,
            "<rect x=\"{}\" y=\"8\" width=\"4\" height=\"14\" fill=\"{}\"/>",
            10 + 4 * i,
            hex(c)
        );
    }
    for e in LOG2_LO as i32..=LOG2_HI as i32 {
        let x = 10.0 + 360.0 * (e as f64 - LOG2_LO) / (LOG2_HI - LOG2_LO);
        // The top of the bar is clipped: larger values take its colour (the max is printed
        // beside the bar).
        let label = match e {
            _ if e == LOG2_HI as i32 => format!("≥ {}", 1 << e),
            _ if e < 0 => format!("1/{}", 1 << -e),
            _ => format!("{}", 1 << e),
        };
        let anchor = "middle";
        let _ = write!(
            body,
            "<line x1=\"{x}\" y1=\"6\" x2=\"{x}\" y2=\"24\" stroke=\"black\"/><text x=\"{x}\" y=\"36\" text-anchor=\"{anchor}\">{label}</text>"
        );
    }
    let st = a.summary.screen.as_ref();
    let _ = write!(
        body,
        "<text x=\"394\" y=\"20\">per-pixel aliasing m (texel extent in pixels; &gt; 1 is blocky), log scale</text>\
         <text x=\"394\" y=\"36\">p50 {:.3}, p95 {:.3}, max {:.3}</text>",
        st.map_or(0.0, |s| s.aliasing_p50),
        st.map_or(0.0, |s| s.aliasing_p95),
        st.map_or(0.0, |s| s.aliasing_max)
    );
    body.push_str(&swatch(10.0, SKY, "sky"));
    body.push_str(&swatch(70.0, SELF_SHADOWED, "facing away from the light"));
    body.push_str(&swatch(290.0, UNSERVED, "outside the split range"));
    body.push_str(&fault_swatches(p.faults, 480.0));
    compose(cols, rows, &colour, &legend_svg(&body))
}

/// The warning colour of a receiver its cascade does not serve, if it is one.
fn fault_colour(p: &Pixel) -> Option<[u8; 3]> {
    p.fault.map(|f| match f {
        ServeFault::Missed => MISSED,
        ServeFault::Clipped => CLIPPED,
    })
}

/// How many receiver pixels each fault marks: (missed, clipped).
fn fault_counts(px: &[Option<Pixel>]) -> (usize, usize) {
    let n = |f: ServeFault| px.iter().flatten().filter(|p| p.fault == Some(f)).count();
    (n(ServeFault::Missed), n(ServeFault::Clipped))
}

/// The legend's warning swatches from `x` on, for the faults the picture has (`(missed,
/// clipped)` receiver pixels; none: empty).
fn fault_swatches((missed, clipped): (usize, usize), x: f64) -> String {
    let mut out = String::new();
    let mut x = x;
    if missed > 0 {
        let label = format!("outside its window: {missed} px");
        out.push_str(&swatch(x, MISSED, &label));
        x += 40.0 + 7.5 * label.len() as f64;
    }
    if clipped > 0 {
        out.push_str(&swatch(x, CLIPPED, &format!("clipped by light depth: {clipped} px")));
    }
    out
}

/// `screen_cascades.png`.
pub(crate) fn cascades_png(a: &Analysis) -> Result<Vec<u8>> {
    cascades_of(a, &pixels(a).expect("written only with geometry"))
}

/// `screen_cascades.png` from the analysis' [`pixels`].
fn cascades_of(a: &Analysis, p: &Pixels) -> Result<Vec<u8>> {
    let (cols, rows, px) = (p.cols, p.rows, &p.px);
    let dim = |c: [u8; 3]| c.map(|x| (x as f64 * 0.4) as u8);
    // Each pixel's cascade, two bytes apiece: the split-line test reads three per pixel.
    let cascades: Vec<Option<u8>> = px.iter().map(|p| p.as_ref().and_then(|p| p.cascade)).collect();
    let cascade_of = |i: usize| cascades[i];
    let colour: Vec<[u8; 3]> = (0..px.len())
        .map(|i| {
            let (x, y) = (i as u32 % cols, i as u32 / cols);
            let c = cascade_of(i);
            // A split line where the right or lower neighbour is served by another cascade.
            let differs = |j: usize| c.is_some() && cascade_of(j).is_some() && cascade_of(j) != c;
            if (x + 1 < cols && differs(i + 1)) || (y + 1 < rows && differs(i + cols as usize)) {
                return SPLIT_LINE;
            }
            match (&px[i], c) {
                (None, _) => SKY,
                (Some(_), None) => UNSERVED,
                (Some(p), Some(_)) if fault_colour(p).is_some() => fault_colour(p).unwrap_or(SKY),
                (Some(p), Some(k)) if !p.lit => dim(rgb(series_color(k as usize))),
                (Some(_), Some(k)) => rgb(series_color(k as usize)),
            }
        })
        .collect();
    let mut body = String::new();
    let mut x = 10.0;
    for c in &a.cascades {
        let label = format!("cascade {}: {:.1}..{:.1}", c.cascade, c.near, c.far);
        let _ = write!(
            body,
            "<rect x=\"{x}\" y=\"8\" width=\"14\" height=\"14\" fill=\"{}\"/><text x=\"{}\" y=\"20\">{label}</text>",
            hex(rgb(series_color(c.cascade))),
            x + 19.0
        );
        x += 40.0 + 7.5 * label.len() as f64;
    }
    body.push_str(&swatch(10.0, SKY, "sky"));
    body.push_str(&swatch(70.0, SPLIT_LINE, "split lines"));
    body.push_str(&swatch(180.0, UNSERVED, "outside the split range"));
    let (missed, clipped) = p.faults;
    if missed + clipped > 0 {
        body.push_str(&fault_swatches(p.faults, 390.0));
    } else {
        body.push_str("<text x=\"390\" y=\"52\">darker: facing away from the light</text>");
    }
    compose(cols, rows, &colour, &legend_svg(&body))
}

pub(crate) struct ScreenAliasingPng;
pub(crate) struct ScreenCascadesPng;

impl Exporter<Analysis> for ScreenAliasingPng {
    fn file_name(&self) -> &'static str {
        "screen_aliasing.png"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        aliasing_png(a)
    }
}

impl Exporter<Analysis> for ScreenCascadesPng {
    fn file_name(&self) -> &'static str {
        "screen_cascades.png"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        cascades_png(a)
    }
}

/// Both images of an analysis with their captions (empty without geometry or on a failure to
/// draw, which only leaves them out of a page).
pub(crate) fn captioned(a: &Analysis, label: &str) -> Vec<(Vec<u8>, String)> {
    if a.config.geometry.is_none() {
        return Vec::new();
    }
    // The pixels are worked out once for both images, which are drawn in parallel.
    let Some(px) = pixels(a) else {
        return Vec::new();
    };
    // Receivers the set-up does not serve are marked, and the captions say so.
    let (missed, clipped) = px.faults;
    let mut note = String::new();
    if missed > 0 {
        note.push_str(&format!(
            " Red: {missed} receiver pixels outside the window of the cascade that reads them (missed slice corners: the map reads \"lit\" there)."
        ));
    }
    if clipped > 0 {
        note.push_str(&format!(
            " Magenta: {clipped} receiver pixels beyond their cascade's light depth range (clipped)."
        ));
    }
    let end = if note.is_empty() { "" } else { "." };
    match rayon::join(|| aliasing_of(a, &px), || cascades_of(a, &px)) {
        (Ok(m), Ok(c)) => vec![
            (
                m,
                format!("{label}: per-pixel aliasing m on screen (log scale){end}{note}"),
            ),
            (
                c,
                format!("{label}: the cascade serving each pixel, with the split lines{end}{note}"),
            ),
        ],
        _ => Vec::new(),
    }
}
