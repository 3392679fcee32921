//! A starter scene for a sketch (`terrain scene`): every section, every key with its value or,
//! where it has none, commented out, each with a comment; the camera the default view; the
//! detail the sketch chose.
//!
//! Rules: the comments are the first sentence of each key's meaning in docs/scene.md, read from
//! the manual's text the caller gives (the `terrain` binary compiles it in), so the starter and
//! the manual cannot disagree (tests/scene_doc.rs checks
//! the manual against these structs); what it writes parses and renders as it is. The camera is
//! written as the default view is made, by `heading_deg` and `pitch_deg` without a place, so an
//! edited heading or pitch frames the sketch anew; the place that view stands at is written
//! beside them commented out, in the keys people place a camera by, to fix it there. A camera
//! `--set` placed is written at its place.
//!
//! Rejected alternatives: a hand-written template, which holds a copy of every default and of
//! every key's description and drifts from both as keys come and go; the default view written
//! at its place, which a new heading turns away from the sketch.

use super::{Scene, place};
use crate::error::Result;
use crate::sketch::Atlas;
use crate::sketch::georef::Units;
use serde::Serialize;
use std::fmt::Write;
use std::path::Path;

/// The widest a key's comment grows before it is cut at a word.
const COMMENT_CHARS: usize = 96;

/// A key's line in the starter.
#[derive(Clone)]
enum Line {
    /// `key = value`.
    Set(String),
    /// `# key = value`: a value to uncomment.
    Offer(String),
    /// `# key = …  (default: …)`, the manual's default.
    Default,
}

/// The starter scene's text for `scene` (read from the sketch at `sketch_path`, as the scene
/// file will name it) over its `atlas`, each key's comment from `manual`, docs/scene.md's text.
pub fn starter(scene: &Scene, atlas: &Atlas, sketch_path: &Path, manual: &str) -> Result<String> {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# A scene for {}, written by `terrain scene`.\n\
         # Keys commented out keep their defaults; docs/scene.md documents each.\n",
        sketch_path.display()
    );
    let path = [("path", Line::Set(toml_str(&sketch_path.to_string_lossy())))];
    section_of(&mut out, manual, "sketch", &scene.sketch, &path);
    if !scene.camera.is_placed() {
        let _ = writeln!(
            out,
            "# With no place (position, map_xy, or lat_deg and lon_deg), the camera frames the\n\
             # sketch along heading_deg and pitch_deg, anew for each. The place commented out\n\
             # below is where it stands now: uncomment its lines to hold the camera there."
        );
    }
    section_of(
        &mut out,
        manual,
        "camera",
        &scene.camera,
        &camera_keys(scene, atlas)?,
    );
    let detail = super::detail_of(scene, atlas);
    let chosen = [
        ("octaves", Line::Set(value(&detail.octaves))),
        (
            "amplitude_m",
            Line::Set(value(&round(detail.amplitude_m, 3))),
        ),
    ];
    section_of(&mut out, manual, "detail", &scene.detail, &chosen);
    section_of(&mut out, manual, "warp", &scene.warp, &[]);
    section_of(&mut out, manual, "importance", &scene.importance, &[]);
    section_of(&mut out, manual, "render", &scene.render, &[]);
    section_of(&mut out, manual, "geomipmap", &scene.geomipmap, &[]);
    section_of(&mut out, manual, "reference", &scene.reference, &[]);
    section_of(&mut out, manual, "light", &scene.light, &[]);
    section_of(&mut out, manual, "surface", &scene.surface, &[]);
    section_of(&mut out, manual, "stream", &scene.stream, &[]);
    let _ = writeln!(
        out,
        "# [path]                    # a camera path for `fly` and `compare` (docs/scene.md, [path])\n\
         # speed_mps = 150.0\n\
         # keys = [{{ map_xy = [x, y], altitude_m = 100.0 }}, {{ position = [x, y, z], look_at = [x, y, z] }}]"
    );
    Ok(out)
}

/// The camera in the keys a user edits: its place by latitude and longitude on a geographic
/// sketch, the file's own coordinates on a projected one, world metres without a georeference,
/// with the height above the ground; heading and pitch; the lens. Without a place of the scene's
/// own, the place is offered commented out and the heading and pitch are the default view's, so
/// the framing makes the view.
fn camera_keys(scene: &Scene, atlas: &Atlas) -> Result<Vec<(&'static str, Line)>> {
    let (eye, target) = place::pose(scene, atlas)?;
    let r = place::report(scene, atlas, eye, target)?;
    let c = &scene.camera;
    let placed = c.is_placed();
    let place = |v: String| if placed { Line::Set(v) } else { Line::Offer(v) };
    let mut keys = Vec::new();
    match (&atlas.georef, r.map_xy) {
        (Some(g), _) if g.units == Units::Degrees && r.lat_deg.is_some() => {
            keys.push(("lat_deg", place(value(&round(r.lat_deg.unwrap_or(0.0), 9)))));
            keys.push(("lon_deg", place(value(&round(r.lon_deg.unwrap_or(0.0), 9)))));
        }
        (Some(_), Some([x, y])) => {
            keys.push(("map_xy", place(value(&[round(x, 2), round(y, 2)]))));
        }
        _ => keys.push(("position", place(value(&r.position.map(|v| round(v, 2)))))),
    }
    if r.map_xy.is_some() {
        keys.push(("altitude_m", place(value(&round(r.altitude_m, 3)))));
    }
    // Unplaced, the framing's own heading and pitch: the view as it asks for it.
    let (heading, pitch) = if placed {
        (r.heading_deg, r.pitch_deg)
    } else {
        (c.heading(), c.pitch_deg.unwrap_or(place::DEFAULT_PITCH_DEG))
    };
    keys.push(("heading_deg", Line::Set(value(&round(heading, 3)))));
    keys.push(("pitch_deg", Line::Set(value(&round(pitch, 3)))));
    keys.push(("fov_y_deg", Line::Set(value(&c.fov_y_deg))));
    keys.push(("width", Line::Set(value(&c.width))));
    keys.push(("height", Line::Set(value(&c.height))));
    Ok(keys)
}

/// A section whose keys are `struct`'s fields in the manual's order, `chosen` lines first.
fn section_of<T: Serialize>(
    out: &mut String,
    manual: &str,
    name: &str,
    fields: &T,
    chosen: &[(&str, Line)],
) {
    let table = toml::Value::try_from(fields)
        .ok()
        .and_then(|v| v.as_table().cloned())
        .unwrap_or_default();
    let keys: Vec<(&str, Line)> = rows(manual, name)
        .map(|(key, _)| {
            let line = chosen
                .iter()
                .find(|(k, _)| *k == key)
                .map(|(_, l)| l.clone())
                .unwrap_or_else(|| {
                    table
                        .get(key)
                        .map_or(Line::Default, |v| Line::Set(v.to_string()))
                });
            (key, line)
        })
        .collect();
    section(out, manual, name, &keys);
}

/// `[name]` and its keys, each with its comment; a key without a value commented out, with its
/// default as the manual words it.
fn section(out: &mut String, manual: &str, name: &str, keys: &[(&str, Line)]) {
    let _ = writeln!(out, "[{name}]");
    for (key, value) in keys {
        let (default, meaning) = rows(manual, name)
            .find(|(k, _)| k == key)
            .map(|(_, row)| row)
            .unwrap_or_default();
        let line = match value {
            Line::Set(v) => format!("{key} = {v}"),
            Line::Offer(v) => format!("# {key} = {v}"),
            Line::Default => format!("# {key} = …  (default: {default})"),
        };
        let _ = writeln!(out, "{line:<27} # {}", first_sentence(&meaning));
    }
    out.push('\n');
}

/// The manual's table rows of `[section]`: each key with its default and meaning columns.
fn rows<'m>(manual: &'m str, section: &str) -> impl Iterator<Item = (&'m str, (String, String))> {
    let head = format!("### [{section}]");
    manual
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
