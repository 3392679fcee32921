//! What the picture shows of the ground, measured from outside as a user's script would: the
//! relief measure (docs/picture.md, "How the relief reads") on the bundled DEM and on fixtures
//! the shading was not tuned on, and a colour ramp against `gdaldem color-relief` of the same DEM
//! and ramp file (tests/data/surface, written by scripts/make-surface-fixtures.sh).

mod common;
use common::*;
use glam::DVec2;
use std::path::Path;
use terrain_engine::scene::{self, Scene};
use terrain_engine::{Atlas, Ground};

/// The straight-down view of a sketch `w` × `h` metres from its south-west node: from
/// `altitude_m` above its centre, 20° field of view, the sun at 315° and 45°, shadows off.
fn straight_down(w: f64, h: f64, altitude_m: f64) -> Vec<String> {
    [
        format!("camera.position=[{},{},{altitude_m}]", w / 2.0, h / 2.0),
        "camera.heading_deg=0".into(),
        "camera.pitch_deg=-90".into(),
        "camera.fov_y_deg=20".into(),
        "light.sun_azimuth_deg=315".into(),
        "light.sun_elevation_deg=45".into(),
        "render.shadows=false".into(),
    ]
    .into_iter()
    .flat_map(|s| ["--set".to_string(), s])
    .collect()
}

/// The sketch's extent in metres (`terrain info --json`).
fn extent(sketch: &Path) -> (f64, f64) {
    let (code, out, err) = terrain(&["info", sketch.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let side = |n: &str, d: &str| (v[n].as_f64().unwrap() - 1.0) * v[d].as_f64().unwrap();
    (side("width", "dx_m"), side("height", "dy_m"))
}

/// Renders `sketch` straight down at 256² with `extra` arguments; its `render --json`, image and
/// world positions.
fn render_down(
    sketch: &Path,
    altitude_m: f64,
    name: &str,
    extra: &[&str],
) -> (serde_json::Value, Vec<u8>, Vec<f64>) {
    let dir = scratch(&format!("picture-{name}"));
    let (png, npy) = (
        dir.join(format!("{name}.png")),
        dir.join(format!("{name}.npy")),
    );
    let (w, h) = extent(sketch);
    let mut args: Vec<String> = [
        "render",
        sketch.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "256",
        "--positions",
        npy.to_str().unwrap(),
        "--json",
    ]
    .map(String::from)
    .to_vec();
    args.extend(straight_down(w, h, altitude_m));
    args.extend(extra.iter().map(|s| s.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, out, err) = terrain(&refs);
    assert_eq!(code, 0, "{err}");
    let (_, _, rgba) = read_png(&png).unwrap();
    (serde_json::from_str(&out).unwrap(), rgba, read_npy(&npy).1)
}

fn relief_r(sketch: &Path, altitude_m: f64, name: &str, extra: &[&str]) -> f64 {
    let (json, _, _) = render_down(sketch, altitude_m, name, extra);
    json["relief_r"]
        .as_f64()
        .expect("relief_r with --positions")
}

#[test]
fn the_relief_reads_on_the_bundled_dem() {
    let dem = manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    // The view the measure is defined by: 57 km above the centre.
    let (json, rgba, world) = render_down(&dem, 57_000.0, "jacksboro", &[]);
    let r = json["relief_r"]
        .as_f64()
        .expect("relief_r with --positions");
    assert!(r >= 0.7, "relief r = {r:.3} on the bundled DEM");
    // The measure itself, from the library: the same picture against the hillshade under the
    // sun's own direction agrees with the command's, and against the opposite sun, whose light
    // and shade are the other way round, turns negative.
    use terrain_cli::eval::relief;
    let text = format!("[sketch]\npath = {:?}\n", dem.to_str().unwrap());
    let scene = terrain_engine::Scene::parse(&text, ".".into()).unwrap();
    let atlas = terrain_engine::scene::load_atlas(&scene).unwrap();
    let sun = |az: f64| terrain_engine::Light::new(az, 45.0, 100.0, 1200.0, 0.0).sun;
    let same = relief::relief_r(
        &rgba,
        &world,
        &atlas,
        &relief::hillshade(&atlas, sun(315.0)).unwrap(),
    );
    assert!((same.unwrap() - r).abs() < 1e-9, "{same:?} against {r}");
    let turned = relief::relief_r(
        &rgba,
        &world,
        &atlas,
        &relief::hillshade(&atlas, sun(135.0)).unwrap(),
    );
    assert!(
        turned.unwrap() < -0.5,
        "against the opposite sun: r = {turned:?}"
    );
}

#[test]
fn the_relief_reads_on_dems_the_shading_was_not_tuned_on() {
    // Jacksboro resampled by GDAL to UTM at 120 m cells: other cells, another grid, filled
    // corners. (The coast fixture, at 1/30° cells, is too gentle at its cells' scale for its
    // hillshade to vary, a spread of 0.03, and a crop 2.8 km wide is seen so close that the
    // detail's light outweighs the sketch's; docs/picture.md gives both figures.)
    let file = manifest_dir().join("tests/data/surface/jacksboro-utm.tif");
    let r = relief_r(&file, 57_000.0, "jacksboro-utm", &[]);
    assert!(r >= 0.7, "relief r = {r:.3} on {}", file.display());
}

/// Pearson's r of the pairs.
fn pearson(pairs: &[(f64, f64)]) -> f64 {
    terrain_cli::eval::relief::pearson(pairs).expect("variation in both")
}

/// A GDAL-written RGB(A) Byte GeoTIFF: (width, height, samples per pixel, samples, rows from the
/// north).
fn read_rgb_tiff(path: &Path) -> (usize, usize, usize, Vec<u8>) {
    let mut d = tiff::decoder::Decoder::new(std::fs::File::open(path).unwrap()).unwrap();
    let (w, h) = d.dimensions().unwrap();
    let spp = match d.colortype().unwrap() {
        tiff::ColorType::RGB(8) => 3,
        tiff::ColorType::RGBA(8) => 4,
        other => panic!("{other:?}"),
    };
    let tiff::decoder::DecodingResult::U8(v) = d.read_image().unwrap() else {
        panic!("not 8-bit");
    };
    (w as usize, h as usize, spp, v)
}

#[test]
fn a_colour_ramp_colours_the_ground_as_gdaldem_does() {
    let data = manifest_dir().join("tests/data/surface");
    let dem = data.join("jacksboro-utm.tif");
    let ramp = data.join("ramp.txt");
    let set = format!("surface.color_ramp={:?}", ramp.to_str().unwrap());
    let (json, rgba, world) = render_down(
        &dem,
        40_000.0,
        "ramp",
        &["--set", "surface.style=\"ramp\"", "--set", &set],
    );
    assert!(json["relief_r"].as_f64().is_some());
    for (c, r) in against_gdaldem(&rgba, &world).iter().enumerate() {
        assert!(
            *r >= 0.9,
            "channel {c}: r = {r:.3} against gdaldem color-relief"
        );
    }
    // The natural surface is no such map.
    let (_, natural, _) = render_down(&dem, 40_000.0, "natural", &[]);
    let pairs: Vec<(f64, f64)> = natural
        .chunks_exact(4)
        .zip(rgba.chunks_exact(4))
        .map(|(a, b)| (a[0] as f64, b[0] as f64))
        .collect();
    assert!(
        pearson(&pairs) < 0.9,
        "the natural surface looks like the ramp"
    );
}

/// `render` of `dem` to `out` with the override `set`, which must fail: its stderr.
fn refused(dem: &Path, out: &Path, set: &str) -> String {
    let (code, _, err) = terrain(&[
        "render",
        dem.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "32",
        "--set",
        set,
    ]);
    assert_ne!(code, 0, "--set {set} rendered: {err}");
    err
}

#[test]
fn a_bad_ramp_is_one_line_naming_the_file_and_line() {
    let dir = scratch("picture-bad-ramp");
    let bad = dir.join("bad.txt");
    std::fs::write(&bad, "0 0 0 0\n100 mauve\n").unwrap();
    let dem = manifest_dir().join("sketches/jacksboro_fault_dem.asc");
    let out = dir.join("x.png");
    for (ramp, expect) in [
        (bad.to_str().unwrap().to_string(), "line 2"),
        (
            dir.join("missing.txt").to_str().unwrap().to_string(),
            "colour ramp",
        ),
    ] {
        let err = refused(&dem, &out, &format!("surface.color_ramp={ramp:?}"));
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains("colour ramp") && err.contains(expect), "{err}");
    }
}

/// Per-channel r between the picture and gdaldem's image of jacksboro-utm.tif on the DEM's own
/// grid (node (i, j) from the south-west is pixel (i, h − 1 − j)), gdaldem's nodata (black, the
/// warped corners) left out.
fn against_gdaldem(rgba: &[u8], world: &[f64]) -> [f64; 3] {
    let data = manifest_dir().join("tests/data/surface");
    let (w, h, spp, relief) = read_rgb_tiff(&data.join("jacksboro-ramp.tif"));
    let (ew, eh) = extent(&data.join("jacksboro-utm.tif"));
    let (dx, dy) = (ew / (w - 1) as f64, eh / (h - 1) as f64);
    let mut channels = [vec![], vec![], vec![]];
    for (p, q) in rgba.chunks_exact(4).zip(world.chunks_exact(4)) {
        let (i, j) = ((q[0] / dx).round(), (q[1] / dy).round());
        if q[3] < 0.5 || i < 0.0 || j < 0.0 || i >= w as f64 || j >= h as f64 {
            continue;
        }
        let k = ((h - 1 - j as usize) * w + i as usize) * spp;
        if relief[k..k + 3] == [0, 0, 0] {
            continue;
        }
        for c in 0..3 {
            channels[c].push((p[c] as f64, relief[k + c] as f64));
        }
    }
    assert!(channels[0].len() > 20_000, "{} pixels", channels[0].len());
    [0, 1, 2].map(|c| pearson(&channels[c]))
}

#[test]
fn imagery_in_another_crs_is_draped_where_it_lies() {
    let data = manifest_dir().join("tests/data/surface");
    let dem = data.join("jacksboro-utm.tif");
    // gdaldem's image of the DEM, warped by GDAL to EPSG:4326: placed through latitude and
    // longitude onto the UTM sketch, it lies where its colours' heights are.
    let image = format!(
        "surface.image={:?}",
        data.join("ortho-4326.tif").to_str().unwrap()
    );
    let (_, rgba, world) = render_down(&dem, 40_000.0, "ortho", &["--set", &image]);
    for (c, r) in against_gdaldem(&rgba, &world).iter().enumerate() {
        assert!(
            *r >= 0.9,
            "channel {c}: r = {r:.3} against the draped image"
        );
    }
    // A PNG with a world file (no coordinate system: the sketch's) of the same image's west
    // part: there the same picture as the GeoTIFF's, east of it the natural surface.
    let png = format!(
        "surface.image={:?}",
        data.join("ortho-west.png").to_str().unwrap()
    );
    let (_, west_png, _) = render_down(&dem, 40_000.0, "ortho-west", &["--set", &png]);
    let edge = 129.0 * 120.0;
    let differ = |keep: &dyn Fn(f64) -> bool| {
        let (mut sum, mut n) = (0.0, 0usize);
        for ((a, b), q) in rgba
            .chunks_exact(4)
            .zip(west_png.chunks_exact(4))
            .zip(world.chunks_exact(4))
        {
            if q[3] > 0.5 && keep(q[0]) {
                sum += (0..3)
                    .map(|c| (a[c] as f64 - b[c] as f64).abs())
                    .sum::<f64>()
                    / 3.0;
                n += 1;
            }
        }
        assert!(n > 5_000, "{n} pixels");
        sum / n as f64
    };
    let west = differ(&|x| x < edge - 2_000.0);
    let east = differ(&|x| x > edge + 2_000.0);
    assert!(
        west < 3.0,
        "the PNG's picture differs from the GeoTIFF's by {west:.2} where both cover"
    );
    assert!(
        east > 10.0,
        "east of the PNG's edge the picture is still the image's ({east:.2})"
    );
}

#[test]
fn an_image_that_cannot_be_placed_is_one_line() {
    let data = manifest_dir().join("tests/data/surface");
    let dir = scratch("picture-bad-image");
    let out = dir.join("x.png");
    let utm = data.join("jacksboro-utm.tif");
    let coast = data.join("coast-4326.tif");
    for (dem, image, expect) in [
        (&utm, "ortho-plain.tif", "no georeference"),
        (&coast, "ortho-4326.tif", "misses the sketch"),
        (&utm, "coast-plain.tif", "8-bit"),
        (&utm, "missing.tif", "surface image"),
    ] {
        let set = format!("surface.image={:?}", data.join(image).to_str().unwrap());
        let err = refused(dem, &out, &set);
        let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("warning:")).collect();
        assert_eq!(lines.len(), 1, "{image}: {err}");
        assert!(
            err.contains("surface image") && err.contains(expect),
            "{image}: {err}"
        );
    }
}

/// The mean luma step (Rec. 709 weights on the encoded values) between 4-neighbour pixels that
/// straddle the sketch's border (one on the sketch by `--positions`, one beyond), over the mean
/// step between neighbours both on the sketch within 4 pixels of it.
fn border_contrast(rgba: &[u8], world: &[f64], side: usize) -> f64 {
    let luma: Vec<f64> = rgba
        .chunks_exact(4)
        .map(|p| (0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64) / 255.0)
        .collect();
    let on: Vec<bool> = world.chunks_exact(4).map(|p| p[3] == 1.0).collect();
    // Distance in pixels (4-neighbour steps, up to 4) from the nearest pixel beyond the sketch.
    let mut near = vec![false; on.len()];
    for (k, n) in near.iter_mut().enumerate() {
        let (x, y) = ((k % side) as i64, (k / side) as i64);
        *n = on[k]
            && (-4i64..=4).any(|dy| {
                (-4i64..=4).any(|dx| {
                    let (i, j) = (x + dx, y + dy);
                    dx.abs() + dy.abs() <= 4
                        && (0..side as i64).contains(&i)
                        && (0..side as i64).contains(&j)
                        && !on[j as usize * side + i as usize]
                })
            });
    }
    let (mut across, mut within) = (Vec::new(), Vec::new());
    for y in 0..side {
        for x in 0..side {
            let a = y * side + x;
            for b in [
                (x + 1 < side).then(|| a + 1),
                (y + 1 < side).then(|| a + side),
            ]
            .into_iter()
            .flatten()
            {
                let step = (luma[a] - luma[b]).abs();
                if on[a] != on[b] {
                    across.push(step);
                } else if on[a] && (near[a] || near[b]) {
                    within.push(step);
                }
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    assert!(
        across.len() > 100 && within.len() > 100,
        "{} {}",
        across.len(),
        within.len()
    );
    mean(&across) / mean(&within)
}

/// hills-high's slab meets the plain without a step: seen from its own camera (the whole sketch
/// and the margin around it), the light across the sketch's border changes no more than between
/// neighbours on the sketch, in a mesh mode and in the reference; the same measure finds the
/// border where the sketch floats over the void.
#[test]
fn the_sketchs_border_draws_no_seam() {
    let scene = manifest_dir().join("sketches/hills-high.toml");
    let dir = scratch("picture-border");
    let contrast = |name: &str, set: &str| {
        let (png, npy) = (
            dir.join(format!("{name}.png")),
            dir.join(format!("{name}.npy")),
        );
        let (code, _, err) = terrain(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--size",
            "256",
            "--positions",
            npy.to_str().unwrap(),
            "--set",
            set,
        ]);
        assert_eq!(code, 0, "{err}");
        let (_, _, rgba) = read_png(&png).unwrap();
        border_contrast(&rgba, &read_npy(&npy).1, 256)
    };
    let warped = contrast("warped", "render.mode=\"warped\"");
    let reference = contrast("reference", "render.mode=\"reference\"");
    let void = contrast("void", "sketch.outside=\"void\"");
    eprintln!("border contrast: warped {warped:.2}, reference {reference:.2}, void {void:.2}");
    assert!(warped <= 1.5 && reference <= 1.5, "{warped} {reference}");
    assert!(void >= 5.0, "{void}");
}

/// Regions of `mask` (4-connected) smaller than 4 pixels, among `within`.
fn small_regions(mask: &[bool], within: &[bool], side: usize) -> usize {
    let mut seen = vec![false; mask.len()];
    let mut small = 0;
    for start in 0..mask.len() {
        if seen[start] || !mask[start] || !within[start] {
            continue;
        }
        let (mut stack, mut size) = (vec![start], 0);
        seen[start] = true;
        while let Some(k) = stack.pop() {
            size += 1;
            let (x, y) = (k % side, k / side);
            let next = [
                (x > 0).then(|| k - 1),
                (x + 1 < side).then(|| k + 1),
                (y > 0).then(|| k - side),
                (y + 1 < side).then(|| k + side),
            ];
            for n in next.into_iter().flatten() {
                if !seen[n] && mask[n] && within[n] {
                    seen[n] = true;
                    stack.push(n);
                }
            }
        }
        small += usize::from(size < 4);
    }
    small
}

/// The GDAL-written coast with bathymetry at 512², its default view: no region of water or land
/// under 4 pixels (sides touching) along the shore. Water and land are told apart by colour (the
/// water's blue exceeds its red by 85 or more of 255; few pixels lie near that line, the test
/// checks), where the sketch at the pixel's position lies within 20 m of the water's level (the
/// height the shore is shaded at; the mesh's own rises across a coast's triangles): toward the
/// horizon the haze turns land hundreds of metres up as blue as the water (five such pixels, at
/// 140–560 m, passed the colour alone). Without the output pass's clean-up of specks, 33 pools
/// remained.
#[test]
fn a_coast_has_few_isolated_shore_pixels() {
    let dem = manifest_dir().join("tests/data/surface/coast-4326.tif");
    let dir = scratch("picture-coast");
    let (png, npy) = (dir.join("coast.png"), dir.join("coast.npy"));
    let (code, _, err) = terrain(&[
        "render",
        dem.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "512",
        "--positions",
        npy.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let (_, _, rgba) = read_png(&png).unwrap();
    let positions = read_npy(&npy).1;
    let on: Vec<bool> = positions.chunks_exact(4).map(|p| p[3] == 1.0).collect();
    let blue: Vec<i32> = rgba
        .chunks_exact(4)
        .map(|p| p[2] as i32 - p[0] as i32)
        .collect();
    let between = (0..on.len())
        .filter(|&k| on[k] && (81..90).contains(&blue[k]))
        .count();
    let ground = on.iter().filter(|&&o| o).count();
    assert!(
        between * 200 < ground,
        "{between} of {ground} pixels between water and land"
    );
    let (loaded, atlas, detail) = coast_sketch(&dem);
    let ground = Ground::new(&loaded, &atlas, &detail);
    let heights: Vec<f64> = positions
        .chunks_exact(4)
        .map(|p| sketch_height(&ground, &atlas, p).unwrap_or(f64::INFINITY))
        .collect();
    let water: Vec<bool> = (0..blue.len())
        .map(|k| blue[k] >= 85 && heights[k] < 20.0)
        .collect();
    let land: Vec<bool> = water.iter().map(|w| !w).collect();
    let (pools, islets) = (
        small_regions(&water, &on, 512),
        small_regions(&land, &on, 512),
    );
    eprintln!("coast at 512²: {pools} water and {islets} land regions under 4 pixels");
    assert!(pools == 0 && islets == 0, "{pools} pools, {islets} islets");
}

/// The sketch `dem` and its detail, for the CPU's terrain function with the octaves off.
fn coast_sketch(dem: &Path) -> (Scene, Atlas, terrain_engine::Detail) {
    let loaded = Scene::load_with(dem, &["detail.octaves=0".to_string()]).unwrap();
    let atlas = scene::load_atlas(&loaded).unwrap();
    let detail = scene::detail_of(&loaded, &atlas);
    (loaded, atlas, detail)
}

/// An 8-bit indexed PNG's indices (the surface classes).
fn read_indexed(path: &Path) -> Vec<u8> {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut indices = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut indices).unwrap();
    assert_eq!(info.color_type, png::ColorType::Indexed);
    indices
}

/// The sketch's height at a `positions` pixel `p` (x, y, z, then 1 on the ground): None on the
/// sky and beyond the sketch.
fn sketch_height(ground: &Ground, atlas: &Atlas, p: &[f64]) -> Option<f64> {
    let xy = DVec2::new(p[0], p[1]);
    let inside = xy.cmpge(atlas.origin).all() && xy.cmple(atlas.max_corner()).all();
    let z = ground.height_at(xy, 0.0).ok().flatten();
    z.filter(|_| p[3] == 1.0 && inside)
}

/// The shore is the sketch's contour, whatever the mesh: on the coast fixture at 512², its default
/// view, with the octaves off (a mesh of 3,042 triangles, far coarser than the sketch's cells) and
/// on, a pixel's class is water where the sketch's own height at the pixel's position (the CPU's
/// terrain function, octaves off) lies at or below the water's level, and only there. Shaded at
/// the mesh's height, the shore followed the mesh's facets: 21,771 pixels disagreed with the
/// octaves off and 9,004 with them on, against 9,439 and 9,426 shore edges; now 19 each (the
/// sketch read here at level 0, by the picture at its footprint's level far away).
#[test]
fn the_shore_is_the_sketchs_contour_whatever_the_mesh() {
    let dem = manifest_dir().join("tests/data/surface/coast-4326.tif");
    let (loaded, atlas, detail) = coast_sketch(&dem);
    let ground = Ground::new(&loaded, &atlas, &detail);
    let water_m = atlas.water_m as f64;
    let dir = scratch("picture-shore");
    let side = 512;
    for octaves in ["0", "4"] {
        let image = dir.join(format!("coast-{octaves}.png"));
        let set = format!("detail.octaves={octaves}");
        let (code, _, err) = terrain(&[
            "render",
            dem.to_str().unwrap(),
            "-o",
            image.to_str().unwrap(),
            "--size",
            "512",
            "--set",
            &set,
            "--outputs",
            "positions,surface",
        ]);
        assert_eq!(code, 0, "{err}");
        let classes = read_indexed(&dir.join(format!("coast-{octaves}.surface.png")));
        let positions = read_npy(&dir.join(format!("coast-{octaves}.positions.npy"))).1;
        // Whether the sketch lies under the water at each ground pixel; None on the sky.
        let under: Vec<Option<bool>> = positions
            .chunks_exact(4)
            .map(|p| sketch_height(&ground, &atlas, p).map(|z| z <= water_m))
            .collect();
        let mut shore = 0;
        for i in 0..side * side {
            let (x, y) = (i % side, i / side);
            let next = [(x + 1 < side, i + 1), (y + 1 < side, i + side)];
            for (inside, j) in next {
                if let (true, Some(a), Some(b)) =
                    (inside, under[i], under.get(j).copied().flatten())
                {
                    shore += usize::from(a != b);
                }
            }
        }
        let wrong = (0..side * side)
            .filter(|&i| under[i].is_some_and(|u| u != (classes[i] == 1)))
            .count();
        eprintln!(
            "octaves {octaves}: {wrong} pixels against the sketch's contour, {shore} shore edges"
        );
        assert!(
            shore > 5_000,
            "{shore} shore edges: the view misses the coast"
        );
        assert!(
            wrong * 100 < shore,
            "{wrong} pixels off the sketch's contour, {shore} shore edges"
        );
    }
}

/// The imagery at `image` draped over jacksboro-utm.tif by the library.
fn drape_over_utm(image: &Path) -> terrain_engine::Result<terrain_engine::surface::Drape> {
    let dem = manifest_dir().join("tests/data/surface/jacksboro-utm.tif");
    let atlas = terrain_engine::Atlas::load(&dem, &Default::default()).unwrap();
    terrain_engine::surface::drape(image, &atlas)
}

/// Per-channel r between two drapes of one grid over the texels both cover fully.
fn drape_r(a: &terrain_engine::surface::Drape, b: &terrain_engine::surface::Drape) -> [f64; 3] {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let both: Vec<(&[u8], &[u8])> = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .filter(|(p, q)| p[3] == 255 && q[3] == 255)
        .collect();
    assert!(both.len() > 20_000, "{} texels covered by both", both.len());
    let r = [0, 1, 2].map(|c| {
        let pairs: Vec<(f64, f64)> = both
            .iter()
            .map(|(p, q)| (p[c] as f64, q[c] as f64))
            .collect();
        pearson(&pairs)
    });
    eprintln!("per-channel r over {} texels: {r:.4?}", both.len());
    r
}

#[test]
fn a_jpeg_with_a_world_file_drapes_as_the_geotiff_does() {
    let data = manifest_dir().join("tests/data/surface");
    let dem = data.join("jacksboro-utm.tif");
    // GDAL's JPEG of gdaldem's image, placed by its .jgw in the sketch's coordinates.
    let jpeg = data.join("ortho.jpg");
    let set = format!("surface.image={:?}", jpeg.to_str().unwrap());
    let (_, rgba, world) = render_down(&dem, 40_000.0, "ortho-jpeg", &["--set", &set]);
    for (c, r) in against_gdaldem(&rgba, &world).iter().enumerate() {
        assert!(*r >= 0.9, "channel {c}: r = {r:.3} against the draped JPEG");
    }
    // The drape itself against the GeoTIFF's: the same texels but for JPEG's loss.
    let from_jpeg = drape_over_utm(&jpeg).unwrap();
    let from_tiff = drape_over_utm(&data.join("jacksboro-ramp.tif")).unwrap();
    for (c, r) in drape_r(&from_jpeg, &from_tiff).iter().enumerate() {
        assert!(
            *r >= 0.98,
            "channel {c}: r = {r:.4} between the JPEG's and the GeoTIFF's drapes"
        );
    }
    // GDAL's own name for the world file, .wld, and .jpeg: the same drape.
    let dir = scratch("picture-jpeg-wld");
    std::fs::copy(&jpeg, dir.join("ortho.jpeg")).unwrap();
    std::fs::copy(data.join("ortho.jgw"), dir.join("ortho.wld")).unwrap();
    let from_wld = drape_over_utm(&dir.join("ortho.jpeg")).unwrap();
    assert_eq!(from_wld.rgba, from_jpeg.rgba);
}

#[test]
fn a_bad_jpeg_is_one_line() {
    let data = manifest_dir().join("tests/data/surface");
    let dir = scratch("picture-bad-jpeg");
    let bytes = std::fs::read(data.join("ortho.jpg")).unwrap();
    let world = std::fs::read(data.join("ortho.jgw")).unwrap();
    let cases: [(&str, Vec<u8>, bool, &str); 4] = [
        (
            "truncated",
            bytes[..bytes.len() / 2].to_vec(),
            true,
            "truncated",
        ),
        (
            "garbage",
            b"not a JPEG at all, only words".to_vec(),
            true,
            "JPEG",
        ),
        ("unplaced", bytes.clone(), false, "no world file"),
        (
            "flipped",
            bytes.iter().map(|b| b ^ 0x20).collect(),
            true,
            "JPEG",
        ),
    ];
    let dem = data.join("jacksboro-utm.tif");
    let out = dir.join("x.png");
    for (name, jpeg, with_world, expect) in cases {
        let path = dir.join(format!("{name}.jpg"));
        std::fs::write(&path, jpeg).unwrap();
        if with_world {
            std::fs::write(dir.join(format!("{name}.jgw")), &world).unwrap();
        }
        let err = refused(
            &dem,
            &out,
            &format!("surface.image={:?}", path.to_str().unwrap()),
        );
        let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("warning:")).collect();
        assert_eq!(lines.len(), 1, "{name}: {err}");
        assert!(
            err.contains("surface image")
                && err.contains(&format!("{name}.jpg"))
                && err.contains(expect),
            "{name}: {err}"
        );
    }
}

/// `terrain tiles SRC --out-dir DIR --json` (with `extra` arguments), which must succeed: its
/// JSON.
fn tiles(src: &Path, dir: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "tiles",
        src.to_str().unwrap(),
        "--out-dir",
        dir.to_str().unwrap(),
    ];
    args.extend(extra);
    args.push("--json");
    let (code, out, err) = terrain(&args);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn an_image_pyramid_drapes_as_the_image_it_was_made_of() {
    let data = manifest_dir().join("tests/data/surface");
    let dir = scratch("picture-image-pyramid");
    // An RGBA image in strips, in EPSG:4326 over the UTM sketch: its pixels (about 110 m) are
    // coarser than the drape's texels, so the drape reads level 0, and the window of it under
    // the sketch gives the drape of the image read whole, texel for texel.
    let ortho = data.join("ortho-4326.tif");
    let pyramid = dir.join("ortho-4326");
    let json = tiles(&ortho, &pyramid, &[]);
    assert_eq!(json["kind"], "image", "{json}");
    let meta = std::fs::read_to_string(pyramid.join("pyramid.toml")).unwrap();
    assert!(
        meta.contains("kind = \"image\"") && meta.contains("samples = \"rgba\""),
        "{meta}"
    );
    let whole = drape_over_utm(&ortho).unwrap();
    let tiled = drape_over_utm(&pyramid).unwrap();
    assert_eq!(
        (tiled.width, tiled.height, tiled.texel),
        (whole.width, whole.height, whole.texel)
    );
    assert!(
        tiled.rgba == whole.rgba,
        "the pyramid's drape differs from the image's"
    );
    // So does the picture, through the scene.
    let set = |p: &Path| format!("surface.image={:?}", p.to_str().unwrap());
    let dem = data.join("jacksboro-utm.tif");
    let (_, a, _) = render_down(&dem, 40_000.0, "pyramid", &["--set", &set(&pyramid)]);
    let (_, b, _) = render_down(&dem, 40_000.0, "pyramid-whole", &["--set", &set(&ortho)]);
    assert!(
        a == b,
        "the picture over the pyramid differs from the picture over the image"
    );

    // A tiled RGB GeoTIFF of 4 m pixels over the DEM's middle 4 km: 3.8 of them to a texel of
    // the drape over the whole DEM (at most 2048 a side), so the drape reads level 2, whose
    // pixels are nearest the texels; the others are removed to show that it reads no other.
    let fine = data.join("ortho-fine.tif");
    let pyramid = dir.join("ortho-fine");
    let json = tiles(&fine, &pyramid, &[]);
    assert_eq!(
        (json["width"].as_u64(), json["levels"].as_u64()),
        (Some(1024), Some(10))
    );
    let levels: Vec<_> = std::fs::read_dir(&pyramid)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    // Resuming: a level and pyramid.toml lost are written again, and only they.
    std::fs::remove_dir_all(pyramid.join("L1")).unwrap();
    std::fs::remove_file(pyramid.join("pyramid.toml")).unwrap();
    let again = tiles(&fine, &pyramid, &[]);
    assert_eq!(again["tiles_written"].as_u64(), Some(4), "{again}");
    for level in levels
        .iter()
        .filter(|p| p.file_name().unwrap().to_str().unwrap().starts_with('L'))
    {
        if level.file_name().unwrap() != "L2" {
            std::fs::remove_dir_all(level).unwrap();
        }
    }
    let whole = drape_over_utm(&fine).unwrap();
    let tiled = drape_over_utm(&pyramid).unwrap();
    assert!(
        (tiled.covered - whole.covered).abs() < 0.002,
        "{} against {}",
        tiled.covered,
        whole.covered
    );
    for (c, r) in drape_r(&tiled, &whole).iter().enumerate() {
        assert!(
            *r >= 0.98,
            "channel {c}: r = {r:.4} between level 2's drape and the image's"
        );
    }
    // A damaged tile of that level is one line naming it.
    let tile = pyramid.join("L2/0/0.tile");
    let bytes = std::fs::read(&tile).unwrap();
    std::fs::write(&tile, &bytes[..bytes.len() / 2]).unwrap();
    let err = drape_over_utm(&pyramid).unwrap_err().to_string();
    assert!(
        err.starts_with("surface image")
            && err.contains("L2/0/0.tile")
            && err.contains("truncated"),
        "{err}"
    );
}

#[test]
fn a_pyramid_in_the_other_role_is_one_line() {
    let data = manifest_dir().join("tests/data/surface");
    let dir = scratch("picture-pyramid-roles");
    let dem = data.join("jacksboro-utm.tif");
    let heights = dir.join("heights");
    assert_eq!(tiles(&dem, &heights, &[])["kind"], "heights");
    // 8-bit grey could be heights: so it is, unless --image says it is an image.
    let grey = dir.join("grey.tif");
    write_grey_utm(&grey);
    assert_eq!(
        tiles(&grey, &dir.join("grey-heights"), &[])["kind"],
        "heights"
    );
    let image = dir.join("image");
    assert_eq!(tiles(&grey, &image, &["--image"])["kind"], "image");
    assert!(drape_over_utm(&image).unwrap().covered > 0.9);
    let out = dir.join("x.png");
    let err = refused(
        &dem,
        &out,
        &format!("surface.image={:?}", heights.to_str().unwrap()),
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("surface image")
            && err.contains("pyramid.toml")
            && err.contains("holds heights"),
        "{err}"
    );
    let (code, _, err) = terrain(&[
        "render",
        image.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "32",
    ]);
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("sketch") && err.contains("pyramid.toml") && err.contains("holds an image"),
        "{err}"
    );
}

/// A 64² 8-bit grey GeoTIFF in UTM 17N over the Jacksboro DEM, 500 m pixels.
fn write_grey_utm(path: &Path) {
    use tiff::encoder::{TiffEncoder, colortype::Gray8};
    use tiff::tags::Tag;
    let mut enc = TiffEncoder::new(std::fs::File::create(path).unwrap()).unwrap();
    let mut image = enc.new_image::<Gray8>(64, 64).unwrap();
    let dir = image.encoder();
    dir.write_tag(Tag::ModelPixelScaleTag, &[500.0f64, 500.0, 0.0][..])
        .unwrap();
    dir.write_tag(
        Tag::ModelTiepointTag,
        &[0.0f64, 0.0, 0.0, 194_000.0, 4_071_000.0, 0.0][..],
    )
    .unwrap();
    // Projected (1024 = 1), pixel-is-area (1025 = 1), EPSG:32617 (3072).
    let keys: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32617];
    dir.write_tag(Tag::GeoKeyDirectoryTag, &keys[..]).unwrap();
    let data: Vec<u8> = (0..64 * 64)
        .map(|k| (((k % 64) * 4) ^ ((k / 64) * 4)) as u8)
        .collect();
    image.write_data(&data).unwrap();
}
