//! Height queries: the terrain function the reference mode ray-marches, evaluated on the CPU in
//! f64, for placing objects on the ground, collision and picking.
//!
//! Rules:
//! - The surface at a point is the sketch, bicubic (Catmull–Rom) on the pyramid level of the
//!   caller's footprint (linear between two levels), plus each octave k weighted by its pixel
//!   share `b_k = clamp(o_px − k + 1, 0, 1)`, and the water's flat surface over it: the
//!   reference's surface (docs/design.md, Procedural detail). A footprint of 0 asks for the
//!   finest: level 0 and every octave whole.
//! - Beyond the sketch lies what `sketch.outside` draws there: the plain or the sea, joined to
//!   the sketch's edge by the margin ([`crate::beyond`]), or nothing (`None`).
//! - A streamed sketch is read from its tiles at the level asked for, as a settled frame draws it.
//! - Nothing non-finite leaves a query: a non-finite point or direction is an error.
//!
//! Rejected: answering from the mesh a mode drew, which changes with the camera and the mode;
//! the terrain function is what every mode converges to and what the reference draws.

use crate::beyond::{Beyond, nearest_on};
use crate::detail::Detail;
use crate::error::{Error, Result};
use crate::scene::{Outside, Scene};
use crate::sketch::Atlas;
use crate::sketch::cubic::Weights;
use crate::sketch::cubic::{catmull_rom, catmull_rom_d};
use glam::{DVec2, DVec3};

/// The ground of a planar scene: its sketch, detail and what lies beyond the sketch.
pub struct Ground<'a> {
    atlas: &'a Atlas,
    detail: &'a Detail,
    beyond: Beyond,
}

impl<'a> Ground<'a> {
    /// The ground of `scene` over `atlas` with `detail` (`scene::detail_of` gives the scene's
    /// own).
    pub fn new(scene: &Scene, atlas: &'a Atlas, detail: &'a Detail) -> Ground<'a> {
        Ground {
            atlas,
            detail,
            beyond: Beyond::new(atlas, scene.outside(atlas)),
        }
    }

    /// The surface's height at world point `p` for a footprint of `footprint_m` metres (0: the
    /// finest), or `None` where nothing is drawn (beyond the sketch with `outside = "void"`).
    ///
    /// ```
    /// use terrain::{Description, Ground, Scene, glam::DVec2};
    ///
    /// let text = "[sketch]\nsynthetic = \"hills\"\nsize = 129\noutside = \"void\"\n";
    /// let description = Description::new(Scene::parse(text, ".".into()).unwrap())?;
    /// let (atlas, detail) = (description.atlas(), description.detail());
    /// let ground = Ground::new(description.scene(), atlas, &detail);
    ///
    /// // The sketch's centre: the hills plus every octave, within the octaves' reach of them.
    /// let centre = atlas.origin + DVec2::new(atlas.dx, atlas.dy) * 64.0;
    /// let z = ground.height_at(centre, 0.0)?.expect("ground inside the sketch");
    /// let reach = detail.reach_m();
    /// assert!(z >= atlas.min_m as f64 - reach && z <= atlas.max_m as f64 + reach);
    ///
    /// // A coarser footprint reads a coarser pyramid level and fewer octaves: another height.
    /// let far = ground.height_at(centre, 500.0)?.unwrap();
    /// assert_ne!(z, far);
    ///
    /// // Beyond the sketch, `outside = "void"` draws nothing.
    /// assert_eq!(ground.height_at(atlas.origin - DVec2::splat(1000.0), 0.0)?, None);
    /// // A non-finite point is an error, not a height.
    /// assert!(ground.height_at(DVec2::new(f64::NAN, 0.0), 0.0).is_err());
    /// # Ok::<(), terrain::Error>(())
    /// ```
    pub fn height_at(&self, p: DVec2, footprint_m: f64) -> Result<Option<f64>> {
        finite_point(p)?;
        if !self.inside(p) {
            return self.beyond_height(p, footprint_m);
        }
        let sketch = self.sketch_at(p, footprint_m)?;
        let land = sketch + self.shore(sketch) * self.octaves_at(p, footprint_m).0;
        Ok(Some(land.max(self.atlas.water_m as f64)))
    }

    /// The surface's unit normal at `p` (straight up on water and beyond the sketch), or `None`
    /// where nothing is drawn.
    pub fn normal_at(&self, p: DVec2, footprint_m: f64) -> Result<Option<DVec3>> {
        let Some(z) = self.height_at(p, footprint_m)? else {
            return Ok(None);
        };
        if z <= self.atlas.water_m as f64 {
            return Ok(Some(DVec3::Z));
        }
        if !self.inside(p) {
            return self.beyond_normal(p, footprint_m);
        }
        let fade = self.shore(self.sketch_at(p, footprint_m)?);
        let g = self.sketch_gradient(p, footprint_m)? + fade * self.octaves_at(p, footprint_m).1;
        Ok(Some(DVec3::new(-g.x, -g.y, 1.0).normalize()))
    }

    /// Where the ray from `origin` along `direction` first meets the surface, marched as the
    /// reference marches a pixel's ray: the footprint at distance t is `t · pixel_scale` (0: the
    /// finest everywhere). `None` where it meets nothing.
    pub fn ray_cast(
        &self,
        origin: DVec3,
        direction: DVec3,
        pixel_scale: f64,
    ) -> Result<Option<DVec3>> {
        if !origin.is_finite() || !direction.is_finite() || direction.length_squared() == 0.0 {
            return Err(Error::Query(format!(
                "a ray needs a finite origin and a non-zero direction, not {origin} along {direction}"
            )));
        }
        let dir = direction.normalize();
        if let Some(hit) = self.march(origin, dir, pixel_scale)? {
            return Ok(Some(hit));
        }
        Ok(self.beyond_hit(origin, dir))
    }

    fn inside(&self, p: DVec2) -> bool {
        let (lo, hi) = (self.atlas.origin, self.atlas.max_corner());
        p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y
    }

    /// The surface `sketch.outside` puts at `p` beyond the sketch: the margin's ground and its
    /// fading octaves, under the water where it lies below it.
    fn beyond_height(&self, p: DVec2, footprint_m: f64) -> Result<Option<f64>> {
        if self.beyond.outside == Outside::Void {
            return Ok(None);
        }
        let water = self.atlas.water_m as f64;
        let (c, d) = nearest_on(self.atlas.origin, self.atlas.max_corner(), p);
        if d >= self.beyond.margin_m {
            return Ok(Some(self.beyond.level_m.max(water)));
        }
        // The edge read ever more broadly outward, as the shaders read it.
        let broad = footprint_m.max(0.5 * d);
        let edge = self.sketch_at(c, broad)?;
        let slope = if d > 0.0 {
            self.sketch_gradient(c, broad)?.dot(p - c) / d
        } else {
            0.0
        };
        let ground = self.beyond.ground(edge, slope, d);
        let octaves = self.beyond.fade(d) * self.shore(ground) * self.octaves_at(p, footprint_m).0;
        Ok(Some((ground + octaves).max(water)))
    }

    /// The margin's normal at `p`, by central differences a sixteenth of a cell (or the
    /// footprint) apart: the fade and the slope's continuation have no closed gradient worth its
    /// code.
    fn beyond_normal(&self, p: DVec2, footprint_m: f64) -> Result<Option<DVec3>> {
        let h = (self.atlas.d_atlas() / 16.0).max(footprint_m);
        let at =
            |q: DVec2| -> Result<f64> { Ok(self.beyond_height(q, footprint_m)?.unwrap_or(0.0)) };
        let dx = at(p + DVec2::X * h)? - at(p - DVec2::X * h)?;
        let dy = at(p + DVec2::Y * h)? - at(p - DVec2::Y * h)?;
        Ok(Some(
            DVec3::new(-dx / (2.0 * h), -dy / (2.0 * h), 1.0).normalize(),
        ))
    }

    /// The level beyond the margin, where the water does not cover it.
    fn level(&self) -> Option<f64> {
        (self.beyond.outside != Outside::Void)
            .then(|| self.beyond.level_m.max(self.atlas.water_m as f64))
    }

    /// The pyramid level (fractional) a footprint reads, as the shaders' `atlas_height`.
    fn lod(&self, footprint_m: f64) -> f64 {
        let top = (self.atlas.levels.len() - 1) as f64;
        (footprint_m.max(1e-9) / self.atlas.d_atlas())
            .log2()
            .clamp(0.0, top)
    }

    fn texel(&self, p: DVec2) -> DVec2 {
        (p - self.atlas.origin) / DVec2::new(self.atlas.dx, self.atlas.dy)
    }

    fn sketch_at(&self, p: DVec2, footprint_m: f64) -> Result<f64> {
        self.blend_levels(p, footprint_m, |uv, l| {
            bicubic(self.atlas, uv, l, catmull_rom, catmull_rom)
        })
    }

    /// The sketch's gradient per metre: the bicubic's own derivatives.
    fn sketch_gradient(&self, p: DVec2, footprint_m: f64) -> Result<DVec2> {
        // The bicubic's derivative is per texel of its level: 2^l level-0 texels.
        let per_level_texel = |l: usize| (1u64 << l) as f64;
        let gx = self.blend_levels(p, footprint_m, |uv, l| {
            Ok(bicubic(self.atlas, uv, l, catmull_rom_d, catmull_rom)? / per_level_texel(l))
        })?;
        let gy = self.blend_levels(p, footprint_m, |uv, l| {
            Ok(bicubic(self.atlas, uv, l, catmull_rom, catmull_rom_d)? / per_level_texel(l))
        })?;
        Ok(DVec2::new(gx / self.atlas.dx, gy / self.atlas.dy))
    }

    /// `sample` on the footprint's two levels, blended linearly.
    fn blend_levels(
        &self,
        p: DVec2,
        footprint_m: f64,
        sample: impl Fn(DVec2, usize) -> Result<f64>,
    ) -> Result<f64> {
        let lod = self.lod(footprint_m);
        let l0 = lod.floor() as usize;
        let t = lod - l0 as f64;
        let uv = self.texel(p);
        let a = sample(uv, l0)?;
        if t <= 0.0 || l0 + 1 >= self.atlas.levels.len() {
            return Ok(a);
        }
        Ok(a + (sample(uv, l0 + 1)? - a) * t)
    }

    /// The octaves' share over sketch height `z` ([`crate::detail::shore`]).
    fn shore(&self, z: f64) -> f64 {
        crate::detail::shore(z, self.atlas.water_m as f64, self.detail.shore_m())
    }

    /// The octaves' height and gradient at `p`, each weighted by its pixel share.
    fn octaves_at(&self, p: DVec2, footprint_m: f64) -> (f64, DVec2) {
        let o_px = if footprint_m > 0.0 {
            (self.detail.d_atlas / footprint_m).log2() as f32
        } else {
            f32::INFINITY
        };
        let last = if o_px.is_infinite() {
            self.detail.octaves
        } else {
            self.detail.last_octave(o_px)
        };
        let (mut h, mut g) = (0.0, DVec2::ZERO);
        for k in 1..=last {
            let b = (o_px - k as f32 + 1.0).clamp(0.0, 1.0) as f64;
            let (v, grad) = self.detail.octave_world(k, p);
            let w = self.detail.weight(k) * b;
            h += w * v as f64;
            g += w * grad.as_dvec2();
        }
        (h, g)
    }

    /// The lowest and highest the surface reaches over the sketch and its margin.
    fn bounds(&self) -> (f64, f64) {
        let reach = self.detail.reach_m();
        let water = self.atlas.water_m as f64;
        let [lo, hi] = self.beyond.span_m;
        (
            lo.min(self.atlas.min_m as f64) - reach,
            (hi + reach).max(water),
        )
    }

    /// The sketch's rectangle, grown by the margin where there is ground beyond it.
    fn march_rect(&self) -> (DVec2, DVec2) {
        let m = match self.beyond.outside {
            Outside::Void => 0.0,
            _ => self.beyond.margin_m,
        };
        (
            self.atlas.origin - DVec2::splat(m),
            self.atlas.max_corner() + DVec2::splat(m),
        )
    }

    /// The reference's march over the box of the sketch, its margin and their heights, then a
    /// bisection.
    fn march(&self, eye: DVec3, dir: DVec3, pixel_scale: f64) -> Result<Option<DVec3>> {
        let (z_lo, z_hi) = self.bounds();
        let (rect_lo, rect_hi) = self.march_rect();
        let lo = rect_lo.extend(z_lo);
        let hi = rect_hi.extend(z_hi);
        let Some((t0, t1)) = slab(eye, dir, lo, hi) else {
            return Ok(None);
        };
        let finest = self.detail.d_atlas / (self.detail.octaves as f64).exp2() / 4.0;
        let above = |t: f64| -> Result<f64> {
            let p = eye + dir * t;
            let z = self.height_at(p.truncate(), t * pixel_scale)?;
            Ok(p.z - z.unwrap_or(f64::NEG_INFINITY))
        };
        let (mut t_prev, mut t) = (t0, t0);
        for step in 0..MAX_STEPS {
            let t_here = t.min(t1);
            let a = above(t_here)?;
            // A ray entering the box through a side wall already under the surface comes from
            // beyond the margin: it met the plain or the sea there first, as the reference has it.
            if a <= 0.0
                && step == 0
                && t0 > 0.0
                && let Some(hit) = self.beyond_hit(eye, dir)
            {
                return Ok(Some(hit));
            }
            if a <= 0.0 {
                return Ok(Some(eye + dir * self.bisect(t_prev, t_here, &above)?));
            }
            if t_here >= t1 {
                return Ok(None);
            }
            t_prev = t_here;
            t = t_here + a.max(t_here * pixel_scale).max(finest) * STEP;
        }
        Ok(None)
    }

    fn bisect(&self, mut lo: f64, mut hi: f64, above: &impl Fn(f64) -> Result<f64>) -> Result<f64> {
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            if above(mid)? > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }

    /// Where a ray that met nothing over the sketch and its margin meets the plain or the sea
    /// beyond them.
    fn beyond_hit(&self, eye: DVec3, dir: DVec3) -> Option<DVec3> {
        let z = self.level()?;
        if dir.z >= 0.0 || eye.z <= z {
            return None;
        }
        let hit = eye + dir * ((z - eye.z) / dir.z);
        let (lo, hi) = self.march_rect();
        let p = hit.truncate();
        let within = p.x > lo.x && p.y > lo.y && p.x < hi.x && p.y < hi.y;
        (!within).then_some(hit)
    }
}

/// The reference's march step, as a fraction of the height above the ground (`reference.step`'s
/// default).
const STEP: f64 = 0.25;
const MAX_STEPS: usize = 1 << 16;

fn finite_point(p: DVec2) -> Result<()> {
    if p.is_finite() {
        Ok(())
    } else {
        Err(Error::Query(format!("the point {p} is not finite")))
    }
}

/// The part `[t0, t1]` of the ray inside the box `lo`…`hi`, if any.
fn slab(eye: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if dir[a].abs() < 1e-15 {
            if eye[a] < lo[a] || eye[a] > hi[a] {
                return None;
            }
        } else {
            let (ta, tb) = ((lo[a] - eye[a]) / dir[a], (hi[a] - eye[a]) / dir[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// The bicubic on level `l` at level-0 texel coordinates `uv`, nodes clamped to the level, with
/// weights `wx` along x and `wy` along y (the Catmull–Rom weights or their derivatives).
fn bicubic(atlas: &Atlas, uv: DVec2, l: usize, wx: Weights, wy: Weights) -> Result<f64> {
    let level = &atlas.levels[l];
    let (w, h) = (level.width as i64, level.height as i64);
    crate::sketch::cubic::bicubic(uv, l, (wx, wy), |i, j| {
        node(
            atlas,
            l,
            i.clamp(0, w - 1) as usize,
            j.clamp(0, h - 1) as usize,
        )
    })
}

/// Node (i, j) of level `l`: from memory, or from a streamed sketch's tile.
fn node(atlas: &Atlas, l: usize, i: usize, j: usize) -> Result<f32> {
    let level = &atlas.levels[l];
    match &atlas.pyramid {
        Some(pyramid) if level.data.is_empty() => pyramid.node(l, i, j),
        _ => Ok(level.data[j * level.width + i]),
    }
}

/// The ground of a planet: its global sketch and detail on the sphere of its radius.
pub struct PlanetGround<'a> {
    planet: crate::planet::Planet<'a>,
    detail: &'a Detail,
}

impl<'a> PlanetGround<'a> {
    /// The ground of a `[planet]` scene over its global `atlas` with `detail`.
    pub fn new(radius_m: f64, atlas: &'a Atlas, detail: &'a Detail) -> PlanetGround<'a> {
        PlanetGround {
            planet: crate::planet::Planet {
                radius: radius_m,
                sketch: atlas,
            },
            detail,
        }
    }

    /// The surface's height above the sphere at latitude and longitude (degrees) for a
    /// footprint of `footprint_m` metres (0: the finest): the ground, or the sea over it.
    pub fn height_at(&self, lat_deg: f64, lon_deg: f64, footprint_m: f64) -> Result<f64> {
        if !lat_deg.is_finite() || !lon_deg.is_finite() || lat_deg.abs() > 90.0 {
            return Err(Error::Query(format!(
                "latitude {lat_deg}°, longitude {lon_deg}° is not a place on the planet"
            )));
        }
        let footprint = if footprint_m > 0.0 { footprint_m } else { 1e-6 };
        let (lat, lon) = (lat_deg.to_radians(), lon_deg.to_radians());
        let ground = self.planet.ground(self.detail, lat, lon, footprint)?;
        Ok(ground.max(self.planet.sketch.water_m as f64))
    }
}
