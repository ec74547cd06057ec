//! The shadow-map family's GPU side: its programs and their keys
//! (`pipelines`), the uniform (`uniform`), the maps' textures (`maps`), the
//! depth pass from a light (`depth_pass`) and the edge mask's bounds chain
//! (`edge_mask`).

pub(super) mod depth_pass;
pub(super) mod edge_mask;
pub(super) mod maps;
pub(super) mod pipelines;
pub(super) mod uniform;

/// The debug frame's numbers per pixel: texel footprint (pixels per texel)
/// and the partition looked up (see [`crate::technique::MapLookup`]).
pub const LOOKUP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// Format of the moment maps (vsm, esm, evsm, msm).
pub const MOMENT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Format of the part maps (`part_ids`): a convex part's scene-wide ID.
pub const PART_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// A 1×1 array texture bound in place of a map that is not in use.
pub fn placeholder(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::TextureView {
    crate::gpu::texture_2d(
        device,
        "shadow map placeholder",
        1,
        1,
        1,
        format,
        wgpu::TextureUsages::TEXTURE_BINDING,
    )
    .create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}
