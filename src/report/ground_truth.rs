//! The ground-truth pass's outputs: `bias.csv` (per cascade: the bias sampled with, acne and
//! leaks, the bias needed per depth format, peter-panning) and the recommended bias printed by
//! `analyze`, in the engine's own setting when the preset's bias is modelled.

use std::fmt::Write as _;

use crate::analysis::ground_truth::GroundTruth;
use crate::analysis::Analysis;
use crate::error::Result;
use crate::output::{csv_bytes, num, short_number, Exporter};
use csm_core::truth::DepthFormat;

pub(crate) struct BiasCsv;

/// The columns of `bias.csv`.
pub(crate) const BIAS_COLUMNS: [&str; 23] = [
    "cascade",
    "points",
    "texel_size",
    "light_depth_range",
    "bias_source",
    "pcf_filter",
    "depth_bias",
    "slope_bias",
    "normal_bias_texels",
    "acne_fraction",
    "edge_error_fraction",
    "leak_fraction",
    "bias_needed_exact",
    "step_d16",
    "step_d24",
    "step_d32f",
    "bias_needed_d16",
    "bias_needed_d24",
    "bias_needed_d32f",
    "slope_bias_needed",
    "peter_pan",
    "recommended",
    "recommended_unit",
];

impl Exporter<Analysis> for BiasCsv {
    fn file_name(&self) -> &'static str {
        "bias.csv"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        let Some(g) = &a.ground_truth else {
            return csv_bytes(&BIAS_COLUMNS, &[]);
        };
        let format = a.config.truth.depth_format;
        let unit = g.engine.map_or("world units", |e| e.unit);
        let rows = g
            .cascades
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let b = &g.bias[i];
                let f = |name: &str, v: f64| num(name, v);
                let o = |name: &str, v: Option<f64>| v.map_or(Ok("n/a".to_string()), |x| num(name, x));
                let needed = |k: usize| o("bias_needed", c.depth_bias.map(|d| d[k]));
                Ok(vec![
                    i.to_string(),
                    c.points.to_string(),
                    f("texel_size", g.texel[i])?,
                    f("light_depth_range", g.ranges[i].1 - g.ranges[i].0)?,
                    g.bias_source.name().to_string(),
                    g.filter.name().to_string(),
                    f("depth_bias", b.depth)?,
                    f("slope_bias", b.slope)?,
                    f("normal_bias_texels", b.normal)?,
                    o("acne_fraction", c.acne_fraction)?,
                    o("edge_error_fraction", c.edge_error_fraction)?,
                    o("leak_fraction", c.leak_fraction)?,
                    o("bias_needed_exact", c.depth_bias_exact)?,
                    f("step_d16", c.step[0])?,
                    f("step_d24", c.step[1])?,
                    f("step_d32f", c.step[2])?,
                    needed(0)?,
                    needed(1)?,
                    needed(2)?,
                    o("slope_bias_needed", c.slope_bias)?,
                    o("peter_pan", c.peter_pan)?,
                    o("recommended", g.recommended_own(i, format))?,
                    unit.to_string(),
                ])
            })
            .collect::<Result<Vec<_>>>()?;
        csv_bytes(&BIAS_COLUMNS, &rows)
    }
}

/// `analyze`'s stdout lines for the pass: receivers, cache, and the recommended depth bias
/// per cascade (configured depth format), in the engine's setting when it is modelled.
pub(crate) fn recommendation(a: &Analysis, g: &GroundTruth) -> String {
    let mut out = String::new();
    let format = a.config.truth.depth_format;
    let _ = writeln!(
        out,
        "ground truth: {} receiver points, {} frames x 2 snap modes; texel cache {} reads, {} rays (hit rate {})",
        g.receivers,
        g.snapped.frames,
        g.cache.reads,
        g.cache.rays,
        short_number(g.cache.hit_rate())
    );
    let _ = writeln!(out, "  {}", bias_sentence(g));
    let (setting, unit) = match &g.engine {
        Some(e) => (e.setting, e.unit),
        None => ("shadow.depth_bias", "world units"),
    };
    let _ = writeln!(
        out,
        "  recommended depth bias ({}, acne <= 0.1 % per cascade, margin 0.1 % + one format step): {setting} in {unit}",
        format.name().to_uppercase()
    );
    let mut largest: f64 = 0.0;
    let o = |x: Option<f64>| x.map_or("n/a".to_string(), short_number);
    for (i, c) in g.cascades.iter().enumerate() {
        let Some(own) = g.recommended_own(i, format) else {
            let _ = writeln!(
                out,
                "  cascade {i}: too few receivers ({}; at least {} are needed)",
                c.points,
                csm_core::truth::MIN_POINTS
            );
            continue;
        };
        largest = largest.max(own);
        let _ = writeln!(
            out,
            "  cascade {i}: {:>10}  (world {}, slope bias alone {}, peter-pan {} world units, {} points)",
            short_number(own),
            o(c.depth_bias.map(|d| d[format_index(format)])),
            o(c.slope_bias),
            o(c.peter_pan),
            c.points
        );
    }
    if g.engine.is_some() {
        let _ = writeln!(
            out,
            "  one value for every cascade: {setting} = {}",
            short_number(largest)
        );
    }
    out
}

/// One sentence on the bias the pass sampled with and where it came from (stdout, reports).
pub(crate) fn bias_sentence(g: &GroundTruth) -> String {
    use crate::analysis::ground_truth::BiasSource;
    let what = match g.bias_source {
        BiasSource::Configured => "the [shadow] bias keys".to_string(),
        BiasSource::Engine => format!(
            "the engine's default bias ({})",
            g.engine.map_or("the preset", |e| e.setting)
        ),
        BiasSource::Recommended => {
            "csm-lab's recommended depth bias per cascade (no bias set; --raw-bias or [shadow] bias = \"none\" samples without)"
                .to_string()
        }
        BiasSource::None => "no bias (--raw-bias or [shadow] bias = \"none\")".to_string(),
    };
    format!(
        "bias_source = {}: sampled with {what}; {} PCF {}x{}",
        g.bias_source.name(),
        g.filter.name(),
        g.pcf(),
        g.pcf()
    )
}

fn format_index(f: DepthFormat) -> usize {
    DepthFormat::ALL.iter().position(|x| *x == f).unwrap_or(2)
}

/// `shadow.png`: frame 0 as the sampled maps shade it, snapped beside unsnapped.
pub(crate) struct ShadowPng;
/// `flicker.png`: how often each receiver pixel flipped along the path, snapped beside unsnapped.
pub(crate) struct FlickerPng;
/// `shadow.apng`: the path's kept frames (every k-th, as the pass kept them), both snap modes.
pub(crate) struct ShadowApng;

fn truth_of(a: &Analysis) -> Result<&GroundTruth> {
    a.ground_truth.as_ref().ok_or_else(|| {
        crate::error::Error::from(crate::error::PlotError::Draw(
            "the ground-truth pictures need the ground-truth pass".to_string(),
        ))
    })
}

impl Exporter<Analysis> for ShadowPng {
    fn file_name(&self) -> &'static str {
        "shadow.png"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        shadow_png_of(truth_of(a)?)
    }
}

impl Exporter<Analysis> for FlickerPng {
    fn file_name(&self) -> &'static str {
        "flicker.png"
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        flicker_png_of(truth_of(a)?)
    }
}

impl Exporter<Analysis> for ShadowApng {
    fn file_name(&self) -> &'static str {
        crate::figures::truth::SHADOW_APNG
    }

    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        animation_of(truth_of(a)?)
    }
}

/// `shadow.png` of a ground-truth pass: frame 0, snapped beside unsnapped.
pub(crate) fn shadow_png_of(g: &GroundTruth) -> Result<Vec<u8>> {
    use crate::figures::truth::{shadow_png, Panel};
    shadow_png(&[
        Panel::snapped(&g.pictures_snapped.frame0),
        Panel::unsnapped(&g.pictures_unsnapped.frame0),
    ])
}

/// `flicker.png` of a ground-truth pass: flip rates, snapped beside unsnapped.
pub(crate) fn flicker_png_of(g: &GroundTruth) -> Result<Vec<u8>> {
    use crate::figures::truth::{flicker_png, Panel};
    flicker_png(&[
        Panel::snapped(&g.pictures_snapped.flips),
        Panel::unsnapped(&g.pictures_unsnapped.flips),
    ])
}

/// `shadow.apng` of a ground-truth pass: its kept frames, both snap modes.
pub(crate) fn animation_of(g: &GroundTruth) -> Result<Vec<u8>> {
    use crate::figures::truth::{write_animation, AnimationPlan, ANIMATION_CAPS};
    let (s, u) = (&g.pictures_snapped.animation, &g.pictures_unsnapped.animation);
    let frame0 = &g.pictures_snapped.frame0;
    // The pass kept every k-th path frame of both modes (at most a few dozen small images):
    // the animation shows each of them once, held for k path frames' time.
    let mut plan = AnimationPlan::new(
        s.len().min(u.len()),
        frame0.cols,
        frame0.rows,
        &["snapped", "unsnapped"],
        &ANIMATION_CAPS,
    )?;
    let k = match s.as_slice() {
        [a, b, ..] => b.0 - a.0,
        _ => 1,
    };
    plan.delay_ms = (1000.0 * (k * plan.every) as f64 / ANIMATION_CAPS.path_fps)
        .round()
        .clamp(40.0, 500.0) as u16;
    let frames = s.iter().zip(u).map(|((_, a), (_, b))| vec![a.clone(), b.clone()]);
    let mut out = Vec::new();
    write_animation(&plan, frames, &mut out)?;
    Ok(out)
}
