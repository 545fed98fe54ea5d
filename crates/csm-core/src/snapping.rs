//! Texel snapping: move a window only in whole texel steps on a grid anchored at the world
//! origin.
//!
//! Light space has no translation (see [`crate::geometry`]), so "a whole multiple of the texel
//! size in light space" is a grid through the world origin that every frame shares. A static
//! point then lands at the same texel coordinate plus an integer in every frame, which is what
//! removes shimmer. Snapping works in *texel units* (light coordinate / texel size) so that the
//! snapped value is an exact integer in floating point and frame-to-frame differences of texel
//! coordinates are exact integers too, even a million units from the origin.

use crate::shimmer::{floor_exact, round_half_away};

/// How an engine rounds the window centre onto its grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SnapMode {
    /// Nearest grid line (Godot, EEVEE, Valient/MJP). Moves the centre by at most half a step.
    Round,
    /// Toward -infinity (Bevy, three.js, DirectX sample). Moves it by up to a whole step.
    Floor,
    /// Toward zero, as `x - fmod(x, step)` does (Filament, Unreal). Up to a whole step, and
    /// the direction flips sign at the origin.
    Trunc,
}

/// A snapping rule: rounding mode and grid step in texels (1, 2 or 4 in engines).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct SnapRule {
    pub mode: SnapMode,
    pub step_texels: u32,
}

impl Default for SnapRule {
    fn default() -> Self {
        SnapRule {
            mode: SnapMode::Round,
            step_texels: 1,
        }
    }
}

impl SnapRule {
    /// Snap a coordinate given in texels to the rule's grid.
    pub fn apply(&self, texels: f64) -> f64 {
        let step = self.step_texels as f64;
        let q = texels / step;
        // The inlined roundings are `f64::round` and `f64::floor` bit for bit, without the libm
        // call baseline x86-64 makes for them (this runs per cascade, frame and snap mode).
        let snapped = match self.mode {
            SnapMode::Round => round_half_away(q),
            SnapMode::Floor => floor_exact(q),
            SnapMode::Trunc => q.trunc(),
        };
        snapped * step
    }

    /// The largest distance, in texels, that snapping can move a centre. A window needs at
    /// least this much border on each side to keep its slice inside after snapping.
    pub fn max_shift_texels(&self) -> f64 {
        match self.mode {
            SnapMode::Round => 0.5 * self.step_texels as f64,
            SnapMode::Floor | SnapMode::Trunc => self.step_texels as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapped_values_are_whole_steps_within_the_stated_shift() {
        for mode in [SnapMode::Round, SnapMode::Floor, SnapMode::Trunc] {
            for step in [1, 2, 4] {
                let rule = SnapRule {
                    mode,
                    step_texels: step,
                };
                for i in -1000..1000 {
                    let x = i as f64 * 0.377 + 1e6 * (i % 3) as f64;
                    let s = rule.apply(x);
                    assert_eq!(s % step as f64, 0.0);
                    assert!((s - x).abs() <= rule.max_shift_texels() + 1e-9, "{mode:?} {x} {s}");
                }
            }
        }
        assert_eq!(SnapRule::default().apply(-2.5), -3.0);
        assert_eq!(
            SnapRule {
                mode: SnapMode::Trunc,
                step_texels: 2
            }
            .apply(-3.9),
            -2.0
        );
    }
}
