//! The CPU stage's figures, all top-down over the sketch map's region, north up (a turned region,
//! `stage::sketch_map`, with its t axis up: north-east or north-west):
//! `importance.png` (log importance), `mesh.png` (the warped grid over the shaded sketch, like the
//! paper's Fig. 3 top row) and `ratio.png` (obtained/demanded density per cell, like Fig. 6).
//!
//! Ratio colours: < 1/4 blue, [1/4, 1/2) cyan, [1/2, 1) green, [1, 2] yellow-green, (2, 4] orange,
//! > 4 red; cells out of view grey.

use crate::output::{Staged, add_image};
use glam::DVec2;
use std::path::Path;
use terrain_engine::Result;
use terrain_engine::sketch::Atlas;
use terrain_engine::stage::CpuStage;
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Stroke, Transform};

const SIZE: u32 = 768;

/// Writes the three figures into `dir`, together: all or none.
pub fn write_all(dir: &Path, atlas: &Atlas, stage: &CpuStage, ratios: &[f32]) -> Result<()> {
    let mut out = Staged::default();
    write_importance(&mut out, &dir.join("importance.png"), stage)?;
    let shade = shaded_relief(atlas, stage);
    let mut mesh = shade.clone();
    draw_mesh(&mut mesh, stage);
    save(&mut out, &dir.join("mesh.png"), &mesh)?;
    let mut ratio = shade;
    draw_ratio(&mut ratio, stage, ratios);
    save(&mut out, &dir.join("ratio.png"), &ratio)?;
    out.commit()
}

fn save(out: &mut Staged, path: &Path, p: &Pixmap) -> Result<()> {
    add_image(out, path, p.width(), p.height(), p.data())
}

/// World metres to pixels over the region.
fn to_px(stage: &CpuStage, w: DVec2) -> (f32, f32) {
    let m = &stage.sketch_map;
    let rel = m.local(w) / m.extent();
    (
        (rel.x * SIZE as f64) as f32,
        ((1.0 - rel.y) * SIZE as f64) as f32,
    )
}

fn write_importance(out: &mut Staged, path: &Path, stage: &CpuStage) -> Result<()> {
    let imp = &stage.importance;
    let n = imp.n;
    let logs: Vec<f32> = imp
        .importance
        .iter()
        .map(|v| v.max(f32::MIN_POSITIVE).log10())
        .collect();
    let lo = logs.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = logs.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let scale = (SIZE as usize / n).max(1);
    let side = n * scale;
    let mut rgba = vec![255u8; side * side * 4];
    for py in 0..side {
        for px in 0..side {
            let (i, j) = (px / scale, n - 1 - py / scale);
            let t = if hi > lo {
                (logs[j * n + i] - lo) / (hi - lo)
            } else {
                0.5
            };
            let c = ramp(t, &VIRIDIS);
            rgba[(py * side + px) * 4..][..3].copy_from_slice(&c);
        }
    }
    add_image(out, path, side as u32, side as u32, &rgba)
}

/// Height-tinted hillshade of the atlas over the region (light from the north-west).
fn shaded_relief(atlas: &Atlas, stage: &CpuStage) -> Pixmap {
    let m = &stage.sketch_map;
    let px_m = m.extent() / SIZE as f64;
    let lod = (px_m / atlas.d_atlas()).log2();
    let height = |w: DVec2| {
        let u = (w.x - atlas.origin.x) / atlas.dx;
        let v = (w.y - atlas.origin.y) / atlas.dy;
        atlas.sample_texel(u, v, lod) as f64
    };
    let range = (atlas.max_m - atlas.min_m).max(1.0) as f64;
    let mut pix = Pixmap::new(SIZE, SIZE).expect("non-zero figure size");
    let data = pix.data_mut();
    for py in 0..SIZE {
        for px in 0..SIZE {
            let w = m.world(DVec2::new(px as f64 + 0.5, (SIZE - py) as f64 - 0.5) * px_m);
            // The slope along the figure's axes, as the light comes from its top left.
            let (s, t) = m.turn.axes();
            let gx = (height(w + s * px_m) - height(w - s * px_m)) / (2.0 * px_m);
            let gy = (height(w + t * px_m) - height(w - t * px_m)) / (2.0 * px_m);
            let normal = glam::DVec3::new(-gx, -gy, 1.0).normalize();
            let light = glam::DVec3::new(-1.0, 1.0, 1.4).normalize();
            let shade = (0.35 + 0.65 * normal.dot(light).max(0.0)) as f32;
            let t = ((height(w) - atlas.min_m as f64) / range) as f32;
            let c = ramp(t, &TERRAIN);
            let k = ((py * SIZE + px) * 4) as usize;
            for ch in 0..3 {
                data[k + ch] = (c[ch] as f32 * shade) as u8;
            }
            data[k + 3] = 255;
        }
    }
    pix
}

fn draw_mesh(pix: &mut Pixmap, stage: &CpuStage) {
    let n = stage.sketch_map.n;
    let mut pb = PathBuilder::new();
    for t in 0..n {
        for s in 0..n {
            let (x, y) = to_px(stage, stage.phi_world(s, t));
            if s == 0 {
                pb.move_to(x, y)
            } else {
                pb.line_to(x, y)
            }
        }
    }
    for s in 0..n {
        for t in 0..n {
            let (x, y) = to_px(stage, stage.phi_world(s, t));
            if t == 0 {
                pb.move_to(x, y)
            } else {
                pb.line_to(x, y)
            }
        }
    }
    if let Some(path) = pb.finish() {
        let paint = solid(Color::from_rgba8(20, 20, 30, 170));
        let stroke = Stroke {
            width: 0.6,
            ..Stroke::default()
        };
        pix.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    draw_view(pix, stage);
}

fn draw_ratio(pix: &mut Pixmap, stage: &CpuStage, ratios: &[f32]) {
    let n = stage.sketch_map.n;
    for t in 0..n - 1 {
        for s in 0..n - 1 {
            let r = ratios[t * (n - 1) + s];
            let corners = [(s, t), (s + 1, t), (s + 1, t + 1), (s, t + 1)];
            let mut pb = PathBuilder::new();
            for (k, &(a, b)) in corners.iter().enumerate() {
                let (x, y) = to_px(stage, stage.phi_world(a, b));
                if k == 0 {
                    pb.move_to(x, y)
                } else {
                    pb.line_to(x, y)
                }
            }
            pb.close();
            let Some(path) = pb.finish() else { continue };
            let c = ratio_colour(r);
            let mut paint = solid(Color::from_rgba8(
                c[0],
                c[1],
                c[2],
                if r.is_nan() { 140 } else { 220 },
            ));
            paint.anti_alias = false;
            pix.fill_path(
                &path,
                &paint,
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }
    draw_view(pix, stage);
}

/// The footprint's box and the camera's ground position.
fn draw_view(pix: &mut Pixmap, stage: &CpuStage) {
    let red = solid(Color::from_rgba8(220, 30, 30, 255));
    if let Some((lo, hi)) = stage.sketch_map.footprint {
        // The box lies along the region's axes, in its turn's frame.
        let turn = stage.sketch_map.turn;
        let (x0, y0) = to_px(stage, turn.world(lo));
        let (x1, y1) = to_px(stage, turn.world(hi));
        if let Some(rect) = tiny_skia::Rect::from_ltrb(x0, y1, x1.max(x0 + 1.0), y0.max(y1 + 1.0)) {
            let path = PathBuilder::from_rect(rect);
            let stroke = Stroke {
                width: 2.0,
                ..Stroke::default()
            };
            pix.stroke_path(&path, &red, &stroke, Transform::identity(), None);
        }
    }
    let eye = stage.last_eye;
    let (x, y) = to_px(stage, eye);
    if let Some(path) = PathBuilder::from_circle(x, y, 5.0) {
        pix.fill_path(&path, &red, FillRule::Winding, Transform::identity(), None);
    }
}

fn solid(c: Color) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(c);
    p.anti_alias = true;
    p
}

fn ratio_colour(r: f32) -> [u8; 3] {
    match r {
        r if r.is_nan() => [150, 150, 150],
        r if r < 0.25 => [30, 60, 220],
        r if r < 0.5 => [40, 200, 220],
        r if r < 1.0 => [40, 190, 60],
        r if r <= 2.0 => [190, 220, 40],
        r if r <= 4.0 => [240, 140, 30],
        _ => [220, 30, 30],
    }
}

const VIRIDIS: [[u8; 3]; 5] = [
    [68, 1, 84],
    [59, 82, 139],
    [33, 145, 140],
    [94, 201, 98],
    [253, 231, 37],
];
const TERRAIN: [[u8; 3]; 5] = [
    [70, 120, 60],
    [120, 160, 80],
    [180, 170, 110],
    [150, 120, 90],
    [240, 240, 240],
];

/// Piecewise-linear colour ramp over evenly spaced stops, t in [0, 1].
fn ramp(t: f32, stops: &[[u8; 3]]) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (stops.len() - 1) as f32;
    let i = (x as usize).min(stops.len() - 2);
    let f = x - i as f32;
    let mut c = [0u8; 3];
    for ch in 0..3 {
        c[ch] = (stops[i][ch] as f32 + (stops[i + 1][ch] as f32 - stops[i][ch] as f32) * f) as u8;
    }
    c
}
