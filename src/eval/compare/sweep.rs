//! The quality settings `compare` sweeps, one per report row.
//!
//! Default sweep:
//! - warped over the budgets where GeoMipMap competes: meshes of fixed size (`warp.budget`
//!   off) on the budget's ladder (`stage::budget`: rungs about 2^(1/4) apart from 16², so
//!   triangles about half an octave apart) up to 8 triangles a pixel, and the scene's own
//!   setting, the mesh its view asks for (the rung it draws is not repeated as a fixed row).
//! - then, where GeoMipMap ran too, warped at GeoMipMap's budgets: for each GeoMipMap row, the
//!   largest fixed mesh with no more triangles than it drew ([`at_geomipmap_budgets`]), unless a
//!   warped row drew as many already. The acceptance asks, row by row, whether warped has less
//!   error at no more triangles; on the ladder alone a warped curve below GeoMipMap's misses rows
//!   that fall just above a rung, so the answer would depend on the ladder's spacing
//!   (docs/decisions.md, “Warped sweep”). A ladder twice as fine would double the warped rows
//!   and still land beside GeoMipMap's counts, not on them.
//! - GeoMipMap over τ 0.5, 1, 2, 4, 8 px at blocks of 17, 33 and 65 vertices;
//! - brute force over grid spacings d_atlas/2^K for K = 0 up to the finest the device and the
//!   vertex budget allow ([`Baselines::default_k`]);
//! - on a planet, clipmaps over φ steps 128, 256, 512, 1024 at 20 rings per level, rings per
//!   level 10 and 40 at 512 φ steps (the paper's n and m, 8× and 4× triangles end to end), and the
//!   paper's triangles split the other ways: 256 × 40 and 128 × 80.
//!
//! Rejected alternatives:
//! - A fixed list of mesh bounds (64² … 1024² at `quad_px` 2, and `quad_px` 1 and 4 at 512²):
//!   every bound above the view's own demand draws the same mesh, and its steps are too coarse
//!   to tell whether warped beats GeoMipMap between them (docs/decisions.md, “Warped sweep”).
//! - Bounds up to the view's own mesh, then `quad_px` ÷√2, ÷2, ÷2√2 above it: with the
//!   geometric-error term lowering `quad_px` raises only the part of the importance the error
//!   term does not set, so the rows jump by octaves of triangles (docs/decisions.md, “Warped
//!   sweep”).
//! - The full product of `quad_px` and mesh size. `quad_px` scales the view importance
//!   everywhere alike, and the warp normalises importance to the mesh it has, so at a fixed mesh
//!   it changes Φ only where the surface bound `I_s` or the floor clip the importance.

use super::report::Row;
use terrain_engine::Baselines;
use terrain_engine::Camera;
use terrain_engine::Result;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::Atlas;
use terrain_engine::stage::Budget;
use terrain_engine::stage::CpuStage;

/// The largest mesh the sweep draws: 2M triangles.
const MAX_MESH: u32 = 1024;
/// The most triangles a pixel the sweep draws: GeoMipMap's τ = 0.5 reaches 6.4 on the bundled
/// views at 256².
const MAX_TRIANGLES_PER_PX: f64 = 8.0;
/// The smallest: 450 triangles, below GeoMipMap's fewest on the bundled views from high up (512
/// and 874 at 256²), where the budget's own smallest (`warp.min_mesh`, 32) would start at 1,922.
const MIN_MESH: u32 = 16;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// `budget`: the mesh the view asks for, up to `mesh` (`warp.budget`); else `mesh` itself.
    Warped {
        quad_px: f64,
        mesh: u32,
        budget: bool,
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

    /// The row's label: each of the mode's swept keys as its row in the mode table names it
    /// (`tau=0.5 block=17`); a warped mesh of fixed size is marked `fixed`.
    pub fn label(&self) -> String {
        let keys = self.mode().row().sweep;
        let values = self.values();
        let words: Vec<String> = keys
            .iter()
            .zip(values)
            .filter_map(|(&(key, name), v)| match key {
                "warp.budget" => (v == 0.0).then(|| name.to_string()),
                _ => Some(format!("{name}={v}")),
            })
            .collect();
        words.join(" ")
    }

    /// The values of the mode's swept keys, in its row's order (a flag as 0 or 1).
    fn values(&self) -> Vec<f64> {
        match *self {
            Setting::Warped {
                quad_px,
                mesh,
                budget,
            } => vec![quad_px, mesh as f64, budget as u8 as f64],
            Setting::GeoMipMap { tau, block } => vec![tau, block as f64],
            Setting::BruteForce { k } => vec![k as f64],
            Setting::Clipmaps {
                phi_steps,
                rings_per_level,
            } => vec![phi_steps as f64, rings_per_level as f64],
        }
    }

    /// Sets a GeoMipMap renderer's τ to this setting's (its settings of one block size share a
    /// renderer).
    pub fn set_tau(&self, r: &mut terrain_engine::Renderer) {
        if let Setting::GeoMipMap { tau, .. } = *self
            && let Some(b) = r.lod_mut::<Baselines>()
        {
            b.params.tau = tau;
        }
    }

    /// The scene with this setting's keys set.
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        match *self {
            Setting::Warped {
                quad_px,
                mesh,
                budget,
            } => {
                s.warp.quad_px = quad_px;
                s.warp.mesh = mesh;
                s.warp.budget = budget;
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
                budget: scene.warp.budget,
            },
            Mode::Geomipmap => Setting::GeoMipMap {
                tau: scene.geomipmap.tau,
                block: scene.geomipmap.block,
            },
            Mode::Bruteforce => Setting::BruteForce {
                k: scene
                    .geomipmap
                    .k
                    .unwrap_or_else(|| Baselines::default_k(atlas)),
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

/// The default sweep of `modes` for `scene` seen by `camera` (the image size of the comparison):
/// the warped rows depend on the mesh this view asks for.
pub fn default_sweep(
    modes: &[Mode],
    scene: &Scene,
    atlas: &Atlas,
    camera: &Camera,
) -> Result<Vec<Setting>> {
    let mut out = Vec::new();
    for &mode in modes {
        match mode {
            Mode::Warped => out.extend(warped_sweep(scene, atlas, camera)?),
            Mode::Geomipmap => {
                for block in [17, 33, 65] {
                    for tau in [0.5, 1.0, 2.0, 4.0, 8.0] {
                        out.push(Setting::GeoMipMap { tau, block });
                    }
                }
            }
            Mode::Bruteforce => {
                for k in 0..=Baselines::default_k(atlas) {
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
    Ok(out)
}

/// The warped rows (the module doc's rule).
fn warped_sweep(scene: &Scene, atlas: &Atlas, camera: &Camera) -> Result<Vec<Setting>> {
    let w = &scene.warp;
    let own = Setting::Warped {
        quad_px: w.quad_px,
        mesh: w.mesh,
        budget: w.budget,
    };
    let drawn = if w.budget {
        view_mesh(scene, atlas, camera)?.min(w.mesh)
    } else {
        w.mesh
    };
    let pixels = camera.width as f64 * camera.height as f64;
    let fits = |m: u32| mesh_triangles(m) as f64 <= MAX_TRIANGLES_PER_PX * pixels;
    let mut out: Vec<Setting> = Budget::new(MIN_MESH, MAX_MESH)
        .rungs()
        .iter()
        .filter(|&&m| m != drawn && (m == MIN_MESH || fits(m)))
        .map(|&mesh| Setting::Warped {
            quad_px: w.quad_px,
            mesh,
            budget: false,
        })
        .collect();
    out.push(own);
    Ok(out)
}

/// The warped rows at GeoMipMap's budgets (at `quad_px`, the scene's), run after the default
/// sweep when both modes ran: for each GeoMipMap row, the largest fixed mesh (up to
/// `MAX_MESH`) with no more triangles than the row drew, unless a warped row already drew as
/// many (the module doc's rule).
pub fn at_geomipmap_budgets(quad_px: f64, rows: &[Row]) -> Vec<Setting> {
    let drawn = |t: u64| rows.iter().any(|r| r.mode == "warped" && r.triangles == t);
    let mut out: Vec<Setting> = Vec::new();
    for g in rows.iter().filter(|r| r.mode == "geomipmap") {
        let mesh = mesh_within(g.triangles);
        let setting = Setting::Warped {
            quad_px,
            mesh,
            budget: false,
        };
        if mesh >= 2 && !drawn(mesh_triangles(mesh)) && !out.contains(&setting) {
            out.push(setting);
        }
    }
    out
}

/// Triangles of a fixed mesh of `mesh`² vertices: two per cell.
fn mesh_triangles(mesh: u32) -> u64 {
    2 * (mesh as u64).saturating_sub(1).pow(2)
}

/// The largest mesh side with at most `triangles` triangles, up to [`MAX_MESH`] (1 below 2).
fn mesh_within(triangles: u64) -> u32 {
    ((triangles / 2).isqrt() + 1).min(MAX_MESH as u64) as u32
}

/// The mesh side the view asks for at the scene's `quad_px`, up to [`MAX_MESH`].
fn view_mesh(scene: &Scene, atlas: &Atlas, camera: &Camera) -> Result<u32> {
    let mut s = scene.clone();
    s.warp.mesh = MAX_MESH.max(s.warp.mesh);
    let detail = terrain_engine::scene::detail_for(&s, atlas, Mode::Warped);
    let mut stage = CpuStage::new(&s, &detail)?;
    stage.run(atlas, camera);
    Ok(stage.mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::compare::report::tests::row;

    fn with_triangles(mode: &str, triangles: u64) -> Row {
        Row {
            triangles,
            ..row(mode, 1.0, 30.0, 0.5)
        }
    }

    /// A row's label names each swept key as the mode table does, in its order.
    #[test]
    fn labels_name_the_swept_keys_from_the_mode_table() {
        let cases = [
            (
                Setting::Warped {
                    quad_px: 2.0,
                    mesh: 125,
                    budget: false,
                },
                "quad_px=2 mesh=125 fixed",
            ),
            (
                Setting::Warped {
                    quad_px: 1.5,
                    mesh: 512,
                    budget: true,
                },
                "quad_px=1.5 mesh=512",
            ),
            (
                Setting::GeoMipMap {
                    tau: 0.5,
                    block: 17,
                },
                "tau=0.5 block=17",
            ),
            (Setting::BruteForce { k: 2 }, "K=2"),
            (
                Setting::Clipmaps {
                    phi_steps: 512,
                    rings_per_level: 20,
                },
                "phi_steps=512 rings=20",
            ),
        ];
        for (s, label) in cases {
            assert_eq!(s.label(), label);
            assert_eq!(s.values().len(), s.mode().row().sweep.len());
        }
    }

    /// Each GeoMipMap row gets the largest mesh within its triangles, once, unless warped drew
    /// as many already; a row too small for any mesh gets none.
    #[test]
    fn warped_rows_at_geomipmap_budgets_fit_within_each_row() {
        let rows: Vec<Row> = [("warped", 450), ("warped", 1058)]
            .into_iter()
            .chain([12_836, 12_836, 3_300, 3_199, 451, 1].map(|t| ("geomipmap", t)))
            .map(|(m, t)| with_triangles(m, t))
            .collect();
        let meshes: Vec<u32> = at_geomipmap_budgets(2.0, &rows)
            .iter()
            .map(|s| match *s {
                Setting::Warped {
                    mesh,
                    budget: false,
                    quad_px: 2.0,
                } => mesh,
                other => panic!("not a fixed warped mesh: {other:?}"),
            })
            .collect();
        // 12,836: 81² has 12,800, 82² 13,122. 3,300: 41² has 3,200, one more than 3,199 holds.
        // 451: 16², 450, drawn already.
        assert_eq!(meshes, [81, 41, 40]);
        for (t, m) in [(12_836, 81), (3_300, 41), (3_199, 40)] {
            assert!(mesh_triangles(m) <= t && mesh_triangles(m + 1) > t);
        }
        assert_eq!(mesh_within(u64::MAX), MAX_MESH);
    }
}
