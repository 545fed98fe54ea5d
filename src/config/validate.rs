//! Checking a parsed file: every value finite and in range, degrees turned into radians, the
//! world offset applied. The checks themselves are the domain's; this only calls them and names
//! the key when one fails.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use crate::error::Result;
use csm_core::geometry::Aabb;
use csm_core::scene::{Precision, SnapSpace};

use super::schema::{RawConfig, RawFile};
use super::*;

fn p_display(path: &MotionPath) -> String {
    match path {
        MotionPath::File { path, .. } => path.display().to_string(),
        other => other.name().to_string(),
    }
}

/// Parses and validates config text, without applying a preset (the presets module applies one afterwards).
/// `label` names the source in messages; `base_dir` resolves a relative motion path file.
pub fn parse(text: &str, label: &str, base_dir: Option<&Path>) -> Result<Config> {
    let raw = RawFile::parse(text).map_err(|e| toml_error(label, text, &e))?;
    let v = Validator { path: label, text };
    let mut config = validate(raw.config, &v, base_dir)?;
    config.preset_input.label = label.to_string();
    config.preset_input.text = Arc::from(text);
    config.preset_input.other_tables = raw.others;
    Ok(config)
}

fn validate(raw: RawConfig, v: &Validator<'_>, base_dir: Option<&Path>) -> Result<Config> {
    // The world offset moves everything that has a position, before any other check, so the
    // rest of the crate only ever sees the moved scene.
    let world_offset = match raw.scene.world_offset {
        Some(o) => v.point("scene.world_offset", o)?,
        None => DVec3::ZERO,
    };
    let moved = |key: &str, p: [f64; 3]| moved(v, world_offset, key, p);

    let camera = camera(&raw.camera, v, world_offset, &moved)?;
    let views = views(&raw.view, v, &camera, &moved)?;
    let width = v.int_range("screen.width", raw.screen.width, 1, 1 << 20)? as u32;
    let height = v.int_range("screen.height", raw.screen.height, 1, 1 << 20)? as u32;
    // Scene: bounds, geometry, and the bounds defaulting to the geometry's; the glTF's cameras
    // and lights for `[views] from_gltf` and `[light] from_gltf`.
    let (scene, geometry, gltf) = scene(&raw.scene, v, base_dir, world_offset, &moved)?;
    let (light_direction, dir_raw) = light_direction(&raw.light, v, gltf.as_ref())?;

    let mut s = raw.shadow;
    let light_update = s.light_update.take();
    let written = written(&s);
    let (shadow, mut truth) = shadow_settings(&s, v, camera.far, geometry.is_some())?;

    let mut m = raw.motion;
    let m_light = super::schema::RawMotion {
        light_path: m.light_path.take(),
        sun_azimuth_step_deg: m.sun_azimuth_step_deg,
        sun_elevation_step_deg: m.sun_elevation_step_deg,
        light_file: m.light_file.take(),
        ..Default::default()
    };
    let mut motion = camera_motion(m, v, base_dir, world_offset)?;
    motion.light = super::light_motion::parse(
        &m_light,
        light_update.as_ref(),
        v,
        base_dir,
        light_direction,
        motion.frames,
    )?;

    truth.enabled = ground_truth(&raw.analysis, v, geometry.is_some(), &motion.light)?.unwrap_or(truth.enabled);
    let analysis = analysis_settings(&raw.analysis, v)?;
    let cost = cost_settings(&raw.cost, v, geometry.is_some())?;
    if geometry.is_some() {
        sampled_pixels_fit(v, width, height, analysis.screen_scale())?;
    }

    let sweep = raw
        .sweep
        .map(|s| super::sweep_spec::validate_raw(s, v, geometry.is_some()))
        .transpose()?;
    if let Some(b) = sweep.as_ref().and_then(|s| s.shadow_ms_budget) {
        if cost.calibration.is_none() {
            return Err(v.invalid(
                "sweep.shadow_ms_budget",
                b,
                "a budget in milliseconds only with a calibrated cost model: give [cost] ns_per_draw, ns_per_triangle, ns_per_fragment and ns_per_texel_cleared (docs/cost.md), or use sweep.cost_budget in cost_index units",
            ));
        }
    }

    if !cost.counts {
        let budgets = sweep.as_ref().map(|s| {
            [
                ("sweep.cost_budget", s.cost_budget),
                ("sweep.shadow_ms_budget", s.shadow_ms_budget),
            ]
        });
        if let Some((key, Some(b))) = budgets.into_iter().flatten().find(|(_, b)| b.is_some()) {
            return Err(v.invalid(
                key,
                b,
                "no render-cost budget with cost.counts = false: the budget is judged on the counts (drop the budget or set cost.counts = true)",
            ));
        }
    }

    let mut config = Config {
        name: "config".to_string(),
        path: None,
        camera,
        screen: Screen { width, height },
        light_direction,
        light_direction_as_written: dir_raw,
        scene,
        geometry,
        world_offset,
        shadow,
        motion,
        analysis,
        sweep,
        preset_input: PresetInput {
            preset: s.preset,
            written,
            ..PresetInput::default()
        },
        truth,
        views: std::sync::Arc::new(views),
        warnings: Vec::new(),
        cost,
    };
    check_camera_path(&config, v)?;
    let sources = super::view_sources::add_views(&mut config, raw.views.as_ref(), v, base_dir, gltf.as_ref())?;
    // Every view of the level, however it was named: not inside geometry, seeing a receiver.
    super::view_sources::check_views(&mut config, v, &sources)?;
    // The binary32 range check needs the cascades, which an engine preset may change: it runs
    // once the preset is applied (`crate::load`).
    Ok(config)
}

/// A written point moved by the world offset, kept within the world bounds.
fn moved(v: &Validator<'_>, world_offset: DVec3, key: &str, p: [f64; 3]) -> Result<DVec3> {
    let q = v.point(key, p)? + world_offset;
    if q.abs().max_element() <= MAX_WORLD {
        Ok(q)
    } else {
        Err(v.invalid(
            "scene.world_offset",
            format!("{:?}", world_offset.to_array()),
            &format!("an offset that keeps {key} within ±1e9 world units ({p:?} + offset)"),
        ))
    }
}

/// `[camera]`: position and target (moved by the world offset), up, field of view and planes.
fn camera(
    raw: &super::schema::RawCamera,
    v: &Validator<'_>,
    world_offset: DVec3,
    moved: &dyn Fn(&str, [f64; 3]) -> Result<DVec3>,
) -> Result<CameraSettings> {
    let position = moved("camera.position", raw.position)?;
    let target = moved("camera.target", raw.target)?;
    let up = match raw.up {
        Some(u) => v.vec3("camera.up", u)?,
        None => DVec3::Y,
    };
    let view = target - position;
    if view.length() <= 1e-12 * (1.0 + position.length()) {
        return Err(v.invalid(
            "camera.target",
            format!("{:?}", raw.target),
            if world_offset == DVec3::ZERO {
                "a point different from camera.position (the view direction is target - position)"
            } else {
                "a point different from camera.position once scene.world_offset is added (at this offset \
                 the two round to the same point)"
            },
        ));
    }
    if up.length() <= 1e-300 {
        return Err(v.invalid("camera.up", format!("{:?}", up.to_array()), "a non-zero vector"));
    }
    if view.normalize().cross(up.normalize()).length() < 1e-9 {
        return Err(v.invalid(
            "camera.up",
            format!("{:?}", up.to_array()),
            "a vector not parallel to the view direction (target - position)",
        ));
    }
    let fov = v.finite("camera.fov_y_deg", raw.fov_y_deg)?;
    // Strictly between 0 and 180, with a margin: at 1e-300 degrees tan(fov/2) underflows and
    // the pixel footprint becomes infinite.
    if !(0.001..=179.999).contains(&fov) {
        return Err(v.invalid(
            "camera.fov_y_deg",
            fov,
            "degrees strictly between 0 and 180, from 0.001 to 179.999",
        ));
    }
    let near = v.finite("camera.near", raw.near)?;
    if near <= 0.0 {
        return Err(v.invalid("camera.near", near, "a number > 0"));
    }
    let far = v.finite("camera.far", raw.far)?;
    if far > MAX_WORLD {
        return Err(v.invalid("camera.far", far, "a number at most 1e9 world units"));
    }
    if far <= near {
        return Err(v.invalid(
            "camera.far",
            far,
            &format!("a number greater than camera.near ({near})"),
        ));
    }
    // A depth ratio beyond 1e12 overflows the logarithmic split term (1e-308 .. 1000 did).
    if far / near > 1e12 {
        return Err(v.invalid(
            "camera.near",
            near,
            &format!(
                "a number at least camera.far / 1e12 ({:e}): far / near may be at most 1e12",
                far / 1e12
            ),
        ));
    }

    Ok(CameraSettings {
        position,
        target,
        up,
        fov_y_deg: fov,
        near,
        far,
    })
}

/// Most views a config may name: each costs one visibility pass and one pass over its pixels
/// per setting of a sweep.
pub(crate) const MAX_VIEWS: usize = 10_000;

/// A view's weight: `[1e-6, 1e6]`, so that its whole steps (`csm_core::screen::
/// view_weight_steps`) are at least one and every pooled sum fits 128 bits.
pub(crate) const VIEW_WEIGHT_RANGE: (f64, f64) = (1e-6, 1e6);

/// `[[view]]`: each entry's name (unique, 1 to 64 printable characters), position and target
/// (moved by the world offset, as `[camera]`'s), up and field of view (`[camera]`'s when left
/// out) and weight (1 when left out). Near and far are always `[camera]`'s.
fn views(
    raw: &[super::schema::RawView],
    v: &Validator<'_>,
    camera: &CameraSettings,
    moved: &dyn Fn(&str, [f64; 3]) -> Result<DVec3>,
) -> Result<Vec<ViewSettings>> {
    if raw.len() > MAX_VIEWS {
        return Err(v.invalid(
            "view",
            format!("{} entries", raw.len()),
            &format!("at most {MAX_VIEWS} [[view]] entries"),
        ));
    }
    let mut out: Vec<ViewSettings> = Vec::with_capacity(raw.len());
    for (i, r) in raw.iter().enumerate() {
        let key = |k: &str| format!("view[{i}].{k}");
        let name = r.name.get_ref();
        let printable = !name.is_empty() && name.chars().count() <= 64 && !name.chars().any(char::is_control);
        if !printable || name.trim() != name {
            return Err(v.invalid_at(
                &key("name"),
                r.name.span(),
                format!("{name:?}"),
                "a name of 1 to 64 printable characters, without leading or trailing spaces",
            ));
        }
        if let Some(j) = out.iter().position(|o| o.name == *name) {
            return Err(v.invalid_at(
                &key("name"),
                r.name.span(),
                format!("{name:?}"),
                &format!("a name no other view has (view[{j}] is {name:?} too)"),
            ));
        }
        let position = moved(&key("position"), r.position)?;
        let target = moved(&key("target"), r.target)?;
        let dir = target - position;
        if dir.length() <= 1e-12 * (1.0 + position.length()) {
            return Err(v.invalid(
                &key("target"),
                format!("{:?}", r.target),
                &format!(
                    "a point different from {} (the view direction is target - position)",
                    key("position")
                ),
            ));
        }
        let up = match r.up {
            Some(u) => {
                let up = v.vec3(&key("up"), u)?;
                if up.length() <= 1e-300 {
                    return Err(v.invalid(&key("up"), format!("{u:?}"), "a non-zero vector"));
                }
                up
            }
            None => camera.up,
        };
        if dir.normalize().cross(up.normalize()).length() < 1e-9 {
            let what = if r.up.is_some() {
                key("up")
            } else {
                "camera.up (the view's default up)".to_string()
            };
            return Err(v.invalid(
                &key(if r.up.is_some() { "up" } else { "target" }),
                format!(
                    "{:?}",
                    if r.up.is_some() {
                        r.up.unwrap_or_default()
                    } else {
                        r.target
                    }
                ),
                &format!("a view direction (target - position) not parallel to {what}"),
            ));
        }
        let fov_y_deg = match r.fov_y_deg {
            Some(f) => {
                let f = v.finite(&key("fov_y_deg"), f)?;
                if !(0.001..=179.999).contains(&f) {
                    return Err(v.invalid(
                        &key("fov_y_deg"),
                        f,
                        "degrees strictly between 0 and 180, from 0.001 to 179.999",
                    ));
                }
                f
            }
            None => camera.fov_y_deg,
        };
        let weight = match r.weight {
            Some(w) => {
                let (lo, hi) = VIEW_WEIGHT_RANGE;
                if !(lo..=hi).contains(&w) {
                    return Err(v.invalid(&key("weight"), w, "a number > 0, from 1e-6 to 1e6"));
                }
                w
            }
            None => 1.0,
        };
        out.push(ViewSettings {
            name: name.clone(),
            camera: CameraSettings {
                position,
                target,
                up,
                fov_y_deg,
                near: camera.near,
                far: camera.far,
            },
            weight,
        });
    }
    Ok(out)
}

/// `light.direction`, or `light.from_gltf = true` (the glTF's first directional light): the
/// unit direction light travels, and the direction as written (as read, from the glTF).
fn light_direction(
    raw: &super::schema::RawLight,
    v: &Validator<'_>,
    gltf: Option<&super::GltfScene>,
) -> Result<(DVec3, DVec3)> {
    let direction = match (raw.direction, raw.from_gltf) {
        (Some(_), Some(true)) => {
            return Err(v.invalid(
                "light.from_gltf",
                true,
                "either light.direction or light.from_gltf = true, not both",
            ))
        }
        (None, Some(true)) => {
            let d = super::view_sources::gltf_light(v, gltf)?;
            return Ok((d, d));
        }
        (Some(d), _) => d,
        (None, _) => {
            return Err(v.invalid(
                "light.direction",
                "(missing)",
                "the direction light travels, e.g. [0.3, -1.0, 0.2], or light.from_gltf = true",
            ))
        }
    };
    let dir_raw = v.vec3("light.direction", direction)?;
    let len = dir_raw.length();
    if len <= 1e-12 || !len.is_finite() {
        return Err(v.invalid(
            "light.direction",
            format!("{direction:?}"),
            "a non-zero vector (the direction light travels)",
        ));
    }
    Ok((dir_raw / len, dir_raw))
}

/// Which `[shadow]` keys the file writes (a preset's defaults fill the others).
fn written(s: &super::schema::RawShadow) -> Written {
    Written {
        max_distance: s.max_distance.is_some(),
        cascades: s.cascades.is_some(),
        resolution: s.resolution.is_some(),
        lambda: s.lambda.is_some(),
        splits: s.splits.is_some(),
        fit: s.fit.is_some(),
        snap: s.snap.is_some(),
        fit_depth_to_scene: s.fit_depth_to_scene.is_some(),
    }
}

/// `[shadow]`: distance, count, λ or fractions, map size, fit, snapping, depth fitting,
/// precision, and the ground-truth settings ([`truth_settings`]), checked in the order they
/// are listed in the file's documentation. `far` is the camera's (the default shadow distance).
fn shadow_settings(
    s: &super::schema::RawShadow,
    v: &Validator<'_>,
    far: f64,
    has_geometry: bool,
) -> Result<(ShadowSettings, crate::config::TruthSettings)> {
    let max_distance = match s.max_distance {
        Some(d) => {
            let d = v.finite("shadow.max_distance", d)?;
            if d <= 0.0 || d > MAX_WORLD {
                return Err(v.invalid("shadow.max_distance", d, "a number > 0 and at most 1e9 world units"));
            }
            d
        }
        None => far,
    };
    let cascades = v.int_range("shadow.cascades", s.cascades.unwrap_or(4), 1, 16)? as usize;
    let lambda = v.finite("shadow.lambda", s.lambda.unwrap_or(0.75))?;
    if !(0.0..=1.0).contains(&lambda) {
        return Err(v.invalid("shadow.lambda", lambda, "a number in [0, 1] (0 uniform, 1 logarithmic)"));
    }
    let splits = match &s.splits {
        None => None,
        Some(x) => Some(split_fractions(v, x, cascades)?),
    };
    let resolution = v.int_range("shadow.resolution", s.resolution.unwrap_or(2048), 16, 16384)? as u32;
    let precision = match s.precision.as_deref() {
        None => Precision::F64,
        Some(name) => Precision::from_name(name)
            .ok_or_else(|| v.invalid("shadow.precision", format!("{name:?}"), "one of \"f64\", \"f32\""))?,
    };
    let snap_space = match s.snap_space.as_deref() {
        None => SnapSpace::World,
        Some(name) => SnapSpace::from_name(name).ok_or_else(|| {
            v.invalid(
                "shadow.snap_space",
                format!("{name:?}"),
                "one of \"world\", \"camera_relative\"",
            )
        })?,
    };
    let truth = truth_settings(s, v)?;
    let update_every = s.update_every.as_ref().map(|x| update_every(v, x)).transpose()?;
    let shadow = ShadowSettings {
        params: ShadowParams {
            max_distance,
            cascades,
            lambda,
            splits,
            resolution,
            fit: match &s.fit {
                Some(f) => v.one_of("shadow.fit", f, &[("sphere", Fit::Sphere), ("aabb", Fit::Aabb)])?,
                None => Fit::Sphere,
            },
            snap: s.snap.unwrap_or(true),
            fit_depth_to_scene: s.fit_depth_to_scene.unwrap_or(true),
            fit_depth_to_visible: match s.fit_depth_to_visible {
                Some(true) if !has_geometry => {
                    return Err(v.invalid(
                        "shadow.fit_depth_to_visible",
                        true,
                        "false without scene geometry: add scene.ground, [[scene.box]] or scene.gltf \
                         (the bounds alone show no visible depth)",
                    ))
                }
                f => f.unwrap_or(false),
            },
            precision,
            snap_space,
        },
        preset: None,
        update_every: update_every.and_then(UpdateEvery::caching),
    };
    Ok((shadow, truth))
}

/// `[shadow]`'s ground-truth settings: the bias keys, the depth format and the PCF kernel
/// (`enabled` is `analysis.ground_truth`'s, set later).
fn truth_settings(s: &super::schema::RawShadow, v: &Validator<'_>) -> Result<crate::config::TruthSettings> {
    let bias_key = |key: &str, x: Option<f64>, allowed: &str| -> Result<Option<f64>> {
        match x {
            Some(b) if !(b.is_finite() && (0.0..=MAX_WORLD).contains(&b)) => Err(v.invalid(key, b, allowed)),
            x => Ok(x),
        }
    };
    let mut truth = crate::config::TruthSettings {
        depth_bias: bias_key(
            "shadow.depth_bias",
            s.depth_bias,
            "a number >= 0: world units added along the light to the stored depth",
        )?,
        slope_bias: bias_key(
            "shadow.slope_bias",
            s.slope_bias,
            "a number >= 0: times the receiver's depth slope per texel",
        )?,
        normal_bias: bias_key(
            "shadow.normal_bias",
            s.normal_bias,
            "a number >= 0: texels the receiver moves along its normal",
        )?,
        ..Default::default()
    };
    if let Some(f) = &s.depth_format {
        use csm_core::truth::DepthFormat;
        truth.depth_format = v.one_of(
            "shadow.depth_format",
            f,
            &[
                ("d16", DepthFormat::D16),
                ("d24", DepthFormat::D24),
                ("d32f", DepthFormat::D32F),
            ],
        )?;
    }
    if let Some(f) = &s.pcf_filter {
        use csm_core::truth::PcfFilter;
        truth.pcf_filter = Some(v.one_of(
            "shadow.pcf_filter",
            f,
            &[("bilinear", PcfFilter::Bilinear), ("nearest", PcfFilter::Nearest)],
        )?);
    }
    if let Some(b) = &s.bias {
        use crate::config::BiasMode;
        let mode = v.one_of(
            "shadow.bias",
            b,
            &[("none", BiasMode::None), ("recommended", BiasMode::Recommended)],
        )?;
        if truth.bias_written() {
            return Err(v.invalid(
                "shadow.bias",
                format!("{:?}", mode.name()),
                "absent when shadow.depth_bias, shadow.slope_bias or shadow.normal_bias is set \
                 (those keys are the bias); \"none\" or \"recommended\" without them",
            ));
        }
        truth.bias_mode = Some(mode);
    }
    if let Some(k) = s.pcf {
        if ![1, 3, 5].contains(&k) {
            return Err(v.invalid("shadow.pcf", k, "1, 3 or 5: the PCF kernel's width in texels"));
        }
        truth.pcf = k as u32;
    }
    Ok(truth)
}

/// `[motion]`'s camera path: the path or paths, their steps and frame count (the light's
/// motion is read apart, [`super::light_motion::parse`]).
fn camera_motion(
    m: super::schema::RawMotion,
    v: &Validator<'_>,
    base_dir: Option<&Path>,
    world_offset: DVec3,
) -> Result<MotionSettings> {
    let frames = v.int_range("motion.frames", m.frames.unwrap_or(240), 2, 1_000_000)? as usize;
    let step_as_written = v.finite("motion.step", m.step.unwrap_or(0.05))?;
    let file = m.file;
    let parse_path = |name: &str, step_as_written: f64, key: &str| {
        motion_path(v, name, step_as_written, key, file.as_deref(), base_dir, world_offset)
    };
    let names = path_names(v, m.path, m.paths)?;
    let steps: Vec<f64> = match m.steps {
        None => vec![step_as_written; names.len()],
        Some(list) if list.len() == names.len() => list
            .into_iter()
            .map(|x| v.finite("motion.steps", x))
            .collect::<Result<_>>()?,
        Some(list) => {
            return Err(v.invalid(
                "motion.steps",
                format!("{} entries", list.len()),
                &format!("one step per entry of motion.paths ({})", names.len()),
            ))
        }
    };
    let key = if names.len() > 1 { "motion.paths" } else { "motion.path" };
    let (path, step) = parse_path(&names[0], steps[0], key)?;
    let step_as_written = steps[0];
    let mut extra = Vec::new();
    for (name, &sw) in names.iter().zip(&steps).skip(1) {
        let (p, st) = parse_path(name, sw, key)?;
        if p.is_translation() && sw.abs() * (frames - 1) as f64 > MAX_WORLD {
            return Err(v.invalid(
                "motion.steps",
                sw,
                &format!("a step whose {} frames travel at most 1e9 world units", frames),
            ));
        }
        extra.push(super::ExtraPath {
            path: p,
            step: st,
            step_as_written: sw,
        });
    }
    let frames = match &path {
        MotionPath::File { poses, .. } => poses.len(),
        _ => frames,
    };
    // Keep the whole path within the world bounds.
    if path.is_translation() && step_as_written.abs() * (frames - 1) as f64 > MAX_WORLD {
        return Err(v.invalid(
            "motion.step",
            step_as_written,
            &format!("a step whose {} frames travel at most 1e9 world units", frames),
        ));
    }
    if let MotionPath::File { poses, .. } = &path {
        if let Some(row) = poses
            .iter()
            .position(|(p, t)| p.abs().max(t.abs()).max_element() > MAX_WORLD)
        {
            return Err(v.invalid(
                "motion.file",
                format!("{} (pose row {})", p_display(&path), row + 1),
                "positions and targets within ±1e9 world units",
            ));
        }
    }

    Ok(MotionSettings {
        path,
        frames,
        step,
        step_as_written,
        extra,
        light: Default::default(),
    })
}

/// `motion.path` or `motion.paths`: the names of the camera paths (`strafe` by default).
fn path_names(v: &Validator<'_>, path: Option<String>, paths: Option<Vec<String>>) -> Result<Vec<String>> {
    Ok(match (path, paths) {
        (Some(_), Some(_)) => {
            return Err(v.invalid(
                "motion.paths",
                "(with motion.path)",
                "either `path = \"NAME\"` or `paths = [\"NAME\", ...]`, not both",
            ))
        }
        (Some(p), None) => vec![p],
        (None, Some(list)) => {
            if list.is_empty() || list.len() > 8 {
                return Err(v.invalid(
                    "motion.paths",
                    format!("{} entries", list.len()),
                    "a list of 1 to 8 path names",
                ));
            }
            for (i, a) in list.iter().enumerate() {
                if list[..i].contains(a) {
                    return Err(v.invalid("motion.paths", format!("{a:?} twice"), "each path at most once"));
                }
            }
            list
        }
        (None, None) => vec!["strafe".to_string()],
    })
}

/// One camera path by name, its step per frame as written and the key it came from: the path
/// and its step in the path's own unit (a `file` path reads its poses, moved by the world
/// offset).
fn motion_path(
    v: &Validator<'_>,
    name: &str,
    step_as_written: f64,
    key: &str,
    file: Option<&str>,
    base_dir: Option<&Path>,
    world_offset: DVec3,
) -> Result<(MotionPath, f64)> {
    if name != "file" {
        if let Some(file) = &file {
            return Err(v.invalid(
                "motion.file",
                format!("{file:?}"),
                &format!(
                    "motion.file only together with motion.path = \"file\" (motion.path is {name:?}); \
                     set motion.path = \"file\" or remove motion.file"
                ),
            ));
        }
        if step_as_written == 0.0 && name != "still" {
            return Err(v.invalid(
                if key == "motion.paths" {
                    "motion.steps"
                } else {
                    "motion.step"
                },
                step_as_written,
                "a non-zero step (world units or degrees per frame); a zero step does not move the camera",
            ));
        }
    }
    Ok(match name {
        name if MotionPath::generated(name).is_some() => {
            let path = MotionPath::generated(name).expect("just matched");
            let step = path.step_from_written(step_as_written);
            (path, step)
        }
        "file" => {
            let file = file.ok_or_else(|| {
                v.invalid(
                    "motion.file",
                    "(missing)",
                    "a CSV file with columns px,py,pz,tx,ty,tz when motion.path = \"file\"",
                )
            })?;
            let p = PathBuf::from(file);
            let p = match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p,
            };
            let poses = super::read_path_file(&p)?
                .into_iter()
                .map(|(position, target)| (position + world_offset, target + world_offset))
                .collect();
            (MotionPath::File { path: p, poses }, 0.0)
        }
        other => {
            return Err(v.invalid(
                key,
                format!("{other:?}"),
                &format!("one of {}", MotionPath::names_quoted()),
            ))
        }
    })
}

/// `analysis.ground_truth`, refused without geometry or under a moving light.
fn ground_truth(
    a: &super::schema::RawAnalysis,
    v: &Validator<'_>,
    has_geometry: bool,
    light: &csm_core::light_motion::LightMotion,
) -> Result<Option<bool>> {
    if let Some(on) = a.ground_truth {
        if on && !has_geometry {
            return Err(v.invalid(
                "analysis.ground_truth",
                true,
                "false without scene geometry: add scene.ground, [[scene.box]] or scene.gltf (the map samples real casters)",
            ));
        }
        if on && light.moves() {
            return Err(v.invalid(
                "analysis.ground_truth",
                true,
                "false while motion.light_path moves the light: the ground-truth pass samples the maps under one still light",
            ));
        }
    }
    Ok(a.ground_truth)
}

/// `[analysis]`: sample counts and the screen scale.
fn analysis_settings(a: &super::schema::RawAnalysis, v: &Validator<'_>) -> Result<AnalysisSettings> {
    Ok(AnalysisSettings {
        density_samples: v.int_range(
            "analysis.density_samples",
            a.density_samples.unwrap_or(512),
            2,
            1_000_000,
        )? as usize,
        probes: v.int_range("analysis.probes", a.probes.unwrap_or(256), 1, 1_000_000)? as usize,
        screen_scale: match a.screen_scale {
            Some(x) if !(x > 0.0 && x <= 1.0) => {
                return Err(v.invalid(
                    "analysis.screen_scale",
                    x,
                    "a number in (0, 1]: the fraction of the screen's width and height sampled (1 = every pixel)",
                ))
            }
            x => x,
        },
    })
}

/// `[cost]`: `cull` is "none" or "receivers" (which needs scene geometry: the receivers come
/// from the visibility pass); the four `ns_per_*` coefficients are finite, at least 0, and
/// given all together or not at all.
fn cost_settings(c: &super::schema::RawCost, v: &Validator<'_>, has_geometry: bool) -> Result<CostSettings> {
    let counts = c.counts.unwrap_or(true);
    let cull = match c.cull.as_deref() {
        None | Some("none") => CostCull::None,
        Some("receivers") if !counts => {
            return Err(v.invalid(
                "cost.cull",
                "\"receivers\"",
                "\"none\" with cost.counts = false: culling changes the counts, which are not taken",
            ))
        }
        Some("receivers") if has_geometry => CostCull::Receivers,
        Some("receivers") => {
            return Err(v.invalid(
                "cost.cull",
                "\"receivers\"",
                "\"none\" without scene geometry: culling by receivers needs the visible receivers (give scene.ground, [[scene.box]] or scene.gltf)",
            ))
        }
        Some(other) => return Err(v.invalid("cost.cull", format!("{other:?}"), "\"none\" or \"receivers\"")),
    };
    let keys = [
        ("cost.ns_per_draw", c.ns_per_draw),
        ("cost.ns_per_triangle", c.ns_per_triangle),
        ("cost.ns_per_fragment", c.ns_per_fragment),
        ("cost.ns_per_texel_cleared", c.ns_per_texel_cleared),
    ];
    let mut given = Vec::new();
    for (key, x) in keys {
        if let Some(x) = x {
            if !(x.is_finite() && x >= 0.0) {
                return Err(v.invalid(key, x, "a finite number of nanoseconds, at least 0"));
            }
            given.push(x);
        }
    }
    let calibration = match given.len() {
        0 => None,
        4 => Some(csm_core::cost::CostModel {
            per_draw: given[0],
            per_triangle: given[1],
            per_fragment: given[2],
            per_texel_cleared: given[3],
        }),
        _ => {
            let (missing, _) = keys.iter().find(|(_, x)| x.is_none()).expect("fewer than four given");
            return Err(v.invalid(
                missing,
                "(missing)",
                "all four of cost.ns_per_draw, cost.ns_per_triangle, cost.ns_per_fragment and cost.ns_per_texel_cleared, or none (docs/cost.md: calibration)",
            ));
        }
    };
    if calibration.is_some_and(|m| m.of(1.0, 1.0, 1.0, 1.0) <= 0.0) {
        return Err(v.invalid(
            "cost.ns_per_draw",
            0,
            "coefficients that are not all 0 (a frame that costs nothing cannot be calibrated)",
        ));
    }
    Ok(CostSettings {
        counts,
        cull,
        calibration,
    })
}

/// Every pose of the motion path must be a valid camera (pitching through the up vector, or a
/// path file row with position == target, is a config error, not a panic later).
pub(crate) fn check_camera_path(config: &Config, v: &Validator<'_>) -> Result<()> {
    // Pose by pose, none kept: a long path costs time, not memory.
    config
        .check_camera_paths()
        .map_err(|(k, frame, why)| match (k, &config.motion.path) {
            (0, MotionPath::File { path, .. }) => v.invalid(
                "motion.file",
                format!("{} line {} (frame {frame})", path.display(), frame + 2),
                &format!("rows that each give a valid camera: {why}"),
            ),
            (0, _) => v.invalid(
                "motion.step",
                format!("{} (frame {frame})", config.motion.step_as_written),
                &format!("a motion that keeps a valid camera in every frame: {why}"),
            ),
            _ => v.invalid(
                "motion.paths",
                format!("{:?} (frame {frame})", config.motion.extra[k - 1].path.name()),
                &format!("a motion that keeps a valid camera in every frame: {why}"),
            ),
        })
}

/// Most pixels the visibility pass samples (`round(width·s) × round(height·s)`): 2^25, an 8K
/// screen (7680 × 4320) at `screen_scale = 1`.
pub(crate) const MAX_SAMPLED_PIXELS: u64 = 1 << 25;

/// Bytes the visibility pass holds per sampled pixel, about (hit, normal, depth and the
/// per-cascade lookups: 16384² sampled pixels asked for 10 GiB at once).
const BYTES_PER_SAMPLED_PIXEL: f64 = 40.0;

/// Refuses, before any work, a screen and `analysis.screen_scale` whose sampled pixel count
/// exceeds [`MAX_SAMPLED_PIXELS`]: the largest accepted screen at the default scale asked for
/// 687 GB in one allocation and aborted. The message gives the estimate and the scale that fits.
fn sampled_pixels_fit(v: &Validator<'_>, width: u32, height: u32, scale: f64) -> Result<()> {
    let n = |x: u32| ((f64::from(x) * scale).round() as u64).clamp(1, u64::from(x));
    let (w, h) = (n(width), n(height));
    let pixels = w * h;
    if pixels <= MAX_SAMPLED_PIXELS {
        return Ok(());
    }
    let fits = (MAX_SAMPLED_PIXELS as f64 / (f64::from(width) * f64::from(height))).sqrt();
    Err(v.invalid(
        "analysis.screen_scale",
        scale,
        &format!(
            "a scale whose sampled grid has at most {MAX_SAMPLED_PIXELS} pixels: the {width} x {height} screen at this \
             scale samples {w} x {h} = {pixels} pixels (about {:.1} GB); set analysis.screen_scale to at most {} or use \
             a smaller screen",
            pixels as f64 * BYTES_PER_SAMPLED_PIXEL / 1e9,
            (fits * 1e4).floor() / 1e4
        ),
    ))
}

/// The scene's bounds and geometry. Without geometry `min` and `max` are required; with it
/// they default to the geometry's bounds (the ground spans the bounds' x/z extent, so it needs
/// either written bounds or other geometry to take them from).
fn scene(
    raw: &super::schema::RawScene,
    v: &Validator<'_>,
    base_dir: Option<&Path>,
    world_offset: DVec3,
    moved: &dyn Fn(&str, [f64; 3]) -> Result<DVec3>,
) -> Result<(Aabb, Option<GeometrySettings>, Option<super::GltfScene>)> {
    let written = match (raw.min, raw.max) {
        (Some(lo), Some(hi)) => {
            let smin = moved("scene.min", lo)?;
            let smax = moved("scene.max", hi)?;
            if smin.cmpgt(smax).any() {
                return Err(v.invalid(
                    "scene.max",
                    format!("{hi:?}"),
                    &format!("each component >= scene.min {lo:?} (a zero thickness is allowed)"),
                ));
            }
            Some(Aabb::new(smin, smax))
        }
        (None, None) => None,
        (Some(_), None) => return Err(v.invalid("scene.max", "(missing)", "a point, given with scene.min")),
        (None, Some(_)) => return Err(v.invalid("scene.min", "(missing)", "a point, given with scene.max")),
    };
    let has_geometry = raw.ground.is_some() || raw.boxes.is_some() || raw.gltf.is_some();
    if !has_geometry {
        let bounds = written.ok_or_else(|| {
            v.invalid(
                "scene.min",
                "(missing)",
                "scene.min and scene.max, or scene geometry (scene.ground, [[scene.box]], scene.gltf)",
            )
        })?;
        return Ok((bounds, None, None));
    }
    let mut mesh = csm_core::mesh::Mesh::default();
    let mut gltf_scene = None;
    let mut boxes = Vec::new();
    for (i, b) in raw.boxes.iter().flatten().enumerate() {
        let lo = moved("scene.box.min", b.min)?;
        let hi = moved("scene.box.max", b.max)?;
        if lo.cmpgt(hi).any() {
            return Err(v.invalid_found(
                "scene.box.max",
                &format!("scene.box[{i}].max"),
                format!("{:?} (box {})", b.max, i + 1),
                &format!("each component >= that box's min {:?}", b.min),
            ));
        }
        let aabb = Aabb::new(lo, hi);
        mesh.add_box(&aabb);
        boxes.push(aabb);
    }
    let gltf = match &raw.gltf {
        Some(name) => {
            let p = PathBuf::from(name);
            let p = match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p,
            };
            let allowed = |why: &str| format!("a readable glTF 2.0 file (.gltf or .glb) with triangles: {why}");
            let mut read = super::read_gltf_scene(&p, raw.gltf_outside_buffers)
                .map_err(|why| v.invalid("scene.gltf", format!("{name:?}"), &allowed(&why)))?;
            let primitives = std::mem::take(&mut read.primitives);
            gltf_scene = Some(read);
            if primitives.iter().all(|t| t.is_empty()) {
                return Err(v.invalid(
                    "scene.gltf",
                    format!("{name:?}"),
                    &allowed("its default scene has no triangles"),
                ));
            }
            for tris in primitives {
                let tris: Vec<[DVec3; 3]> = tris.into_iter().map(|t| t.map(|p| p + world_offset)).collect();
                if tris.iter().flatten().any(|p| p.abs().max_element() > MAX_WORLD) {
                    return Err(v.invalid(
                        "scene.gltf",
                        format!("{name:?}"),
                        "vertices within ±1e9 world units (after scene.world_offset)",
                    ));
                }
                // One draw call per primitive instance.
                mesh.add_object(csm_core::mesh::ObjectKind::Primitive, tris);
            }
            Some(p)
        }
        None => None,
    };
    let ground = match raw.ground {
        Some(y) => {
            let y = v.finite("scene.ground", y)? + world_offset.y;
            if y.abs() > MAX_WORLD {
                return Err(v.invalid("scene.ground", y, "a height within ±1e9 world units"));
            }
            let extent = written.or_else(|| mesh.bounds()).ok_or_else(|| {
                v.invalid(
                    "scene.ground",
                    y,
                    "a ground with an extent: give scene.min and scene.max, or boxes or a glTF to take it from",
                )
            })?;
            mesh.add_ground(y, extent.min.x, extent.max.x, extent.min.z, extent.max.z);
            Some(y)
        }
        None => None,
    };
    let Some(mesh_bounds) = mesh.bounds() else {
        return Err(v.invalid(
            "scene.box",
            "(only boxes of zero volume and area)",
            "at least one box with a face of non-zero area",
        ));
    };
    let bounds = written.unwrap_or(mesh_bounds);
    let geometry = GeometrySettings {
        ground,
        boxes,
        gltf,
        scene: Arc::new(csm_core::visibility::SceneGeometry::new(mesh)),
        pool_memo: Arc::default(),
    };
    Ok((bounds, Some(geometry), gltf_scene))
}

/// `shadow.splits`: `cascades − 1` fractions of the split range, strictly increasing inside
/// (0, 1). The error names the key, the value and what is allowed.
fn split_fractions(v: &Validator<'_>, x: &[f64], cascades: usize) -> Result<csm_core::free_splits::SplitFractions> {
    let allowed = format!(
        "{} fraction{} of the split range (shadow.cascades − 1), strictly increasing and strictly between 0 and 1, \
         e.g. {}",
        cascades - 1,
        if cascades == 2 { "" } else { "s" },
        example_fractions(cascades)
    );
    let shown = format!("{x:?}");
    if x.len() + 1 != cascades {
        return Err(v.invalid(
            "shadow.splits",
            &shown,
            &format!("{allowed} (got {} for {cascades} cascades)", x.len()),
        ));
    }
    csm_core::free_splits::SplitFractions::new(x).ok_or_else(|| v.invalid("shadow.splits", &shown, &allowed))
}

/// The largest `shadow.update_every`: frames between two renders of a cascade.
pub(crate) const MAX_UPDATE_EVERY: i64 = 256;

/// `shadow.update_every`: an integer in 1..=256, or an array of them (one per cascade; the
/// count is checked once the cascades are known, `crate::load`).
fn update_every(v: &Validator<'_>, x: &toml::Value) -> Result<UpdateEvery> {
    let allowed = format!(
        "an integer in 1..={MAX_UPDATE_EVERY} (frames between two renders of every cascade) or an array of them, \
         one per cascade, nearest first, e.g. [1, 1, 2, 4]"
    );
    let one = |k: &toml::Value| match k.as_integer() {
        Some(k) if (1..=MAX_UPDATE_EVERY).contains(&k) => Some(k as u32),
        _ => None,
    };
    let bad = || v.invalid("shadow.update_every", x, &allowed);
    match x {
        toml::Value::Array(a) if !a.is_empty() => a
            .iter()
            .map(|k| one(k).ok_or_else(bad))
            .collect::<Result<Vec<u32>>>()
            .map(UpdateEvery::PerCascade),
        k => one(k).map(UpdateEvery::All).ok_or_else(bad),
    }
}

/// An example of `cascades − 1` valid split fractions (the logarithmic split of 0.1 to 100).
fn example_fractions(cascades: usize) -> String {
    let space = csm_core::free_splits::FractionSpace {
        lo: 0.0,
        hi: 100.0,
        start: 0.1,
    };
    let f: Vec<String> = space
        .practical(cascades, 0.75)
        .iter()
        .map(|p| csm_core::free_splits::round_significant(*p, 2).to_string())
        .collect();
    format!("[{}]", f.join(", "))
}

#[cfg(test)]
mod view_tests {
    use super::*;

    const SCENE: &str = "[camera]\nposition = [0.0, 10.0, 0.0]\ntarget = [0.0, 0.0, -50.0]\nfov_y_deg = 60.0\nnear = 0.1\nfar = 1000.0\n\
        [screen]\nwidth = 640\nheight = 360\n[light]\ndirection = [-0.4, -1.0, -0.3]\n\
        [scene]\nmin = [-200.0, 0.0, -200.0]\nmax = [200.0, 40.0, 200.0]\nworld_offset = [1000.0, 0.0, 0.0]\n";

    /// `[camera]` gives a view what it leaves out (up, field of view, and always near and
    /// far); the world offset moves a view as it moves the camera; weight defaults to 1.
    #[test]
    fn views_take_the_cameras_defaults_and_the_world_offset() {
        let text = format!(
            "{SCENE}[[view]]\nname = \"a\"\nposition = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, -10.0]\n\
             [[view]]\nname = \"b\"\nposition = [1.0, 5.0, 0.0]\ntarget = [0.0, 0.0, -10.0]\nup = [1.0, 1.0, 0.0]\nfov_y_deg = 30.0\nweight = 2.5\n"
        );
        let c = parse(&text, "t.toml", None).unwrap();
        let v = c.level_views();
        assert_eq!(v.len(), 2);
        assert_eq!((v[0].name.as_str(), v[1].name.as_str()), ("a", "b"));
        assert_eq!(v[0].camera.position, DVec3::new(1000.0, 5.0, 0.0));
        assert_eq!(v[0].camera.target, DVec3::new(1000.0, 0.0, -10.0));
        assert_eq!(
            (v[0].camera.fov_y_deg, v[0].camera.up, v[0].weight),
            (60.0, DVec3::Y, 1.0)
        );
        assert_eq!(
            (v[1].camera.fov_y_deg, v[1].camera.up, v[1].weight),
            (30.0, DVec3::new(1.0, 1.0, 0.0), 2.5)
        );
        for x in &v {
            assert_eq!((x.camera.near, x.camera.far), (0.1, 1000.0));
        }
        // Without views, [camera] is the one view.
        let c = parse(SCENE, "t.toml", None).unwrap();
        assert!(c.views.is_empty());
        assert_eq!(c.level_views()[0].camera, c.camera);
    }
}
