//! The mip pyramid: a level's grid, its CPU sampling (bilinear per level) and how each level is
//! built from the one below.
//!
//! Rule: level l is a 2×2 box average of level l−1, sizes halved rounding down as texture mips
//! are, so the CPU and the GPU hold the same pyramid; every bilinear read of heights on the CPU
//! goes through [`bilinear_cell`] and [`bilinear_blend`].

/// One level of the pyramid: a row-major grid of finite heights.
#[derive(Clone, Debug)]
pub struct Level {
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Heights in metres, row-major, row 0 south; empty for a streamed level not held in memory.
    pub data: Vec<f32>,
}

impl Level {
    /// The mean height of the edge nodes.
    pub(super) fn edge_mean(&self) -> f32 {
        let (sum, n) = self
            .edge()
            .fold((0.0, 0usize), |(s, n), z| (s + z as f64, n + 1));
        (sum / n.max(1) as f64) as f32
    }

    /// The heights of the edge nodes, each once (none without data).
    pub(super) fn edge(&self) -> impl Iterator<Item = f32> + '_ {
        let (w, h) = (self.width, self.height);
        let held = self.data.len() == w * h && w > 0 && h > 0;
        let at = move |i: usize, j: usize| self.data[j * w + i];
        let rows = (0..w).filter(move |_| held).flat_map(move |i| {
            let top = (h > 1).then(|| at(i, h - 1));
            std::iter::once(at(i, 0)).chain(top)
        });
        let cols = (1..h.saturating_sub(1))
            .filter(move |_| held)
            .flat_map(move |j| {
                let east = (w > 1).then(|| at(w - 1, j));
                std::iter::once(at(0, j)).chain(east)
            });
        rows.chain(cols)
    }

    /// [`Atlas::level_curvature`] of this level, of spacing `dx` × `dy`: NaN without data or
    /// without an interior texel.
    pub(super) fn mean_curvature(&self, dx: f64, dy: f64, water_m: f32) -> f64 {
        let (w, h) = (self.width, self.height);
        if self.data.len() != w * h || w < 3 || h < 3 {
            return f64::NAN;
        }
        let at = |i: usize, j: usize| f64::from(self.data[j * w + i].max(water_m));
        let stride = (w.max(h) / 256).max(1);
        let (mut sum, mut count) = (0.0, 0usize);
        for j in (1..h - 1).step_by(stride) {
            for i in (1..w - 1).step_by(stride) {
                let c = at(i, j);
                let hxx = (at(i + 1, j) - 2.0 * c + at(i - 1, j)) / (dx * dx);
                let hyy = (at(i, j + 1) - 2.0 * c + at(i, j - 1)) / (dy * dy);
                let hxy = (at(i + 1, j + 1) - at(i - 1, j + 1) - at(i + 1, j - 1)
                    + at(i - 1, j - 1))
                    / (4.0 * dx * dy);
                sum += hxx.abs().max(hyy.abs()).max(hxy.abs());
                count += 1;
            }
        }
        sum / count as f64
    }

    /// Bilinear sample at level-0 texel coordinates (u, v), this being level `l`.
    pub(super) fn bilinear_at_level(&self, u: f64, v: f64, l: usize) -> f32 {
        let s = (1u64 << l) as f64;
        let off = (s - 1.0) * 0.5;
        self.bilinear((u - off) / s, (v - off) / s)
    }

    /// Bilinear sample at this level's texel coordinates, clamped to the edge.
    pub fn bilinear(&self, u: f64, v: f64) -> f32 {
        let ((i, j), f) = bilinear_cell(u, v, self.width, self.height);
        let w = self.width;
        let r0 = &self.data[j * w + i..j * w + i + 2];
        let r1 = &self.data[(j + 1) * w + i..(j + 1) * w + i + 2];
        bilinear_blend([[r0[0], r0[1]], [r1[0], r1[1]]], f)
    }
}

/// The cell of a `width` × `height` grid (at least 2 × 2) a bilinear sample at (u, v) reads,
/// clamped to the edge: its south-west node and the fractions across it. With
/// [`bilinear_blend`], the one rule of every bilinear read of heights on the CPU, in memory or
/// from a pyramid's tiles (`tiles::Pyramid::bilinear`), so they agree bit for bit.
pub fn bilinear_cell(u: f64, v: f64, width: usize, height: usize) -> ((usize, usize), [f32; 2]) {
    let u = u.clamp(0.0, (width - 1) as f64);
    let v = v.clamp(0.0, (height - 1) as f64);
    let i = (u.floor() as usize).min(width - 2);
    let j = (v.floor() as usize).min(height - 2);
    ((i, j), [(u - i as f64) as f32, (v - j as f64) as f32])
}

/// A cell's corners `z[row][column]` (row 0 south) blended at fractions `f`.
pub fn bilinear_blend(z: [[f32; 2]; 2], f: [f32; 2]) -> f32 {
    let a = z[0][0] + (z[0][1] - z[0][0]) * f[0];
    let b = z[1][0] + (z[1][1] - z[1][0]) * f[0];
    a + (b - a) * f[1]
}

/// Halves (rounding down, as texture mip levels do, so the GPU holds the same pyramid) while the
/// next level keeps 2 texels on its shorter side; an odd level's last row or column is dropped.
pub(crate) fn build_pyramid(base: Level) -> Vec<Level> {
    let mut levels = vec![base];
    loop {
        let prev = levels.last().expect("pyramid has a base");
        let (w, h) = (prev.width / 2, prev.height / 2);
        if w.min(h) < 2 {
            break;
        }
        let mut data = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let at = |x: usize, y: usize| prev.data[y * prev.width + x];
                let (x, y) = (2 * i, 2 * j);
                data.push(0.25 * (at(x, y) + at(x + 1, y) + at(x, y + 1) + at(x + 1, y + 1)));
            }
        }
        levels.push(Level {
            width: w,
            height: h,
            data,
        });
    }
    levels
}
