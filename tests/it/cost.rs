//! Cost counts (docs/cost.md): object and triangle counts against a brute-force separating-axis
//! test on random scenes, fragment areas against a brute-force rasterisation of the window and
//! against closed forms, and receiver-aware culling against the ground-truth pass.

use csm_core::cost::{self, CasterVolume, LightScene};
use csm_core::geometry::{Aabb, LightBasis};
use csm_core::mesh::{Mesh, ObjectKind};
use csm_core::visibility::SceneGeometry;
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::Config;
use glam::{DVec2, DVec3};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Brute force: the separating-axis theorem over vertex lists
// ---------------------------------------------------------------------------------------------

/// Two convex point sets are apart when some axis separates their projections; for polyhedra
/// the face normals and the cross products of edge directions are enough. Written over plain
/// vertex lists, independently of the box structure the code under test uses.
fn sat_apart(a: &[DVec3], b: &[DVec3], axes: &[DVec3]) -> bool {
    axes.iter().filter(|x| x.length_squared() > 1e-18).any(|x| {
        let (alo, ahi) = a.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.dot(*x)), h.max(p.dot(*x)))
        });
        let (blo, bhi) = b.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.dot(*x)), h.max(p.dot(*x)))
        });
        ahi < blo || bhi < alo
    })
}

/// The 8 world corners of a volume.
fn volume_corners(v: &CasterVolume) -> Vec<DVec3> {
    let b = &v.basis;
    let mut out = Vec::new();
    for x in [v.lo.x, v.hi.x] {
        for y in [v.lo.y, v.hi.y] {
            for z in [v.lo.z, v.hi.z] {
                out.push(b.x * x + b.y * y + b.z * z);
            }
        }
    }
    out
}

fn box_corners(b: &Aabb) -> Vec<DVec3> {
    (0..8).map(|c| b.corner(c)).collect()
}

/// A world box against the volume by brute-force SAT: the 3 + 3 face normals and 9 crosses.
fn brute_box_meets(b: &Aabb, v: &CasterVolume) -> bool {
    let world = [DVec3::X, DVec3::Y, DVec3::Z];
    let light = [v.basis.x, v.basis.y, v.basis.z];
    let mut axes: Vec<DVec3> = world.iter().chain(light.iter()).copied().collect();
    for a in world {
        for l in light {
            axes.push(a.cross(l));
        }
    }
    !sat_apart(&box_corners(b), &volume_corners(v), &axes)
}

/// A world triangle against the volume by brute-force SAT: the box's 3 normals, the
/// triangle's normal and the 9 crosses of their edges.
fn brute_triangle_meets(t: &[DVec3; 3], v: &CasterVolume) -> bool {
    let light = [v.basis.x, v.basis.y, v.basis.z];
    let edges = [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let mut axes: Vec<DVec3> = light.to_vec();
    axes.push(edges[0].cross(edges[1]));
    for e in edges {
        for l in light {
            axes.push(e.cross(l));
        }
    }
    !sat_apart(t, &volume_corners(v), &axes)
}

/// Brute-force counts: every object's bounds and every triangle tested on its own.
fn brute_counts(mesh: &Mesh, v: &CasterVolume) -> (u64, u64, u64) {
    let (mut objects, mut tris, mut inside) = (0, 0, 0);
    for o in &mesh.objects {
        if brute_box_meets(&o.bounds, v) {
            objects += 1;
            tris += o.triangles.len() as u64;
            inside += mesh.triangles[o.triangles.clone()]
                .iter()
                .filter(|t| brute_triangle_meets(t, v))
                .count() as u64;
        }
    }
    (objects, tris, inside)
}

/// Brute-force fragments: an `n x n` grid of sample points over the window, each counting
/// every caster triangle whose projection contains it (overdraw included); the area each
/// sample stands for is the window's over n². Returns the estimate in texels and the bound on
/// its error: a sample can be misclassified only in a cell a triangle's projected edge passes
/// through, and an edge of length L meets at most `L / h * 2 + 2` cells of side h per axis
/// direction, so the error is at most (sum of projected perimeters / h · 2 + 6 per triangle)
/// cells.
fn brute_fragments(mesh: &Mesh, v: &CasterVolume, n: usize) -> (f64, f64) {
    let b = &v.basis;
    let (lo, hi) = (v.lo.truncate(), v.hi.truncate());
    let cell = (hi - lo) / n as f64;
    let cell_area = cell.x * cell.y;
    let mut count = 0u64;
    let mut perimeter_cells = 0.0;
    let casters: Vec<usize> = mesh
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| brute_box_meets(&o.bounds, v))
        .flat_map(|(_, o)| o.triangles.clone())
        .collect();
    for &k in &casters {
        let t = mesh.triangles[k].map(|p| DVec2::new(b.x.dot(p), b.y.dot(p)));
        let per: f64 = (0..3).map(|e| (t[(e + 1) % 3] - t[e]).length()).sum();
        perimeter_cells += 2.0 * per / cell.x.min(cell.y) + 6.0;
        let d = (t[1] - t[0]).perp_dot(t[2] - t[0]);
        if d == 0.0 {
            continue;
        }
        for i in 0..n {
            for j in 0..n {
                let p = lo + DVec2::new((i as f64 + 0.5) * cell.x, (j as f64 + 0.5) * cell.y);
                let w0 = (t[1] - p).perp_dot(t[2] - p);
                let w1 = (t[2] - p).perp_dot(t[0] - p);
                let w2 = (t[0] - p).perp_dot(t[1] - p);
                let inside = if d > 0.0 {
                    w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0
                } else {
                    w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0
                };
                if inside {
                    count += 1;
                }
            }
        }
    }
    let texel_area = v.texel.x * v.texel.y;
    (
        count as f64 * cell_area / texel_area,
        perimeter_cells * cell_area / texel_area,
    )
}

// ---------------------------------------------------------------------------------------------
// Random scenes
// ---------------------------------------------------------------------------------------------

fn point(r: f64) -> impl Strategy<Value = DVec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// A random scene: boxes, triangle clusters (a glTF primitive each) and a ground.
fn scene() -> impl Strategy<Value = Mesh> {
    (
        prop::collection::vec((point(40.0), point(8.0)), 0..8),
        prop::collection::vec(
            (
                point(40.0),
                prop::collection::vec((point(10.0), point(10.0), point(10.0)), 1..12),
            ),
            0..6,
        ),
        prop::option::of(-10.0..5.0f64),
    )
        .prop_map(|(boxes, clusters, ground)| {
            let mut m = Mesh::default();
            for (c, e) in boxes {
                let e = e.abs() + DVec3::splat(0.1);
                m.add_box(&Aabb::new(c - e, c + e));
            }
            for (c, tris) in clusters {
                m.add_object(
                    ObjectKind::Primitive,
                    tris.into_iter().map(|(a, b, d)| [c + a, c + b, c + d]),
                );
            }
            if let Some(y) = ground {
                m.add_ground(y, -50.0, 50.0, -60.0, 45.0);
            }
            m
        })
}

/// A random light direction (not vertical within a degree, nor exactly so: both work) and a
/// random caster volume in its light space.
fn volume() -> impl Strategy<Value = CasterVolume> {
    (
        point(1.0).prop_filter("a direction", |d| d.length() > 0.2),
        (-40.0..40.0f64, -40.0..40.0f64, 1.0..60.0f64, 1.0..60.0f64),
        (-60.0..20.0f64, 0.0..80.0f64),
        prop::sample::select(vec![64u32, 256, 1000]),
    )
        .prop_map(|(d, (x, y, w, h), (z, depth), res)| {
            let basis = LightBasis::new(d);
            CasterVolume {
                basis,
                lo: DVec3::new(x, y, z),
                hi: DVec3::new(x + w, y + h, z + depth),
                texel: DVec2::new(w, h) / res as f64,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Objects (bounds against the volume), their triangles and the triangles inside the
    /// volume equal a brute-force separating-axis test of every box and every triangle.
    #[test]
    fn object_and_triangle_counts_equal_a_brute_force_separating_axis_test(m in scene(), v in volume()) {
        let light = LightScene::new(&m, &v.basis);
        let c = light.counts(&m, &v, |_| true);
        let (objects, tris, inside) = brute_counts(&m, &v);
        prop_assert_eq!(c.caster_objects, objects);
        prop_assert_eq!(c.caster_triangles, tris);
        prop_assert_eq!(c.caster_triangles_inside, inside);
    }

    /// The exact fragment area equals a brute-force rasterisation of the window within the
    /// rasterisation's error bound.
    #[test]
    fn fragments_equal_a_brute_force_rasterisation_within_its_sampling_error(m in scene(), v in volume()) {
        let light = LightScene::new(&m, &v.basis);
        let c = light.counts(&m, &v, |_| true);
        let (estimate, bound) = brute_fragments(&m, &v, 160);
        prop_assert!((c.raster_fragments - estimate).abs() <= bound + 1e-9 * estimate.abs(),
            "exact {} brute force {} bound {}", c.raster_fragments, estimate, bound);
    }

    /// Keeping a subset of the objects keeps exactly their part of every count.
    #[test]
    fn counts_over_kept_objects_add_up(m in scene(), v in volume(), mask in prop::collection::vec(any::<bool>(), 16)) {
        let light = LightScene::new(&m, &v.basis);
        let keep = |k: usize| mask[k % mask.len()];
        let a = light.counts(&m, &v, keep);
        let b = light.counts(&m, &v, |k| !keep(k));
        let all = light.counts(&m, &v, |_| true);
        prop_assert_eq!(a.caster_objects + b.caster_objects, all.caster_objects);
        prop_assert_eq!(a.caster_triangles_inside + b.caster_triangles_inside, all.caster_triangles_inside);
        prop_assert!((a.raster_fragments + b.raster_fragments - all.raster_fragments).abs() <= 1e-9 * (1.0 + all.raster_fragments));
    }
}

// ---------------------------------------------------------------------------------------------
// Closed forms
// ---------------------------------------------------------------------------------------------

/// A ground quad of area A under a light of direction d projects to A |d_y| on the light plane
/// (its normal is +Y); a window holding the whole projection rasterises exactly that many
/// square texels' worth, whatever the tilt.
#[test]
fn a_ground_quad_under_a_tilted_light_rasterises_its_projected_area() {
    let mut m = Mesh::default();
    m.add_ground(0.0, -30.0, 50.0, -20.0, 10.0);
    let area = 80.0 * 30.0;
    for d in [
        DVec3::new(-0.4, -1.0, -0.3),
        DVec3::new(1.0, -0.2, 0.0),
        DVec3::new(0.3, -0.9, 0.8),
        DVec3::new(0.0, -1.0, 0.0),
    ] {
        let basis = LightBasis::new(d);
        let texel = 0.25;
        let v = CasterVolume {
            basis,
            lo: DVec3::new(-500.0, -500.0, -500.0),
            hi: DVec3::new(500.0, 500.0, 500.0),
            texel: DVec2::splat(texel),
        };
        let c = LightScene::new(&m, &basis).counts(&m, &v, |_| true);
        let expected = area * d.normalize().y.abs() / (texel * texel);
        assert!(
            (c.raster_fragments - expected).abs() <= 1e-9 * expected,
            "{d}: {} vs {expected}",
            c.raster_fragments
        );
        assert_eq!(
            (c.caster_objects, c.caster_triangles, c.caster_triangles_inside),
            (1, 2, 2)
        );
    }
}

/// Under a vertical light the quad projects to itself; a window covering part of it
/// rasterises the overlap of two rectangles.
#[test]
fn a_window_over_part_of_a_quad_rasterises_the_overlap_of_two_rectangles() {
    let mut m = Mesh::default();
    m.add_ground(2.0, 0.0, 10.0, 0.0, 20.0);
    let basis = LightBasis::new(DVec3::NEG_Y);
    // The quad's light x/y rectangle, from its corners.
    let xs = [0.0, 10.0].map(|x| basis.x.dot(DVec3::new(x, 2.0, 0.0)));
    let ys = [0.0, 20.0].map(|z| basis.y.dot(DVec3::new(0.0, 2.0, z)));
    let (qx, qy) = (
        (xs[0].min(xs[1]), xs[0].max(xs[1])),
        (ys[0].min(ys[1]), ys[0].max(ys[1])),
    );
    let lo = DVec2::new(qx.0 + 3.0, qy.0 - 5.0);
    let hi = DVec2::new(qx.0 + 7.5, qy.0 + 6.0);
    let v = CasterVolume {
        basis,
        lo: lo.extend(-100.0),
        hi: hi.extend(100.0),
        texel: DVec2::new(0.5, 0.25),
    };
    let c = LightScene::new(&m, &basis).counts(&m, &v, |_| true);
    let overlap = (hi.x.min(qx.1) - lo.x.max(qx.0)) * (hi.y.min(qy.1) - lo.y.max(qy.0));
    assert!(
        (c.raster_fragments - overlap / 0.125).abs() < 1e-9,
        "{} vs {}",
        c.raster_fragments,
        overlap / 0.125
    );
    // Exactly on the quad's light depth (the light near plane of a scene that is only it).
    let z = basis.z.dot(DVec3::new(0.0, 2.0, 0.0));
    let v = CasterVolume {
        lo: lo.extend(z),
        hi: hi.extend(z + 1.0),
        ..v
    };
    assert_eq!(LightScene::new(&m, &basis).counts(&m, &v, |_| true).caster_objects, 1);
    // A volume that ends before the quad's depth draws nothing.
    let v = CasterVolume {
        lo: lo.extend(z - 10.0),
        hi: hi.extend(z - 1.0),
        ..v
    };
    let c = LightScene::new(&m, &basis).counts(&m, &v, |_| true);
    assert_eq!((c.caster_objects, c.raster_fragments), (0, 0.0));
}

/// A box whose bounds meet the volume only across a corner is drawn, but none of its
/// triangles lies inside: the two counts differ as a per-triangle culler would.
#[test]
fn a_box_grazing_the_volume_is_a_draw_call_with_its_triangles_all_outside_unless_they_meet_it() {
    let basis = LightBasis::new(DVec3::new(-0.4, -1.0, -0.3));
    let mut m = Mesh::default();
    // A thin diagonal sliver: its bounds are a big box, its triangle a narrow strip.
    let a = DVec3::new(0.0, 0.0, 0.0);
    let b = DVec3::new(10.0, 10.0, 10.0);
    m.add_object(ObjectKind::Primitive, [[a, b, b + DVec3::new(0.01, 0.0, 0.0)]]);
    // The volume around the bounds' corner (10, 0, 0), away from the diagonal.
    let c = basis.to_light(DVec3::new(10.0, 0.0, 0.0));
    let v = CasterVolume {
        basis,
        lo: c - DVec3::splat(0.5),
        hi: c + DVec3::splat(0.5),
        texel: DVec2::splat(0.1),
    };
    let got = LightScene::new(&m, &basis).counts(&m, &v, |_| true);
    assert_eq!(
        (got.caster_objects, got.caster_triangles, got.caster_triangles_inside),
        brute_counts(&m, &v)
    );
    assert_eq!(got.caster_objects, 1);
    assert_eq!(got.caster_triangles_inside, 0);
    assert!(cost::aabb_meets_volume(&m.objects[0].bounds, &v));
}

// ---------------------------------------------------------------------------------------------
// The analysis: counts, totals, bounds-only configs, and culling against ground truth
// ---------------------------------------------------------------------------------------------

fn default_config() -> Config {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    Config::from_toml_str(&text, "default.toml", None).unwrap()
}

/// The analysis's per-cascade counts are those of the cascade's caster volume (window
/// rectangle, scene light near to the cascade's light far) counted by brute force, and the
/// totals add the cascades.
#[test]
fn the_analysis_counts_each_cascade_s_caster_volume() {
    let c = default_config();
    let a = analyze(&c, &AnalysisOptions::summary_only());
    let rig = a.rig().unwrap();
    let mesh = &c.geometry.as_ref().unwrap().scene.mesh;
    let pose = c.camera.pose();
    let lp = csm_core::cascades::LightPose::new(&rig.light, &pose);
    let mut objects = 0;
    for (i, r) in a.cascades.iter().enumerate() {
        let w = rig.window(i, &lp, c.shadow.snap);
        let v = csm_lab::analysis::cost::volume(&c, rig, i, &lp, &w);
        let (scene_near, _) = cost::light_depth_extent(&v.basis, &c.scene);
        assert_eq!(v.lo.z, scene_near);
        assert_eq!(v.hi.z, rig.light_depth(i, &lp, &w, &c.scene).far);
        let counts = r.cost.counts.unwrap();
        assert_eq!(
            (
                counts.caster_objects,
                counts.caster_triangles,
                counts.caster_triangles_inside
            ),
            brute_counts(mesh, &v)
        );
        let (estimate, bound) = brute_fragments(mesh, &v, 200);
        assert!((counts.raster_fragments - estimate).abs() <= bound);
        assert_eq!(r.cost.texels_cleared, 2048 * 2048);
        objects += counts.caster_objects;
    }
    let total = a.summary.cost.counts.unwrap();
    assert_eq!(total.caster_objects, objects);
    assert_eq!(a.summary.cost.texels_cleared, 4 * 2048 * 2048);
    assert_eq!(a.summary.cost.bytes_written, 4 * 4 * 2048 * 2048);
    assert_eq!(a.summary.cost.cost_index, Some(1.0));
    let shares: f64 = a.cascades.iter().map(|r| r.cost.cost_index.unwrap()).sum();
    assert!((shares - 1.0).abs() < 1e-12);
    // Every object of the default scene is drawn by some cascade: the near band draws the
    // ground and the objects around the camera, the far cascade the rest.
    assert!(a.cascades.iter().all(|r| r.cost.counts.unwrap().caster_objects >= 1));
    assert!(a.summary.cost.shadow_ms.is_none());
}

/// Without geometry the counts are absent (n/a), never 0; the cleared texels are known.
#[test]
fn a_bounds_only_config_has_no_counts_but_its_cleared_texels() {
    let c = csm_lab::Config::from_toml_str(crate::common::BASE, "t.toml", None).unwrap();
    let a = analyze(&c, &AnalysisOptions::full());
    assert_eq!(a.summary.cost.counts, None);
    assert_eq!(a.summary.cost.cost_index, None);
    assert_eq!(a.summary.cost.texels_cleared, 4 * 2048 * 2048);
    let keys: Vec<&str> = csm_lab::metric::summary_json(&a.summary)
        .iter()
        .map(|(k, _)| *k)
        .collect();
    assert!(keys.contains(&"texels_cleared") && keys.contains(&"bytes_written"));
    for k in [
        "caster_objects",
        "caster_triangles",
        "raster_fragments",
        "cost_index",
        "shadow_ms",
    ] {
        assert!(!keys.contains(&k), "{k} in {keys:?}");
    }
    let e = csm_lab::Config::from_toml_str(
        &crate::common::with(&[("cost.cull", "cull = \"receivers\"")]),
        "t.toml",
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("cost.cull") && e.contains("scene geometry"), "{e}");
}

/// Calibrated coefficients give milliseconds: the model with the user's nanoseconds.
#[test]
fn calibrated_coefficients_give_shadow_ms_and_partial_ones_are_refused() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let calibrated = format!(
        "{text}\n[cost]\nns_per_draw = 3000.0\nns_per_triangle = 0.5\nns_per_fragment = 0.02\nns_per_texel_cleared = 0.004\n"
    );
    let c = Config::from_toml_str(&calibrated, "d.toml", None).unwrap();
    let a = analyze(&c, &AnalysisOptions::summary_only());
    let t = a.summary.cost.counts.unwrap();
    let ns = 3000.0 * t.caster_objects as f64
        + 0.5 * t.caster_triangles as f64
        + 0.02 * t.raster_fragments
        + 0.004 * a.summary.cost.texels_cleared as f64;
    assert!((a.summary.cost.shadow_ms.unwrap() - ns * 1e-6).abs() < 1e-12);
    let partial = format!("{text}\n[cost]\nns_per_draw = 3000.0\n");
    let e = Config::from_toml_str(&partial, "d.toml", None).unwrap_err().to_string();
    assert!(e.contains("cost.ns_per_triangle") && e.contains("all four"), "{e}");
    let negative = format!(
        "{text}\n[cost]\nns_per_draw = -1.0\nns_per_triangle = 0.5\nns_per_fragment = 0.02\nns_per_texel_cleared = 0.004\n"
    );
    let e = Config::from_toml_str(&negative, "d.toml", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cost.ns_per_draw") && e.contains("-1"), "{e}");
}

/// Receiver-aware culling never drops a caster that shadows a visible receiver: for each
/// cascade, the ground-truth pass over only the objects that cascade keeps gives every one of
/// its receivers the same lit/shadowed answer (with and without the bias) as over the whole
/// scene. And it does cull: some cascade draws fewer objects than without culling.
#[test]
fn culling_by_receivers_never_changes_the_ground_truth_states() {
    for (name, text) in [
        (
            "default",
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap(),
        ),
        (
            "village",
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/village.toml")).unwrap(),
        ),
    ] {
        let culled_text = format!("{text}\n[cost]\ncull = \"receivers\"\n");
        let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/configs"));
        let mut c = Config::from_toml_str(&culled_text, "c.toml", Some(dir)).unwrap();
        let plain = Config::from_toml_str(&text, "c.toml", Some(dir)).unwrap();
        c.truth.enabled = true;
        c.motion.frames = 2;
        let a = analyze(&c, &AnalysisOptions::full());
        let b = analyze(&plain, &AnalysisOptions::summary_only());
        let culled_any = a
            .cascades
            .iter()
            .zip(&b.cascades)
            .any(|(x, y)| x.cost.counts.unwrap().caster_objects < y.cost.counts.unwrap().caster_objects);
        assert!(culled_any, "{name}: culling culled nothing");
        let g = a.ground_truth.as_ref().unwrap();
        let rig = a.rig().unwrap();
        let geometry = c.geometry.as_ref().unwrap();
        let scene = &geometry.scene;
        let pose = c.camera.pose();
        let lp = csm_core::cascades::LightPose::new(&rig.light, &pose);
        let vis = c.setup().visibility().unwrap();
        let sampling = csm_core::truth::Sampling {
            bias: g.bias.clone(),
            format: Some(c.truth.depth_format),
            ranges: g.ranges.clone(),
            pcf: c.truth.pcf,
            filter: g.filter,
            binary32: None,
        };
        let windows: Vec<_> = (0..rig.cascade_count())
            .map(|i| (rig.basis(i, &lp), rig.window(i, &lp, c.shadow.snap)))
            .collect();
        let mut compared = 0;
        for i in 0..rig.cascade_count() {
            let v = csm_lab::analysis::cost::volume(&c, rig, i, &lp, &windows[i].1);
            let kept = csm_lab::analysis::cost::kept_objects(&c, rig, i, &v, scene, &vis).unwrap();
            let mut mesh = Mesh::default();
            for (k, o) in scene.mesh.objects.iter().enumerate() {
                if kept[k] {
                    mesh.add_object(o.kind, scene.mesh.triangles[o.triangles.clone()].iter().copied());
                }
            }
            let culled = SceneGeometry::new(mesh);
            let cascades: Vec<Option<usize>> = g.zero.iter().map(|z| z.cascade.filter(|&x| x == i)).collect();
            let (zero, _) =
                csm_core::truth::frame_zero_in(&culled, &rig.light, &windows, &cascades, &g.points, &sampling);
            for (j, z) in zero.iter().enumerate() {
                if cascades[j].is_none() {
                    continue;
                }
                let (x, y) = (z.answer.unwrap(), g.zero[j].answer.unwrap());
                assert_eq!(
                    (x.lit, x.lit_unbiased),
                    (y.lit, y.lit_unbiased),
                    "{name}: cascade {i}, receiver {j}"
                );
                compared += 1;
            }
        }
        assert!(compared > 1000, "{name}: {compared} receivers compared");
    }
}

/// The objects each cascade keeps under culling (found through the receivers sorted by view
/// depth once per pass and basis, and a range query per cascade) are those of the documented
/// rule applied by brute force: a scan of every sampled pixel for the lit-facing ones in the
/// cascade's depth intervals, their padded light-space box, and each object's world box in
/// light space extruded to the scene's far side. Several λ, so the intervals move.
#[test]
fn culling_keeps_the_objects_of_a_scan_of_every_receiver() {
    let biased = "[shadow]\npcf = 3\nnormal_bias = 2.5\ndepth_bias = 0.01\n";
    for (name, shadow) in [
        ("default", "[shadow]\n"),
        ("village", "[shadow]\n"),
        ("default", biased),
    ] {
        let text = std::fs::read_to_string(format!("{}/configs/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
        let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/configs"));
        for lambda in [0.2, 0.75, 0.95] {
            let text = format!("{text}\n[cost]\ncull = \"receivers\"\n")
                .replace("[shadow]\n", shadow)
                .replace("lambda = 0.75", &format!("lambda = {lambda}"));
            let c = Config::from_toml_str(&text, "c.toml", Some(dir)).unwrap();
            let rig = csm_lab::analysis::rig(&c).unwrap();
            let scene = &c.geometry.as_ref().unwrap().scene;
            let lp = csm_core::cascades::LightPose::new(&rig.light, &c.camera.pose());
            let vis = c.setup().visibility().unwrap();
            let mut kept_some = 0;
            for i in 0..rig.cascade_count() {
                let w = rig.window(i, &lp, c.shadow.snap);
                let v = csm_lab::analysis::cost::volume(&c, &rig, i, &lp, &w);
                let kept = csm_lab::analysis::cost::kept_objects(&c, &rig, i, &v, scene, &vis).unwrap();
                // The rule, by brute force.
                let intervals: Vec<(f64, f64)> = rig.covered_intervals(i).collect();
                let points = vis.samples.iter().enumerate().filter_map(|(k, s)| {
                    let s = s.filter(|s| s.lit && intervals.iter().any(|&(a, b)| s.depth >= a && s.depth <= b))?;
                    Some(vis.position(k, s.depth))
                });
                let texel = v.texel.x.max(v.texel.y);
                let n = c.truth.normal_bias.unwrap_or(0.0).abs().max(1.0);
                let pad_xy = (c.truth.pcf as f64 / 2.0 + 1.5 + n) * texel;
                let pad_z = (n + 1.0) * texel + c.truth.depth_bias.unwrap_or(0.0).abs();
                let target = cost::ReceiverBox::of(&v.basis, points, pad_xy, pad_z);
                let (_, far) = cost::light_depth_extent(&v.basis, &c.scene);
                let expected: Vec<bool> = scene
                    .mesh
                    .objects
                    .iter()
                    .map(|o| {
                        let (lo, hi) = cost::light_bounds_of(&v.basis, &o.bounds);
                        target.is_some_and(|t| t.shadowed_by(lo, hi, far))
                    })
                    .collect();
                assert_eq!(kept, expected, "{name} λ {lambda} cascade {i}");
                kept_some += kept.iter().filter(|&&k| k).count();
            }
            assert!(kept_some > 0, "{name} λ {lambda}: nothing kept");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Sweeps: columns, cost_index against the configured setting, the cost budget
// ---------------------------------------------------------------------------------------------

fn sweep_default(dir: &std::path::Path, sweep_table: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let text = text.split("[sweep]").next().unwrap().to_string() + sweep_table;
    let cfg = dir.join("d.toml");
    std::fs::write(&cfg, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--quiet",
            "--out",
            dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&std::fs::read(dir.join("recommendation.json")).unwrap()).unwrap()
}

/// `sweep.csv` carries the counts and `cost_index` (1 for the configured setting's row, each
/// row's model over the configured one's); a cost budget keeps the recommendation within it
/// and says what it cost in quality; the cost figure is written.
#[test]
fn a_sweep_carries_the_counts_and_recommends_within_a_cost_budget() {
    let grid =
        "[sweep]\nlambda = [0.5, 0.75]\ncascades = [1, 2, 3, 4]\nresolution = [1024, 2048]\nmemory_budget_mib = 64\n";
    let free_tmp = tempfile::tempdir().unwrap();
    let free_dir = free_tmp.path();
    let free = sweep_default(free_dir, grid);
    let (header, rows) = crate::common::read_csv(&free_dir.join("sweep.csv"));
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name} in {header:?}"))
    };
    let at = |r: &Vec<String>, name: &str| r[col(name)].clone();
    let configured = rows
        .iter()
        .find(|r| at(r, "lambda") == "0.75" && at(r, "cascades") == "4" && at(r, "resolution") == "2048")
        .unwrap();
    assert_eq!(at(configured, "cost_index"), "1");
    // Each row's cost_index is its own analysis's model over the configured setting's.
    let text = std::fs::read_to_string(free_dir.join("d.toml")).unwrap();
    let base = Config::from_toml_str(&text, "d.toml", None).unwrap();
    let model = |c: &Config| {
        let a = analyze(c, &AnalysisOptions::summary_only());
        let t = a.summary.cost.counts.unwrap();
        2000.0 * t.caster_objects as f64
            + 0.5 * t.caster_triangles as f64
            + 0.01 * t.raster_fragments
            + 0.002 * a.summary.cost.texels_cleared as f64
    };
    let reference = model(&base);
    for r in &rows {
        let c = base
            .with_lambda(at(r, "lambda").parse().unwrap())
            .unwrap()
            .with_cascades(at(r, "cascades").parse().unwrap())
            .unwrap()
            .with_resolution(at(r, "resolution").parse().unwrap())
            .unwrap();
        let got: f64 = at(r, "cost_index").parse().unwrap();
        assert!((got - model(&c) / reference).abs() < 1e-12, "{r:?}");
        let cleared: u64 = at(r, "texels_cleared").parse().unwrap();
        let (n, res): (u64, u64) = (at(r, "cascades").parse().unwrap(), at(r, "resolution").parse().unwrap());
        assert_eq!(cleared, n * res * res);
        assert!(at(r, "caster_objects").parse::<u64>().unwrap() >= n);
    }
    assert!(free_dir.join("cost_pareto.png").exists());
    let unconstrained = free["recommended"]["cost_index"].as_f64().unwrap();
    // A budget below the free recommendation's cost forces a cheaper one.
    let budget = 0.9 * unconstrained;
    let dir = tempfile::tempdir().unwrap();
    let v = sweep_default(dir.path(), &format!("{grid}cost_budget = {budget}\n"));
    let rec = v["recommended"]["cost_index"].as_f64().unwrap();
    assert!(rec <= budget, "{rec} over {budget}");
    assert_eq!(v["cost_budget"].as_f64(), Some(budget));
    assert_eq!(v["within_cost_budget"], true);
    assert_eq!(v["without_cost_budget"]["configuration"], free["recommended"]);
    let effect = v["cost_budget_effect"].as_str().unwrap();
    assert!(effect.contains("cost quality"), "{effect}");
    let obj = v["objective_metric"].as_str().unwrap();
    assert!(v["recommended"][obj].as_f64().unwrap() >= free["recommended"][obj].as_f64().unwrap());
    // The rows over the budget that beat it on the objective lost on the budget.
    let kinds: Vec<&str> = v["alternatives"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["kind"].as_str().unwrap())
        .collect();
    assert!(!kinds.is_empty());
    // The cheaper-to-render alternative of the free sweep costs less and is on the cost front.
    if let Some(a) = free["alternatives"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["kind"] == "cheaper_to_render")
    {
        assert!(a["configuration"]["cost_index"].as_f64().unwrap() < unconstrained);
        assert!(free["cost_pareto_front"]
            .as_array()
            .unwrap()
            .contains(&a["configuration"]));
    }
}

/// A cost budget without geometry, and milliseconds without calibration, are config errors.
#[test]
fn cost_budgets_need_geometry_and_milliseconds_need_calibration() {
    let e = Config::from_toml_str(
        &format!(
            "{}\n[sweep]\ncascades = [1, 2]\ncost_budget = 0.5\n",
            crate::common::BASE
        ),
        "t.toml",
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("sweep.cost_budget") && e.contains("scene geometry"), "{e}");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let text =
        text.split("[sweep]").next().unwrap().to_string() + "[sweep]\ncascades = [1, 2]\nshadow_ms_budget = 1.0\n";
    let e = Config::from_toml_str(&text, "t.toml", None).unwrap_err().to_string();
    assert!(e.contains("sweep.shadow_ms_budget") && e.contains("calibrated"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Means over the camera path, cached cascades' savings, the update_every axis
// ---------------------------------------------------------------------------------------------

/// The default scene with a short path (and `extra` appended to `[shadow]`).
fn short_path(frames: usize, shadow_extra: &str, tail: &str) -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let text = text.split("[sweep]").next().unwrap().to_string();
    let text = text
        .replace("frames = 240", &format!("frames = {frames}"))
        .replace("[shadow]\n", &format!("[shadow]\n{shadow_extra}\n"));
    assert!(text.contains(&format!("frames = {frames}")));
    text + tail
}

/// The means over the path are, per cascade, the counts of every frame's caster volume
/// counted by brute force (separating axes, a sampled rasterisation), summed over the frames
/// that render the cascade (all, or `t mod k = 0` with a cadence) and divided by the frames
/// walked; a held cascade's cleared texels are resolution² over the share of frames that
/// render it. The totals add the cascades, `cost_index_mean` is the model of the means over
/// the configured frame 0's, and frame 0's counts stay what they were.
#[test]
fn the_means_over_the_path_are_the_brute_force_counts_of_the_frames_rendered() {
    let frames = 12;
    for cadence in ["", "update_every = [1, 1, 2, 4]", "update_every = 3"] {
        let c = Config::from_toml_str(&short_path(frames, cadence, ""), "d.toml", None).unwrap();
        let opts = AnalysisOptions {
            cost_means: true,
            ..AnalysisOptions::summary_only()
        };
        let a = analyze(&c, &opts);
        let plain = analyze(&c, &AnalysisOptions::summary_only());
        assert!(plain.summary.cost.means.is_none());
        assert_eq!(plain.summary.cost.counts, a.summary.cost.counts, "{cadence}");
        let rig = a.rig().unwrap();
        let mesh = &c.geometry.as_ref().unwrap().scene.mesh;
        let every: Vec<usize> = match cadence {
            "" => vec![1; 4],
            "update_every = 3" => vec![3; 4],
            _ => vec![1, 1, 2, 4],
        };
        let setup = c.setup();
        let poses: Vec<_> = csm_core::motion::poses(&setup.camera, &setup.motion)
            .map(|p| p.unwrap())
            .collect();
        assert_eq!(poses.len(), frames);
        let mut total_objects = 0.0;
        for (i, r) in a.cascades.iter().enumerate() {
            let m = r.cost.means.expect("measured");
            let (mut objects, mut tris, mut inside, mut frag, mut bound, mut cleared) =
                (0u64, 0u64, 0u64, 0.0, 0.0, 0u64);
            for (t, pose) in poses.iter().enumerate() {
                if t % every[i] != 0 {
                    continue;
                }
                let lp = csm_core::cascades::LightPose::new(&rig.light, pose);
                let w = rig.window(i, &lp, c.shadow.snap);
                let v = csm_lab::analysis::cost::volume(&c, rig, i, &lp, &w);
                let (o, k, n) = brute_counts(mesh, &v);
                objects += o;
                tris += k;
                inside += n;
                let (f, b) = brute_fragments(mesh, &v, 120);
                frag += f;
                bound += b;
                cleared += 2048 * 2048;
            }
            let f = frames as f64;
            assert_eq!(m.caster_objects_mean, objects as f64 / f, "{cadence} cascade {i}");
            assert_eq!(m.caster_triangles_mean, tris as f64 / f, "{cadence} cascade {i}");
            assert_eq!(
                m.caster_triangles_inside_mean,
                inside as f64 / f,
                "{cadence} cascade {i}"
            );
            assert!(
                (m.raster_fragments_mean - frag / f).abs() <= bound / f,
                "{cadence} cascade {i}: {} against {} ± {}",
                m.raster_fragments_mean,
                frag / f,
                bound / f
            );
            assert_eq!(m.texels_cleared_mean, cleared as f64 / f, "{cadence} cascade {i}");
            // The renders: frame 0 and every k-th frame after it.
            let renders = frames.div_ceil(every[i]) as f64;
            assert_eq!(m.texels_cleared_mean, 2048.0 * 2048.0 * renders / f);
            total_objects += m.caster_objects_mean;
        }
        let t = a.summary.cost.means.unwrap();
        assert!((t.caster_objects_mean - total_objects).abs() < 1e-12);
        let model = |o: f64, k: f64, fr: f64, cl: f64| 2000.0 * o + 0.5 * k + 0.01 * fr + 0.002 * cl;
        let counts = a.summary.cost.counts.unwrap();
        let frame0 = model(
            counts.caster_objects as f64,
            counts.caster_triangles as f64,
            counts.raster_fragments,
            a.summary.cost.texels_cleared as f64,
        );
        let mean = model(
            t.caster_objects_mean,
            t.caster_triangles_mean,
            t.raster_fragments_mean,
            t.texels_cleared_mean,
        );
        assert!((t.cost_index_mean.unwrap() - mean / frame0).abs() < 1e-12, "{cadence}");
        let shares: f64 = a
            .cascades
            .iter()
            .map(|r| r.cost.means.unwrap().cost_index_mean.unwrap())
            .sum();
        assert!((shares - t.cost_index_mean.unwrap()).abs() < 1e-12);
        if !cadence.is_empty() {
            assert!(t.cost_index_mean.unwrap() < 0.9, "{cadence}: caching saves");
        }
    }
}

/// Where the means cannot be measured they are absent, never 0: with receiver-aware culling
/// (the visible receivers are frame 0's) and for a preset whose light basis follows the camera.
#[test]
fn the_means_are_absent_with_culling_and_a_basis_that_follows_the_camera() {
    let opts = AnalysisOptions::full();
    let culled = Config::from_toml_str(&short_path(6, "", "\n[cost]\ncull = \"receivers\"\n"), "d.toml", None).unwrap();
    assert!(analyze(&culled, &opts).summary.cost.means.is_none());
    let filament = Config::from_toml_str(&short_path(6, "preset = \"filament\"", ""), "d.toml", None).unwrap();
    let a = analyze(&filament, &opts);
    assert!(a.summary.cost.counts.is_some());
    assert!(a.summary.cost.means.is_none());
    let json = csm_lab::metric::summary_json(&a.summary);
    assert!(
        json.iter()
            .all(|(k, _)| !k.ends_with("_mean") || k.contains("aliasing")),
        "{json:?}"
    );
    let plain = Config::from_toml_str(&short_path(6, "", ""), "d.toml", None).unwrap();
    assert!(analyze(&plain, &opts).summary.cost.means.is_some());
}

/// The `update_every` axis: each row equals a single-setting sweep of the config with that
/// cadence (the same summary, bit for bit), and `sweep.csv` names the cadence and carries the
/// means and the cached-cascade columns (n/a where a row renders every cascade every frame).
#[test]
fn the_update_every_axis_rows_equal_single_setting_runs() {
    use csm_lab::commands::sweep::grid::{parse_update_every_spec, Grid};
    use csm_lab::commands::sweep::run::run;
    use csm_lab::config::sweep_spec::SweepAxes;
    let tail = "\n[sweep]\nlambda = [0.75]\ncascades = [4]\nresolution = [1024]\n";
    let base = Config::from_toml_str(&short_path(16, "", tail), "d.toml", None).unwrap();
    let axes = SweepAxes {
        update_every: Some(parse_update_every_spec("1,2,1/1/2/4").unwrap()),
        ..SweepAxes::default()
    };
    let grid = Grid::resolve(&base, &axes).unwrap();
    assert_eq!(grid.len(), 3);
    let rows = run(&base, &grid, Some(2), &|| {}).unwrap();
    for (row, value) in rows.iter().zip(["1", "2", "[1, 1, 2, 4]"]) {
        let single_tail = format!("{tail}cost_means = true\n");
        let text = short_path(16, &format!("update_every = {value}"), &single_tail);
        let single = Config::from_toml_str(&text, "d.toml", None).unwrap();
        let one = Grid::resolve(&single, &SweepAxes::default()).unwrap();
        assert_eq!(one.len(), 1);
        let alone = run(&single, &one, Some(1), &|| {}).unwrap();
        assert_eq!(row.summary, alone[0].summary, "update_every = {value}");
        assert!(row.summary.cost.means.is_some(), "{value}");
        assert_eq!(row.summary.cache.is_some(), value != "1", "{value}");
    }
    // The saving: a far cascade held for 4 frames and two held for 2 cost less per frame.
    let mean = |k: usize| rows[k].summary.cost.means.unwrap().cost_index_mean.unwrap();
    assert!(mean(1) < mean(2) && mean(2) < mean(0));
    assert_eq!(rows[0].summary.cost.cost_index, rows[1].summary.cost.cost_index);

    // On the command line: the column, the means, and n/a for the uncached row.
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("d.toml");
    std::fs::write(&cfg, short_path(16, "", tail)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--quiet",
            "--no-plots",
            "--update-every",
            "1,1/1/2/4",
            "--out",
        ])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (header, csv) = crate::common::read_csv(&dir.path().join("out/sweep.csv"));
    let at = |r: usize, name: &str| {
        csv[r][header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name} in {header:?}"))]
        .clone()
    };
    assert_eq!(
        (at(0, "shadow.update_every"), at(1, "shadow.update_every")),
        ("1".into(), "1/1/2/4".into())
    );
    assert_eq!(
        (at(0, "renders_per_frame"), at(1, "renders_per_frame")),
        ("n/a".into(), "2.75".into())
    );
    assert!(at(1, "cost_index_mean").parse::<f64>().unwrap() < at(0, "cost_index_mean").parse::<f64>().unwrap());
    assert!(!header.iter().any(|h| h == "shadow_ms"));

    // A per-cascade cadence of another cascade count is refused, naming the key.
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args([
            "sweep",
            cfg.to_str().unwrap(),
            "--quiet",
            "--no-plots",
            "--update-every",
            "1/2",
            "--out",
        ])
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let e = String::from_utf8_lossy(&bad.stderr);
    assert!(e.contains("shadow.update_every") && e.contains("[1, 2]"), "{e}");
    let e = parse_update_every_spec("1,0").unwrap_err().to_string();
    assert!(e.contains("--update-every") && e.contains("1..=256"), "{e}");
    let e = parse_update_every_spec("2,2").unwrap_err().to_string();
    assert!(e.contains("twice"), "{e}");
}

/// A calibrated sweep writes `shadow_ms` per row (the calibrated model of the row's counts);
/// an uncalibrated one never does.
#[test]
fn a_calibrated_sweep_writes_shadow_ms_per_row() {
    let dir = tempfile::tempdir().unwrap();
    let tail = "\n[sweep]\nlambda = [0.5, 0.75]\ncascades = [2, 4]\nresolution = [1024]\n\n[cost]\nns_per_draw = 3000.0\nns_per_triangle = 0.5\nns_per_fragment = 0.02\nns_per_texel_cleared = 0.004\n";
    let cfg = dir.path().join("d.toml");
    std::fs::write(&cfg, short_path(8, "", tail)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(["sweep", cfg.to_str().unwrap(), "--quiet", "--no-plots", "--out"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (header, csv) = crate::common::read_csv(&dir.path().join("out/sweep.csv"));
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name}"))
    };
    assert_eq!(csv.len(), 4);
    for r in &csv {
        let x = |n: &str| r[col(n)].parse::<f64>().unwrap();
        let ns = 3000.0 * x("caster_objects")
            + 0.5 * x("caster_triangles")
            + 0.02 * x("raster_fragments")
            + 0.004 * x("texels_cleared");
        assert!((x("shadow_ms") - ns * 1e-6).abs() <= 1e-12 * (1.0 + ns), "{r:?}");
    }
}

/// `[cost] counts = false` skips the counts (absent, as without geometry; every other metric
/// as with them), and refuses what needs them: a render-cost budget, culling.
#[test]
fn counts_can_be_switched_off_and_then_nothing_needs_them() {
    let on = Config::from_toml_str(&short_path(6, "", ""), "d.toml", None).unwrap();
    let off = Config::from_toml_str(&short_path(6, "", "\n[cost]\ncounts = false\n"), "d.toml", None).unwrap();
    let (a, b) = (
        analyze(&on, &AnalysisOptions::full()),
        analyze(&off, &AnalysisOptions::full()),
    );
    assert!(a.summary.cost.counts.is_some() && a.summary.cost.means.is_some());
    assert_eq!(b.summary.cost.counts, None);
    assert_eq!((b.summary.cost.cost_index, b.summary.cost.means), (None, None));
    assert_eq!(b.summary.cost.texels_cleared, a.summary.cost.texels_cleared);
    let mut without_cost = b.summary.clone();
    without_cost.cost = a.summary.cost;
    assert_eq!(without_cost, a.summary, "counting changes no other metric");
    for (tail, key) in [
        ("\n[cost]\ncounts = false\ncull = \"receivers\"\n", "cost.cull"),
        (
            "\n[sweep]\ncost_budget = 0.8\n\n[cost]\ncounts = false\n",
            "sweep.cost_budget",
        ),
    ] {
        let e = Config::from_toml_str(&short_path(6, "", tail), "d.toml", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains(key) && e.contains("counts = false"), "{e}");
    }
}
