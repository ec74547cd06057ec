//! Light icons ([000] §5): a sphere for point lights, an arrow for
//! directional lights, an arrow inside a cone for spot lights; unlit, in the
//! light's colour, sized from the scene bounds.

use super::overlay::OverlayPipeline;
use crate::frame::{FrameTargets, MAX_LIGHTS};
use crate::gpu::GpuContext;
use crate::scene::{Aabb, Light, LightType, Mesh, shapes};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct IconVertex {
    position: [f32; 3],
    normal: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct IconUniform {
    model: Mat4,
    color: Vec4,
    _pad: [Vec4; 11],
}

struct IconMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

pub struct LightIcons {
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// point, directional, spot
    meshes: [IconMesh; 3],
}

/// Arrow along −y from the origin: shaft and head, unit length.
fn arrow() -> Mesh {
    let mut m = Mesh::default();
    let shaft = shapes::cylinder(0.06, 0.7, 12);
    m.append(&shaft, Mat4::from_rotation_x(std::f32::consts::PI));
    let head = shapes::lathe(
        "head",
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(0.16, 0.0),
            Vec2::new(0.0, 0.3),
        ],
        16,
    );
    m.append(&head, Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0)));
    m
}

fn upload(device: &wgpu::Device, mut m: Mesh) -> IconMesh {
    m.finalize().expect("icon meshes are valid");
    let v: Vec<IconVertex> = m
        .positions
        .iter()
        .zip(&m.normals)
        .map(|(p, n)| IconVertex {
            position: p.to_array(),
            normal: n.to_array(),
        })
        .collect();
    IconMesh {
        vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("icon vertices"),
            contents: bytemuck::cast_slice(&v),
            usage: wgpu::BufferUsages::VERTEX,
        }),
        indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("icon indices"),
            contents: bytemuck::cast_slice(&m.indices),
            usage: wgpu::BufferUsages::INDEX,
        }),
        count: m.indices.len() as u32,
    }
}

impl LightIcons {
    pub fn new(gpu: &GpuContext, frame_layout: &wgpu::BindGroupLayout) -> LightIcons {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("icon"),
            entries: &[crate::gpu::uniform_entry(
                gpu,
                0,
                wgpu::ShaderStages::VERTEX_FRAGMENT,
                true,
            )],
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("icon uniforms"),
            size: (std::mem::size_of::<IconUniform>() * MAX_LIGHTS) as u64,
            usage: crate::gpu::uniform_usage(gpu),
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("icon"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: crate::gpu::dynamic_uniform::<IconUniform>(&uniforms),
            }],
        });
        let device = &gpu.device;
        let module = crate::frame::shader_module(gpu, "icons", &[include_str!("icons.wgsl")]);
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("icons"),
            bind_group_layouts: &[Some(frame_layout), None, Some(&layout)],
            immediate_size: 0,
        });
        let mut spot = arrow();
        let cone = shapes::lathe("cone", &[Vec2::new(0.45, 0.0), Vec2::new(0.0, 0.9)], 24);
        spot.append(&cone, Mat4::from_translation(Vec3::new(0.0, -0.9, 0.0)));
        LightIcons {
            module,
            layout: pl,
            uniforms,
            bind_group,
            meshes: [
                upload(device, shapes::sphere(0.25, 16, 8)),
                upload(device, arrow()),
                upload(device, spot),
            ],
        }
    }

    /// The pipeline drawing into a colour image of `color_format`.
    fn pipeline(
        &self,
        gpu: &GpuContext,
        color_format: wgpu::TextureFormat,
    ) -> wgpu::RenderPipeline {
        OverlayPipeline {
            label: "icons",
            layout: &self.layout,
            module: &self.module,
            vertex_entry: "vs_icon",
            fragment_entry: "fs_icon",
            vertex_buffer: wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<IconVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            },
            topology: wgpu::PrimitiveTopology::TriangleList,
            blend: None,
        }
        .get(gpu, color_format)
    }

    /// Model matrix of a light's icon: at the light (directional lights:
    /// outside the scene bounds, up-light), −y turned to the light direction.
    pub fn icon_transform(light: &Light, bounds: &Aabb) -> Mat4 {
        let radius = if bounds.is_empty() {
            1.0
        } else {
            bounds.size().length() * 0.5
        };
        let scale = (radius * 0.08).max(1e-3);
        let pos = match light.kind {
            LightType::Directional => {
                bounds.center() - light.direction.normalize_or_zero() * radius * 0.9
            }
            _ => light.position,
        };
        let rot = Quat::from_rotation_arc(Vec3::NEG_Y, light.direction.normalize_or(Vec3::NEG_Y));
        Mat4::from_scale_rotation_translation(Vec3::splat(scale), rot, pos)
    }

    pub fn draw(
        &self,
        gpu: &GpuContext,
        pass: &mut wgpu::RenderPass,
        frame: &FrameTargets,
        lights: &[Light],
        bounds: &Aabb,
    ) {
        let data: Vec<IconUniform> = lights
            .iter()
            .map(|l| IconUniform {
                model: Self::icon_transform(l, bounds),
                color: (l.color.normalize_or(Vec3::ONE) * 1.2)
                    .min(Vec3::ONE)
                    .extend(1.0),
                _pad: [Vec4::ZERO; 11],
            })
            .collect();
        gpu.queue
            .write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&data));
        pass.set_pipeline(&self.pipeline(gpu, frame.color_format()));
        pass.set_bind_group(0, frame.frame_bind_group(), &[]);
        for (i, l) in lights.iter().enumerate() {
            let mesh = &self.meshes[match l.kind {
                LightType::Point => 0,
                LightType::Directional => 1,
                LightType::Spot => 2,
            }];
            pass.set_bind_group(
                2,
                &self.bind_group,
                &[(i * std::mem::size_of::<IconUniform>()) as u32],
            );
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.count, 0, 0..1);
        }
    }
}

#[cfg(test)]
mod wgsl_tests {
    /// `IconUniform` of icons.wgsl is laid out as the Rust struct (up to its
    /// padding to the uniform stride).
    #[test]
    fn the_uniform_matches_its_wgsl_struct() {
        let source = [crate::frame::COMMON_WGSL, include_str!("icons.wgsl")].join("\n");
        crate::gpu::wgsl_layout::assert_struct_matches(
            &source,
            "IconUniform",
            crate::field_offsets!(super::IconUniform; model, color),
            std::mem::offset_of!(super::IconUniform, _pad),
        );
    }
}
