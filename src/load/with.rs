//! Changing a validated [`Config`]: every constructor checks the new value as the file's
//! validation would, re-runs the checks that involve several settings (a valid camera in every
//! frame, binary32 range), and returns a new config or the error naming the key. Sweeps and
//! `bench` build their variants through these, so no unchecked setting reaches the core.

use super::{binary32_range, cross_checks, f64_windows, update_every};
use crate::config::{Config, Fit, MotionPath, Precision, SplitRange, Validator, MAX_WORLD};
use crate::error::Result;

impl Config {
    /// How errors about this config name it: its file, or its name.
    fn label(&self) -> String {
        self.path
            .as_ref()
            .map_or_else(|| self.name.clone(), |p| p.display().to_string())
    }

    /// The "value not allowed" error for `key`, located at this config's file.
    fn refuse(&self, key: &str, value: impl std::fmt::Display, allowed: &str) -> crate::error::Error {
        let label = self.label();
        Validator { path: &label, text: "" }.invalid(key, value, allowed)
    }

    /// The config after changes made outside these constructors (an engine's sweep knobs,
    /// which never move the camera), checked again.
    pub(crate) fn rechecked(self) -> Result<Config> {
        self.checked()
    }

    /// The checks that involve several settings, for a change that kept the camera path:
    /// only the binary32 range and the cached cascades' count can be affected (a loaded config's path is already valid, and
    /// checking it again cost a sweep one path of poses per point).
    fn checked(self) -> Result<Config> {
        let label = self.label();
        let v = Validator { path: &label, text: "" };
        f64_windows(&self, &v, false)?;
        binary32_range(&self, &v)?;
        // A per-cascade `update_every` fits one cascade count: a sweep row of another count is
        // an error, never a row silently rendered every frame.
        update_every(&self, &v)?;
        Ok(self)
    }

    /// The checks for a change of the camera path.
    fn checked_with_path(self) -> Result<Config> {
        let label = self.label();
        cross_checks(&self, &Validator { path: &label, text: "" })?;
        Ok(self)
    }

    fn set_lambda(&mut self, lambda: f64) -> Result<()> {
        if !(0.0..=1.0).contains(&lambda) {
            return Err(self.refuse("shadow.lambda", lambda, "a number in [0, 1] (0 uniform, 1 logarithmic)"));
        }
        self.shadow.lambda = lambda;
        // A λ replaces explicit split fractions: the practical split applies again.
        self.shadow.splits = None;
        Ok(())
    }

    fn set_cascades(&mut self, n: usize) -> Result<()> {
        if !(1..=16).contains(&n) {
            return Err(self.refuse("shadow.cascades", n, "an integer in 1..=16"));
        }
        self.shadow.cascades = n;
        // Explicit split fractions hold for one count only.
        if self.shadow.splits.is_some_and(|f| f.len() + 1 != n) {
            self.shadow.splits = None;
        }
        Ok(())
    }

    fn set_resolution(&mut self, n: u32) -> Result<()> {
        if !(16..=16384).contains(&n) {
            return Err(self.refuse("shadow.resolution", n, "an integer in 16..=16384"));
        }
        self.shadow.resolution = n;
        Ok(())
    }

    /// The config with `shadow.lambda` set.
    pub fn with_lambda(&self, lambda: f64) -> Result<Config> {
        let mut c = self.clone();
        c.set_lambda(lambda)?;
        c.checked()
    }

    /// The config with explicit split fractions (`shadow.splits`: one fewer than the cascades,
    /// strictly increasing inside (0, 1)) instead of the practical split.
    pub fn with_splits(&self, fractions: &[f64]) -> Result<Config> {
        let mut c = self.clone();
        let n = c.shadow.cascades;
        match csm_core::free_splits::SplitFractions::new(fractions) {
            Some(f) if f.len() + 1 == n => c.shadow.splits = Some(f),
            _ => {
                return Err(self.refuse(
                    "shadow.splits",
                    format!("{fractions:?}"),
                    &format!(
                        "{} fractions (shadow.cascades − 1), strictly increasing and strictly between 0 and 1",
                        n - 1
                    ),
                ))
            }
        }
        c.checked()
    }

    /// The config with `shadow.cascades` set.
    pub fn with_cascades(&self, n: usize) -> Result<Config> {
        let mut c = self.clone();
        c.set_cascades(n)?;
        c.checked()
    }

    /// The config with `shadow.resolution` set.
    pub fn with_resolution(&self, n: u32) -> Result<Config> {
        let mut c = self.clone();
        c.set_resolution(n)?;
        c.checked()
    }

    /// The config with `shadow.fit` set.
    pub fn with_fit(&self, fit: Fit) -> Result<Config> {
        let mut c = self.clone();
        c.shadow.fit = fit;
        c.checked()
    }

    /// The config with `shadow.precision` set.
    pub(crate) fn with_precision(&self, precision: Precision) -> Result<Config> {
        let mut c = self.clone();
        c.shadow.precision = precision;
        c.checked()
    }

    /// One point of a sweep of csm-lab's own pipeline: λ, cascade count, map size and fit,
    /// checked together (one cross-check for the four).
    pub fn with_sweep_point(
        &self,
        lambda: f64,
        cascades: usize,
        resolution: u32,
        fit: Fit,
        range: SplitRange,
    ) -> Result<Config> {
        let mut c = self.clone();
        c.set_lambda(lambda)?;
        c.set_cascades(cascades)?;
        c.set_resolution(resolution)?;
        c.shadow.fit = fit;
        c.set_split_range(range)?;
        c.checked()
    }

    /// The splits on the bounds' depth range or on the visible depths (`fit_depth_to_visible`),
    /// which needs scene geometry.
    pub(crate) fn with_split_range(&self, range: SplitRange) -> Result<Config> {
        let mut c = self.clone();
        c.set_split_range(range)?;
        c.checked()
    }

    fn set_split_range(&mut self, range: SplitRange) -> Result<()> {
        if range.is_visible() && self.geometry.is_none() {
            return Err(self.refuse(
                "shadow.fit_depth_to_visible",
                true,
                "false without scene geometry (the bounds alone show no visible depth)",
            ));
        }
        self.shadow.fit_depth_to_visible = range.is_visible();
        Ok(())
    }

    /// The config with a generated motion path (not a path file): `frames` poses, `step` as a
    /// config file would write it (world units per frame, or degrees for the rotations).
    pub(crate) fn with_motion(&self, path: MotionPath, frames: usize, step_as_written: f64) -> Result<Config> {
        let v = |key: &str, value: &dyn std::fmt::Display, allowed: &str| self.refuse(key, value, allowed);
        if matches!(path, MotionPath::File { .. }) {
            return Err(v(
                "motion.path",
                &"\"file\"",
                &format!(
                    "a generated path ({})",
                    MotionPath::GENERATED.map(|p| p.name()).join(", ")
                ),
            ));
        }
        if !(2..=1_000_000).contains(&frames) {
            return Err(v("motion.frames", &frames, "an integer in 2..=1000000"));
        }
        if !step_as_written.is_finite() {
            return Err(v("motion.step", &step_as_written, "a finite number"));
        }
        if path.is_translation() && step_as_written.abs() * (frames - 1) as f64 > MAX_WORLD {
            return Err(v(
                "motion.step",
                &step_as_written,
                &format!("a step whose {frames} frames travel at most 1e9 world units"),
            ));
        }
        let step = path.step_from_written(step_as_written);
        let mut c = self.clone();
        c.motion.path = path;
        c.motion.frames = frames;
        c.motion.step = step;
        c.motion.step_as_written = step_as_written;
        c.checked_with_path()
    }

    /// The config with the light travelling along `direction` (any non-zero length, normalised
    /// exactly as `light.direction` in a file is), as a sun-angle sweep sets it.
    pub fn with_light_direction(&self, direction: glam::DVec3) -> Result<Config> {
        let len = direction.length();
        if !(direction.is_finite() && len > 1e-12 && len.is_finite()) {
            return Err(self.refuse(
                "light.direction",
                format!("{:?}", direction.to_array()),
                "a non-zero vector (the direction light travels)",
            ));
        }
        let mut c = self.clone();
        c.light_direction = direction / len;
        c.light_direction_as_written = direction;
        c.checked()
    }
}
