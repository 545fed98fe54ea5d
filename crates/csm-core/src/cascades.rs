//! Building the cascades an engine would build: split, fit, snap, and light near/far.
//!
//! A [`Rig`] holds everything that stays fixed while the camera moves: the lens, the light
//! basis, the split depths and, for constant-size windows, each window's size. Engines keep
//! split intervals static from frame to frame (refitting them every frame is unstable by
//! construction), and so does the rig: the splits come from the configured camera.
//! Per frame only the window position (and, for box fits, its size) is recomputed.
//!
//! **Selection vs fitted slices.** `splits` are the *selection* boundaries: cascade `i` is the
//! one a view depth in `[splits[i], splits[i+1])` reads (in a blend band, the coarser of the two
//! cascades counts, since it is the blurrier of the two a pixel may read). `slices` are the *fitted* intervals the
//! windows are built around. csm-lab's own pipeline uses one for the other; engine presets
//! (built above the core, in the presets layer) may overlap their fitted slices (blend bands, Bevy's overlap, EEVEE's
//! fade) or select differently from how they fit (three.js, seed 004).
//!
//! **Scheme.** How a window is sized, centred and snapped, which light basis a cascade uses,
//! and which light depth range it renders are described by a [`Scheme`]. csm-lab's built-in
//! fits are the schemes [`Rig::new`] builds: minimal sphere or tight box, snapped with the
//! rounding rule of [`SnapRule::default`] on the world-anchored grid, light depth from the scene.

use glam::{DVec2, DVec3};

use crate::depth_range::{self, DepthRange};
use crate::fitting::{minimal_sphere, Fit, Sphere, Window};
use crate::geometry::{
    intersection_max_from, intersection_range, Aabb, CameraPose, Corner, Hexahedron, Lens, LightBasis, MaxCandidate,
    Plane,
};
use crate::scene::Setup;
use crate::snapping::SnapRule;
use crate::splits;

/// The camera frame in light-space x/y, computed once per frame so that slice corners and
/// sphere centres of every cascade cost a few multiply-adds each. `pose` is kept for schemes
/// whose light basis depends on the camera.
#[derive(Debug, Clone, Copy)]
pub struct LightPose {
    pub position: DVec2,
    pub forward: DVec2,
    pub right: DVec2,
    pub up: DVec2,
    pub pose: CameraPose,
}

impl LightPose {
    pub fn new(light: &LightBasis, pose: &CameraPose) -> Self {
        LightPose {
            position: light.to_light_xy(pose.position),
            forward: light.to_light_xy(pose.forward),
            right: light.to_light_xy(pose.right),
            up: light.to_light_xy(pose.up),
            pose: *pose,
        }
    }

    /// Light-space x/y of the point at view depth `z` with image slopes (sx, sy).
    pub fn point(&self, sx: f64, sy: f64, z: f64) -> DVec2 {
        self.position + self.forward * z + self.right * (sx * z) + self.up * (sy * z)
    }

    /// Light-space x/y of the 8 corners of the slice `[near, far]`.
    pub fn corners(&self, lens: &Lens, near: f64, far: f64) -> [DVec2; 8] {
        Corner::each(|c| {
            let (sx, sy, z) = c.of_slice(lens, near, far);
            self.point(sx, sy, z)
        })
    }
}

/// One cascade's fitted slice: depth interval and minimal bounding sphere (fixed for the run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slice {
    pub near: f64,
    pub far: f64,
    pub sphere: Sphere,
}

impl Slice {
    /// The slices of these depth intervals, each with its minimal bounding sphere (`k2` of the
    /// lens, see [`Lens::k2`]).
    fn all(intervals: impl Iterator<Item = (f64, f64)>, k2: f64) -> Vec<Slice> {
        intervals
            .map(|(near, far)| Slice {
                near,
                far,
                sphere: minimal_sphere(near, far, k2),
            })
            .collect()
    }
}

/// Which light-space basis a cascade uses in a frame.
#[derive(Debug, Clone, PartialEq)]
pub enum BasisRule {
    /// The rig's `light` basis in every frame: fixed in the world (csm-lab, most engines).
    Fixed,
    /// Look-to along the light with the camera's right axis as the up reference (Filament):
    /// the basis turns when the camera yaws. Falls back to `light` when the camera's right
    /// axis is within acos(0.999) of the light direction.
    CameraRight,
    /// Look-to along the light with a fixed world `up` reference (Filament: the world-origin
    /// transform's x axis, +X unless an IBL is rotated): `y` is the part of `up`
    /// perpendicular to the light, `x = light × y`; when `|up · light| > 0.999` the reference
    /// becomes `(up.z, up.x, up.y)` first. Fixed in the world: it does not turn with the camera.
    LookToUp(DVec3),
    /// Look-at from a light *position* to the centroid of each slice, up +Y (seed 004): every
    /// cascade has its own direction, and it changes whenever the camera moves.
    LookAtFrom(DVec3),
}

/// How a cascade's window is sized and centred, in its light basis.
#[derive(Debug, Clone, PartialEq)]
pub enum WindowRule {
    /// Square of side `sphere_side[i]` centred on the view-axis point at `centre_depth[i]`
    /// (any sphere fit: minimal, corner average, far cap).
    AxisCentred { centre_depth: Vec<f64> },
    /// Square of side `sphere_side[i]` centred on the light-space bounding-box centre of the
    /// slice's corners (the slice-diameter windows of three.js and Bevy).
    BoxCentred,
    /// Tight light-space bounding box of the slice's corners, grown by `pad` world units per
    /// side and, with `border`, by the snap rule's largest shift (csm-lab's `aabb` fit).
    Tight { pad: f64, border: bool },
    /// Tight box extents, but centred on the light-space axis through the world origin (the
    /// window-centring defect of seed 002).
    TightAtOrigin,
}

/// The light depth range a cascade renders, and whether casters nearer the light survive.
/// Depths are light-space z (along the direction light travels) in the cascade's basis.
#[derive(Debug, Clone, PartialEq)]
pub enum LightDepthRule {
    /// Fitted to the scene: casters within the window's prism, receivers of the slice (csm-lab;
    /// also the model for engines that fit to scene bounds, or where the source does not say).
    Scene,
    /// The slice's own light-depth extent. `keeps_casters`: casters in front are kept by
    /// unclipped depth or pancaking (Bevy); otherwise they are lost (seed 002).
    Slice { keeps_casters: bool },
    /// Sphere centre ± max(r, `min_half`), the near side extended by `toward_light`; casters
    /// in front are kept (Godot's pancake, Unreal's whole-scene caster range).
    Sphere {
        radius: Vec<f64>,
        toward_light: f64,
        min_half: f64,
    },
    /// A light plane `margin` in front of the slice's nearest corner, rendering distances
    /// `[near, far]` from it; nothing else is kept (three.js).
    Margin { margin: f64, near: f64, far: f64 },
    /// Distances `[near, far]` from a point along the light (EEVEE 2017's lamp clip range).
    FromPoint { point: DVec3, near: f64, far: f64 },
    /// Seed 004's mirrored range: light-view z values passed as distances, so the rendered
    /// distances from `eye` are `[-dmax - pad, -dmin + pad]` for a slice at `[dmin, dmax]`.
    Mirrored { eye: DVec3, pad: f64 },
}

/// Everything about how cascades are placed besides the split depths.
#[derive(Debug, Clone, PartialEq)]
pub struct Scheme {
    /// Short name of the fit for tables and CSV (`sphere`, `aabb`, `diameter-ceil`, ...).
    pub fit_label: String,
    pub basis: BasisRule,
    pub window: WindowRule,
    /// False for implementations that never snap: then the "snapped" window is the unsnapped one.
    pub snaps: bool,
    /// Light-space x/y of a point the snap grid runs through: zero for a grid anchored at the
    /// world origin, the lamp's position for EEVEE.
    pub snap_anchor: DVec2,
    pub depth: LightDepthRule,
}

/// The light depth range a cascade renders and what falls outside it (frame 0).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LightDepth {
    /// Rendered range, light-space z in the cascade's basis (world units along the light).
    pub near: f64,
    pub far: f64,
    /// World units of receiver depth (the cascade's slice within the scene bounds) outside the range.
    pub receivers_outside: f64,
    /// World units of caster depth toward the light (scene within the window's prism) in front
    /// of the range that the cascade loses; 0 when the engine keeps such casters.
    pub casters_outside: f64,
}

use crate::walk::FrameCoverage;

/// Everything fixed over a motion path.
#[derive(Debug, Clone)]
pub struct Rig {
    pub lens: Lens,
    pub light: LightBasis,
    /// csm-lab's fit; for a preset, the nearest built-in family (sphere for constant-size
    /// windows, aabb for box fits) — the preset's own rule is in `scheme`.
    pub fit: Fit,
    pub resolution: u32,
    pub snap_rule: SnapRule,
    /// Selection boundaries (see the module docs); equal to the fitted boundaries for csm-lab's
    /// own pipeline.
    pub splits: Vec<f64>,
    /// Fitted slices.
    pub slices: Vec<Slice>,
    /// Constant-size windows: side per cascade, border included.
    pub sphere_side: Vec<f64>,
    pub scheme: Scheme,
}

impl Rig {
    /// csm-lab's own rig for a set-up (practical splits over its depth range, or the
    /// explicit `shadow.splits` fractions of it), or None when
    /// the scene needs no cascades. (Engine presets build theirs with [`Rig::with_scheme`].)
    pub fn for_setup(setup: &Setup) -> Option<Rig> {
        Rig::for_setup_in(setup, depth_range::for_setup(setup))
    }

    /// [`Rig::for_setup`] with the setup's split range already computed
    /// ([`depth_range::for_setup`], which reads neither the split positions nor the resolution,
    /// so a caller trying many splits of one setup computes it once).
    pub fn for_setup_in(setup: &Setup, range: DepthRange) -> Option<Rig> {
        let DepthRange::Range { z_lo, z_hi } = range else {
            return None;
        };
        let s = &setup.shadow;
        let splits = match &s.splits {
            Some(f) if f.len() + 1 == s.cascades => splits::from_positions(z_lo, z_hi, f.as_slice()),
            _ => splits::practical(z_lo, z_hi, s.cascades, s.lambda),
        };
        Some(Rig::new(
            setup.camera.lens(),
            LightBasis::new(setup.light_direction),
            s.fit,
            s.resolution,
            SnapRule::default(),
            splits,
        ))
    }

    /// csm-lab's own pipeline: fitted slices = selection intervals = consecutive splits.
    pub fn new(lens: Lens, light: LightBasis, fit: Fit, resolution: u32, snap_rule: SnapRule, splits: Vec<f64>) -> Rig {
        let slices = Slice::all(splits.windows(2).map(|w| (w[0], w[1])), lens.k2());
        let shift = snap_rule.max_shift_texels();
        let sides = slices
            .iter()
            .map(|s| Window::side_with_border(2.0 * s.sphere.radius, resolution, shift))
            .collect();
        let window = match fit {
            Fit::Sphere => WindowRule::AxisCentred {
                centre_depth: slices.iter().map(|s| s.sphere.centre_depth).collect(),
            },
            Fit::Aabb => WindowRule::Tight { pad: 0.0, border: true },
        };
        let scheme = Scheme {
            fit_label: fit.name().to_string(),
            basis: BasisRule::Fixed,
            window,
            snaps: true,
            snap_anchor: DVec2::ZERO,
            depth: LightDepthRule::Scene,
        };
        Rig::assemble(lens, light, fit, resolution, snap_rule, splits, slices, sides, scheme)
    }

    /// Moves a rig of csm-lab's own pipeline ([`Rig::new`]) to another resolution: it becomes
    /// what [`Rig::new`] builds from the same lens, light, fit, snap rule and splits with
    /// `resolution`, bit for bit. Only the constant window sides read the resolution (the
    /// slices and the scheme do not), so they alone are made again. Not for a rig of
    /// [`Rig::with_scheme`], whose sides its caller chose.
    pub fn set_resolution(&mut self, resolution: u32) {
        let shift = self.snap_rule.max_shift_texels();
        for (side, s) in self.sphere_side.iter_mut().zip(&self.slices) {
            *side = Window::side_with_border(2.0 * s.sphere.radius, resolution, shift);
        }
        self.resolution = resolution;
    }

    /// A rig for an arbitrary scheme: `selection` has one more entry than `fitted`, and
    /// `sides` gives the constant window side per cascade (ignored by box fits).
    #[allow(clippy::too_many_arguments)]
    pub fn with_scheme(
        lens: Lens,
        light: LightBasis,
        fit: Fit,
        resolution: u32,
        snap_rule: SnapRule,
        selection: Vec<f64>,
        fitted: &[(f64, f64)],
        sides: Vec<f64>,
        scheme: Scheme,
    ) -> Rig {
        assert_eq!(selection.len(), fitted.len() + 1, "one selection interval per cascade");
        assert_eq!(sides.len(), fitted.len(), "one window side per cascade");
        let slices = Slice::all(fitted.iter().copied(), lens.k2());
        Rig::assemble(
            lens, light, fit, resolution, snap_rule, selection, slices, sides, scheme,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        lens: Lens,
        light: LightBasis,
        fit: Fit,
        resolution: u32,
        snap_rule: SnapRule,
        splits: Vec<f64>,
        slices: Vec<Slice>,
        sphere_side: Vec<f64>,
        scheme: Scheme,
    ) -> Rig {
        Rig {
            lens,
            light,
            fit,
            resolution,
            snap_rule,
            splits,
            slices,
            sphere_side,
            scheme,
        }
    }

    pub fn cascade_count(&self) -> usize {
        self.slices.len()
    }

    /// True when every cascade uses `light` in every frame, so light-space coordinates of a
    /// static point never change.
    pub fn fixed_basis(&self) -> bool {
        self.scheme.basis == BasisRule::Fixed
    }

    /// The selection interval of cascade `i`: the view depths that read it.
    pub fn selection(&self, i: usize) -> (f64, f64) {
        (self.splits[i], self.splits[i + 1])
    }

    /// Cascade `i`'s light basis in the frame of `lp`.
    pub fn basis(&self, i: usize, lp: &LightPose) -> LightBasis {
        self.basis_with(i, lp, &self.light)
    }

    /// Cascade `i`'s light basis in the frame of `lp` when the light of that frame has the
    /// basis `light` (a moving light; [`Rig::basis`] is this with the rig's own light).
    pub fn basis_with(&self, i: usize, lp: &LightPose, light: &LightBasis) -> LightBasis {
        match &self.scheme.basis {
            BasisRule::Fixed => *light,
            BasisRule::CameraRight => camera_right_basis(light.z, lp.pose.right).unwrap_or(*light),
            BasisRule::LookToUp(up) => look_to_basis(light.z, *up).unwrap_or(*light),
            BasisRule::LookAtFrom(eye) => {
                let s = &self.slices[i];
                // The 8 corners of a symmetric slice average to its axis point at mid-depth.
                let centroid = lp.pose.position + lp.pose.forward * (0.5 * (s.near + s.far));
                let dir = centroid - *eye;
                if dir.length() > 1e-12 * (1.0 + eye.length()) {
                    LightBasis::new(dir)
                } else {
                    *light
                }
            }
        }
    }

    /// Cascade `i`'s basis in the frame of `lp`, and the camera frame expressed in it.
    pub fn cascade_pose(&self, i: usize, lp: &LightPose) -> (LightBasis, LightPose) {
        if self.fixed_basis() {
            (self.light, *lp)
        } else {
            let b = self.basis(i, lp);
            (b, LightPose::new(&b, &lp.pose))
        }
    }

    /// [`Rig::cascade_pose`] for a frame whose light has the basis `light`, with `lp` the
    /// camera frame in that basis.
    pub fn cascade_pose_with(&self, i: usize, lp: &LightPose, light: &LightBasis) -> (LightBasis, LightPose) {
        if self.fixed_basis() {
            (*light, *lp)
        } else {
            let b = self.basis_with(i, lp, light);
            (b, LightPose::new(&b, &lp.pose))
        }
    }

    /// With a fixed basis, each probe's light-space x/y (the same in every frame); empty
    /// otherwise.
    pub fn fixed_probe_xy(&self, probes: &[Vec<DVec3>]) -> Vec<Vec<DVec2>> {
        if self.fixed_basis() {
            probes
                .iter()
                .map(|ps| ps.iter().map(|p| self.light.to_light_xy(*p)).collect())
                .collect()
        } else {
            Vec::new()
        }
    }

    /// Cascade `i`'s window for a camera frame, in the cascade's basis ([`Rig::basis`]). Both
    /// snap modes use the same window size, so comparing them isolates the effect of snapping.
    pub fn window(&self, i: usize, lp: &LightPose, snapped: bool) -> Window {
        if self.fixed_basis() {
            self.window_in(i, lp, snapped)
        } else {
            self.window_in(i, &LightPose::new(&self.basis(i, lp), &lp.pose), snapped)
        }
    }

    /// The window given the camera frame `lp` in the cascade's own basis.
    pub fn window_in(&self, i: usize, lp: &LightPose, snapped: bool) -> Window {
        let slice = &self.slices[i];
        let snap = (snapped && self.scheme.snaps).then_some(self.snap_rule);
        match &self.scheme.window {
            WindowRule::AxisCentred { centre_depth } => {
                let centre = lp.position + lp.forward * centre_depth[i];
                self.centred(centre, DVec2::splat(self.sphere_side[i]), snap)
            }
            WindowRule::BoxCentred => {
                let (lo, hi) = bounds_2d(&lp.corners(&self.lens, slice.near, slice.far));
                self.centred(0.5 * (lo + hi), DVec2::splat(self.sphere_side[i]), snap)
            }
            WindowRule::Tight { pad, border } => {
                let corners = lp.corners(&self.lens, slice.near, slice.far);
                let (lo, hi) = bounds_2d(&corners);
                let extent = hi - lo + DVec2::splat(2.0 * pad);
                let size = if *border {
                    let shift = self.snap_rule.max_shift_texels();
                    DVec2::new(
                        Window::side_with_border(extent.x, self.resolution, shift),
                        Window::side_with_border(extent.y, self.resolution, shift),
                    )
                } else {
                    extent
                };
                self.centred(0.5 * (lo + hi), size, snap)
            }
            WindowRule::TightAtOrigin => {
                let (lo, hi) = bounds_2d(&lp.corners(&self.lens, slice.near, slice.far));
                self.centred(DVec2::ZERO, hi - lo, snap)
            }
        }
    }

    /// A window centred at `centre`, snapped on the grid through `snap_anchor`.
    fn centred(&self, centre: DVec2, size: DVec2, snap: Option<SnapRule>) -> Window {
        let anchor = self.scheme.snap_anchor;
        if anchor == DVec2::ZERO {
            return Window::centred(centre, size, self.resolution, snap);
        }
        // Snap relative to the anchor, then express the origin relative to the world origin
        // again: a constant (non-integer) offset per cascade, so frame differences of snapped
        // origins stay whole texels.
        let mut w = Window::centred(centre - anchor, size, self.resolution, snap);
        w.origin_texels += anchor / w.texel;
        w
    }

    /// How well cascade `i`'s window `w` covers what it must in the frame of `lp`: its fitted
    /// slice, plus its selection interval where that reaches outside the fitted slice. The
    /// slices and the window are convex, so a slice's light-space footprint is the hull of its
    /// corners and checking the corners is exact.
    pub fn coverage(&self, i: usize, lp: &LightPose, w: &Window) -> FrameCoverage {
        if self.fixed_basis() {
            self.coverage_in(i, lp, w)
        } else {
            self.coverage_in(i, &LightPose::new(&self.basis(i, lp), &lp.pose), w)
        }
    }

    /// [`Rig::coverage`] given the camera frame `lp` in the cascade's own basis.
    pub fn coverage_in(&self, i: usize, lp: &LightPose, w: &Window) -> FrameCoverage {
        let mut out = FrameCoverage::default();
        let n = self.resolution as f64;
        for (near, far) in self.covered_intervals(i) {
            for c in lp.corners(&self.lens, near, far) {
                out.corner(w.texel_coords(c), n, (c / w.texel).abs().max_element());
            }
        }
        out
    }

    /// The depth intervals cascade `i`'s window must cover: its fitted slice, and its
    /// selection interval where that reaches outside the fitted slice.
    pub fn covered_intervals(&self, i: usize) -> impl Iterator<Item = (f64, f64)> {
        let s = &self.slices[i];
        let (a, b) = self.selection(i);
        let outside = b > a && (a < s.near || b > s.far);
        std::iter::once((s.near, s.far)).chain(outside.then_some((a, b)))
    }

    /// Light-space depth range the cascade must render: near far enough toward the light to
    /// keep every caster of the scene that can shadow the window, far enough to cover every
    /// receiver of the slice. Computed from the scene bounds clipped to the window's prism.
    pub fn light_depth_range(&self, i: usize, pose: &CameraPose, window: &Window, scene: &Aabb) -> (f64, f64) {
        let slice = &self.slices[i];
        let n = depth_needs(&self.light, &self.lens, pose, (slice.near, slice.far), window, scene);
        let near = n.casters_near.map_or(n.slice_lo, |a| a.min(n.slice_hi));
        let far = n.receivers.map_or(n.slice_hi, |(_, b)| b);
        (near.min(far), far)
    }

    /// [`Rig::light_depth`]'s `far` alone, bit for bit. Under the scene rule with a fixed basis
    /// the far plane is where the slice leaves the scene, which does not depend on the window:
    /// the caster side (the window's prism against the scene) is skipped. Per-frame cost
    /// counts need only this.
    pub fn light_far(&self, i: usize, lp: &LightPose, window: &Window, scene: &Aabb) -> f64 {
        self.light_far_from(i, lp, window, scene, &mut None)
    }

    /// [`Rig::light_far`], bit for bit, with a hint for the convex intersection's maximum
    /// ([`intersection_max_from`]): the same variable passed for cascade `i` frame after frame
    /// lets each frame start from the candidate that gave the previous frame's far.
    pub fn light_far_from(
        &self,
        i: usize,
        lp: &LightPose,
        window: &Window,
        scene: &Aabb,
        hint: &mut Option<MaxCandidate>,
    ) -> f64 {
        if self.scheme.depth == LightDepthRule::Scene && self.fixed_basis() {
            let s = &self.slices[i];
            return slice_far_in_scene(&self.light, &self.lens, &lp.pose, (s.near, s.far), scene, hint);
        }
        self.light_depth(i, lp, window, scene).far
    }

    /// The light depth range cascade `i` renders under the scheme's rule, and how much of the
    /// scene falls outside it, for the camera frame `lp` and its window `window`.
    pub fn light_depth(&self, i: usize, lp: &LightPose, window: &Window, scene: &Aabb) -> LightDepth {
        if self.scheme.depth == LightDepthRule::Scene && self.fixed_basis() {
            let (near, far) = self.light_depth_range(i, &lp.pose, window, scene);
            return LightDepth {
                near,
                far,
                receivers_outside: 0.0,
                casters_outside: 0.0,
            };
        }
        let basis = self.basis(i, lp);
        let s = &self.slices[i];
        let fitted = depth_needs(&basis, &self.lens, &lp.pose, (s.near, s.far), window, scene);
        // Receivers: the fitted slice and, where it reaches outside, the selection interval.
        let mut receivers = fitted.receivers;
        let (a, b) = self.selection(i);
        if b > a && (a < s.near || b > s.far) {
            let sel = depth_needs(&basis, &self.lens, &lp.pose, (a, b), window, scene);
            receivers = match (receivers, sel.receivers) {
                (Some((p, q)), Some((r, t))) => Some((p.min(r), q.max(t))),
                (x, y) => x.or(y),
            };
        }
        let (slice_lo, slice_hi) = (fitted.slice_lo, fitted.slice_hi);
        let (near, far, keeps_casters) = match &self.scheme.depth {
            LightDepthRule::Scene => {
                let near = fitted.casters_near.map_or(slice_lo, |a| a.min(slice_hi));
                let far = fitted.receivers.map_or(slice_hi, |(_, b)| b);
                (near.min(far), far, true)
            }
            LightDepthRule::Slice { keeps_casters } => (slice_lo, slice_hi, *keeps_casters),
            LightDepthRule::Sphere {
                radius,
                toward_light,
                min_half,
            } => {
                let WindowRule::AxisCentred { centre_depth } = &self.scheme.window else {
                    unreachable!("sphere depth ranges go with axis-centred windows")
                };
                let c = basis.z.dot(lp.pose.position + lp.pose.forward * centre_depth[i]);
                let h = radius[i].max(*min_half);
                (c - h - toward_light, c + h, true)
            }
            LightDepthRule::Margin { margin, near, far } => {
                let plane = slice_lo - margin;
                (plane + near, plane + far, false)
            }
            LightDepthRule::FromPoint { point, near, far } => {
                let p = basis.z.dot(*point);
                (p + near, p + far, false)
            }
            LightDepthRule::Mirrored { eye, pad } => {
                let e = basis.z.dot(*eye);
                let (dmin, dmax) = (slice_lo - e, slice_hi - e);
                (e - dmax - pad, e - dmin + pad, false)
            }
        };
        let receivers_outside = receivers.map_or(0.0, |(lo, hi)| {
            let inside = (hi.min(far) - lo.max(near)).max(0.0);
            (hi - lo) - inside
        });
        let casters_outside = if keeps_casters {
            0.0
        } else {
            fitted.casters_near.map_or(0.0, |c| (near - c).max(0.0))
        };
        LightDepth {
            near,
            far,
            receivers_outside,
            casters_outside,
        }
    }
}

/// Light-depth facts about one slice for one pose, in `basis`.
struct DepthNeeds {
    slice_lo: f64,
    slice_hi: f64,
    /// Nearest scene point within the window's prism (casters that can shadow the window).
    casters_near: Option<f64>,
    /// Light-depth range of the slice within the scene (receivers).
    receivers: Option<(f64, f64)>,
}

fn depth_needs(
    l: &LightBasis,
    lens: &Lens,
    pose: &CameraPose,
    (near, far): (f64, f64),
    window: &Window,
    scene: &Aabb,
) -> DepthNeeds {
    let slice = slice_in_scene(l, lens, pose, (near, far), scene);
    let scene_z = (0..8).map(|c| l.z.dot(scene.corner(c)));
    let (scene_lo, scene_hi) = scene_z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| (a.min(z), b.max(z)));
    // The window's prism along the light, long enough to hold the scene and the slice.
    let lo = window.min();
    let hi = lo + DVec2::new(window.width(), window.height());
    let z0 = scene_lo.min(slice.slice_lo) - 1.0;
    let z1 = scene_hi.max(slice.slice_hi) + 1.0;
    let prism = Hexahedron {
        vertices: Corner::each(|c| l.x * c.x(lo.x, hi.x) + l.y * c.y(lo.y, hi.y) + l.z * c.z(z0, z1)),
        planes: [
            Plane::new(-l.x, -lo.x),
            Plane::new(l.x, hi.x),
            Plane::new(-l.y, -lo.y),
            Plane::new(l.y, hi.y),
            Plane::new(-l.z, -z0),
            Plane::new(l.z, z1),
        ],
    };
    DepthNeeds {
        casters_near: intersection_range(&scene.hexahedron(), &prism, l.z).map(|(a, _)| a),
        ..slice
    }
}

/// [`depth_needs`] without `casters_near` (which alone depends on the window).
fn slice_in_scene(l: &LightBasis, lens: &Lens, pose: &CameraPose, (near, far): (f64, f64), scene: &Aabb) -> DepthNeeds {
    let slice_hex = pose.slice_hexahedron(lens, near, far);
    let slice_z = slice_hex.vertices.iter().map(|v| l.z.dot(*v));
    let (slice_lo, slice_hi) = slice_z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| (a.min(z), b.max(z)));
    DepthNeeds {
        slice_lo,
        slice_hi,
        casters_near: None,
        receivers: intersection_range(&slice_hex, &scene.hexahedron(), l.z),
    }
}

/// The far end of [`slice_in_scene`]'s light depths, bit for bit: the receivers' largest light
/// depth, or the slice's when the slice misses the scene. Only the upper end of the
/// intersection is needed, and [`intersection_max_from`] finds it with fewer inside tests
/// (a per-frame cost, e.g. the cost counts' means over a long path).
fn slice_far_in_scene(
    l: &LightBasis,
    lens: &Lens,
    pose: &CameraPose,
    (near, far): (f64, f64),
    scene: &Aabb,
    hint: &mut Option<MaxCandidate>,
) -> f64 {
    let slice_hex = pose.slice_hexahedron(lens, near, far);
    intersection_max_from(&slice_hex, &scene.hexahedron(), l.z, hint).unwrap_or_else(|| {
        slice_hex
            .vertices
            .iter()
            .map(|v| l.z.dot(*v))
            .fold(f64::NEG_INFINITY, f64::max)
    })
}

/// Look-to basis along `z` whose y axis is the component of `up` perpendicular to `z`, or None
/// when `up` is within acos(0.999) of `z`.
pub fn camera_right_basis(z: DVec3, up: DVec3) -> Option<LightBasis> {
    let up = up.try_normalize()?;
    if up.dot(z).abs() > 0.999 {
        return None;
    }
    let y = (up - z * up.dot(z)).normalize();
    let x = y.cross(z);
    Some(LightBasis {
        x,
        y,
        z,
        vertical_fallback: false,
    })
}

/// The light basis of a look-to along `z` (unit, the way light travels) with the fixed
/// reference `up` (Filament's directional-shadow rule): `y` is `up` with its part along `z`
/// removed, `x = z × y`; when `|up · z| > 0.999`, `up` is first replaced by
/// `(up.z, up.x, up.y)` (+X becomes +Y). None when `up` is zero or still parallel to `z`.
pub fn look_to_basis(z: DVec3, up: DVec3) -> Option<LightBasis> {
    let mut up = up.try_normalize()?;
    if up.dot(z).abs() > 0.999 {
        up = DVec3::new(up.z, up.x, up.y);
    }
    let y = (up - z * up.dot(z)).try_normalize()?;
    let x = z.cross(y);
    Some(LightBasis {
        x,
        y,
        z,
        vertical_fallback: false,
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A rig moved to another resolution equals the rig built at that resolution, field by
    /// field (Debug prints every float so that it reads back exactly), and its windows give the
    /// same texel sizes: for both fits, both snap rules' shifts, from a coarser and a finer
    /// map; and it does differ from the rig it came from.
    #[test]
    fn a_rig_at_another_resolution_equals_the_rig_built_at_it() {
        let lens = Lens::new(1.0, 16.0 / 9.0);
        let light = LightBasis::new(DVec3::new(0.3, -1.0, 0.2).normalize());
        let pose = CameraPose::look_at(DVec3::new(3.0, 2.0, -7.0), DVec3::new(40.0, -1.0, 30.0), DVec3::Y).unwrap();
        let lp = LightPose::new(&light, &pose);
        let splits = splits::practical(0.3, 140.0, 4, 0.6);
        let rules = [
            SnapRule::default(),
            SnapRule {
                mode: crate::snapping::SnapMode::Floor,
                ..SnapRule::default()
            },
        ];
        for fit in [Fit::Sphere, Fit::Aabb] {
            for rule in rules {
                for (from, to) in [(512, 4096), (4096, 1024), (2048, 2048)] {
                    let built = Rig::new(lens, light, fit, to, rule, splits.clone());
                    let mut moved = Rig::new(lens, light, fit, from, rule, splits.clone());
                    moved.set_resolution(to);
                    assert_eq!(format!("{moved:?}"), format!("{built:?}"), "{fit:?} {from} -> {to}");
                    for snapped in [false, true] {
                        for i in 0..built.cascade_count() {
                            let (a, b) = (moved.window(i, &lp, snapped), built.window(i, &lp, snapped));
                            assert_eq!(a.texel_size().to_bits(), b.texel_size().to_bits());
                        }
                    }
                    if from != to {
                        let old = Rig::new(lens, light, fit, from, rule, splits.clone());
                        assert_ne!(format!("{moved:?}"), format!("{old:?}"));
                    }
                }
            }
        }
    }

    #[test]
    fn camera_right_basis_is_orthonormal_right_handed_and_follows_the_camera() {
        let z = DVec3::new(0.3, -1.0, 0.2).normalize();
        for up in [DVec3::X, DVec3::new(0.6, 0.0, 0.8), DVec3::new(-0.2, 0.1, 1.0)] {
            let b = camera_right_basis(z, up).unwrap();
            assert!((b.x.length() - 1.0).abs() < 1e-12 && (b.y.length() - 1.0).abs() < 1e-12);
            assert!(b.x.dot(b.y).abs() < 1e-12 && b.x.dot(b.z).abs() < 1e-12 && b.y.dot(b.z).abs() < 1e-12);
            assert!((b.x.cross(b.y).dot(b.z) - 1.0).abs() < 1e-12);
            // y is the reference direction with its component along the light removed.
            let expected = (up.normalize() - z * up.normalize().dot(z)).normalize();
            assert!((b.y - expected).length() < 1e-12);
        }
        assert!(camera_right_basis(z, z * 3.0).is_none());
    }
}
