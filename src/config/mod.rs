//! The scene file: TOML in, a validated [`Config`] out.
//!
//! This is the only place where degrees appear: `fov_y_deg` and the rotational motion steps
//! are converted to radians here, and everything downstream works in radians. Unknown keys,
//! NaN, infinities and out-of-range values are errors that name the key, the value and what
//! is allowed; TOML syntax and type errors carry the line and column.

use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::geometry::{Aabb, CameraPose};
mod path_file;
mod with;

pub use crate::fitting::Fit;
pub use crate::motion::MotionPath;
pub use crate::precision::{Precision, SnapSpace};
use crate::presets::PresetChoice;
pub use path_file::read_path_file;

/// Largest world coordinate or distance accepted, in world units: far beyond any real world
/// (engines re-centre long before), and small enough that every derived quantity (texel
/// coordinates, squared radii) stays finite. Found necessary by the property tests: a camera
/// strafing 1e305 units per frame turned the shimmer metrics into NaN.
pub const MAX_WORLD: f64 = 1e9;

/// The camera as configured (frame 0 of the motion path).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CameraSettings {
    pub position: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view in degrees, as written in the file.
    pub fov_y_deg: f64,
    /// Near and far clip planes, world units along the view axis.
    pub near: f64,
    pub far: f64,
}

impl CameraSettings {
    /// Vertical field of view in radians.
    pub fn fov_y(&self) -> f64 {
        self.fov_y_deg.to_radians()
    }

    pub fn pose(&self) -> CameraPose {
        CameraPose::look_at(self.position, self.target, self.up)
            .expect("validated: position != target and up not parallel to the view direction")
    }
}

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Screen {
    pub width: u32,
    pub height: u32,
}

impl Screen {
    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }
}

/// Shadow settings: the knobs an engine exposes.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ShadowSettings {
    /// Shadow distance: cascades end at min(camera far, max_distance). Larger spreads the same
    /// texels over more depth (blurrier); smaller cuts shadows off sooner.
    pub max_distance: f64,
    /// Number of cascades (1..=16). More cascades lower the worst-case aliasing at the cost of
    /// memory and draw calls; returns diminish beyond about 4.
    pub cascades: usize,
    /// Practical split weight: 0 uniform (starves the near cascades), 1 logarithmic (equal worst
    /// case in every cascade, but a tiny first cascade when near is small).
    pub lambda: f64,
    /// Texels per side of each cascade's map (16..=16384). Texel size scales as 1/resolution.
    pub resolution: u32,
    pub fit: Fit,
    /// Move each window in whole texels on a world-anchored grid. Removes shimmer under camera
    /// translation (and rotation, for the sphere fit).
    pub snap: bool,
    /// Clip the split range to where the scene's bounds are visible; skips empty depth.
    pub fit_depth_to_scene: bool,
    /// Arithmetic of the cascade pipeline: exact f64, or an engine's binary32 emulated
    /// operation by operation (see [`crate::precision`]).
    pub precision: Precision,
    /// Where the binary32 pipeline computes: at absolute world coordinates, or relative to a
    /// camera-near anchor. Only matters with `precision = "f32"`.
    pub snap_space: SnapSpace,
    /// An engine's whole cascade set-up instead of csm-lab's own ([`crate::presets`]). When set,
    /// `cascades`, `resolution` and `max_distance` hold the preset's effective values, `snap`
    /// whether it snaps, `fit` the family of its fit, and `fit_depth_to_scene` is false.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<crate::presets::Preset>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct MotionSettings {
    pub path: MotionPath,
    /// Number of poses, frame 0 being the configured camera.
    pub frames: usize,
    /// World units per frame (strafe, dolly) or radians per frame (yaw, pitch, orbit).
    pub step: f64,
    /// The step as written: degrees for the rotational paths.
    pub step_as_written: f64,
}

/// How densely the sampled quantities are sampled. The closed forms do not depend on these.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AnalysisSettings {
    /// Log-spaced depths in `density.csv` (plus both sides of every split).
    pub density_samples: usize,
    /// World-fixed probe points per cascade for the shimmer metrics S3/S4.
    pub probes: usize,
}

impl Default for AnalysisSettings {
    fn default() -> Self {
        AnalysisSettings {
            density_samples: 512,
            probes: 256,
        }
    }
}

/// A validated scene and shadow setting.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// The file stem, used for the default output directory `reports/<name>/`.
    pub name: String,
    /// Where the config was read from, if from a file.
    pub path: Option<PathBuf>,
    pub camera: CameraSettings,
    pub screen: Screen,
    /// Unit direction in which light travels.
    pub light_direction: DVec3,
    /// The light direction as written (any length).
    pub light_direction_as_written: DVec3,
    /// World-space bounds of everything that casts or receives shadows.
    pub scene: Aabb,
    /// `[scene] world_offset`: already added to the camera, target, scene bounds and path-file
    /// poses above; kept for the echo.
    pub world_offset: DVec3,
    pub shadow: ShadowSettings,
    pub motion: MotionSettings,
    pub analysis: AnalysisSettings,
    /// The `[sweep]` table, if any.
    pub sweep: Option<crate::sweep::SweepSpec>,
}

// ---------------------------------------------------------------------------------------------
// Raw TOML layer
// ---------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    camera: RawCamera,
    screen: RawScreen,
    light: RawLight,
    scene: RawScene,
    #[serde(default)]
    shadow: RawShadow,
    #[serde(default)]
    motion: RawMotion,
    #[serde(default)]
    analysis: RawAnalysis,
    sweep: Option<crate::sweep::RawSweep>,
    // Engine knob tables, one per preset (see crate::presets).
    dart: Option<crate::presets::RawDart>,
    threejs: Option<crate::presets::RawThreejs>,
    #[serde(rename = "unity-sample")]
    unity_sample: Option<crate::presets::RawUnitySample>,
    eevee: Option<crate::presets::RawEevee>,
    learnopengl: Option<crate::presets::RawLearnOpenGl>,
    bevy: Option<crate::presets::RawBevy>,
    godot: Option<crate::presets::RawGodot>,
    unreal: Option<crate::presets::RawUnreal>,
    unity: Option<crate::presets::RawUnity>,
    #[serde(rename = "unity-urp")]
    unity_urp: Option<crate::presets::RawUnityUrp>,
    filament: Option<crate::presets::RawFilament>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    position: [f64; 3],
    target: [f64; 3],
    up: Option<[f64; 3]>,
    fov_y_deg: f64,
    near: f64,
    far: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScreen {
    width: i64,
    height: i64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    direction: [f64; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    min: [f64; 3],
    max: [f64; 3],
    world_offset: Option<[f64; 3]>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShadow {
    max_distance: Option<f64>,
    cascades: Option<i64>,
    lambda: Option<f64>,
    resolution: Option<i64>,
    fit: Option<Fit>,
    snap: Option<bool>,
    fit_depth_to_scene: Option<bool>,
    precision: Option<String>,
    snap_space: Option<String>,
    preset: Option<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMotion {
    path: Option<String>,
    frames: Option<i64>,
    step: Option<f64>,
    file: Option<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAnalysis {
    density_samples: Option<i64>,
    probes: Option<i64>,
}

// ---------------------------------------------------------------------------------------------
// Loading and validation
// ---------------------------------------------------------------------------------------------

/// Byte offset to 1-based (line, column), counting columns in characters.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = text[line_start..offset].chars().count() + 1;
    (line, column)
}

/// Turn a `toml` deserialisation error into one with the file's line and column.
pub fn toml_error(path: &str, text: &str, err: &toml::de::Error) -> Error {
    let (line, column) = err.span().map(|span| line_column(text, span.start)).unwrap_or((1, 1));
    Error::Toml {
        path: path.to_string(),
        line,
        column,
        message: err.message().trim().to_string(),
    }
}

/// Finds where `table.key = ...` is written, for error messages about values that parsed
/// but are out of range. Returns 1-based (line, column) of the key, if found.
pub fn locate_key(text: &str, dotted: &str) -> Option<(usize, usize)> {
    let (table, key) = match dotted.rsplit_once('.') {
        Some((t, k)) => (t, k),
        None => ("", dotted),
    };
    let mut current = String::new();
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix('[') {
            let rest = rest.trim_start_matches('[');
            if let Some(end) = rest.find(']') {
                current = rest[..end].trim().to_string();
            }
            continue;
        }
        if current != table {
            continue;
        }
        if let Some(after) = trimmed.strip_prefix(key) {
            if after.trim_start().starts_with('=') {
                let column = line.len() - trimmed.len() + 1;
                return Some((i + 1, column));
            }
        }
    }
    None
}

/// Builds "value not allowed" errors that point at the key in the file.
pub struct Validator<'a> {
    pub path: &'a str,
    pub text: &'a str,
}

impl Validator<'_> {
    pub fn invalid(&self, key: &str, value: impl std::fmt::Display, allowed: &str) -> Error {
        let location = match (self.path.is_empty(), locate_key(self.text, key)) {
            (_, Some((line, column))) if !self.path.is_empty() => {
                format!("{}:{line}:{column}: ", self.path)
            }
            (_, Some((line, column))) => format!("line {line}, column {column}: "),
            (false, None) => format!("{}: ", self.path),
            (true, None) => String::new(),
        };
        Error::Invalid {
            location,
            key: key.to_string(),
            value: value.to_string(),
            allowed: allowed.to_string(),
        }
    }

    pub fn finite(&self, key: &str, v: f64) -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(key, v, "a finite number"))
        }
    }

    pub fn vec3(&self, key: &str, v: [f64; 3]) -> Result<DVec3> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(DVec3::from_array(v))
        } else {
            Err(self.invalid(key, format!("{v:?}"), "three finite numbers"))
        }
    }

    /// Three finite numbers, none beyond [`MAX_WORLD`] in magnitude.
    pub fn point(&self, key: &str, v: [f64; 3]) -> Result<DVec3> {
        let p = self.vec3(key, v)?;
        if p.abs().max_element() <= MAX_WORLD {
            Ok(p)
        } else {
            Err(self.invalid(key, format!("{v:?}"), "three numbers within ±1e9 world units"))
        }
    }

    pub fn int_range(&self, key: &str, v: i64, lo: i64, hi: i64) -> Result<i64> {
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.invalid(key, v, &format!("an integer in {lo}..={hi}")))
        }
    }
}

impl Config {
    /// Reads and validates a config file. Relative paths inside it (the motion path file)
    /// are resolved against the file's directory.
    pub fn load(path: &Path) -> Result<Config> {
        Config::load_with_preset(path, &PresetChoice::default())
    }

    /// [`Config::load`] with the preset chosen (or overridden) as in `choice`.
    pub fn load_with_preset(path: &Path, choice: &PresetChoice) -> Result<Config> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "config".to_string());
        let mut config = Config::from_toml_str_with_preset(&text, &path.display().to_string(), path.parent(), choice)?;
        config.name = name;
        config.path = Some(path.to_path_buf());
        Ok(config)
    }

    /// Parses and validates config text. `label` names the source in messages; `base_dir`
    /// resolves a relative motion path file.
    pub fn from_toml_str(text: &str, label: &str, base_dir: Option<&Path>) -> Result<Config> {
        Config::from_toml_str_with_preset(text, label, base_dir, &PresetChoice::default())
    }

    /// [`Config::from_toml_str`] with the preset chosen (or overridden) as in `choice`.
    pub fn from_toml_str_with_preset(
        text: &str,
        label: &str,
        base_dir: Option<&Path>,
        choice: &PresetChoice,
    ) -> Result<Config> {
        let raw: RawConfig = toml::from_str(text).map_err(|e| toml_error(label, text, &e))?;
        let v = Validator { path: label, text };
        validate(raw, &v, base_dir, choice)
    }

    /// The inputs as used, for `summary.json`.
    pub fn echo(&self) -> serde_json::Value {
        let motion_step_unit = match self.motion.path {
            MotionPath::Strafe | MotionPath::Dolly => "world units per frame",
            MotionPath::File { .. } => "unused (poses from file)",
            _ => "degrees per frame",
        };
        let mut motion = serde_json::json!({
            "path": self.motion.path.name(),
            "frames": self.motion.frames,
            "step": self.motion.step_as_written,
            "step_unit": motion_step_unit,
        });
        if let MotionPath::File { path, .. } = &self.motion.path {
            motion["file"] = serde_json::Value::String(path.display().to_string());
        }
        serde_json::json!({
            "camera": self.camera,
            "screen": self.screen,
            "light": {
                "direction": self.light_direction_as_written,
                "direction_normalised": self.light_direction,
            },
            "scene": { "min": self.scene.min, "max": self.scene.max, "world_offset": self.world_offset },
            "shadow": self.shadow,
            "motion": motion,
            "analysis": self.analysis,
        })
    }

    /// Effective far end of the shadow range before scene clipping: min(far, max_distance).
    pub fn shadow_far(&self) -> f64 {
        self.camera.far.min(self.shadow.max_distance)
    }

    /// The validated settings as the core's plain domain values (radians, unit light
    /// direction, world offset already applied).
    pub fn setup(&self) -> crate::scene::Setup {
        use crate::scene::{Camera, Motion, Setup, ShadowParams};
        let s = &self.shadow;
        Setup {
            camera: Camera {
                position: self.camera.position,
                target: self.camera.target,
                up: self.camera.up,
                fov_y: self.camera.fov_y(),
                aspect: self.screen.aspect(),
                near: self.camera.near,
                far: self.camera.far,
                screen_height: self.screen.height,
            },
            light_direction: self.light_direction,
            bounds: self.scene,
            shadow: ShadowParams {
                max_distance: s.max_distance,
                cascades: s.cascades,
                lambda: s.lambda,
                resolution: s.resolution,
                fit: s.fit,
                snap: s.snap,
                fit_depth_to_scene: s.fit_depth_to_scene,
                precision: s.precision,
                snap_space: s.snap_space,
            },
            motion: Motion {
                path: self.motion.path.clone(),
                frames: self.motion.frames,
                step: self.motion.step,
            },
        }
    }

    /// Camera poses of every frame of the motion path, or the first invalid frame and why.
    pub fn camera_path(&self) -> std::result::Result<Vec<CameraPose>, (usize, String)> {
        let setup = self.setup();
        crate::motion::camera_path(&setup.camera, &setup.motion)
    }
}

fn p_display(path: &MotionPath) -> String {
    match path {
        MotionPath::File { path, .. } => path.display().to_string(),
        other => other.name().to_string(),
    }
}

fn validate(raw: RawConfig, v: &Validator<'_>, base_dir: Option<&Path>, choice: &PresetChoice) -> Result<Config> {
    // The world offset moves everything that has a position, before any other check, so the
    // rest of the crate only ever sees the moved scene.
    let world_offset = match raw.scene.world_offset {
        Some(o) => v.point("scene.world_offset", o)?,
        None => DVec3::ZERO,
    };

    let moved = |key: &str, p: [f64; 3]| -> Result<DVec3> {
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
    };

    // Camera.
    let position = moved("camera.position", raw.camera.position)?;
    let target = moved("camera.target", raw.camera.target)?;
    let up = match raw.camera.up {
        Some(u) => v.vec3("camera.up", u)?,
        None => DVec3::Y,
    };
    let view = target - position;
    if view.length() <= 1e-12 * (1.0 + position.length()) {
        return Err(v.invalid(
            "camera.target",
            format!("{:?}", raw.camera.target),
            if world_offset == DVec3::ZERO {
                "a point different from camera.position (the view direction is target - position)"
            } else {
                "a point different from camera.position once scene.world_offset is added (at this offset \
                 the two round to the same point)"
            },
        ));
    }
    if up.length() <= 1e-300 {
        return Err(v.invalid("camera.up", format!("{up:?}"), "a non-zero vector"));
    }
    if view.normalize().cross(up.normalize()).length() < 1e-9 {
        return Err(v.invalid(
            "camera.up",
            format!("{:?}", up.to_array()),
            "a vector not parallel to the view direction (target - position)",
        ));
    }
    let fov = v.finite("camera.fov_y_deg", raw.camera.fov_y_deg)?;
    // Strictly between 0 and 180, with a margin: at 1e-300 degrees tan(fov/2) underflows and
    // the pixel footprint becomes infinite.
    if !(0.001..=179.999).contains(&fov) {
        return Err(v.invalid(
            "camera.fov_y_deg",
            fov,
            "degrees strictly between 0 and 180, from 0.001 to 179.999",
        ));
    }
    let near = v.finite("camera.near", raw.camera.near)?;
    if near <= 0.0 {
        return Err(v.invalid("camera.near", near, "a number > 0"));
    }
    let far = v.finite("camera.far", raw.camera.far)?;
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

    // Screen.
    let width = v.int_range("screen.width", raw.screen.width, 1, 1 << 20)? as u32;
    let height = v.int_range("screen.height", raw.screen.height, 1, 1 << 20)? as u32;

    // Light.
    let dir_raw = v.vec3("light.direction", raw.light.direction)?;
    let len = dir_raw.length();
    if len <= 1e-12 || !len.is_finite() {
        return Err(v.invalid(
            "light.direction",
            format!("{:?}", raw.light.direction),
            "a non-zero vector (the direction light travels)",
        ));
    }
    let light_direction = dir_raw / len;

    // Scene.
    let smin = moved("scene.min", raw.scene.min)?;
    let smax = moved("scene.max", raw.scene.max)?;
    if smin.cmpgt(smax).any() {
        return Err(v.invalid(
            "scene.max",
            format!("{:?}", raw.scene.max),
            &format!(
                "each component >= scene.min {:?} (a zero thickness is allowed)",
                raw.scene.min
            ),
        ));
    }

    // Shadow.
    let s = raw.shadow;
    let written = crate::presets::Written {
        max_distance: s.max_distance.is_some(),
        cascades: s.cascades.is_some(),
        resolution: s.resolution.is_some(),
        lambda: s.lambda.is_some(),
        fit: s.fit.is_some(),
        snap: s.snap.is_some(),
        fit_depth_to_scene: s.fit_depth_to_scene.is_some(),
    };
    let max_distance = match s.max_distance {
        Some(d) => {
            let d = v.finite("shadow.max_distance", d)?;
            if d <= 0.0 {
                return Err(v.invalid("shadow.max_distance", d, "a number > 0"));
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
    let mut shadow = ShadowSettings {
        max_distance,
        cascades,
        lambda,
        resolution,
        fit: s.fit.unwrap_or(Fit::Sphere),
        snap: s.snap.unwrap_or(true),
        fit_depth_to_scene: s.fit_depth_to_scene.unwrap_or(true),
        precision,
        snap_space,
        preset: None,
    };
    let camera = CameraSettings {
        position,
        target,
        up,
        fov_y_deg: fov,
        near,
        far,
    };
    let scene = Aabb::new(smin, smax);
    let tables = crate::presets::RawTables {
        dart: raw.dart,
        threejs: raw.threejs,
        unity_sample: raw.unity_sample,
        eevee: raw.eevee,
        learnopengl: raw.learnopengl,
        bevy: raw.bevy,
        godot: raw.godot,
        unreal: raw.unreal,
        unity: raw.unity,
        unity_urp: raw.unity_urp,
        filament: raw.filament,
    };
    let cx = crate::presets::ResolveContext {
        choice,
        file_preset: s.preset,
        written,
        tables,
        camera: &camera,
        light_direction,
        scene: &scene,
    };
    crate::presets::resolve(cx, &mut shadow, v)?;
    // Motion.
    let m = raw.motion;
    let frames = v.int_range("motion.frames", m.frames.unwrap_or(240), 2, 1_000_000)? as usize;
    let step_as_written = v.finite("motion.step", m.step.unwrap_or(0.05))?;
    let path_name = m.path.unwrap_or_else(|| "strafe".to_string());
    let (path, step) = match path_name.as_str() {
        "strafe" => (MotionPath::Strafe, step_as_written),
        "dolly" => (MotionPath::Dolly, step_as_written),
        "yaw" => (MotionPath::Yaw, step_as_written.to_radians()),
        "pitch" => (MotionPath::Pitch, step_as_written.to_radians()),
        "orbit" => (MotionPath::Orbit, step_as_written.to_radians()),
        "file" => {
            let file = m.file.ok_or_else(|| {
                v.invalid(
                    "motion.file",
                    "(missing)",
                    "a CSV file with columns px,py,pz,tx,ty,tz when motion.path = \"file\"",
                )
            })?;
            let p = PathBuf::from(&file);
            let p = match base_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p,
            };
            let poses = read_path_file(&p)?
                .into_iter()
                .map(|(position, target)| (position + world_offset, target + world_offset))
                .collect();
            (MotionPath::File { path: p, poses }, 0.0)
        }
        other => {
            return Err(v.invalid(
                "motion.path",
                format!("{other:?}"),
                "one of \"strafe\", \"dolly\", \"yaw\", \"pitch\", \"orbit\", \"file\"",
            ))
        }
    };
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

    let a = raw.analysis;
    let analysis = AnalysisSettings {
        density_samples: v.int_range(
            "analysis.density_samples",
            a.density_samples.unwrap_or(512),
            2,
            1_000_000,
        )? as usize,
        probes: v.int_range("analysis.probes", a.probes.unwrap_or(256), 1, 1_000_000)? as usize,
    };

    let sweep = raw.sweep.map(|s| crate::sweep::validate_raw(s, v)).transpose()?;

    let config = Config {
        name: "config".to_string(),
        path: None,
        camera,
        screen: Screen { width, height },
        light_direction,
        light_direction_as_written: dir_raw,
        scene,
        world_offset,
        shadow,
        motion: MotionSettings {
            path,
            frames,
            step,
            step_as_written,
        },
        analysis,
        sweep,
    };
    cross_checks(&config, v)?;
    Ok(config)
}

/// The checks that involve several settings at once, run when a file is read and again by
/// every constructor that changes a validated config ([`Config::with_lambda`] and friends).
fn cross_checks(config: &Config, v: &Validator<'_>) -> Result<()> {
    // Every pose of the motion path must be a valid camera (pitching through the up vector,
    // or a path file row with position == target, is a config error, not a panic later).
    config.camera_path().map_err(|(frame, why)| {
        v.invalid(
            if matches!(config.motion.path, MotionPath::File { .. }) {
                "motion.file"
            } else {
                "motion.step"
            },
            format!("{} (frame {frame})", config.motion.step_as_written),
            &format!("a motion that keeps a valid camera in every frame: {why}"),
        )
    })?;
    // binary32 must be able to hold every texel coordinate the emulated pipeline computes.
    if config.shadow.precision == Precision::F32 {
        if let Some(why) = crate::analysis::f32_range_problem(config) {
            return Err(v.invalid("shadow.precision", "\"f32\"", &why));
        }
    }
    Ok(())
}
