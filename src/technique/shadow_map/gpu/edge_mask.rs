//! Edge-masked filtering (`edge_mask=true`; [000] §4.3: PCF only at shadow
//! silhouettes): a chain of depth bounds of the map (`edge_mask.wgsl`: per
//! cell, two parallel planes that every stored depth lies between — on a
//! flat or sloped surface they follow it, elsewhere they are the least and
//! greatest depth), after which the lookup reads 2×2 texels of the level
//! that covers a pixel's whole kernel and runs the kernel only where the
//! receiver depth, along its plane, can lie between them — elsewhere every
//! tap would agree (all lit or all shadowed), so the answer is known
//! without them. A min/max chain alone calls a lit sloped receiver an edge
//! wherever its own depths under the cell span its depth.
//!
//! With `part_ids` a receiver ignores its own convex part's texels, which
//! the bounds cannot tell apart, so a second chain keeps each cell's part:
//! the one part all its texels came from, or [`MIXED_PART`]. A cell of the
//! receiver's own part is lit whatever its depths; a mixed one is an edge.

use super::{PART_FORMAT, placeholder};
use crate::gpu::GpuContext;
use anyhow::Result;
use std::sync::Arc;

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// A part chain's cell whose texels came from more than one part.
pub const MIXED_PART: u32 = u32::MAX;
const WORKGROUP: u32 = 8;
/// log2 of the map texels per side of a level-0 texel (8): a kernel of
/// radius 1 or more (the default is 1.5) spans 5 texels or more and reads
/// 8-texel cells anyway; a narrower one gets a looser test, still exact.
const BLOCK_LOG2: u32 = 3;
const BLOCK: u32 = 1 << BLOCK_LOG2;

/// The WGSL constant `CHAIN_BLOCK_LOG2` that the chain's reduction and the
/// lookup's classification share.
pub fn wgsl_constants() -> String {
    format!(
        "const CHAIN_BLOCK_LOG2: u32 = {BLOCK_LOG2}u;\nconst MIXED_PART: u32 = {MIXED_PART}u;\n"
    )
}

/// The reduction programs, shared per device.
struct ChainShared {
    layout: wgpu::BindGroupLayout,
    from_depth: wgpu::ComputePipeline,
    from_bytes: wgpu::ComputePipeline,
    from_level: wgpu::ComputePipeline,
    /// Bound in place of the source not read by a step.
    placeholder_depth: wgpu::TextureView,
    placeholder_values: wgpu::TextureView,
    /// Part 0 (none) everywhere: the source of a map without part ids.
    placeholder_parts: wgpu::TextureView,
    nearest: wgpu::Sampler,
}

impl ChainShared {
    fn new(gpu: &GpuContext) -> ChainShared {
        let device = &gpu.device;
        let texture = |binding, sample_type| {
            crate::gpu::sampled_texture_entry(
                binding,
                wgpu::ShaderStages::COMPUTE,
                sample_type,
                wgpu::TextureViewDimension::D2Array,
            )
        };
        let storage = |binding, format| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2Array,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("edge mask chain"),
            entries: &[
                texture(0, wgpu::TextureSampleType::Depth),
                texture(1, wgpu::TextureSampleType::Float { filterable: false }),
                storage(2, FORMAT),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                    count: None,
                },
                texture(4, wgpu::TextureSampleType::Uint),
                storage(5, PART_FORMAT),
            ],
        });
        let [from_depth, from_bytes, from_level] = crate::gpu::compute_pipelines(
            gpu,
            "edge mask chain",
            &layout,
            &(wgsl_constants() + include_str!("edge_mask.wgsl")),
            ["from_depth", "from_bytes", "from_level"],
        );
        ChainShared {
            from_depth,
            from_bytes,
            from_level,
            placeholder_depth: placeholder(device, wgpu::TextureFormat::Depth32Float),
            placeholder_values: placeholder(device, wgpu::TextureFormat::R8Unorm),
            placeholder_parts: placeholder(device, PART_FORMAT),
            nearest: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("edge mask chain gather"),
                ..Default::default()
            }),
            layout,
        }
    }
}

/// Where the chain's level 0 reads from.
pub enum ChainSource<'a> {
    Depth(&'a wgpu::TextureView),
    Bytes(&'a wgpu::TextureView),
}

/// What the chain reduces: the map's depths and, with `part_ids`, its parts.
pub struct ChainInput<'a> {
    pub depths: ChainSource<'a>,
    pub parts: Option<&'a wgpu::TextureView>,
}

/// One light's bounds chain: levels from an eighth of the map's side down
/// to 1×1.
pub struct BoundsChain {
    shared: Arc<ChainShared>,
    /// The map side and layers it was made for.
    size: u32,
    layers: u32,
    /// Per level, its side and its bounds and parts views (written, then
    /// read by the next).
    levels: Vec<(u32, wgpu::TextureView, wgpu::TextureView)>,
    /// Every level, read by the lookup.
    pub view: wgpu::TextureView,
    /// Every level of the part chain, read by the lookup.
    pub part_view: wgpu::TextureView,
    pub bytes: u64,
}

impl BoundsChain {
    /// Keeps `chain` when it fits a map of `size`² × `layers`, else makes one.
    pub fn ensure(
        chain: &mut Option<BoundsChain>,
        gpu: &GpuContext,
        size: u32,
        layers: u32,
    ) -> Result<()> {
        if chain
            .as_ref()
            .is_some_and(|c| (c.size, c.layers) == (size, layers))
        {
            return Ok(());
        }
        *chain = None;
        *chain = Some(BoundsChain::new(gpu, size, layers)?);
        Ok(())
    }

    fn new(gpu: &GpuContext, size: u32, layers: u32) -> Result<BoundsChain> {
        let sides: Vec<u32> = std::iter::successors(Some(size.div_ceil(BLOCK).max(1)), |&s| {
            (s > 1).then(|| s.div_ceil(2))
        })
        .collect();
        // 16 bytes of bounds and 4 of part per cell.
        let bytes = sides.iter().map(|&s| s as u64 * s as u64 * 20).sum::<u64>() * layers as u64;
        gpu.check_allocation(
            &format!("shadow-map: the edge mask's bounds chain of a {size}² map"),
            (sides[0], sides[0], layers),
            bytes,
        )?;
        gpu.checked("allocating the edge mask's bounds chain", || {
            let chain_texture = |label, format| {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: sides[0],
                        height: sides[0],
                        depth_or_array_layers: layers,
                    },
                    mip_level_count: sides.len() as u32,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::STORAGE_BINDING
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            };
            let bounds = chain_texture("edge mask bounds chain", FORMAT);
            let parts = chain_texture("edge mask part chain", PART_FORMAT);
            let view = |texture: &wgpu::Texture, level: Option<u32>| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    base_mip_level: level.unwrap_or(0),
                    mip_level_count: level.map(|_| 1),
                    ..Default::default()
                })
            };
            let levels = (0..sides.len() as u32)
                .map(|l| {
                    (
                        sides[l as usize],
                        view(&bounds, Some(l)),
                        view(&parts, Some(l)),
                    )
                })
                .collect();
            Ok(BoundsChain {
                shared: gpu.cache.shared(|| ChainShared::new(gpu)),
                size,
                layers,
                levels,
                view: view(&bounds, None),
                part_view: view(&parts, None),
                bytes,
            })
        })
    }

    /// Records the reduction of the map into every level.
    pub fn record(&self, gpu: &GpuContext, encoder: &mut wgpu::CommandEncoder, input: ChainInput) {
        let shared = &self.shared;
        let mut pass = gpu.compute_pass(
            encoder,
            &wgpu::ComputePassDescriptor {
                label: Some("edge mask bounds chain"),
                timestamp_writes: None,
            },
        );
        for (level, (side, destination, destination_parts)) in self.levels.iter().enumerate() {
            let (pipeline, depth, values, parts) = match (level.checked_sub(1), &input.depths) {
                (None, ChainSource::Depth(d)) => (
                    &shared.from_depth,
                    *d,
                    &shared.placeholder_values,
                    input.parts.unwrap_or(&shared.placeholder_parts),
                ),
                (None, ChainSource::Bytes(b)) => (
                    &shared.from_bytes,
                    &shared.placeholder_depth,
                    *b,
                    input.parts.unwrap_or(&shared.placeholder_parts),
                ),
                (Some(below), _) => {
                    let (_, bounds, parts) = &self.levels[below];
                    (&shared.from_level, &shared.placeholder_depth, bounds, parts)
                }
            };
            let view = |binding, view| wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            };
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("edge mask chain level"),
                layout: &shared.layout,
                entries: &[
                    view(0, depth),
                    view(1, values),
                    view(2, destination),
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::Sampler(&shared.nearest),
                    },
                    view(4, parts),
                    view(5, destination_parts),
                ],
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            let groups = side.div_ceil(WORKGROUP);
            pass.dispatch_workgroups(groups, groups, self.layers);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Side of the test map: not a multiple of the block, so the last
    /// cells of each level reach past it (the gathers' clamp).
    const SIDE: u32 = 60;

    /// The test map's 8-bit depths: the plane (x + 2y)/255 with a square
    /// caster at 10/255.
    fn depth(x: u32, y: u32) -> u8 {
        if in_square(x, y) {
            10
        } else {
            (x + 2 * y) as u8
        }
    }

    fn in_square(x: u32, y: u32) -> bool {
        (20..30).contains(&x) && (24..34).contains(&y)
    }

    /// The test map's parts: 1 for the plane, 2 for the square caster.
    fn part(x: u32, y: u32) -> u32 {
        if in_square(x, y) { 2 } else { 1 }
    }

    fn map_view(
        gpu: &GpuContext,
        format: wgpu::TextureFormat,
        texels: &[u8],
        bytes: u32,
    ) -> wgpu::TextureView {
        let map = crate::gpu::texture_2d(
            &gpu.device,
            "edge mask test map",
            SIDE,
            SIDE,
            1,
            format,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        gpu.queue.write_texture(
            map.as_image_copy(),
            texels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(SIDE * bytes),
                rows_per_image: Some(SIDE),
            },
            map.size(),
        );
        map.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    }

    /// The chain of a test map, reduced.
    fn reduced(
        gpu: &GpuContext,
        depths: &wgpu::TextureView,
        parts: Option<&wgpu::TextureView>,
    ) -> BoundsChain {
        let mut chain = None;
        BoundsChain::ensure(&mut chain, gpu, SIDE, 1).unwrap();
        let chain = chain.unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        chain.record(
            gpu,
            &mut encoder,
            ChainInput {
                depths: ChainSource::Bytes(depths),
                parts,
            },
        );
        gpu.queue.submit([encoder.finish()]);
        chain
    }

    /// Map texels of cell (cx, cy) of a level whose cells cover `cover`
    /// texels a side, those inside the map.
    fn cell_texels(cx: u32, cy: u32, cover: u32) -> impl Iterator<Item = (u32, u32)> {
        (cy * cover..((cy + 1) * cover).min(SIDE))
            .flat_map(move |ty| (cx * cover..((cx + 1) * cover).min(SIDE)).map(move |tx| (tx, ty)))
    }

    /// The part chain holds a cell's one part where all its texels (those
    /// inside the map) came from it, else MIXED_PART, at every level; a
    /// map without parts is part 0 throughout.
    #[test]
    fn part_chain_keeps_a_cells_one_part_or_mixed() {
        let gpu = GpuContext::new(None).expect("a Vulkan adapter (install mesa-vulkan-drivers)");
        let depths: Vec<u8> = (0..SIDE * SIDE)
            .map(|i| depth(i % SIDE, i / SIDE))
            .collect();
        let parts: Vec<u8> = (0..SIDE * SIDE)
            .flat_map(|i| part(i % SIDE, i / SIDE).to_le_bytes())
            .collect();
        let depth_view = map_view(&gpu, wgpu::TextureFormat::R8Unorm, &depths, 1);
        let part_view = map_view(&gpu, PART_FORMAT, &parts, 4);
        for with_parts in [true, false] {
            let chain = reduced(&gpu, &depth_view, with_parts.then_some(&part_view));
            let mut mixed = 0;
            for (level, &(side, _, _)) in chain.levels.iter().enumerate() {
                let data = gpu
                    .read_texture_level(chain.part_view.texture(), 0, level as u32, 4)
                    .unwrap();
                let cover = BLOCK << level;
                for (cx, cy) in (0..side).flat_map(|y| (0..side).map(move |x| (x, y))) {
                    let at = ((cy * side + cx) * 4) as usize;
                    let got = u32::from_le_bytes(data[at..at + 4].try_into().unwrap());
                    let mut seen = cell_texels(cx, cy, cover).map(|(tx, ty)| part(tx, ty));
                    let first = seen.next().unwrap();
                    let want = match (with_parts, seen.all(|p| p == first)) {
                        (false, _) => 0,
                        (true, true) => first,
                        (true, false) => MIXED_PART,
                    };
                    assert_eq!(
                        got, want,
                        "parts {with_parts}, level {level} cell ({cx}, {cy})"
                    );
                    mixed += (got == MIXED_PART) as u32;
                }
            }
            // Every cell that holds part of the square (x 20–29, y 24–33)
            // also holds plane: level 0 (8 texels) x cells 2–3, y 3–4;
            // level 1 (16) x 1, y 1–2; level 2 (32) x 0, y 0–1; level 3.
            assert_eq!(mixed, if with_parts { 4 + 2 + 2 + 1 } else { 0 });
        }
    }

    /// Every texel of a map lies between its cell's two planes at every
    /// level, and cells on the sloped plane alone are bounded tightly (the
    /// planes follow it): a min/max chain there spans the cell's slope,
    /// 24/255 at level 0, and a misread gather order breaks the bound.
    #[test]
    fn bounds_chain_holds_every_texel_and_follows_a_sloped_plane() {
        let gpu = GpuContext::new(None).expect("a Vulkan adapter (install mesa-vulkan-drivers)");
        let texels: Vec<u8> = (0..SIDE * SIDE)
            .map(|i| depth(i % SIDE, i / SIDE))
            .collect();
        let view = map_view(&gpu, wgpu::TextureFormat::R8Unorm, &texels, 1);
        let chain = reduced(&gpu, &view, None);
        let mut tight = 0;
        for (level, &(side, _, _)) in chain.levels.iter().enumerate() {
            let data = gpu
                .read_texture_level(chain.view.texture(), 0, level as u32, 16)
                .unwrap();
            let cells: Vec<f32> = data
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            let cover = BLOCK << level;
            for (cx, cy) in (0..side).flat_map(|y| (0..side).map(move |x| (x, y))) {
                let at = ((cy * side + cx) * 4) as usize;
                let [lo, hi, gx, gy] = [cells[at], cells[at + 1], cells[at + 2], cells[at + 3]];
                let mut planar = (cx + 1) * cover <= SIDE && (cy + 1) * cover <= SIDE;
                for (tx, ty) in cell_texels(cx, cy, cover) {
                    let d = depth(tx, ty);
                    planar &= d as u32 == tx + 2 * ty;
                    let u = |t: u32, c: u32| (t as f32 + 0.5) / cover as f32 - (c as f32 + 0.5);
                    let plane = gx * u(tx, cx) + gy * u(ty, cy);
                    let d = d as f32 / 255.0;
                    assert!(
                        d >= lo + plane - 1e-6 && d <= hi + plane + 1e-6,
                        "level {level} cell ({cx}, {cy}): texel ({tx}, {ty}) {d} outside {lo}..{hi} + {plane}"
                    );
                }
                if planar {
                    assert!(
                        hi - lo < 1e-5,
                        "level {level} cell ({cx}, {cy}): {lo}..{hi} on a plane"
                    );
                    tight += 1;
                }
            }
        }
        // Cells inside the map and off the caster: level 0, 7² less 2×2;
        // level 1, 3² less 1×2; level 2, its one inside cell holds the caster.
        assert_eq!(tight, 45 + 7, "cells bounded tightly on the plane");
    }
}
