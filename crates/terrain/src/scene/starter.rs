//! A starter scene for a sketch (`terrain scene`): every section, every key with its value or,
//! where it has none, commented out, each with a comment; the camera the default view written
//! out in the keys people place a camera by; the detail the sketch chose.
//!
//! Rules: the comments are the first sentence of each key's meaning in docs/scene.md, read from
//! the text compiled in, so the starter and the manual cannot disagree (tests/scene_doc.rs checks
//! the manual against these structs); what it writes parses and renders as it is.
//!
//! Rejected alternative: a hand-written template. It holds a copy of every default and of every
//! key's description, and drifts from both as keys come and go.

use super::{Scene, place};
use crate::error::Result;
use crate::sketch::Atlas;
use crate::sketch::georef::Units;
use serde::Serialize;
use std::fmt::Write;
use std::path::Path;

const MANUAL: &str = include_str!("../../../../docs/scene.md");
/// The widest a key's comment grows before it is cut at a word.
const COMMENT_CHARS: usize = 96;

/// The starter scene's text for `scene` (read from the sketch at `sketch_path`, as the scene
/// file will name it) over its `atlas`.
pub fn starter(scene: &Scene, atlas: &Atlas, sketch_path: &Path) -> Result<String> {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# A scene for {}, written by `terrain scene`.\n\
         # Keys commented out keep their defaults; docs/scene.md documents each.\n",
        sketch_path.display()
    );
    let path = [("path", Some(toml_str(&sketch_path.to_string_lossy())))];
    section_of(&mut out, "sketch", &scene.sketch, &path);
    section_of(
        &mut out,
        "camera",
        &scene.camera,
        &camera_keys(scene, atlas)?,
    );
    let detail = super::detail_of(scene, atlas);
    let chosen = [
        ("octaves", Some(value(&detail.octaves))),
        ("amplitude_m", Some(value(&round(detail.amplitude_m, 3)))),
    ];
    section_of(&mut out, "detail", &scene.detail, &chosen);
    section_of(&mut out, "warp", &scene.warp, &[]);
    section_of(&mut out, "importance", &scene.importance, &[]);
    section_of(&mut out, "render", &scene.render, &[]);
    section_of(&mut out, "geomipmap", &scene.geomipmap, &[]);
    section_of(&mut out, "reference", &scene.reference, &[]);
    section_of(&mut out, "light", &scene.light, &[]);
    section_of(&mut out, "stream", &scene.stream, &[]);
    let _ = writeln!(
        out,
        "# [path]                    # a camera path for `fly` and `compare` (docs/scene.md, [path])\n\
         # speed_mps = 150.0\n\
         # keys = [{{ map_xy = [x, y], altitude_m = 100.0 }}, {{ position = [x, y, z], look_at = [x, y, z] }}]"
    );
    Ok(out)
}

/// The default view in the keys a user edits: latitude and longitude on a geographic sketch,
/// the file's own coordinates on a projected one, world metres without a georeference; then the
/// height above the ground, heading and pitch, and the lens.
fn camera_keys(scene: &Scene, atlas: &Atlas) -> Result<Vec<(&'static str, Option<String>)>> {
    let (eye, target) = place::pose(scene, atlas)?;
    let r = place::report(scene, atlas, eye, target)?;
    let c = &scene.camera;
    let mut keys = Vec::new();
    match (&atlas.georef, r.map_xy) {
        (Some(g), _) if g.units == Units::Degrees && r.lat_deg.is_some() => {
            keys.push(("lat_deg", r.lat_deg.map(|v| value(&round(v, 9)))));
            keys.push(("lon_deg", r.lon_deg.map(|v| value(&round(v, 9)))));
        }
        (Some(_), Some([x, y])) => {
            keys.push(("map_xy", Some(value(&[round(x, 2), round(y, 2)]))));
        }
        _ => keys.push(("position", Some(value(&r.position.map(|v| round(v, 2)))))),
    }
    if r.map_xy.is_some() {
        keys.push(("altitude_m", Some(value(&round(r.altitude_m, 3)))));
    }
    keys.push(("heading_deg", Some(value(&round(r.heading_deg, 3)))));
    keys.push(("pitch_deg", Some(value(&round(r.pitch_deg, 3)))));
    keys.push(("fov_y_deg", Some(value(&c.fov_y_deg))));
    keys.push(("width", Some(value(&c.width))));
    keys.push(("height", Some(value(&c.height))));
    Ok(keys)
}

/// A section whose keys are `struct`'s fields in the manual's order, `chosen` values first.
fn section_of<T: Serialize>(
    out: &mut String,
    name: &str,
    fields: &T,
    chosen: &[(&str, Option<String>)],
) {
    let table = toml::Value::try_from(fields)
        .ok()
        .and_then(|v| v.as_table().cloned())
        .unwrap_or_default();
    let keys: Vec<(&str, Option<String>)> = rows(name)
        .map(|(key, _)| {
            let v = chosen
                .iter()
                .find(|(k, _)| *k == key)
                .map(|(_, v)| v.clone())
                .unwrap_or_else(|| table.get(key).map(|v| v.to_string()));
            (key, v)
        })
        .collect();
    section(out, name, &keys);
}

/// `[name]` and its keys, each with its comment; a key without a value commented out, with its
/// default as the manual words it.
fn section(out: &mut String, name: &str, keys: &[(&str, Option<String>)]) {
    let _ = writeln!(out, "[{name}]");
    for (key, value) in keys {
        let (default, meaning) = rows(name)
            .find(|(k, _)| k == key)
            .map(|(_, row)| row)
            .unwrap_or_default();
        let line = match value {
            Some(v) => format!("{key} = {v}"),
            None => format!("# {key} = …  (default: {default})"),
        };
        let _ = writeln!(out, "{line:<27} # {}", first_sentence(&meaning));
    }
    out.push('\n');
}

/// The manual's table rows of `[section]`: each key with its default and meaning columns.
fn rows(section: &str) -> impl Iterator<Item = (&'static str, (String, String))> {
    let head = format!("### [{section}]");
    MANUAL
        .split_once(&head)
        .map(|(_, rest)| rest.split("\n### ").next().unwrap_or(""))
        .unwrap_or("")
        .lines()
        .filter_map(|l| {
            let cells: Vec<&str> = l.strip_prefix("| `")?.split('|').map(str::trim).collect();
            let key = cells.first()?.strip_suffix('`')?;
            let plain = |s: &str| s.replace('`', "");
            let meaning = cells.get(4..)?.join("|");
            Some((
                key,
                (plain(cells.get(2)?), plain(meaning.trim_end_matches('|'))),
            ))
        })
}

fn first_sentence(text: &str) -> String {
    let text = text.trim();
    let end = text.find(". ").map_or(text.len(), |k| k + 1);
    let s = &text[..end];
    if s.chars().count() <= COMMENT_CHARS {
        return s.to_string();
    }
    let cut: String = s.chars().take(COMMENT_CHARS).collect();
    format!("{}…", cut.rsplit_once(' ').map_or(cut.as_str(), |(a, _)| a))
}

fn value<T: Serialize + ?Sized>(v: &T) -> String {
    toml::Value::try_from(v).map_or_else(|_| String::new(), |v| v.to_string())
}

fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn round(v: f64, digits: i32) -> f64 {
    let k = 10f64.powi(digits);
    (v * k).round() / k
}
