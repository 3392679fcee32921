//! Timing the settings side by side: every kept setting draws one timed frame a round, the
//! rounds run `repeat` times, and each row's times are the medians over its rounds.
//!
//! Rules:
//! - A setting's renderer is kept for the rounds while the renderers kept so far hold at most
//!   [`KEEP_BYTES`] of GPU memory (`Renderer::gpu_bytes`; GeoMipMap's settings of one block size
//!   share one renderer, and its block sizes and brute force of one K one baked grid, counted
//!   in the renderer that baked it). A setting that does not fit is timed alone, its `repeat` frames one after
//!   another as it is measured, and `report.json`'s `timed_alone` names it.
//! - A round that is not timed comes first: each row's renderer settles at the camera again.
//! - Odd rounds visit the settings in reverse: each setting's mean place in a round is the same.
//! - Each frame chooses its level of detail as a fresh renderer would (`Renderer::forget`), as
//!   when timed alone, and must draw the triangles of the frame the row was measured by.
//!
//! Why: timed alone, one setting after another, a row's frames fall within a second or two,
//! and this VM's speed drifts over a run by more than the differences `compare` is asked to
//! tell apart. Fifteen rounds are the default. The rounds remove a run's drift, not the spread of
//! single frames on this VM (docs/decisions.md, “Timing in rounds”).
//!
//! Rejected alternative: one renderer per mode, its setting changed between frames: a warped
//! renderer's buffers are sized for its `warp.mesh`, so that would time small meshes in buffers
//! sized for another.

use super::measure::Timed;
use super::report::Row;
use super::sweep::Setting;
use terrain_engine::Camera;
use terrain_engine::Renderer;
use terrain_engine::Result;

/// The most GPU memory the renderers kept for the rounds may hold together: at 256² every row
/// of the bundled view fits (0.55 GB: jacksboro's GeoMipMap grid 105 MB, counted in its first
/// block size and lent to the others and to brute force, its 30 warped renderers 279 MB
/// together). Beside them live the reference renderer and one renderer at a time that did not
/// fit.
pub const KEEP_BYTES: u64 = 1 << 30;

/// The renderers kept for the rounds, the rows each times, and the last renderer that did not
/// fit.
pub(super) struct Rounds {
    kept: Vec<(Setting, Renderer)>,
    bytes: u64,
    cap: u64,
    rows: Vec<Entry>,
    /// A renderer timed alone, kept only while the next setting may draw with it: GeoMipMap's,
    /// for its block size's next τ.
    spare: Option<(Setting, Renderer)>,
}

/// A row timed in the rounds.
#[derive(Clone)]
struct Entry {
    /// Its index among the rows measured.
    row: usize,
    /// Its kept renderer.
    renderer: usize,
    setting: Setting,
    /// The triangles its measured frame drew.
    triangles: u64,
}

/// A row's frames from the rounds, and why the rounds stopped timing it, if they did.
pub(super) struct RowTimes {
    pub row: usize,
    pub setting: Setting,
    pub timed: Timed,
    pub failure: Option<String>,
}

impl Rounds {
    pub fn new(cap: u64) -> Rounds {
        Rounds {
            kept: Vec::new(),
            bytes: 0,
            cap,
            rows: Vec::new(),
            spare: None,
        }
    }

    /// Measures setting `s`, whose row will be `row` if it succeeds, by `measure` (a renderer
    /// and the frames to time): with the kept renderer that draws it, else with the spare or one
    /// `build` makes. A renderer that fits is kept and its row timed in the rounds (`measure`
    /// times one frame); else the row's `repeat` frames are timed there, one after another.
    pub fn measure(
        &mut self,
        s: &Setting,
        row: usize,
        repeat: u32,
        build: impl FnOnce() -> Result<Renderer>,
        mut measure: impl FnMut(&mut Renderer, u32) -> Result<(Row, Vec<u8>)>,
    ) -> Result<(Row, Vec<u8>)> {
        if let Some(i) = self.kept.iter().position(|(k, _)| k.shares_renderer(s)) {
            let measured = measure(&mut self.kept[i].1, 1);
            self.time_row(&measured, row, i, s);
            return measured;
        }
        let mut r = match self.spare.take() {
            Some((k, r)) if k.shares_renderer(s) => r,
            // Dropped before the next is built: one large grid at a time.
            other => {
                drop(other);
                build()?
            }
        };
        if self.bytes.saturating_add(r.gpu_bytes()) > self.cap {
            let measured = measure(&mut r, repeat);
            self.spare = (!s.mode.row().retuned.is_empty()).then(|| (s.clone(), r));
            return measured;
        }
        self.bytes += r.gpu_bytes();
        self.kept.push((s.clone(), r));
        let i = self.kept.len() - 1;
        let measured = measure(&mut self.kept[i].1, 1);
        if measured.is_err()
            && let Some((_, r)) = self.kept.pop()
        {
            self.bytes -= r.gpu_bytes();
        }
        self.time_row(&measured, row, i, s);
        measured
    }

    fn time_row(&mut self, measured: &Result<(Row, Vec<u8>)>, row: usize, i: usize, s: &Setting) {
        if let Ok((r, _)) = measured {
            self.rows.push(Entry {
                row,
                renderer: i,
                setting: s.clone(),
                triangles: r.triangles,
            });
        }
    }

    /// Lets go of the renderer timed alone.
    pub fn drop_spare(&mut self) {
        self.spare = None;
    }

    /// Runs `repeat` rounds at `camera`, after one that is not timed, and returns each timed
    /// row's frames. The untimed round settles each renderer at `camera` again (a streamed
    /// sketch holds the tiles of the camera path its LOD change was measured along). A row whose
    /// frame fails, or draws other triangles than its measured frame, drops out of the later
    /// rounds and keeps the frames it had, with the cause.
    pub fn run(
        &mut self,
        camera: &Camera,
        repeat: u32,
        mut progress: impl FnMut(u32),
    ) -> Vec<RowTimes> {
        let mut times: Vec<RowTimes> = self
            .rows
            .iter()
            .map(|e| RowTimes {
                row: e.row,
                setting: e.setting.clone(),
                timed: Timed::default(),
                failure: None,
            })
            .collect();
        for (e, t) in self.rows.iter().zip(&mut times) {
            let r = &mut self.kept[e.renderer].1;
            e.setting.retune(r);
            r.forget();
            if let Err(err) = r.render_settled(camera) {
                t.failure = Some(format!("settling before the timing rounds: {err}"));
            }
        }
        for round in 0..repeat {
            for k in order(self.rows.len(), round) {
                if times[k].failure.is_some() {
                    continue;
                }
                let e = &self.rows[k];
                let r = &mut self.kept[e.renderer].1;
                e.setting.retune(r);
                r.forget();
                match r.render(camera) {
                    Ok(frame) if frame.gpu.triangles == e.triangles => times[k].timed.push(&frame),
                    Ok(frame) => {
                        times[k].failure = Some(format!(
                            "timing round {}: drew {} triangles, its measured frame {}",
                            round + 1,
                            frame.gpu.triangles,
                            e.triangles
                        ))
                    }
                    Err(err) => {
                        times[k].failure = Some(format!("timing round {}: {err}", round + 1))
                    }
                }
            }
            progress(round);
        }
        times
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
