//! The quality settings `compare` sweeps, one per report row.
//!
//! Default sweep: warped over mesh 64², 96², 128², 192², 256², 384², 512², 1024² at `quad_px` 2
//! (from GeoMipMap's triangle counts up: 4k to 2M triangles), and `quad_px` 1 and 4 at mesh 512²; GeoMipMap over τ 0.5, 1, 2, 4, 8 px at blocks of 17, 33 and 65 vertices; brute force
//! over grid spacings d_atlas/2^K for K = 0 up to the finest the device and the vertex budget
//! allow ([`default_k`]).
//!
//! Rejected alternative: the full product of `quad_px` and mesh size. `quad_px` scales the view
//! importance everywhere alike, and the warp normalises importance to the mesh it has, so it
//! changes Φ only where the surface bound `I_s` or the floor clip the importance; three of its
//! values at one mesh size show that at a third of the cost.

use crate::lod::baseline::default_k;
use crate::scene::{Mode, Scene};
use crate::sketch::Atlas;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    Warped { quad_px: f64, mesh: u32 },
    GeoMipMap { tau: f64, block: u32 },
    BruteForce { k: u32 },
}

impl Setting {
    pub fn mode(&self) -> Mode {
        match self {
            Setting::Warped { .. } => Mode::Warped,
            Setting::GeoMipMap { .. } => Mode::Geomipmap,
            Setting::BruteForce { .. } => Mode::Bruteforce,
        }
    }

    /// The mode's name in reports: `warped`, `geomipmap`, `bruteforce`.
    pub fn mode_name(&self) -> &'static str {
        self.mode().name()
    }

    pub fn label(&self) -> String {
        match *self {
            Setting::Warped { quad_px, mesh } => format!("quad_px={quad_px} mesh={mesh}"),
            Setting::GeoMipMap { tau, block } => format!("tau={tau} block={block}"),
            Setting::BruteForce { k } => format!("K={k}"),
        }
    }

    /// The scene with this setting's keys set.
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        match *self {
            Setting::Warped { quad_px, mesh } => {
                s.warp.quad_px = quad_px;
                s.warp.mesh = mesh;
            }
            Setting::GeoMipMap { tau, block } => {
                s.geomipmap.tau = tau;
                s.geomipmap.block = block;
            }
            Setting::BruteForce { k } => s.geomipmap.k = Some(k),
        }
        s
    }

    /// The setting a mode runs with from the scene as given (the path's and the strip's).
    pub fn of_scene(mode: Mode, scene: &Scene, atlas: &Atlas) -> Option<Setting> {
        Some(match mode {
            Mode::Warped => Setting::Warped {
                quad_px: scene.warp.quad_px,
                mesh: scene.warp.mesh,
            },
            Mode::Geomipmap => Setting::GeoMipMap {
                tau: scene.geomipmap.tau,
                block: scene.geomipmap.block,
            },
            Mode::Bruteforce => Setting::BruteForce {
                k: scene.geomipmap.k.unwrap_or_else(|| default_k(atlas)),
            },
            Mode::Reference | Mode::Clipmaps => return None,
        })
    }
}

/// The default sweep of `modes` over `atlas`.
pub fn default_sweep(modes: &[Mode], atlas: &Atlas) -> Vec<Setting> {
    let mut out = Vec::new();
    for &mode in modes {
        match mode {
            Mode::Warped => {
                for mesh in [64, 96, 128, 192, 256, 384, 512, 1024] {
                    out.push(Setting::Warped { quad_px: 2.0, mesh });
                }
                for quad_px in [1.0, 4.0] {
                    out.push(Setting::Warped { quad_px, mesh: 512 });
                }
            }
            Mode::Geomipmap => {
                for block in [17, 33, 65] {
                    for tau in [0.5, 1.0, 2.0, 4.0, 8.0] {
                        out.push(Setting::GeoMipMap { tau, block });
                    }
                }
            }
            Mode::Bruteforce => {
                for k in 0..=default_k(atlas) {
                    out.push(Setting::BruteForce { k });
                }
            }
            Mode::Reference | Mode::Clipmaps => {}
        }
    }
    out
}
