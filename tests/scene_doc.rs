//! docs/scene.md against the code: every key of the scene and jobs structs is documented, every
//! documented key exists, and every default written as a literal is the code's default. A key
//! added, renamed or given a new default without the document fails here.

mod common;
use common::manifest_dir;
use serde_aux::serde_introspection::serde_introspect;
use std::collections::{BTreeMap, BTreeSet};
use terrain_cli::app::batch::{JobsFile, RandomSection};
use terrain_engine::scene::*;

/// The documented keys of each table, by its dotted name, with their default cells.
fn documented() -> BTreeMap<String, BTreeMap<String, String>> {
    let text = std::fs::read_to_string(manifest_dir().join("docs/scene.md")).unwrap();
    let mut tables: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    let (mut file, mut table) = (String::new(), String::new());
    for line in text.lines() {
        if let Some(h) = line.strip_prefix("## ") {
            file = if h.starts_with("Jobs") {
                "jobs"
            } else {
                "scene"
            }
            .into();
        } else if let Some(h) = line.strip_prefix("### ") {
            let name = h.trim_matches(['[', ']']);
            table = match (file.as_str(), name) {
                ("jobs", "top level") => "jobs".into(),
                ("jobs", n) => format!("jobs.{n}"),
                (_, n) => n.into(),
            };
        } else if let Some(rest) = line.strip_prefix("Each entry of `") {
            let list = rest.split('`').next().unwrap();
            table = format!("{table}.{list}");
        } else if let Some(row) = line
            .strip_prefix("| ")
            .filter(|r| !r.starts_with("key |") && !table.is_empty())
        {
            let cells: Vec<&str> = row.split(" | ").collect();
            let key = cells[0].trim_matches('`').to_string();
            let default = cells.get(2).copied().unwrap_or("").trim().to_string();
            let previous = tables
                .entry(table.clone())
                .or_default()
                .insert(key.clone(), default);
            assert!(previous.is_none(), "{table}.{key} is documented twice");
        }
    }
    tables
}

/// The code's keys of each table.
fn code() -> BTreeMap<String, BTreeSet<String>> {
    let keys = |f: &[&str]| f.iter().map(|k| k.to_string()).collect::<BTreeSet<_>>();
    let mut m = BTreeMap::new();
    m.insert("sketch".into(), keys(serde_introspect::<SketchSection>()));
    m.insert("camera".into(), keys(serde_introspect::<CameraSection>()));
    m.insert("detail".into(), keys(serde_introspect::<DetailSection>()));
    m.insert("warp".into(), keys(serde_introspect::<WarpSection>()));
    m.insert(
        "importance".into(),
        keys(serde_introspect::<ImportanceSection>()),
    );
    m.insert("render".into(), keys(serde_introspect::<RenderSection>()));
    m.insert(
        "geomipmap".into(),
        keys(serde_introspect::<GeoMipMapSection>()),
    );
    m.insert(
        "reference".into(),
        keys(serde_introspect::<ReferenceSection>()),
    );
    m.insert("light".into(), keys(serde_introspect::<LightSection>()));
    m.insert("surface".into(), keys(serde_introspect::<SurfaceSection>()));
    m.insert("stream".into(), keys(serde_introspect::<StreamSection>()));
    m.insert("planet".into(), keys(serde_introspect::<PlanetSection>()));
    m.insert("path".into(), keys(serde_introspect::<PathSection>()));
    m.insert("path.keys".into(), keys(serde_introspect::<PathKey>()));
    m.insert("jobs".into(), keys(serde_introspect::<JobsFile>()));
    m.insert(
        "jobs.random".into(),
        keys(serde_introspect::<RandomSection>()),
    );
    // A job is a name plus any scene sections (documented as one row).
    m.insert("jobs.job".into(), keys(&["name", "any scene section"]));
    m
}

#[test]
fn every_key_of_the_scene_and_jobs_structs_is_documented_and_no_other() {
    let docs = documented();
    let code = code();
    // Every section of a scene has its table.
    for section in serde_introspect::<Scene>() {
        assert!(
            docs.contains_key(*section),
            "[{section}] has no table in docs/scene.md"
        );
    }
    for (table, keys) in &code {
        let doc: BTreeSet<String> = docs
            .get(table)
            .unwrap_or_else(|| panic!("no table for {table} in docs/scene.md"))
            .keys()
            .cloned()
            .collect();
        let undocumented: Vec<_> = keys.difference(&doc).collect();
        let unknown: Vec<_> = doc.difference(keys).collect();
        assert!(
            undocumented.is_empty(),
            "{table}: not in docs/scene.md: {undocumented:?}"
        );
        assert!(
            unknown.is_empty(),
            "{table}: documented but not in the code: {unknown:?}"
        );
    }
    let extra: Vec<_> = docs.keys().filter(|t| !code.contains_key(*t)).collect();
    assert!(
        extra.is_empty(),
        "tables documented that the code lacks: {extra:?}"
    );
}

#[test]
fn documented_literal_defaults_are_the_codes() {
    // A minimal scene and jobs file: whatever they do not give is the code's default.
    let scene = Scene::parse(
        "[sketch]\nsynthetic = \"flat\"\n[camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [1.0, 1.0, 0.0]\n[path]\nkeys = [{ position = [0.0, 0.0, 10.0] }, { position = [5.0, 0.0, 10.0] }]\n",
        Default::default(),
    )
    .unwrap();
    let scene = toml::Value::try_from(&scene).unwrap();
    let planet = Scene::parse(
        "[sketch]\nsynthetic = \"planet\"\n[planet]\n[camera]\nlat_deg = 0.0\nlon_deg = 0.0\naltitude_m = 10.0\n",
        Default::default(),
    )
    .unwrap();
    let planet = toml::Value::try_from(&planet).unwrap();
    let jobs: JobsFile = toml::from_str("scene = \"s.toml\"\n[random]\ncount = 1\n").unwrap();
    let jobs = toml::Value::try_from(&jobs).unwrap();
    let mut checked = 0;
    for (table, keys) in documented() {
        for (key, default) in keys {
            // Only a cell that is exactly one `literal` states a value; words describe a rule.
            let Some(literal) = default
                .strip_prefix('`')
                .and_then(|d| d.strip_suffix('`'))
                .filter(|d| !d.contains('`'))
            else {
                continue;
            };
            let want: toml::Value = toml::from_str::<toml::Table>(&format!("v = {literal}"))
                .unwrap_or_else(|e| panic!("{table}.{key}: `{literal}` is not TOML: {e}"))
                .remove("v")
                .unwrap();
            let root = if table.starts_with("jobs") {
                &jobs
            } else if table == "planet" {
                &planet
            } else {
                &scene
            };
            let path = table
                .strip_prefix("jobs")
                .unwrap_or(&table)
                .trim_start_matches('.');
            let mut here = root;
            for part in path.split('.').filter(|p| !p.is_empty()) {
                here = &here[part];
            }
            let got = here.get(&key).unwrap_or_else(|| {
                panic!("{table}.{key}: documented default {literal}, none in the code")
            });
            assert_eq!(
                got, &want,
                "{table}.{key}: docs say {literal}, the code {got}"
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 25,
        "only {checked} literal defaults found: is the table format intact?"
    );
}

#[test]
fn unset_detail_follows_the_sketch_and_set_detail_is_kept() {
    let load = |sketch: &str, detail: &str| {
        let scene = Scene::parse(
            &format!("[sketch]\n{sketch}\n[camera]\nposition = [0.0, 0.0, 5000.0]\nlook_at = [1.0, 1.0, 0.0]\n{detail}"),
            manifest_dir().join("sketches"),
        )
        .unwrap();
        let atlas = terrain_engine::scene::load_atlas(&scene).unwrap();
        terrain_engine::scene::detail_of(&scene, &atlas)
    };
    let dem = load("path = \"jacksboro_fault_dem.asc\"", "");
    let hills = load("synthetic = \"hills\"", "");
    let flat = load("synthetic = \"flat\"", "");
    // The rugged DEM gets metres of detail, the gentle hills less, the flat plain the floor;
    // 74 m cells get one octave more than 30 m cells.
    assert!(
        (5.0..30.0).contains(&dem.amplitude_m),
        "{}",
        dem.amplitude_m
    );
    assert!(
        hills.amplitude_m < dem.amplitude_m / 3.0,
        "{}",
        hills.amplitude_m
    );
    assert_eq!(flat.amplitude_m, 0.3);
    assert_eq!((dem.octaves, hills.octaves), (10, 9));
    let set = load(
        "synthetic = \"hills\"",
        "[detail]\namplitude_m = 8.0\noctaves = 12\n",
    );
    assert_eq!((set.amplitude_m, set.octaves), (8.0, 12));
}
