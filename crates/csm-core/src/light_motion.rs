//! A light that moves along the path: the direction of every frame, and the direction an
//! engine actually uses for its shadows in that frame.
//!
//! The **true** direction of frame `t` comes from the light path: still (the configured
//! direction in every frame), a sun that turns by fixed compass steps per frame (azimuth and
//! elevation, see [`crate::sun`]), or one direction per frame read from a file. The **used**
//! direction is what the shadow maps are rendered with, after the engine's update rule
//! ([`LightUpdate`]): every frame, every `K` frames (frames `0, K, 2K, ...` take the true
//! direction and the frames between keep it), or snapped to a grid of azimuth and elevation.
//! A frame whose used direction differs from the previous frame's is an **update**; the frame
//! pairs between updates are where crawl is measured, the updates are where jumps happen (see
//! `docs/metrics.md`).

use std::path::PathBuf;

use glam::DVec3;

use crate::geometry::LightBasis;
use crate::sun::SunAngles;

/// How the light direction moves from frame to frame.
#[derive(Debug, Clone, PartialEq)]
pub enum LightPath {
    /// The configured direction in every frame.
    Still,
    /// The sun turns by `azimuth` and `elevation` radians per frame from the configured
    /// direction's compass angles.
    Sun { azimuth: f64, elevation: f64 },
    /// One light direction per frame (unit vectors), read from `path`.
    File { path: PathBuf, directions: Vec<DVec3> },
}

impl LightPath {
    pub fn name(&self) -> &'static str {
        match self {
            LightPath::Still => "still",
            LightPath::Sun { .. } => "sun",
            LightPath::File { .. } => "file",
        }
    }
}

/// How often an engine re-aims its shadow maps at the light.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum LightUpdate {
    /// The used direction is the true one in every frame.
    EveryFrame,
    /// The used direction is the true one of the last frame that is a multiple of `K` (≥ 1).
    EveryFrames(usize),
    /// The used direction's azimuth and elevation are rounded to multiples of this step
    /// (radians, > 0); the elevation is kept within one step above the horizon and the zenith.
    Quantize(f64),
}

/// The light's motion over a path: its path and the engine's update rule.
#[derive(Debug, Clone, PartialEq)]
pub struct LightMotion {
    pub path: LightPath,
    pub update: LightUpdate,
}

impl Default for LightMotion {
    fn default() -> Self {
        LightMotion {
            path: LightPath::Still,
            update: LightUpdate::EveryFrame,
        }
    }
}

impl LightMotion {
    /// True when the used direction can differ between frames. A still light ignores the
    /// update rule: it is the configured direction in every frame, as without light motion.
    pub fn moves(&self) -> bool {
        !matches!(self.path, LightPath::Still)
    }

    /// The true light direction of frame `t`, starting from `start` (the configured unit
    /// direction).
    pub fn direction(&self, start: DVec3, t: usize) -> DVec3 {
        match &self.path {
            LightPath::Still => start,
            LightPath::Sun { azimuth, elevation } => sun_at(start, *azimuth, *elevation, t).light_direction(),
            LightPath::File { directions, .. } => directions[t.min(directions.len() - 1)],
        }
    }

    /// The direction used for the shadows of frame `t`.
    pub fn used_direction(&self, start: DVec3, t: usize) -> DVec3 {
        if !self.moves() {
            return start;
        }
        match self.update {
            LightUpdate::EveryFrame => self.direction(start, t),
            LightUpdate::EveryFrames(k) => self.direction(start, t - t % k.max(1)),
            LightUpdate::Quantize(q) => quantize(self.direction(start, t), q),
        }
    }
}

/// A light motion as a walk reads it: the used direction of each frame, turned into the
/// light basis by the pipeline's own rule (csm-lab's [`LightBasis::new`], or an engine's).
#[derive(Debug, Clone, Copy)]
pub struct LightTrack<'a> {
    pub motion: &'a LightMotion,
    /// The configured unit light direction (frame 0 of a sun path).
    pub start: DVec3,
    /// How the pipeline builds its basis from a light direction.
    pub basis: fn(DVec3) -> LightBasis,
    /// The path frame of the walk's frame 0 (a walk over a later stretch of the path).
    pub first_frame: usize,
}

impl LightTrack<'_> {
    /// The light basis used for the shadows of frame `t`.
    pub fn basis_at(&self, t: usize) -> LightBasis {
        (self.basis)(self.motion.used_direction(self.start, self.first_frame + t))
    }
}

/// The sun of frame `t` of a sun path: the start's compass angles plus `t` steps.
pub fn sun_at(start: DVec3, azimuth_step: f64, elevation_step: f64, t: usize) -> SunAngles {
    let s = SunAngles::of_light_direction(start);
    SunAngles {
        azimuth: s.azimuth + azimuth_step * t as f64,
        elevation: s.elevation + elevation_step * t as f64,
    }
}

/// `direction` with its azimuth and elevation rounded to multiples of `step` radians; the
/// elevation stays within `[step, π/2]` (a sun just above the horizon does not snap onto it).
pub fn quantize(direction: DVec3, step: f64) -> DVec3 {
    let s = SunAngles::of_light_direction(direction);
    let snap = |x: f64| (x / step).round() * step;
    SunAngles {
        azimuth: snap(s.azimuth),
        elevation: snap(s.elevation).clamp(step.min(std::f64::consts::FRAC_PI_2), std::f64::consts::FRAC_PI_2),
    }
    .light_direction()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sun(start_az_deg: f64, start_el_deg: f64) -> DVec3 {
        SunAngles {
            azimuth: start_az_deg.to_radians(),
            elevation: start_el_deg.to_radians(),
        }
        .light_direction()
    }

    #[test]
    fn a_still_light_ignores_the_update_rule() {
        let d = sun(30.0, 40.0);
        let m = LightMotion {
            path: LightPath::Still,
            update: LightUpdate::Quantize(0.1),
        };
        assert_eq!(m.used_direction(d, 17), d);
        assert!(!m.moves());
    }

    #[test]
    fn every_k_frames_holds_the_direction_of_the_last_multiple_of_k() {
        let d = sun(30.0, 40.0);
        let m = LightMotion {
            path: LightPath::Sun {
                azimuth: 0.5f64.to_radians(),
                elevation: -0.25f64.to_radians(),
            },
            update: LightUpdate::EveryFrames(4),
        };
        for t in 0..13 {
            let held = t - t % 4;
            assert_eq!(m.used_direction(d, t), m.direction(d, held), "frame {t}");
        }
        // Frame 6's true direction: 3° east and 1.5° lower than the start.
        let s = SunAngles::of_light_direction(m.direction(d, 6));
        assert!((s.azimuth.to_degrees() - 33.0).abs() < 1e-9);
        assert!((s.elevation.to_degrees() - 38.5).abs() < 1e-9);
    }

    #[test]
    fn quantizing_rounds_both_angles_to_the_grid() {
        let q = 0.5f64.to_radians();
        let s = SunAngles::of_light_direction(quantize(sun(30.2, 40.3), q));
        assert!((s.azimuth.to_degrees() - 30.0).abs() < 1e-9, "{s:?}");
        assert!((s.elevation.to_degrees() - 40.5).abs() < 1e-9, "{s:?}");
        // A sun 0.1° above the horizon stays one step above it.
        let low = SunAngles::of_light_direction(quantize(sun(10.0, 0.1), q));
        assert!((low.elevation.to_degrees() - 0.5).abs() < 1e-9, "{low:?}");
    }
}
