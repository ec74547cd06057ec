//! The depth pass from a light: what its pipelines depend on
//! ([`DepthPassKey`]), which casters each draws (with `cull=solids`, solids
//! and the rest apart: second-depth maps, Wang & Molnar 1994), and the
//! pipelines themselves, with the bare `stage=floor` pass
//! (`depth_pass.wgsl`).

use super::pipelines::{MapProjection, MapShape, ShadowMapShared};
use super::{MOMENT_FORMAT, PART_FORMAT};
use crate::frame::{DrawCall, VERTEX_LAYOUT};
use crate::gpu::GpuContext;
use crate::scene::AlphaMode;
use crate::scene::topology::SolidKind;
use crate::technique::params::{BlendedCasters, CasterAlpha, Choice};
use crate::technique::shadow_map::config::{CullFace, DepthFormat, Filter};

/// What a depth-pass pipeline depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DepthPassKey {
    pub format: DepthFormat,
    pub cull: CullFace,
    pub bias: i32,
    pub slope_bits: u32,
    /// The bias's cap in the map's depth units (`f32` bits; 0: none).
    pub clamp_bits: u32,
    /// The moment filter whose moments the pass stores, if any.
    pub moments: Option<Filter>,
    /// The maps' shape: a paraboloid's pass drops what lies behind the
    /// hemisphere; a warped face's writes the linear depth and applies the
    /// bias itself (`fs_depth_linear`).
    pub shape: MapShape,
    /// Pages of a virtual map: positions relative to the camera.
    pub virtual_map: bool,
    /// Convex part IDs written beside the depth (`fs_depth_part`).
    pub parts: bool,
    /// Cut-out casters: the fragment stage drops their holes
    /// (`CUTOUT` in depth_pass.wgsl).
    pub cutout: bool,
    /// Translucent casters against a hash of the texel, its depth and the
    /// object (`HASHED`).
    pub hashed: bool,
}

impl CullFace {
    /// The culling maps of `shape` get: `Solids` becomes `None` on warped
    /// maps (a perspective warp can mirror the light's image, which swaps
    /// front and back faces: PSM and TSM stored lit faces unbiased, a
    /// false shadow over whole lit surfaces) and on paraboloid
    /// hemispheres (projected in the vertex stage).
    pub fn for_shape(self, shape: MapShape) -> CullFace {
        let keeps_facing = !shape.warped && shape.projection != MapProjection::Paraboloid;
        match self {
            CullFace::Solids if !keeps_facing => CullFace::None,
            c => c,
        }
    }
}

/// Which casters a depth-pass pipeline draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Casters {
    All,
    /// Those that do not bound a solid.
    NotSolids,
    Solids,
    /// Solids that can shadow themselves ([`SolidKind::Concave`]).
    ConcaveSolids,
}

impl Casters {
    /// Whether the set holds `d`, a shadow caster.
    fn holds(self, d: &DrawCall) -> bool {
        match self {
            Casters::All => true,
            Casters::NotSolids => d.solid == SolidKind::NotSolid,
            Casters::Solids => d.solid != SolidKind::NotSolid,
            Casters::ConcaveSolids => d.solid == SolidKind::Concave,
        }
    }
}

/// Which casters a depth-pass pipeline draws by their opacity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surfaces {
    /// Every caster, solid (the bare floor pass).
    AllSolid,
    /// Those drawn opaque.
    Opaque(CasterAlpha),
    /// Those drawn as cut-outs.
    Cutout(CasterAlpha),
    /// The translucent ones, in passes of their own
    /// (`blended_casters=transmit`).
    Translucent,
}

impl Surfaces {
    fn holds(self, d: &DrawCall) -> bool {
        match self {
            Surfaces::AllSolid => true,
            Surfaces::Opaque(a) => a.draws_as(d.alpha_mode) == Some(AlphaMode::Opaque),
            Surfaces::Cutout(a) => a.draws_as(d.alpha_mode) == Some(AlphaMode::Mask),
            Surfaces::Translucent => d.alpha_mode == AlphaMode::Blend,
        }
    }
}

/// One pipeline of a depth pass and the casters it draws.
#[derive(Clone)]
pub struct DepthDraw {
    pub pipeline: wgpu::RenderPipeline,
    pub casters: Casters,
    pub surfaces: Surfaces,
}

impl DepthDraw {
    /// Whether this draw takes `d`: a shadow caster of its sets.
    pub fn takes(&self, d: &DrawCall) -> bool {
        d.casts_shadow && self.casters.holds(d) && self.surfaces.holds(d)
    }
}

/// Whether `alpha` draws any of `draws`' casters as a cut-out.
fn has_cutout_casters(draws: &[DrawCall], alpha: CasterAlpha) -> bool {
    draws
        .iter()
        .any(|d| d.casts_shadow && alpha.draws_as(d.alpha_mode) == Some(AlphaMode::Mask))
}

impl DepthPassKey {
    /// The pipelines a depth pass draws with, each with the casters it
    /// draws. With `cull=solids`, the casters that are not solids take
    /// both faces and the bias; solids their back faces without bias and,
    /// where the bias is capped (unwarped orthographic maps) and
    /// `solid_front_bias` is not 0, concave solids their front faces too,
    /// with that many times the slope bias and its cap: a concave solid's
    /// back face can lie too close before the part of it that it shadows
    /// (a convex one never shadows its own lit side). Uncapped, at grazing
    /// light the pushed front faces still meet the lit faces they come from,
    /// which take no normal offset, and shadow them.
    fn draws(self, solid_front_bias: f32) -> Vec<(DepthPassKey, Casters)> {
        if self.cull != CullFace::Solids {
            return vec![(self, Casters::All)];
        }
        let back = DepthPassKey {
            cull: CullFace::Front,
            bias: 0,
            slope_bits: 0,
            clamp_bits: 0,
            ..self
        };
        let mut draws = vec![
            (
                DepthPassKey {
                    cull: CullFace::None,
                    ..self
                },
                Casters::NotSolids,
            ),
            (back, Casters::Solids),
        ];
        if solid_front_bias > 0.0 && f32::from_bits(self.clamp_bits) > 0.0 {
            let scaled = |bits: u32| (f32::from_bits(bits) * solid_front_bias).to_bits();
            let front = DepthPassKey {
                cull: CullFace::Back,
                slope_bits: scaled(self.slope_bits),
                clamp_bits: scaled(self.clamp_bits),
                ..self
            };
            draws.push((front, Casters::ConcaveSolids));
        }
        draws
    }
}

impl ShadowMapShared {
    /// The depth passes from the light and the casters each draws (see
    /// [`DepthPassKey::draws`]): each set once drawn opaque and, where
    /// `alpha` makes some of `scene_draws` cut-outs, once alpha-tested.
    pub fn depth_passes(
        &self,
        gpu: &GpuContext,
        key: DepthPassKey,
        solid_front_bias: f32,
        alpha: CasterAlpha,
        scene_draws: &[DrawCall],
    ) -> Vec<DepthDraw> {
        let cutouts = has_cutout_casters(scene_draws, alpha);
        key.draws(solid_front_bias)
            .into_iter()
            .flat_map(|(key, casters)| {
                let opaque = DepthDraw {
                    pipeline: self.depth_pass(gpu, key),
                    casters,
                    surfaces: Surfaces::Opaque(alpha),
                };
                let cutout_key = DepthPassKey {
                    cutout: true,
                    hashed: alpha.blended == BlendedCasters::Hashed,
                    ..key
                };
                let cutout = cutouts.then(|| DepthDraw {
                    pipeline: self.depth_pass(gpu, cutout_key),
                    casters,
                    surfaces: Surfaces::Cutout(alpha),
                });
                std::iter::once(opaque).chain(cutout)
            })
            .collect()
    }

    /// The translucent casters' depth pass (`blended_casters=transmit`):
    /// the nearest one's depth per texel, from both faces, into a d32f map
    /// of its own, biased as the other casters that bound no solid are.
    pub fn translucent_depth_pass(&self, gpu: &GpuContext, key: DepthPassKey) -> DepthDraw {
        let key = DepthPassKey {
            format: DepthFormat::D32f,
            cull: CullFace::None,
            moments: None,
            parts: false,
            cutout: false,
            hashed: false,
            ..key
        };
        DepthDraw {
            pipeline: self.depth_pass(gpu, key),
            casters: Casters::All,
            surfaces: Surfaces::Translucent,
        }
    }

    /// The depth pass from the light.
    fn depth_pass(&self, gpu: &GpuContext, key: DepthPassKey) -> wgpu::RenderPipeline {
        gpu.cache.render_pipeline("shadow map depth", &key, || {
            let (entry, color) = if key.parts {
                (Some("fs_depth_part"), Some(PART_FORMAT))
            } else if key.moments.is_some() {
                (Some("fs_depth_moments"), Some(MOMENT_FORMAT))
            } else if key.format == DepthFormat::R8 {
                (Some("fs_depth_byte"), Some(wgpu::TextureFormat::R8Unorm))
            } else if key.shape.projection == MapProjection::Paraboloid {
                (Some("fs_depth_paraboloid"), None)
            } else if key.shape.warped {
                (Some("fs_depth_linear"), None)
            } else if key.cutout {
                (Some("fs_depth_cutout"), None)
            } else {
                (None, None)
            };
            let mut constants = vec![
                (
                    "FILTER_KIND",
                    key.moments.map_or(Filter::Grid, |f| f).index() as f64,
                ),
                ("VIRTUAL", key.virtual_map as u32 as f64),
                ("CUTOUT", key.cutout as u32 as f64),
                ("HASHED", key.hashed as u32 as f64),
            ];
            constants.extend(key.shape.constants());
            let options = wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            };
            let targets = [color.map(wgpu::ColorTargetState::from)];
            gpu.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("shadow map depth"),
                    layout: Some(&self.pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &self.module,
                        entry_point: Some("vs_depth"),
                        compilation_options: options.clone(),
                        buffers: &[Some(VERTEX_LAYOUT)],
                    },
                    primitive: wgpu::PrimitiveState {
                        cull_mode: key.cull.face(),
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: key.format.depth_texture(),
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::LessEqual),
                        stencil: Default::default(),
                        // Written depth takes no polygon offset: the
                        // linear pass biases in its fragment stage.
                        bias: if key.shape.warped && key.moments.is_none() {
                            wgpu::DepthBiasState::default()
                        } else {
                            wgpu::DepthBiasState {
                                constant: key.bias,
                                slope_scale: f32::from_bits(key.slope_bits),
                                clamp: f32::from_bits(key.clamp_bits),
                            }
                        },
                    }),
                    multisample: Default::default(),
                    fragment: entry.map(|e| wgpu::FragmentState {
                        module: &self.module,
                        entry_point: Some(e),
                        compilation_options: options,
                        targets: if targets[0].is_some() { &targets } else { &[] },
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        })
    }

    /// The floor of `stage=floor`: positions transformed by the face matrix,
    /// depth test and write, nothing else.
    pub fn floor(
        &self,
        gpu: &GpuContext,
        format: wgpu::TextureFormat,
        shape: MapShape,
    ) -> wgpu::RenderPipeline {
        gpu.cache
            .render_pipeline("shadow map floor", &(format, shape), || {
                let constants = shape.constants();
                gpu.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("shadow map floor"),
                        layout: Some(&self.pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some("vs_floor"),
                            compilation_options: wgpu::PipelineCompilationOptions {
                                constants: &constants,
                                ..Default::default()
                            },
                            buffers: &[Some(VERTEX_LAYOUT)],
                        },
                        primitive: Default::default(),
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format,
                            depth_write_enabled: Some(true),
                            depth_compare: Some(wgpu::CompareFunction::LessEqual),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        multisample: Default::default(),
                        fragment: None,
                        multiview_mask: None,
                        cache: None,
                    })
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(cull: CullFace, projection: MapProjection, warped: bool, clamp: f32) -> DepthPassKey {
        DepthPassKey {
            format: DepthFormat::D32f,
            cull,
            bias: 2,
            slope_bits: 2.0f32.to_bits(),
            clamp_bits: clamp.to_bits(),
            moments: None,
            shape: MapShape {
                projection,
                cascaded: false,
                warped,
            },
            virtual_map: false,
            parts: false,
            cutout: false,
            hashed: false,
        }
    }

    #[test]
    fn solids_draw_back_faces_unbiased_and_concave_ones_front_faces_under_a_capped_bias() {
        let ortho = key(CullFace::Solids, MapProjection::Orthographic, false, 0.01);
        let draws = ortho.draws(4.0);
        let kinds: Vec<_> = draws
            .iter()
            .map(|(k, casters)| (k.cull, *casters, k.bias, f32::from_bits(k.slope_bits)))
            .collect();
        assert_eq!(
            kinds,
            [
                (CullFace::None, Casters::NotSolids, 2, 2.0),
                (CullFace::Front, Casters::Solids, 0, 0.0),
                (CullFace::Back, Casters::ConcaveSolids, 2, 8.0),
            ]
        );
        assert_eq!(f32::from_bits(draws[1].0.clamp_bits), 0.0);
        assert_eq!(f32::from_bits(draws[2].0.clamp_bits), 0.04);
        assert_eq!(ortho.draws(0.0).len(), 2, "no front faces at 0");
        let cube = key(CullFace::Solids, MapProjection::Cube, false, 0.0);
        assert_eq!(cube.draws(4.0).len(), 2, "uncapped: back faces only");
        let none = key(CullFace::None, MapProjection::Orthographic, false, 0.01);
        assert_eq!(none.draws(4.0), [(none, Casters::All)]);
    }

    #[test]
    fn warped_and_paraboloid_maps_draw_both_faces_for_solids() {
        let shape = |projection, warped| key(CullFace::Solids, projection, warped, 0.0).shape;
        let solids = CullFace::Solids;
        assert_eq!(
            solids.for_shape(shape(MapProjection::Orthographic, false)),
            solids
        );
        assert_eq!(solids.for_shape(shape(MapProjection::Cube, false)), solids);
        assert_eq!(
            solids.for_shape(shape(MapProjection::Perspective, false)),
            solids
        );
        assert_eq!(
            solids.for_shape(shape(MapProjection::Orthographic, true)),
            CullFace::None
        );
        assert_eq!(
            solids.for_shape(shape(MapProjection::Paraboloid, false)),
            CullFace::None
        );
        assert_eq!(
            CullFace::Back.for_shape(shape(MapProjection::Orthographic, true)),
            CullFace::Back
        );
    }
}
