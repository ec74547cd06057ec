//! Edge-masked filtering (`edge_mask=true`; 000 §4.3: PCF only at shadow
//! silhouettes): a chain of depth bounds of the map (`edge_mask.wgsl`: per
//! cell, two parallel planes that every stored depth lies between — on a
//! flat or sloped surface they follow it, elsewhere they are the least and
//! greatest depth), after which the lookup reads 2×2 texels of the level
//! that covers a pixel's whole kernel and runs the kernel only where the
//! receiver depth, along its plane, can lie between them — elsewhere every
//! tap would agree (all lit or all shadowed), so the answer is known
//! without them. A min/max chain alone calls a lit sloped receiver an edge
//! wherever its own depths under the cell span its depth.

use super::pipelines::placeholder;
use crate::gpu::GpuContext;
use anyhow::Result;
use std::sync::Arc;

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const WORKGROUP: u32 = 8;
/// log2 of the map texels per side of a level-0 texel (8): a kernel of
/// radius 1 or more (the default is 1.5) spans 5 texels or more and reads
/// 8-texel cells anyway; a narrower one gets a looser test, still exact.
const BLOCK_LOG2: u32 = 3;
const BLOCK: u32 = 1 << BLOCK_LOG2;

/// The WGSL constant `CHAIN_BLOCK_LOG2` that the chain's reduction and the
/// lookup's classification share.
pub fn wgsl_constants() -> String {
    format!("const CHAIN_BLOCK_LOG2: u32 = {BLOCK_LOG2}u;\n")
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
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2Array,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("edge mask chain"),
            entries: &[
                texture(0, wgpu::TextureSampleType::Depth),
                texture(1, wgpu::TextureSampleType::Float { filterable: false }),
                storage(2),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                    count: None,
                },
            ],
        });
        let [from_depth, from_bytes, from_level] = crate::gpu::compute_pipelines(
            device,
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

/// One light's bounds chain: levels from an eighth of the map's side down
/// to 1×1.
pub struct BoundsChain {
    shared: Arc<ChainShared>,
    /// The map side and layers it was made for.
    size: u32,
    layers: u32,
    /// Per level, its side and its view (written, then read by the next).
    levels: Vec<(u32, wgpu::TextureView)>,
    /// Every level, read by the lookup.
    pub view: wgpu::TextureView,
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
        let bytes = sides.iter().map(|&s| s as u64 * s as u64 * 16).sum::<u64>() * layers as u64;
        gpu.check_allocation(
            &format!("shadow-map: the edge mask's bounds chain of a {size}² map"),
            (sides[0], sides[0], layers),
            bytes,
        )?;
        gpu.checked("allocating the edge mask's bounds chain", || {
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("edge mask bounds chain"),
                size: wgpu::Extent3d {
                    width: sides[0],
                    height: sides[0],
                    depth_or_array_layers: layers,
                },
                mip_level_count: sides.len() as u32,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FORMAT,
                usage: wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let level_view = |level: u32| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    base_mip_level: level,
                    mip_level_count: Some(1),
                    ..Default::default()
                })
            };
            let levels = (0..sides.len() as u32)
                .map(|l| (sides[l as usize], level_view(l)))
                .collect();
            Ok(BoundsChain {
                shared: gpu.cache.shared(|| ChainShared::new(gpu)),
                size,
                layers,
                levels,
                view: texture.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    ..Default::default()
                }),
                bytes,
            })
        })
    }

    /// Records the reduction of the map into every level.
    pub fn record(
        &self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        source: ChainSource,
    ) {
        let shared = &self.shared;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("edge mask bounds chain"),
            timestamp_writes: None,
        });
        for (level, (side, destination)) in self.levels.iter().enumerate() {
            let (pipeline, depth, values) = match (level, &source) {
                (0, ChainSource::Depth(d)) => (&shared.from_depth, *d, &shared.placeholder_values),
                (0, ChainSource::Bytes(b)) => (&shared.from_bytes, &shared.placeholder_depth, *b),
                _ => (
                    &shared.from_level,
                    &shared.placeholder_depth,
                    &self.levels[level - 1].1,
                ),
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
        if (20..30).contains(&x) && (24..34).contains(&y) {
            10
        } else {
            (x + 2 * y) as u8
        }
    }

    /// Every texel of a map lies between its cell's two planes at every
    /// level, and cells on the sloped plane alone are bounded tightly (the
    /// planes follow it): a min/max chain there spans the cell's slope,
    /// 24/255 at level 0, and a misread gather order breaks the bound.
    #[test]
    fn bounds_chain_holds_every_texel_and_follows_a_sloped_plane() {
        let gpu = GpuContext::new(None).expect("a Vulkan adapter (install mesa-vulkan-drivers)");
        let map = crate::gpu::texture_2d(
            &gpu.device,
            "edge mask test map",
            SIDE,
            SIDE,
            1,
            wgpu::TextureFormat::R8Unorm,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        let texels: Vec<u8> = (0..SIDE * SIDE)
            .map(|i| depth(i % SIDE, i / SIDE))
            .collect();
        gpu.queue.write_texture(
            map.as_image_copy(),
            &texels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(SIDE),
                rows_per_image: Some(SIDE),
            },
            map.size(),
        );
        let view = map.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let mut chain = None;
        BoundsChain::ensure(&mut chain, &gpu, SIDE, 1).unwrap();
        let chain = chain.unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        chain.record(&gpu, &mut encoder, ChainSource::Bytes(&view));
        gpu.queue.submit([encoder.finish()]);
        let mut tight = 0;
        for (level, &(side, _)) in chain.levels.iter().enumerate() {
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
                for ty in cy * cover..((cy + 1) * cover).min(SIDE) {
                    for tx in cx * cover..((cx + 1) * cover).min(SIDE) {
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
