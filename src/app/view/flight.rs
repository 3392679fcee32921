//! The camera the window flies, over a sketch or over a planet, and how the held keys, the tour
//! and the recorder move it each frame.
//!
//! Rule: over a sketch the eye never sinks below the ground plus all the detail can add plus the
//! clearance; over a planet the camera keeps its own altitude above the ground.

use super::App;
use std::time::Instant;
use terrain_engine::Result;
use terrain_engine::flight::flycam::{
    CLEARANCE_M, FlyCamera, Motion, PathRecorder, PlanetFlyCamera,
};
use terrain_engine::scene::ground_under;
use winit::keyboard::KeyCode;

/// The camera the window flies: over a sketch, or over a planet.
pub(super) enum Flyer {
    Plane(FlyCamera),
    Planet(PlanetFlyCamera),
}

impl Flyer {
    pub(super) fn look(&mut self, dx: f64, dy: f64) {
        match self {
            Flyer::Plane(c) => c.look(dx, dy),
            Flyer::Planet(c) => c.look(dx, dy),
        }
    }

    /// The camera's `[path]` key, and where its eye is in world metres.
    pub(super) fn key(&self) -> (terrain_engine::scene::PathKey, glam::DVec3) {
        match self {
            Flyer::Plane(c) => (PathRecorder::key_of(c), c.eye),
            Flyer::Planet(c) => (c.key(), c.world()),
        }
    }
}

impl App {
    /// The least height of the eye at its position: the ground plus everything the detail can
    /// add plus the clearance (a planet's camera keeps its own: its altitude is above the ground).
    fn floor(&self) -> Option<f64> {
        let Flyer::Plane(c) = &self.cam else {
            return None;
        };
        // A tile that cannot be read fails the frame that draws it; here it only loses the floor.
        let ground = ground_under(&self.atlas, c.eye.truncate()).ok().flatten();
        ground.map(|g| g + self.reach_m + CLEARANCE_M)
    }

    pub(super) fn camera(&self) -> Result<terrain_engine::Camera> {
        let (w, h) = self.size;
        match &self.cam {
            Flyer::Plane(c) => c.camera(self.scene.camera.fov_y_deg, w, h, self.far),
            Flyer::Planet(c) => c.camera(&self.scene, &self.atlas, w, h),
        }
    }

    /// Metres between the eye and the ground under it.
    pub(super) fn above_m(&self) -> f64 {
        match &self.cam {
            Flyer::Plane(c) => {
                let ground = ground_under(&self.atlas, c.eye.truncate()).ok().flatten();
                c.eye.z - ground.unwrap_or(self.atlas.min_m as f64)
            }
            Flyer::Planet(c) => c.altitude,
        }
    }

    fn motion(&self) -> Motion {
        let axis = |plus: KeyCode, minus: KeyCode| {
            (self.held.contains(&plus) as i32 - self.held.contains(&minus) as i32) as f64
        };
        Motion {
            forward: axis(KeyCode::KeyW, KeyCode::KeyS),
            right: axis(KeyCode::KeyD, KeyCode::KeyA),
            up: axis(KeyCode::KeyE, KeyCode::KeyQ),
            fast: self.held.contains(&KeyCode::ShiftLeft)
                || self.held.contains(&KeyCode::ShiftRight),
        }
    }

    /// Moves the camera by the time since the last frame; returns that time, seconds.
    pub(super) fn step(&mut self) -> f64 {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f64();
        self.last = now;
        let motion = self.motion();
        let floor = self.floor();
        if !self.held.is_empty() || self.drag.is_some() {
            self.tour = None;
        }
        if let (Some((path, t)), Flyer::Plane(c)) = (&mut self.tour, &mut self.cam) {
            *t = (*t + dt).rem_euclid(path.duration_s());
            let s = *t * path.speed_mps;
            *c = FlyCamera::looking(path.position(s), path.direction(s));
        }
        match &mut self.cam {
            Flyer::Plane(c) => c.step(dt, &motion, floor),
            Flyer::Planet(c) => c.step(dt, &motion),
        }
        if let Some(r) = &mut self.recorder {
            let (key, at) = self.cam.key();
            r.record(key, at, dt);
        }
        dt
    }
}
