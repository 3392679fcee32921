//! The sun and the air: where the sun stands, the colour its light has when it reaches the ground,
//! and the haze the aerial perspective integrates.
//!
//! Rules:
//! - The sun's direction follows `light.sun_azimuth_deg` (0 north, 90 east) and
//!   `light.sun_elevation_deg`; x is east, y north, z up.
//! - Its colour is the extraterrestrial sun dimmed by the air it crosses: Rayleigh extinction
//!   (β_R = 5.8, 13.5, 33.1 ·10⁻⁶ /m at sea level, scale height 8 km) and haze (β_M = 3.912 /
//!   visibility, scale height `light.haze_height_m`), over the air mass of Kasten and Young (1989),
//!   which stays finite at the horizon. It is normalised so that a sun at 35° (the default)
//!   gives the warm white the surfaces were tuned under; a low sun turns orange and red.
//! - The same two media, each thinning exponentially with height, are what the shaders'
//!   aerial perspective integrates between the eye and the ground (`shaders/shared/shading.wgsl`),
//!   so a view from 20 km crosses little air and keeps its contrast.
//!
//! Rejected alternative: a fixed fog density at every height (the previous shading,
//! 3.5·10⁻⁵ /m). From 20 km up it put 1 − e^(−0.98) = 62 % of the horizon's colour over the whole
//! Jacksboro view (terrain luminance standard deviation 0.026 at 256²).

use glam::DVec3;

/// Rayleigh extinction at sea level, per metre, for red, green and blue.
pub const RAYLEIGH: [f64; 3] = [5.8e-6, 13.5e-6, 33.1e-6];
/// Rayleigh scale height, metres.
pub const RAYLEIGH_SCALE_M: f64 = 8000.0;
/// Koschmieder's constant: haze extinction = 3.912 / visibility (2 % contrast left).
const KOSCHMIEDER: f64 = 3.912;
/// The elevation the surfaces' colours were tuned under.
const REFERENCE_ELEVATION_DEG: f64 = 35.0;

/// What a frame needs of the sun and the air.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit vector toward the sun.
    pub sun: DVec3,
    /// The sun's light on the ground, linear RGB (1.1 × a warm white at 35°).
    pub sun_colour: [f64; 3],
    /// How much of the day's sky light there is: 1 by day, fading to 0 as the sun sets.
    pub daylight: f64,
    /// Haze extinction at sea level, per metre.
    pub haze_per_m: f64,
    pub haze_height_m: f64,
}

impl Light {
    pub fn new(
        azimuth_deg: f64,
        elevation_deg: f64,
        visibility_km: f64,
        haze_height_m: f64,
    ) -> Light {
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        let sun = DVec3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin());
        let haze_per_m = KOSCHMIEDER / (visibility_km * 1000.0);
        let t = transmittance(elevation_deg, haze_per_m, haze_height_m);
        let t_ref = transmittance(REFERENCE_ELEVATION_DEG, haze_per_m, haze_height_m);
        let white = [1.1, 1.045, 0.935];
        let sun_colour = [0, 1, 2].map(|c| white[c] * t[c] / t_ref[c]);
        // Civil twilight: the sky's light fades from 10° up to 6° below the horizon.
        let s = ((elevation_deg + 6.0) / 16.0).clamp(0.0, 1.0);
        Light {
            sun,
            sun_colour,
            daylight: s * s * (3.0 - 2.0 * s),
            haze_per_m,
            haze_height_m,
        }
    }
}

/// Kasten and Young's relative air mass at `elevation_deg` (1 at the zenith, 38 at the horizon).
pub fn air_mass(elevation_deg: f64) -> f64 {
    let h = elevation_deg.max(0.0);
    1.0 / (h.to_radians().sin() + 0.50572 * (h + 6.07995).powf(-1.6364))
}

/// The fraction of sunlight at sea level, per channel, after the air column at `elevation_deg`.
fn transmittance(elevation_deg: f64, haze_per_m: f64, haze_height_m: f64) -> [f64; 3] {
    let m = air_mass(elevation_deg);
    RAYLEIGH.map(|r| (-(r * RAYLEIGH_SCALE_M + haze_per_m * haze_height_m) * m).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn azimuth_90_is_east_and_elevation_90_straight_up() {
        let east = Light::new(90.0, 0.0, 100.0, 1200.0).sun;
        assert!((east - DVec3::X).length() < 1e-12, "{east}");
        let north = Light::new(0.0, 30.0, 100.0, 1200.0).sun;
        assert!(north.x.abs() < 1e-12 && north.y > 0.8);
        let up = Light::new(123.0, 90.0, 100.0, 1200.0).sun;
        assert!((up - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn the_sun_reddens_and_the_sky_dims_as_it_sets() {
        let at = |el: f64| Light::new(150.0, el, 100.0, 1200.0);
        let noon = at(35.0);
        for (c, want) in noon.sun_colour.iter().zip([1.1, 1.045, 0.935]) {
            assert!((c - want).abs() < 1e-12, "{:?}", noon.sun_colour);
        }
        let mut last_ratio = 0.0;
        for el in [35.0, 20.0, 10.0, 5.0, 2.0, 0.0] {
            let l = at(el);
            let ratio = l.sun_colour[0] / l.sun_colour[2];
            assert!(ratio > last_ratio, "{el}°: red/blue {ratio}");
            assert!(l.sun_colour.iter().all(|c| c.is_finite() && *c >= 0.0));
            last_ratio = ratio;
        }
        // Below the horizon the air mass stays the horizon's: dim, red, finite.
        assert!(
            at(-30.0)
                .sun_colour
                .iter()
                .all(|c| c.is_finite() && *c >= 0.0)
        );
        assert_eq!(at(35.0).daylight, 1.0);
        assert!(at(0.0).daylight < 0.5 && at(-6.0).daylight == 0.0);
    }

    #[test]
    fn air_mass_is_one_at_the_zenith_and_finite_below_the_horizon() {
        assert!((air_mass(90.0) - 1.0).abs() < 1e-3);
        assert!((air_mass(0.0) - 38.0).abs() < 0.2, "{}", air_mass(0.0));
        assert_eq!(air_mass(-10.0), air_mass(0.0));
    }
}
