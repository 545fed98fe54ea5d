//! The scene file: TOML in, a validated [`Config`] out.
//!
//! Parts: `schema` (the raw TOML structs), `location` (line and column of keys, the
//! [`Validator`] that builds errors naming them) and `validate` (the checks). This is the only
//! place where degrees appear: `fov_y_deg` and the rotational motion steps become radians here.
//! An engine preset is applied afterwards by [`crate::presets`]; this module only carries the
//! result in [`ShadowSettings::preset`].

mod gltf_file;
mod light_motion;
pub(crate) use light_motion::{light_update_label, parse_light_update_list};
mod location;
mod path_file;
mod schema;
mod view_sources;
/// Exactly three numbers (a fourth is an error) for `[x, y, z]` keys of preset tables too.
pub(crate) use schema::opt_vec3;
pub mod sweep_spec;
mod validate;

pub(crate) use location::{excerpt, locate};
pub(crate) use location::{locate_key, locate_table, toml_error, Validator};
pub(crate) use schema::SECTIONS;
pub(crate) use validate::check_camera_path;
pub use validate::parse;

use std::any::Any;
use std::path::PathBuf;
use std::sync::Arc;

use glam::DVec3;

use csm_core::geometry::{Aabb, CameraPose};
pub use csm_core::scene::{ShadowParams, SplitRange};

pub use csm_core::fitting::Fit;
pub use csm_core::scene::MotionPath;
pub use csm_core::scene::{Precision, SnapSpace};
pub use gltf_file::{read_gltf, read_gltf_primitives};
pub(crate) use gltf_file::{read_gltf_scene, GltfScene};
pub use path_file::read_path_file;

/// Largest world coordinate or distance accepted, in world units: far beyond any real world
/// (engines re-centre long before), and small enough that every derived quantity (texel
/// coordinates, squared radii) stays finite. Found necessary by the property tests: a camera
/// strafing 1e305 units per frame turned the shimmer metrics into NaN.
pub(crate) const MAX_WORLD: f64 = 1e9;

/// A config or thresholds file larger than this is refused before it is read.
pub(crate) const MAX_TEXT_FILE_BYTES: u64 = 4 << 20;

/// Opens `path` for reading if it is a regular file of at most `max` bytes (checked before a
/// byte is read: `/dev/zero` or a 50 MB file fails at once, naming the file and the limit).
/// Reads through a `take(max + 1)` as well, in case the file grows or is not regular.
pub(crate) fn open_bounded(
    path: &std::path::Path,
    max: u64,
    what: &'static str,
) -> crate::Result<std::io::Take<std::fs::File>> {
    use std::io::Read;
    // Checked before opening: opening a FIFO blocks until someone writes to it.
    regular_file(path)?;
    let file = std::fs::File::open(path).map_err(|e| crate::Error::read(path, e))?;
    let meta = file.metadata().map_err(|e| crate::Error::read(path, e))?;
    let too_large = |size: u64| -> crate::Error {
        crate::error::IoError::TooLarge {
            path: path.to_path_buf(),
            what,
            size,
            max,
        }
        .into()
    };
    if !meta.is_file() {
        return Err(not_regular(path));
    }
    if meta.len() > max {
        return Err(too_large(meta.len()));
    }
    Ok(file.take(max + 1))
}

fn not_regular(path: &std::path::Path) -> crate::Error {
    crate::Error::read(
        path,
        std::io::Error::other("not a regular file (a FIFO, device or directory is not read)"),
    )
}

/// Refuses `path` unless it is a regular file (after following symbolic links), without
/// opening it.
pub(crate) fn regular_file(path: &std::path::Path) -> crate::Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| crate::Error::read(path, e))?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(not_regular(path))
    }
}

/// At most the first 200 characters of `text` for an error message, with the full length when
/// cut: a path file whose first line is 500 MB long is not echoed whole.
pub(crate) fn clip_quote(text: &str) -> String {
    match text.char_indices().nth(200) {
        Some((at, _)) => format!("{}... ({} characters in all)", &text[..at], text.chars().count()),
        None => text.to_string(),
    }
}

/// The bytes of a regular file of at most `max` bytes (see [`open_bounded`]).
pub(crate) fn read_bytes_bounded(path: &std::path::Path, max: u64, what: &'static str) -> crate::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    open_bounded(path, max, what)?
        .read_to_end(&mut bytes)
        .map_err(|e| crate::Error::read(path, e))?;
    if bytes.len() as u64 > max {
        return Err(crate::error::IoError::TooLarge {
            path: path.to_path_buf(),
            what,
            size: bytes.len() as u64,
            max,
        }
        .into());
    }
    Ok(bytes)
}

/// The whole text of a file of at most `max` bytes (see [`open_bounded`]).
pub(crate) fn read_bounded(path: &std::path::Path, max: u64, what: &'static str) -> crate::Result<String> {
    use std::io::Read;
    let mut text = String::new();
    open_bounded(path, max, what)?
        .read_to_string(&mut text)
        .map_err(|e| crate::Error::read(path, e))?;
    if text.len() as u64 > max {
        return Err(crate::error::IoError::TooLarge {
            path: path.to_path_buf(),
            what,
            size: text.len() as u64,
            max,
        }
        .into());
    }
    Ok(text)
}

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

/// One named camera view of the level: `[[view]]`, a glTF camera node, a pose of a recorded
/// path or a sampled player position. Every view shares `[camera]`'s near and far planes and
/// the screen; `camera.fov_y_deg` is the view's own when it names one, else `[camera]`'s.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct ViewSettings {
    /// Unique within the config: the `[[view]]` name, the glTF camera node's name, or a
    /// generated name (`path_000120`, `sample_007`).
    pub(crate) name: String,
    pub(crate) camera: CameraSettings,
    /// How much each of the view's receiver pixels counts in the pooled statistics (default 1).
    pub(crate) weight: f64,
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

/// Shadow settings: csm-lab's own cascade parameters (what each does to quality is documented
/// on [`ShadowParams`]) and the engine preset applied on top, if any. Reads as the parameters
/// (`config.shadow.cascades`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ShadowSettings {
    #[serde(flatten)]
    pub params: ShadowParams,
    /// An engine's whole cascade set-up instead of csm-lab's own ([`crate::presets`]). When set,
    /// `cascades`, `resolution` and `max_distance` hold the preset's effective values, `snap`
    /// whether it snaps, `fit` the family of its fit, and `fit_depth_to_scene` is false.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<AppliedPreset>,
    /// `[shadow] update_every`: cached cascades, when some cascade is rendered less often than
    /// every frame (None when the key is absent or every value is 1: today's pipeline).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub update_every: Option<UpdateEvery>,
}

/// `[shadow] update_every`: the frames between two renders of a cascade, one value for every
/// cascade or one per cascade (nearest first). Held as written: the cascade count may change
/// after it is read (an engine preset, a sweep's cascade axis).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[serde(untagged)]
pub enum UpdateEvery {
    All(u32),
    PerCascade(Vec<u32>),
}

impl UpdateEvery {
    /// The written value, or None when it renders every cascade every frame.
    pub(crate) fn caching(self) -> Option<UpdateEvery> {
        let caches = match &self {
            UpdateEvery::All(k) => *k > 1,
            UpdateEvery::PerCascade(v) => v.iter().any(|&k| k > 1),
        };
        caches.then_some(self)
    }

    /// Each of `m` cascades' cadence (None when a per-cascade list has another length).
    pub fn per_cascade(&self, m: usize) -> Option<Vec<usize>> {
        match self {
            UpdateEvery::All(k) => Some(vec![*k as usize; m]),
            UpdateEvery::PerCascade(v) => (v.len() == m).then(|| v.iter().map(|&k| k as usize).collect()),
        }
    }

    /// As written in TOML (`4`, `[1, 1, 2, 4]`).
    pub fn label(&self) -> String {
        match self {
            UpdateEvery::All(k) => k.to_string(),
            UpdateEvery::PerCascade(v) => {
                format!("[{}]", v.iter().map(|k| k.to_string()).collect::<Vec<_>>().join(", "))
            }
        }
    }
}

/// Most cascades a per-cascade cadence of a sweep's `update_every` axis lists (the largest
/// cascade count csm-lab takes).
pub(crate) const MAX_CADENCE_CASCADES: usize = 16;

/// One value of a sweep's `update_every` axis (`--update-every 1,2,1/1/2/4`): a
/// `shadow.update_every` as written, one cadence for every cascade (`4`) or one per cascade
/// (`1/1/2/4`, nearest first). Fixed size so that a grid point stays `Copy`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SweptCadence {
    /// The cadences, `len` of them used; `len` 0 means one value, `every[0]`, for every cascade.
    every: [u16; MAX_CADENCE_CASCADES],
    len: u8,
}

impl SweptCadence {
    /// The value of one written token (`4`, `1/1/2/4`): each cadence a whole number in
    /// 1..=256, at most 16 of them.
    pub(crate) fn parse(token: &str) -> std::result::Result<SweptCadence, String> {
        let parts: Vec<&str> = token.split('/').map(str::trim).collect();
        if parts.len() > MAX_CADENCE_CASCADES {
            return Err(format!(
                "{token:?} lists {} cascades; at most {MAX_CADENCE_CASCADES}",
                parts.len()
            ));
        }
        let mut every = [0u16; MAX_CADENCE_CASCADES];
        for (i, p) in parts.iter().enumerate() {
            every[i] = p
                .parse::<u16>()
                .ok()
                .filter(|k| (1..=256).contains(k))
                .ok_or_else(|| format!("{p:?} in {token:?} is not a whole number of frames in 1..=256"))?;
        }
        Ok(SweptCadence {
            every,
            len: if parts.len() == 1 { 0 } else { parts.len() as u8 },
        })
    }

    /// As `shadow.update_every` holds it.
    pub(crate) fn update_every(self) -> UpdateEvery {
        if self.len == 0 {
            UpdateEvery::All(u32::from(self.every[0]))
        } else {
            UpdateEvery::PerCascade(self.every[..self.len as usize].iter().map(|&k| u32::from(k)).collect())
        }
    }

    /// As written on the command line and in `sweep.csv`'s `shadow.update_every` column: `4`,
    /// `1/1/2/4`.
    pub(crate) fn label(self) -> String {
        let n = (self.len as usize).max(1);
        self.every[..n]
            .iter()
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join("/")
    }
}

/// The values of an `update_every` axis written as `4,1/1/2/4`: each a [`SweptCadence`], none
/// twice.
pub(crate) fn parse_update_every_list(spec: &str) -> std::result::Result<Vec<SweptCadence>, String> {
    let values = spec
        .split(',')
        .map(|t| SweptCadence::parse(t.trim()))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    for (i, v) in values.iter().enumerate() {
        if values[..i].contains(v) {
            return Err(format!("{} is listed twice", v.label()));
        }
    }
    Ok(values)
}

impl std::ops::Deref for ShadowSettings {
    type Target = ShadowParams;
    fn deref(&self) -> &ShadowParams {
        &self.params
    }
}

impl std::ops::DerefMut for ShadowSettings {
    fn deref_mut(&mut self) -> &mut ShadowParams {
        &mut self.params
    }
}

/// A value stored in [`AppliedPreset`]: what the settings need to clone, compare, print and
/// echo it without knowing its type.
pub(crate) trait PresetValue: Any + std::fmt::Debug + Send + Sync {
    fn clone_value(&self) -> Box<dyn PresetValue>;
    fn eq_value(&self, other: &dyn PresetValue) -> bool;
    /// For `summary.json`'s echo of the inputs.
    fn to_json(&self) -> serde_json::Value;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// The engine preset applied to the settings, held without naming its type (presets build on
/// the config, not the other way round); `crate::presets` gives typed access.
#[derive(Debug)]
pub struct AppliedPreset(Box<dyn PresetValue>);

impl AppliedPreset {
    pub(crate) fn new(value: impl PresetValue) -> Self {
        AppliedPreset(Box::new(value))
    }

    pub(crate) fn downcast_ref<T: Any>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref()
    }

    pub(crate) fn downcast_mut<T: Any>(&mut self) -> Option<&mut T> {
        self.0.as_any_mut().downcast_mut()
    }
}

impl Clone for AppliedPreset {
    fn clone(&self) -> Self {
        AppliedPreset(self.0.clone_value())
    }
}

impl PartialEq for AppliedPreset {
    fn eq(&self, other: &Self) -> bool {
        self.0.eq_value(other.0.as_ref())
    }
}

impl serde::Serialize for AppliedPreset {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.0.to_json().serialize(s)
    }
}

/// Which `[shadow]` keys the file wrote (their values are validated in [`ShadowSettings`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Written {
    pub max_distance: bool,
    pub cascades: bool,
    pub resolution: bool,
    pub lambda: bool,
    pub splits: bool,
    pub fit: bool,
    pub snap: bool,
    pub fit_depth_to_scene: bool,
}

/// What applying a preset needs from the file besides the validated settings: its text (engine
/// tables are read from it and errors point into it), `shadow.preset` as written, the `[shadow]`
/// keys written and the top-level tables that are not csm-lab's own.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PresetInput {
    /// Names the file in messages.
    pub label: String,
    pub text: Arc<str>,
    pub preset: Option<String>,
    pub written: Written,
    /// Engine tables (or unknown ones), sorted by name.
    pub other_tables: Vec<String>,
}

impl PresetInput {
    /// A validator pointing into the file.
    pub(crate) fn validator(&self) -> Validator<'_> {
        Validator {
            path: &self.label,
            text: &self.text,
        }
    }
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
    /// Further paths of `motion.paths` after the first (empty with a single path). Each is
    /// walked from the configured camera; the summary's path metrics take the worst of all.
    pub extra: Vec<ExtraPath>,
    /// The light's motion (`motion.light_path`) and the engine's update rule
    /// (`shadow.light_update`); still by default.
    pub light: csm_core::light_motion::LightMotion,
}

/// A further motion path of `motion.paths`, with its own step.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtraPath {
    pub path: MotionPath,
    pub step: f64,
    pub step_as_written: f64,
}

impl MotionSettings {
    /// Every path, first the primary one: (path, step in internal units, step as written).
    pub(crate) fn all_paths(&self) -> Vec<(&MotionPath, f64, f64)> {
        std::iter::once((&self.path, self.step, self.step_as_written))
            .chain(self.extra.iter().map(|e| (&e.path, e.step, e.step_as_written)))
            .collect()
    }
}

/// The light's motion in the echo (nothing under a still light, so the echo is as before).
fn light_echo(light: &csm_core::light_motion::LightMotion, motion: &mut serde_json::Value) {
    use csm_core::light_motion::{LightPath, LightUpdate};
    match &light.path {
        LightPath::Still => return,
        LightPath::Sun { azimuth, elevation } => {
            motion["light_path"] = "sun".into();
            motion["sun_azimuth_step_deg"] = azimuth.to_degrees().into();
            motion["sun_elevation_step_deg"] = elevation.to_degrees().into();
        }
        LightPath::File { path, .. } => {
            motion["light_path"] = "file".into();
            motion["light_file"] = path.display().to_string().into();
        }
    }
    motion["light_update"] = match light.update {
        LightUpdate::EveryFrame => serde_json::json!({ "every_frames": 1 }),
        LightUpdate::EveryFrames(k) => serde_json::json!({ "every_frames": k }),
        LightUpdate::Quantize(q) => serde_json::json!({ "quantize_deg": q.to_degrees() }),
    };
}

fn step_unit(path: &MotionPath) -> &'static str {
    match path {
        MotionPath::Strafe | MotionPath::Dolly => "world units per frame",
        MotionPath::File { .. } => "unused (poses from file)",
        MotionPath::Still => "unused (the camera is still)",
        _ => "degrees per frame",
    }
}

/// How densely the sampled quantities are sampled. The closed forms do not depend on these.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AnalysisSettings {
    /// Log-spaced depths in `density.csv` (plus both sides of every split).
    pub density_samples: usize,
    /// World-fixed probe points per cascade for the shimmer metrics S3/S4.
    pub probes: usize,
    /// `[analysis] screen_scale` as written: the fraction of the screen's width and height
    /// sampled by the visibility pass (see [`AnalysisSettings::screen_scale`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub screen_scale: Option<f64>,
}

/// The visibility pass samples an eighth of the screen's width and height by default.
pub(crate) const DEFAULT_SCREEN_SCALE: f64 = 0.125;

impl AnalysisSettings {
    /// The sampling scale in effect.
    pub(crate) fn screen_scale(&self) -> f64 {
        self.screen_scale.unwrap_or(DEFAULT_SCREEN_SCALE)
    }
}

impl Default for AnalysisSettings {
    fn default() -> Self {
        AnalysisSettings {
            density_samples: 512,
            probes: 256,
            screen_scale: None,
        }
    }
}

/// The scene's geometry as configured: where it came from, and the triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometrySettings {
    /// `[scene] ground`, after the world offset.
    pub ground: Option<f64>,
    /// `[[scene.box]]` entries, after the world offset.
    pub boxes: Vec<Aabb>,
    /// `[scene] gltf`, resolved against the config's folder.
    pub gltf: Option<PathBuf>,
    pub scene: Arc<csm_core::visibility::SceneGeometry>,
    /// A level's pooled screen statistics already computed (a cache shared by every setting
    /// of a sweep, `csm_core::screen::pool_memo`).
    pub(crate) pool_memo: Arc<csm_core::screen::PoolMemo>,
}

impl GeometrySettings {
    pub(crate) fn echo(&self) -> serde_json::Value {
        let mut v = serde_json::json!({
            "boxes": self.boxes.iter().map(|b| serde_json::json!({"min": b.min, "max": b.max})).collect::<Vec<_>>(),
            "triangles": self.scene.mesh.triangles.len(),
        });
        if let Some(y) = self.ground {
            v["ground"] = y.into();
        }
        if let Some(p) = &self.gltf {
            v["gltf"] = p.display().to_string().into();
        }
        v
    }
}

/// A validated scene and shadow setting.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// The file stem, used for the default output directory `out/<name>/`.
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
    /// Scene geometry (ground, boxes, glTF), or None in the bounds-only mode.
    pub geometry: Option<GeometrySettings>,
    /// `[scene] world_offset`: already added to the camera, target, scene bounds and path-file
    /// poses above; kept for the echo.
    pub world_offset: DVec3,
    pub shadow: ShadowSettings,
    pub motion: MotionSettings,
    pub analysis: AnalysisSettings,
    /// The `[sweep]` table, if any.
    pub sweep: Option<sweep_spec::SweepSpec>,
    /// What [`crate::presets`] reads to apply the file's engine preset.
    pub preset_input: PresetInput,
    /// The ground-truth pass: whether it runs, and how the maps are sampled.
    pub truth: TruthSettings,
    /// The level's views when the config names any (`[[view]]`, `[views]`); empty means
    /// `[camera]` is the one view, as before views existed. See [`Config::level_views`].
    // Shared, so a view's config (`config_for_view`) clones the rest without copying the list.
    pub(crate) views: std::sync::Arc<Vec<ViewSettings>>,
    /// Warnings about the config that do not stop it (a view that sees no receiver, a glTF
    /// camera's aspect ratio unlike the screen's): printed on stderr when a file is loaded.
    pub(crate) warnings: Vec<String>,
    /// `[cost]`: culling and the cost model's calibration.
    pub cost: CostSettings,
}

/// `[cost] cull`: which casters each cascade draws (docs/cost.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CostCull {
    /// Every object whose bounds meet the cascade's caster volume.
    #[default]
    None,
    /// Only those of them that can shadow one of the cascade's visible receivers.
    Receivers,
}

impl CostCull {
    pub(crate) fn name(self) -> &'static str {
        match self {
            CostCull::None => "none",
            CostCull::Receivers => "receivers",
        }
    }
}

/// `[cost]`: receiver-aware culling, and the cost model's coefficients in nanoseconds when the
/// user measured them (all four or none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostSettings {
    /// `counts = false` skips the cost counts (draws, triangles, fragments, `cost_index` and
    /// their means are then absent, as without geometry): for a scene too large to count in a
    /// sweep, and to measure what counting costs (docs/cost.md).
    pub counts: bool,
    pub cull: CostCull,
    /// `ns_per_draw`, `ns_per_triangle`, `ns_per_fragment`, `ns_per_texel_cleared`.
    pub calibration: Option<csm_core::cost::CostModel>,
}

impl Default for CostSettings {
    fn default() -> Self {
        CostSettings {
            counts: true,
            cull: CostCull::None,
            calibration: None,
        }
    }
}

impl Config {
    /// The views the level is judged on: the configured views, or `[camera]` alone (named
    /// `camera`, weight 1) when none is configured.
    pub(crate) fn level_views(&self) -> Vec<ViewSettings> {
        if self.views.is_empty() {
            vec![ViewSettings {
                name: "camera".to_string(),
                camera: self.camera.clone(),
                weight: 1.0,
            }]
        } else {
            self.views.to_vec()
        }
    }
}

/// `[analysis] ground_truth` and the `[shadow]` keys of the sampled maps (docs/ground-truth.md).
#[derive(Debug, Clone, PartialEq)]
pub struct TruthSettings {
    /// Run the ground-truth pass (`[analysis] ground_truth` or `analyze --ground-truth`).
    pub enabled: bool,
    /// `[shadow] depth_bias` (world units along the light); None: the preset's, else 0.
    pub depth_bias: Option<f64>,
    /// `[shadow] slope_bias` (times the receiver's depth slope per texel).
    pub slope_bias: Option<f64>,
    /// `[shadow] normal_bias` (texels along the normal).
    pub normal_bias: Option<f64>,
    pub depth_format: csm_core::truth::DepthFormat,
    /// PCF kernel width in texels: 1, 3 or 5.
    pub pcf: u32,
    /// `[shadow] pcf_filter`; None: the preset engine's filter, else bilinear.
    pub pcf_filter: Option<csm_core::truth::PcfFilter>,
    /// `[shadow] bias = "none" | "recommended"` (or `analyze --raw-bias`, which is "none");
    /// None: the bias keys, else the preset's engine bias, else the recommended bias.
    pub bias_mode: Option<BiasMode>,
}

/// `[shadow] bias`: which bias the ground-truth pass samples with, when not its keys'.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiasMode {
    /// No bias at all (the raw maps).
    None,
    /// csm-lab's recommended depth bias, per cascade.
    Recommended,
}

impl BiasMode {
    pub(crate) fn name(self) -> &'static str {
        match self {
            BiasMode::None => "none",
            BiasMode::Recommended => "recommended",
        }
    }
}

impl Default for TruthSettings {
    fn default() -> Self {
        TruthSettings {
            enabled: false,
            depth_bias: None,
            slope_bias: None,
            normal_bias: None,
            depth_format: csm_core::truth::DepthFormat::D32F,
            pcf: 1,
            pcf_filter: None,
            bias_mode: None,
        }
    }
}

impl TruthSettings {
    /// Whether any bias key was written (then they replace the preset's bias).
    pub(crate) fn bias_written(&self) -> bool {
        self.depth_bias.is_some() || self.slope_bias.is_some() || self.normal_bias.is_some()
    }

    /// The echo in `summary.json` (only when the pass runs).
    pub(crate) fn echo(&self) -> serde_json::Value {
        let mut v = serde_json::json!({
            "depth_format": self.depth_format.name(),
            "pcf": self.pcf,
        });
        if let Some(f) = self.pcf_filter {
            v["pcf_filter"] = f.name().into();
        }
        if let Some(m) = self.bias_mode {
            v["bias"] = m.name().into();
        }
        for (k, x) in [
            ("depth_bias", self.depth_bias),
            ("slope_bias", self.slope_bias),
            ("normal_bias", self.normal_bias),
        ] {
            if let Some(x) = x {
                v[k] = x.into();
            }
        }
        v
    }
}

impl Config {
    /// A hash of the scene (camera, screen, light, scene bounds, motion; not the shadow or
    /// analysis settings, which a baseline comparison is meant to vary), as 16 hex digits:
    /// FNV-1a over the canonical JSON of those inputs (and a motion file's poses, not its
    /// path). `summary.json` carries it; `check --baseline` refuses a baseline of another scene.
    pub fn scene_hash(&self) -> String {
        let mut echo = self.echo();
        if let Some(obj) = echo.as_object_mut() {
            obj.remove("shadow");
            obj.remove("analysis");
            if let Some(m) = obj.get_mut("motion").and_then(|m| m.as_object_mut()) {
                m.remove("file");
                m.remove("light_file");
                // A shadow setting, which a baseline comparison may vary.
                m.remove("light_update");
            }
        }
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for b in bytes {
                h ^= u64::from(*b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        eat(echo.to_string().as_bytes());
        // The echo counts the triangles; a glTF edited in place must change the hash too.
        if let Some(g) = &self.geometry {
            for tri in &g.scene.mesh.triangles {
                for x in tri.iter().flat_map(|v| v.to_array()) {
                    eat(&x.to_bits().to_le_bytes());
                }
            }
        }
        if let MotionPath::File { poses, .. } = &self.motion.path {
            for (p, t) in poses {
                for x in p.to_array().into_iter().chain(t.to_array()) {
                    eat(&x.to_bits().to_le_bytes());
                }
            }
        }
        format!("{h:016x}")
    }

    /// The inputs as used, for `summary.json`.
    pub fn echo(&self) -> serde_json::Value {
        let motion_step_unit = step_unit(&self.motion.path);
        let mut motion = serde_json::json!({
            "path": self.motion.path.name(),
            "frames": self.motion.frames,
            "step": self.motion.step_as_written,
            "step_unit": motion_step_unit,
        });
        if let MotionPath::File { path, .. } = &self.motion.path {
            motion["file"] = serde_json::Value::String(path.display().to_string());
        }
        light_echo(&self.motion.light, &mut motion);
        if !self.motion.extra.is_empty() {
            motion["paths"] = self
                .motion
                .all_paths()
                .into_iter()
                .map(|(p, _, step)| serde_json::json!({ "path": p.name(), "step": step, "step_unit": step_unit(p) }))
                .collect();
        }
        let mut scene =
            serde_json::json!({ "min": self.scene.min, "max": self.scene.max, "world_offset": self.world_offset });
        if let Some(g) = &self.geometry {
            scene["geometry"] = g.echo();
        }
        let mut echo = serde_json::json!({
            "camera": self.camera,
            "screen": self.screen,
            "light": {
                "direction": self.light_direction_as_written,
                "direction_normalised": self.light_direction,
            },
            "scene": scene,
            "shadow": self.shadow,
            "motion": motion,
            "analysis": self.analysis,
        });
        if self.truth.enabled {
            echo["ground_truth"] = self.truth.echo();
        }
        if self.cost != CostSettings::default() {
            let mut cost = serde_json::json!({ "cull": self.cost.cull.name() });
            if !self.cost.counts {
                cost["counts"] = false.into();
            }
            if let Some(m) = self.cost.calibration {
                cost["ns_per_draw"] = m.per_draw.into();
                cost["ns_per_triangle"] = m.per_triangle.into();
                cost["ns_per_fragment"] = m.per_fragment.into();
                cost["ns_per_texel_cleared"] = m.per_texel_cleared.into();
            }
            echo["cost"] = cost;
        }
        echo
    }

    /// Effective far end of the shadow range before scene clipping: min(far, max_distance).
    pub fn shadow_far(&self) -> f64 {
        self.camera.far.min(self.shadow.max_distance)
    }

    /// The validated settings as the core's plain domain values (radians, unit light
    /// direction, world offset already applied).
    pub fn setup(&self) -> csm_core::scene::Setup {
        self.setup_seen_by(&self.camera)
    }

    /// [`Config::setup`] with `camera` in place of `[camera]`: the set-up of the config as a
    /// view sees it (`analysis::config_for_view`), without copying the config.
    pub(crate) fn setup_seen_by(&self, camera: &CameraSettings) -> csm_core::scene::Setup {
        use csm_core::scene::{Camera, Geometry, Motion, Setup};
        let s = &self.shadow;
        Setup {
            camera: Camera {
                position: camera.position,
                target: camera.target,
                up: camera.up,
                fov_y: camera.fov_y(),
                aspect: self.screen.aspect(),
                near: camera.near,
                far: camera.far,
                screen_height: self.screen.height,
            },
            light_direction: self.light_direction,
            bounds: self.scene,
            geometry: self.geometry.as_ref().map(|g| Geometry {
                scene: g.scene.clone(),
                screen_width: self.screen.width,
                screen_scale: self.analysis.screen_scale(),
            }),
            shadow: s.params,
            motion: Motion {
                path: self.motion.path.clone(),
                frames: self.motion.frames,
                step: self.motion.step,
            },
            light: self.motion.light.clone(),
        }
    }

    /// Camera poses of every frame of the motion path, or the first invalid frame and why.
    pub fn camera_path(&self) -> std::result::Result<Vec<CameraPose>, (usize, String)> {
        let setup = self.setup();
        csm_core::motion::camera_path(&setup.camera, &setup.motion)
    }

    /// Each further path of `motion.paths` (after the first), with its name, as a motion of
    /// the configured frame count.
    pub(crate) fn extra_motions(&self) -> Vec<(&'static str, csm_core::scene::Motion)> {
        self.motion
            .extra
            .iter()
            .map(|e| {
                let motion = csm_core::scene::Motion {
                    path: e.path.clone(),
                    frames: self.motion.frames,
                    step: e.step,
                };
                (e.path.name(), motion)
            })
            .collect()
    }

    /// Checks every pose of the motion path and of each further path without keeping them:
    /// the first invalid frame as (path index: 0 for the first path, 1-based in
    /// `motion.paths` after it; frame; why).
    pub(crate) fn check_camera_paths(&self) -> std::result::Result<(), (usize, usize, String)> {
        let setup = self.setup();
        let first = std::iter::once(setup.motion.clone());
        for (k, motion) in first
            .chain(self.extra_motions().into_iter().map(|(_, m)| m))
            .enumerate()
        {
            if let Some(Err((frame, why))) = csm_core::motion::poses(&setup.camera, &motion).find(|p| p.is_err()) {
                return Err((k, frame, why));
            }
        }
        Ok(())
    }
}
