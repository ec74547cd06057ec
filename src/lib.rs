//! shadowlab: a real-time shadow rendering lab. Every shadow technique
//! writes a per-light screen-space visibility mask; the lighting pass
//! composes `ambient + visibility × (diffuse + specular)`; a CPU ray tracer
//! writes the same mask from the same G-buffer, so each technique can be
//! measured against ground truth pixel by pixel.
//!
//! The command line, its reports, the guide's generated pages and the
//! viewer are native only; the browser build (`web`, wasm32) renders the
//! same frames and runs the same reference in the page.

pub mod args;
#[cfg(not(target_arch = "wasm32"))]
pub mod cli;
pub mod clock;
pub mod frame;
#[cfg(not(target_arch = "wasm32"))]
pub mod fuzz_input;
pub mod gpu;
#[cfg(not(target_arch = "wasm32"))]
pub mod guide;
pub mod headless;
pub mod measure;
pub mod renderer;
#[cfg(not(target_arch = "wasm32"))]
pub mod report;
pub mod scene;
pub mod technique;
#[cfg(all(feature = "viewer", not(target_arch = "wasm32")))]
pub mod viewer;
pub mod web;
