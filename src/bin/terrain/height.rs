//! `terrain height SCENE --xy X,Y`: the terrain function's height at a point, as the reference
//! draws it (`terrain_engine::query`).

use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use terrain_engine::Error;
use terrain_engine::scene::{self, Scene};
use terrain_engine::sketch::Atlas;
use terrain_engine::{Ground, PlanetGround};

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("place").required(true).args(["xy", "map_xy", "lat_lon"])))]
pub struct Args {
    /// A scene file, or a sketch (any format `terrain info` reads) seen as a scene with every
    /// default.
    scene: PathBuf,
    /// The point in world metres (x east, y north, from the sketch's south-west node).
    #[arg(long, value_name = "X,Y", value_parser = pair, allow_hyphen_values = true)]
    xy: Option<[f64; 2]>,
    /// The point in the sketch file's own coordinates (as `terrain info` prints them).
    #[arg(long = "map-xy", value_name = "X,Y", value_parser = pair, allow_hyphen_values = true)]
    map_xy: Option<[f64; 2]>,
    /// The point by latitude and longitude, degrees: on a planet, or through a georeferenced
    /// sketch's coordinate system.
    #[arg(long = "lat-lon", value_name = "LAT,LON", value_parser = pair, allow_hyphen_values = true)]
    lat_lon: Option<[f64; 2]>,
    /// The detail to answer at: the footprint in metres that one sample covers (the sketch's
    /// pyramid level and the octaves finer than it fade as in a pixel that size); 0, the
    /// default, is the finest: every octave whole.
    #[arg(long = "footprint-m", value_name = "M", default_value_t = 0.0)]
    footprint_m: f64,
    /// Overrides a scene key, e.g. `--set detail.octaves=0` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

/// `--json`: where, and the height there. A planet's point has `lat_deg` and `lon_deg` and no
/// `x`, `y`.
#[derive(Serialize)]
struct Report {
    #[serde(skip_serializing_if = "Option::is_none")]
    x: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    y: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lat_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lon_deg: Option<f64>,
    /// Metres: above the sphere on a planet.
    z: f64,
    /// The surface's unit normal (planar scenes).
    #[serde(skip_serializing_if = "Option::is_none")]
    normal: Option<[f64; 3]>,
    footprint_m: f64,
}

fn pair(s: &str) -> std::result::Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let number = |t: &str| {
        t.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("expected two finite numbers A,B, not {s:?}"))
    };
    match parts.as_slice() {
        [a, b] => Ok([number(a)?, number(b)?]),
        _ => Err(format!("expected two numbers A,B, not {s:?}")),
    }
}

pub fn run(a: Args) -> Result<()> {
    if let Some([lat, _]) = a.lat_lon
        && lat.abs() > 90.0
    {
        let why = format!("latitude {lat}° is not within −90° to 90°");
        return Err(Error::Value {
            key: "--lat-lon",
            reason: why,
        }
        .into());
    }
    if !(a.footprint_m >= 0.0 && a.footprint_m.is_finite()) {
        let why = format!("must be 0 or more metres, not {}", a.footprint_m);
        return Err(Error::Value {
            key: "--footprint-m",
            reason: why,
        }
        .into());
    }
    let scene = crate::load_scene(&a.scene, &a.set)?;
    let atlas = scene::load_atlas(&scene)?;
    let detail = scene::detail_of(&scene, &atlas);
    let report = match &scene.planet {
        Some(planet) => {
            let Some([lat, lon]) = a.lat_lon else {
                let why = "a planet's points are given by --lat-lon LAT,LON";
                return Err(Error::Value {
                    key: "--xy",
                    reason: why.into(),
                }
                .into());
            };
            let ground = PlanetGround::new(planet.radius_m, &atlas, &detail);
            let z = ground.height_at(lat, lon, a.footprint_m)?;
            Report {
                x: None,
                y: None,
                lat_deg: Some(lat),
                lon_deg: Some(lon),
                z,
                normal: None,
                footprint_m: a.footprint_m,
            }
        }
        None => planar(&a, &scene, &atlas, &detail)?,
    };
    if a.json {
        outln!("{}", serde_json::to_string(&report)?);
    } else {
        outln!("{}", summary(&report));
    }
    Ok(())
}

fn planar(
    a: &Args,
    scene: &Scene,
    atlas: &Atlas,
    detail: &terrain_engine::Detail,
) -> Result<Report> {
    // The point, and how it was given for a warning about it.
    let (p, given) = match (a.xy, a.map_xy, a.lat_lon) {
        (Some([x, y]), _, _) => (glam::DVec2::new(x, y), format!("--xy {x},{y}")),
        (_, Some([x, y]), _) => {
            let p = scene::world_of_map(atlas, [x, y]).map_err(|why| Error::Value {
                key: "--map-xy",
                reason: why,
            })?;
            (p, format!("--map-xy {x},{y}"))
        }
        (_, _, Some([lat, lon])) => {
            let map = atlas
                .georef
                .as_ref()
                .ok_or("the sketch has no georeference: give the point by --xy".to_string())
                .and_then(|g| g.from_lat_lon(lat, lon))
                .map_err(|why| Error::Value {
                    key: "--lat-lon",
                    reason: why,
                })?;
            let p = scene::world_of_map(atlas, map).map_err(|why| Error::Value {
                key: "--lat-lon",
                reason: why,
            })?;
            (p, format!("--lat-lon {lat},{lon}"))
        }
        (None, None, None) => {
            let why = "give the point by --xy, --map-xy or --lat-lon".to_string();
            return Err(Error::Value {
                key: "--xy",
                reason: why,
            }
            .into());
        }
    };
    // A point far off the sketch is most often a coordinate of another place or system.
    let far = scene::off_map_warning(atlas, &format!("{given} lies"), p)
        .map(|line| format!("{line}: the height there is what sketch.outside draws"));
    let ground = Ground::new(scene, atlas, detail);
    let Some(z) = ground.height_at(p, a.footprint_m)? else {
        let why = format!(
            "nothing is drawn at ({}, {}): it lies beyond the sketch, and sketch.outside is \"void\"",
            p.x, p.y
        );
        return Err(Error::Query(why).into());
    };
    let normal = ground.normal_at(p, a.footprint_m)?.map(|n| n.to_array());
    // Said with an answer only: a point nothing is drawn at gets its error alone.
    crate::warn(&far.into_iter().collect::<Vec<_>>());
    let (lat_deg, lon_deg) = match a.lat_lon {
        Some([lat, lon]) => (Some(lat), Some(lon)),
        None => (None, None),
    };
    Ok(Report {
        x: Some(p.x),
        y: Some(p.y),
        lat_deg,
        lon_deg,
        z,
        normal,
        footprint_m: a.footprint_m,
    })
}

fn summary(r: &Report) -> String {
    let place = match (r.x, r.y, r.lat_deg, r.lon_deg) {
        (Some(x), Some(y), _, _) => format!("x {x:.3} m, y {y:.3} m"),
        (_, _, Some(lat), Some(lon)) => format!("{lat:.6}° N, {lon:.6}° E"),
        _ => String::new(),
    };
    match r.normal {
        Some([nx, ny, nz]) => format!(
            "{place}: ground at {:.3} m, normal ({nx:.4}, {ny:.4}, {nz:.4})",
            r.z
        ),
        None => format!("{place}: ground at {:.3} m above the sphere", r.z),
    }
}
