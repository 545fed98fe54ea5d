//! The [`Rig`] of a preset: its engine's light basis, window rule, snap rule and light depth
//! around a layout.

use glam::DVec3;

use crate::config::Config;
use csm_core::cascades::{Rig, Scheme};
use csm_core::geometry::Lens;

use super::*;

/// Builds a preset's rig for a layout. `light_direction` is the configured (unit) light
/// direction, from which the engine builds its basis; `near`/`far` the camera planes and
/// `max_distance` the shadow distance the layout was built for. None when no visible depth
/// reads any cascade.
// The camera planes and the shadow distance are three plain numbers a window rule may need.
#[allow(clippy::too_many_arguments)]
pub fn rig_for_layout(
    knobs: &Knobs,
    lens: Lens,
    light_direction: DVec3,
    resolution: u32,
    lay: &Layout,
    near: f64,
    far: f64,
    max_distance: f64,
) -> Option<Rig> {
    let selection = clip_selection(&lay.selection, near, far)?;
    let engine = knobs.engine();
    let light = engine.light_basis(light_direction);
    let rule = engine.snap_rule(knobs);
    let scheme = engine.scheme(
        knobs,
        &Fitting {
            lens,
            light,
            resolution,
            fitted: &lay.fitted,
            snap_rule: rule,
            near,
            far,
            max_distance,
        },
    );
    Some(Rig::with_scheme(
        lens,
        light,
        engine.fit(),
        resolution,
        rule,
        selection,
        &lay.fitted,
        scheme.sides,
        Scheme {
            fit_label: scheme.label.to_string(),
            basis: scheme.basis,
            window: scheme.window,
            snaps: engine.snaps(),
            snap_anchor: scheme.anchor,
            depth: scheme.depth,
        },
    ))
}

/// How the engine of `preset` builds its light basis from a light direction (the basis of
/// every frame under a moving light).
pub(crate) fn light_basis_rule(preset: &Preset) -> fn(DVec3) -> csm_core::geometry::LightBasis {
    preset.knobs.engine().light_basis_fn()
}

/// The rig of a config whose preset is `preset`, or None when no visible depth reads a cascade.
pub fn rig(config: &Config, preset: &Preset) -> Option<Rig> {
    let s = &config.shadow;
    let cam = &config.camera;
    let lay = layout(&preset.knobs, s.cascades, s.max_distance, cam.near, cam.far);
    let lens = Lens::new(cam.fov_y(), config.screen.aspect());
    rig_for_layout(
        &preset.knobs,
        lens,
        config.light_direction,
        s.resolution,
        &lay,
        cam.near,
        cam.far,
        s.max_distance,
    )
}
