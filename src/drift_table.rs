//! The drift table of `docs/accuracy.md`: snapped S3 and S7 of one sphere-fit cascade against
//! the world offset, for the exact f64 pipeline and the emulated binary32 one in both snap
//! spaces. Each row is an ordinary config run through the ordinary analysis.

use crate::config::Config;
use csm_core::precision::ulp32;
use csm_core::scene::{Precision, SnapSpace};

/// World offsets of the drift table (world units, along +x).
pub const DRIFT_OFFSETS: [f64; 5] = [0.0, 1e3, 1e4, 1e5, 1e6];
/// Window sides of the drift table (world units, snapping border included), at 2048².
pub const DRIFT_WINDOWS: [f64; 2] = [20.0, 200.0];
/// Camera strafe per frame (world units) and path length of the drift table.
pub(crate) const DRIFT_STEP: f64 = 0.0137;
pub(crate) const DRIFT_FRAMES: usize = 120;
pub(crate) const DRIFT_PROBES: usize = 256;
const DRIFT_RESOLUTION: u32 = 2048;

/// One row of the drift table: one window size, world offset and arithmetic.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DriftRow {
    /// Window side (world units) and texel size.
    pub window: f64,
    pub texel: f64,
    pub offset: f64,
    pub precision: Precision,
    pub snap_space: SnapSpace,
    /// Snapped S3 over the path: largest and RMS per-frame drift (texels).
    pub drift_max: f64,
    pub drift_rms: f64,
    /// S7 largest (texels; 0 in f64).
    pub lookup_error_max: f64,
    /// `ulp32(|u|)/T` with `u` the camera's light-space x/y (larger axis): the expected scale.
    pub ulp32_over_texel: f64,
    pub coverage_violations: u64,
}

/// The drift-table scene as config text: the default outdoor camera strafing
/// [`DRIFT_STEP`] per frame, one sphere-fit cascade from 0.1 to a far distance chosen so
/// that its snapped window is `window` units wide at 2048², everything moved by
/// `[offset, 0, 0]`.
pub(crate) fn drift_scene_toml(window: f64, offset: f64, precision: Precision, space: SnapSpace) -> String {
    let lens = csm_core::geometry::Lens::new(60f64.to_radians(), 1920.0 / 1080.0);
    let n = DRIFT_RESOLUTION as f64;
    // Far-cap case of the minimal sphere (c = f, R = k f, which holds for k^2 >= 1), and the
    // round rule's border W = 2R N / (N - 1): solve for the far distance.
    let far = window * (n - 1.0) / (2.0 * lens.k2().sqrt() * n);
    format!(
        r#"[camera]
position = [0.0, 10.0, 0.0]
target = [0.0, 0.0, -50.0]
fov_y_deg = 60.0
near = 0.1
far = 1000.0

[screen]
width = 1920
height = 1080

[light]
direction = [-0.4, -1.0, -0.3]

[scene]
min = [-1000.0, -1000.0, -1000.0]
max = [1000.0, 1000.0, 1000.0]
world_offset = [{offset:?}, 0.0, 0.0]

[shadow]
max_distance = {far:?}
cascades = 1
resolution = {DRIFT_RESOLUTION}
fit = "sphere"
snap = true
fit_depth_to_scene = false
precision = "{precision}"
snap_space = "{space}"

[motion]
path = "strafe"
frames = {DRIFT_FRAMES}
step = {DRIFT_STEP:?}

[analysis]
probes = {DRIFT_PROBES}
"#
    )
}

/// Measures one drift-table row through the ordinary config and analysis path.
pub(crate) fn drift_row(window: f64, offset: f64, precision: Precision, space: SnapSpace) -> crate::Result<DriftRow> {
    let text = drift_scene_toml(window, offset, precision, space);
    let config = Config::from_toml_str(&text, "drift-table", None)?;
    let a = crate::analysis::analyze(&config, &crate::analysis::AnalysisOptions::summary_only());
    let rig = a.rig().ok_or_else(|| {
        crate::error::Error::from(crate::error::GridError::Unusable {
            context: "drift table".into(),
            message: "the scene needs no cascade".into(),
        })
    })?;
    let snapped = a.snapped().expect("a rig implies a path");
    let texel = rig.sphere_side[0] / rig.resolution as f64;
    let u = rig.light.to_light_xy(config.camera.position).abs().max_element();
    Ok(DriftRow {
        window: rig.sphere_side[0],
        texel,
        offset,
        precision,
        snap_space: space,
        drift_max: snapped.stats.max,
        drift_rms: snapped.stats.rms,
        lookup_error_max: a.summary.lookup_error_max,
        ulp32_over_texel: ulp32(u) / texel,
        coverage_violations: a.summary.coverage_violations,
    })
}

/// Every row of the table: windows x offsets x {f64, f32 world, f32 camera-relative}, in that
/// order (computed in parallel, collected in order).
pub fn drift_table() -> crate::Result<Vec<DriftRow>> {
    use rayon::prelude::*;
    let mut specs = Vec::new();
    for &w in &DRIFT_WINDOWS {
        for &o in &DRIFT_OFFSETS {
            for (p, s) in [
                (Precision::F64, SnapSpace::World),
                (Precision::F32, SnapSpace::World),
                (Precision::F32, SnapSpace::CameraRelative),
            ] {
                specs.push((w, o, p, s));
            }
        }
    }
    specs.par_iter().map(|&(w, o, p, s)| drift_row(w, o, p, s)).collect()
}

/// The table as Markdown: one line per window and offset.
pub fn drift_table_markdown(rows: &[DriftRow]) -> String {
    use std::fmt::Write as _;
    let mut out = String::from(
        "| window | offset | ulp32/T | f64 drift max | f32 world drift max (RMS) | f32 world S7 max \
         | f32 camera-relative drift max (RMS) | f32 camera-relative S7 max |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    let find = |w: f64, o: f64, p: Precision, s: SnapSpace| {
        rows.iter()
            .find(|r| r.window == w && r.offset == o && r.precision == p && r.snap_space == s)
    };
    let mut keys: Vec<(f64, f64)> = Vec::new();
    for r in rows {
        if !keys.contains(&(r.window, r.offset)) {
            keys.push((r.window, r.offset));
        }
    }
    let g = |v: f64| if v == 0.0 { "0".to_string() } else { format!("{v:.2e}") };
    for (w, o) in keys {
        let f64r = find(w, o, Precision::F64, SnapSpace::World);
        let wr = find(w, o, Precision::F32, SnapSpace::World);
        let cr = find(w, o, Precision::F32, SnapSpace::CameraRelative);
        let cell = |r: Option<&DriftRow>, f: &dyn Fn(&DriftRow) -> String| r.map_or("–".to_string(), f);
        let _ = writeln!(
            out,
            "| {:.0} ({:.2} mm texels) | {} | {} | {} | {} | {} | {} | {} |",
            w,
            1000.0 * w / DRIFT_RESOLUTION as f64,
            if o == 0.0 { "0".to_string() } else { format!("{o:.0e}") },
            cell(wr.or(f64r), &|r| format!("{:.3}", r.ulp32_over_texel)),
            cell(f64r, &|r| g(r.drift_max)),
            cell(wr, &|r| format!("{} ({})", g(r.drift_max), g(r.drift_rms))),
            cell(wr, &|r| g(r.lookup_error_max)),
            cell(cr, &|r| format!("{} ({})", g(r.drift_max), g(r.drift_rms))),
            cell(cr, &|r| g(r.lookup_error_max)),
        );
    }
    out
}
