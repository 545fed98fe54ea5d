//! Building the cascades an engine would build: split, fit, snap, and light near/far.
//!
//! A [`Rig`] holds everything that stays fixed while the camera moves: the lens, the light
//! basis, the split depths and, for the sphere fit, each window's size. Engines keep split
//! intervals static from frame to frame (refitting them every frame is unstable by
//! construction), and so does the rig: the splits come from the configured camera.
//! Per frame only the window position (and, for the AABB fit, its size) is recomputed.

use glam::{DVec2, DVec3};

use crate::config::{Config, Fit};
use crate::depth_range::{self, DepthRange};
use crate::fitting::{minimal_sphere, Sphere, Window};
use crate::geometry::{intersection_range, Aabb, CameraPose, Hexahedron, Lens, LightBasis, Plane};
use crate::snapping::SnapRule;
use crate::splits;

/// The camera frame in light-space x/y, computed once per frame so that slice corners and
/// sphere centres of every cascade cost a few multiply-adds each.
#[derive(Debug, Clone, Copy)]
pub struct LightPose {
    pub position: DVec2,
    pub forward: DVec2,
    pub right: DVec2,
    pub up: DVec2,
}

impl LightPose {
    pub fn new(light: &LightBasis, pose: &CameraPose) -> Self {
        LightPose {
            position: light.to_light_xy(pose.position),
            forward: light.to_light_xy(pose.forward),
            right: light.to_light_xy(pose.right),
            up: light.to_light_xy(pose.up),
        }
    }

    /// Light-space x/y of the point at view depth `z` with image slopes (sx, sy).
    pub fn point(&self, sx: f64, sy: f64, z: f64) -> DVec2 {
        self.position + self.forward * z + self.right * (sx * z) + self.up * (sy * z)
    }

    /// Light-space x/y of the 8 corners of the slice `[near, far]`.
    pub fn corners(&self, lens: &Lens, near: f64, far: f64) -> [DVec2; 8] {
        std::array::from_fn(|i| {
            let sx = if i & 1 == 0 { -lens.tan_h } else { lens.tan_h };
            let sy = if i & 2 == 0 { -lens.tan_v } else { lens.tan_v };
            let z = if i & 4 == 0 { near } else { far };
            self.point(sx, sy, z)
        })
    }
}

/// One cascade's slice: depth interval and minimal bounding sphere (fixed for the whole run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slice {
    pub near: f64,
    pub far: f64,
    pub sphere: Sphere,
}

/// Everything fixed over a motion path.
#[derive(Debug, Clone)]
pub struct Rig {
    pub lens: Lens,
    pub light: LightBasis,
    pub fit: Fit,
    pub resolution: u32,
    pub snap_rule: SnapRule,
    pub splits: Vec<f64>,
    pub slices: Vec<Slice>,
    /// Sphere fit: window side per cascade, with the snapping border included.
    pub sphere_side: Vec<f64>,
}

impl Rig {
    /// Builds the rig for a config, or None when the scene needs no cascades.
    pub fn from_config(config: &Config) -> Option<Rig> {
        let DepthRange::Range { z_lo, z_hi } = depth_range::for_config(config) else {
            return None;
        };
        let s = &config.shadow;
        let splits = splits::practical(z_lo, z_hi, s.cascades, s.lambda);
        let lens = Lens::new(config.camera.fov_y(), config.screen.aspect());
        Some(Rig::new(
            lens,
            LightBasis::new(config.light_direction),
            s.fit,
            s.resolution,
            SnapRule::default(),
            splits,
        ))
    }

    pub fn new(lens: Lens, light: LightBasis, fit: Fit, resolution: u32, snap_rule: SnapRule, splits: Vec<f64>) -> Rig {
        let k2 = lens.k2();
        let slices: Vec<Slice> = splits
            .windows(2)
            .map(|w| Slice {
                near: w[0],
                far: w[1],
                sphere: minimal_sphere(w[0], w[1], k2),
            })
            .collect();
        let shift = snap_rule.max_shift_texels();
        let sphere_side = slices
            .iter()
            .map(|s| Window::side_with_border(2.0 * s.sphere.radius, resolution, shift))
            .collect();
        Rig {
            lens,
            light,
            fit,
            resolution,
            snap_rule,
            splits,
            slices,
            sphere_side,
        }
    }

    pub fn cascade_count(&self) -> usize {
        self.slices.len()
    }

    /// Cascade `i`'s window for a camera frame. Both snap modes use the same window size, so
    /// comparing them isolates the effect of snapping.
    pub fn window(&self, i: usize, lp: &LightPose, snapped: bool) -> Window {
        let slice = &self.slices[i];
        let snap = snapped.then_some(self.snap_rule);
        match self.fit {
            Fit::Sphere => {
                let centre = lp.position + lp.forward * slice.sphere.centre_depth;
                Window::centred(centre, DVec2::splat(self.sphere_side[i]), self.resolution, snap)
            }
            Fit::Aabb => {
                let corners = lp.corners(&self.lens, slice.near, slice.far);
                let (lo, hi) = bounds_2d(&corners);
                let shift = self.snap_rule.max_shift_texels();
                let extent = hi - lo;
                let size = DVec2::new(
                    Window::side_with_border(extent.x, self.resolution, shift),
                    Window::side_with_border(extent.y, self.resolution, shift),
                );
                Window::centred(0.5 * (lo + hi), size, self.resolution, snap)
            }
        }
    }

    /// Light-space depth range the cascade must render: near far enough toward the light to
    /// keep every caster of the scene that can shadow the window, far enough to cover every
    /// receiver of the slice. Computed from the scene bounds clipped to the window's prism.
    pub fn light_depth_range(&self, i: usize, pose: &CameraPose, window: &Window, scene: &Aabb) -> (f64, f64) {
        let slice = &self.slices[i];
        let slice_hex = pose.slice_hexahedron(&self.lens, slice.near, slice.far);
        let scene_hex = scene.hexahedron();
        let l = &self.light;
        let slice_z = slice_hex.vertices.iter().map(|v| l.z.dot(*v));
        let (slice_lo, slice_hi) = slice_z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| (a.min(z), b.max(z)));
        let scene_z = (0..8).map(|c| l.z.dot(scene.corner(c)));
        let (scene_lo, scene_hi) = scene_z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| (a.min(z), b.max(z)));
        // The window's prism along the light, long enough to hold the scene and the slice.
        let lo = window.min();
        let hi = lo + DVec2::new(window.width(), window.height());
        let z0 = scene_lo.min(slice_lo) - 1.0;
        let z1 = scene_hi.max(slice_hi) + 1.0;
        let prism = Hexahedron {
            vertices: std::array::from_fn(|c| {
                let x = if c & 1 == 0 { lo.x } else { hi.x };
                let y = if c & 2 == 0 { lo.y } else { hi.y };
                let z = if c & 4 == 0 { z0 } else { z1 };
                l.x * x + l.y * y + l.z * z
            }),
            planes: [
                Plane::new(-l.x, -lo.x),
                Plane::new(l.x, hi.x),
                Plane::new(-l.y, -lo.y),
                Plane::new(l.y, hi.y),
                Plane::new(-l.z, -z0),
                Plane::new(l.z, z1),
            ],
        };
        let near = intersection_range(&scene_hex, &prism, l.z).map_or(slice_lo, |(a, _)| a.min(slice_hi));
        let far = intersection_range(&slice_hex, &scene_hex, l.z).map_or(slice_hi, |(_, b)| b);
        (near.min(far), far)
    }
}

/// Component-wise min and max of a set of 2-D points.
pub fn bounds_2d(points: &[DVec2]) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (lo, hi)
}

/// World-space corners of a cascade's slice for a pose (for plots and tests).
pub fn slice_corners_world(rig: &Rig, i: usize, pose: &CameraPose) -> [DVec3; 8] {
    let s = &rig.slices[i];
    pose.slice_corners(&rig.lens, s.near, s.far)
}
