//! Tests of what the crate keeps private: every shader against naga and the Rust twins of its
//! structs, every pass's bindings against its WGSL, GeoMipMapping's selection on the CPU, the
//! warp's properties. They live inside the crate because what they test is not its API; the
//! tests of the API are the workspace's `tests/`. A mode's passes are held to their CPU twins in
//! the mode's own folder (`lod/warped/tests.rs`, `lod/clipmaps/tests.rs`).

mod bindings;
mod geomipmap;
mod shaders;
mod warp_props;
