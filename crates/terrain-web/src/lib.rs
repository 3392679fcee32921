//! The web page's renderer: the `terrain` library compiled to WebAssembly, drawing a scene into
//! a canvas through the browser's WebGPU with the host API ([`terrain::Terrain`]), as any host
//! does. `terrain web` writes the page (`site/index.html`, `site/main.js`) beside this module.
//!
//! Rules:
//! - One renderer: every pass, the CPU stage and the flights are the library's; this crate owns
//!   only what a page has and a window does not (a canvas, the browser's clock and input).
//! - The page's script owns the DOM (overlay, buttons, events, the animation frame); it tells a
//!   `Viewer` the time, the keys and the drags, and reads `Viewer::stats`.
//! - A frame is settled once the GPU has finished the first frame drawn with the current mode,
//!   view and size (a sketch read whole has nothing more to load).
//!
//! Rejected: a JavaScript renderer reading the engine's shaders — a second implementation of
//! every pass, which would drift from the one `terrain render` measures.

#![deny(missing_docs)]
// The page is a host: its canvas's textures are its own, outside the library's ledger.
#![allow(clippy::disallowed_methods)]

mod frames;
// The page's side exists in a browser only: wasm-bindgen's types are not Send elsewhere.
#[cfg(target_arch = "wasm32")]
mod present;
#[cfg(target_arch = "wasm32")]
mod viewer;
#[cfg(target_arch = "wasm32")]
pub use viewer::Viewer;
