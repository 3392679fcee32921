//! Timing the settings side by side: every kept setting draws one timed frame a round, the
//! rounds run `repeat` times, and each row's times are the medians over its rounds.
//!
//! Rules:
//! - A setting's renderer is kept for the rounds while the renderers kept so far hold at most
//!   [`KEEP_BYTES`] of GPU memory (`Renderer::gpu_bytes`; GeoMipMap's settings of one block size
//!   share one). A setting that does not fit is timed alone, its `repeat` frames one after
//!   another as it is measured, and `report.json`'s `timed_alone` names it.
//! - Odd rounds visit the settings in reverse, so that no setting always follows the same one.
//! - Each frame is drawn as by a fresh renderer (`Renderer::forget`), as when timed alone.
//!
//! Why: timed alone, one setting after another, a row's frames fall within a second or two,
//! and this VM's speed drifts over a run by more than the differences `compare` is asked to
//! tell apart. Measured (`render sketches/jacksboro.toml --size 256 --repeat 10 --json`, the
//! median `gpu_ms` plus the CPU stage of 10 frames, four settings alternately, 8 times): warped
//! at mesh 48 fixed 15.34 ms, GeoMipMap at τ 8 with blocks of 65 15.89 ms, blocks of 33
//! 15.97 ms; single invocations of the same settings ranged over 16.2–20.1 ms. Timed alone in
//! `compare` (stop 44, three runs of the six bundled views), rows that this put 3 % apart came
//! out either way. Rejected alternative: one renderer per mode, its setting changed between
//! frames: a warped renderer's mesh is fixed when it is built (`warp.mesh` sizes its buffers),
//! so that would time meshes in buffers sized for another.

use super::measure::Timed;
use super::sweep::Setting;
use crate::camera::Camera;
use crate::lod::baseline::Baselines;
use crate::render::Renderer;

/// The most GPU memory the renderers kept for the rounds may hold together: at 256² the
/// warped and GeoMipMap rows of every bundled view fit (0.37–0.73 GiB; jacksboro's three
/// GeoMipMap grids take about 170 MB each, its 31 warped renderers 261 MB together).
pub const KEEP_BYTES: u64 = 1 << 30;

/// The renderers kept for the rounds and the rows each times.
pub(super) struct Rounds {
    kept: Vec<(Setting, Renderer)>,
    bytes: u64,
    cap: u64,
    /// Each row timed in rounds: its index, its kept renderer, its setting and the triangles
    /// its measured frame drew.
    rows: Vec<(usize, usize, Setting, u64)>,
}

impl Rounds {
    pub fn new(cap: u64) -> Rounds {
        Rounds {
            kept: Vec::new(),
            bytes: 0,
            cap,
            rows: Vec::new(),
        }
    }

    /// The kept renderer that can draw `s`: GeoMipMap's of the same block size.
    pub fn find(&self, s: &Setting) -> Option<usize> {
        let Setting::GeoMipMap { block, .. } = *s else {
            return None;
        };
        self.kept
            .iter()
            .position(|(k, _)| matches!(*k, Setting::GeoMipMap { block: b, .. } if b == block))
    }

    /// Whether `r` may be kept beside the renderers kept so far.
    pub fn fits(&self, r: &Renderer) -> bool {
        self.bytes.saturating_add(r.gpu_bytes()) <= self.cap
    }

    /// Keeps `r`, built for `s` (that it [`Rounds::fits`] is the caller's choice); its index.
    pub fn keep(&mut self, s: Setting, r: Renderer) -> usize {
        self.bytes += r.gpu_bytes();
        self.kept.push((s, r));
        self.kept.len() - 1
    }

    /// Lets go of the renderer last kept (its setting failed before any row was timed).
    pub fn release_last(&mut self) {
        if let Some((_, r)) = self.kept.pop() {
            self.bytes -= r.gpu_bytes();
        }
    }

    pub fn renderer(&mut self, i: usize) -> &mut Renderer {
        &mut self.kept[i].1
    }

    /// Row `row` is timed in the rounds with kept renderer `renderer`, set to `s`; its measured
    /// frame drew `triangles`.
    pub fn time_row(&mut self, row: usize, renderer: usize, s: Setting, triangles: u64) {
        self.rows.push((row, renderer, s, triangles));
    }

    /// Runs `repeat` rounds at `camera` and returns each timed row's frames, by row index. A
    /// setting whose frame fails, or draws other triangles than its measured frame (a renderer
    /// left at another setting), drops out of the later rounds and keeps the frames it had.
    pub fn run(
        &mut self,
        camera: &Camera,
        repeat: u32,
        mut progress: impl FnMut(u32),
    ) -> Vec<(usize, Timed)> {
        let mut timed: Vec<Timed> = self.rows.iter().map(|_| Timed::default()).collect();
        let mut failed = vec![false; self.rows.len()];
        for round in 0..repeat {
            for k in order(self.rows.len(), round) {
                if failed[k] {
                    continue;
                }
                let (_, i, s, triangles) = self.rows[k];
                let r = &mut self.kept[i].1;
                set_tau(r, &s);
                r.forget();
                match r.render(camera) {
                    Ok(frame) if frame.gpu.triangles == triangles => timed[k].push(&frame),
                    _ => failed[k] = true,
                }
            }
            progress(round);
        }
        self.rows
            .iter()
            .zip(timed)
            .filter(|(_, t)| !t.is_empty())
            .map(|(&(row, ..), t)| (row, t))
            .collect()
    }
}

/// Sets a GeoMipMap renderer's τ to `s`'s (its settings of one block size share a renderer).
pub(super) fn set_tau(r: &mut Renderer, s: &Setting) {
    if let Setting::GeoMipMap { tau, .. } = *s
        && let Some(b) = r.lod_mut::<Baselines>()
    {
        b.params.tau = tau;
    }
}

/// The rows' order in round `round`: as kept, reversed in odd rounds.
fn order(rows: usize, round: u32) -> Vec<usize> {
    let mut v: Vec<usize> = (0..rows).collect();
    if round % 2 == 1 {
        v.reverse();
    }
    v
}

#[cfg(test)]
mod tests {
    use super::order;

    /// Over two rounds every row sits, on average, mid-round: a drift over the run falls on each
    /// row alike (a sequence of rows timed one after another would give the last the most).
    #[test]
    fn rounds_visit_rows_in_balanced_order() {
        let rows = 7;
        let mut at = vec![0usize; rows];
        for round in 0..4 {
            let o = order(rows, round);
            assert_eq!(o.len(), rows);
            for (place, &k) in o.iter().enumerate() {
                at[k] += place;
            }
        }
        assert!(at.iter().all(|&a| a == at[0]), "{at:?}");
    }
}
