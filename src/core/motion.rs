//! Camera paths for the shimmer metrics: one camera pose per frame, frame 0 being the
//! configured camera. Translations are in world units per frame, rotations in radians per
//! frame (converted from degrees in [`crate::config`]).

use crate::error::IoError;
use std::path::Path;

use glam::{DQuat, DVec3};

use crate::config::{Config, MotionPath};
use crate::error::{Error, Result};
use crate::geometry::CameraPose;

/// Poses for every frame of the config's motion path, or the first frame whose camera is
/// invalid (up parallel to the view direction, position equal to target) and why.
pub fn camera_path(config: &Config) -> std::result::Result<Vec<CameraPose>, (usize, String)> {
    let cam = &config.camera;
    let up = cam.up;
    let frames = config.motion.frames;
    let step = config.motion.step;
    let pose0 = CameraPose::look_at(cam.position, cam.target, up)
        .ok_or((0, "camera.up is parallel to the view direction".to_string()))?;
    let dir0 = cam.target - cam.position;
    let bad = |t: usize| (t, "the view direction becomes parallel to camera.up".to_string());
    let mut poses = Vec::with_capacity(frames);
    match &config.motion.path {
        MotionPath::File { poses: rows, .. } => {
            for (t, (p, target)) in rows.iter().enumerate() {
                let pose = CameraPose::look_at(*p, *target, up).ok_or((
                    t,
                    "position equals target, or the view direction is parallel to camera.up".to_string(),
                ))?;
                poses.push(pose);
            }
        }
        path => {
            for t in 0..frames {
                let s = step * t as f64;
                let pose = match path {
                    MotionPath::Strafe => {
                        let d = pose0.right * s;
                        CameraPose::look_to(cam.position + d, dir0, up)
                    }
                    MotionPath::Dolly => {
                        let d = pose0.forward * s;
                        CameraPose::look_to(cam.position + d, dir0, up)
                    }
                    MotionPath::Yaw => {
                        let q = DQuat::from_axis_angle(up.normalize(), s);
                        CameraPose::look_to(cam.position, q * dir0, up)
                    }
                    MotionPath::Pitch => {
                        let q = DQuat::from_axis_angle(pose0.right, s);
                        CameraPose::look_to(cam.position, q * dir0, up)
                    }
                    MotionPath::Orbit => {
                        let q = DQuat::from_axis_angle(up.normalize(), s);
                        CameraPose::look_at(cam.target + q * (cam.position - cam.target), cam.target, up)
                    }
                    MotionPath::File { .. } => unreachable!("handled above"),
                };
                let pose = pose.ok_or_else(|| bad(t))?;
                // Pitching over the top flips the camera's right axis: a discontinuity no
                // real camera controller makes, so it is an error rather than a silent roll.
                // (Yaw and orbit turn the right axis continuously, through any angle.)
                if matches!(path, MotionPath::Pitch) && pose.right.dot(pose0.right) <= 0.0 {
                    return Err(bad(t));
                }
                poses.push(pose);
            }
        }
    }
    Ok(poses)
}

/// Reads a camera path CSV: a header `px,py,pz,tx,ty,tz` and one row per frame
/// (camera position, then the point it looks at). At least two rows.
pub fn read_path_file(path: &Path) -> Result<Vec<(DVec3, DVec3)>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let expected = ["px", "py", "pz", "tx", "ty", "tz"];
    let headers = reader.headers().map_err(|e| {
        Error::from(IoError::DataFile {
            path: path.to_path_buf(),
            line: 1,
            message: e.to_string(),
        })
    })?;
    if headers.iter().collect::<Vec<_>>() != expected {
        return Err(Error::from(IoError::DataFile {
            path: path.to_path_buf(),
            line: 1,
            message: format!(
                "header is {:?}; expected the columns px,py,pz,tx,ty,tz",
                headers.iter().collect::<Vec<_>>().join(",")
            ),
        }));
    }
    let mut rows = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let line = i + 2;
        let record = record.map_err(|e| {
            Error::from(IoError::DataFile {
                path: path.to_path_buf(),
                line,
                message: e.to_string(),
            })
        })?;
        if record.len() != 6 {
            return Err(Error::from(IoError::DataFile {
                path: path.to_path_buf(),
                line,
                message: format!("{} values; expected 6 (px,py,pz,tx,ty,tz)", record.len()),
            }));
        }
        let mut v = [0.0; 6];
        for (j, field) in record.iter().enumerate() {
            v[j] = field.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                Error::from(IoError::DataFile {
                    path: path.to_path_buf(),
                    line,
                    message: format!("column {} = {field:?} is not a finite number", expected[j]),
                })
            })?;
        }
        rows.push((DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5])));
    }
    if rows.len() < 2 {
        return Err(Error::from(IoError::DataFile {
            path: path.to_path_buf(),
            line: rows.len() + 1,
            message: format!("{} pose rows; a path needs at least 2 frames", rows.len()),
        }));
    }
    Ok(rows)
}
