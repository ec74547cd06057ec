//! The browser build (`bash scripts/web.sh` → `out/web/`): the lab on
//! WebGPU. [`query`] reads a page's link as the command line's arguments
//! (native too, so that its tests run with the others); in wasm32, `page`
//! renders into the canvas and runs the reference on the page's thread,
//! and `readback` awaits the textures a comparison reads.

#[cfg(target_arch = "wasm32")]
pub mod page;
#[cfg(target_arch = "wasm32")]
mod present;
pub mod query;
#[cfg(target_arch = "wasm32")]
mod readback;
