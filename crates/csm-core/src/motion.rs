//! Camera paths for the shimmer metrics: one camera pose per frame, frame 0 being the
//! configured camera.
//!
//! Translations are in world units per frame, rotations in radians per frame (degrees exist
//! only in the config file and are converted when it is read). Rotations follow the right-hand
//! rule about their axis: yaw and orbit about the camera's up vector, pitch about its right
//! axis. A path given as explicit poses (position, target per frame) is used as is.

use glam::DQuat;

use crate::geometry::CameraPose;
use crate::scene::{Camera, Motion, MotionPath};

/// Poses for every frame of a motion path, or the first frame whose camera is
/// invalid (up parallel to the view direction, position equal to target) and why.
/// Collects [`poses`]; a walk along a long path should take the iterator instead.
pub fn camera_path(cam: &Camera, motion: &Motion) -> std::result::Result<Vec<CameraPose>, (usize, String)> {
    poses(cam, motion).collect()
}

/// One frame's pose, or that frame and why its camera is invalid.
pub type PoseResult = std::result::Result<CameraPose, (usize, String)>;

/// The poses of a motion path, one per frame, generated as they are read: a path of any
/// length takes the memory of one pose (a path file's rows are already in memory). Yields
/// `Err` for the first invalid frame (and for frame 0 when the configured camera is
/// invalid); a caller stops there.
pub fn poses<'a>(cam: &'a Camera, motion: &'a Motion) -> Poses<'a> {
    let len = match &motion.path {
        MotionPath::File { poses, .. } => poses.len(),
        _ => motion.frames,
    };
    Poses {
        cam,
        motion,
        pose0: CameraPose::look_at(cam.position, cam.target, cam.up),
        t: 0,
        len,
    }
}

/// The iterator [`poses`] returns: exact size, cheap to clone (it borrows the camera and
/// the motion).
#[derive(Debug, Clone)]
pub struct Poses<'a> {
    cam: &'a Camera,
    motion: &'a Motion,
    pose0: Option<CameraPose>,
    t: usize,
    len: usize,
}

impl Poses<'_> {
    fn pose(&self, t: usize) -> PoseResult {
        let (cam, up) = (self.cam, self.cam.up);
        let pose0 = self
            .pose0
            .ok_or_else(|| (0, "camera.up is parallel to the view direction".to_string()))?;
        let dir0 = cam.target - cam.position;
        let bad = |t: usize| (t, "the view direction becomes parallel to camera.up".to_string());
        let path = &self.motion.path;
        if let MotionPath::File { poses: rows, .. } = path {
            let (p, target) = rows[t];
            return CameraPose::look_at(p, target, up).ok_or((
                t,
                "position equals target, or the view direction is parallel to camera.up".to_string(),
            ));
        }
        let s = self.motion.step * t as f64;
        let pose = match path {
            // A translation keeps frame 0's view direction and up: `look_to` of those gives
            // frame 0's axes, so only the position is new (and must be finite, as `look_to`
            // requires): the same pose, bit for bit, without three normalisations per frame.
            MotionPath::Strafe => pose0.moved_to(cam.position + pose0.right * s),
            MotionPath::Dolly => pose0.moved_to(cam.position + pose0.forward * s),
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
            MotionPath::Still => Some(pose0),
            MotionPath::File { .. } => unreachable!("handled above"),
        };
        let pose = pose.ok_or_else(|| bad(t))?;
        // Pitching over the top flips the camera's right axis: a discontinuity no
        // real camera controller makes, so it is an error rather than a silent roll.
        // (Yaw and orbit turn the right axis continuously, through any angle.)
        if matches!(path, MotionPath::Pitch) && pose.right.dot(pose0.right) <= 0.0 {
            return Err(bad(t));
        }
        Ok(pose)
    }
}

impl Iterator for Poses<'_> {
    type Item = PoseResult;

    /// Skips to frame `t + n` without computing the frames between (each pose is a closed
    /// form of its index; a long path's later chunks start at once).
    fn nth(&mut self, n: usize) -> Option<PoseResult> {
        self.t = self.t.saturating_add(n).min(self.len);
        self.next()
    }

    fn next(&mut self) -> Option<PoseResult> {
        if self.t >= self.len {
            return None;
        }
        let r = self.pose(self.t);
        // After an invalid frame the path ends.
        self.t = if r.is_ok() { self.t + 1 } else { self.len };
        Some(r)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.len - self.t;
        (n, Some(n))
    }
}

impl ExactSizeIterator for Poses<'_> {}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A strafe or dolly pose is `look_to` of the moved position with frame 0's view direction
    /// and up, bit for bit (the poses keep frame 0's axes instead of recomputing them).
    #[test]
    fn translated_poses_equal_look_to_bit_for_bit() {
        let mut rng = crate::rng::SplitMix64::new(3);
        let v =
            |rng: &mut crate::rng::SplitMix64, s: f64| DVec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        for k in 0..2000 {
            let scale = [1.0, 1e3, 1e6][k % 3];
            let position = v(&mut rng, scale);
            let cam = Camera {
                position,
                target: position + v(&mut rng, 100.0),
                up: v(&mut rng, 1.0),
                fov_y: 1.0,
                aspect: 1.5,
                near: 0.1,
                far: 100.0,
                screen_height: 1080,
            };
            let pose0 = CameraPose::look_at(cam.position, cam.target, cam.up);
            let Some(pose0) = pose0 else { continue };
            for (path, axis) in [(MotionPath::Strafe, pose0.right), (MotionPath::Dolly, pose0.forward)] {
                let motion = Motion {
                    path,
                    frames: 50,
                    step: rng.range(-3.0, 3.0),
                };
                for (t, pose) in poses(&cam, &motion).enumerate() {
                    let got = pose.expect("a translation keeps a valid camera");
                    let want = CameraPose::look_to(
                        cam.position + axis * (motion.step * t as f64),
                        cam.target - cam.position,
                        cam.up,
                    )
                    .expect("valid");
                    assert_eq!(format!("{got:?}"), format!("{want:?}"), "frame {t}");
                }
            }
        }
    }
}
