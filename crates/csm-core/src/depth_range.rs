//! Scene-aware depth range: split only the depths where the scene can be seen.
//!
//! Depths are view depths (world units along the camera's forward axis, see
//! [`crate::geometry`]).
//!
//! With `fit_depth_to_scene`, the scene's bounding box is intersected with the view frustum
//! (clipped at `min(far, max_distance)`) and the split range is the view-depth extent of that
//! intersection: `z_lo = max(near, nearest)`, `z_hi = min(far, max_distance, farthest)`. View depth is
//! linear, so the extremes sit at vertices of the (convex) intersection; see
//! [`crate::geometry::intersection_range`]. Without it the range is `[near, min(far, max_distance)]`.
//!
//! With `fit_depth_to_visible` (scene geometry only), the range is then narrowed to the view
//! depths of the geometry the visibility pass sees (what SDSM reads from the depth buffer).

use crate::geometry::{intersection_range, Aabb, CameraPose, Lens};
use crate::scene::Setup;

/// Where cascades are needed along the view axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DepthRange {
    /// Split `[z_lo, z_hi]`.
    Range { z_lo: f64, z_hi: f64 },
    /// The scene is not visible within the shadow distance: no cascades are needed.
    Empty,
}

impl DepthRange {
    pub fn bounds(&self) -> Option<(f64, f64)> {
        match *self {
            DepthRange::Range { z_lo, z_hi } => Some((z_lo, z_hi)),
            DepthRange::Empty => None,
        }
    }
}

/// The split range for one camera pose.
pub fn receiver_range(
    pose: &CameraPose,
    lens: &Lens,
    near: f64,
    shadow_far: f64,
    scene: &Aabb,
    fit_to_scene: bool,
) -> DepthRange {
    // A shadow distance at or below the near plane leaves nothing to split, with or without
    // scene clipping (unclipped, it used to give a decreasing range).
    if shadow_far <= near {
        return DepthRange::Empty;
    }
    if !fit_to_scene {
        // The same "thinner than a relative 1e-9" rule as below: a shadow distance at (or
        // before) the near plane leaves nothing to split.
        return if shadow_far > near * (1.0 + 1e-9) {
            DepthRange::Range {
                z_lo: near,
                z_hi: shadow_far,
            }
        } else {
            DepthRange::Empty
        };
    }
    let frustum = pose.slice_hexahedron(lens, near, shadow_far);
    match intersection_range(&frustum, &scene.hexahedron(), pose.forward) {
        Some((lo, hi)) => {
            let depth0 = pose.forward.dot(pose.position);
            let z_lo = (lo - depth0).max(near);
            let z_hi = (hi - depth0).min(shadow_far);
            // A range thinner than a relative 1e-9 is a touching contact: nothing to shadow.
            if z_hi > z_lo * (1.0 + 1e-9) {
                DepthRange::Range { z_lo, z_hi }
            } else {
                DepthRange::Empty
            }
        }
        None => DepthRange::Empty,
    }
}

/// The split range of a set-up's own camera (frame 0); Empty when its camera is invalid.
pub fn for_setup(setup: &Setup) -> DepthRange {
    let Some(pose) = setup.camera.pose() else {
        return DepthRange::Empty;
    };
    let bounds = receiver_range(
        &pose,
        &setup.camera.lens(),
        setup.camera.near,
        setup.shadow_far(),
        &setup.bounds,
        setup.shadow.fit_depth_to_scene,
    );
    if !setup.shadow.fit_depth_to_visible {
        return bounds;
    }
    // Fitted to what is visible: the visible geometry's depth extent within the bounds' range.
    let (Some((lo, hi)), Some(vis)) = (bounds.bounds(), setup.visibility()) else {
        return DepthRange::Empty;
    };
    match crate::screen::visible_range(&vis, lo, hi) {
        Some((z_lo, z_hi)) if z_hi > z_lo * (1.0 + 1e-9) => DepthRange::Range { z_lo, z_hi },
        _ => DepthRange::Empty,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Brute-force oracle: dense sampling of points in the box, keeping those in the frustum.
    fn sampled(pose: &CameraPose, lens: &Lens, near: f64, far: f64, scene: &Aabb) -> Option<(f64, f64)> {
        let n = 60;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    let t = DVec3::new(i as f64, j as f64, k as f64) / n as f64;
                    let p = scene.min + (scene.max - scene.min) * t;
                    let d = pose.depth(p);
                    let q = p - pose.position;
                    if d >= near
                        && d <= far
                        && pose.right.dot(q).abs() <= lens.tan_h * d
                        && pose.up.dot(q).abs() <= lens.tan_v * d
                    {
                        lo = lo.min(d);
                        hi = hi.max(d);
                    }
                }
            }
        }
        (lo <= hi).then_some((lo, hi))
    }

    #[test]
    fn clipped_range_contains_and_nearly_equals_dense_samples() {
        let lens = Lens::new(60f64.to_radians(), 16.0 / 9.0);
        let scene = Aabb::new(DVec3::new(-200.0, 0.0, -200.0), DVec3::new(200.0, 40.0, 200.0));
        let poses = [
            (DVec3::new(0.0, 10.0, 0.0), DVec3::new(0.0, 0.0, -50.0)),
            (DVec3::new(0.0, 300.0, 0.0), DVec3::new(10.0, 0.0, -1.0)),
            (DVec3::new(-400.0, 20.0, 0.0), DVec3::new(0.0, 20.0, 0.0)),
        ];
        for (pos, target) in poses {
            let pose = CameraPose::look_at(pos, target, DVec3::Y).unwrap();
            let DepthRange::Range { z_lo, z_hi } = receiver_range(&pose, &lens, 0.1, 1000.0, &scene, true) else {
                panic!("expected a range");
            };
            let (slo, shi) = sampled(&pose, &lens, 0.1, 1000.0, &scene).unwrap();
            assert!(z_lo <= slo + 1e-9 && z_hi >= shi - 1e-9, "{z_lo} {z_hi} vs {slo} {shi}");
            // The exact range is at most one sample spacing wider than the samples.
            let spacing = 400.0 / 60.0 * 2.0;
            assert!(
                slo - z_lo < spacing && z_hi - shi < spacing,
                "{z_lo} {z_hi} vs {slo} {shi}"
            );
        }
    }

    /// Regression (found by the property tests): without scene fitting, a shadow distance
    /// shorter than the near plane gave a reversed range, and the aggregates panicked.
    #[test]
    fn a_shadow_distance_before_the_near_plane_needs_no_cascades() {
        let lens = Lens::new(1.0, 1.5);
        let pose = CameraPose::look_at(DVec3::ZERO, DVec3::NEG_Z, DVec3::Y).unwrap();
        let scene = Aabb::new(DVec3::splat(-10.0), DVec3::splat(10.0));
        for fit in [false, true] {
            assert_eq!(receiver_range(&pose, &lens, 9.0, 8.3, &scene, fit), DepthRange::Empty);
            assert_eq!(receiver_range(&pose, &lens, 9.0, 9.0, &scene, fit), DepthRange::Empty);
        }
        assert_eq!(
            receiver_range(&pose, &lens, 0.5, 8.3, &scene, false),
            DepthRange::Range { z_lo: 0.5, z_hi: 8.3 }
        );
    }

    #[test]
    fn scene_behind_the_camera_needs_no_cascades() {
        let lens = Lens::new(1.0, 1.5);
        let pose = CameraPose::look_at(DVec3::ZERO, DVec3::NEG_Z, DVec3::Y).unwrap();
        let scene = Aabb::new(DVec3::new(-1.0, -1.0, 1.0), DVec3::new(1.0, 1.0, 3.0));
        assert_eq!(
            receiver_range(&pose, &lens, 0.1, 100.0, &scene, true),
            DepthRange::Empty
        );
        // Beyond the shadow distance is empty too.
        let far = Aabb::new(DVec3::new(-1.0, -1.0, -300.0), DVec3::new(1.0, 1.0, -200.0));
        assert_eq!(receiver_range(&pose, &lens, 0.1, 150.0, &far, true), DepthRange::Empty);
    }

    /// Regression (found by `csm-lab stress`): a shadow distance below the near plane without
    /// scene clipping gave the range [near, shadow_far] backwards, and the analysis panicked.
    #[test]
    fn a_shadow_distance_below_the_near_plane_needs_no_cascades_with_or_without_clipping() {
        let lens = Lens::new(1.0, 1.5);
        let pose = CameraPose::look_at(DVec3::ZERO, DVec3::NEG_Z, DVec3::Y).unwrap();
        let scene = Aabb::new(DVec3::splat(-100.0), DVec3::splat(100.0));
        for fit in [false, true] {
            for shadow_far in [0.05, 0.1] {
                assert_eq!(
                    receiver_range(&pose, &lens, 0.1, shadow_far, &scene, fit),
                    DepthRange::Empty,
                    "{fit} {shadow_far}"
                );
            }
            assert!(receiver_range(&pose, &lens, 0.1, 0.2, &scene, fit).bounds().is_some());
        }
    }
}
