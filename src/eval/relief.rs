//! The relief measure: how well a picture shows the land's form, as Pearson's r between each
//! ground pixel's Rec. 709 luma and Horn's hillshade of the sketch under the same sun at the
//! pixel's world position (docs/picture.md, "How the relief reads").
//!
//! Rules:
//! - The hillshade is the one GIS tools draw (gdaldem `hillshade`, Horn's 3×3 gradient): the
//!   cosine between the sun and the sketch's normal at each level-0 node, 0 where the node faces
//!   away; edge nodes repeat their neighbours, as gdaldem's `-compute_edges` does.
//! - It is sampled bilinearly at each pixel's world position; pixels off the sketch (sky, the
//!   plain or the sea beyond it) and on the water's surface do not count: the hillshade says
//!   nothing of them.
//! - Luma is Rec. 709's weighting of the encoded (display) values, as a reader's eye takes them.
//!
//! Rejected: the hillshade at the rendered surface's own normal, which would reward a picture
//! for its procedural detail; the sketch is what the user gave and what a map reader knows.

use glam::{DVec2, DVec3};
use terrain_engine::sketch::{Atlas, Level};

/// Ground within this of the water's surface is the water's (the shaders' `ON_WATER_M`).
const WATER_EPS_M: f64 = 0.01;

/// Horn's hillshade of the atlas's level 0 under the unit vector `sun` (x east, y north, z up),
/// in 0…1, on level 0's grid; `None` for a streamed sketch, whose level 0 is not in memory.
pub fn hillshade(atlas: &Atlas, sun: DVec3) -> Option<Level> {
    let level = &atlas.levels[0];
    let (w, h) = (level.width, level.height);
    if level.data.len() != w * h || w < 2 || h < 2 {
        return None;
    }
    let z = |i: isize, j: isize| -> f64 {
        let i = i.clamp(0, w as isize - 1) as usize;
        let j = j.clamp(0, h as isize - 1) as usize;
        level.data[j * w + i] as f64
    };
    let mut data = Vec::with_capacity(w * h);
    for j in 0..h as isize {
        for i in 0..w as isize {
            // Horn: the east–west difference weighted 1-2-1 over the three rows, alike north–south.
            let dzdx = ((z(i + 1, j + 1) + 2.0 * z(i + 1, j) + z(i + 1, j - 1))
                - (z(i - 1, j + 1) + 2.0 * z(i - 1, j) + z(i - 1, j - 1)))
                / (8.0 * atlas.dx);
            let dzdy = ((z(i - 1, j + 1) + 2.0 * z(i, j + 1) + z(i + 1, j + 1))
                - (z(i - 1, j - 1) + 2.0 * z(i, j - 1) + z(i + 1, j - 1)))
                / (8.0 * atlas.dy);
            let n = DVec3::new(-dzdx, -dzdy, 1.0).normalize();
            data.push(n.dot(sun).max(0.0) as f32);
        }
    }
    Some(Level {
        width: w,
        height: h,
        data,
    })
}

/// Pearson's r between the luma of each pixel of `rgba` whose world position in `world`
/// (x, y, z, ground flag per pixel, as `render --positions` writes) lies on the sketch's land and
/// the hillshade `shade` (from [`hillshade`]) there; `None` with fewer than two such pixels or no
/// variation in either.
pub fn relief_r(rgba: &[u8], world: &[f64], atlas: &Atlas, shade: &Level) -> Option<f64> {
    let (w, h) = (shade.width, shade.height);
    let mut pairs = Vec::new();
    for (p, q) in rgba.chunks_exact(4).zip(world.chunks_exact(4)) {
        // Sky, and the water's flat surface, of which the hillshade says nothing.
        if q[3] < 0.5 || q[2] <= atlas.water_m as f64 + WATER_EPS_M {
            continue;
        }
        let uv = (DVec2::new(q[0], q[1]) - atlas.origin) / DVec2::new(atlas.dx, atlas.dy);
        if !(uv.x >= 0.0 && uv.y >= 0.0 && uv.x <= (w - 1) as f64 && uv.y <= (h - 1) as f64) {
            continue;
        }
        let luma = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
        pairs.push((luma, shade.bilinear(uv.x, uv.y) as f64));
    }
    pearson(&pairs)
}

/// Pearson's correlation of the pairs, `None` where it is undefined.
pub fn pearson(pairs: &[(f64, f64)]) -> Option<f64> {
    if pairs.len() < 2 {
        return None;
    }
    let n = pairs.len() as f64;
    let (mx, my) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in pairs {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pearson_of_a_line_and_its_mirror() {
        let up: Vec<(f64, f64)> = (0..10).map(|i| (i as f64, 3.0 * i as f64 + 1.0)).collect();
        assert!((pearson(&up).unwrap() - 1.0).abs() < 1e-12);
        let down: Vec<(f64, f64)> = (0..10).map(|i| (i as f64, -(i as f64))).collect();
        assert!((pearson(&down).unwrap() + 1.0).abs() < 1e-12);
        assert_eq!(pearson(&[(1.0, 2.0), (1.0, 3.0)]), None);
    }
}
