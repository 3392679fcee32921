//! Cameras that move: the scene's `[path]` flown at constant speed ([`path`]), and the camera a
//! user flies with the mouse and keys, with the recorder that writes what was flown as a
//! `[path]` ([`flycam`]). The `terrain` tools and the web page fly the same ones.
//!
//! Rules: a camera from here is an ordinary [`Camera`](crate::Camera) of the scene; nothing here
//! reads the clock (callers pass the seconds flown), so a flight is the same at any frame rate
//! and in a page, where the time is the browser's. Rejected: each front end (window, files,
//! page) its own flight, which drifted apart.

pub mod flycam;
pub mod path;
