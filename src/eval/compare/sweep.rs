//! The quality settings `compare` sweeps, one per report row.
//!
//! Default sweep: warped over mesh 64², 96², 128², 192², 256², 384², 512², 1024² at `quad_px` 2
//! (from GeoMipMap's triangle counts up: 4k to 2M triangles), and `quad_px` 1 and 4 at mesh 512²; GeoMipMap over τ 0.5, 1, 2, 4, 8 px at blocks of 17, 33 and 65 vertices; brute force
//! over grid spacings d_atlas/2^K for K = 0 up to the finest the device and the vertex budget
//! allow ([`default_k`]); on a planet, clipmaps over φ steps 128, 256, 512, 1024 at 20 rings per
//! level, rings per level 10 and 40 at 512 φ steps (the paper's n and m, 8× and 4× triangles end
//! to end), and the paper's triangles split the other ways: 256 × 40 and 128 × 80.
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
    Warped {
        quad_px: f64,
        mesh: u32,
    },
    GeoMipMap {
        tau: f64,
        block: u32,
    },
    BruteForce {
        k: u32,
    },
    Clipmaps {
        phi_steps: u32,
        rings_per_level: u32,
    },
}

impl Setting {
    pub fn mode(&self) -> Mode {
        match self {
            Setting::Warped { .. } => Mode::Warped,
            Setting::GeoMipMap { .. } => Mode::Geomipmap,
            Setting::BruteForce { .. } => Mode::Bruteforce,
            Setting::Clipmaps { .. } => Mode::Clipmaps,
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
            Setting::Clipmaps {
                phi_steps,
                rings_per_level,
            } => format!("phi_steps={phi_steps} rings={rings_per_level}"),
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
            Setting::Clipmaps {
                phi_steps,
                rings_per_level,
            } => {
                let mut p = s.planet().unwrap_or_default();
                (p.phi_steps, p.rings_per_level) = (phi_steps, rings_per_level);
                s.planet = Some(p);
            }
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
            Mode::Clipmaps => {
                let p = scene.planet()?;
                Setting::Clipmaps {
                    phi_steps: p.phi_steps,
                    rings_per_level: p.rings_per_level,
                }
            }
            Mode::Reference => return None,
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
            Mode::Clipmaps => {
                for phi_steps in [128, 256, 512, 1024] {
                    out.push(Setting::Clipmaps {
                        phi_steps,
                        rings_per_level: 20,
                    });
                }
                for rings_per_level in [10, 40] {
                    out.push(Setting::Clipmaps {
                        phi_steps: 512,
                        rings_per_level,
                    });
                }
                for (phi_steps, rings_per_level) in [(256, 40), (128, 80)] {
                    out.push(Setting::Clipmaps {
                        phi_steps,
                        rings_per_level,
                    });
                }
            }
            Mode::Reference => {}
        }
    }
    out
}
