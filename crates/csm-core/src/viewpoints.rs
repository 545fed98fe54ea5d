//! Where a level's camera views stand: player positions sampled on walkable surfaces, and the
//! two checks every view gets (does it stand inside geometry, does it see any receiver).
//!
//! **Directions.** The 26 probe directions are the unit vectors toward the neighbours of a cell
//! in a 3 × 3 × 3 grid: 6 faces, 12 edges, 8 corners. Eight of them are horizontal (`y = 0`),
//! nine point upward (`y > 0`) and nine downward.
//!
//! **Inside geometry.** A point stands inside geometry when either
//! - the first hit lies within [`CLOSE`] (0.1 world units) in most (more than half) of the 26
//!   directions: a wall or a slab fills the view; or
//! - it is enclosed: a ray crosses the surfaces an odd number of times on its way out of the
//!   scene (the parity rule of a closed solid) in most of the eight horizontal directions *and*
//!   in most of the nine upward ones. Triangle winding is not trusted (the meshes are soups), so
//!   parity is what says inside. The downward rays are left out because an open ground quad
//!   under a solid turns their parity even; asking for both the sideways and the upward rays keeps
//!   a camera under an open roof quad (a porch: upward odd, sideways even) outside.
//!
//! **Receivers seen.** A view sees a receiver when a ray of a coarse grid over its screen
//! ([`RECEIVER_GRID`]) meets, between the near and far planes, a surface whose normal (turned
//! toward the camera) points toward the light: the lit-facing receivers of [`crate::visibility`].
//! Only whether any ray does matters (a view that sees none draws a warning), so
//! [`sees_receiver`] stops at the first ray that does, rows from the bottom of the screen up:
//! each ray's answer depends on that ray alone, so the answer is that of every ray cast
//! ([`receivers_seen`] counts them all; a test holds the two together).
//!
//! **Walkable positions.** [`sample_positions`] draws points uniformly over the scene bounds'
//! x/z extent from a seeded [`SplitMix64`], casts a vertical ray down from above the bounds and
//! collects every surface along it (all of them, so floors under a roof count too). A surface is
//! walkable when its slope (the angle between its normal and +Y, winding ignored) is at most the
//! limit. The eye stands `eye_height` above it; the position is kept only when nothing lies
//! between the surface and `eye_height + CLOSE` above it (no ceiling, no overhang at head
//! height) and the eye is not inside geometry by the rule above (a "floor" found under a solid,
//! such as a box's bottom face resting on the ground, would otherwise put the eye inside it). Among the walkable surfaces of one vertical line one is drawn
//! at random. The view then looks in a random horizontal direction (yaw uniform in [0, 2π),
//! measured from −Z toward +X) pitched by an angle uniform in the stated range (positive looks
//! up). Everything follows from the seed: the same seed, scene and settings give the same views.

use glam::DVec3;

use crate::geometry::{Aabb, CameraPose, Lens};
use crate::rng::SplitMix64;
use crate::visibility::SceneGeometry;

/// A first hit within this distance (world units) counts as "close" for the inside test, and
/// the clearance kept above a sampled eye.
pub const CLOSE: f64 = 0.1;

/// Columns and rows of rays the receiver check casts per view.
pub const RECEIVER_GRID: (u32, u32) = (64, 36);

/// Most surfaces followed along one ray (parity and sampling): a bound on the work per ray.
const MAX_CROSSINGS: usize = 4096;

/// The 26 unit directions toward a cell's neighbours in a 3 × 3 × 3 grid, in a fixed order.
pub fn probe_directions() -> Vec<DVec3> {
    let mut out = Vec::with_capacity(26);
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) != (0, 0, 0) {
                    out.push(DVec3::new(x as f64, y as f64, z as f64).normalize());
                }
            }
        }
    }
    out
}

/// What the 26 probe rays from a point found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Enclosure {
    /// Directions whose first hit lies within [`CLOSE`].
    pub close: usize,
    /// Horizontal directions (of 8) that cross the surfaces an odd number of times.
    pub odd_horizontal: usize,
    /// Upward directions (of 9) that cross the surfaces an odd number of times.
    pub odd_up: usize,
}

impl Enclosure {
    /// Inside geometry by the rule of the module's documentation.
    pub fn inside(&self) -> bool {
        self.close > 13 || (self.odd_horizontal > 4 && self.odd_up > 4)
    }
}

/// The number of surfaces a ray from `origin` along unit `dir` crosses within `reach`.
/// Coincident surfaces (two triangles within a millimetre along the ray) count once.
fn crossings(scene: &SceneGeometry, origin: DVec3, dir: DVec3, reach: f64) -> usize {
    let mut n = 0;
    let mut t0 = 0.0;
    while n < MAX_CROSSINGS {
        let Some(hit) = scene.first_hit(origin, dir, t0, reach) else {
            break;
        };
        n += 1;
        t0 = hit.t.max(t0) + 1e-3;
    }
    n
}

/// Probes the 26 directions from `p`; `reach` is how far a ray goes to leave the scene.
pub fn enclosure(scene: &SceneGeometry, p: DVec3, reach: f64) -> Enclosure {
    let mut e = Enclosure {
        close: 0,
        odd_horizontal: 0,
        odd_up: 0,
    };
    for d in probe_directions() {
        if scene.first_hit(p, d, 0.0, CLOSE).is_some() {
            e.close += 1;
        }
        if d.y < 0.0 {
            continue;
        }
        let odd = crossings(scene, p, d, reach) % 2 == 1;
        if odd && d.y == 0.0 {
            e.odd_horizontal += 1;
        } else if odd {
            e.odd_up += 1;
        }
    }
    e
}

/// How far a ray from inside `bounds` must go to leave them (their diagonal, plus a margin).
pub fn reach(bounds: &Aabb) -> f64 {
    2.0 * (bounds.max - bounds.min).length() + 1.0
}

/// The camera of one view for the receiver check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewCamera {
    pub pose: CameraPose,
    pub lens: Lens,
    pub near: f64,
    pub far: f64,
}

/// Whether ray (`col`, `row`) of a [`RECEIVER_GRID`] over the view meets a lit-facing
/// surface between the near and far planes (`light` is the unit direction light travels).
fn sees_at(scene: &SceneGeometry, cam: &ViewCamera, light: DVec3, col: u32, row: u32) -> bool {
    let (cols, rows) = RECEIVER_GRID;
    let sx = (2.0 * (col as f64 + 0.5) / cols as f64 - 1.0) * cam.lens.tan_h;
    let sy = (1.0 - 2.0 * (row as f64 + 0.5) / rows as f64) * cam.lens.tan_v;
    // Depth along the view axis is t |d| along the unit ray, as in the visibility pass.
    let d = cam.pose.forward + cam.pose.right * sx + cam.pose.up * sy;
    let len = d.length();
    let Some(hit) = scene.first_hit(cam.pose.position, d / len, cam.near * len, cam.far * len) else {
        return false;
    };
    let mut n = scene.triangle_normal(hit.triangle);
    if n.dot(d) > 0.0 {
        n = -n;
    }
    n.dot(-light) > 0.0
}

/// How many rays of a [`RECEIVER_GRID`] over the view meet a lit-facing surface between the
/// near and far planes (`light` is the unit direction light travels).
pub fn receivers_seen(scene: &SceneGeometry, cam: &ViewCamera, light: DVec3) -> usize {
    let (cols, rows) = RECEIVER_GRID;
    (0..rows)
        .flat_map(|row| (0..cols).map(move |col| (col, row)))
        .filter(|&(col, row)| sees_at(scene, cam, light, col, row))
        .count()
}

/// Whether [`receivers_seen`] is above zero, casting only as many of its rays as it takes: the
/// same rays, one at a time, stopping at the first that meets a lit-facing surface. Each ray's
/// answer depends on that ray alone, so the order is free; the rows are taken from the bottom
/// of the screen up (a view's lower rows look at the ground, where a receiver is most often
/// found first), each row left to right. A view that sees no receiver still casts every ray.
pub fn sees_receiver(scene: &SceneGeometry, cam: &ViewCamera, light: DVec3) -> bool {
    let (cols, rows) = RECEIVER_GRID;
    (0..rows)
        .rev()
        .any(|row| (0..cols).any(|col| sees_at(scene, cam, light, col, row)))
}

/// How [`sample_positions`] draws player views.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleSpec {
    pub count: usize,
    pub seed: u64,
    /// Height of the eye above the surface stood on (world units).
    pub eye_height: f64,
    /// Steepest walkable surface, radians from horizontal.
    pub max_slope: f64,
    /// Pitch range, radians (positive looks up), `lo <= hi`.
    pub pitch: (f64, f64),
    /// Candidate points drawn at most, over all views (a scene with little walkable ground
    /// gives fewer views, never an endless loop).
    pub max_tries: usize,
}

/// One sampled player view: where the eye is and the unit direction it looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledView {
    pub eye: DVec3,
    pub forward: DVec3,
    /// The surface stood on, and its slope (radians).
    pub ground: DVec3,
    pub slope: f64,
}

/// The walkable surfaces under (x, z): (point, slope) of every surface a vertical ray from
/// above `top` meets, highest first.
fn surfaces_under(scene: &SceneGeometry, x: f64, z: f64, top: f64, bottom: f64) -> Vec<(DVec3, f64)> {
    let origin = DVec3::new(x, top, z);
    let down = DVec3::NEG_Y;
    let reach = top - bottom + 1.0;
    let mut out = Vec::new();
    let mut t0 = 0.0;
    while out.len() < MAX_CROSSINGS {
        let Some(hit) = scene.first_hit(origin, down, t0, reach) else {
            break;
        };
        let n = scene.triangle_normal(hit.triangle);
        let slope = n.y.abs().clamp(0.0, 1.0).acos();
        out.push((origin + down * hit.t, slope));
        t0 = hit.t.max(t0) + 1e-3;
    }
    out
}

/// The eye above `ground` if it is a valid player position: clear of geometry up to
/// `eye_height + CLOSE` and not inside geometry.
fn standing_eye(scene: &SceneGeometry, ground: DVec3, eye_height: f64, reach: f64) -> Option<DVec3> {
    if scene.first_hit(ground, DVec3::Y, 1e-3, eye_height + CLOSE).is_some() {
        return None;
    }
    let eye = ground + DVec3::Y * eye_height;
    (!enclosure(scene, eye, reach).inside()).then_some(eye)
}

/// Up to `spec.count` player views on walkable surfaces of `scene` within `bounds` (see the
/// module's documentation); fewer when `spec.max_tries` candidate points do not give them all.
pub fn sample_positions(scene: &SceneGeometry, bounds: &Aabb, spec: &SampleSpec) -> Vec<SampledView> {
    let mut rng = SplitMix64::new(spec.seed);
    let reach = reach(bounds);
    let top = bounds.max.y + 1.0;
    let bottom = bounds.min.y - 1.0;
    let mut out = Vec::with_capacity(spec.count);
    let mut tries = 0;
    while out.len() < spec.count && tries < spec.max_tries {
        tries += 1;
        let x = rng.range(bounds.min.x, bounds.max.x);
        let z = rng.range(bounds.min.z, bounds.max.z);
        let walkable: Vec<(DVec3, f64)> = surfaces_under(scene, x, z, top, bottom)
            .into_iter()
            .filter(|&(_, slope)| slope <= spec.max_slope)
            .collect();
        // Always draw the pick, so the sequence does not depend on what the checks below find.
        let pick = rng.unit();
        let yaw = rng.range(0.0, std::f64::consts::TAU);
        let pitch = rng.range(spec.pitch.0, spec.pitch.1);
        if walkable.is_empty() {
            continue;
        }
        let (ground, slope) = walkable[((pick * walkable.len() as f64) as usize).min(walkable.len() - 1)];
        let Some(eye) = standing_eye(scene, ground, spec.eye_height, reach) else {
            continue;
        };
        out.push(SampledView {
            eye,
            forward: look_direction(yaw, pitch),
            ground,
            slope,
        });
    }
    out
}

/// The unit direction of a view with yaw (from −Z toward +X) and pitch (positive up).
pub fn look_direction(yaw: f64, pitch: f64) -> DVec3 {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    DVec3::new(cp * sy, sp, -cp * cy)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    fn scene(boxes: &[Aabb], ground: Option<(f64, f64)>) -> SceneGeometry {
        let mut m = Mesh::default();
        for b in boxes {
            m.add_box(b);
        }
        if let Some((y, half)) = ground {
            m.add_ground(y, -half, half, -half, half);
        }
        SceneGeometry::new(m)
    }

    #[test]
    fn there_are_26_directions_8_horizontal_9_up() {
        let d = probe_directions();
        assert_eq!(d.len(), 26);
        assert_eq!(d.iter().filter(|v| v.y == 0.0).count(), 8);
        assert_eq!(d.iter().filter(|v| v.y > 0.0).count(), 9);
        for v in &d {
            assert!((v.length() - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn inside_a_solid_box_is_inside_and_beside_it_or_under_a_roof_is_not() {
        let b = Aabb::new(DVec3::new(-5.0, 0.0, -5.0), DVec3::new(5.0, 4.0, 5.0));
        let s = scene(&[b], Some((0.0, 50.0)));
        let r = reach(&Aabb::new(DVec3::splat(-50.0), DVec3::splat(50.0)));
        let inside = enclosure(&s, DVec3::new(1.0, 2.0, 1.0), r);
        assert_eq!((inside.odd_horizontal, inside.odd_up), (8, 9));
        assert!(inside.inside());
        let outside = enclosure(&s, DVec3::new(10.0, 1.7, 0.5), r);
        // Sideways toward the box: through it, twice; nothing above.
        assert_eq!((outside.odd_horizontal, outside.odd_up), (0, 0));
        assert!(!outside.inside());
        // 5 cm from the wall: only the directions with x-component above 1/2 hit within 0.1.
        let near_wall = enclosure(&s, DVec3::new(5.05, 1.7, 0.0), r);
        assert_eq!(near_wall.close, 9);
        assert!(!near_wall.inside());
        // Under an open roof quad: upward odd, sideways even.
        let mut m = Mesh::default();
        m.add_ground(0.0, -50.0, 50.0, -50.0, 50.0);
        m.add_ground(3.0, -4.0, 4.0, -4.0, 4.0);
        let porch = enclosure(&SceneGeometry::new(m), DVec3::new(0.0, 1.7, 0.0), r);
        assert_eq!((porch.odd_horizontal, porch.odd_up), (0, 9));
        assert!(!porch.inside());
    }

    #[test]
    fn a_thin_slab_around_the_point_is_close_in_every_direction() {
        // A box of about 0.1 m around the point, off-centre so that no probe ray runs through
        // one of its edges or vertices: every first hit within 0.1 (the farthest at 0.087).
        let b = Aabb::new(DVec3::new(-0.05, -0.04, -0.045), DVec3::new(0.045, 0.05, 0.04));
        let e = enclosure(&scene(&[b], None), DVec3::ZERO, 10.0);
        assert_eq!(e.close, 26);
        assert!(e.inside());
    }

    #[test]
    fn a_view_at_the_sky_sees_no_receiver_and_one_at_the_ground_does() {
        let s = scene(&[], Some((0.0, 100.0)));
        let lens = Lens::new(1.0, 16.0 / 9.0);
        let up = CameraPose::look_to(DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.0, 1.0, -0.2), DVec3::Y).unwrap();
        let down = CameraPose::look_to(DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.0, -1.0, -1.0), DVec3::Y).unwrap();
        let light = DVec3::new(0.3, -1.0, 0.2).normalize();
        let cam = |pose| ViewCamera {
            pose,
            lens,
            near: 0.1,
            far: 500.0,
        };
        assert_eq!(receivers_seen(&s, &cam(up), light), 0);
        assert!(!sees_receiver(&s, &cam(up), light));
        // Looking down 45° with a 1 rad fov: every ray hits the ground, lit from above.
        let (c, r) = RECEIVER_GRID;
        assert_eq!(receivers_seen(&s, &cam(down), light) as u32, c * r);
        assert!(sees_receiver(&s, &cam(down), light));
        // Lit from below, the ground is self-shadowed: no receiver.
        assert_eq!(receivers_seen(&s, &cam(down), -light), 0);
        assert!(!sees_receiver(&s, &cam(down), -light));
    }

    /// The early stop answers as the full count does: on views from many places in a scene
    /// of boxes over a ground (some inside a box, some looking at the sky, some at the ground),
    /// under lights from above and from below, `sees_receiver` is `receivers_seen > 0`; and
    /// both answers occur.
    #[test]
    fn the_early_stop_answers_as_the_count_does() {
        let boxes = [
            Aabb::new(DVec3::new(-8.0, 0.0, -8.0), DVec3::new(-2.0, 5.0, -2.0)),
            Aabb::new(DVec3::new(2.0, 0.0, 2.0), DVec3::new(9.0, 3.0, 9.0)),
        ];
        let s = scene(&boxes, Some((0.0, 40.0)));
        let mut rng = SplitMix64::new(11);
        let (mut yes, mut no) = (0, 0);
        for k in 0..120 {
            let eye = DVec3::new(rng.range(-12.0, 12.0), rng.range(0.5, 8.0), rng.range(-12.0, 12.0));
            let forward = look_direction(rng.range(0.0, std::f64::consts::TAU), rng.range(-1.4, 1.4));
            let Some(pose) = CameraPose::look_to(eye, forward, DVec3::Y) else {
                continue;
            };
            let cam = ViewCamera {
                pose,
                lens: Lens::new(rng.range(0.2, 1.6), 16.0 / 9.0),
                near: 0.1,
                far: rng.range(2.0, 300.0),
            };
            let light = if k % 3 == 0 {
                DVec3::new(0.2, 1.0, -0.4).normalize()
            } else {
                DVec3::new(0.3, -1.0, 0.2).normalize()
            };
            let seen = receivers_seen(&s, &cam, light);
            assert_eq!(
                sees_receiver(&s, &cam, light),
                seen > 0,
                "view {k}: {seen} rays see a receiver"
            );
            if seen > 0 {
                yes += 1;
            } else {
                no += 1;
            }
        }
        assert!(yes > 10 && no > 10, "{yes} views see a receiver, {no} do not");
    }

    #[test]
    fn sampled_views_are_reproducible_stand_on_walkable_ground_and_never_inside_a_box() {
        // A ground, two solid boxes, a 60° ramp (steeper than the limit) and a low box whose
        // underside is 1 m up: none of the eyes may end inside a box.
        let boxes = [
            Aabb::new(DVec3::new(-8.0, 0.0, -8.0), DVec3::new(-2.0, 5.0, -2.0)),
            Aabb::new(DVec3::new(2.0, 0.0, 2.0), DVec3::new(9.0, 3.0, 9.0)),
            Aabb::new(DVec3::new(-9.0, 1.0, 3.0), DVec3::new(-3.0, 2.5, 9.0)),
        ];
        let mut m = Mesh::default();
        for b in &boxes {
            m.add_box(b);
        }
        m.add_ground(0.0, -10.0, 10.0, -10.0, 10.0);
        let (a, b) = (DVec3::new(0.0, 0.0, -9.0), DVec3::new(1.0, 3f64.sqrt(), -9.0));
        m.push([a, b, DVec3::new(1.0, 3f64.sqrt(), -4.0)]);
        m.push([a, DVec3::new(1.0, 3f64.sqrt(), -4.0), DVec3::new(0.0, 0.0, -4.0)]);
        let s = SceneGeometry::new(m);
        let bounds = s.mesh.bounds().unwrap();
        let spec = SampleSpec {
            count: 60,
            seed: 7,
            eye_height: 1.7,
            max_slope: 30f64.to_radians(),
            pitch: (-0.2, 0.1),
            max_tries: 100_000,
        };
        let views = sample_positions(&s, &bounds, &spec);
        assert_eq!(views.len(), 60);
        assert_eq!(views, sample_positions(&s, &bounds, &spec));
        let other = sample_positions(&s, &bounds, &SampleSpec { seed: 8, ..spec });
        assert_ne!(views, other);
        let strictly_inside = |b: &Aabb, p: DVec3| p.cmpgt(b.min).all() && p.cmplt(b.max).all();
        for v in &views {
            assert!((v.eye - v.ground - DVec3::Y * 1.7).length() < 1e-12);
            assert!(v.slope <= spec.max_slope + 1e-12, "{v:?}");
            // On the ground, a box top or... never the ramp (60°).
            let on_top = v.ground.y.abs() < 1e-9 || boxes.iter().any(|b| (v.ground.y - b.max.y).abs() < 1e-9);
            assert!(on_top, "{v:?}");
            for b in &boxes {
                assert!(!strictly_inside(b, v.eye), "{v:?} inside {b:?}");
            }
            // Under the low box (1 m up) nobody stands: 1.7 m do not fit.
            let under_low = v.ground.y.abs() < 1e-9 && strictly_inside(&boxes[2], DVec3::new(v.eye.x, 1.5, v.eye.z));
            assert!(!under_low, "{v:?}");
            assert!((v.forward.length() - 1.0).abs() < 1e-12);
            let pitch = v.forward.y.asin();
            assert!((-0.2 - 1e-12..=0.1 + 1e-12).contains(&pitch));
        }
        // Both the ground and the box tops are drawn.
        assert!(views.iter().any(|v| v.ground.y > 2.0));
        assert!(views.iter().any(|v| v.ground.y.abs() < 1e-9));
    }

    #[test]
    fn a_scene_without_walkable_ground_gives_fewer_views_and_stops() {
        let mut m = Mesh::default();
        // A single 60° ramp.
        m.push([
            DVec3::ZERO,
            DVec3::new(1.0, 3f64.sqrt(), 0.0),
            DVec3::new(1.0, 3f64.sqrt(), 5.0),
        ]);
        let s = SceneGeometry::new(m);
        let spec = SampleSpec {
            count: 5,
            seed: 1,
            eye_height: 1.7,
            max_slope: 30f64.to_radians(),
            pitch: (0.0, 0.0),
            max_tries: 200,
        };
        assert!(sample_positions(&s, &s.mesh.bounds().unwrap(), &spec).is_empty());
    }

    #[test]
    fn look_direction_is_minus_z_at_zero_and_plus_x_at_a_quarter_turn() {
        assert!((look_direction(0.0, 0.0) - DVec3::NEG_Z).length() < 1e-15);
        assert!((look_direction(std::f64::consts::FRAC_PI_2, 0.0) - DVec3::X).length() < 1e-15);
        assert!((look_direction(0.0, 0.5).y - 0.5f64.sin()).abs() < 1e-15);
    }
}
