//! The shadow-map family's GPU side: its programs and their keys
//! (`pipelines`), the uniform (`uniform`), the maps' textures (`maps`), the
//! depth pass from a light (`depth_pass`), the translucent casters' passes
//! (`transmittance`) and the edge mask's bounds chain (`edge_mask`).

pub(super) mod depth_pass;
pub(super) mod edge_mask;
pub(super) mod maps;
pub(super) mod pipelines;
pub(super) mod transmittance;
pub(super) mod uniform;

/// The family's group-2 bindings, declared once: the layout
/// (`ShadowMapShared::new`) and the bind groups use these, and a test
/// checks that the WGSL's `@binding`s agree, by variable name.
pub mod binding {
    /// `sm`: the uniform, one slot per face and sample (dynamic offset).
    pub const UNIFORM: u32 = 0;
    /// `depth_map`: the depth maps, one layer per face.
    pub const DEPTH_MAP: u32 = 3;
    /// `compare_sampler`: hardware 2×2 PCF.
    pub const COMPARE_SAMPLER: u32 = 4;
    /// `byte_map`: the 8-bit depth maps (`format=r8`).
    pub const BYTE_MAP: u32 = 5;
    /// `moment_map`: the moment filters' maps.
    pub const MOMENT_MAP: u32 = 6;
    /// `edge_bounds`: the edge mask's bounds chain.
    pub const EDGE_BOUNDS: u32 = 7;
    /// `vsm_marks`, `vsm_table`, `vsm`, `vsm_pixel_level`: a virtual map's
    /// page marks, page table, levels and each pixel's level.
    pub const VIRTUAL: [u32; 4] = [8, 9, 10, 11];
    /// `part_map`: the convex part each texel's depth came from.
    pub const PART_MAP: u32 = 12;
    /// `part_sampler`: nearest texels of the part maps.
    pub const PART_SAMPLER: u32 = 13;
    /// `edge_parts`: the bounds chain's part per cell.
    pub const EDGE_PARTS: u32 = 14;
    /// `transmit_depth`: the nearest translucent caster's depth.
    pub const TRANSMIT_DEPTH: u32 = 15;
    /// `transmittance`: the translucent casters' transmittance.
    pub const TRANSMITTANCE: u32 = 16;

    /// Every binding with the WGSL variable bound there (checked by a test).
    #[cfg(test)]
    pub const NAMED: [(&str, u32); 15] = [
        ("sm", UNIFORM),
        ("depth_map", DEPTH_MAP),
        ("compare_sampler", COMPARE_SAMPLER),
        ("byte_map", BYTE_MAP),
        ("moment_map", MOMENT_MAP),
        ("edge_bounds", EDGE_BOUNDS),
        ("vsm_marks", VIRTUAL[0]),
        ("vsm_table", VIRTUAL[1]),
        ("vsm", VIRTUAL[2]),
        ("vsm_pixel_level", VIRTUAL[3]),
        ("part_map", PART_MAP),
        ("part_sampler", PART_SAMPLER),
        ("edge_parts", EDGE_PARTS),
        ("transmit_depth", TRANSMIT_DEPTH),
        ("transmittance", TRANSMITTANCE),
    ];
}

/// The debug frame's numbers per pixel: texel footprint (pixels per texel)
/// and the partition looked up (see [`crate::technique::MapLookup`]).
pub const LOOKUP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// Format of the moment maps (vsm, esm, evsm, msm).
pub const MOMENT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Format of the part maps (`part_ids`): a convex part's scene-wide ID.
pub const PART_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Format of the transmittance maps (`blended_casters=transmit`): blended
/// multiplicatively, which 8 bits hold to 1/255.
pub const TRANSMITTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

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
