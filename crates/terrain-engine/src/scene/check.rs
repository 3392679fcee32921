//! The ranges a parsed scene must keep, each fault naming its dotted key.

use super::{MAX_OCTAVES, Msaa, Placement, Scene};

impl Scene {
    pub(super) fn check(&self) -> std::result::Result<(), String> {
        let s = &self.sketch;
        match (&s.path, &s.synthetic) {
            (Some(_), Some(_)) => return Err("sketch: give `path` or `synthetic`, not both".into()),
            (None, None) => return Err("sketch: give `path` or `synthetic`".into()),
            (None, Some(name))
                if name != "planet"
                    && !crate::sketch::synthetic::NAMES.contains(&name.as_str()) =>
            {
                return Err(format!(
                    "sketch.synthetic = \"{name}\": one of {}, planet",
                    crate::sketch::synthetic::NAMES.join(", ")
                ));
            }
            (Some(_), None) if s.size.is_some() => {
                return Err("sketch.size applies to synthetic sketches only".into());
            }
            _ => {}
        }
        positive("sketch.spacing_m", s.spacing_m)?;
        positive("sketch.height_scale", s.height_scale)?;
        if let Some(size) = s.size {
            // A planet's width: halved down its pyramid, 16384 × 8192 f32 is 512 MiB.
            let (least, most) = if self.planet().is_some() {
                (8.0, 16384.0)
            } else {
                (2.0, 4097.0)
            };
            within("sketch.size", size as f64, least, most)?;
        }
        if let Some(o) = s.origin_m {
            finite_all("sketch.origin_m", &o)?;
        }
        if let Some(r) = s.height_range_m {
            finite_all("sketch.height_range_m", &r)?;
        }
        let c = &self.camera;
        if let Some(p) = self.planet() {
            if c.position.is_some() || c.look_at.is_some() || c.map_xy.is_some() {
                return Err(
                    "camera: a planet's camera is placed by lat_deg, lon_deg and \
                    altitude_m (with heading_deg, pitch_deg), not position, map_xy or look_at"
                        .into(),
                );
            }
            if c.lat_deg.is_none() || c.lon_deg.is_none() || c.altitude_m.is_none() {
                return Err(
                    "camera: a planet's camera needs lat_deg, lon_deg and altitude_m".into(),
                );
            }
            planet_keys(
                "camera",
                [
                    c.lat_deg.unwrap_or(0.0),
                    c.lon_deg.unwrap_or(0.0),
                    c.altitude_m.unwrap_or(1.0),
                    c.heading(),
                    c.pitch(),
                ],
            )?;
            within("planet.radius_m", p.radius_m, 1000.0, 1e9)?;
            within("planet.phi_steps", p.phi_steps as f64, 8.0, 8192.0)?;
            within(
                "planet.rings_per_level",
                p.rings_per_level as f64,
                1.0,
                256.0,
            )?;
            planet_render(&self.render)?;
            if s.path.is_none() && s.synthetic.as_deref() != Some("planet") {
                return Err(
                    "sketch: a planet needs `synthetic = \"planet\"` or a global sketch file"
                        .into(),
                );
            }
        } else {
            planar_keys("camera", &c.placement(), false)?;
        }
        open_range("camera.fov_y_deg", c.fov_y_deg, 0.0, 180.0)?;
        within("camera.width", c.width as f64, 1.0, 16384.0)?;
        within("camera.height", c.height as f64, 1.0, 16384.0)?;
        positive("camera.far_m", c.far_m)?;
        let d = &self.detail;
        if let Some(o) = d.octaves {
            within("detail.octaves", o as f64, 0.0, MAX_OCTAVES as f64)?;
        }
        if let Some(a) = d.amplitude_m {
            within("detail.amplitude_m", a, 0.0, 1e5)?;
        }
        within("detail.gain", d.gain, 0.0, 1.0)?;
        if let Some(b) = d.bias {
            within("detail.bias", b, -4.0, 8.0)?;
        }
        let w = &self.warp;
        open_range("warp.quad_px", w.quad_px, 0.0, 1e4)?;
        within("warp.mesh", w.mesh as f64, 2.0, 4096.0)?;
        within("warp.min_mesh", w.min_mesh as f64, 2.0, 4096.0)?;
        open_range("warp.hold_drift", w.hold_drift, 0.0, 64.0)?;
        within("warp.size", w.size as f64, 2.0, 4096.0)?;
        within("warp.max_log2_step", w.max_log2_step, 0.0, 64.0)?;
        let g = &self.geomipmap;
        open_range("geomipmap.tau", g.tau, 0.0, 1e6)?;
        if ![17, 33, 65, 129].contains(&g.block) {
            return Err(format!(
                "geomipmap.block = {}: one of 17, 33, 65, 129",
                g.block
            ));
        }
        if let Some(k) = g.k {
            within("geomipmap.k", k as f64, 0.0, 6.0)?;
        }
        within(
            "geomipmap.max_blocks",
            g.max_blocks as f64,
            1.0,
            2_097_152.0,
        )?;
        let st = &self.stream;
        within("stream.gpu_mb", st.gpu_mb, 1.0, 65536.0)?;
        within("stream.cpu_mb", st.cpu_mb, 0.0, 1048576.0)?;
        within(
            "stream.loads_per_frame",
            st.loads_per_frame as f64,
            1.0,
            4096.0,
        )?;
        within("stream.fade_frames", st.fade_frames as f64, 0.0, 1000.0)?;
        within("stream.threads", st.threads as f64, 1.0, 64.0)?;
        up_to_one("reference.step", self.reference.step)?;
        let l = &self.light;
        if let Some(az) = l.sun_azimuth_deg {
            finite_all("light.sun_azimuth_deg", &[az])?;
        }
        if let Some(el) = l.sun_elevation_deg {
            within("light.sun_elevation_deg", el, -90.0, 90.0)?;
        }
        let by_time = [
            l.latitude_deg.is_some(),
            l.day_of_year.is_some(),
            l.solar_time_h.is_some(),
        ];
        if by_time.iter().any(|&b| b) {
            if !by_time.iter().all(|&b| b) {
                return Err(
                    "light: the sun from the time needs latitude_deg, day_of_year and \
                    solar_time_h together"
                        .into(),
                );
            }
            if l.sun_azimuth_deg.is_some() || l.sun_elevation_deg.is_some() {
                return Err("light: give the sun's position (sun_azimuth_deg, \
                    sun_elevation_deg) or its time (latitude_deg, day_of_year, solar_time_h), \
                    not both"
                    .into());
            }
            within(
                "light.latitude_deg",
                l.latitude_deg.unwrap_or(0.0),
                -90.0,
                90.0,
            )?;
            within(
                "light.day_of_year",
                l.day_of_year.unwrap_or(1) as f64,
                1.0,
                366.0,
            )?;
            within(
                "light.solar_time_h",
                l.solar_time_h.unwrap_or(0.0),
                0.0,
                24.0,
            )?;
        }
        open_range("light.haze_visibility_km", l.haze_visibility_km, 0.0, 1e6)?;
        open_range("light.haze_height_m", l.haze_height_m, 0.0, 1e6)?;
        within("light.exposure_ev", l.exposure_ev, -16.0, 16.0)?;
        within("sketch.water_level_m", self.sketch.water_level_m, -1e6, 1e6)?;
        let style = self.surface.style();
        if style != super::Style::Natural && self.planet().is_some() {
            return Err(format!(
                "surface.style = \"{style}\": a planet is drawn with its own surface types; \
                 ramps and images drape planar sketches"
            ));
        }
        if style == super::Style::Image && self.surface.image.is_none() {
            return Err("surface.style = \"image\" needs surface.image, the image to drape".into());
        }
        let i = &self.importance;
        open_range("importance.error_px", i.error_px, 0.0, 1e4)?;
        up_to_one("importance.error_flat_share", i.error_flat_share)?;
        positive("importance.max_per_m", i.max_per_m)?;
        up_to_one("importance.floor", i.floor)?;
        up_to_one("importance.backface_floor", i.backface_floor)?;
        if let Some(p) = &self.path {
            positive("path.speed_mps", Some(p.speed_mps))?;
            if p.keys.len() < 2 {
                return Err(format!(
                    "path.keys: {} given, a path needs at least 2",
                    p.keys.len()
                ));
            }
            let planet = self.planet().is_some();
            if let Some(d) = p.duration_s {
                open_range("path.duration_s", d, 0.0, 1e9)?;
            }
            for (k, key) in p.keys.iter().enumerate() {
                let geo = [key.lat_deg, key.lon_deg, key.altitude_m];
                if planet {
                    if key.position.is_some()
                        || key.look_at.is_some()
                        || key.map_xy.is_some()
                        || geo.iter().any(|g| g.is_none())
                    {
                        return Err(format!(
                            "path.keys[{k}]: a planet's key gives lat_deg, lon_deg and \
                             altitude_m (with heading_deg, pitch_deg), not position and look_at"
                        ));
                    }
                    planet_keys(
                        &format!("path.keys[{k}]"),
                        [
                            key.lat_deg.unwrap_or(0.0),
                            key.lon_deg.unwrap_or(0.0),
                            key.altitude_m.unwrap_or(1.0),
                            key.heading_deg.unwrap_or(0.0),
                            key.pitch_deg.unwrap_or(0.0),
                        ],
                    )?;
                    continue;
                }
                planar_keys(&format!("path.keys[{k}]"), &key.placement(), true)?;
            }
        }
        Ok(())
    }
}

/// A planar camera's keys under `table`: at most one place (`position`, `map_xy`, or `lat_deg`
/// with `lon_deg`), `altitude_m` with the last two and only with them, and one aim (`look_at`,
/// or `heading_deg` and `pitch_deg`). A camera may leave out its place (`need_place` false): it
/// then frames the sketch, from the side its heading and pitch say.
fn planar_keys(table: &str, k: &Placement, need_place: bool) -> std::result::Result<(), String> {
    let geo = k.lat_deg.is_some() || k.lon_deg.is_some();
    let places = [k.position.is_some(), k.map_xy.is_some(), geo];
    let placed = places.iter().filter(|&&b| b).count();
    if placed > 1 {
        return Err(format!(
            "{table}: give one place: position, map_xy, or lat_deg and lon_deg"
        ));
    }
    if geo && (k.lat_deg.is_none() || k.lon_deg.is_none()) {
        return Err(format!("{table}: lat_deg and lon_deg go together"));
    }
    if placed == 0 {
        if need_place {
            return Err(format!(
                "{table}: give position, map_xy or lat_deg and lon_deg (with altitude_m)"
            ));
        }
        if k.look_at.is_some() || k.altitude_m.is_some() {
            return Err(format!(
                "{table}: look_at and altitude_m need a place: position, map_xy, or lat_deg \
                 and lon_deg"
            ));
        }
    }
    if k.position.is_some() && k.altitude_m.is_some() {
        return Err(format!(
            "{table}.altitude_m: position gives the height itself; altitude_m goes with map_xy \
             or lat_deg and lon_deg"
        ));
    }
    if (k.map_xy.is_some() || geo) && k.altitude_m.is_none() {
        return Err(format!(
            "{table}: map_xy and lat_deg, lon_deg need altitude_m, the height above the ground \
             there"
        ));
    }
    if k.look_at.is_some() && (k.heading_deg.is_some() || k.pitch_deg.is_some()) {
        return Err(format!(
            "{table}: give look_at, or heading_deg and pitch_deg, not both"
        ));
    }
    if let Some(p) = k.position {
        finite_all(&format!("{table}.position"), &p)?;
    }
    if let Some(l) = k.look_at {
        finite_all(&format!("{table}.look_at"), &l)?;
        if k.position == Some(l) {
            return Err(format!(
                "{table}.look_at equals {table}.position: no view direction"
            ));
        }
    }
    if let Some(xy) = k.map_xy {
        finite_all(&format!("{table}.map_xy"), &xy)?;
    }
    if let Some(lat) = k.lat_deg {
        within(&format!("{table}.lat_deg"), lat, -90.0, 90.0)?;
    }
    if let Some(lon) = k.lon_deg {
        within(&format!("{table}.lon_deg"), lon, -360.0, 360.0)?;
    }
    if let Some(a) = k.altitude_m {
        within(&format!("{table}.altitude_m"), a, 0.01, 1e9)?;
    }
    if let Some(h) = k.heading_deg {
        finite_all(&format!("{table}.heading_deg"), &[h])?;
    }
    if let Some(p) = k.pitch_deg {
        within(&format!("{table}.pitch_deg"), p, -90.0, 90.0)?;
    }
    Ok(())
}

/// What a planet's passes cannot draw yet, refused rather than left out of the picture: the
/// detail's shadow and multisampling (`render.shadows` stays on by default everywhere, so a
/// planet ignores it instead of refusing every scene that does not turn it off).
fn planet_render(r: &super::RenderSection) -> std::result::Result<(), String> {
    if r.detail_shadows {
        return Err("render.detail_shadows = true: a planet draws no shadows yet".into());
    }
    if r.msaa == Msaa::X4 {
        return Err(
            "render.msaa = \"4x\": a planet is not multisampled yet (\"auto\" or \"off\")".into(),
        );
    }
    Ok(())
}

/// A planet camera's keys under `table` (`camera`, `path.keys[k]`): latitude, longitude,
/// altitude, heading and pitch.
fn planet_keys(
    table: &str,
    [lat, lon, altitude, heading, pitch]: [f64; 5],
) -> std::result::Result<(), String> {
    within(&format!("{table}.lat_deg"), lat, -90.0, 90.0)?;
    finite_all(&format!("{table}.lon_deg"), &[lon])?;
    within(&format!("{table}.altitude_m"), altitude, 0.01, 1e9)?;
    finite_all(&format!("{table}.heading_deg"), &[heading])?;
    within(&format!("{table}.pitch_deg"), pitch, -90.0, 90.0)
}

fn finite_all(key: &str, v: &[f64]) -> std::result::Result<(), String> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("{key}: {x} is not a finite number")),
        None => Ok(()),
    }
}

fn within(key: &str, v: f64, lo: f64, hi: f64) -> std::result::Result<(), String> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(format!("{key} = {v}: must be in [{lo}, {hi}]"))
    }
}

fn open_range(key: &str, v: f64, lo: f64, hi: f64) -> std::result::Result<(), String> {
    if v.is_finite() && v > lo && v < hi {
        Ok(())
    } else {
        Err(format!("{key} = {v}: must be in ({lo}, {hi})"))
    }
}

/// (0, 1]: a share or a weight that may be whole but not nothing.
fn up_to_one(key: &str, v: f64) -> std::result::Result<(), String> {
    if v.is_finite() && v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        Err(format!("{key} = {v}: must be in (0, 1]"))
    }
}

fn positive(key: &str, v: Option<f64>) -> std::result::Result<(), String> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => {
            Err(format!("{key} = {x}: must be a positive number"))
        }
        _ => Ok(()),
    }
}
