//! The casters' volumes written as index lists: the welded caster geometry
//! uploaded once per scene, and each frame's extrusion — by the compute
//! shader in `extrude.wgsl` into the index buffer and indirect arguments,
//! or on the CPU ([`silhouette`](super::silhouette)) and uploaded.

use super::adjacency::Adjacency;
use super::silhouette::{self, CasterPlan, VolumeKind, VolumeMesh};
use super::{ARGS_SIZE, Args, ExtrudeParams, ShadowVolumeRenderer, buffer, entry, index_usage};
use crate::gpu::GpuContext;
use crate::scene::Scene;
use anyhow::{Result, bail};
use bytemuck::{Pod, Zeroable};
use glam::Vec4;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CasterGpu {
    light: Vec4,
    kind: u32,
    zfail: u32,
    caps: u32,
    _pad: u32,
}

/// Per-scene GPU copies of the welded caster geometry.
pub(super) struct Geometry {
    pub(super) fingerprint: u64,
    pub(super) mesh: VolumeMesh,
    pub(super) positions: wgpu::Buffer,
    pub(super) faces: wgpu::Buffer,
    pub(super) edges: wgpu::Buffer,
    pub(super) casters: wgpu::Buffer,
    /// Casters whose mesh is not closed were reported in the log.
    pub(super) reported_open: bool,
}

/// A buffer holding `data`, zero-padded to the 16 bytes a binding needs
/// (an empty scene has no casters).
fn buffer_with(
    gpu: &GpuContext,
    label: &str,
    data: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    let mut contents = data.to_vec();
    contents.resize(data.len().max(16), 0);
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &contents,
            usage,
        })
}

impl ShadowVolumeRenderer {
    /// Welds and uploads the casters of `scene` when it changed.
    pub(super) fn ensure_geometry(&mut self, gpu: &GpuContext, scene: &Scene) {
        let key = crate::scene::scene_fingerprint(scene);
        if self.geometry.as_ref().is_some_and(|g| g.fingerprint == key) {
            return;
        }
        if self.adjacency.as_ref().is_none_or(|(k, _)| *k != key) {
            let t = crate::clock::Instant::now();
            let used: Vec<bool> = (0..scene.meshes.len())
                .map(|m| {
                    scene
                        .objects
                        .iter()
                        .any(|o| o.mesh == m && o.casts_shadow && !o.shadow_plane)
                })
                .collect();
            let adjacency: Vec<Option<Adjacency>> = {
                use rayon::prelude::*;
                scene
                    .meshes
                    .par_iter()
                    .zip(&used)
                    .map(|(m, &u)| u.then(|| Adjacency::of(m)))
                    .collect()
            };
            for (m, a) in scene.meshes.iter().zip(&adjacency) {
                if let Some(a) = a {
                    log::info!("shadow-volume: mesh '{}': {}", m.name, a.summary());
                }
            }
            log::info!(
                "shadow-volume: adjacency of {} meshes in {:.1} ms",
                adjacency.iter().flatten().count(),
                t.elapsed().as_secs_f64() * 1e3
            );
            self.adjacency = Some((key, adjacency));
        }
        let mesh = VolumeMesh::new(scene, &self.adjacency.as_ref().expect("built above").1);
        let storage = wgpu::BufferUsages::STORAGE;
        self.geometry = Some(Geometry {
            fingerprint: key,
            positions: buffer_with(
                gpu,
                "shadow volume positions",
                bytemuck::cast_slice(&mesh.positions),
                storage,
            ),
            faces: buffer_with(
                gpu,
                "shadow volume faces",
                bytemuck::cast_slice(&mesh.faces),
                storage,
            ),
            edges: buffer_with(
                gpu,
                "shadow volume edges",
                bytemuck::cast_slice(&mesh.edges),
                storage,
            ),
            casters: buffer(
                &gpu.device,
                "shadow volume casters",
                (mesh.casters.len() * std::mem::size_of::<CasterGpu>()) as u64,
                storage | wgpu::BufferUsages::COPY_DST,
            ),
            mesh,
            reported_open: false,
        });
    }

    /// Writes the volumes of `plans` into the index buffer and the
    /// indirect arguments: on the GPU (records the extrusion compute pass)
    /// or on the CPU (uploads).
    pub(super) fn extrude(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        plans: &[CasterPlan],
        dark_cap: bool,
        gpu_extrusion: bool,
    ) -> Result<()> {
        let geometry = self.geometry.as_ref().expect("ensured");
        let vm = &geometry.mesh;
        // The two lists' regions of the index buffer.
        let mut bounds = [0usize; 2];
        for (c, plan) in vm.casters.iter().zip(plans) {
            bounds[plan.zfail as usize] += plan.index_bound(c, dark_cap);
        }
        let needed = ((bounds[0] + bounds[1]) * 4) as u64;
        let limits = gpu.device.limits();
        let max = if gpu_extrusion {
            limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size)
        } else {
            limits.max_buffer_size
        };
        if needed > max {
            bail!(
                "shadow-volume: the volumes may need {needed} bytes of indices, more than the device allows ({max}){}",
                if gpu_extrusion {
                    "; try --set extrusion=cpu"
                } else {
                    ""
                }
            );
        }
        if self.indices.size() < needed {
            self.indices = buffer(
                &gpu.device,
                "shadow volume indices",
                needed.next_power_of_two().min(max),
                index_usage(),
            );
        }
        let mut args = Args::default();
        for (i, list) in args.lists.iter_mut().enumerate() {
            list.instance_count = 1;
            list.first_index = if i == 0 { 0 } else { bounds[0] as u32 };
        }
        if gpu_extrusion {
            let casters: Vec<CasterGpu> = plans
                .iter()
                .map(|p| CasterGpu {
                    light: p.light,
                    kind: match p.kind {
                        VolumeKind::Skip => 0,
                        VolumeKind::Silhouette => 1,
                        VolumeKind::Triangles => 2,
                    },
                    zfail: p.zfail as u32,
                    caps: p.caps() as u32,
                    _pad: 0,
                })
                .collect();
            gpu.queue
                .write_buffer(&geometry.casters, 0, bytemuck::cast_slice(&casters));
            gpu.queue
                .write_buffer(&self.args, 0, bytemuck::bytes_of(&args));
            let params = ExtrudeParams {
                edge_count: vm.edges.len() as u32,
                face_count: vm.faces.len() as u32,
                dark_cap: dark_cap as u32,
                _pad: 0,
            };
            gpu.queue
                .write_buffer(&self.extrude_params, 0, bytemuck::bytes_of(&params));
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow volume extrusion"),
                layout: &self.shared.extrude_layout,
                entries: &[
                    entry(0, &self.extrude_params),
                    entry(1, &geometry.faces),
                    entry(2, &geometry.edges),
                    entry(3, &geometry.casters),
                    entry(4, &self.indices),
                    entry(5, &self.args),
                ],
            });
            let mut pass = gpu.compute_pass(
                encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some("shadow volume extrusion"),
                    timestamp_writes: None,
                },
            );
            pass.set_bind_group(0, &group, &[]);
            for (pipeline, n) in [
                (&self.shared.extrude_edges, vm.edges.len()),
                (&self.shared.extrude_faces, vm.faces.len()),
            ] {
                let groups = n.div_ceil(64) as u32;
                if groups > 0 {
                    pass.set_pipeline(pipeline);
                    pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
                }
            }
        } else {
            let (lists, silhouettes) = silhouette::volumes(vm, plans, dark_cap);
            for (i, list) in lists.iter().enumerate() {
                args.lists[i].index_count = list.len() as u32;
                gpu.queue.write_buffer(
                    &self.indices,
                    args.lists[i].first_index as u64 * 4,
                    bytemuck::cast_slice(list),
                );
            }
            args.silhouette_edges = silhouettes as u32;
            gpu.queue
                .write_buffer(&self.args, 0, bytemuck::bytes_of(&args));
        }
        Ok(())
    }

    /// The welded casters of `scene` (built on first use).
    pub fn volume_mesh(&mut self, gpu: &GpuContext, scene: &Scene) -> &VolumeMesh {
        self.ensure_geometry(gpu, scene);
        &self.geometry.as_ref().expect("ensured").mesh
    }

    /// Extrudes the volumes of `plans` like a frame does and reads them back:
    /// the z-pass and z-fail index lists and the silhouette edge count.
    pub fn volumes_read_back(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        plans: &[CasterPlan],
        dark_cap: bool,
        gpu_extrusion: bool,
    ) -> Result<([Vec<u32>; 2], u32)> {
        self.ensure_geometry(gpu, scene);
        gpu.checked("shadow volume read-back", || {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            self.extrude(gpu, &mut encoder, plans, dark_cap, gpu_extrusion)?;
            let copy = buffer(
                &gpu.device,
                "shadow volume index readback",
                self.indices.size(),
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            );
            encoder.copy_buffer_to_buffer(&self.indices, 0, &copy, 0, self.indices.size());
            let args_copy = buffer(
                &gpu.device,
                "shadow volume args readback",
                ARGS_SIZE,
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            );
            encoder.copy_buffer_to_buffer(&self.args, 0, &args_copy, 0, ARGS_SIZE);
            gpu.queue.submit([encoder.finish()]);
            let indices: Vec<u32> = bytemuck::cast_slice(&gpu.read_buffer(&copy)?).to_vec();
            let args: Args =
                bytemuck::pod_read_unaligned(&gpu.read_buffer(&args_copy)?[..ARGS_SIZE as usize]);
            let lists = args.lists.map(|l| {
                indices[l.first_index as usize..(l.first_index + l.index_count) as usize].to_vec()
            });
            Ok((lists, args.silhouette_edges))
        })
    }
}

/// Test support: `Face`, `Edge` (its two faces flattened to `f0`, `f1`) and
/// `Caster` of extrude.wgsl are laid out as the Rust structs the extrusion
/// uploads.
#[cfg(test)]
pub fn assert_buffers_match_wgsl(source: &str) {
    use super::adjacency::Edge;
    use super::silhouette::Face;
    use crate::gpu::wgsl_layout::assert_struct_matches;
    use std::mem::{offset_of, size_of};
    assert_struct_matches(
        source,
        "Face",
        crate::field_offsets!(Face; v, caster, plane),
        size_of::<Face>(),
    );
    let faces = offset_of!(Edge, faces);
    assert_struct_matches(
        source,
        "Edge",
        &[
            ("a", offset_of!(Edge, a)),
            ("b", offset_of!(Edge, b)),
            ("f0", faces),
            ("f1", faces + size_of::<u32>()),
        ],
        size_of::<Edge>(),
    );
    assert_struct_matches(
        source,
        "Caster",
        crate::field_offsets!(CasterGpu; light, kind, zfail, caps, _pad),
        size_of::<CasterGpu>(),
    );
}
