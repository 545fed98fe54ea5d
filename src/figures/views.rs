//! `views.png`: the contact sheet of a level's views: each view's `screen_aliasing` image as a
//! small multiple, all on the one log colour scale of `screen_aliasing.png` (`m` from 1/8 to
//! 64), named, the worst view by the objective framed in red, with one legend below.

use std::fmt::Write as _;

use super::screen::{aliasing_color, LOG2_HI, LOG2_LO, SELF_SHADOWED, SKY, UNSERVED};
use super::{colormap, encode_png, svg_to_rgb, FONT};
use crate::analysis::view_pixels;
use crate::config::Config;
use crate::error::Result;

/// Most views the sheet shows (the first ones, in the config's order; the caption says so).
pub(crate) const MAX_TILES: usize = 48;
/// Widest tile, pixels.
const TILE_W: u32 = 240;
/// The caption strip above each tile and the gap around it.
const CAPTION_H: u32 = 18;
const GAP: u32 = 6;
const LEGEND_H: u32 = 64;

/// The sheet of `config`'s views at its setting (a config with views and geometry); `worst`
/// is the index of the view to frame.
pub(crate) fn views_png(config: &Config, worst: Option<usize>) -> Result<Vec<u8>> {
    let shown = config.views.len().min(MAX_TILES);
    let tiles: Vec<_> = (0..shown).filter_map(|k| view_pixels(config, k)).collect();
    let (cols0, rows0) = tiles.first().map_or((1, 1), |t| (t.0, t.1));
    // Every view shares the screen, so every tile has one size: sampled pixels shrunk (or
    // enlarged) by nearest neighbour to TILE_W wide.
    let tw = TILE_W;
    let th = ((rows0 as f64 * tw as f64 / cols0 as f64).round() as u32).max(1);
    let per_row = (shown as f64).sqrt().ceil().max(1.0) as u32;
    let grid_rows = (shown as u32).div_ceil(per_row).max(1);
    let cell_w = tw + 2 * GAP;
    let cell_h = th + CAPTION_H + 2 * GAP;
    let w = (per_row * cell_w).max(960);
    let h = grid_rows * cell_h + LEGEND_H;
    // The text (names, legend) as one SVG, rasterised; the tiles are pasted over it.
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"{FONT}\" font-size=\"12\">\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>"
    );
    let esc = |t: &str| t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;");
    for k in 0..shown {
        let (cx, cy) = ((k as u32 % per_row) * cell_w + GAP, (k as u32 / per_row) * cell_h + GAP);
        let _ = write!(
            svg,
            "<text x=\"{cx}\" y=\"{}\">{}</text>",
            cy + CAPTION_H - 5,
            esc(&config.views[k].name)
        );
        if worst == Some(k) {
            let _ = write!(
                svg,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#d00\" stroke-width=\"4\"/>",
                cx - 3,
                cy + CAPTION_H - 3,
                tw + 6,
                th + 6
            );
        }
    }
    let ly = grid_rows * cell_h;
    for i in 0..90 {
        let c = colormap(i as f64 / 90.0);
        let _ = write!(
            svg,
            "<rect x=\"{}\" y=\"{}\" width=\"4\" height=\"14\" fill=\"#{:02x}{:02x}{:02x}\"/>",
            24 + 4 * i,
            ly + 8,
            c.0,
            c.1,
            c.2
        );
    }
    for e in LOG2_LO as i32..=LOG2_HI as i32 {
        let x = 24.0 + 360.0 * (e as f64 - LOG2_LO) / (LOG2_HI - LOG2_LO);
        let label = if e < 0 {
            format!("1/{}", 1 << -e)
        } else {
            format!("{}", 1 << e)
        };
        let _ = write!(
            svg,
            "<line x1=\"{x}\" y1=\"{}\" x2=\"{x}\" y2=\"{}\" stroke=\"black\"/><text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">{label}</text>",
            ly + 6,
            ly + 24,
            ly + 38
        );
    }
    let more = if config.views.len() > shown {
        format!(" (the first {shown} of {} views)", config.views.len())
    } else {
        String::new()
    };
    let _ = write!(
        svg,
        "<text x=\"400\" y=\"{}\">per-pixel aliasing m, one log scale for every view{}</text>\
         <text x=\"400\" y=\"{}\">grey: sky, dark: facing away, mid: unserved; red frame: the worst view</text></svg>",
        ly + 20,
        esc(&more),
        ly + 38
    );
    let (sw, sh, mut rgb) = svg_to_rgb(svg.as_bytes(), 1.0)?;
    for (k, (cols, rows, px)) in tiles.iter().enumerate() {
        let (cx, cy) = (
            (k as u32 % per_row) * cell_w + GAP,
            (k as u32 / per_row) * cell_h + GAP + CAPTION_H,
        );
        for y in 0..th {
            for x in 0..tw {
                let (sx, sy) = ((x * cols / tw).min(cols - 1), (y * rows / th).min(rows - 1));
                let c = match &px[(sy * cols + sx) as usize] {
                    None => SKY,
                    Some((false, _)) => SELF_SHADOWED,
                    Some((true, None)) => UNSERVED,
                    Some((true, Some(m))) => aliasing_color(*m),
                };
                let (ox, oy) = (cx + x, cy + y);
                if ox < sw && oy < sh {
                    let o = ((oy * sw + ox) * 3) as usize;
                    rgb[o..o + 3].copy_from_slice(&c);
                }
            }
        }
    }
    encode_png(sw, sh, &rgb)
}
