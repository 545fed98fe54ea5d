//! The sun's position as a compass azimuth and an elevation, and the light direction it gives.
//!
//! World space is right-handed with +Y up (see [`crate::geometry`]). Looking down from +Y, −Z is
//! north and +X is east. The **azimuth** is the compass bearing of the sun, measured from north
//! (−Z) toward east (+X); the **elevation** is its angle above the horizontal plane. Both are in
//! radians here (degrees exist only at the config boundary). The direction *toward* the sun is
//!
//! ```text
//! s = (cos e · sin a,  sin e,  −cos e · cos a)
//! ```
//!
//! and the light direction of the crate, the way light travels, is `L = −s`. A sun above the
//! horizon has `0 < e ≤ π/2`; at `e = π/2` the azimuth is undefined and taken as 0.

use glam::DVec3;

/// Where the sun stands in the sky, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunAngles {
    /// Compass bearing from north (−Z) toward east (+X).
    pub azimuth: f64,
    /// Angle above the horizon.
    pub elevation: f64,
}

impl SunAngles {
    /// The unit direction in which this sun's light travels.
    pub fn light_direction(self) -> DVec3 {
        let (se, ce) = self.elevation.sin_cos();
        let (sa, ca) = self.azimuth.sin_cos();
        -DVec3::new(ce * sa, se, -ce * ca)
    }

    /// The sun of a light direction (need not be unit length; must not be zero). The azimuth is
    /// in (−π, π], 0 when the light is vertical; the elevation is negative for light that travels
    /// upward (a sun below the horizon).
    pub fn of_light_direction(light: DVec3) -> SunAngles {
        let s = -light.normalize();
        let horizontal = (s.x * s.x + s.z * s.z).sqrt();
        // atan2 of both components (rather than asin of s.y) keeps full precision near the
        // zenith, where asin's slope is infinite.
        let elevation = s.y.atan2(horizontal);
        let azimuth = if horizontal == 0.0 { 0.0 } else { s.x.atan2(-s.z) };
        SunAngles { azimuth, elevation }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn compass_points_give_the_expected_light() {
        // A sun low in the north sends light south (+Z), in the east sends it west (−X).
        let north = SunAngles {
            azimuth: 0.0,
            elevation: 0.0,
        };
        assert!(close(north.light_direction(), DVec3::new(0.0, 0.0, 1.0)));
        let east = SunAngles {
            azimuth: FRAC_PI_2,
            elevation: 0.0,
        };
        assert!(close(east.light_direction(), DVec3::new(-1.0, 0.0, 0.0)));
        let zenith = SunAngles {
            azimuth: 1.0,
            elevation: FRAC_PI_2,
        };
        assert!(close(zenith.light_direction(), DVec3::new(0.0, -1.0, 0.0)));
        let mid = SunAngles {
            azimuth: PI,
            elevation: FRAC_PI_4,
        };
        let h = FRAC_PI_4.cos();
        assert!(close(mid.light_direction(), DVec3::new(0.0, -h, -h)));
    }

    #[test]
    fn angles_round_trip_through_the_direction() {
        for ai in -11..=12 {
            for ei in 1..=17 {
                let sun = SunAngles {
                    azimuth: ai as f64 * PI / 12.0,
                    elevation: ei as f64 * FRAC_PI_2 / 18.0,
                };
                let back = SunAngles::of_light_direction(sun.light_direction() * 3.0);
                assert!((back.elevation - sun.elevation).abs() < 1e-12, "{sun:?} → {back:?}");
                assert!((back.azimuth - sun.azimuth).abs() < 1e-12, "{sun:?} → {back:?}");
            }
        }
        let vertical = SunAngles::of_light_direction(DVec3::new(0.0, -2.0, 0.0));
        assert_eq!(
            vertical,
            SunAngles {
                azimuth: 0.0,
                elevation: FRAC_PI_2
            }
        );
    }
}
