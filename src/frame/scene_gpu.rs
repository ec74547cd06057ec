//! The scene on the GPU: every mesh in one vertex and one index buffer, the
//! object table (group 1) and one bind group per material.

use super::{FrameLayouts, Vertex, textures};
use crate::gpu::GpuContext;
use crate::scene::clusters::{CLUSTER_TRIANGLES, Cluster, Clustered, clustered};
use crate::scene::extent::SceneExtent;
use crate::scene::opacity::OpacityMaps;
use crate::scene::topology::{SolidKind, Solidity, parts_meeting_other_meshes};
use crate::scene::{Aabb, AlphaMode, Material, Object, Scene, Texture};
use anyhow::{Context, Result, bail};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ObjectGpu {
    model: Mat4,
    normal_matrix: Mat4,
    info: [u32; 4],
    /// x: the global ID of the object's convex parts less one, y: 1 where
    /// they are not used ([`parts_meeting_other_meshes`]), z: 1 where the
    /// second half of its mesh's triangles are the back faces
    /// [`crate::scene::Mesh::make_double_sided`] added.
    parts: [u32; 4],
    /// x [`AlphaMode`] as index, y cutoff, z opacity factor, w uv scale
    /// (`f32` bits).
    alpha: [u32; 4],
    /// x first byte of its opacity map in the texel buffer, y width, z
    /// height, w levels (0: no map) in bits 0..8 and the map's wrap modes
    /// along u and v in bits 8..10 and 10..12.
    opacity_map: [u32; 4],
}

/// Every opacity map's mip chain, one byte per texel, in one buffer; where
/// each map starts.
fn opacity_texels(maps: &OpacityMaps) -> (Vec<u32>, Vec<u32>) {
    let mut bytes: Vec<u8> = vec![];
    let mut starts = vec![];
    for m in &maps.maps {
        starts.push(bytes.len() as u32);
        for level in &m.levels {
            bytes.extend_from_slice(level);
        }
    }
    // A storage binding cannot be empty.
    bytes.resize(bytes.len().next_multiple_of(4).max(4), 0);
    let words = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    (words, starts)
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MaterialGpu {
    ka: Vec4,
    kd: Vec4,
    ks: Vec4,
    proc_a: Vec4,
    proc_b: Vec4,
    flags: Vec4,
}

/// One indexed draw of one object.
#[derive(Clone, Copy, Debug)]
pub struct DrawCall {
    pub object: u32,
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    pub material: usize,
    pub casts_shadow: bool,
    pub shadow_plane: bool,
    /// How its material's opacity is used.
    pub alpha_mode: AlphaMode,
    /// What the mesh encloses ([`crate::scene::Mesh::solidity`]).
    pub solid: SolidKind,
    /// World-space bounds of the object (for culling against light views).
    pub bounds: Aabb,
    /// Its clusters: `SceneGpu::parts[first_part..first_part + part_count]`.
    pub first_part: u32,
    pub part_count: u32,
}

/// One cluster of an object's triangles ([`crate::scene::clusters`]).
#[derive(Clone, Copy, Debug)]
pub struct DrawPart {
    pub first_index: u32,
    pub index_count: u32,
    /// World-space bounds of the cluster.
    pub bounds: Aabb,
}

/// The scene's GPU buffers: all meshes in one vertex and one index buffer,
/// the object table and one bind group per material.
pub struct SceneGpu {
    pub vertex_buffer: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    pub object_buffer: wgpu::Buffer,
    pub object_bind_group: wgpu::BindGroup,
    pub draws: Vec<DrawCall>,
    /// Every draw call's clusters, in draw order.
    pub parts: Vec<DrawPart>,
    pub material_bind_groups: Vec<wgpu::BindGroup>,
    /// Per material, the shader features the lighting pass specialises on.
    pub material_variants: Vec<MaterialVariant>,
    pub triangle_count: usize,
    pub caster_triangle_count: usize,
    pub bounds: Aabb,
    /// The world bounds of the clusters the camera can see (every drawn
    /// object's, not the planes that only receive planar shadows).
    pub drawn_part_bounds: Vec<Aabb>,
}

/// The features of a material that select a lighting-pass variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MaterialVariant {
    pub diffuse_texture: bool,
    pub normal_map: bool,
    /// 0 none, else [`crate::scene::ProceduralKind`] as index + 1.
    pub procedural: u32,
    /// A translucent ([`AlphaMode::Blend`]) surface, blended over the
    /// opaque image.
    pub translucent: bool,
}

impl MaterialVariant {
    fn of(m: &Material) -> MaterialVariant {
        MaterialVariant {
            diffuse_texture: m.diffuse_texture.is_some(),
            normal_map: m.normal_map.is_some(),
            procedural: m.procedural.map_or(0, |p| p.kind as u32 + 1),
            translucent: m.alpha_mode == AlphaMode::Blend,
        }
    }
}

/// One draw per object (its mesh's range in the shared buffers) and the
/// clusters it is drawn in, with their world bounds.
fn draw_calls(
    scene: &Scene,
    ranges: &[(i32, u32, u32)],
    clustered: &[Clustered],
    solidity: &[Solidity],
) -> (Vec<DrawCall>, Vec<DrawPart>) {
    let mut parts = vec![];
    let draws = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let (base_vertex, first_index, index_count) = ranges[o.mesh];
            let first_part = parts.len() as u32;
            parts.extend(
                clustered[o.mesh]
                    .clusters
                    .iter()
                    .map(|c: &Cluster| DrawPart {
                        first_index: first_index + c.first_index,
                        index_count: c.index_count,
                        bounds: c.bounds.transformed(o.transform),
                    }),
            );
            DrawCall {
                object: i as u32,
                first_index,
                index_count,
                base_vertex,
                material: o.material,
                casts_shadow: o.casts_shadow,
                shadow_plane: o.shadow_plane,
                alpha_mode: scene.materials[o.material].alpha_mode,
                solid: solidity[o.mesh].kind,
                bounds: scene.meshes[o.mesh].bounds().transformed(o.transform),
                first_part,
                part_count: parts.len() as u32 - first_part,
            }
        })
        .collect();
    (draws, parts)
}

/// Object `o`'s row of the object table: transforms, flags, its parts'
/// first ID and whether they are used (`parts`), whether its mesh has
/// back faces added, its material's alpha terms and its opacity map.
fn object_gpu(
    scene: &Scene,
    o: &Object,
    parts: [u32; 2],
    solidity: &[Solidity],
    opacity_maps: &OpacityMaps,
    map_starts: &[u32],
) -> ObjectGpu {
    ObjectGpu {
        model: o.transform,
        normal_matrix: o.transform.inverse().transpose(),
        info: [
            o.material as u32,
            o.casts_shadow as u32,
            o.receives_shadow as u32,
            match solidity[o.mesh].kind {
                SolidKind::NotSolid => 0,
                SolidKind::Convex => 1,
                SolidKind::Concave => 2,
            },
        ],
        parts: [
            parts[0],
            parts[1],
            scene.meshes[o.mesh].sides_doubled as u32,
            0,
        ],
        alpha: {
            let m = &scene.materials[o.material];
            [
                m.alpha_mode as u32,
                m.alpha_cutoff.to_bits(),
                m.alpha.to_bits(),
                m.uv_scale.to_bits(),
            ]
        },
        opacity_map: {
            let m = &scene.materials[o.material];
            match (m.alpha_texture, opacity_maps.for_material(m)) {
                (Some(t), Some(map)) => [
                    map_starts[opacity_maps.of_texture[&t]],
                    map.width,
                    map.height,
                    map.levels.len() as u32 | map.wrap[0].index() << 8 | map.wrap[1].index() << 10,
                ],
                _ => [0; 4],
            }
        },
    }
}

/// A buffer made with `contents`.
fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage,
    })
}

/// The wrap modes of `texture` (repeat where there is none) as u + 4·v,
/// for `surface_colors` in scene.wgsl.
fn wrap_code(texture: Option<usize>, textures: &[Texture]) -> u32 {
    let [u, v] = texture.map_or(Default::default(), |t| textures[t].wrap);
    u.index() + 4 * v.index()
}

/// Material `m`'s bind group: its uniform, its diffuse texture and normal
/// map (of the scene's `textures`, uploaded as `gpu_textures`; `[white,
/// flat normal]` where it has none).
fn material_group(
    gpu: &GpuContext,
    layouts: &FrameLayouts,
    m: &Material,
    (textures, gpu_textures): (&[Texture], &[wgpu::TextureView]),
    [white, flat_normal]: [&wgpu::TextureView; 2],
) -> wgpu::BindGroup {
    let device = &gpu.device;
    let proc_kind = m.procedural.map_or(0.0, |p| p.kind as u32 as f32 + 1.0);
    let p = m.procedural;
    let data = MaterialGpu {
        ka: m.ka.extend(m.uv_scale),
        kd: m.kd.extend(m.diffuse_texture.is_some() as u32 as f32),
        ks: m.ks.extend(m.shininess.max(1.0)),
        proc_a: p.map_or(Vec3::ZERO, |p| p.color_a).extend(proc_kind),
        proc_b: p
            .map_or(Vec3::ZERO, |p| p.color_b)
            .extend(p.map_or(1.0, |p| p.scale)),
        flags: Vec4::new(
            m.normal_map.is_some() as u32 as f32,
            p.map_or(0.0, |p| p.octaves as f32),
            m.alpha,
            wrap_code(m.diffuse_texture, textures) as f32
                + 16.0 * wrap_code(m.normal_map, textures) as f32,
        ),
    };
    let buf = buffer_init(
        device,
        "material",
        bytemuck::bytes_of(&data),
        gpu.uniform_space.usage(),
    );
    let diffuse = m.diffuse_texture.map_or(white, |t| &gpu_textures[t]);
    let normal = m.normal_map.map_or(flat_normal, |t| &gpu_textures[t]);
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(&m.name),
        layout: &layouts.material,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(diffuse),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(normal),
            },
        ],
    })
}

impl SceneGpu {
    /// Uploads a scene: meshes, object table, materials and textures.
    pub fn upload(gpu: &GpuContext, scene: &Scene) -> Result<SceneGpu> {
        let layouts = FrameLayouts::of(gpu);
        let device = &gpu.device;
        let mut vertices: Vec<Vertex> = vec![];
        let mut indices: Vec<u32> = vec![];
        let mut ranges = vec![];
        let clustered: Vec<_> = scene
            .meshes
            .par_iter()
            .map(|m| clustered(m, CLUSTER_TRIANGLES))
            .collect();
        let solidity: Vec<Solidity> = scene.meshes.par_iter().map(|m| m.solidity()).collect();
        for ((m, c), s) in scene.meshes.iter().zip(&clustered).zip(&solidity) {
            let base = vertices.len() as i32;
            let first = indices.len() as u32;
            vertices.extend((0..m.positions.len()).map(|i| Vertex {
                position: m.positions[i].into(),
                normal: m.normals[i].into(),
                uv: m.uvs[i].into(),
                tangent: m.tangents[i].into(),
                part: s.vertex_parts[i],
                color: Vertex::encode_color(m.colors.get(i).copied().unwrap_or(Vec3::ONE)),
            }));
            indices.extend_from_slice(&c.indices);
            ranges.push((base, first, m.indices.len() as u32));
        }
        if vertices.is_empty() || indices.is_empty() {
            bail!("scene '{}' has no triangles", scene.name);
        }
        // Each object's parts take the next IDs after the previous object's.
        let mut next_part = 0u32;
        let mut part_bases = Vec::with_capacity(scene.objects.len());
        for o in &scene.objects {
            part_bases.push(next_part);
            next_part = next_part
                .checked_add(solidity[o.mesh].parts)
                .filter(|&n| n < u32::MAX)
                .with_context(|| {
                    format!("scene '{}' has more than 2^32 convex parts", scene.name)
                })?;
        }
        let opacity_maps = OpacityMaps::of(scene);
        let (texels, map_starts) = opacity_texels(&opacity_maps);
        let parts_unused = parts_meeting_other_meshes(scene, &solidity);
        let objects: Vec<ObjectGpu> = scene
            .objects
            .iter()
            .zip(&part_bases)
            .zip(&parts_unused)
            .map(|((o, &part_base), &unused)| {
                let parts = [part_base, unused as u32];
                object_gpu(scene, o, parts, &solidity, &opacity_maps, &map_starts)
            })
            .collect();
        let (draws, parts) = draw_calls(scene, &ranges, &clustered, &solidity);
        let init =
            |label: &str, contents: &[u8], usage| buffer_init(device, label, contents, usage);
        let storage_ro = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let vertex_buffer = init(
            "vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX | storage_ro,
        );
        let index_buffer = init(
            "indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX | storage_ro,
        );
        let object_buffer = init("objects", bytemuck::cast_slice(&objects), storage_ro);
        let opacity_buffer = init("opacity maps", bytemuck::cast_slice(&texels), storage_ro);
        let object_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("objects"),
            layout: &layouts.objects,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: object_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: opacity_buffer.as_entire_binding(),
                },
            ],
        });
        let gpu_textures: Vec<wgpu::TextureView> = scene
            .textures
            .iter()
            .map(|t| textures::upload(gpu, t))
            .collect();
        let white = textures::solid(gpu, [255, 255, 255, 255], true);
        let flat_normal = textures::solid(gpu, [128, 128, 255, 255], false);
        let material_bind_groups = scene
            .materials
            .iter()
            .map(|m| {
                let textures = (&scene.textures[..], &gpu_textures[..]);
                material_group(gpu, &layouts, m, textures, [&white, &flat_normal])
            })
            .collect();
        let drawn_part_bounds = draws
            .iter()
            .filter(|d| !d.shadow_plane)
            .flat_map(|d| &parts[d.first_part as usize..(d.first_part + d.part_count) as usize])
            .map(|p| p.bounds)
            .collect();
        Ok(SceneGpu {
            vertex_buffer,
            index_buffer,
            object_buffer,
            object_bind_group,
            draws,
            parts,
            material_bind_groups,
            material_variants: scene.materials.iter().map(MaterialVariant::of).collect(),
            triangle_count: scene.triangle_count(),
            caster_triangle_count: scene.caster_triangle_count(),
            bounds: scene.bounds(),
            drawn_part_bounds,
        })
    }

    /// The scene as the light's views are fitted to it.
    pub fn extent(&self) -> SceneExtent<'_> {
        SceneExtent {
            bounds: &self.bounds,
            parts: &self.drawn_part_bounds,
        }
    }

    /// Binds the vertex and index buffers and draws every non-plane object
    /// that `filter` accepts, with `instance_index` = object id; returns the
    /// number of triangles drawn. The caller sets pipeline and bind groups 0
    /// and 1.
    pub fn draw_objects(
        &self,
        pass: &mut wgpu::RenderPass,
        filter: impl Fn(&DrawCall) -> bool,
    ) -> u64 {
        self.draw_visible(pass, filter, |_| true)
    }

    /// Like [`Self::draw_objects`] for a view with a culling test: draws,
    /// of each object that `filter` accepts and whose bounds `visible`
    /// accepts, only the clusters whose bounds it accepts (consecutive ones
    /// in one draw: an object wholly seen is one draw); returns the number
    /// of triangles drawn.
    pub fn draw_visible(
        &self,
        pass: &mut wgpu::RenderPass,
        filter: impl Fn(&DrawCall) -> bool,
        visible: impl Fn(&Aabb) -> bool,
    ) -> u64 {
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        let mut triangles = 0;
        let mut draw = |indices: std::ops::Range<u32>, d: &DrawCall| {
            triangles += indices.len() as u64 / 3;
            pass.draw_indexed(indices, d.base_vertex, d.object..d.object + 1);
        };
        for d in self
            .draws
            .iter()
            .filter(|d| !d.shadow_plane && filter(d) && visible(&d.bounds))
        {
            let parts = &self.parts[d.first_part as usize..(d.first_part + d.part_count) as usize];
            let whole = parts.len() == 1;
            // The run of consecutive visible clusters not yet drawn.
            let mut run: Option<std::ops::Range<u32>> = None;
            for p in parts {
                if whole || visible(&p.bounds) {
                    let end = p.first_index + p.index_count;
                    run = Some(run.map_or(p.first_index..end, |r| r.start..end));
                } else if let Some(r) = run.take() {
                    draw(r, d);
                }
            }
            if let Some(r) = run {
                draw(r, d);
            }
        }
        triangles
    }
}

#[cfg(test)]
mod wgsl_tests {
    use super::*;

    /// The frame uniform, its lights and the object table are laid out as
    /// `Frame`, `LightGpu` and `ObjectGpu` of common.wgsl, its alpha modes
    /// are `AlphaMode`'s, and the material uniform is `MaterialGpu` of
    /// scene.wgsl.
    #[test]
    fn the_shared_structs_match_common_wgsl() {
        use crate::gpu::wgsl_layout::assert_struct_matches;
        use std::mem::size_of;
        let source = crate::frame::COMMON_WGSL;
        assert_struct_matches(
            source,
            "Frame",
            crate::field_offsets!(crate::frame::FrameUniform; view_proj, inv_view_proj, view,
                proj, camera_pos, ambient, size, lights),
            size_of::<crate::frame::FrameUniform>(),
        );
        assert_struct_matches(
            source,
            "LightGpu",
            crate::field_offsets!(crate::frame::LightGpu; position, direction, color),
            size_of::<crate::frame::LightGpu>(),
        );
        let lighting = [
            source,
            include_str!("../renderer/procedural.wgsl"),
            include_str!("../renderer/scene.wgsl"),
        ]
        .join("\n");
        assert_struct_matches(
            &lighting,
            "MaterialGpu",
            crate::field_offsets!(MaterialGpu; ka, kd, ks, proc_a, proc_b, flags),
            size_of::<MaterialGpu>(),
        );
        crate::gpu::wgsl_layout::assert_consts_match(
            source,
            &[
                ("ALPHA_OPAQUE", AlphaMode::Opaque as u32),
                ("ALPHA_MASK", AlphaMode::Mask as u32),
                ("ALPHA_BLEND", AlphaMode::Blend as u32),
            ],
        );
        assert_struct_matches(
            source,
            "ObjectGpu",
            crate::field_offsets!(ObjectGpu; model, normal_matrix, info, parts, alpha,
                opacity_map),
            size_of::<ObjectGpu>(),
        );
    }
}
