//! The light-projection step: a light (or an area light's samples), the
//! camera and the scene's bounds become this frame's shadow views — the
//! spot, point or directional frusta of `setup`, a directional map or its
//! cascades fitted to the view frustum or, with SDSM (the single map's
//! default), to what the camera saw (`cascades`, `depth_bounds`), and the
//! warps (`warp`, `trapezoid`).

pub(super) mod bias_cap;
pub mod cascades;
pub(super) mod caster_cull;
pub(super) mod convex;
pub(super) mod depth_bounds;
pub(super) mod roll;
pub mod setup;
pub(super) mod spot_focus;
pub(super) mod stable_window;
pub mod view_depths;
pub mod warp;

use self::depth_bounds::{DepthReduction, ReduceInputs, SeenBounds, SpotImage};
use self::setup::Turn;
use self::setup::ViewFit;
use self::setup::{LightSetup, light_setup};
use super::{Cascades, Fit, Omni, Roll, ShadowMapConfig, ShadowMapTechnique, Warp};
use crate::scene::area::area_samples;
use crate::scene::{Light, LightType};
use crate::technique::MaskContext;
use anyhow::Result;
use glam::Vec2;

impl ShadowMapTechnique {
    /// The setups of `lights` for this frame, seen with `aspect`; with
    /// SDSM, records (or waits for) the reduction of the frame's G-buffer.
    pub(in crate::technique::shadow_map) fn light_setups(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        lights: &[Light],
        aspect: f32,
    ) -> Result<Vec<LightSetup>> {
        let c = self.config.for_light(ctx.light, ctx.gpu.max_texture_size());
        let size = c.size;
        // Warped maps are not stabilised.
        let stabilize = c.cascades.stabilize && c.warp.kind == Warp::None;
        let frustum_params = FrustumParams::of(&c, stabilize);
        let directional = ctx.light.kind == LightType::Directional;
        let cascaded = directional && c.cascades.count > 1;
        // One unwarped map: fitted and turned by `directional_setup`.
        let single = directional && !cascaded && c.warp.kind == Warp::None;
        // A spot light's map focused on what the camera sees of its cone
        // (`spot_focus`); not an area light's maps, each from another point.
        let spot = (ctx.light.kind == LightType::Spot
            && c.cascades.fit == Fit::Samples
            && lights.len() == 1)
            .then(|| SpotImage {
                cone_tan: (ctx.light.outer_cone_deg.to_radians()).tan(),
                position: ctx.light.position,
            });
        // A spot map focused on the view frustum's part of its cone.
        let spot_frustum = ctx.light.kind == LightType::Spot
            && c.cascades.fit == Fit::Frustum
            && lights.len() == 1;
        let focused_spot = spot.is_some() || spot_frustum;
        self.last_seen = self.reduce_seen(ctx, encoder, spot)?;
        let fitted_turn = match c.roll {
            Roll::Up => Turn::Upright,
            Roll::Square => Turn::Fitted {
                previous: self.turn,
            },
        };
        // What one directional or focused spot map is fitted to: the same
        // for every light sample, found once.
        let view_fit = self.single_map_fit(ctx);
        let mut fits = vec![];
        let setups = lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                // Last frame's window kept while it fits; one directional
                // or focused spot map is also fitted and turned.
                let kept = FrustumParams {
                    previous_half: self.stable_halves.get(i).copied(),
                    ..frustum_params
                };
                let fitted = FrustumParams {
                    view_fit,
                    turn: fitted_turn,
                    ..kept
                };
                let mut setup = if cascaded {
                    cascades::cascade_setup(
                        l.direction,
                        ctx.scene_gpu.extent(),
                        ctx.fit_camera,
                        aspect,
                        &Cascades {
                            stabilize,
                            ..c.cascades
                        },
                        size,
                        self.last_seen.as_ref(),
                    )
                } else if single {
                    let (mut setup, fit) = setup::directional_setup(
                        l,
                        &ctx.scene_gpu.bounds,
                        ctx.fit_camera,
                        aspect,
                        &fitted,
                    );
                    fits.push(fit);
                    setup.moment_depth = self.seen_depths(ctx).and_then(|seen| {
                        setup::seen_depth_window(
                            setup.faces[0],
                            ctx.fit_camera,
                            aspect,
                            &ctx.scene_gpu.bounds,
                            seen,
                        )
                    });
                    setup
                } else if focused_spot {
                    let (setup, fit) = setup::spot_setup(l, &ctx.scene_gpu.bounds, &fitted);
                    fits.push(fit);
                    setup
                } else {
                    light_setup(l, &ctx.scene_gpu.bounds, ctx.fit_camera, aspect, &kept)
                };
                if l.kind == LightType::Directional && c.warp.kind != Warp::None {
                    warp::warp_setup(
                        &mut setup,
                        (ctx.fit_camera, aspect),
                        l.direction,
                        &ctx.scene_gpu.bounds,
                        (&c.warp, size),
                        self.seen_view(ctx),
                    );
                }
                setup
            })
            .collect::<Vec<LightSetup>>();
        self.turn = fits.first().map(|f| f.turn);
        // A stabilised single directional or focused spot map's window,
        // kept next frame while it fits (`FrustumParams::previous_half`).
        self.stable_halves = if stabilize && (focused_spot || single) {
            fits.iter().map(|f| f.half).collect()
        } else {
            vec![]
        };
        Ok(setups)
    }

    /// SDSM: records (or waits for) the reduction of what the frame's
    /// G-buffer shows, where this frame's maps are fitted to it.
    fn reduce_seen(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        spot: Option<SpotImage>,
    ) -> Result<Option<SeenBounds>> {
        let c = self.config;
        let directional = ctx.light.kind == LightType::Directional;
        let fits_seen = spot.is_some() || (directional && c.cascades.fit != Fit::Frustum);
        if !fits_seen {
            return Ok(None);
        }
        let reduction = self
            .depth_reduction
            .get_or_insert_with(|| DepthReduction::new(ctx.gpu));
        let inputs = ReduceInputs {
            fit: c.cascades.fit,
            light_view: match spot {
                Some(_) => setup::spot_view(ctx.light),
                None => setup::light_view_of_scene(ctx.light.direction, &ctx.scene_gpu.bounds).0,
            },
            // One map fitted to the samples, warped or not.
            supports: spot.is_some()
                || (directional && c.cascades.count == 1 && c.cascades.fit == Fit::Samples),
            spot,
            cascades: c.cascades.count,
            split_lambda: c.cascades.split_lambda,
            far_limit: c.cascades.far_limit(ctx.fit_camera.far),
        };
        reduction.seen(ctx, encoder, &inputs)
    }

    /// The view depths the camera saw (SDSM's reduction), where the maps
    /// are fitted to them (`fit=depth|samples`) and the reduction has them:
    /// what a single warped map's body spans.
    fn seen_depths(&self, ctx: &MaskContext) -> Option<(f32, f32)> {
        let c = &self.config.cascades;
        let seen = self.last_seen.as_ref().filter(|_| c.fit != Fit::Frustum)?;
        Some(cascades::partitioned_depths(
            ctx.fit_camera,
            ctx.fit_frame.width() as f32 / ctx.fit_frame.height() as f32,
            ctx.scene_gpu.extent(),
            c,
            Some(seen),
        ))
    }

    /// What a warped map's body is cut to this frame (`warp::SeenView`):
    /// the depths the camera saw and, for one map fitted to the samples,
    /// the prism along the light around them.
    fn seen_view(&self, ctx: &MaskContext) -> warp::SeenView {
        let prism = self
            .last_seen
            .as_ref()
            .filter(|_| self.config.cascades.fit == Fit::Samples)
            .and_then(|seen| seen.supports)
            .map(|supports| warp::SeenPrism {
                view: setup::light_view_of_scene(ctx.light.direction, &ctx.scene_gpu.bounds).0,
                supports,
            });
        warp::SeenView {
            depths: self.seen_depths(ctx),
            prism,
        }
    }

    /// What a directional light's single map, or a spot light's map, is
    /// fitted to this frame: the view frustum, or (SDSM with one map) the
    /// depths or the light-view box of the pixels the camera saw, when the
    /// reduction has them; a spot's map under `fit=frustum`, to what the
    /// view frustum holds of its cone (`spot_focus::frustum_supports`).
    fn single_map_fit(&self, ctx: &MaskContext) -> ViewFit {
        let c = &self.config.cascades;
        let size = self.config.map_side(ctx.light, ctx.gpu.max_texture_size());
        match (c.fit, self.last_seen.as_ref()) {
            (Fit::Frustum, _) if ctx.light.kind == LightType::Spot => {
                let aspect = ctx.fit_frame.width() as f32 / ctx.fit_frame.height() as f32;
                spot_focus::frustum_supports(
                    setup::spot_view(ctx.light),
                    ctx.light.outer_cone_deg.to_radians().tan(),
                    (ctx.fit_camera, aspect),
                    &ctx.scene_gpu.bounds,
                )
                .map_or(ViewFit::Frustum, |supports| ViewFit::Samples {
                    supports,
                    size,
                })
            }
            (Fit::Samples, Some(seen)) => match seen.supports {
                Some(supports) => ViewFit::Samples { supports, size },
                None => ViewFit::Frustum,
            },
            (Fit::Depth, Some(seen)) => {
                let (near, far) = cascades::partitioned_depths(
                    ctx.fit_camera,
                    ctx.fit_frame.width() as f32 / ctx.fit_frame.height() as f32,
                    ctx.scene_gpu.extent(),
                    c,
                    Some(seen),
                );
                ViewFit::Depths { near, far }
            }
            _ => ViewFit::Frustum,
        }
    }
}

/// The user's choices for the light frustum (0 = fitted).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrustumParams {
    pub near: f32,
    pub far: f32,
    pub fov_deg: f32,
    /// Point lights: two paraboloid hemispheres instead of six faces.
    pub paraboloid: bool,
    /// Directional lights and focused spot maps: the fitted window's sides
    /// rounded up to eighths of an octave and its centre snapped to whole
    /// texels of a map of `size`², so that small camera moves leave the
    /// texel grid in place.
    pub stabilize_size: Option<u32>,
    /// The same, stabilised: the previous frame's half-extents, each kept
    /// while the fit's [`stable_window::Hold`] keeps it (hysteresis: a size at a rounding
    /// step does not flip from frame to frame, moving every texel edge).
    pub previous_half: Option<Vec2>,
    /// Directional, one map: what its window is fitted to; spot lights:
    /// `Samples` focuses the map on them (`spot_focus`), in the light's
    /// image (x/−z, y/−z) rather than its view.
    pub view_fit: ViewFit,
    /// Directional, one map: how it is turned about the light.
    pub turn: Turn,
}

impl FrustumParams {
    /// The configuration's choices, fitted to the frustum and upright;
    /// stabilised to texels of the map's size where `stabilize`.
    fn of(c: &ShadowMapConfig, stabilize: bool) -> FrustumParams {
        FrustumParams {
            near: c.near,
            far: c.far,
            fov_deg: c.fov_deg,
            paraboloid: c.omni == Omni::DualParaboloid,
            stabilize_size: stabilize.then_some(c.size),
            previous_half: None,
            view_fit: ViewFit::Frustum,
            turn: Turn::Upright,
        }
    }

    /// These parameters with last frame's window dropped where `turn`
    /// differs from last frame's ([`Turn::keeps_window`]).
    pub(super) fn kept_under(&self, turn: usize) -> FrustumParams {
        FrustumParams {
            previous_half: self.previous_half.filter(|_| self.turn.keeps_window(turn)),
            ..*self
        }
    }
}

/// The point lights a map is rendered from: an area light with `area` on
/// becomes several samples; one light keeps its area's radius for PCSS.
pub(super) fn light_samples(
    c: &ShadowMapConfig,
    ctx: &MaskContext,
) -> (Vec<crate::scene::Light>, f32) {
    // An area light with `area` on becomes several point samples.
    let lights = if c.area && ctx.light.area.is_some() {
        area_samples(
            ctx.light,
            c.area_maps as usize,
            ctx.scene_gpu.bounds.center(),
        )
    } else {
        vec![*ctx.light]
    };
    let area_radius = match ctx.light.area {
        Some(crate::scene::LightArea::Sphere { radius }) if lights.len() == 1 => radius,
        Some(crate::scene::LightArea::Rect { width, height }) if lights.len() == 1 => {
            width.max(height) * 0.5
        }
        _ => 0.0,
    };
    (lights, area_radius)
}
