//! What the ground is coloured with beyond the natural surface types: a user's colour ramp
//! ([`ramp`]), uploaded as its stops for the shading to interpolate.

pub mod ramp;

pub use ramp::{ColorRamp, Stop};
