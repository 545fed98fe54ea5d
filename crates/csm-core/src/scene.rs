//! The set-up being measured, as plain values: camera, light, scene bounds, shadow parameters
//! and camera motion.
//!
//! These are the core's inputs. They carry no file names, no key names and no degrees: the
//! config layer validates a file and builds a [`Setup`], and every function of the core takes
//! these types (or parts of them). Lengths are world units, angles radians, the light direction
//! is the unit vector along which light travels (conventions in [`crate::geometry`]).

use std::path::PathBuf;
use std::sync::Arc;

use glam::DVec3;

use crate::fitting::Fit;
use crate::geometry::{Aabb, CameraPose, Lens};
use crate::visibility::{Hits, SceneGeometry, View, Visibility};

/// The camera of frame 0 and its lens.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Width over height of the screen.
    pub aspect: f64,
    /// Near and far clip planes, world units of view depth.
    pub near: f64,
    pub far: f64,
    /// Screen height in pixels (the pixel footprint of the aliasing metrics).
    pub screen_height: u32,
}

impl Camera {
    /// The camera's frame, or None when position equals target or up is parallel to the view.
    pub fn pose(&self) -> Option<CameraPose> {
        CameraPose::look_at(self.position, self.target, self.up)
    }

    pub fn lens(&self) -> Lens {
        Lens::new(self.fov_y, self.aspect)
    }
}

/// csm-lab's own cascade parameters: the knobs an engine exposes, and what each does to quality.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ShadowParams {
    /// Shadow distance, world units: cascades end at `min(camera far, max_distance)`. Larger
    /// spreads the same texels over more depth (blurrier); smaller cuts shadows off sooner.
    pub max_distance: f64,
    /// Number of cascades (1..=16). More cascades lower the worst-case aliasing at the cost of
    /// memory and draw calls; returns diminish beyond about 4.
    pub cascades: usize,
    /// Practical split weight in [0, 1]: 0 uniform (starves the near cascades), 1 logarithmic
    /// (equal worst case in every cascade, but a tiny first cascade when near is small).
    pub lambda: f64,
    /// Texels per side of each cascade's map (16..=16384). Texel size scales as 1/resolution.
    pub resolution: u32,
    /// How a window is fitted around its slice: a sphere never changes size (stable), a tight
    /// box is sharper but changes size as the camera turns.
    pub fit: Fit,
    /// Move each window in whole texels on a world-anchored grid. Removes shimmer under camera
    /// translation (and rotation, for the sphere fit).
    pub snap: bool,
    /// Explicit split fractions of the split range `[z_lo, z_hi]` (`shadow.splits`, one fewer
    /// than the cascades) instead of the practical split: what `sweep --optimize-splits` finds.
    /// None: the practical split with `lambda`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splits: Option<crate::free_splits::SplitFractions>,
    /// Split only the depths where the scene bounds are visible; skips empty depth.
    pub fit_depth_to_scene: bool,
    /// Split only the view depths where geometry is visible (needs [`Setup::geometry`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub fit_depth_to_visible: bool,
    /// Arithmetic of the cascade pipeline: exact f64, or an engine's binary32 emulated
    /// operation by operation.
    pub precision: Precision,
    /// Where the binary32 pipeline computes: at absolute world coordinates, or relative to a
    /// camera-near anchor. Only matters with binary32.
    pub snap_space: SnapSpace,
}

/// The camera's motion: a path kind with its frame count and step (world units or radians
/// per frame), or explicit poses.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    pub path: MotionPath,
    pub frames: usize,
    pub step: f64,
}

/// Scene geometry with the screen sampling of the visibility pass.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    pub scene: Arc<SceneGeometry>,
    /// Screen width in pixels (the height is [`Camera::screen_height`]).
    pub screen_width: u32,
    /// Fraction of the width and height sampled, in (0, 1].
    pub screen_scale: f64,
}

/// Which view depths the splits divide: the scene bounds' range (every metre of it, seen or
/// not) or only the range where geometry is visible (what SDSM reads from the depth buffer;
/// sharper, needs geometry). The same choice as [`ShadowParams::fit_depth_to_visible`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SplitRange {
    Bounds,
    Visible,
}

impl SplitRange {
    pub fn of(fit_depth_to_visible: bool) -> Self {
        if fit_depth_to_visible {
            SplitRange::Visible
        } else {
            SplitRange::Bounds
        }
    }

    pub fn is_visible(self) -> bool {
        self == SplitRange::Visible
    }

    pub fn name(self) -> &'static str {
        match self {
            SplitRange::Bounds => "bounds",
            SplitRange::Visible => "visible",
        }
    }
}

impl std::fmt::Display for SplitRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Everything the core measures, in one value.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    pub camera: Camera,
    /// Unit direction in which light travels.
    pub light_direction: DVec3,
    /// World-space bounds of everything that casts or receives shadows.
    pub bounds: Aabb,
    /// The scene's triangles and how the screen is sampled; None in the bounds-only mode.
    pub geometry: Option<Geometry>,
    pub shadow: ShadowParams,
    pub motion: Motion,
    /// How the light moves along the path (still by default): the direction of frame `t` is
    /// `light.used_direction(light_direction, t)`.
    pub light: crate::light_motion::LightMotion,
}

impl Setup {
    /// Far end of the shadow range before scene clipping: `min(camera far, max_distance)`.
    pub fn shadow_far(&self) -> f64 {
        self.camera.far.min(self.shadow.max_distance)
    }

    /// What the visibility pass of frame 0 depends on; None without geometry or camera.
    pub fn view(&self) -> Option<View> {
        let g = self.geometry.as_ref()?;
        Some(View {
            pose: self.camera.pose()?,
            lens: self.camera.lens(),
            near: self.camera.near,
            far: self.camera.far,
            width: g.screen_width,
            height: self.camera.screen_height,
            scale: g.screen_scale,
            light: self.light_direction,
        })
    }

    /// The visibility pass of frame 0 (made once per view and shared), or None without geometry.
    pub fn visibility(&self) -> Option<Arc<Visibility>> {
        let view = self.view()?;
        Some(self.geometry.as_ref()?.scene.visibility(&view))
    }

    /// The light-independent part of that pass (the rays cast; made once per camera and screen
    /// and shared by every light), or None without geometry.
    pub fn visibility_hits(&self) -> Option<Arc<Hits>> {
        let view = self.view()?;
        Some(self.geometry.as_ref()?.scene.hits(&view))
    }
}

/// Arithmetic of the cascade pipeline (`[shadow] precision`, `--precision`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Exact: texel-unit windows, snapped shimmer exactly 0 at any world offset.
    #[default]
    F64,
    /// An engine's binary32 pipeline, emulated operation by operation.
    F32,
}

impl Precision {
    pub fn name(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "f64" => Some(Precision::F64),
            "f32" => Some(Precision::F32),
            _ => None,
        }
    }
}

impl std::str::FromStr for Precision {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Precision::from_name(s).ok_or_else(|| format!("{s:?} is not one of f64, f32"))
    }
}

impl std::fmt::Display for Precision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where the binary32 pipeline computes (`[shadow] snap_space`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SnapSpace {
    /// Absolute world coordinates rounded to f32 (what engines do by default).
    #[default]
    World,
    /// Positions relative to a camera-near, grid-aligned anchor, subtracted in f64.
    CameraRelative,
}

impl SnapSpace {
    pub fn name(self) -> &'static str {
        match self {
            SnapSpace::World => "world",
            SnapSpace::CameraRelative => "camera_relative",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "world" => Some(SnapSpace::World),
            "camera_relative" => Some(SnapSpace::CameraRelative),
            _ => None,
        }
    }
}

impl std::fmt::Display for SnapSpace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which way the camera moves along the shimmer path, one pose per frame.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionPath {
    /// Sideways along the camera's right axis, `step` world units per frame.
    Strafe,
    /// Along the view direction, `step` world units per frame.
    Dolly,
    /// Turning about the camera's up vector, `step` radians per frame.
    Yaw,
    /// Tilting about the camera's right axis, `step` radians per frame.
    Pitch,
    /// Circling the target about the up vector, `step` radians per frame.
    Orbit,
    /// A camera that does not move: the configured pose in every frame (the step is unused).
    Still,
    /// Poses read from a CSV file: (position, target) per frame.
    File { path: PathBuf, poses: Vec<(DVec3, DVec3)> },
}

impl MotionPath {
    /// The paths generated from the configured camera, by name: a new path is a variant here,
    /// its name in [`MotionPath::name`] and its poses in [`crate::motion::camera_path`], nothing else.
    pub const GENERATED: [MotionPath; 6] = [
        MotionPath::Strafe,
        MotionPath::Dolly,
        MotionPath::Yaw,
        MotionPath::Pitch,
        MotionPath::Orbit,
        MotionPath::Still,
    ];

    /// The generated path of a name (`"strafe"`, ...); None for `"file"` and unknown names.
    pub fn generated(name: &str) -> Option<MotionPath> {
        Self::GENERATED.into_iter().find(|p| p.name() == name)
    }

    /// Every name a config may give, quoted, for error messages.
    pub fn names_quoted() -> String {
        let mut names: Vec<String> = Self::GENERATED.iter().map(|p| format!("{:?}", p.name())).collect();
        names.push("\"file\"".to_string());
        names.join(", ")
    }

    /// The per-frame step as used from the step as written: world units for translations,
    /// degrees converted to radians for rotations (degrees exist only in the config).
    pub fn step_from_written(&self, written: f64) -> f64 {
        if self.is_translation() {
            written
        } else {
            written.to_radians()
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            MotionPath::Strafe => "strafe",
            MotionPath::Dolly => "dolly",
            MotionPath::Yaw => "yaw",
            MotionPath::Pitch => "pitch",
            MotionPath::Orbit => "orbit",
            MotionPath::Still => "still",
            MotionPath::File { .. } => "file",
        }
    }

    /// True when every frame differs from the previous one by a pure translation.
    pub fn is_translation(&self) -> bool {
        matches!(self, MotionPath::Strafe | MotionPath::Dolly)
    }
}
