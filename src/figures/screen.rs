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

/// Colour of aliasing `m` on the log scale: [`colour_of_log2`] of `log2 m`, read from
/// [`ColourTable`] where the table holds it (the same bytes).
pub(crate) fn aliasing_color(m: f64) -> [u8; 3] {
    static TABLE: std::sync::OnceLock<ColourTable> = std::sync::OnceLock::new();
    TABLE.get_or_init(ColourTable::new).colour(m.log2())
}

/// The colour of `l = log2 m` on the aliasing scale: the plain formula.
fn colour_of_log2(l: f64) -> [u8; 3] {
    rgb(colormap((l - LOG2_LO) / (LOG2_HI - LOG2_LO)))
}

/// Which stop interval of the colour map [`colour_of_log2`] interpolates in at `l`, and the
/// colour: the key that is constant between two equal ends (see [`ColourTable`]).
fn colour_key(l: f64) -> (usize, [u8; 3]) {
    let t = ((l - LOG2_LO) / (LOG2_HI - LOG2_LO)).clamp(0.0, 1.0);
    (((t * 4.0) as usize).min(3), colour_of_log2(l))
}

/// `f64`'s order as unsigned integers (negative numbers reversed, below positive), and back.
fn ordered(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | (1 << 63)
    }
}

fn from_ordered(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// [`colour_of_log2`] as a table over `l` in `[LOG2_LO, LOG2_HI]`, exact to the byte.
///
/// Between two values of `l` in one interval of the colour map's stops, each channel is a
/// monotone function of `l`: `t = (l - lo) / (hi - lo)`, the clamp, `x = 4 t`, `f = x - i`,
/// `p + (q - p) f` and the rounding are each monotone under IEEE rounding (a constant added,
/// a positive constant divided by, a fixed factor multiplied by, its sign fixing the
/// direction), and the interval `i = min(trunc x, 3)` never decreases with `l`. So where the
/// interval and the colour are equal at both ends of a range of `l`, they are the same at every
/// `l` between. The range is cut into [`CELLS`] cells; a cell whose ends have one key holds that
/// colour; a cell holding one change holds the first `l` (as found by bisection over the
/// values between, in their order) with the upper end's key, checked by the same argument on
/// both sides of it. Any other `l` (outside the range, or a cell with more than one change)
/// is coloured by the formula. The call to `log2` stays: only the map after it is read.
struct ColourTable {
    cells: Vec<Cell>,
}

/// Cells of [`ColourTable`]: at about 700 colour changes over the range, few cells hold two.
const CELLS: usize = 4096;

/// A cell of [`ColourTable`]: `l` in `[lo, hi]` is `below` under `at`, `above` from it on;
/// `lo` NaN for a cell the table does not answer.
#[derive(Clone, Copy)]
struct Cell {
    lo: f64,
    at: f64,
    hi: f64,
    below: [u8; 3],
    above: [u8; 3],
}

impl ColourTable {
    fn new() -> ColourTable {
        let width = (LOG2_HI - LOG2_LO) / CELLS as f64;
        let cells = (0..CELLS)
            .map(|j| {
                let lo = LOG2_LO + j as f64 * width;
                let hi = if j + 1 == CELLS {
                    LOG2_HI
                } else {
                    LOG2_LO + (j + 1) as f64 * width
                };
                Self::cell(lo, hi)
            })
            .collect();
        ColourTable { cells }
    }

    /// The cell for `[lo, hi]`: uniform, one change, or unanswered.
    fn cell(lo: f64, hi: f64) -> Cell {
        let (a, b) = (colour_key(lo), colour_key(hi));
        if a == b {
            return Cell {
                lo,
                at: hi,
                hi,
                below: a.1,
                above: a.1,
            };
        }
        // The first value with the upper end's key: keys before it differ from b's.
        let (mut below, mut above) = (ordered(lo), ordered(hi));
        while above - below > 1 {
            let mid = below + (above - below) / 2;
            if colour_key(from_ordered(mid)) == b {
                above = mid;
            } else {
                below = mid;
            }
        }
        // One change: the values up to `below` have a's key (equal ends), and from `above`
        // on b's (equal ends).
        let one_change = colour_key(from_ordered(below)) == a;
        Cell {
            lo: if one_change { lo } else { f64::NAN },
            at: from_ordered(above),
            hi,
            below: a.1,
            above: b.1,
        }
    }

    /// [`colour_of_log2`] of `l`.
    #[inline]
    fn colour(&self, l: f64) -> [u8; 3] {
        let j = ((l - LOG2_LO) * (CELLS as f64 / (LOG2_HI - LOG2_LO))) as usize;
        if let Some(c) = self.cells.get(j) {
            // NaN bounds (an unanswered cell, or l itself) fail both tests.
            if c.lo <= l && l <= c.hi {
                return if l < c.at { c.below } else { c.above };
            }
        }
        colour_of_log2(l)
    }
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
    #[inline]
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
    // Only a receiver (a sample) has a fault, so the counts are those of the faults' list.
    let faults = faults.as_deref().map_or((0, 0), fault_counts);
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

/// How many receiver pixels each fault marks: (missed, clipped), in one pass.
fn fault_counts(faults: &[Option<ServeFault>]) -> (usize, usize) {
    faults.iter().fold((0, 0), |(m, c), f| match f {
        Some(ServeFault::Missed) => (m + 1, c),
        Some(ServeFault::Clipped) => (m, c + 1),
        None => (m, c),
    })
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
    // Every cascade's colour, lit and dimmed, once (not per pixel).
    let shades: Vec<([u8; 3], [u8; 3])> = (0..=u8::MAX as usize)
        .map(|k| {
            let c = rgb(series_color(k));
            (c, dim(c))
        })
        .collect();
    let n = cols as usize;
    let mut colour: Vec<[u8; 3]> = vec![SKY; px.len()];
    // Row by row: a split line where the right or lower neighbour is served by another
    // cascade (the last column has no right neighbour, the last row no lower one).
    for (y, (out, (here, this_px))) in colour
        .chunks_exact_mut(n)
        .zip(cascades.chunks_exact(n).zip(px.chunks_exact(n)))
        .enumerate()
    {
        let below = cascades.get((y + 1) * n..(y + 2) * n);
        for x in 0..n {
            let c = here[x];
            let differs = |o: Option<u8>| c.is_some() && o.is_some() && o != c;
            if (x + 1 < n && differs(here[x + 1])) || below.is_some_and(|b| differs(b[x])) {
                out[x] = SPLIT_LINE;
                continue;
            }
            out[x] = match (&this_px[x], c) {
                (None, _) => SKY,
                (Some(_), None) => UNSERVED,
                (Some(p), Some(k)) => match fault_colour(p) {
                    Some(f) => f,
                    None if !p.lit => shades[k as usize].1,
                    None => shades[k as usize].0,
                },
            };
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The table gives the formula's colour at every value around each change it holds, at
    /// the cells' ends, and at random values of `m` and `log2 m` over and beyond the scale.
    #[test]
    fn the_colour_table_is_the_formula_to_the_byte() {
        let table = ColourTable::new();
        let mut ls = vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 0.0, LOG2_LO, LOG2_HI];
        let mut answered = 0;
        for c in &table.cells {
            for x in [c.lo, c.at, c.hi] {
                if x.is_finite() {
                    ls.extend([x, x.next_up(), x.next_down()]);
                }
            }
            answered += usize::from(!c.lo.is_nan());
        }
        // Nearly every cell answers (at most one change in it).
        assert!(answered > CELLS * 9 / 10, "{answered} of {CELLS} cells answer");
        let mut rng = csm_core::rng::SplitMix64::new(5);
        ls.extend((0..200_000).map(|_| LOG2_LO - 1.0 + rng.unit() * (LOG2_HI - LOG2_LO + 2.0)));
        for l in ls {
            assert_eq!(table.colour(l), colour_of_log2(l), "log2 m = {l:e}");
        }
        // Through log2, as the pictures call it.
        let mut ms = vec![0.0, f64::MIN_POSITIVE, 1.0 / 8.0, 1.0, 64.0, 1e300, f64::INFINITY];
        ms.extend((0..200_000).map(|_| (2f64).powf(-4.0 + 11.0 * rng.unit())));
        for m in ms {
            assert_eq!(aliasing_color(m), colour_of_log2(m.log2()), "m = {m:e}");
        }
    }
}
