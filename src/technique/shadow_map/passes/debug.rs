//! The shadow-map family's debug views: face 0 of the map (256²), the map
//! projected onto the scene (tinted per cascade), the texels per pixel, and
//! the numbers `compare` reads (texel footprint, partition looked up).

use crate::gpu::GpuContext;
use crate::technique::shadow_map::gpu::LOOKUP_FORMAT;
use crate::technique::shadow_map::gpu::pipelines::LookupKey;
use crate::technique::shadow_map::{ShadowMapTechnique, clear_op};
use crate::technique::{DebugImage, DebugViews, MapLookup, MaskContext, frustum_lines};
use anyhow::Result;

impl ShadowMapTechnique {
    /// With debug views on, renders them from the lookup bind group at
    /// `offset` (the last map sample's face 0).
    pub(in crate::technique::shadow_map) fn render_debug(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        lookup_group: &wgpu::BindGroup,
        lookup_key: LookupKey,
        offset: u32,
    ) {
        if !self.want_debug {
            return;
        }
        let t = self.debug.get_or_insert_with(|| {
            crate::gpu::texture_2d(
                &ctx.gpu.device,
                "shadow map debug",
                256,
                256,
                1,
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            )
        });
        // Face 0 of the (last) map, for the viewer.
        let view = t.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map debug"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: clear_op(wgpu::Color::BLACK),
            })],
            ..Default::default()
        });
        pass.set_pipeline(&self.shared.debug_map(ctx.gpu, lookup_key));
        ctx.bind_frame_groups(&mut pass);
        pass.set_bind_group(crate::frame::OWN_GROUP, lookup_group, &[offset]);
        pass.draw(0..3, 0..1);
        drop(pass);
        // The frame-sized views, (re)made at the frame's size.
        let (w, h) = (ctx.frame.width(), ctx.frame.height());
        if self
            .debug_frame
            .as_ref()
            .is_none_or(|t| (t[0].width(), t[0].height()) != (w, h))
        {
            let formats = [
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureFormat::Rgba8Unorm,
                LOOKUP_FORMAT,
            ];
            self.debug_frame = Some(formats.map(|format| {
                crate::gpu::texture_2d(
                    &ctx.gpu.device,
                    "shadow map debug frame",
                    w,
                    h,
                    1,
                    format,
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                )
            }));
        }
        let views = self
            .debug_frame
            .as_ref()
            .expect("made above")
            .each_ref()
            .map(|t| t.create_view(&Default::default()));
        let attachments = views.each_ref().map(|v| {
            Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: clear_op(wgpu::Color::BLACK),
            })
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map debug frame"),
            color_attachments: &attachments,
            ..Default::default()
        });
        pass.set_pipeline(&self.shared.debug_frame(ctx.gpu, lookup_key));
        ctx.bind_frame_groups(&mut pass);
        pass.set_bind_group(crate::frame::OWN_GROUP, lookup_group, &[offset]);
        pass.draw(0..3, 0..1);
    }

    pub(in crate::technique::shadow_map) fn read_debug_views(
        &self,
        gpu: &GpuContext,
    ) -> Result<DebugViews> {
        let mut views = DebugViews::default();
        if !self.last_paraboloid {
            for m in &self.last_faces {
                views.lines.extend(frustum_lines(*m, [1.0, 0.85, 0.2, 1.0]));
            }
        }
        if let Some(t) = &self.debug {
            views.images.push(DebugImage {
                label: if self.virtual_state().is_some() {
                    "virtual map pool, layer 0 (every resident page, depth)"
                } else {
                    "shadow map (face 0, linear depth)"
                }
                .into(),
                width: t.width(),
                height: t.height(),
                rgba: gpu.read_texture(t, 0, 4)?,
            });
        }
        if let Some(v) = self.virtual_state() {
            views.images.extend(v.page_table_images());
        }
        if let Some([projection, texels, _]) = &self.debug_frame {
            for (t, label) in [
                (
                    projection,
                    if self.virtual_state().is_some() {
                        "virtual map pages over the scene, tinted by level (page borders darker; dark red: page not resident)"
                    } else {
                        "map projected onto the scene (depth, tinted per cascade; dark red: outside the map)"
                    },
                ),
                (
                    texels,
                    "shadow-map texels per pixel (blue < 1/4: aliasing, green 1, red > 4)",
                ),
            ] {
                views.images.push(DebugImage {
                    label: label.into(),
                    width: t.width(),
                    height: t.height(),
                    rgba: gpu.read_texture(t, 0, 4)?,
                });
            }
        }
        Ok(views)
    }

    pub(in crate::technique::shadow_map) fn read_map_lookup(
        &self,
        gpu: &GpuContext,
    ) -> Result<Option<MapLookup>> {
        let Some([_, _, lookup]) = &self.debug_frame else {
            return Ok(None);
        };
        let raw = gpu.read_texture(lookup, 0, 8)?;
        let pairs: &[[f32; 2]] = bytemuck::cast_slice(&raw);
        Ok(Some(MapLookup {
            footprint: pairs.iter().map(|p| p[0]).collect(),
            partition: pairs.iter().map(|p| p[1] as u32).collect(),
        }))
    }
}
