//! shadowlab: a real-time shadow rendering lab. Every shadow technique
//! writes a per-light screen-space visibility mask; the lighting pass
//! composes `ambient + visibility × (diffuse + specular)`; a CPU ray tracer
//! writes the same mask from the same G-buffer, so each technique can be
//! measured against ground truth pixel by pixel.

pub mod args;
pub mod cli;
pub mod frame;
pub mod fuzz_input;
pub mod gpu;
pub mod guide;
pub mod headless;
pub mod measure;
pub mod renderer;
pub mod report;
pub mod scene;
pub mod technique;
#[cfg(feature = "viewer")]
pub mod viewer;
