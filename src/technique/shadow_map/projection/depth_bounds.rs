//! SDSM's depth bounds (Lauritzen, Salvi & Lefohn 2011): a GPU reduction
//! of the prepass G-buffer to the view depths the camera actually sees and,
//! per cascade, the light-view x/y bounds of the pixels it shades
//! (`depth_bounds.wgsl`). Measurements wait for this frame's result; the
//! viewer reads the latest that has arrived, a frame late, without a stall
//! ([`Feedback`]), and widens it for the camera's motion in between.

use super::roll::{DIRECTIONS, Supports};
use crate::gpu::{FrameFeedback, GpuContext, SectionTimer};
use crate::technique::shadow_map::config::partition::Fit;
use crate::technique::{Feedback, MaskContext};
use anyhow::Result;
use glam::{Mat4, UVec4, Vec3, Vec4};
use std::sync::Arc;

/// At most this many cascades (the uniform's split arrays).
const MAX_CASCADES: usize = 8;
/// Result words: least and greatest depth, 4 per cascade, then the least
/// and greatest extent along each support direction (`roll::Supports`).
const SUPPORT_WORD: usize = 2 + 4 * MAX_CASCADES;
const WORDS: usize = SUPPORT_WORD + 2 * DIRECTIONS;
const RESULT_BYTES: u64 = (WORDS * 4) as u64;
/// Pixels along each axis of the block one invocation reduces
/// (`depth_bounds.wgsl`'s `TILE`).
const TILE: u32 = 8;
/// Pixels per workgroup along each axis: 8×8 invocations of `TILE`² pixels.
const WORKGROUP_PIXELS: u32 = 8 * TILE;
const BLOCKS_LABEL: &str = "sdsm block bounds";
/// Bytes of one block's record (`BlockBounds`: vec2f, then vec4f at 16).
const BLOCK_RECORD_BYTES: u64 = 32;

/// A frame-late result covers this much more depth (factor on far, its
/// inverse on near) and x/y extent (fraction of each half-extent per side).
const LATE_DEPTH_FACTOR: f32 = 1.25;
const LATE_XY_MARGIN: f32 = 0.1;

/// What the camera saw: view depths of the receiving pixels and, with
/// `fit=samples`, per cascade the light-view x/y box of its pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct SeenBounds {
    pub near: f32,
    pub far: f32,
    /// Per cascade `[min x, min y, max x, max y]`; `None` for a cascade
    /// that shades no pixel. Empty unless the fit is `samples`.
    pub cascades_xy: Vec<Option<[f32; 4]>>,
    /// A single map fitted to the samples: their extents along the support
    /// directions of the light view's image (its turns' boxes).
    pub supports: Option<Supports>,
}

impl SeenBounds {
    /// Widened for a camera that may have moved since it was measured.
    fn widened(&self) -> SeenBounds {
        SeenBounds {
            near: self.near / LATE_DEPTH_FACTOR,
            far: self.far * LATE_DEPTH_FACTOR,
            cascades_xy: self
                .cascades_xy
                .iter()
                .map(|b| {
                    b.map(|[x0, y0, x1, y1]| {
                        let (mx, my) = (
                            (x1 - x0) * 0.5 * LATE_XY_MARGIN,
                            (y1 - y0) * 0.5 * LATE_XY_MARGIN,
                        );
                        [x0 - mx, y0 - my, x1 + mx, y1 + my]
                    })
                })
                .collect(),
            supports: self.supports.map(|s| s.widened(LATE_XY_MARGIN)),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ReduceParams {
    view_z: Vec4,
    light_view: Mat4,
    split: Vec4,
    /// x, y: blocks of `TILE`² pixels along x and y.
    blocks: UVec4,
    /// A spot light's image (`ReduceInputs::spot`): x the tangent of its
    /// cone's half-angle, yzw its position; x = 0 for a directional view.
    spot: Vec4,
}

/// What the reduction needs from the light set-up.
pub struct ReduceInputs {
    pub fit: Fit,
    pub light_view: Mat4,
    /// One map fitted to the samples: take the extents along the support
    /// directions (for its turn, `roll`) instead of the cascades' boxes.
    pub supports: bool,
    /// A spot light's map (`light_view` its view): the extents are taken in
    /// its image (x/−z, y/−z) over the pixels it reaches — inside its cone
    /// and facing it ([`Light::reaches`](crate::scene::Light::reaches)).
    pub spot: Option<SpotImage>,
    pub cascades: u32,
    pub split_lambda: f32,
    /// The farthest split allowed (`max_distance`, else the camera's far).
    pub far_limit: f32,
}

/// What the reduction needs of a spot light.
#[derive(Clone, Copy, Debug)]
pub struct SpotImage {
    /// Tangent of the cone's half-angle.
    pub cone_tan: f32,
    pub position: Vec3,
}

/// The device's reduction programs.
struct ReduceShared {
    layout: wgpu::BindGroupLayout,
    depth_range: wgpu::ComputePipeline,
    /// `depth_range` with the extents along the support directions.
    depth_range_supports: wgpu::ComputePipeline,
    cascade_bounds: wgpu::ComputePipeline,
}

impl ReduceShared {
    fn new(gpu: &GpuContext) -> ReduceShared {
        let device = &gpu.device;
        let texture = |binding| {
            crate::gpu::sampled_texture_entry(
                binding,
                wgpu::ShaderStages::COMPUTE,
                wgpu::TextureSampleType::Float { filterable: false },
                wgpu::TextureViewDimension::D2,
            )
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sdsm reduction"),
            entries: &[
                texture(0),
                texture(1),
                crate::gpu::uniform_entry(gpu, 2, wgpu::ShaderStages::COMPUTE, false),
                crate::gpu::storage_entry(3, wgpu::ShaderStages::COMPUTE, false),
                crate::gpu::storage_entry(4, wgpu::ShaderStages::COMPUTE, false),
            ],
        });
        let source = include_str!("depth_bounds.wgsl");
        let [depth_range, cascade_bounds] = crate::gpu::compute_pipelines(
            gpu,
            "sdsm reduction",
            &layout,
            source,
            ["depth_range", "cascade_bounds"],
        );
        let [depth_range_supports] = crate::gpu::compute_pipelines_with(
            gpu,
            "sdsm reduction with supports",
            &layout,
            source,
            ["depth_range"],
            &[("SUPPORTS", 1.0)],
        );
        ReduceShared {
            depth_range,
            depth_range_supports,
            cascade_bounds,
            layout,
        }
    }
}

/// One light's reduction: its buffers and the latest result.
pub struct DepthReduction {
    shared: Arc<ReduceShared>,
    params: wgpu::Buffer,
    result: wgpu::Buffer,
    /// Per block of pixels, its depth range and light-view box (grown to
    /// the frame's size).
    blocks: wgpu::Buffer,
    feedback: FrameFeedback,
    latest: Option<SeenBounds>,
    /// GPU time of the reduction's passes (counter `sdsm_reduction_ms`).
    pub timer: SectionTimer,
    /// Wall time of the last waited-for reduction, from its submission to
    /// the bounds on the CPU (counter `sdsm_wait_ms`): the GPU's work
    /// before it, the passes and the read-back.
    pub wait_ms: f64,
}

impl DepthReduction {
    pub fn new(gpu: &GpuContext) -> DepthReduction {
        let buffer = |label, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: RESULT_BYTES,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        DepthReduction {
            shared: gpu.cache.shared(|| ReduceShared::new(gpu)),
            params: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("sdsm reduction parameters"),
                size: std::mem::size_of::<ReduceParams>() as u64,
                usage: crate::gpu::uniform_usage(gpu),
                mapped_at_creation: false,
            }),
            result: buffer("sdsm bounds", U::STORAGE | U::COPY_SRC | U::COPY_DST),
            blocks: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(BLOCKS_LABEL),
                size: BLOCK_RECORD_BYTES,
                usage: U::STORAGE,
                mapped_at_creation: false,
            }),
            feedback: FrameFeedback::new(&gpu.device, "sdsm bounds read-back", RESULT_BYTES),
            latest: None,
            timer: SectionTimer::new("sdsm reduction timestamps"),
            wait_ms: 0.0,
        }
    }

    /// What the camera sees for this frame's set-up: this frame's (waiting
    /// for the GPU) or, with [`Feedback::PreviousFrame`], the latest arrived,
    /// widened; `None` while nothing has arrived or nothing receives.
    pub fn seen(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ReduceInputs,
    ) -> Result<Option<SeenBounds>> {
        let gpu = ctx.gpu;
        let cascades = inputs.cascades.min(MAX_CASCADES as u32);
        let samples = inputs.fit == Fit::Samples;
        let wait = ctx.feedback == Feedback::ThisFrame;
        let start = crate::clock::Instant::now();
        let mut own = FrameFeedback::own_encoder(gpu, wait);
        self.record(ctx, own.as_mut().unwrap_or(&mut *encoder), inputs);
        let bytes = self
            .feedback
            .collect(gpu, own, encoder, &self.result, RESULT_BYTES)?;
        if let Some(bytes) = bytes {
            self.latest = decode(&bytes, cascades as usize, samples, inputs.supports);
        }
        if wait {
            self.wait_ms = start.elapsed().as_secs_f64() * 1e3;
            Ok(self.latest.clone())
        } else {
            Ok(self.latest.as_ref().map(SeenBounds::widened))
        }
    }

    /// After the frame's submission: asks for the frame-late result and
    /// the passes' timestamps.
    pub fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        self.feedback.after_frame();
        self.timer.after_frame(gpu)
    }

    /// Records the reduction of the frame's G-buffer into `encoder`, its
    /// passes timed.
    fn record(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ReduceInputs,
    ) {
        let gpu = ctx.gpu;
        let (bx, by) = (
            ctx.fit_frame.width().div_ceil(TILE),
            ctx.fit_frame.height().div_ceil(TILE),
        );
        let block_bytes = (bx * by) as u64 * BLOCK_RECORD_BYTES;
        crate::gpu::grow_buffer(&gpu.device, &mut self.blocks, block_bytes, BLOCKS_LABEL);
        let params = ReduceParams {
            view_z: ctx.fit_camera.view().row(2),
            light_view: inputs.light_view,
            split: Vec4::new(
                inputs.cascades.min(MAX_CASCADES as u32) as f32,
                inputs.split_lambda,
                ctx.fit_camera.near,
                inputs.far_limit,
            ),
            blocks: UVec4::new(bx, by, 0, 0),
            spot: inputs.spot.map_or(Vec4::ZERO, |s| {
                Vec4::new(s.cone_tan, s.position.x, s.position.y, s.position.z)
            }),
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        // Empty bounds: least values at the top of the order, greatest at 0.
        let mut empty = [0u32; WORDS];
        empty[0] = u32::MAX;
        for c in 0..MAX_CASCADES {
            empty[2 + 4 * c] = u32::MAX;
            empty[3 + 4 * c] = u32::MAX;
        }
        for k in 0..DIRECTIONS {
            empty[SUPPORT_WORD + 2 * k] = u32::MAX;
        }
        gpu.queue
            .write_buffer(&self.result, 0, bytemuck::cast_slice(&empty));
        let [position, normal] = ctx.fit_frame.gbuffer_views();
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sdsm reduction"),
            layout: &self.shared.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(position),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(normal),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: self.result.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: self.blocks.as_entire_binding(),
                },
            ],
        });
        let groups = |n: u32| n.div_ceil(WORKGROUP_PIXELS);
        let (w, h) = (
            groups(ctx.fit_frame.width()),
            groups(ctx.fit_frame.height()),
        );
        let passes = match (inputs.fit, inputs.supports) {
            (Fit::Samples, true) => vec![&self.shared.depth_range_supports],
            (Fit::Samples, false) => vec![&self.shared.depth_range, &self.shared.cascade_bounds],
            _ => vec![&self.shared.depth_range],
        };
        // One pass per step: the second reads what the first wrote.
        self.timer.time(gpu, encoder, |encoder| {
            for pipeline in passes {
                let mut pass = gpu.compute_pass(
                    encoder,
                    &wgpu::ComputePassDescriptor {
                        label: Some("sdsm reduction"),
                        timestamp_writes: None,
                    },
                );
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(w, h, 1);
            }
        });
    }
}

/// The float of `depth_bounds.wgsl`'s order-preserving bits.
fn from_ordered(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 {
        u ^ 0x8000_0000
    } else {
        !u
    })
}

/// The bounds in a result buffer; `None` when no pixel receives.
fn decode(bytes: &[u8], cascades: usize, samples: bool, supports: bool) -> Option<SeenBounds> {
    let words: &[u32] = bytemuck::cast_slice(&bytes[..RESULT_BYTES as usize]);
    if words[0] == u32::MAX {
        return None;
    }
    let cascades_xy = if samples && !supports {
        (0..cascades)
            .map(|c| {
                let w = &words[2 + 4 * c..6 + 4 * c];
                (w[0] != u32::MAX).then(|| [0, 1, 2, 3].map(|k| from_ordered(w[k])))
            })
            .collect()
    } else {
        vec![]
    };
    Some(SeenBounds {
        near: from_ordered(words[0]),
        far: from_ordered(words[1]),
        cascades_xy,
        supports: supports.then(|| {
            Supports(std::array::from_fn(|k| {
                [0, 1].map(|e| from_ordered(words[SUPPORT_WORD + 2 * k + e]))
            }))
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `ReduceParams`, the block record and the word layout of
    /// depth_bounds.wgsl are the ones declared here.
    #[test]
    fn the_reduction_interface_matches_its_wgsl() {
        use crate::gpu::wgsl_layout::{assert_consts_match, assert_struct_matches, wgsl_struct};
        let source = include_str!("depth_bounds.wgsl");
        assert_struct_matches(
            source,
            "ReduceParams",
            crate::field_offsets!(ReduceParams; view_z, light_view, split, blocks, spot),
            std::mem::size_of::<ReduceParams>(),
        );
        let (fields, size) = wgsl_struct(source, "BlockBounds");
        assert_eq!(fields.iter().map(|f| f.1).collect::<Vec<_>>(), [0, 16]);
        assert_eq!(size as u64, BLOCK_RECORD_BYTES);
        assert_consts_match(
            source,
            &[
                ("MAX_CASCADES", MAX_CASCADES as u32),
                ("SUPPORT_WORD", SUPPORT_WORD as u32),
                ("TILE", TILE),
            ],
        );
    }

    /// The WGSL's `ordered` mapping, for the test.
    fn ordered(f: f32) -> u32 {
        let b = f.to_bits();
        if b & 0x8000_0000 != 0 {
            !b
        } else {
            b ^ 0x8000_0000
        }
    }

    #[test]
    fn ordered_bits_sort_like_their_floats_and_decode_back() {
        let v = [-1e9f32, -3.5, -1e-20, 0.0, 1e-20, 0.25, 7.0, 1e9];
        for w in v.windows(2) {
            assert!(ordered(w[0]) < ordered(w[1]), "{} {}", w[0], w[1]);
        }
        for x in v {
            assert_eq!(from_ordered(ordered(x)), x);
        }
    }
}
