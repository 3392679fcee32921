//! Tests of what the crate keeps private: every shader against naga and its Rust twins, every
//! pass's bindings against its WGSL, GeoMipMapping's selection on the CPU, the warp's properties.
//! They live inside the crate because what they test is not its API; the tests of the API are
//! the workspace's `tests/`.

mod bindings;
mod geomipmap;
mod shaders;
mod twins;
mod warp_props;
