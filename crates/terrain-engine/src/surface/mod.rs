//! What the ground is coloured with beyond the natural surface types: a user's colour ramp
//! ([`ramp`]), uploaded as its stops for the shading to interpolate, and a user's imagery
//! ([`image`]), resampled onto the sketch's grid.

pub mod image;
mod picture;
pub mod ramp;
pub(crate) mod tiff;

pub use image::{Drape, drape};
pub use ramp::{ColorRamp, Stop};
