//! The sun and the air: where the sun stands, the light it and the sky shed on the ground, the
//! sky's colour and the aerial perspective, from one reduced single-scattering atmosphere.
//!
//! Rules:
//! - The sun's direction follows `light.sun_azimuth_deg` (0 north, 90 east) and
//!   `light.sun_elevation_deg`; x is east, y north, z up.
//! - The atmosphere is plane-parallel: air (Rayleigh, β_R = 5.8, 13.5, 33.1 ·10⁻⁶ /m at sea
//!   level, scale height 8 km) and haze (Mie, β_M = 3.912 / visibility, scale height
//!   `light.haze_height_m`, single-scattering albedo 0.9, Cornette–Shanks phase with g = 0.76),
//!   each thinning exponentially with height. Sunlight reaching height z has crossed the column
//!   above z times the air mass of Kasten and Young (1989), which stays finite at the horizon.
//! - The sky along a ray, and the light the air between the eye and the ground scatters toward
//!   the eye (aerial perspective), are the single-scattering integral of that sunlight over the
//!   ray, in [`STEPS`] samples spaced quadratically from the eye (where the light comes from),
//!   plus an isotropic share for the orders of scattering the integral leaves out
//!   ([`MULTIPLE`]). Reduced from Hillaire (2020) to what a planar frame needs: no look-up
//!   tables, no planet curvature (rays are cut at [`TOP_M`] and [`FAR_M`]).
//! - `shaders/shared/shading.wgsl` evaluates the same integral per pixel (its twin, held to it by
//!   tests/gpu.rs); here it runs once per scene, to integrate the sky's light on level ground
//!   ([`Light::sky_light`]), which the shading applies to every surface by how much of the sky
//!   it faces.
//! - Light is in units where a white surface facing a sun of irradiance 1 has radiance 1
//!   (radiance × π): the sun above the air is normalised so that a sun at 35° in the default
//!   air (visibility 100 km, haze height 1200 m) lights sea level with 1.1 × a warm white, the
//!   light the surfaces were tuned under.
//! - Exposure is metered as a photographer's "sunny 16": a level 18 % grey card under a 35° sun
//!   in the scene's air comes out at middle grey (0.18), so a low sun or a hazy day darkens the
//!   picture as it would a fixed camera's; `light.exposure_ev` adds stops before the tone map.
//!
//! Rejected alternatives: a fixed fog density at every height (3.5·10⁻⁵ /m; from 20 km up it put
//! 62 % of the horizon's colour over the whole Jacksboro view, terrain luminance standard
//! deviation 0.026 at 256²); and a hand-painted sky gradient with the aerial perspective fading
//! to the horizon's colour, which made the sky light on the ground a free constant (0.23 of a
//! white surface's, twice the 0.1–0.15 a clear sky gives) and lit the lee of every ridge.

use glam::DVec3;

/// Rayleigh extinction at sea level, per metre, for red, green and blue.
pub const RAYLEIGH: [f64; 3] = [5.8e-6, 13.5e-6, 33.1e-6];
/// Rayleigh scale height, metres.
pub const RAYLEIGH_SCALE_M: f64 = 8000.0;
/// Koschmieder's constant: haze extinction = 3.912 / visibility (2 % contrast left).
const KOSCHMIEDER: f64 = 3.912;
/// The share of the haze's extinction that scatters (the rest is absorbed).
pub const HAZE_ALBEDO: f64 = 0.9;
/// Cornette–Shanks asymmetry of the haze's phase function.
pub const MIE_G: f64 = 0.76;
/// Isotropic phase added for multiple scattering, as a share of 1/(4π).
pub const MULTIPLE: f64 = 1.0;
/// Samples of the single-scattering integral along a ray.
pub const STEPS: usize = 12;
/// Rays through the sky end at this height...
pub const TOP_M: f64 = 60_000.0;
/// ...or this far, the horizon of a planar world.
pub const FAR_M: f64 = 400_000.0;
/// The elevation the surfaces' colours were tuned under.
const REFERENCE_ELEVATION_DEG: f64 = 35.0;
/// The sunlight at sea level under the reference elevation (a warm white).
const REFERENCE_WHITE: [f64; 3] = [1.1, 1.045, 0.935];

/// What a frame needs of the sun and the air.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit vector toward the sun.
    pub sun: DVec3,
    /// The sunlight above the air, linear RGB.
    pub sun_top: [f64; 3],
    /// Kasten–Young air mass of the sun's elevation.
    pub air_mass: f64,
    /// The sunlight at sea level, linear RGB.
    pub sun_colour: [f64; 3],
    /// How much of the day's sky light there is: 1 by day, fading to 0 as the sun sets.
    pub daylight: f64,
    /// The sky's light on level ground at sea level (irradiance, in the units of `sun_colour`).
    pub sky_light: [f64; 3],
    /// Haze extinction at sea level, per metre.
    pub haze_per_m: f64,
    /// The haze's scale height, metres: its density falls by e every `haze_height_m` up
    /// (`light.haze_height_m`, default 1200).
    pub haze_height_m: f64,
    /// The factor light is scaled by before the tone map: 2^exposure_ev.
    pub exposure: f64,
}

impl Light {
    /// The sun at compass `azimuth_deg` (0 north, 90 east) and `elevation_deg` above the horizon,
    /// haze of meteorological visibility `visibility_km` at sea level and scale height
    /// `haze_height_m`, and the picture scaled by `2^exposure_ev` (the `[light]` keys).
    pub fn new(
        azimuth_deg: f64,
        elevation_deg: f64,
        visibility_km: f64,
        haze_height_m: f64,
        exposure_ev: f64,
    ) -> Light {
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        let sun = DVec3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin());
        let haze_per_m = KOSCHMIEDER / (visibility_km * 1000.0);
        // The sun above the air: what leaves the reference white under the default air.
        let default_air = column_above(0.0, KOSCHMIEDER / 100_000.0, 1200.0);
        let m_ref = air_mass(REFERENCE_ELEVATION_DEG);
        let sun_top = [0, 1, 2].map(|c| REFERENCE_WHITE[c] * (m_ref * default_air[c]).exp());
        let air_mass = air_mass(elevation_deg);
        // Civil twilight: the sky's light fades from 10° up to 6° below the horizon.
        let s = ((elevation_deg + 6.0) / 16.0).clamp(0.0, 1.0);
        let mut light = Light {
            sun,
            sun_top,
            air_mass,
            sun_colour: [0.0; 3],
            daylight: s * s * (3.0 - 2.0 * s),
            sky_light: [0.0; 3],
            haze_per_m,
            haze_height_m,
            exposure: exposure_ev.exp2(),
        };
        light.sun_colour = light.sun_at(0.0);
        light.sky_light = light.sky_irradiance(0.0);
        // Metering: the same air under the reference sun.
        let reference = if elevation_deg == REFERENCE_ELEVATION_DEG {
            light
        } else {
            Light::new(
                azimuth_deg,
                REFERENCE_ELEVATION_DEG,
                visibility_km,
                haze_height_m,
                0.0,
            )
        };
        light.exposure *= reference.metered();
        light
    }

    /// The exposure that renders a level 18 % grey card under this sun at 0.18.
    fn metered(&self) -> f64 {
        let card = [0, 1, 2].map(|c| self.sun_colour[c] * self.sun.z + self.sky_light[c]);
        1.0 / luminance(card)
    }

    /// The sunlight reaching height `z`.
    pub fn sun_at(&self, z: f64) -> [f64; 3] {
        let column = column_above(z, self.haze_per_m, self.haze_height_m);
        [0, 1, 2].map(|c| self.sun_top[c] * (-self.air_mass * column[c]).exp())
    }

    /// The light scattered toward the eye at height `eye_z` from `len` metres along `dir`, and
    /// what that stretch of air lets through of the light behind it.
    pub fn scatter(&self, eye_z: f64, dir: DVec3, len: f64) -> ([f64; 3], [f64; 3]) {
        let (hr, hm) = (RAYLEIGH_SCALE_M, self.haze_height_m);
        let mu = dir.dot(self.sun);
        let rayleigh_phase = 3.0 / 16.0 * (1.0 + mu * mu);
        let g = MIE_G;
        let mie_phase = 3.0 / 8.0 * (1.0 - g * g) * (1.0 + mu * mu)
            / ((2.0 + g * g) * (1.0 + g * g - 2.0 * g * mu).powf(1.5));
        let iso = MULTIPLE * 0.25;
        let mut inscatter = [0.0; 3];
        for i in 0..STEPS {
            let u = (i as f64 + 0.5) / STEPS as f64;
            let t = len * u * u;
            let dt = len * 2.0 * u / STEPS as f64;
            let z = eye_z + dir.z * t;
            let (air, haze) = (density(z, hr), density(z, hm));
            let (air_t, haze_t) = (air_along(eye_z, z, t, hr), air_along(eye_z, z, t, hm));
            let sun = self.sun_at(z);
            for c in 0..3 {
                let scattered = RAYLEIGH[c] * air * (rayleigh_phase + iso)
                    + self.haze_per_m * HAZE_ALBEDO * haze * (mie_phase + iso);
                let tau = RAYLEIGH[c] * air_t + self.haze_per_m * haze_t;
                inscatter[c] += scattered * (-tau).exp() * sun[c] * dt;
            }
        }
        let z1 = eye_z + dir.z * len;
        let (air_t, haze_t) = (air_along(eye_z, z1, len, hr), air_along(eye_z, z1, len, hm));
        let through = [0, 1, 2].map(|c| (-(RAYLEIGH[c] * air_t + self.haze_per_m * haze_t)).exp());
        (inscatter.map(|v| v * self.daylight), through)
    }

    /// `light` exposed and tone-mapped as a pixel shows it: display-referred linear RGB, before
    /// sRGB encoding.
    pub fn display(&self, light: [f64; 3]) -> [f64; 3] {
        display(light, self.exposure)
    }

    /// The sky seen from height `eye_z` along `dir` (without the sun's disc).
    pub fn sky(&self, eye_z: f64, dir: DVec3) -> [f64; 3] {
        self.scatter(eye_z, dir, sky_length(eye_z, dir)).0
    }

    /// The sky's light on level ground at height `z`: ∫ sky · cos θ dω / π over the upper
    /// hemisphere, by the midpoint rule in cos² θ (uniform in projected solid angle).
    pub fn sky_irradiance(&self, z: f64) -> [f64; 3] {
        let (rings, sectors) = (16, 32);
        let mut sum = [0.0; 3];
        for i in 0..rings {
            let cos_theta = ((i as f64 + 0.5) / rings as f64).sqrt();
            let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
            for j in 0..sectors {
                let phi = (j as f64 + 0.5) / sectors as f64 * std::f64::consts::TAU;
                let dir = DVec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta);
                let l = self.sky(z, dir);
                for c in 0..3 {
                    sum[c] += l[c];
                }
            }
        }
        sum.map(|s| s / (rings * sectors) as f64)
    }
}

/// Exposure and the tone map (Khronos PBR Neutral), the twin of `display` in
/// `shaders/shared/shading.wgsl`: light in, display-referred linear RGB (before sRGB encoding) out.
fn display(light: [f64; 3], exposure: f64) -> [f64; 3] {
    let (start, desaturation) = (0.8 - 0.04, 0.15);
    let mut c = light.map(|v| v * exposure);
    let x = c[0].min(c[1]).min(c[2]);
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    c = c.map(|v| v - offset);
    let peak = c[0].max(c[1]).max(c[2]);
    if peak < start {
        return c;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    c.map(|v| v * new_peak / peak * (1.0 - g) + new_peak * g)
}

/// Rec. 709 luminance of a linear RGB colour.
pub fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Air density relative to sea level at height `z`, for a medium of scale height `scale`.
fn density(z: f64, scale: f64) -> f64 {
    (-z / scale).exp()
}

/// Optical depth of the column above height `z` (per unit air mass), per channel.
fn column_above(z: f64, haze_per_m: f64, haze_height_m: f64) -> [f64; 3] {
    let haze = haze_per_m * haze_height_m * density(z, haze_height_m);
    RAYLEIGH.map(|r| r * RAYLEIGH_SCALE_M * density(z, RAYLEIGH_SCALE_M) + haze)
}

/// The air along a segment from height `z0` to `z1`, `dist` long, whose density falls as
/// exp(−z / scale): ∫ exp(−z(t) / scale) dt, in metres of sea-level air. Written as a difference
/// of two bounded exponentials, so a segment from 100 km up does not overflow f32 in the twin.
pub fn air_along(z0: f64, z1: f64, dist: f64, scale: f64) -> f64 {
    let x = (z1 - z0) / scale;
    let (a, b) = (density(z0, scale), density(z1, scale));
    if x.abs() < 1e-3 {
        dist * a * (1.0 - 0.5 * x)
    } else {
        dist * (a - b) / x
    }
}

/// How far a ray from height `eye_z` along `dir` crosses the sky: to the top of the air going
/// up, to sea level going down, never past the planar horizon.
pub fn sky_length(eye_z: f64, dir: DVec3) -> f64 {
    let to = if dir.z > 1e-6 {
        (TOP_M - eye_z).max(0.0) / dir.z
    } else if dir.z < -1e-6 {
        eye_z.max(0.0) / -dir.z
    } else {
        FAR_M
    };
    to.min(FAR_M)
}

/// The sun's azimuth (0 north, 90 east) and elevation, degrees, at `latitude_deg` on day
/// `day_of_year` at local solar time `solar_time_h` (12 at solar noon): the declination by
/// Cooper's formula, the hour angle 15° an hour from noon; no equation of time (the time is the
/// sun's own) and no refraction.
pub fn sun_position(latitude_deg: f64, day_of_year: u32, solar_time_h: f64) -> (f64, f64) {
    let phi = latitude_deg.to_radians();
    let delta = (23.44f64.to_radians())
        * (std::f64::consts::TAU * (284.0 + day_of_year as f64) / 365.0).sin();
    let h = (15.0 * (solar_time_h - 12.0)).to_radians();
    let sin_el = phi.sin() * delta.sin() + phi.cos() * delta.cos() * h.cos();
    let elevation = sin_el.clamp(-1.0, 1.0).asin();
    let azimuth =
        h.sin().atan2(h.cos() * phi.sin() - delta.tan() * phi.cos()) + std::f64::consts::PI;
    (
        azimuth.to_degrees().rem_euclid(360.0),
        elevation.to_degrees(),
    )
}

/// Kasten and Young's relative air mass at `elevation_deg` (1 at the zenith, 38 at the horizon).
pub fn air_mass(elevation_deg: f64) -> f64 {
    let h = elevation_deg.max(0.0);
    1.0 / (h.to_radians().sin() + 0.50572 * (h + 6.07995).powf(-1.6364))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(el: f64) -> Light {
        Light::new(150.0, el, 100.0, 1200.0, 0.0)
    }

    #[test]
    fn azimuth_90_is_east_and_elevation_90_straight_up() {
        let east = Light::new(90.0, 0.0, 100.0, 1200.0, 0.0).sun;
        assert!((east - DVec3::X).length() < 1e-12, "{east}");
        let north = Light::new(0.0, 30.0, 100.0, 1200.0, 0.0).sun;
        assert!(north.x.abs() < 1e-12 && north.y > 0.8);
        let up = Light::new(123.0, 90.0, 100.0, 1200.0, 0.0).sun;
        assert!((up - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn the_sun_reddens_and_the_sky_dims_as_it_sets() {
        let noon = at(35.0);
        for (c, want) in noon.sun_colour.iter().zip(REFERENCE_WHITE) {
            assert!((c - want).abs() < 1e-12, "{:?}", noon.sun_colour);
        }
        let mut last_ratio = 0.0;
        let mut last_sky = f64::INFINITY;
        for el in [35.0, 20.0, 10.0, 5.0, 2.0, 0.0] {
            let l = at(el);
            let ratio = l.sun_colour[0] / l.sun_colour[2];
            assert!(ratio > last_ratio, "{el}°: red/blue {ratio}");
            assert!(l.sun_colour.iter().all(|c| c.is_finite() && *c >= 0.0));
            let sky = luminance(l.sky_light);
            assert!(sky < last_sky, "{el}°: sky light {sky}");
            last_ratio = ratio;
            last_sky = sky;
        }
        let night = at(-30.0);
        assert!(night.sun_colour.iter().all(|c| c.is_finite() && *c >= 0.0));
        assert_eq!(night.sky_light, [0.0; 3]);
        assert_eq!(at(35.0).daylight, 1.0);
        assert!(at(0.0).daylight < 0.5 && at(-6.0).daylight == 0.0);
    }

    #[test]
    fn a_clear_sky_lights_the_ground_with_a_tenth_to_a_fifth_of_the_sun() {
        // Clear-sky diffuse fractions of global irradiance are 0.1–0.2 at mid elevations.
        let l = at(35.0);
        let sun = luminance(l.sun_colour) * l.sun.z;
        let sky = luminance(l.sky_light);
        let share = sky / (sky + sun);
        assert!((0.08..0.25).contains(&share), "diffuse share {share}");
        // Bluer than the sun.
        assert!(l.sky_light[2] / l.sky_light[0] > l.sun_colour[2] / l.sun_colour[0]);
    }

    #[test]
    fn the_sky_is_blue_overhead_whiter_at_the_horizon_and_bright_around_the_sun() {
        let l = at(35.0);
        let zenith = l.sky(0.0, DVec3::Z);
        let horizon = l.sky(0.0, DVec3::new(-l.sun.x, -l.sun.y, 0.02).normalize());
        assert!(zenith[2] > zenith[1] && zenith[1] > zenith[0], "{zenith:?}");
        assert!(
            horizon[2] / horizon[0] < zenith[2] / zenith[0],
            "{horizon:?} {zenith:?}"
        );
        let near_sun = l.sky(0.0, (l.sun + DVec3::new(0.0, 0.0, 0.05)).normalize());
        assert!(luminance(near_sun) > 3.0 * luminance(zenith));
        // From 50 km up there is little air left to scatter: the sky darkens.
        assert!(luminance(l.sky(50_000.0, DVec3::Z)) < 0.05 * luminance(zenith));
    }

    #[test]
    fn air_along_is_finite_from_any_height_and_matches_its_integral() {
        for (z0, z1, dist) in [
            (0.0, 0.0, 1000.0),
            (5e5, 0.0, 5e5),
            (0.0, 5e5, 5e5),
            (-400.0, 30.0, 1.0),
        ] {
            for scale in [1200.0, 8000.0] {
                let v = air_along(z0, z1, dist, scale);
                let n = 100_000;
                let numeric: f64 = (0..n)
                    .map(|i| {
                        let s = (i as f64 + 0.5) / n as f64;
                        density(z0 + (z1 - z0) * s, scale) * dist / n as f64
                    })
                    .sum();
                assert!(
                    v.is_finite() && (v - numeric).abs() <= 1e-5 * numeric.max(1e-300) + 1e-12,
                    "{z0} {z1} {dist} {scale}: {v} vs {numeric}"
                );
            }
        }
    }

    #[test]
    fn aerial_perspective_keeps_a_view_from_20_km_mostly_clear() {
        let l = at(35.0);
        let dir = DVec3::new(0.0, 1.0, -1.0).normalize();
        let (_, through) = l.scatter(20_000.0, dir, 20_000.0 * 2f64.sqrt());
        assert!(through.iter().all(|t| *t > 0.4 && *t < 1.0), "{through:?}");
        // Blue is taken most.
        assert!(through[2] < through[0]);
    }

    #[test]
    fn exposure_renders_a_grey_card_under_the_reference_sun_at_middle_grey() {
        let l = at(35.0);
        let card = [0, 1, 2].map(|c| 0.18 * (l.sun_colour[c] * l.sun.z + l.sky_light[c]));
        assert!((luminance(card) * l.exposure - 0.18).abs() < 1e-9);
        // A fixed camera: a low sun keeps the reference's exposure and darkens the picture.
        assert_eq!(at(8.0).exposure, l.exposure);
        let brighter = Light::new(150.0, 35.0, 100.0, 1200.0, 1.0);
        assert!((brighter.exposure / l.exposure - 2.0).abs() < 1e-12);
        // Thicker haze dims the sun, and the meter opens up for it.
        assert!(Light::new(150.0, 35.0, 10.0, 1200.0, 0.0).exposure > l.exposure);
    }

    #[test]
    fn the_tone_map_is_linear_through_the_mid_tones_and_rolls_off_to_white() {
        let mid = display([0.3, 0.2, 0.1], 1.0);
        for (m, want) in mid.iter().zip([0.26, 0.16, 0.06]) {
            assert!((m - want).abs() < 1e-12, "{mid:?}");
        }
        let bright = display([40.0, 40.0, 40.0], 1.0);
        assert!(bright.iter().all(|c| *c > 0.99 && *c <= 1.0), "{bright:?}");
        let lo = display([0.0; 3], 1.0);
        assert_eq!(lo, [0.0; 3]);
    }

    #[test]
    fn the_sun_by_the_clock_rises_east_culminates_south_and_sets_west() {
        // 45° N at the June solstice: noon at 90 − 45 + 23.44°, due south.
        let (az, el) = sun_position(45.0, 172, 12.0);
        assert!(
            (el - 68.44).abs() < 0.05 && (az - 180.0).abs() < 1e-9,
            "{az} {el}"
        );
        // The equinox at the equator: overhead at noon, rising due east at 6.
        let (_, el) = sun_position(0.0, 80, 12.0);
        assert!(el > 89.0, "{el}");
        let (az, el) = sun_position(0.0, 80, 6.0);
        assert!((az - 90.0).abs() < 1.0 && el.abs() < 1.0, "{az} {el}");
        let (az, _) = sun_position(45.0, 172, 17.0);
        assert!((225.0..315.0).contains(&az), "afternoon sun at {az}");
        // Midnight at a pole in its winter: below the horizon, finite.
        let (az, el) = sun_position(90.0, 355, 0.0);
        assert!(el < 0.0 && az.is_finite());
        // South of the sun's latitude, noon is due north.
        let (az, _) = sun_position(-33.9, 172, 12.0);
        assert!(az.abs() < 1e-9 || (az - 360.0).abs() < 1e-9, "{az}");
    }

    #[test]
    fn air_mass_is_one_at_the_zenith_and_finite_below_the_horizon() {
        assert!((air_mass(90.0) - 1.0).abs() < 1e-3);
        assert!((air_mass(0.0) - 38.0).abs() < 0.2, "{}", air_mass(0.0));
        assert_eq!(air_mass(-10.0), air_mass(0.0));
    }
}
