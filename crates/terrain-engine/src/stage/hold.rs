//! Holding the warp: a frame keeps the last Φ (and its sketch map) while the demand it was made
//! for still describes the view, instead of warping anew.
//!
//! Why: the warped mesh follows the camera, so every vertex slides over the terrain each frame,
//! and the geometric octaves near the mesh's sampling limit, sampled at new places, change the
//! picture. That change hardly grows with how far the mesh moved, so holding the warp while it
//! still fits turns continuous swimming into rare updates, and the held frames skip the warp
//! (docs/decisions.md, “Held warp”).
//!
//! Rules:
//! - The sketch map's region is held too (`SketchMap::update` keeps its corner while it still
//!   encloses the footprint at the same spacing and turn); a frame whose region moved or turned
//!   (`stage::sketch_map::Turn`) warps anew.
//! - Otherwise the frame computes its importance over the held region on every [`ROW_STEP`]-th
//!   row and compares it with the importance the held Φ was made for, over the texels in view
//!   (`S_f ≥ 0.5` now). Where the demand changed by more than `warp.hold_drift` octaves on
//!   texels that ask for more than [`SHARE`] of the cells in view (each texel weighted by I², its
//!   cells) — the camera came closer, turned, or new ground came into view — it warps anew.
//!   Counted by texels, the few near the camera, which ask for most of the cells, would drift
//!   unseen.
//! - A snapshot must not depend on the frames before it: [`Hold::forget`] (through
//!   `Renderer::forget`) drops the held warp, as `batch` does before each job.
//!
//! Not built, by argument rather than measurement: blending Φ toward each new warp (exponential
//! smoothing). In steady flight the blended mesh moves as fast as the camera, only later, so it
//! would slide as much per frame.

use crate::stage::importance::ImportanceMap;

/// The share of the cells in view whose demand may drift past the tolerance before the warp is redone.
pub const SHARE: f32 = 0.05;

/// The drift check computes the importance on every fourth row: a fraction of the whole map's
/// time, and the demand varies smoothly from row to row.
pub const ROW_STEP: usize = 4;

/// The importance the held Φ was made for is the stage's importance map itself, which only a
/// frame that warps anew updates (`CpuStage::run`), so it is not copied (64 KiB at 128²).
#[derive(Clone, Debug)]
pub struct Hold {
    /// Largest drift of the demand, in octaves (log2 of the ratio), that a texel may show.
    pub drift: f32,
    /// Whether a Φ is held.
    holding: bool,
    /// Frames that kept the held warp since the last one warped anew.
    pub held_frames: u32,
}

impl Hold {
    pub fn new(drift: f64) -> Hold {
        Hold {
            drift: drift as f32,
            holding: false,
            held_frames: 0,
        }
    }

    /// Whether the held Φ, made for `made_for`, still serves `now`, the importance of this frame
    /// over the held region computed on every [`ROW_STEP`]-th row
    /// ([`ImportanceMap::update_rows`]).
    pub fn serves(&self, now: &ImportanceMap, made_for: &ImportanceMap) -> bool {
        if !self.holding || made_for.importance.len() != now.importance.len() {
            return false;
        }
        let n = now.n;
        let limit = self.drift.exp2();
        // Weighted by the cells each texel asks for now (I², up to the common d0²).
        let (mut wanted, mut drifted) = (0f64, 0f64);
        for j in (0..n).step_by(ROW_STEP) {
            let row = j * n..(j + 1) * n;
            let (i_now, i_made) = (
                &now.importance[row.clone()],
                &made_for.importance[row.clone()],
            );
            let (mut w, mut d) = (0f32, 0f32);
            for ((&a, &b), &f) in i_now.iter().zip(i_made).zip(&now.frustum[row]) {
                let cells = if f >= 0.5 { a * a } else { 0.0 };
                // a, b > 0 (the floor): the ratio test needs no log.
                let off = a > b * limit || b > a * limit;
                w += cells;
                d += if off { cells } else { 0.0 };
            }
            (wanted, drifted) = (wanted + w as f64, drifted + d as f64);
        }
        drifted <= SHARE as f64 * wanted
    }

    /// Whether a warp is held (one was made since the last [`Hold::forget`]).
    pub fn is_holding(&self) -> bool {
        self.holding
    }

    /// A new Φ was made, for the stage's importance map as it is now.
    pub fn made(&mut self) {
        self.holding = true;
        self.held_frames = 0;
    }

    pub fn forget(&mut self) {
        self.holding = false;
        self.held_frames = 0;
    }
}
