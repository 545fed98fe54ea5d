//! Fitting a shadow window around a slice of the view frustum.
//!
//! Slices are described in view coordinates by their depths `n < f` and the lens (`k^2 =
//! tanH^2 + tanV^2`); by symmetry every sphere below is centred on the view axis at depth
//! `centre_depth`. A [`Window`] is a rectangle in light-space x/y plus a resolution; its
//! position is kept in *texel units* so snapped windows sit on exact integers.

use glam::DVec2;

use crate::snapping::SnapRule;

/// How the window of a cascade is fitted around its slice of the view frustum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Fit {
    /// Minimal bounding sphere of the slice (closed form): a square window whose size depends
    /// only on the lens and the split depths, so it never changes as the camera moves or turns.
    /// Costs about 2x the texel area of a tight box on average, buys exact stability.
    Sphere,
    /// Tight light-space bounding box of the slice's 8 corners, refitted every frame. Sharper
    /// (smaller texels) but its size changes whenever the camera turns, which snapping cannot fix.
    Aabb,
}

impl Fit {
    pub fn name(self) -> &'static str {
        match self {
            Fit::Sphere => "sphere",
            Fit::Aabb => "aabb",
        }
    }
}

impl std::fmt::Display for Fit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A sphere on the view axis: centre at view depth `centre_depth`, radius `radius`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub centre_depth: f64,
    pub radius: f64,
}

/// The minimal bounding sphere of the slice `[n, f]`, in closed form.
///
/// The near corners' distance to an axis point grows with its depth and the far corners'
/// shrinks, so the minimax centre is where they are equal, unless that lies beyond `f`, in
/// which case the far cap alone decides (`c = f`, `R = k f`). Because R depends only on
/// `(n, f, lens)` and never on transformed corners, it is bit-identical in every frame: the
/// texel size never jitters, with no radius-rounding tricks needed.
pub fn minimal_sphere(n: f64, f: f64, k2: f64) -> Sphere {
    if k2 >= (f - n) / (f + n) {
        Sphere {
            centre_depth: f,
            radius: k2.sqrt() * f,
        }
    } else {
        let c = 0.5 * (f + n) * (1.0 + k2);
        Sphere {
            centre_depth: c,
            radius: (k2 * f * f + (f - c) * (f - c)).sqrt(),
        }
    }
}

/// Centre at the mean of the 8 corners, radius to the farthest corner (Godot, Filament stable,
/// later EEVEE, MJP, seed 000). Never smaller than the minimal sphere.
pub fn corner_average_sphere(n: f64, f: f64, k2: f64) -> Sphere {
    let half = 0.5 * (f - n);
    Sphere {
        centre_depth: 0.5 * (n + f),
        radius: (k2 * f * f + half * half).sqrt(),
    }
}

/// Centre on the far cap (EEVEE 2017, seed 003): minimal only in the far-cap case.
pub fn far_cap_sphere(n: f64, f: f64, k2: f64) -> Sphere {
    Sphere {
        centre_depth: f,
        radius: (k2 * f * f).sqrt().max((k2 * n * n + (f - n) * (f - n)).sqrt()),
    }
}

/// Largest distance between two corners of the slice: the far-cap diagonal or the body
/// diagonal (three.js, Bevy window side before rounding).
pub fn slice_diameter(n: f64, f: f64, k2: f64) -> f64 {
    (2.0 * k2.sqrt() * f).max((k2 * (f + n) * (f + n) + (f - n) * (f - n)).sqrt())
}

/// A shadow-map window in light space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// World size of one texel along light x and y.
    pub texel: DVec2,
    /// The window's minimum corner divided by the texel size. Snapped windows keep this on
    /// whole numbers (or whole plus a constant half for odd resolutions).
    pub origin_texels: DVec2,
    /// Texels per side.
    pub resolution: u32,
}

impl Window {
    /// Window of side `size` (world units per axis) centred at light-space `centre`.
    /// With `snap`, the centre is moved onto the rule's grid in texel units.
    pub fn centred(centre: DVec2, size: DVec2, resolution: u32, snap: Option<SnapRule>) -> Window {
        let n = resolution as f64;
        let texel = size / n;
        let mut centre_texels = centre / texel;
        if let Some(rule) = snap {
            centre_texels = DVec2::new(rule.apply(centre_texels.x), rule.apply(centre_texels.y));
        }
        Window {
            texel,
            origin_texels: centre_texels - DVec2::splat(0.5 * n),
            resolution,
        }
    }

    /// Window side that leaves just enough border for `extent` to stay inside after a snap
    /// that moves the centre by up to `shift` texels: `W = extent + 2*shift*W/N`.
    pub fn side_with_border(extent: f64, resolution: u32, shift_texels: f64) -> f64 {
        let n = resolution as f64;
        extent * n / (n - 2.0 * shift_texels)
    }

    pub fn width(&self) -> f64 {
        self.texel.x * self.resolution as f64
    }

    pub fn height(&self) -> f64 {
        self.texel.y * self.resolution as f64
    }

    /// The larger of the two texel sizes: the one that limits shadow detail.
    pub fn texel_size(&self) -> f64 {
        self.texel.x.max(self.texel.y)
    }

    pub fn centre(&self) -> DVec2 {
        (self.origin_texels + DVec2::splat(0.5 * self.resolution as f64)) * self.texel
    }

    pub fn min(&self) -> DVec2 {
        self.origin_texels * self.texel
    }

    /// Texel coordinates of a light-space point: 0 at the window's minimum edge, N at its
    /// maximum. Computed as `p/T - origin` so that, for a static point and a fixed texel size,
    /// `p/T` is the same number every frame and frame differences are exact.
    pub fn texel_coords(&self, light_xy: DVec2) -> DVec2 {
        light_xy / self.texel - self.origin_texels
    }

    /// How far outside the window a point lies, in texels (0 when inside).
    pub fn outside_by_texels(&self, light_xy: DVec2) -> f64 {
        let s = self.texel_coords(light_xy);
        let n = self.resolution as f64;
        let ox = (-s.x).max(s.x - n).max(0.0);
        let oy = (-s.y).max(s.y - n).max(0.0);
        ox.max(oy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use glam::DVec3;

    fn k2(fov_deg: f64, aspect: f64) -> f64 {
        let lens = crate::geometry::Lens::new(fov_deg.to_radians(), aspect);
        lens.k2()
    }

    fn corners(n: f64, f: f64, tan_h: f64, tan_v: f64) -> Vec<DVec3> {
        let mut v = Vec::new();
        for z in [n, f] {
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    v.push(DVec3::new(sx * tan_h * z, sy * tan_v * z, z));
                }
            }
        }
        v
    }

    /// Exact minimal enclosing sphere by brute force over all 2-, 3- and 4-point support sets.
    fn brute_force_sphere(points: &[DVec3]) -> (DVec3, f64) {
        let n = points.len();
        let mut best = (DVec3::ZERO, f64::INFINITY);
        let mut consider = |c: DVec3, r: f64| {
            if r < best.1 && points.iter().all(|p| (*p - c).length() <= r * (1.0 + 1e-12) + 1e-12) {
                best = (c, r);
            }
        };
        for i in 0..n {
            for j in i + 1..n {
                let c = 0.5 * (points[i] + points[j]);
                consider(c, (points[i] - c).length());
                for k in j + 1..n {
                    // Circumcircle centre of a triangle, in its plane.
                    let a = points[i];
                    let ab = points[j] - a;
                    let ac = points[k] - a;
                    let nrm = ab.cross(ac);
                    let d = 2.0 * nrm.length_squared();
                    if d > 1e-18 {
                        let c = a + (ac.length_squared() * nrm.cross(ab) + ab.length_squared() * ac.cross(nrm)) / d;
                        consider(c, (a - c).length());
                    }
                    for pl in &points[k + 1..] {
                        // Circumsphere of a tetrahedron: solve 2(p_m - a).c' = |p_m|^2 - |a|^2.
                        let ad = *pl - a;
                        let m = glam::DMat3::from_cols(ab, ac, ad).transpose();
                        if m.determinant().abs() > 1e-12 {
                            let rhs = 0.5 * DVec3::new(ab.length_squared(), ac.length_squared(), ad.length_squared());
                            let c = a + m.inverse() * rhs;
                            consider(c, (a - c).length());
                        }
                    }
                }
            }
        }
        best
    }

    #[test]
    fn minimal_sphere_matches_brute_force_on_random_slices() {
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut near_far_cases = 0;
        for _ in 0..300 {
            let fov = rng.range(5.0, 120.0);
            let aspect = rng.range(0.3, 4.0);
            let n = 10f64.powf(rng.range(-2.0, 2.0));
            let f = n * 10f64.powf(rng.range(0.01, 3.0));
            let lens = crate::geometry::Lens::new(fov.to_radians(), aspect);
            let s = minimal_sphere(n, f, lens.k2());
            let (c, r) = brute_force_sphere(&corners(n, f, lens.tan_h, lens.tan_v));
            assert!(
                (s.radius - r).abs() <= 1e-12 * r,
                "fov {fov} aspect {aspect} [{n}, {f}]: {} vs {r}",
                s.radius
            );
            assert!((s.centre_depth - c.z).abs() <= 1e-12 * r.max(c.z.abs()));
            assert!(c.x.abs() < 1e-9 * r && c.y.abs() < 1e-9 * r);
            if s.centre_depth < f {
                near_far_cases += 1;
            }
        }
        assert!(near_far_cases > 20, "both branches exercised ({near_far_cases})");
    }

    #[test]
    fn sphere_reference_values() {
        // Hand-computed radii and texel-area ratios for a 60 degree, 16:9 lens.
        let k2_60 = k2(60.0, 16.0 / 9.0);
        assert_relative_eq!(k2_60, 1.386831, epsilon = 1e-6);
        for ((n, f), (r_min, ratio)) in [(0.1, 5.0), (5.0, 20.0), (20.0, 80.0), (80.0, 200.0)].into_iter().zip([
            (5.88819, 1.08311),
            (23.55276, 1.04948),
            (94.21104, 1.04948),
            (235.52760, 1.03194),
        ]) {
            let s = minimal_sphere(n, f, k2_60);
            assert_eq!(s.centre_depth, f);
            assert_relative_eq!(s.radius, r_min, epsilon = 1e-5);
            assert_relative_eq!(
                corner_average_sphere(n, f, k2_60).radius / s.radius,
                ratio,
                epsilon = 1e-5
            );
        }
        let k2_30 = k2(30.0, 1.0);
        let s = minimal_sphere(5.0, 20.0, k2_30);
        assert_relative_eq!(s.centre_depth, 14.2949, epsilon = 1e-4);
        assert_relative_eq!(s.radius, 9.48606, epsilon = 1e-5);
        assert_relative_eq!(
            slice_diameter(5.0, 20.0, k2_30) / (2.0 * s.radius),
            1.0 / (1.0 + k2_30).sqrt(),
            epsilon = 1e-12
        );
        assert_relative_eq!(slice_diameter(0.1, 25.372, k2_60), 59.758, epsilon = 1e-3);
        for ((n, f), ratio) in [(0.1, 5.0), (5.0, 20.0), (20.0, 80.0), (80.0, 200.0)]
            .into_iter()
            .zip([1.740, 1.594, 1.594, 1.445])
        {
            assert_relative_eq!(
                far_cap_sphere(n, f, k2_30).radius / minimal_sphere(n, f, k2_30).radius,
                ratio,
                epsilon = 1e-3
            );
        }
    }

    #[test]
    fn window_border_keeps_extent_inside_after_snapping() {
        let rule = SnapRule::default();
        let side = Window::side_with_border(10.0, 64, rule.max_shift_texels());
        assert_relative_eq!(side, 10.0 * 64.0 / 63.0, epsilon = 1e-12);
        let w = Window::centred(DVec2::new(3.3, -7.7), DVec2::splat(side), 64, Some(rule));
        assert_eq!(w.origin_texels.x.fract(), 0.0);
        // The worst points of a 10-wide extent around the true centre stay inside.
        for p in [DVec2::new(3.3 - 5.0, -7.7 - 5.0), DVec2::new(3.3 + 5.0, -7.7 + 5.0)] {
            assert!(w.outside_by_texels(p) <= 1e-9);
        }
    }
}
