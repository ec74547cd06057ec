//! Live GPU objects of a device, from wgpu's internal counters (the
//! `counters` feature): how many buffers, textures, views, bind groups,
//! pipelines and query sets exist now, and the bytes the buffers and
//! textures hold. A frame loop that keeps something per frame shows here
//! as a count that grows with the frame number.

use serde::Serialize;

/// The live objects of one device at one moment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LiveResources {
    pub buffers: isize,
    pub textures: isize,
    pub texture_views: isize,
    pub bind_groups: isize,
    pub bind_group_layouts: isize,
    pub render_pipelines: isize,
    pub compute_pipelines: isize,
    pub pipeline_layouts: isize,
    pub samplers: isize,
    pub shader_modules: isize,
    pub query_sets: isize,
    pub command_encoders: isize,
    /// Bytes of GPU memory attributed to buffers.
    pub buffer_bytes: isize,
    /// Bytes of GPU memory attributed to textures.
    pub texture_bytes: isize,
}

impl LiveResources {
    /// The counts of `device` now. Backends that keep no counters report 0
    /// for all of them (Vulkan, Metal and DX12 keep them).
    pub fn of(device: &wgpu::Device) -> LiveResources {
        let h = device.get_internal_counters().hal;
        LiveResources {
            buffers: h.buffers.read(),
            textures: h.textures.read(),
            texture_views: h.texture_views.read(),
            bind_groups: h.bind_groups.read(),
            bind_group_layouts: h.bind_group_layouts.read(),
            render_pipelines: h.render_pipelines.read(),
            compute_pipelines: h.compute_pipelines.read(),
            pipeline_layouts: h.pipeline_layouts.read(),
            samplers: h.samplers.read(),
            shader_modules: h.shader_modules.read(),
            query_sets: h.query_sets.read(),
            command_encoders: h.command_encoders.read(),
            buffer_bytes: h.buffer_memory.read(),
            texture_bytes: h.texture_memory.read(),
        }
    }

    /// Every object count (not the bytes), named, in declaration order.
    pub fn counts(&self) -> [(&'static str, isize); 12] {
        [
            ("buffers", self.buffers),
            ("textures", self.textures),
            ("texture_views", self.texture_views),
            ("bind_groups", self.bind_groups),
            ("bind_group_layouts", self.bind_group_layouts),
            ("render_pipelines", self.render_pipelines),
            ("compute_pipelines", self.compute_pipelines),
            ("pipeline_layouts", self.pipeline_layouts),
            ("samplers", self.samplers),
            ("shader_modules", self.shader_modules),
            ("query_sets", self.query_sets),
            ("command_encoders", self.command_encoders),
        ]
    }

    /// Whether the device keeps counters at all (some object exists).
    pub fn counted(&self) -> bool {
        self.counts().iter().any(|(_, n)| *n > 0)
    }
}
