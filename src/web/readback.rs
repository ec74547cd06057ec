//! Reading textures back in the browser: the copy is submitted as natively
//! ([`GpuContext::copy_texture`]), and the map is awaited as a JavaScript
//! promise, because a page cannot block while WebGPU completes it.

use crate::gpu::GpuContext;
use anyhow::{Result, anyhow};
use wasm_bindgen::JsValue;

/// Awaits the map of a `MAP_READ` buffer and returns its bytes.
pub async fn map_read(buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let mut settle = None;
    let promise = js_sys::Promise::new(&mut |resolve, reject| settle = Some((resolve, reject)));
    let (resolve, reject) = settle.ok_or_else(|| anyhow!("a promise runs its executor at once"))?;
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = match r {
            Ok(()) => resolve.call0(&JsValue::NULL),
            Err(e) => reject.call1(&JsValue::NULL, &JsValue::from_str(&e.to_string())),
        };
    });
    wasm_bindgen_futures::JsFuture::from(promise)
        .await
        .map_err(|e| anyhow!("reading a GPU buffer back: {e:?}"))?;
    let data = buffer.slice(..).get_mapped_range()?.to_vec();
    buffer.unmap();
    Ok(data)
}

/// One layer of a 2D texture, rows tightly packed.
pub async fn read_texture(
    gpu: &GpuContext,
    texture: &wgpu::Texture,
    layer: u32,
    bytes_per_pixel: u32,
) -> Result<Vec<u8>> {
    let copy = gpu.copy_texture(texture, layer, 0, bytes_per_pixel);
    Ok(copy.unpad(&map_read(&copy.buffer).await?))
}
