//! `[views]`: the level's views taken from the glTF's camera nodes (`from_gltf`), a recorded
//! path (`from_path`, `every`) or player positions sampled on walkable surfaces (`sample`,
//! `seed`, `eye_height`, `max_slope_deg`, `pitch_deg`), appended to `Config::views` after any
//! `[[view]]` entries; and the checks every view of the level gets ([`check_views`]). The math
//! (sampling, the inside test, the receiver check) is the core's `viewpoints`.

use std::path::{Path, PathBuf};

use glam::DVec3;

use csm_core::viewpoints;

use super::schema::RawViews;
use super::*;
use crate::error::Result;

/// Default `[views]` values: eye height (world units), slope limit and pitch range (degrees).
pub(crate) const DEFAULT_EYE_HEIGHT: f64 = 1.7;
pub(crate) const DEFAULT_MAX_SLOPE_DEG: f64 = 35.0;
pub(crate) const DEFAULT_PITCH_DEG: [f64; 2] = [-10.0, 10.0];
/// Most views one source may give (and `views.sample` at most).
pub(crate) const MAX_VIEWS: usize = 10_000;
/// Candidate points drawn per sampled view at most.
const TRIES_PER_VIEW: usize = 200;

/// A view looking from `position` along unit `forward` (its target one world unit ahead), with
/// `up`, the given field of view and `[camera]`'s near and far planes.
fn view_camera(camera: &CameraSettings, position: DVec3, forward: DVec3, up: DVec3, fov_y_deg: f64) -> CameraSettings {
    CameraSettings {
        position,
        target: position + forward,
        up,
        fov_y_deg,
        near: camera.near,
        far: camera.far,
    }
}

/// `name`, or `name_2`, `name_3`, ... when it is taken.
fn unique(name: &str, taken: &[ViewSettings]) -> String {
    let used = |n: &str| taken.iter().any(|v| v.name == n);
    if !used(name) {
        return name.to_string();
    }
    (2..)
        .map(|k| format!("{name}_{k}"))
        .find(|n| !used(n))
        .expect("an unused suffix exists")
}

/// Where each view of `config.views` came from: `(end, key)` in order, each source's views
/// ending before index `end` (the `[[view]]` entries first, then `views.from_gltf`,
/// `views.from_path`, `views.sample`), so an error about a view names the key that made it.
pub(crate) type ViewKeys = Vec<(usize, &'static str)>;

/// Appends the views `[views]` names to `config.views`, in the order glTF cameras, path poses,
/// sampled positions, and says which key made which ([`ViewKeys`]). `gltf` is what
/// `scene.gltf` held (None without one).
pub(crate) fn add_views(
    config: &mut Config,
    raw: Option<&RawViews>,
    v: &Validator<'_>,
    base_dir: Option<&Path>,
    gltf: Option<&GltfScene>,
) -> Result<ViewKeys> {
    let mut keys = vec![(config.views.len(), "view")];
    let Some(raw) = raw else {
        return Ok(keys);
    };
    if raw.from_gltf == Some(true) {
        let (views, warnings) = gltf_views(config, v, gltf)?;
        std::sync::Arc::make_mut(&mut config.views).extend(views);
        config.warnings.extend(warnings);
        keys.push((config.views.len(), "views.from_gltf"));
    }
    let path_keys_alone = raw.from_path.is_none() && raw.every.is_some();
    if path_keys_alone {
        return Err(v.invalid(
            "views.every",
            raw.every.unwrap_or_default(),
            "views.every only together with views.from_path",
        ));
    }
    if let Some(from) = &raw.from_path {
        let views = path_views(config, v, base_dir, from, raw.every)?;
        std::sync::Arc::make_mut(&mut config.views).extend(views);
        keys.push((config.views.len(), "views.from_path"));
    }
    sampled_views(config, v, raw)?;
    keys.push((config.views.len(), "views.sample"));
    Ok(keys)
}

/// The key an error about view `k` names: `camera.position` for `[camera]` (no view
/// configured), `view[k].position` for a `[[view]]` entry, else the `[views]` key that made it.
fn view_key(k: usize, configured: bool, keys: &[(usize, &'static str)]) -> String {
    if !configured {
        return "camera.position".to_string();
    }
    match keys.iter().find(|(end, _)| k < *end).map(|x| x.1) {
        Some("view") => format!("view[{k}].position"),
        Some(key) => key.to_string(),
        None => "views".to_string(),
    }
}

/// `views.from_gltf = true`: one view per perspective camera node, named by its node; and a
/// warning for each camera whose aspect ratio is not the screen's (the screen's is used, the
/// vertical field of view kept).
fn gltf_views(
    config: &Config,
    v: &Validator<'_>,
    gltf: Option<&GltfScene>,
) -> Result<(Vec<ViewSettings>, Vec<String>)> {
    let Some(g) = gltf else {
        return Err(v.invalid(
            "views.from_gltf",
            true,
            "true only with scene.gltf (the cameras are read from its nodes)",
        ));
    };
    if g.cameras.is_empty() {
        let ortho = if g.orthographic_cameras > 0 {
            format!(
                " ({} orthographic camera{} left out: a player view is perspective)",
                g.orthographic_cameras,
                if g.orthographic_cameras == 1 { "" } else { "s" }
            )
        } else {
            String::new()
        };
        return Err(v.invalid(
            "views.from_gltf",
            true,
            &format!(
                "true only when scene.gltf has a perspective camera node in its default scene; {} has none{ortho}",
                config
                    .geometry
                    .as_ref()
                    .and_then(|g| g.gltf.as_ref())
                    .map_or_else(|| "the file".to_string(), |p| p.display().to_string())
            ),
        ));
    }
    let mut out: Vec<ViewSettings> = config.views.to_vec();
    let first = out.len();
    let mut warnings = Vec::new();
    for cam in &g.cameras {
        let label = cam.name.clone().unwrap_or_else(|| format!("camera_node_{}", cam.node));
        let bad = |why: &str| {
            v.invalid(
                "views.from_gltf",
                format!("camera node {label:?} (node {})", cam.node),
                &format!("camera nodes that give a valid view: {why}"),
            )
        };
        let fov = cam.yfov.to_degrees();
        if !(0.001..=179.999).contains(&fov) {
            return Err(bad(&format!(
                "its yfov is {} rad ({fov} degrees); a field of view strictly between 0 and 180 degrees",
                cam.yfov
            )));
        }
        let position = cam.position + config.world_offset;
        if position.abs().max_element() > MAX_WORLD {
            return Err(bad("a position within ±1e9 world units (after scene.world_offset)"));
        }
        if cam.forward.cross(cam.up).length() < 1e-9 {
            return Err(bad(
                "its −Z and +Y axes are parallel in world space (a degenerate transform)",
            ));
        }
        let name = unique(&label, &out);
        let screen = config.screen.aspect();
        if let Some(a) = cam.aspect.filter(|a| (a / screen - 1.0).abs() > 0.01) {
            warnings.push(format!(
                "view {name:?}: the glTF camera's aspect ratio {} is not the screen's {} ({} x {}); the screen's is                  used and the camera's vertical field of view kept",
                crate::output::short_number(a),
                crate::output::short_number(screen),
                config.screen.width,
                config.screen.height
            ));
        }
        out.push(ViewSettings {
            name,
            camera: view_camera(&config.camera, position, cam.forward, cam.up, fov),
            weight: 1.0,
        });
    }
    Ok((out.split_off(first), warnings))
}

/// `views.from_path`: every k-th pose of a path file, or of the configured motion path (`true`).
fn path_views(
    config: &Config,
    v: &Validator<'_>,
    base_dir: Option<&Path>,
    from: &toml::Value,
    every: Option<i64>,
) -> Result<Vec<ViewSettings>> {
    let every = match every {
        Some(k) => v.int_range("views.every", k, 1, 1_000_000)? as usize,
        None => 1,
    };
    let poses: Vec<(DVec3, DVec3)> = match from {
        toml::Value::Boolean(false) => return Ok(Vec::new()),
        toml::Value::Boolean(true) => config
            .camera_path()
            .map_err(|(frame, why)| v.invalid("views.from_path", format!("true (frame {frame})"), &why))?
            .iter()
            .map(|p| (p.position, p.position + p.forward))
            .collect(),
        toml::Value::String(name) => {
            let p = PathBuf::from(name);
            let p = match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p,
            };
            read_path_rows(&p, v, name)?
                .into_iter()
                .map(|(pos, target)| (pos + config.world_offset, target + config.world_offset))
                .collect()
        }
        other => {
            return Err(v.invalid(
                "views.from_path",
                other.to_string(),
                "a path file (\"poses.csv\", columns px,py,pz,tx,ty,tz) or true (the configured motion path)",
            ))
        }
    };
    let picked: Vec<(usize, (DVec3, DVec3))> = poses.into_iter().enumerate().step_by(every).collect();
    if picked.len() > MAX_VIEWS {
        return Err(v.invalid(
            "views.every",
            every,
            &format!(
                "a step that keeps at most {MAX_VIEWS} views ({} poses give {})",
                picked.len() * every,
                picked.len()
            ),
        ));
    }
    let mut out: Vec<ViewSettings> = config.views.to_vec();
    let first = out.len();
    for (frame, (position, target)) in picked {
        if position.abs().max(target.abs()).max_element() > MAX_WORLD {
            return Err(v.invalid(
                "views.from_path",
                format!("pose {frame}"),
                "positions and targets within ±1e9 world units",
            ));
        }
        let camera = CameraSettings {
            position,
            target,
            up: config.camera.up,
            fov_y_deg: config.camera.fov_y_deg,
            near: config.camera.near,
            far: config.camera.far,
        };
        if CameraPose::look_at(position, target, camera.up).is_none() {
            return Err(v.invalid(
                "views.from_path",
                format!(
                    "pose {frame} (position {:?}, target {:?})",
                    position.to_array(),
                    target.to_array()
                ),
                "poses whose target differs from the position and whose view is not parallel to camera.up",
            ));
        }
        let name = unique(&format!("path_{frame:06}"), &out);
        out.push(ViewSettings {
            name,
            camera,
            weight: 1.0,
        });
    }
    Ok(out.split_off(first))
}

/// A path file's rows; at least one (the motion path's two-row minimum does not apply to views).
fn read_path_rows(path: &Path, v: &Validator<'_>, written: &str) -> Result<Vec<(DVec3, DVec3)>> {
    match super::path_file::read_path_rows(path) {
        Ok(rows) if rows.is_empty() => Err(v.invalid(
            "views.from_path",
            format!("{written:?}"),
            &format!(
                "a path file with at least one pose row; {} has a header and no rows",
                path.display()
            ),
        )),
        other => other,
    }
}

/// `views.sample = N` (with `seed`, `eye_height`, `max_slope_deg`, `pitch_deg`): N player views.
fn sampled_views(config: &mut Config, v: &Validator<'_>, raw: &RawViews) -> Result<()> {
    let Some(n) = raw.sample else {
        for (key, set) in [
            ("views.seed", raw.seed.is_some()),
            ("views.eye_height", raw.eye_height.is_some()),
            ("views.max_slope_deg", raw.max_slope_deg.is_some()),
            ("views.pitch_deg", raw.pitch_deg.is_some()),
        ] {
            if set {
                return Err(v.invalid(key, "(set)", &format!("{key} only together with views.sample")));
            }
        }
        return Ok(());
    };
    let count = v.int_range("views.sample", n, 1, MAX_VIEWS as i64)? as usize;
    let Some(geometry) = &config.geometry else {
        return Err(v.invalid(
            "views.sample",
            n,
            "a count only with scene geometry (scene.ground, [[scene.box]] or scene.gltf): players stand on its surfaces",
        ));
    };
    let seed = match raw.seed {
        Some(s) if s < 0 => return Err(v.invalid("views.seed", s, "a whole number >= 0")),
        Some(s) => s as u64,
        None => 1,
    };
    let eye_height = v.finite("views.eye_height", raw.eye_height.unwrap_or(DEFAULT_EYE_HEIGHT))?;
    if !(eye_height > 0.0 && eye_height <= 1e4) {
        return Err(v.invalid(
            "views.eye_height",
            eye_height,
            "a height > 0 and at most 1e4 world units",
        ));
    }
    let slope = v.finite(
        "views.max_slope_deg",
        raw.max_slope_deg.unwrap_or(DEFAULT_MAX_SLOPE_DEG),
    )?;
    if !(0.0..=89.0).contains(&slope) {
        return Err(v.invalid("views.max_slope_deg", slope, "degrees from 0 (flat only) to 89"));
    }
    let pitch = match &raw.pitch_deg {
        None => DEFAULT_PITCH_DEG,
        Some(p) => {
            let ok = p.len() == 2 && p.iter().all(|x| x.is_finite() && x.abs() <= 80.0) && p[0] <= p[1];
            if !ok {
                return Err(v.invalid(
                    "views.pitch_deg",
                    format!("{p:?}"),
                    "[lo, hi]: two degrees from -80 to 80 with lo <= hi (positive looks up)",
                ));
            }
            [p[0], p[1]]
        }
    };
    let spec = viewpoints::SampleSpec {
        count,
        seed,
        eye_height,
        max_slope: slope.to_radians(),
        pitch: (pitch[0].to_radians(), pitch[1].to_radians()),
        max_tries: count * TRIES_PER_VIEW,
    };
    let found = viewpoints::sample_positions(&geometry.scene, &config.scene, &spec);
    if found.len() < count {
        return Err(v.invalid(
            "views.sample",
            count,
            &format!(
                "a count the scene has room for: {} candidate points over the scene's x/z extent gave {} walkable \
                 position{} (surfaces at most {slope}° steep with {eye_height} world units clear above, not inside \
                 geometry); lower views.sample, raise views.max_slope_deg or lower views.eye_height",
                spec.max_tries,
                found.len(),
                if found.len() == 1 { "" } else { "s" }
            ),
        ));
    }
    let width = count.saturating_sub(1).to_string().len().max(3);
    for (k, s) in found.into_iter().enumerate() {
        let name = unique(&format!("sample_{k:0width$}"), &config.views);
        let camera = view_camera(&config.camera, s.eye, s.forward, DVec3::Y, config.camera.fov_y_deg);
        std::sync::Arc::make_mut(&mut config.views).push(ViewSettings {
            name,
            camera,
            weight: 1.0,
        });
    }
    Ok(())
}

/// `light.from_gltf = true`: the first directional light of `scene.gltf`, as (unit direction,
/// the direction as read).
pub(crate) fn gltf_light(v: &Validator<'_>, gltf: Option<&GltfScene>) -> Result<DVec3> {
    let Some(g) = gltf else {
        return Err(v.invalid(
            "light.from_gltf",
            true,
            "true only with scene.gltf (the light is read from its KHR_lights_punctual directional light)",
        ));
    };
    g.directional_lights.first().map(|l| l.direction).ok_or_else(|| {
        v.invalid(
            "light.from_gltf",
            true,
            "true only when scene.gltf has a node with a KHR_lights_punctual directional light in its default scene",
        )
    })
}

/// The checks every view of the level gets (`[camera]` when no view is configured): a view
/// inside geometry is an error naming it; a view that sees no receiver adds a warning to
/// `config.warnings`. Without geometry there is nothing to check.
pub(crate) fn check_views(config: &mut Config, v: &Validator<'_>, keys: &[(usize, &'static str)]) -> Result<()> {
    let Some(geometry) = &config.geometry else {
        return Ok(());
    };
    let scene = &geometry.scene;
    let views = config.level_views();
    let configured = !config.views.is_empty();
    let mesh = scene.mesh.bounds().unwrap_or(config.scene);
    let reach = viewpoints::reach(&Aabb::new(
        config.scene.min.min(mesh.min),
        config.scene.max.max(mesh.max),
    ));
    let mut warnings = Vec::new();
    for (k, view) in views.iter().enumerate() {
        let c = &view.camera;
        let e = viewpoints::enclosure(scene, c.position, reach);
        if e.inside() {
            let why = if e.close > 13 {
                format!(
                    "a surface lies within {} world units in {} of 26 directions",
                    viewpoints::CLOSE,
                    e.close
                )
            } else {
                format!(
                    "it is enclosed: rays cross the surfaces an odd number of times in {} of 8 sideways and {} of 9 \
                     upward directions",
                    e.odd_horizontal, e.odd_up
                )
            };
            return Err(v.invalid(
                &view_key(k, configured, keys),
                format!("view {:?} at {:?}", view.name, c.position.to_array()),
                &format!("views that do not stand inside geometry; this one does ({why})"),
            ));
        }
        let Some(pose) = CameraPose::look_at(c.position, c.target, c.up) else {
            continue;
        };
        let cam = viewpoints::ViewCamera {
            pose,
            lens: csm_core::geometry::Lens::new(c.fov_y(), config.screen.aspect()),
            near: c.near,
            far: c.far,
        };
        if !viewpoints::sees_receiver(scene, &cam, config.light_direction) {
            let (cols, rows) = viewpoints::RECEIVER_GRID;
            warnings.push(format!(
                "view {:?} sees no receiver: none of a {cols} x {rows} grid of rays over its screen meets a surface \
                 facing the light between near and far (it looks at the sky, or at shadowed sides only)",
                view.name
            ));
        }
    }
    config.warnings.extend(warnings);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A glTF with a rotated and translated parent node, a camera child with its own rotation
    /// and translation, a directional light on another rotated node, and a triangle.
    fn write_gltf(dir: &Path, with_camera: bool) -> PathBuf {
        // Parent: translate (10, 2, -5), rotate 90° about +Y (quaternion [0, sin45, 0, cos45]).
        // Child camera: translate (0, 0, 4) in the parent's frame, pitched 30° down about +X
        // (quaternion [sin(-15°), 0, 0, cos(-15°)]).
        let (s45, c45) = (std::f64::consts::FRAC_PI_4.sin(), std::f64::consts::FRAC_PI_4.cos());
        let h = (-15f64).to_radians();
        let camera = if with_camera {
            format!(
                r#",{{"name":"gate","translation":[0,0,4],"rotation":[{},0,0,{}],"camera":0}},
                   {{"name":"gate","translation":[1,0,0],"camera":0}}"#,
                h.sin(),
                h.cos()
            )
        } else {
            String::new()
        };
        let children = if with_camera { "[1,2]" } else { "[]" };
        // A triangle (3 vertices, float VEC3), as base64 of 36 bytes.
        let verts: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let bytes: Vec<u8> = verts.iter().flat_map(|f| f.to_le_bytes()).collect();
        let b64 = base64(&bytes);
        let light_node = if with_camera { 3 } else { 1 };
        let text = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,{light_node},{mesh_node}]}}],
            "extensionsUsed":["KHR_lights_punctual"],
            "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point"}},{{"type":"directional"}}]}}}},
            "nodes":[{{"name":"rig","translation":[10,2,-5],"rotation":[0,{s45},0,{c45}],"children":{children}}}{camera},
              {{"name":"sun","rotation":[{lx},0,0,{lw}],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}},
              {{"mesh":0}}],
            "cameras":[{{"type":"perspective","perspective":{{"yfov":0.8,"aspectRatio":1.5,"znear":0.1}}}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#,
            mesh_node = light_node + 1,
            // The sun: rotated -60° about +X, so its -Z points down and forward.
            lx = (-30f64).to_radians().sin(),
            lw = (-30f64).to_radians().cos(),
        );
        let p = dir.join("scene.gltf");
        std::fs::write(&p, text).unwrap();
        p
    }

    fn base64(bytes: &[u8]) -> String {
        const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for c in bytes.chunks(3) {
            let n = (u32::from(c[0]) << 16)
                | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
                | u32::from(*c.get(2).unwrap_or(&0));
            for i in 0..4 {
                if i <= c.len() {
                    out.push(A[((n >> (18 - 6 * i)) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    fn config(dir: &Path, extra: &str) -> Result<Config> {
        let text = format!(
            "[camera]\nposition = [0, 5, 30]\ntarget = [0, 0, 0]\nfov_y_deg = 60\nnear = 0.1\nfar = 300\n\
             [screen]\nwidth = 320\nheight = 180\n[scene]\ngltf = \"scene.gltf\"\nground = 0\nmin = [-50, -1, -50]\nmax = [50, 20, 50]\n{extra}"
        );
        crate::config::parse(&text, "test.toml", Some(dir))
    }

    #[test]
    fn gltf_camera_nodes_read_back_with_their_parents_transform() {
        let dir = tempfile::tempdir().unwrap();
        write_gltf(dir.path(), true);
        let c = config(dir.path(), "[light]\nfrom_gltf = true\n[views]\nfrom_gltf = true\n").unwrap();
        assert_eq!(c.views.len(), 2);
        // By hand: the parent rotates 90° about +Y, which takes local +Z to world +X, local -Z
        // to world -X, local +X to world -Z. The camera sits at parent + R (0, 0, 4) =
        // (10, 2, -5) + (4, 0, 0) = (14, 2, -5). Its own pitch of -30° about +X turns its -Z
        // into (0, -sin30, -cos30) in the parent's frame: in world, (-cos30, -sin30, 0).
        let gate = &c.views[0];
        assert_eq!(gate.name, "gate");
        let (s30, c30) = (0.5, 3f64.sqrt() / 2.0);
        let close = |a: DVec3, b: DVec3| (a - b).length() < 1e-6;
        assert!(
            close(gate.camera.position, DVec3::new(14.0, 2.0, -5.0)),
            "{:?}",
            gate.camera.position
        );
        let forward = (gate.camera.target - gate.camera.position).normalize();
        assert!(close(forward, DVec3::new(-c30, -s30, 0.0)), "{forward:?}");
        // Its up: local +Y pitched by -30° about +X is (0, cos30, -sin30), in world (-sin30, cos30, 0).
        assert!(
            close(gate.camera.up, DVec3::new(-s30, c30, 0.0)),
            "{:?}",
            gate.camera.up
        );
        assert!((gate.camera.fov_y_deg - 0.8f64.to_degrees()).abs() < 1e-5);
        // `[camera]`'s planes.
        assert_eq!((gate.camera.near, gate.camera.far), (0.1, 300.0));
        // The second node has the same name: made unique. It sits at parent + R (1, 0, 0) =
        // (10, 2, -6) and looks along R (0, 0, -1) = (-1, 0, 0).
        let second = &c.views[1];
        assert_eq!(second.name, "gate_2");
        assert!(close(second.camera.position, DVec3::new(10.0, 2.0, -6.0)));
        assert!(close(
            (second.camera.target - second.camera.position).normalize(),
            DVec3::NEG_X
        ));
        // The light: its node rotated -60° about +X turns -Z into (0, -sin60, -cos60).
        assert!(
            close(c.light_direction, DVec3::new(0.0, -c30, -s30)),
            "{:?}",
            c.light_direction
        );
    }

    #[test]
    fn a_gltf_without_cameras_or_a_light_is_an_error_naming_the_key() {
        let dir = tempfile::tempdir().unwrap();
        write_gltf(dir.path(), false);
        let e = config(
            dir.path(),
            "[light]\ndirection = [0, -1, 0]\n[views]\nfrom_gltf = true\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("views.from_gltf") && e.contains("perspective camera node"),
            "{e}"
        );
        // This file has a directional light, so light.from_gltf reads it without error.
        assert!(config(dir.path(), "[light]\nfrom_gltf = true\n").is_ok());
        let e = config(dir.path(), "[light]\ndirection = [0, -1, 0]\nfrom_gltf = true\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("light.from_gltf"), "{e}");
    }

    #[test]
    fn path_views_take_every_kth_pose_and_an_empty_file_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        write_gltf(dir.path(), false);
        let mut csv = String::from("px,py,pz,tx,ty,tz\n");
        for i in 0..7 {
            csv.push_str(&format!("{i},1.7,10,{i},1.7,0\n"));
        }
        std::fs::write(dir.path().join("walk.csv"), csv).unwrap();
        let c = config(
            dir.path(),
            "[light]\ndirection = [0.3, -1, 0.2]\n[views]\nfrom_path = \"walk.csv\"\nevery = 3\n",
        )
        .unwrap();
        let names: Vec<&str> = c.views.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names, ["path_000000", "path_000003", "path_000006"]);
        assert_eq!(c.views[1].camera.position, DVec3::new(3.0, 1.7, 10.0));
        assert_eq!(c.views[1].camera.target, DVec3::new(3.0, 1.7, 0.0));
        std::fs::write(dir.path().join("empty.csv"), "px,py,pz,tx,ty,tz\n").unwrap();
        let e = config(
            dir.path(),
            "[light]\ndirection = [0.3, -1, 0.2]\n[views]\nfrom_path = \"empty.csv\"\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("views.from_path") && e.contains("no rows"), "{e}");
        // `true`: the configured motion path, here 4 frames of a strafe 0.5 apart.
        let c = config(
            dir.path(),
            "[light]\ndirection = [0.3, -1, 0.2]\n[motion]\npath = \"strafe\"\nframes = 4\nstep = 0.5\n[views]\nfrom_path = true\nevery = 2\n",
        )
        .unwrap();
        let expected = c.camera_path().unwrap();
        assert_eq!(c.views.len(), 2);
        assert_eq!(c.views[1].camera.position, expected[2].position);
    }

    #[test]
    fn sampled_views_follow_the_seed_and_a_view_inside_a_box_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        write_gltf(dir.path(), false);
        let box_ = "[[scene.box]]\nmin = [-5, 0, -5]\nmax = [5, 4, 5]\n";
        let sampled = |seed: u32| {
            config(
                dir.path(),
                &format!("{box_}[light]\ndirection = [0.3, -1, 0.2]\n[views]\nsample = 12\nseed = {seed}\n"),
            )
            .unwrap()
            .views
        };
        let a = sampled(3);
        assert_eq!(a.len(), 12);
        assert_eq!(a, sampled(3));
        assert_ne!(a, sampled(4));
        assert_eq!(a[0].name, "sample_000");
        let b = Aabb::new(DVec3::new(-5.0, 0.0, -5.0), DVec3::new(5.0, 4.0, 5.0));
        for v in a.iter() {
            let p = v.camera.position;
            assert!(
                !(p.cmpgt(b.min).all() && p.cmplt(b.max).all()),
                "{} inside the box",
                v.name
            );
        }
        // The configured camera inside the box: an error naming it.
        let text = format!(
            "[camera]\nposition = [0, 2, 0]\ntarget = [0, 0, -10]\nfov_y_deg = 60\nnear = 0.1\nfar = 300\n\
             [screen]\nwidth = 320\nheight = 180\n[light]\ndirection = [0.3, -1, 0.2]\n[scene]\nground = 0\n\
             min = [-50, -1, -50]\nmax = [50, 20, 50]\n{box_}"
        );
        let e = crate::config::parse(&text, "t.toml", None).unwrap_err().to_string();
        assert!(
            e.contains("camera.position") && e.contains("\"camera\"") && e.contains("inside geometry"),
            "{e}"
        );
        // Looking straight up from the ground: a warning with the view's name, not an error.
        let text = text
            .replace("position = [0, 2, 0]", "position = [20, 2, 20]")
            .replace("target = [0, 0, -10]", "target = [20.1, 50, 20]");
        let c = crate::config::parse(&text, "t.toml", None).unwrap();
        assert_eq!(c.warnings.len(), 1);
        assert!(
            c.warnings[0].contains("view \"camera\" sees no receiver"),
            "{:?}",
            c.warnings
        );
    }
}
