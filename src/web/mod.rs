//! The browser build (`bash scripts/web.sh` → `out/web/`): the lab on
//! WebGPU. [`query`] reads a page's link as the command line's arguments
//! (native too, so that its tests run with the others); in wasm32, `lab`
//! is the interface JavaScript calls, `page` renders into the canvas and
//! runs the reference on the page's thread, `present` puts frames on the
//! canvas and `readback` awaits the textures a comparison reads.

#[cfg(target_arch = "wasm32")]
pub mod lab;
#[cfg(target_arch = "wasm32")]
mod page;
#[cfg(target_arch = "wasm32")]
mod present;
pub mod query;
#[cfg(target_arch = "wasm32")]
mod readback;
