//! `[motion] light_path` (with its steps or file) and `[shadow] light_update`: the light's
//! motion, validated into [`LightMotion`]. Degrees become radians here.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::location::Validator;
use super::schema::{RawLightUpdate, RawMotion};
use crate::error::{Error, Result};
use csm_core::light_motion::{sun_at, LightMotion, LightPath, LightUpdate};

/// At most this many direction rows (the `motion.frames` limit).
const MAX_ROWS: usize = super::path_file::MAX_PATH_ROWS;

/// The light's motion of a config. `start` is the configured unit light direction, `frames`
/// the camera path's frame count (every frame of the light path must exist and keep the sun
/// above the horizon).
pub fn parse(
    m: &RawMotion,
    update: Option<&RawLightUpdate>,
    v: &Validator<'_>,
    base_dir: Option<&Path>,
    start: DVec3,
    frames: usize,
) -> Result<LightMotion> {
    let name = m.light_path.as_deref().unwrap_or("still");
    let refuse_extra = |key: &str, present: bool, which: &str| -> Result<()> {
        if present {
            Err(v.invalid(
                key,
                "(set)",
                &format!("{key} only together with motion.light_path = \"{which}\" (motion.light_path is {name:?})"),
            ))
        } else {
            Ok(())
        }
    };
    if name != "sun" {
        refuse_extra("motion.sun_azimuth_step_deg", m.sun_azimuth_step_deg.is_some(), "sun")?;
        refuse_extra(
            "motion.sun_elevation_step_deg",
            m.sun_elevation_step_deg.is_some(),
            "sun",
        )?;
    }
    if name != "file" {
        refuse_extra("motion.light_file", m.light_file.is_some(), "file")?;
    }
    let path = match name {
        "still" => LightPath::Still,
        "sun" => {
            let az = v.finite("motion.sun_azimuth_step_deg", m.sun_azimuth_step_deg.unwrap_or(0.0))?;
            let el = v.finite("motion.sun_elevation_step_deg", m.sun_elevation_step_deg.unwrap_or(0.0))?;
            if az == 0.0 && el == 0.0 {
                return Err(v.invalid(
                    "motion.sun_azimuth_step_deg",
                    "0 (and motion.sun_elevation_step_deg 0)",
                    "a non-zero azimuth or elevation step (degrees per frame); a sun that does not move is \
                     motion.light_path = \"still\"",
                ));
            }
            for (key, x) in [
                ("motion.sun_azimuth_step_deg", az),
                ("motion.sun_elevation_step_deg", el),
            ] {
                if x.abs() > 90.0 {
                    return Err(v.invalid(key, x, "a step in [-90, 90] degrees per frame"));
                }
            }
            let path = LightPath::Sun {
                azimuth: az.to_radians(),
                elevation: el.to_radians(),
            };
            check_elevations(v, start, &path, frames)?;
            path
        }
        "file" => {
            let file = m.light_file.as_ref().ok_or_else(|| {
                v.invalid(
                    "motion.light_file",
                    "(missing)",
                    "a CSV file with columns x,y,z (one light direction per frame) when motion.light_path = \"file\"",
                )
            })?;
            let p = PathBuf::from(file);
            let p = match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p,
            };
            let directions = read_light_file(&p)?;
            if directions.len() != frames {
                return Err(v.invalid(
                    "motion.light_file",
                    format!("{} ({} rows)", p.display(), directions.len()),
                    &format!("one direction per frame of the camera path ({frames} rows)"),
                ));
            }
            LightPath::File { path: p, directions }
        }
        other => {
            return Err(v.invalid(
                "motion.light_path",
                format!("{other:?}"),
                "one of \"still\", \"sun\", \"file\"",
            ))
        }
    };
    let update = match update {
        None => LightUpdate::EveryFrame,
        Some(u) => match (u.every_frames, u.quantize_deg) {
            (Some(_), Some(_)) | (None, None) => {
                return Err(v.invalid(
                    "shadow.light_update",
                    "(both or neither key)",
                    "exactly one of { every_frames = K } or { quantize_deg = Q }",
                ))
            }
            (Some(k), None) => {
                LightUpdate::EveryFrames(v.int_range("shadow.light_update.every_frames", k, 1, 1_000_000)? as usize)
            }
            (None, Some(q)) => {
                if !(q.is_finite() && q > 0.0 && q <= 90.0) {
                    return Err(v.invalid(
                        "shadow.light_update.quantize_deg",
                        q,
                        "a grid step in (0, 90] degrees of azimuth and elevation",
                    ));
                }
                LightUpdate::Quantize(q.to_radians())
            }
        },
    };
    Ok(LightMotion { path, update })
}

/// The sun must stand above the horizon (elevation in (0°, 90°]) in every frame; its
/// elevation is linear in the frame, so the first and last frames decide.
fn check_elevations(v: &Validator<'_>, start: DVec3, path: &LightPath, frames: usize) -> Result<()> {
    let LightPath::Sun { azimuth, elevation } = *path else {
        return Ok(());
    };
    let e0 = sun_at(start, azimuth, elevation, 0).elevation;
    if e0 <= 0.0 {
        return Err(v.invalid(
            "light.direction",
            format!("{start:?} (sun elevation {:.6}°)", e0.to_degrees()),
            "a direction pointing down (a sun above the horizon, elevation in (0, 90] degrees) when \
             motion.light_path = \"sun\"",
        ));
    }
    // The first frame outside (0, π/2], if any (a tiny tolerance keeps a path that ends
    // exactly at the zenith).
    let bad = (0..frames).find(|&t| {
        let e = sun_at(start, azimuth, elevation, t).elevation;
        e <= 0.0 || e > std::f64::consts::FRAC_PI_2 + 1e-12
    });
    if let Some(t) = bad {
        let e = sun_at(start, azimuth, elevation, t).elevation.to_degrees();
        return Err(v.invalid(
            "motion.sun_elevation_step_deg",
            format!("{} (frame {t}: elevation {e:.6}°)", elevation.to_degrees()),
            "a step that keeps the sun's elevation in (0, 90] degrees over every frame of the path",
        ));
    }
    Ok(())
}

/// Reads a light path CSV: a header `x,y,z` and one light direction (the way light travels)
/// per frame; each must be finite, non-zero and point down (a sun above the horizon).
pub(crate) fn read_light_file(path: &Path) -> Result<Vec<DVec3>> {
    let mut rows = Vec::new();
    for row in super::path_file::read_number_rows(
        path,
        "a light path file",
        ["x", "y", "z"],
        &format!("rows; a path has at most {MAX_ROWS} frames"),
    )? {
        let (d, line) = row?;
        let d = DVec3::from_array(d);
        let len = d.length();
        if !(len > 1e-12 && len.is_finite()) {
            return Err(Error::data_file(
                path,
                line,
                "a zero direction; expected the way light travels",
            ));
        }
        if d.y >= 0.0 {
            return Err(Error::data_file(
                path,
                line,
                format!(
                    "direction ({}, {}, {}) does not point down: the sun must stand above the horizon \
                     (elevation in (0, 90] degrees, y < 0)",
                    d.x, d.y, d.z
                ),
            ));
        }
        rows.push(d / len);
    }
    if rows.is_empty() {
        return Err(Error::data_file(path, 1, "no direction rows; expected one per frame"));
    }
    Ok(rows)
}

/// A list of light update rules as a sweep axis takes them: `every:1,2,4,8`,
/// `quantize:0.1,0.25,0.5`, or both (`every:1,4,quantize:0.5`); a value without a prefix keeps
/// the kind of the one before. `K` is a whole number in 1..=1000000, `q` degrees in (0, 90].
pub(crate) fn parse_light_update_list(spec: &str) -> std::result::Result<Vec<LightUpdate>, String> {
    let mut kind: Option<&str> = None;
    let mut out = Vec::new();
    for token in spec.split(',').map(str::trim) {
        let value = match token.split_once(':') {
            Some((k, v)) => {
                let k = k.trim();
                if k != "every" && k != "quantize" {
                    return Err(format!("{k:?} is not an update rule; use every:K or quantize:DEG"));
                }
                kind = Some(if k == "every" { "every" } else { "quantize" });
                v.trim()
            }
            None => token,
        };
        let update = match kind {
            None => {
                return Err(format!(
                    "{token:?} has no rule; start with every:K (every K frames) or quantize:DEG (a DEG-degree grid)"
                ))
            }
            Some("every") => match value.parse::<usize>() {
                Ok(k) if (1..=1_000_000).contains(&k) => LightUpdate::EveryFrames(k),
                _ => return Err(format!("every:{value} is not a frame count in 1..=1000000")),
            },
            Some(_) => match value.parse::<f64>() {
                Ok(q) if q.is_finite() && q > 0.0 && q <= 90.0 => LightUpdate::Quantize(q.to_radians()),
                _ => return Err(format!("quantize:{value} is not a grid step in (0, 90] degrees")),
            },
        };
        if out.contains(&update) {
            return Err(format!("{token:?} twice; each rule at most once"));
        }
        out.push(update);
    }
    Ok(out)
}

/// A light update rule as a sweep names it: `every:K` or `quantize:DEG` (DEG back in degrees,
/// to 9 decimals).
pub(crate) fn light_update_label(u: LightUpdate) -> String {
    match u {
        LightUpdate::EveryFrame => "every:1".to_string(),
        LightUpdate::EveryFrames(k) => format!("every:{k}"),
        LightUpdate::Quantize(q) => format!("quantize:{}", (q.to_degrees() * 1e9).round() / 1e9),
    }
}
