//! Fits, snapping, light basis and light depth: the [`Rig`] of a preset.

use glam::DVec2;

use crate::cascades::{BasisRule, LightDepthRule, Rig, Scheme, WindowRule};
use crate::config::{Config, Fit};
use crate::fitting::{corner_average_sphere, far_cap_sphere, minimal_sphere, slice_diameter, Sphere, Window};
use crate::geometry::{Lens, LightBasis};
use crate::snapping::{SnapMode, SnapRule};

use super::*;

/// Unreal's bounding sphere of a slice: centre depth `far − offset` clamped to the slice, with
/// `offset = (Db² − Da²)/(2L) + L/2`, radius the largest corner distance, at least 1 cm.
pub fn unreal_sphere(near: f64, far: f64, lens: &Lens) -> Sphere {
    let da2 = (lens.tan_h * far).powi(2) + (lens.tan_v * far).powi(2);
    let db2 = (lens.tan_h * near).powi(2) + (lens.tan_v * near).powi(2);
    let l = far - near;
    let offset = (db2 - da2) / (2.0 * l) + 0.5 * l;
    let c = (far - offset).clamp(near, far);
    let r_near = (db2 + (c - near).powi(2)).sqrt();
    let r_far = (da2 + (far - c).powi(2)).sqrt();
    Sphere {
        centre_depth: c,
        radius: r_near.max(r_far).max(0.01),
    }
}

/// Unreal's border per side, in texels (modelled as the 4-texel snap step).
pub const UNREAL_BORDER_TEXELS: f64 = 4.0;

/// Bevy's window side: the slice diameter rounded up to a whole world unit.
pub fn bevy_window_side(near: f64, far: f64, k2: f64) -> f64 {
    slice_diameter(near, far, k2).ceil()
}

/// The family of csm-lab's fits a preset's window belongs to.
pub(crate) fn fit_family(k: &Knobs) -> Fit {
    match k {
        Knobs::UnitySample(_) | Knobs::LearnOpenGl(_) => Fit::Aabb,
        _ => Fit::Sphere,
    }
}

pub(crate) fn snaps(k: &Knobs) -> bool {
    !matches!(k, Knobs::UnitySample(_) | Knobs::LearnOpenGl(_))
}

pub(crate) fn snap_rule(k: &Knobs) -> SnapRule {
    let (mode, step) = match k {
        Knobs::Threejs(_) | Knobs::Bevy(_) => (SnapMode::Floor, 1),
        Knobs::Godot(_) => (SnapMode::Round, 2),
        Knobs::Unreal(_) => (SnapMode::Trunc, 4),
        Knobs::Filament(_) => (SnapMode::Trunc, 2),
        _ => (SnapMode::Round, 1),
    };
    SnapRule {
        mode,
        step_texels: step,
    }
}

/// Builds a preset's rig for a layout. `light` is the configured light basis; `near`/`far`
/// the camera planes. None when no visible depth reads any cascade.
pub fn rig_for_layout(
    knobs: &Knobs,
    lens: Lens,
    light: LightBasis,
    resolution: u32,
    lay: &Layout,
    near: f64,
    far: f64,
) -> Option<Rig> {
    let selection = clip_selection(&lay.selection, near, far)?;
    let k2 = lens.k2();
    let n = resolution as f64;
    let fitted = &lay.fitted;
    let each = |f: &dyn Fn(f64, f64) -> f64| -> Vec<f64> { fitted.iter().map(|&(a, b)| f(a, b)).collect() };
    let spheres = |f: &dyn Fn(f64, f64) -> Sphere| -> Vec<Sphere> { fitted.iter().map(|&(a, b)| f(a, b)).collect() };
    let rule = snap_rule(knobs);
    let axis = |s: &[Sphere]| WindowRule::AxisCentred {
        centre_depth: s.iter().map(|s| s.centre_depth).collect(),
    };
    // A sphere of radius r on `usable` of the map's N texels: window side 2r·N/usable.
    let on = |s: &[Sphere], usable: f64| -> Vec<f64> { s.iter().map(|s| 2.0 * s.radius * n / usable).collect() };
    let (label, window, sides, basis, anchor, depth) = match knobs {
        Knobs::Dart(_) => {
            let s = spheres(&|a, b| corner_average_sphere(a, b, k2));
            (
                "sphere-average",
                axis(&s),
                on(&s, n),
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Scene,
            )
        }
        Knobs::Threejs(t) => (
            "diameter",
            WindowRule::BoxCentred,
            each(&|a, b| slice_diameter(a, b, k2)),
            BasisRule::Fixed,
            DVec2::ZERO,
            LightDepthRule::Margin {
                margin: t.light_margin,
                near: t.light_near,
                far: t.light_far,
            },
        ),
        Knobs::UnitySample(u) => (
            if u.centre_on_slice { "aabb" } else { "aabb-at-origin" },
            if u.centre_on_slice {
                WindowRule::Tight {
                    pad: 0.0,
                    border: false,
                }
            } else {
                WindowRule::TightAtOrigin
            },
            each(&|a, b| 2.0 * minimal_sphere(a, b, k2).radius),
            BasisRule::Fixed,
            DVec2::ZERO,
            LightDepthRule::Slice { keeps_casters: false },
        ),
        Knobs::Eevee(e) => {
            let s = spheres(&|a, b| far_cap_sphere(a, b, k2));
            (
                "sphere-far-cap",
                axis(&s),
                on(&s, n),
                BasisRule::Fixed,
                light.to_light_xy(e.lamp_position),
                LightDepthRule::FromPoint {
                    point: e.lamp_position,
                    near: e.clip_start,
                    far: e.clip_end,
                },
            )
        }
        Knobs::LearnOpenGl(l) => (
            "aabb-padded",
            WindowRule::Tight {
                pad: l.pad_xy,
                border: false,
            },
            each(&|a, b| 2.0 * minimal_sphere(a, b, k2).radius),
            BasisRule::LookAtFrom(l.light_position),
            DVec2::ZERO,
            LightDepthRule::Mirrored {
                eye: l.light_position,
                pad: l.pad_z,
            },
        ),
        Knobs::Bevy(_) => (
            "diameter-ceil",
            WindowRule::BoxCentred,
            each(&|a, b| bevy_window_side(a, b, k2)),
            BasisRule::Fixed,
            DVec2::ZERO,
            LightDepthRule::Slice { keeps_casters: true },
        ),
        Knobs::Godot(g) => {
            let s = spheres(&|a, b| corner_average_sphere(a, b, k2));
            // r·T/(T − 2): one texel of border per side.
            let sides = on(&s, n - 2.0);
            (
                "sphere-average+border",
                axis(&s),
                sides.clone(),
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Sphere {
                    radius: sides.iter().map(|w| 0.5 * w).collect(),
                    toward_light: g.pancake_size,
                    min_half: 0.0,
                },
            )
        }
        Knobs::Unreal(_) => {
            let s = spheres(&|a, b| unreal_sphere(a, b, &lens));
            (
                "sphere-minimal+border",
                axis(&s),
                on(&s, n - 2.0 * UNREAL_BORDER_TEXELS),
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Sphere {
                    radius: s.iter().map(|s| s.radius).collect(),
                    toward_light: 0.0,
                    min_half: 50.0,
                },
            )
        }
        Knobs::Unity(_) | Knobs::UnityUrp(_) => {
            let s = spheres(&|a, b| minimal_sphere(a, b, k2));
            let sides = s
                .iter()
                .map(|s| Window::side_with_border(2.0 * s.radius, resolution, rule.max_shift_texels()))
                .collect();
            (
                "sphere",
                axis(&s),
                sides,
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Scene,
            )
        }
        Knobs::Filament(_) => {
            let s = spheres(&|a, b| corner_average_sphere(a, b, k2));
            (
                "sphere-average+border",
                axis(&s),
                // mapSize − 2 usable texels: one texel of border per side.
                on(&s, n - 2.0),
                BasisRule::CameraRight,
                DVec2::ZERO,
                LightDepthRule::Scene,
            )
        }
    };
    Some(Rig::with_scheme(
        lens,
        light,
        fit_family(knobs),
        resolution,
        rule,
        selection,
        fitted,
        sides,
        Scheme {
            fit_label: label.to_string(),
            basis,
            window,
            snaps: snaps(knobs),
            snap_anchor: anchor,
            depth,
        },
    ))
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
        LightBasis::new(config.light_direction),
        s.resolution,
        &lay,
        cam.near,
        cam.far,
    )
}
