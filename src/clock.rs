//! The monotonic clock every frame timing reads: std's `Instant` on native
//! targets; in the browser, where std's `Instant::now` panics on
//! wasm32-unknown-unknown, web-time's, which reads `performance.now()`.

#[cfg(not(target_arch = "wasm32"))]
pub use std::time::Instant;
#[cfg(target_arch = "wasm32")]
pub use web_time::Instant;
