//! Ground truth beside the images (`--outputs`, docs/batch.md): depth against the positions and
//! against the terrain function's own ray cast, flow against reprojection, the cameras against
//! their pixels, and the NeRF and COLMAP exports read back as those tools read them.

mod common;
use common::*;
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use serde_json::Value;
use std::path::Path;
use terrain::{Description, Ground, Scene};

/// A `.npy` of f32 or f64 as f64 values, with its shape.
fn npy(path: &Path) -> (Vec<usize>, Vec<f64>) {
    let b = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
    let n = u16::from_le_bytes([b[8], b[9]]) as usize;
    let header = String::from_utf8(b[10..10 + n].to_vec()).unwrap();
    let shape_text = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let shape = shape_text
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let data = &b[10 + n..];
    let values = if header.contains("'<f4'") {
        data.chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect()
    } else {
        assert!(header.contains("'<f8'"), "{header}");
        data.chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    (shape, values)
}

fn matrix(v: &Value) -> DMat4 {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
    DMat4::from_cols_array_2d(&std::array::from_fn(|c| {
        std::array::from_fn(|r| rows[r][c])
    }))
}

/// Pixel position (OpenCV's convention) of world point `p`, and its depth.
fn project(k: &Value, w2c: DMat4, p: DVec3) -> (f64, f64, f64) {
    let c = w2c * p.extend(1.0);
    let f = |key: &str| k[key].as_f64().unwrap();
    (
        f("fx") * c.x / c.z + f("cx"),
        f("fy") * c.y / c.z + f("cy"),
        c.z,
    )
}

/// A small deterministic generator (the tests' pixel picks).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self, n: usize) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) as usize) % n
    }
}

const SIZE: usize = 128;

/// The mode the depth is checked in: the reference, whose pixels lie on the terrain function
/// (`TERRAIN_TRUTH_MODE` measures another; the mesh modes' lie within their own error of it).
fn mode() -> String {
    std::env::var("TERRAIN_TRUTH_MODE").unwrap_or_else(|_| "reference".into())
}

#[test]
fn depth_matches_the_positions_and_the_terrain_functions_ray_cast() {
    let dir = scratch("truth-depth");
    let mut report = Vec::new();
    for view in ["jacksboro.toml", "jacksboro-high.toml", "hills-high.toml"] {
        let source = manifest_dir().join("sketches").join(view);
        let image = dir.join(view.replace(".toml", ".png"));
        let size = SIZE.to_string();
        let (code, out, err) = terrain(&[
            "render",
            source.to_str().unwrap(),
            "-o",
            image.to_str().unwrap(),
            "--size",
            &size,
            "--mode",
            &mode(),
            "--outputs",
            "depth,distance,positions",
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        let json: Value = serde_json::from_str(&out).unwrap();
        let stem = image.with_extension("");
        let stem = stem.to_str().unwrap();
        let (shape, depth) = npy(Path::new(&format!("{stem}.depth.npy")));
        assert_eq!(shape, [SIZE, SIZE]);
        let (_, distance) = npy(Path::new(&format!("{stem}.distance.npy")));
        let (shape, positions) = npy(Path::new(&format!("{stem}.positions.npy")));
        assert_eq!(shape, [SIZE, SIZE, 4]);
        assert_eq!(
            json["outputs"]["depth"].as_str().unwrap(),
            format!("{stem}.depth.npy")
        );
        let k = &json["intrinsics"];
        let w2c = matrix(&json["extrinsics"]["world_to_camera"]);
        let c2w = matrix(&json["extrinsics"]["camera_to_world"]);
        assert!((w2c * c2w).abs_diff_eq(DMat4::IDENTITY, 1e-9));
        let eye = c2w.w_axis.truncate();

        let description = Description::new(Scene::load(&source).unwrap()).unwrap();
        let detail = description.detail();
        let ground = Ground::new(description.scene(), description.atlas(), &detail);
        let fy = k["fy"].as_f64().unwrap();
        let pixel_scale = 1.0 / fy;

        let ground_px: Vec<usize> = (0..SIZE * SIZE)
            .filter(|&i| positions[4 * i + 3] > 0.5)
            .collect();
        assert!(
            ground_px.len() > 1000,
            "{view}: {} ground pixels",
            ground_px.len()
        );
        let sky = (0..SIZE * SIZE).find(|&i| positions[4 * i + 3] < 0.5);
        if let Some(i) = sky {
            assert!(depth[i].is_infinite() && distance[i].is_infinite());
        }
        let mut rng = Lcg(view.len() as u64);
        let (mut depth_rel, mut centre_px) = (0.0f64, 0.0f64);
        let mut cast = Vec::with_capacity(1000);
        for _ in 0..1000 {
            let i = ground_px[rng.next(ground_px.len())];
            let p = DVec3::new(positions[4 * i], positions[4 * i + 1], positions[4 * i + 2]);
            let (u, v, z) = project(k, w2c, p);
            depth_rel = depth_rel.max((depth[i] - z).abs() / z);
            depth_rel = depth_rel.max((distance[i] - p.distance(eye)).abs() / p.distance(eye));
            let (col, row) = ((i % SIZE) as f64, (i / SIZE) as f64);
            centre_px = centre_px.max((u - col).hypot(v - row));
            // The ray through the pixel's centre, from K and the pose alone.
            let cam = DVec4::new(
                (col - k["cx"].as_f64().unwrap()) / k["fx"].as_f64().unwrap(),
                (row - k["cy"].as_f64().unwrap()) / fy,
                1.0,
                0.0,
            );
            let dir = (c2w * cam).truncate();
            let hit = ground
                .ray_cast(eye, dir, pixel_scale)
                .unwrap()
                .expect("the ray meets the ground the pixel shows");
            cast.push(hit.distance(p));
        }
        cast.sort_by(f64::total_cmp);
        let cast_m = cast[cast.len() - 1];
        report.push(format!(
            "{view} ({}): depth {depth_rel:.1e} relative, centre {centre_px:.1e} px, ray cast \
             median {:.3} m, p99 {:.3} m, most {cast_m:.3} m",
            mode(),
            cast[cast.len() / 2],
            cast[cast.len() * 99 / 100],
        ));
        assert!(depth_rel < 1e-4, "{}", report.join("; "));
        assert!(centre_px < 0.01, "{}", report.join("; "));
        if mode() == "reference" {
            assert!(cast_m < 0.5, "{}", report.join("; "));
        }
    }
    eprintln!("{}", report.join("\n"));
}

/// A grey PNG's bytes.
fn gray_png(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    buf.truncate(info.buffer_size());
    buf
}

#[test]
fn flow_is_the_reprojection_into_the_next_frame_and_occlusion_is_what_it_hides() {
    let dir = scratch("truth-flow");
    let source = manifest_dir().join("sketches/jacksboro.toml");
    let description = Description::new(Scene::load(&source).unwrap()).unwrap();
    let detail = description.detail();
    let ground = Ground::new(description.scene(), description.atlas(), &detail);
    let (w, h) = (96usize, 64usize);
    let (code, _, err) = terrain(&[
        "fly",
        source.to_str().unwrap(),
        "--out-dir",
        dir.to_str().unwrap(),
        "--frames",
        "10",
        "--size",
        "96x64",
        "--no-mp4",
        // The reference's pixels lie on the terrain function, which the check below ray-casts.
        "--mode",
        "reference",
        // 100 m of the bundled view's heading, a walk's ten frames apart.
        "--set",
        "path.keys=[{position=[15000.0,2000.0,1120.0],look_at=[15000.0,20000.0,400.0]},\
         {position=[15000.0,2100.0,1120.0],look_at=[15000.0,20100.0,400.0]}]",
        "--outputs",
        "flow,positions",
    ]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<Value> = std::fs::read_to_string(dir.join("frames.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 10);
    assert!(
        !dir.join("frame-00009.flow.npy").exists(),
        "the last frame has no next one"
    );
    let (mut worst, mut seen, mut moved, mut hidden_far) = (0.0f64, 0usize, 0.0f64, 0usize);
    let mut ground_px = 0;
    for k in 0..9 {
        let file = |s: &str| dir.join(format!("frame-{k:05}.{s}"));
        assert_eq!(
            lines[k]["outputs"]["flow"].as_str(),
            Some(format!("frame-{k:05}.flow.npy").as_str())
        );
        let (shape, flow) = npy(&file("flow.npy"));
        assert_eq!(shape, [h, w, 2]);
        let (_, here) = npy(&file("positions.npy"));
        let occluded = gray_png(&file("occlusion.png"));
        let flo = std::fs::read(file("flow.flo")).unwrap();
        assert_eq!(&flo[..4], b"PIEH");
        let k1 = &lines[k + 1]["intrinsics"];
        let w2c1 = matrix(&lines[k + 1]["extrinsics"]["world_to_camera"]);
        let c2w1 = matrix(&lines[k + 1]["extrinsics"]["camera_to_world"]);
        let pixel_scale = 1.0 / k1["fy"].as_f64().unwrap();
        for i in 0..w * h {
            let flo_u = f32::from_le_bytes(flo[12 + 8 * i..16 + 8 * i].try_into().unwrap());
            if here[4 * i + 3] < 0.5 {
                assert_eq!(occluded[i], 255, "sky is occluded");
                assert!(flow[2 * i].is_nan() && flo_u > 1e9);
                continue;
            }
            ground_px += 1;
            let p = DVec3::new(here[4 * i], here[4 * i + 1], here[4 * i + 2]);
            let (u, v, _) = project(k1, w2c1, p);
            let (col, row) = ((i % w) as f64, (i / w) as f64);
            if flow[2 * i].is_nan() {
                // Behind the next camera: no flow, and occluded.
                assert!(flo_u > 1e9 && occluded[i] == 255);
                continue;
            }
            assert_eq!(flo_u, flow[2 * i] as f32);
            if occluded[i] != 0 {
                continue;
            }
            seen += 1;
            let err = (col + flow[2 * i] - u).hypot(row + flow[2 * i + 1] - v);
            worst = worst.max(err);
            moved = moved.max(flow[2 * i].hypot(flow[2 * i + 1]));
            // Seen from the next eye, nothing of the terrain function stands before the point.
            let eye1 = c2w1.w_axis.truncate();
            let hit = ground.ray_cast(eye1, p - eye1, pixel_scale).unwrap();
            if hit.is_none_or(|q| q.distance(eye1) < p.distance(eye1) * 0.98 - 1.0) {
                hidden_far += 1;
            }
        }
    }
    // Walking forward, most ground stays in view; what leaves is the bottom rows.
    assert!(
        seen * 10 > ground_px * 8,
        "{seen} of {ground_px} ground pixels seen in the next frame"
    );
    assert!(moved > 0.5, "the camera moves: flow up to {moved} px");
    assert!(worst < 0.05, "flow off its reprojection by {worst} px");
    assert!(
        hidden_far * 100 < seen,
        "{hidden_far} of {seen} unoccluded pixels are hidden from the next eye"
    );
    eprintln!(
        "flow: {seen} pixels, worst {worst:.1e} px off the reprojection, up to {moved:.1} px; \
         {hidden_far} hidden from the next eye"
    );
}

#[test]
fn colmap_and_nerf_exports_read_back_as_their_tools_read_them() {
    let dir = scratch("truth-export");
    let jobs = dir.join("jobs.toml");
    let scene = manifest_dir().join("sketches/jacksboro.toml");
    std::fs::write(
        &jobs,
        format!(
            "scene = {:?}\n[random]\ncount = 3\nseed = 5\n[[job]]\nname = \"north\"\n\
             camera = {{ position = [15000.0, 2000.0, 1120.0], look_at = [15000.0, 20000.0, 400.0] }}\n",
            scene.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.join("out");
    for export in ["colmap", "nerf"] {
        let (code, _, err) = terrain(&[
            "batch",
            jobs.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
            "--size",
            "48x32",
            "--outputs",
            "positions",
            "--export",
            export,
            "--resume",
        ]);
        assert_eq!(code, 0, "{err}");
    }
    let manifest: Vec<Value> = std::fs::read_to_string(out.join("manifest.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(manifest.len(), 4);

    // COLMAP's text model: cameras by id, images with their quaternion, translation, camera.
    let cameras: std::collections::HashMap<u32, Vec<f64>> =
        std::fs::read_to_string(out.join("cameras.txt"))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                assert_eq!(f[1], "PINHOLE");
                (
                    f[0].parse().unwrap(),
                    f[2..].iter().map(|v| v.parse().unwrap()).collect(),
                )
            })
            .collect();
    let images_text = std::fs::read_to_string(out.join("images.txt")).unwrap();
    let data: Vec<&str> = images_text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .collect();
    assert_eq!(data.len(), 8, "two lines an image");
    assert!(out.join("points3D.txt").is_file());
    let mut worst = 0.0f64;
    for pair in data.chunks(2) {
        let f: Vec<&str> = pair[0].split_whitespace().collect();
        let n: Vec<f64> = f[1..8].iter().map(|v| v.parse().unwrap()).collect();
        let q = DQuat::from_xyzw(n[1], n[2], n[3], n[0]);
        let t = DVec3::new(n[4], n[5], n[6]);
        let cam = &cameras[&f[8].parse::<u32>().unwrap()];
        let (w, fx, fy, cx, cy) = (cam[0] as usize, cam[2], cam[3], cam[4], cam[5]);
        assert!(pair[1].trim().is_empty(), "no 2D points");
        let name = f[9];
        let (_, positions) = npy(&out.join(name.replace(".png", ".positions.npy")));
        let r = DMat3::from_quat(q);
        for i in (0..positions.len() / 4).filter(|&i| positions[4 * i + 3] > 0.5) {
            let p = DVec3::new(positions[4 * i], positions[4 * i + 1], positions[4 * i + 2]);
            let c = r * p + t;
            // COLMAP puts the top-left pixel's centre at (0.5, 0.5).
            let (u, v) = (fx * c.x / c.z + cx, fy * c.y / c.z + cy);
            let (col, row) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            worst = worst.max((u - col).hypot(v - row));
        }
    }
    assert!(
        worst < 0.01,
        "COLMAP's cameras put points {worst} px off their pixels"
    );

    // NeRF: camera-to-world in OpenGL's axes (y up, z backward).
    let transforms: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("transforms.json")).unwrap())
            .unwrap();
    let frames = transforms["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4);
    let gl = DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0));
    for (frame, line) in frames.iter().zip(&manifest) {
        assert_eq!(frame["file_path"], line["output"]);
        let c2w = matrix(&line["extrinsics"]["camera_to_world"]);
        let m = matrix(&frame["transform_matrix"]);
        assert!(m.abs_diff_eq(c2w * gl, 1e-9), "{m} vs {c2w}");
        // The camera looks down its −z: toward the ground the image shows.
        let eye = m.w_axis.truncate();
        let ahead = eye - m.z_axis.truncate() * 100.0;
        let fwd = matrix(&line["extrinsics"]["world_to_camera"]) * ahead.extend(1.0);
        assert!(fwd.z > 99.0);
        assert!((frame["cx"].as_f64().unwrap() - 24.0).abs() < 1e-12);
    }
}

#[test]
fn surface_classes_are_indexed_with_their_legend_and_follow_the_water_and_the_sky() {
    let dir = scratch("truth-surface");
    let image = dir.join("flooded.png");
    let (code, out, err) = terrain(&[
        "render",
        manifest_dir()
            .join("sketches/jacksboro.toml")
            .to_str()
            .unwrap(),
        "-o",
        image.to_str().unwrap(),
        "--size",
        "96x64",
        "--set",
        "sketch.water_level_m=420",
        "--outputs",
        "surface,positions",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let json: Value = serde_json::from_str(&out).unwrap();
    let png_path = dir.join("flooded.surface.png");
    assert_eq!(json["outputs"]["surface"].as_str(), png_path.to_str());
    let legend: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("flooded.surface.json")).unwrap())
            .unwrap();
    let names: Vec<&str> = legend["classes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names[..3], ["sky", "water", "meadow"]);
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png_path).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let palette = reader.info().palette.clone().expect("an indexed PNG");
    for (i, class) in legend["classes"].as_array().unwrap().iter().enumerate() {
        let rgb: Vec<u8> = serde_json::from_value(class["colour"].clone()).unwrap();
        assert_eq!(palette[3 * i..3 * i + 3], rgb[..], "palette entry {i}");
    }
    let mut classes = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut classes).unwrap();
    let (_, positions) = npy(&dir.join("flooded.positions.npy"));
    let (mut agree, mut ground, mut seen) = (0, 0, std::collections::BTreeSet::new());
    for (i, &c) in classes.iter().enumerate() {
        let sky = positions[4 * i + 3] < 0.5;
        assert_eq!(c == 0, sky, "pixel {i}: class {c}, sky {sky}");
        assert!((c as usize) < names.len());
        if sky {
            continue;
        }
        ground += 1;
        seen.insert(names[c as usize]);
        let under = positions[4 * i + 2] <= 420.0 + 0.05;
        agree += usize::from((c == 1) == under);
    }
    assert!(seen.contains("water") && seen.len() >= 3, "{seen:?}");
    assert!(
        agree * 100 >= ground * 99,
        "water class matches the water's height at {agree} of {ground}"
    );
}
