//! What the ground is coloured with beyond the natural surface types: a user's colour ramp
//! ([`ramp`]), uploaded as its stops for the shading to interpolate, and a user's imagery
//! ([`image`]), resampled onto the sketch's grid.

pub mod image;
pub mod ramp;

pub use image::{Drape, drape};
pub use ramp::{ColorRamp, Stop};
