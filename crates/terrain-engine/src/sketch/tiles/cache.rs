//! The tile cache: which tiles of a pyramid are resident in a fixed pool of GPU pages, what the
//! page table says of them, and the loader threads that read them off the render thread.
//! [`crate::gpu::stream`] owns the GPU buffers and moves the bytes; this is the policy, testable
//! without a GPU.
//!
//! Rules:
//! - The page table has one entry per tile of every level, level 0 first. An entry is two exact
//!   f32s: `page·256 + fade` (fade 255: arrived) and the level of the tile in that page. A tile
//!   not resident is filled down with its finest resident ancestor's page and level (the ancestor
//!   of tile t on level r is t >> (r − l), clamped to level r's tiles, as the shader computes it),
//!   so a lookup is one read, never a walk. The pool holds [`Budget::pages`] pages, each one tile
//!   with its border; they never move or grow.
//! - The coarsest levels are pinned: from the top level down, every level whose tiles still fit in
//!   a quarter of the pool, loaded before the first frame. So every sample has a resident level to
//!   fall back to, and a frame never waits for a tile.
//! - What to load is what the frame asked for: the shaders mark every entry they look up (1:
//!   missing, 2: used; see `shaders/shared/atlas.wgsl`). After the frame the missing entries
//!   become the loader's queue, coarsest level first (a coarse tile improves the stand-in for the
//!   most ground), replacing the last frame's queue so a camera that moved on does not wait behind
//!   tiles it no longer sees.
//! - At most [`Budget::loads_per_frame`] arrived tiles are placed per frame, and the loader
//!   holds no more than that many read and not yet placed (memory stays bounded, and what
//!   arrives is what recent frames asked for). A tile takes a free page, else the least recently
//!   used page that the last frame did not use; when every page was used by the last frame, the
//!   tile is dropped and asked for again later (the stand-in stays: a budget too small for the
//!   view shows coarser ground, never a hole).
//! - A placed tile's fade rises from 0 to 255 over [`Budget::fade_frames`] frames; the shader
//!   blends it over the next coarser resident level meanwhile.
//! - A snapshot (`render`, `batch`, `compare`'s views) settles instead ([`TileCache::settle`]):
//!   each frame waits for the tiles the last one missed and places them at once, so a few frames
//!   converge on the image of the sketch held whole; a flight never waits.
//!
//! Rejected alternatives: requests computed on the CPU from the view (the sketch map's Φ, the
//! blocks' boxes): each consumer would need its own estimate, and the shading's reads (pixel
//! normals, the sun's shadow ray, the surface types' footprints) none would see; the marks are
//! exact for every mode and cost one store per sample. A hash-map page table on the GPU: the
//! table for a 32,768² pyramid is 21,852 entries, 175 KB, cheaper to index than to probe.

use super::Pyramid;
use crate::error::{Error, Result};
use serde::Serialize;
use std::collections::HashSet;
use std::sync::{Arc, Condvar, Mutex, mpsc};
use std::thread::JoinHandle;
use std::time::Duration;

/// How long a settling frame waits for a missed tile: a tile is read in milliseconds, so this
/// only ends a wait on a loader that has nothing left to send.
pub const SETTLE_WAIT: Duration = Duration::from_secs(10);

/// The shaders' marks in the feedback buffer.
pub const MARK_MISSING: u32 = 1;
pub const MARK_USED: u32 = 2;

/// The cache's budgets (the `[stream]` scene keys).
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    /// Tiles resident at once.
    pub pages: usize,
    /// Arrived tiles placed per frame at most.
    pub loads_per_frame: usize,
    /// Frames a placed tile takes to blend in over its stand-in (0: at once).
    pub fade_frames: u32,
    /// Threads reading and decoding tiles.
    pub threads: usize,
}

/// Where each level's tiles sit in the page table.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Level l's first entry.
    pub first: Vec<usize>,
    /// Level l's tiles east and north.
    pub tiles: Vec<(usize, usize)>,
    /// Entries in all.
    pub len: usize,
}

impl Layout {
    pub fn new(pyramid: &Pyramid) -> Layout {
        let mut first = Vec::new();
        let mut tiles = Vec::new();
        let mut len = 0;
        for l in 0..pyramid.meta.levels.len() {
            let t = pyramid.meta.tiles(l);
            first.push(len);
            tiles.push(t);
            len += t.0 * t.1;
        }
        Layout { first, tiles, len }
    }

    /// Level and tile of entry `e`.
    pub fn tile_of(&self, e: usize) -> (usize, usize, usize) {
        let l = self.first.partition_point(|&f| f <= e) - 1;
        let k = e - self.first[l];
        (l, k % self.tiles[l].0, k / self.tiles[l].0)
    }
}

/// A tile to copy into a page.
pub struct Upload {
    pub page: u32,
    pub heights: Vec<f32>,
}

/// What a frame did with the cache.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct StreamStats {
    /// Tiles placed in pages before this frame was drawn.
    pub loaded: usize,
    /// Tiles the frame asked for that were not resident.
    pub missing: usize,
    /// Whether any sample read a stand-in level: a missing tile, or one still blending in.
    pub stand_in: bool,
    /// Pages holding a tile after the frame.
    pub resident: usize,
    /// Tiles that arrived but found no page the last frame had not used.
    pub dropped: usize,
}

struct Page {
    entry: usize,
    last_used: u64,
    pinned: bool,
    placed: u64,
}

pub struct TileCache {
    pub layout: Layout,
    budget: Budget,
    /// The page table as the shaders read it: two floats per entry, filled down.
    table: Vec<f32>,
    /// The table needs filling again: a tile was placed or evicted, or a fade moved.
    dirty: bool,
    page_of: Vec<Option<u32>>,
    /// Each resident entry's fade, 0..=255.
    fade: Vec<u8>,
    pages: Vec<Option<Page>>,
    free: Vec<u32>,
    /// Entries still blending in.
    fading: Vec<usize>,
    frame: u64,
    pending_uploads: Vec<Upload>,
    loader: Loader,
    last: StreamStats,
    /// Frames wait for the tiles the last one missed and place them without a fade.
    settling: bool,
}

impl TileCache {
    /// Opens the cache over `pyramid`, reading its pinned levels now.
    pub fn new(pyramid: Pyramid, budget: Budget) -> Result<TileCache> {
        let layout = Layout::new(&pyramid);
        let levels = layout.first.len();
        let mut pinned_tiles = 0;
        let mut pinned_from = levels;
        for l in (0..levels).rev() {
            let n = layout.tiles[l].0 * layout.tiles[l].1;
            if l + 1 < levels && pinned_tiles + n > budget.pages / 4 {
                break;
            }
            pinned_tiles += n;
            pinned_from = l;
        }
        if pinned_tiles > budget.pages {
            return Err(Error::value(
                "stream.gpu_mb",
                format!(
                    "{} pages hold less than the pyramid's top level ({pinned_tiles} tiles)",
                    budget.pages
                ),
            ));
        }
        let mut cache = TileCache {
            table: vec![0.0; 2 * layout.len],
            dirty: true,
            page_of: vec![None; layout.len],
            fade: vec![0; layout.len],
            pages: (0..budget.pages).map(|_| None).collect(),
            free: (0..budget.pages as u32).rev().collect(),
            fading: Vec::new(),
            frame: 0,
            pending_uploads: Vec::new(),
            loader: Loader::start(Arc::new(pyramid.clone()), layout.clone(), &budget),
            last: StreamStats::default(),
            settling: false,
            layout,
            budget,
        };
        for l in pinned_from..levels {
            let (tx, ty) = cache.layout.tiles[l];
            for y in 0..ty {
                for x in 0..tx {
                    let e = cache.layout.first[l] + y * tx + x;
                    let heights = pyramid.tile(l, x, y)?;
                    let page = cache.free.pop().expect("pinned tiles fit the pool");
                    cache.place(e, page, true);
                    cache.pending_uploads.push(Upload { page, heights });
                }
            }
        }
        Ok(cache)
    }

    /// The page table as the shaders read it: two floats per entry.
    pub fn table(&self) -> &[f32] {
        &self.table
    }

    pub fn budget(&self) -> Budget {
        self.budget
    }

    /// Snapshots: with `on`, a frame waits (up to [`SETTLE_WAIT`]) for the first of the tiles
    /// the last frame missed, and tiles are placed without a fade (those fading finish), so each
    /// frame is as fine as the tiles read so far allow.
    pub fn settle(&mut self, on: bool) {
        self.settling = on;
    }

    /// Before a frame: advances the fades and places arrived tiles; returns the tiles to copy into
    /// their pages, and whether the page table changed (it needs copying too). A tile that failed
    /// to read fails the frame, naming it.
    pub fn begin_frame(&mut self) -> Result<(Vec<Upload>, bool)> {
        self.frame += 1;
        let mut uploads = std::mem::take(&mut self.pending_uploads);
        self.advance_fades();
        let wait = self.settling && self.last.missing > 0;
        let (mut loaded, mut dropped) = (0, 0);
        while loaded < self.budget.loads_per_frame {
            let next = if wait && loaded + dropped == 0 {
                self.loader.take_within(SETTLE_WAIT)
            } else {
                self.loader.try_take()
            };
            let Some((e, heights)) = next else {
                break;
            };
            let heights = match heights {
                Ok(h) => h,
                Err(e) => {
                    // The pages placed so far keep their heights for the next frame's copy.
                    self.pending_uploads = uploads;
                    return Err(e);
                }
            };
            if self.page_of[e].is_some() {
                continue;
            }
            let Some(page) = self.free.pop().or_else(|| self.evict()) else {
                dropped += 1;
                continue;
            };
            self.place(e, page, false);
            uploads.push(Upload { page, heights });
            loaded += 1;
        }
        self.last = StreamStats {
            loaded,
            dropped,
            ..StreamStats::default()
        };
        let changed = self.dirty;
        if changed {
            self.fill();
        }
        Ok((uploads, changed))
    }

    /// After a frame: `marks` holds the shaders' mark per entry. Keeps what was used, queues what
    /// was missing, and returns the frame's figures.
    pub fn end_frame(&mut self, marks: &[u32]) -> StreamStats {
        let mut missing = Vec::new();
        let mut stand_in = false;
        for (e, &m) in marks.iter().enumerate().take(self.layout.len) {
            match (m, self.page_of[e]) {
                (MARK_USED, Some(p)) => {
                    let page = self.pages[p as usize]
                        .as_mut()
                        .expect("a mapped page is held");
                    page.last_used = self.frame;
                    stand_in |= self.fade[e] < 255;
                }
                (MARK_MISSING, None) => missing.push(e),
                _ => {}
            }
        }
        stand_in |= !missing.is_empty();
        // Entries are numbered level 0 first, so the loader, taking from the end, reads the
        // coarsest first.
        self.loader.want(&missing);
        self.last.missing = missing.len();
        self.last.stand_in = stand_in;
        self.last.resident = self.pages.iter().filter(|p| p.is_some()).count();
        self.last
    }

    fn place(&mut self, e: usize, page: u32, pinned: bool) {
        let fade = if pinned || self.settling || self.budget.fade_frames == 0 {
            255
        } else {
            self.fading.push(e);
            0
        };
        self.pages[page as usize] = Some(Page {
            entry: e,
            last_used: self.frame,
            pinned,
            placed: self.frame,
        });
        self.page_of[e] = Some(page);
        self.fade[e] = fade;
        self.dirty = true;
    }

    /// Writes every entry: its own page, or its finest resident ancestor's.
    fn fill(&mut self) {
        let levels = self.layout.first.len();
        for l in 0..levels {
            let (tx, ty) = self.layout.tiles[l];
            for y in 0..ty {
                for x in 0..tx {
                    let e = self.layout.first[l] + y * tx + x;
                    let (page, fade, r) = (l..levels)
                        .find_map(|r| {
                            let (rx, ry) = self.layout.tiles[r];
                            let k = r - l;
                            let a = self.layout.first[r]
                                + (y >> k).min(ry - 1) * rx
                                + (x >> k).min(rx - 1);
                            self.page_of[a].map(|p| (p, self.fade[a], r))
                        })
                        .expect("the top level is pinned");
                    self.table[2 * e] = (page * 256 + fade as u32) as f32;
                    self.table[2 * e + 1] = r as f32;
                }
            }
        }
        self.dirty = false;
    }

    /// The least recently used page the last frame did not use, emptied.
    fn evict(&mut self) -> Option<u32> {
        let (k, _) = self
            .pages
            .iter()
            .enumerate()
            .filter_map(|(k, p)| p.as_ref().map(|p| (k, p)))
            .filter(|(_, p)| !p.pinned && p.last_used + 1 < self.frame)
            .min_by_key(|(_, p)| p.last_used)?;
        let page = self.pages[k].take().expect("found held");
        self.page_of[page.entry] = None;
        self.dirty = true;
        self.fading.retain(|&e| e != page.entry);
        Some(k as u32)
    }

    fn advance_fades(&mut self) {
        let frames = match self.settling {
            true => 1,
            false => self.budget.fade_frames.max(1) as u64,
        };
        let frame = self.frame;
        let (pages, fades, page_of) = (&self.pages, &mut self.fade, &self.page_of);
        self.dirty |= !self.fading.is_empty();
        self.fading.retain(|&e| {
            let p = page_of[e].expect("a fading entry is resident");
            let placed = pages[p as usize].as_ref().expect("held").placed;
            let fade = ((frame - placed) * 255 / frames).min(255) as u8;
            fades[e] = fade;
            fade < 255
        });
    }
}

type Loaded = (usize, Result<Vec<f32>>);

struct Queue {
    /// Entries to load, the next one last.
    wanted: Vec<usize>,
    /// Entries being read or read and not yet taken by the render thread.
    in_flight: HashSet<usize>,
    /// The most entries in flight: decoded tiles wait in memory until placed, so the loader
    /// reads no more than a frame places (`loads_per_frame`), and arrivals stay current.
    most: usize,
    stop: bool,
}

/// Threads that read and decode tiles the render thread asks for.
struct Loader {
    queue: Arc<(Mutex<Queue>, Condvar)>,
    arrived: mpsc::Receiver<Loaded>,
    threads: Vec<JoinHandle<()>>,
}

impl Loader {
    fn start(pyramid: Arc<Pyramid>, layout: Layout, budget: &Budget) -> Loader {
        let queue = Arc::new((
            Mutex::new(Queue {
                wanted: Vec::new(),
                in_flight: HashSet::new(),
                most: budget.loads_per_frame.max(1),
                stop: false,
            }),
            Condvar::new(),
        ));
        let (send, arrived) = mpsc::channel();
        let threads = (0..budget.threads.max(1))
            .map(|_| {
                let (queue, send, pyramid, layout) =
                    (queue.clone(), send.clone(), pyramid.clone(), layout.clone());
                std::thread::spawn(move || load_loop(&queue, &send, &pyramid, &layout))
            })
            .collect();
        Loader {
            queue,
            arrived,
            threads,
        }
    }

    /// Replaces the queue with `wanted` (the next one last), less what is being read.
    fn want(&self, wanted: &[usize]) {
        let (lock, wake) = &*self.queue;
        let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
        let q = &mut *q;
        q.wanted.clear();
        q.wanted
            .extend(wanted.iter().filter(|e| !q.in_flight.contains(e)));
        wake.notify_all();
    }

    fn try_take(&self) -> Option<Loaded> {
        self.received(self.arrived.try_recv().ok()?)
    }

    /// The next tile to arrive within `wait`, if any.
    fn take_within(&self, wait: Duration) -> Option<Loaded> {
        self.received(self.arrived.recv_timeout(wait).ok()?)
    }

    fn received(&self, loaded: Loaded) -> Option<Loaded> {
        let (lock, wake) = &*self.queue;
        lock.lock()
            .unwrap_or_else(|e| e.into_inner())
            .in_flight
            .remove(&loaded.0);
        // A slot freed: a loader waiting on the bound may read the next.
        wake.notify_one();
        Some(loaded)
    }
}

fn load_loop(
    queue: &(Mutex<Queue>, Condvar),
    send: &mpsc::Sender<Loaded>,
    pyramid: &Pyramid,
    layout: &Layout,
) {
    let (lock, wake) = queue;
    loop {
        let e = {
            let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                if q.stop {
                    return;
                }
                if q.in_flight.len() < q.most
                    && let Some(e) = q.wanted.pop()
                {
                    q.in_flight.insert(e);
                    break e;
                }
                q = wake.wait(q).unwrap_or_else(|e| e.into_inner());
            }
        };
        let (l, tx, ty) = layout.tile_of(e);
        if send.send((e, pyramid.tile(l, tx, ty))).is_err() {
            return;
        }
    }
}

impl Drop for Loader {
    fn drop(&mut self) {
        {
            let (lock, wake) = &*self.queue;
            lock.lock().unwrap_or_else(|e| e.into_inner()).stop = true;
            wake.notify_all();
        }
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    /// A 600² pyramid (levels of 3×3, 2×2, then single tiles) in a fresh folder.
    fn pyramid(name: &str) -> Pyramid {
        let dir = std::env::temp_dir().join(format!("terrain-cache-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let n = 600;
        let mut asc = format!("ncols {n}\nnrows {n}\nxllcorner 0\nyllcorner 0\ncellsize 10\n");
        for j in 0..n {
            let row: Vec<String> = (0..n)
                .map(|i| format!("{}", (i * 7 + j * 3) % 50))
                .collect();
            asc.push_str(&row.join(" "));
            asc.push('\n');
        }
        let src = dir.join("sketch.asc");
        std::fs::write(&src, asc).unwrap();
        let out = dir.join("pyr");
        let opts = crate::sketch::convert::BuildOptions {
            load: Default::default(),
            threads: 1,
            ..Default::default()
        };
        crate::sketch::convert::build(&src, &out, &opts).unwrap();
        Pyramid::open(&out).unwrap()
    }

    fn budget(pages: usize) -> Budget {
        Budget {
            pages,
            loads_per_frame: 8,
            fade_frames: 4,
            threads: 1,
        }
    }

    /// Frames until `done` holds (the loader runs on its own thread), with `marks` each frame.
    fn frames_until(
        cache: &mut TileCache,
        marks: &[u32],
        done: impl Fn(&TileCache) -> bool,
    ) -> usize {
        let start = Instant::now();
        let mut frames = 0;
        while !done(cache) {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "the loader never delivered"
            );
            cache.begin_frame().unwrap();
            cache.end_frame(marks);
            frames += 1;
            std::thread::sleep(Duration::from_millis(5));
        }
        frames
    }

    fn level_of(cache: &TileCache, e: usize) -> f32 {
        cache.table()[2 * e + 1]
    }

    #[test]
    fn a_missing_tile_stands_in_with_its_ancestor_then_loads_and_fades_in() {
        let p = pyramid("load");
        let mut cache = TileCache::new(p, budget(8)).unwrap();
        let layout = cache.layout.clone();
        assert_eq!(layout.tiles[0], (3, 3));
        // Pinned: the top levels while they fit a quarter of the pool (8 / 4 = 2 tiles).
        let top = layout.first.len() - 1;
        cache.begin_frame().unwrap();
        let e = layout.first[0] + 4; // level 0, tile (1, 1)
        assert_eq!(level_of(&cache, e), (top - 1) as f32);
        let mut marks = vec![0; layout.len];
        marks[e] = MARK_MISSING;
        let stats = cache.end_frame(&marks);
        assert!(stats.stand_in && stats.missing == 1, "{stats:?}");
        frames_until(&mut cache, &marks, |c| level_of(c, e) == 0.0);
        let fade = |c: &TileCache| c.table()[2 * e] as u32 & 255;
        assert!(fade(&cache) < 255, "a placed tile blends in");
        marks[e] = MARK_USED;
        let frames = frames_until(&mut cache, &marks, |c| fade(c) == 255);
        assert!(frames <= 4, "faded in over {frames} frames, fade_frames 4");
        cache.begin_frame().unwrap();
        assert!(!cache.end_frame(&marks).stand_in);
        // Every other level-0 entry still stands in with the pinned level.
        assert_eq!(level_of(&cache, layout.first[0]), (top - 1) as f32);
    }

    #[test]
    fn the_loader_holds_no_more_tiles_read_and_unplaced_than_a_frame_places() {
        let p = pyramid("bound");
        let mut cache = TileCache::new(
            p,
            Budget {
                loads_per_frame: 2,
                threads: 3,
                ..budget(16)
            },
        )
        .unwrap();
        let layout = cache.layout.clone();
        cache.begin_frame().unwrap();
        // All nine level-0 tiles are missing at once.
        let mut marks = vec![0; layout.len];
        for k in 0..9 {
            marks[layout.first[0] + k] = MARK_MISSING;
        }
        assert_eq!(cache.end_frame(&marks).missing, 9);
        let held = |c: &TileCache| {
            let q = c.loader.queue.0.lock().unwrap();
            (q.in_flight.len(), q.wanted.len())
        };
        // Three threads, and time to read all nine: two are read, the rest wait their turn.
        std::thread::sleep(Duration::from_millis(300));
        assert_eq!(held(&cache), (2, 7));
        let stats = {
            cache.begin_frame().unwrap();
            cache.end_frame(&marks)
        };
        assert_eq!(stats.loaded, 2);
        assert!(held(&cache).0 <= 2, "{:?}", held(&cache));
    }

    #[test]
    fn eviction_takes_the_least_recently_used_page_and_never_one_the_last_frame_used() {
        let p = pyramid("evict");
        // One pinned page (the top level) and three free.
        let mut cache = TileCache::new(p, budget(4)).unwrap();
        let first = cache.layout.first[0];
        let len = cache.layout.len;
        let resident = |c: &TileCache, e: usize| c.page_of[e].is_some();
        let mut marks = vec![0; len];
        for k in 0..3 {
            marks[first + k] = MARK_MISSING;
        }
        frames_until(&mut cache, &marks, |c| {
            (0..3).all(|k| resident(c, first + k))
        });
        // All three in use, a fourth asked for: it finds no page and is dropped, not forced in.
        let mut marks = vec![0; len];
        for k in 0..3 {
            marks[first + k] = MARK_USED;
        }
        marks[first + 3] = MARK_MISSING;
        let start = Instant::now();
        let mut dropped = 0;
        while dropped == 0 && start.elapsed() < Duration::from_secs(10) {
            dropped += cache.begin_frame().map(|_| cache.last.dropped).unwrap();
            cache.end_frame(&marks);
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(dropped > 0);
        assert!((0..3).all(|k| resident(&cache, first + k)));
        // Tile 0 falls out of use first, then tile 1: the fourth takes tile 0's page.
        marks[first] = 0;
        cache.begin_frame().unwrap();
        cache.end_frame(&marks);
        marks[first + 1] = 0;
        frames_until(&mut cache, &marks, |c| resident(c, first + 3));
        assert!(!resident(&cache, first));
        assert!(resident(&cache, first + 1) && resident(&cache, first + 2));
    }

    #[test]
    fn a_pool_smaller_than_the_top_level_is_refused() {
        let p = pyramid("small");
        let e = TileCache::new(p, budget(0)).err().expect("refused");
        assert!(e.to_string().contains("stream.gpu_mb"), "{e}");
    }
}
