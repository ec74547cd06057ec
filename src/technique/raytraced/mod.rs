//! `raytraced`: the ground truth. Shadow rays from each pixel's surface
//! point, read from the frame's G-buffer (world position, geometric normal),
//! to the light, against a BVH (the `obvhs` crate) over the world-space
//! triangles of the shadow casters. Hard lights: one ray. Area lights
//! (sphere radius or rectangle): N stratified samples give fractional
//! visibility. Ray origins are offset along the geometric normal by a number
//! of float ULPs of the position (Wächter & Binder, "A Fast and Robust
//! Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6), so the
//! offset scales with the magnitude of the position, and lifted off the
//! surface by a fraction of the pixel's footprint on it: the G-buffer's
//! position is the rasterizer's interpolation, whose error grows with the
//! footprint, not a ray tracer's hit point.

use super::{Family, MaskContext, ParamSpec, ParamValues, Preset, ShadowTechnique};
use crate::clock::Instant;
use crate::frame::FrameUniform;
use crate::scene::area::{concentric_disk, stratified_square};
use crate::scene::bvh::{CasterBvh, TraceKernel};
use crate::scene::{Light, LightArea, LightType};
use anyhow::Result;
use glam::{Mat4, UVec2, Vec2, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

const SAMPLES: ParamSpec = ParamSpec::int(
    "samples",
    256,
    1,
    4096,
    "shadow rays per pixel for area lights (stratified); hard lights use one",
);
/// Sub-pixel samples (shared with `irregular`, whose `subpixel` preset this
/// reference measures): each pixel's visibility is the mean over points of
/// its footprint on its surface plane.
pub const PIXEL_SAMPLES: ParamSpec = ParamSpec::int(
    "pixel_samples",
    1,
    1,
    32,
    "visibility samples per pixel, on the pixel's surface plane (where the camera rays through a Hammersley pattern of the pixel meet the plane of its G-buffer surface): 1 samples the pixel's centre; more give the fraction of the pixel's footprint that sees the light (a supersampled reference for sub-pixel techniques)",
);
pub const OFFSET_ULPS: ParamSpec = ParamSpec::float(
    "offset_ulps",
    64.0,
    1.0,
    65536.0,
    1.0,
    "ray-origin offset along the geometric normal, in float ULPs of the position (scales with its magnitude)",
);
/// The ray origins' lift off the surface as a fraction of the pixel's
/// footprint (shared with `irregular`, which starts its rays where the
/// reference does).
pub const OFFSET_FOOTPRINT: ParamSpec = ParamSpec::float(
    "offset_footprint",
    0.004,
    0.0,
    0.25,
    0.001,
    "ray origins also lifted along the geometric normal by this fraction of the pixel's footprint on its surface (its width across the camera ray over the cosine between ray and normal, the cosine at least ⅛): the G-buffer's position is the rasterizer's interpolation, whose error grows with the footprint — without the lift, pixels at the concave creases of a terrain start their rays under the next triangle and shadow themselves (speckles of false shadow); 0: the ULP offset alone",
);

crate::technique::params::choice_enum! {
    /// Which kernel traces the shadow rays.
    pub enum Kernel { Auto = "auto", Obvhs = "obvhs", Embree = "embree" }
}

const KERNEL: ParamSpec = ParamSpec::choice_of::<Kernel>(
    "kernel",
    Kernel::Auto as usize,
    "ray-tracing kernel: embree (Embree 3, loaded at run time; Debian libembree3-3), obvhs (a pure-Rust CWBVH), auto: Embree when it loads, else obvhs; their masks differ only where a ray grazes a triangle's edge",
);

pub static FAMILY: Family = Family {
    id: "raytraced",
    summary: "ground truth: CPU shadow rays from the G-buffer against a BVH of the casters",
    capabilities: super::Capabilities {
        point_lights: true,
        spot_lights: true,
        directional_lights: true,
        soft_shadows: true,
        self_shadowing: true,
        open_meshes: true,
        curved_receivers: true,
        cutout_casters: true,
    },
    params: &[
        SAMPLES,
        PIXEL_SAMPLES,
        OFFSET_ULPS,
        OFFSET_FOOTPRINT,
        KERNEL,
    ],
    presets: &[
        Preset {
            name: "default",
            summary: "256 samples for area lights",
            values: &[],
        },
        Preset {
            name: "reference",
            summary: "1024 samples for area lights (soft-shadow reference)",
            values: &[(SAMPLES.name, "1024")],
        },
        Preset {
            name: "subpixel",
            summary: "32 samples per pixel on its surface plane (the supersampled reference of `irregular:subpixel`)",
            values: &[(PIXEL_SAMPLES.name, "32")],
        },
    ],
    create: |_, params| {
        Ok(Box::new(RayTraced {
            settings: ReferenceSettings::from_params(params)?,
            bvh: None,
            rays: 0.0,
            trace_ms: 0.0,
            build_ms: 0.0,
            bvh_bytes: 0,
        }))
    },
};

/// The reference's settings, read from its parameter table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Shadow rays per pixel for area lights.
    pub samples: usize,
    /// Visibility samples per pixel on its surface plane.
    pub pixel_samples: u32,
    /// Ray-origin offset in float ULPs of the position.
    pub offset_ulps: f32,
    /// Ray-origin lift as a fraction of the pixel's footprint.
    pub offset_footprint: f32,
    pub kernel: Kernel,
}

impl ReferenceSettings {
    pub fn from_params(p: &ParamValues) -> Result<Self> {
        Ok(ReferenceSettings {
            samples: p.int(&SAMPLES)? as usize,
            pixel_samples: p.int(&PIXEL_SAMPLES)?,
            offset_ulps: p.float(&OFFSET_ULPS)?,
            offset_footprint: p.float(&OFFSET_FOOTPRINT)?,
            kernel: p.choice(&KERNEL)?,
        })
    }
    /// The defaults of the family's table (`raytraced:default`), which the
    /// viewer's heatmap uses so that it agrees with `compare`.
    pub fn defaults() -> Self {
        Self::from_params(&ParamValues::defaults(FAMILY.params))
            .expect("the raytraced table has samples and offset_ulps")
    }
    /// Rays per pixel for `light`: one for a hard light.
    /// The kernel to trace with: `auto` takes Embree when it loads.
    pub fn trace_kernel(&self) -> TraceKernel {
        match self.kernel {
            Kernel::Obvhs => TraceKernel::Obvhs,
            Kernel::Embree => TraceKernel::Embree,
            Kernel::Auto => {
                if crate::scene::embree::available().is_ok() {
                    TraceKernel::Embree
                } else {
                    TraceKernel::Obvhs
                }
            }
        }
    }

    /// The casters of `scene` for this kernel (`held` when it matches).
    pub fn casters(
        &self,
        scene: &crate::scene::Scene,
        held: Option<&Arc<CasterBvh>>,
    ) -> Result<Arc<CasterBvh>> {
        CasterBvh::for_scene(scene, held, self.trace_kernel()).map_err(|e| anyhow::anyhow!(e))
    }

    pub fn samples_for(&self, light: &Light) -> usize {
        if light.area.is_some() {
            self.samples
        } else {
            1
        }
    }

    /// `light`'s mask from the G-buffer as read back (`gbuffer`: positions
    /// as Rgba32Float, geometric normals as Rgba16Float) of the frame
    /// `frame` describes: the reference's render_mask, the viewer's
    /// heatmap's, and the browser page's, which can only await its
    /// readbacks.
    pub fn mask_from_gbuffer_bytes(
        &self,
        bvh: &CasterBvh,
        light: &Light,
        gbuffer: (&[u8], &[u8]),
        frame: &FrameUniform,
    ) -> Vec<f32> {
        let positions: &[[f32; 4]] = bytemuck::cast_slice(gbuffer.0);
        let normals: Vec<Vec3> = bytemuck::cast_slice::<u8, [half::f16; 4]>(gbuffer.1)
            .iter()
            .map(|n| Vec3::new(n[0].to_f32(), n[1].to_f32(), n[2].to_f32()).normalize_or_zero())
            .collect();
        let sampling = PixelSampling::of_frame(frame, self.pixel_samples, self.offset_footprint);
        mask_from_gbuffer(
            bvh,
            light,
            positions,
            &normals,
            self.samples_for(light),
            self.offset_ulps,
            &sampling,
        )
    }
}

/// Offsets `p` along `n` by `ulps` units in the last place of each
/// coordinate (Wächter & Binder 2019), with a small absolute offset near the
/// origin where ULPs vanish.
pub fn offset_ray_origin(p: Vec3, n: Vec3, ulps: f32) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    let step = |p: f32, n: f32| -> f32 {
        let of = (ulps * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = f32::from_bits((if p < 0.0 { bits - of } else { bits + of }) as u32);
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n * ulps / 256.0
        } else {
            moved
        }
    };
    Vec3::new(step(p.x, n.x), step(p.y, n.y), step(p.z, n.z))
}

/// Orthonormal basis (t, b) perpendicular to unit `n`.
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let t = n.any_orthonormal_vector();
    (t, n.cross(t))
}

/// Small deterministic per-pixel random numbers (PCG hash).
fn pcg(mut v: u32) -> u32 {
    v = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let w = ((v >> ((v >> 28) + 4)) ^ v).wrapping_mul(277803737);
    (w >> 22) ^ w
}

/// Visibility of `light` from the surface point `p` with geometric normal
/// `n`: the light a shadow ray carries past the casters (0 or 1 unless it
/// crosses translucent ones) for hard lights, its mean over `samples` rays
/// for area lights. A ray below the surface's plane carries none (the
/// surface itself hides the light there), nor does a light that does not
/// shine on `p` (outside a spot's cone, past the range): the irregular
/// z-buffer bins no such sample.
pub fn visibility(
    bvh: &CasterBvh,
    light: &Light,
    p: Vec3,
    n: Vec3,
    samples: usize,
    ulps: f32,
    seed: u32,
) -> f32 {
    let origin = offset_ray_origin(p, n, ulps);
    if !light.shines_on(origin) {
        return 0.0;
    }
    // Along unit `dir` for `len`: nothing below the surface's plane.
    let through = |dir: Vec3, len: f32| {
        if dir.dot(n) <= 0.0 {
            0.0
        } else {
            bvh.transmittance(origin, dir, len)
        }
    };
    let to_point = |target: Vec3| {
        let d = target - origin;
        let len = d.length();
        if len <= 0.0 {
            1.0
        } else {
            through(d / len, len)
        }
    };
    let to_dir = |dir: Vec3| through(dir.normalize(), f32::INFINITY);
    let Some(area) = light.area.filter(|_| samples > 1) else {
        return match light.kind {
            LightType::Directional => to_dir(-light.direction),
            _ => to_point(light.position),
        };
    };
    let mut state = pcg(seed);
    let mut rnd = move || {
        state = pcg(state);
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let points = stratified_square(samples, || (rnd(), rnd()));
    let light_through: f32 = points
        .iter()
        .map(|&(a, b)| {
            // Offsets in the light's plane: a disk for spheres, the rectangle's half extents.
            let ((u, v), (hu, hv)) = match area {
                LightArea::Sphere { radius } => (concentric_disk(a, b), (radius, radius)),
                LightArea::Rect { width, height } => ((a, b), (width * 0.5, height * 0.5)),
            };
            match light.kind {
                LightType::Directional => {
                    let d = -light.direction.normalize();
                    let (t, bt) = basis(d);
                    to_dir(d + t * (u * hu) + bt * (v * hv))
                }
                _ => {
                    // Spheres present a disk facing the point; rectangles face along the light direction.
                    let axis = match area {
                        LightArea::Sphere { .. } => (light.position - p).normalize_or(Vec3::Y),
                        LightArea::Rect { .. } => light.direction.normalize_or(Vec3::NEG_Y),
                    };
                    let (t, bt) = basis(axis);
                    to_point(light.position + t * (u * hu) + bt * (v * hv))
                }
            }
        })
        .sum();
    light_through / samples as f32
}

/// How a pixel is sampled: its centre (`count` 1), or `count` points of
/// its footprint on its surface plane, for a frame of `size` pixels seen
/// through `inv_view_proj` from `eye`; and how far its rays' origins are
/// lifted off the surface ([`footprint_lift`]).
#[derive(Clone, Copy, Debug)]
pub struct PixelSampling {
    pub inv_view_proj: Mat4,
    pub size: UVec2,
    pub count: u32,
    pub eye: Vec3,
    /// The angle a pixel spans at the frame's centre, in radians.
    pub pixel_angle: f32,
    /// The lift as a fraction of the pixel's footprint (`offset_footprint`).
    pub footprint_fraction: f32,
}

impl PixelSampling {
    /// Each pixel's centre, its rays offset by ULPs alone (G-buffers made
    /// by hand, with no camera).
    pub const CENTRE: PixelSampling = PixelSampling {
        inv_view_proj: Mat4::IDENTITY,
        size: UVec2::ONE,
        count: 1,
        eye: Vec3::ZERO,
        pixel_angle: 0.0,
        footprint_fraction: 0.0,
    };

    /// `count` samples per pixel of the frame `frame` describes, the ray
    /// origins lifted by `footprint_fraction` of the pixel's footprint.
    pub fn of_frame(frame: &FrameUniform, count: u32, footprint_fraction: f32) -> PixelSampling {
        PixelSampling {
            inv_view_proj: frame.inv_view_proj,
            size: UVec2::new(frame.size.x as u32, frame.size.y as u32),
            count,
            eye: frame.camera_pos.truncate(),
            pixel_angle: pixel_angle(frame.proj.y_axis.y, frame.size.y),
            footprint_fraction,
        }
    }
}

/// The angle a pixel spans at the centre of a perspective frame `height`
/// pixels high whose projection scales y by `cot_half_fov` (0 where there
/// is no such frame).
fn pixel_angle(cot_half_fov: f32, height: f32) -> f32 {
    if cot_half_fov > 0.0 && height > 0.0 {
        2.0 / (cot_half_fov * height)
    } else {
        0.0
    }
}

/// The cosine between a camera ray and a surface below which the
/// footprint lift stops growing (83°: a surface seen edge-on would lift
/// its rays without bound).
pub const MIN_FOOTPRINT_COSINE: f32 = 0.125;

/// How far the ray origins of a pixel whose G-buffer surface lies at `p`
/// with unit normal `n` are lifted along `n`, besides the ULP offset: the
/// sampling's fraction of the pixel's footprint on the surface, its width
/// across the camera ray (distance times the pixel's angle) over the
/// cosine between the ray and the normal. The rasterizer interpolates the
/// position from screen-space plane equations whose terms grow with the
/// footprint, so its error does too; a ULP offset covers only the rounding
/// of the position itself. `footprint_lift` of irregular/samples.wgsl is
/// its twin.
pub fn footprint_lift(s: &PixelSampling, p: Vec3, n: Vec3) -> f32 {
    let to_p = p - s.eye;
    let distance = to_p.length();
    if s.footprint_fraction <= 0.0 || distance <= 0.0 {
        return 0.0;
    }
    let cosine = (to_p.dot(n) / distance).abs().max(MIN_FOOTPRINT_COSINE);
    s.footprint_fraction * distance * s.pixel_angle / cosine
}

/// Sub-pixel sample `k` of `count` within a pixel, in [0, 1)²: a Hammersley
/// pattern (x stratified, y the base-2 radical inverse), centred in its
/// strata. `pixel_sample_offset` of irregular/samples.wgsl is its twin.
pub fn pixel_sample_offset(k: u32, count: u32) -> Vec2 {
    let n = count as f32;
    Vec2::new(
        (k as f32 + 0.5) / n,
        k.reverse_bits() as f32 * 2.328_306_4e-10 + 0.5 / n,
    )
}

/// Where sub-pixel sample `k` of pixel `px` lies on the plane through `p`
/// with normal `n`: the camera ray through it met with the plane (the
/// pixel's footprint on its surface); `p` itself for one sample, or where
/// the ray runs along the plane. Written relative to `p`, so that the point
/// stays on the plane to the precision of `p` (the ray-origin offset is a
/// few ULPs of it), and lifted off it by [`PLANE_LIFT`] of its distance from
/// `p`. `sub_sample_point` of irregular/samples.wgsl is its twin.
pub fn pixel_sample_point(s: &PixelSampling, px: UVec2, k: u32, p: Vec3, n: Vec3) -> Vec3 {
    if s.count <= 1 {
        return p;
    }
    let uv = (px.as_vec2() + pixel_sample_offset(k, s.count)) / s.size.as_vec2();
    let ndc = Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let near = s
        .inv_view_proj
        .project_point3(ndc.extend(crate::scene::NEAR_PLANE_DEPTH));
    let mid = s.inv_view_proj.project_point3(ndc.extend(0.5));
    let d = (mid - near).normalize_or_zero();
    let along = d.dot(n);
    if along.abs() < 1e-6 {
        return p;
    }
    let to_near = near - p;
    let q = p + to_near - d * (to_near.dot(n) / along);
    q + n * (PLANE_LIFT * (q - p).length())
}

/// How far a sub-pixel sample is lifted off its pixel's plane, per unit of
/// its distance from the pixel's centre: a mesh bends away from its
/// triangle's plane at the triangle's edges, and a sample on the plane
/// past a concave edge would lie under the next triangle and shadow
/// itself (a wireframe of false shadow); ¼ clears bends up to 14°.
pub const PLANE_LIFT: f32 = 0.25;

/// Computes a whole visibility mask on the CPU from G-buffer data
/// (`positions`: xyzw with w = coverage, `normals`: xyz geometric normal),
/// each pixel sampled as `sampling` says: the mean visibility of its
/// sub-pixel points ([`PixelSampling::CENTRE`]: its centre).
pub fn mask_from_gbuffer(
    bvh: &CasterBvh,
    light: &Light,
    positions: &[[f32; 4]],
    normals: &[Vec3],
    samples: usize,
    ulps: f32,
    sampling: &PixelSampling,
) -> Vec<f32> {
    let width = sampling.size.x.max(1);
    let pixels = positions.len() as u32;
    positions
        .par_iter()
        .zip(normals.par_iter())
        .enumerate()
        .map(|(i, (p, n))| {
            if p[3] < 0.5 {
                return 1.0;
            }
            let px = UVec2::new(i as u32 % width, i as u32 / width);
            let centre = Vec3::new(p[0], p[1], p[2]);
            let count = sampling.count.max(1);
            let lift = *n * footprint_lift(sampling, centre, *n);
            let through: f32 = (0..count)
                .map(|k| {
                    let q = pixel_sample_point(sampling, px, k, centre, *n) + lift;
                    let seed = (i as u32).wrapping_add(k.wrapping_mul(pixels));
                    visibility(bvh, light, q, *n, samples, ulps, seed)
                })
                .sum();
            through / count as f32
        })
        .collect()
}

pub struct RayTraced {
    settings: ReferenceSettings,
    bvh: Option<Arc<CasterBvh>>,
    rays: f64,
    trace_ms: f64,
    build_ms: f64,
    bvh_bytes: u64,
}

impl ShadowTechnique for RayTraced {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.settings = ReferenceSettings::from_params(params)?;
        Ok(())
    }

    fn render_mask(
        &mut self,
        ctx: &MaskContext,
        _encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        let gpu = ctx.gpu;
        let frame = ctx.frame;
        let bvh = self.settings.casters(ctx.scene, self.bvh.as_ref())?;
        self.bvh = Some(bvh.clone());
        self.build_ms = bvh.build_ms;
        self.bvh_bytes = bvh.bytes();
        let pos_raw = gpu.read_texture(frame.gbuffer_position(), 0, 16)?;
        let nrm_raw = gpu.read_texture(frame.gbuffer_normal(), 0, 8)?;
        let t = Instant::now();
        let mask = self.settings.mask_from_gbuffer_bytes(
            &bvh,
            ctx.light,
            (&pos_raw, &nrm_raw),
            frame.uniform(),
        );
        self.trace_ms = t.elapsed().as_secs_f64() * 1e3;
        let positions: &[[f32; 4]] = bytemuck::cast_slice(&pos_raw);
        self.rays = positions.iter().filter(|p| p[3] >= 0.5).count() as f64
            * self.settings.samples_for(ctx.light) as f64
            * self.settings.pixel_samples as f64;
        crate::frame::write_mask(gpu, frame, ctx.light_index, &mask);
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("rays", self.rays),
            ("trace_ms", self.trace_ms),
            (
                "rays_per_second",
                if self.trace_ms > 0.0 {
                    self.rays / (self.trace_ms / 1e3)
                } else {
                    0.0
                },
            ),
            ("bvh_build_ms", self.build_ms),
            (
                "kernel_embree",
                self.bvh
                    .as_ref()
                    .map_or(0.0, |b| (b.kernel() == TraceKernel::Embree) as u32 as f64),
            ),
        ]
    }

    fn resource_bytes(&self) -> u64 {
        self.bvh_bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    /// The lift is the fraction of the pixel's width across the ray
    /// (distance 10 × 0.02 rad) over the cosine to the normal, the cosine
    /// at least ⅛; none without a camera. A 90° frame 100 pixels high
    /// spans 0.02 rad a pixel at its centre.
    #[test]
    fn the_footprint_lift_follows_distance_and_slant() {
        let sampling = PixelSampling {
            pixel_angle: 0.02,
            footprint_fraction: 0.004,
            ..PixelSampling::CENTRE
        };
        let p = Vec3::new(0.0, 0.0, -10.0);
        let lift = |n: Vec3| footprint_lift(&sampling, p, n);
        let slant = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
        assert!((lift(Vec3::Z) - 0.0008).abs() < 1e-9);
        assert!((lift(slant) - 0.0016).abs() < 1e-8);
        assert!((lift(Vec3::X) - 0.0064).abs() < 1e-8);
        assert_eq!(footprint_lift(&PixelSampling::CENTRE, p, Vec3::Z), 0.0);
        assert!((pixel_angle(1.0, 100.0) - 0.02).abs() < 1e-9);
        assert_eq!(pixel_angle(0.0, 100.0), 0.0);
    }

    #[test]
    fn offset_scales_with_position_magnitude() {
        let n = Vec3::Y;
        let small = offset_ray_origin(Vec3::new(1.0, 1.0, 1.0), n, 512.0).y - 1.0;
        let large = offset_ray_origin(Vec3::new(1000.0, 1000.0, 1000.0), n, 512.0).y - 1000.0;
        assert!(small > 0.0 && large > 0.0);
        // ulp(1000) / ulp(1) = 2^9.
        assert!((large / small - 512.0).abs() < 1.0, "{small} {large}");
        // Negative coordinates move along the normal too.
        assert!(offset_ray_origin(Vec3::new(0.0, -5.0, 0.0), n, 512.0).y > -5.0);
        assert!(offset_ray_origin(Vec3::new(0.0, 0.001, 0.0), n, 512.0).y > 0.001);
    }

    #[test]
    fn negative_zero_direction_components_still_hit() {
        let mut s = Scene::new("slab");
        let m = s.add_material(crate::scene::Material::default());
        let cube = s.add_mesh(crate::scene::shapes::cuboid(Vec3::new(0.2, 0.1, 4.0)));
        s.add_object("Box", cube, m, glam::Mat4::IDENTITY);
        s.finalize().unwrap();
        let bvh = CasterBvh::build(&s, TraceKernel::Obvhs).unwrap();
        let origin = Vec3::new(0.5, 0.0, 0.0);
        for z in [0.0f32, -0.0] {
            let dir = Vec3::new(-0.9986295, 0.05233596, z);
            assert_eq!(
                bvh.transmittance(origin, dir, f32::INFINITY),
                0.0,
                "z = {z:?}"
            );
        }
        // A sun straight down: the ray towards it is (−0, 1, −0).
        let above = Vec3::new(0.0, -1.0, 0.0);
        let light = Light::directional(Vec3::new(0.0, -1.0, 0.0), 1.0);
        assert_eq!(visibility(&bvh, &light, above, Vec3::Y, 1, 64.0, 0), 0.0);
    }

    #[test]
    fn a_light_the_surface_or_the_cone_hides_is_not_traced() {
        let mut s = Scene::new("far box");
        let m = s.add_material(crate::scene::Material::default());
        let cube = s.add_mesh(crate::scene::shapes::cuboid(Vec3::splat(0.5)));
        s.add_object(
            "Box",
            cube,
            m,
            glam::Mat4::from_translation(Vec3::new(50.0, 0.0, 0.0)),
        );
        s.finalize().unwrap();
        let bvh = CasterBvh::build(&s, TraceKernel::Obvhs).unwrap();
        let (p, n) = (Vec3::ZERO, Vec3::Y);
        let vis = |l: &Light, samples| visibility(&bvh, l, p, n, samples, 64.0, 7);
        // A sun overhead lights the point; one under its surface does not.
        assert_eq!(vis(&Light::directional(Vec3::NEG_Y, 1.0), 1), 1.0);
        assert_eq!(vis(&Light::directional(Vec3::Y, 1.0), 1), 0.0);
        // A spot lights it inside its cone only.
        let above = Vec3::new(0.0, 5.0, 0.0);
        assert_eq!(vis(&Light::spot(above, p, 1.0, 20.0, 30.0), 1), 1.0);
        assert_eq!(
            vis(
                &Light::spot(above, Vec3::new(9.0, 0.0, 0.0), 1.0, 20.0, 30.0),
                1
            ),
            0.0
        );
        // A point light within its range only.
        let mut point = Light::point(above, 1.0);
        point.range = 10.0;
        assert_eq!(vis(&point, 1), 1.0);
        point.range = 2.0;
        assert_eq!(vis(&point, 1), 0.0);
        // A sphere light centred on the horizon: the half below it is hidden.
        let mut horizon = Light::point(Vec3::new(-5.0, 0.0, 0.0), 1.0);
        horizon.area = Some(LightArea::Sphere { radius: 1.0 });
        let half = vis(&horizon, 256);
        assert!((half - 0.5).abs() < 0.1, "{half}");
    }
}
