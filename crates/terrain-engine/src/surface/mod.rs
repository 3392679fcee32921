//! What the ground is coloured with beyond the natural surface types: a user's colour ramp
//! ([`ramp`]), uploaded as its stops for the shading to interpolate, and a user's imagery
//! ([`image`]), resampled onto the sketch's grid.

pub mod image;
mod picture;
pub mod ramp;
pub(crate) mod tiff;

pub use image::{Drape, drape};
pub use ramp::{ColorRamp, Stop};

/// The surface classes, by index: name and colour in the surface view (linear RGB; the WGSL
/// gets them as `CLASS_*` and `CLASS_COLOURS` through `#import constants`). 0 is the sky; `ramp`
/// and `image` are `surface.style`'s.
pub const SURFACE_CLASSES: [(&str, [f32; 3]); 12] = [
    ("sky", [0.0, 0.0, 0.0]),
    ("water", [0.0, 0.0, 1.0]),
    ("meadow", [0.5, 1.0, 0.0]),
    ("heath", [1.0, 1.0, 0.0]),
    ("forest", [0.0, 0.5, 0.0]),
    ("soil", [0.5, 0.0, 0.0]),
    ("scree", [0.5, 0.5, 0.5]),
    ("rock", [1.0, 0.0, 1.0]),
    ("sand", [1.0, 0.5, 0.0]),
    ("snow", [1.0, 1.0, 1.0]),
    ("ramp", [0.0, 1.0, 1.0]),
    ("image", [0.5, 0.0, 1.0]),
];
