//! `raytraced`: the ground truth. Shadow rays from each pixel's surface
//! point, read from the frame's G-buffer (world position, geometric normal),
//! to the light, against a BVH (the `obvhs` crate) over the world-space
//! triangles of the shadow casters. Hard lights: one ray. Area lights
//! (sphere radius or rectangle): N stratified samples give fractional
//! visibility. Ray origins are offset along the geometric normal by a number
//! of float ULPs of the position (Wächter & Binder, "A Fast and Robust
//! Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6), so the
//! offset scales with the magnitude of the position.

use super::{Family, MaskContext, ParamSpec, ParamValues, Preset, ShadowTechnique};
use crate::scene::{Light, LightArea, LightType, Scene};
use anyhow::Result;
use glam::Vec3;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use rayon::prelude::*;
use std::sync::{Arc, Mutex, Weak};
use std::time::Instant;

pub static FAMILY: Family = Family {
    id: "raytraced",
    summary: "ground truth: CPU shadow rays from the G-buffer against a BVH of the casters",
    params: &[
        ParamSpec::int(
            "samples",
            256,
            1,
            4096,
            "shadow rays per pixel for area lights (stratified); hard lights use one",
        ),
        ParamSpec::float(
            "offset_ulps",
            64.0,
            1.0,
            65536.0,
            1.0,
            "ray-origin offset along the geometric normal, in float ULPs of the position (scales with its magnitude)",
        ),
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
            values: &[("samples", "1024")],
        },
    ],
    create: |_| Ok(Box::new(RayTraced::default())),
};

/// The reference's settings, read from its parameter table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Shadow rays per pixel for area lights.
    pub samples: usize,
    /// Ray-origin offset in float ULPs of the position.
    pub offset_ulps: f32,
}

impl ReferenceSettings {
    pub fn from_params(p: &ParamValues) -> Result<Self> {
        Ok(ReferenceSettings {
            samples: p.get_usize("samples")?,
            offset_ulps: p.get_f32("offset_ulps")?,
        })
    }
    /// The defaults of the family's table (`raytraced:default`), which the
    /// viewer's heatmap uses so that it agrees with `compare`.
    pub fn defaults() -> Self {
        Self::from_params(&ParamValues::defaults(FAMILY.params))
            .expect("the raytraced table has samples and offset_ulps")
    }
    /// Rays per pixel for `light`: one for a hard light.
    pub fn samples_for(&self, light: &Light) -> usize {
        if light.area.is_some() {
            self.samples
        } else {
            1
        }
    }
}

/// BVH over the world-space triangles of a scene's shadow casters.
pub struct CasterBvh {
    key: u64,
    bvh: Option<CwBvh>,
    triangles: Vec<Triangle>,
    pub build_ms: f64,
}

impl CasterBvh {
    pub fn build(scene: &Scene) -> CasterBvh {
        let t = Instant::now();
        let key = super::scene_fingerprint(scene);
        let triangles: Vec<Triangle> = scene
            .world_triangles(|o| o.casts_shadow && !o.shadow_plane)
            .into_iter()
            .map(|[a, b, c]| Triangle {
                v0: a.into(),
                v1: b.into(),
                v2: c.into(),
            })
            .collect();
        let bvh = (!triangles.is_empty()).then(|| {
            obvhs::cwbvh::builder::build_cwbvh_from_tris(
                &triangles,
                obvhs::BvhBuildParams::medium_build(),
                &mut std::time::Duration::default(),
            )
        });
        CasterBvh {
            key,
            bvh,
            triangles,
            build_ms: t.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// The BVH of `scene`'s casters, shared between all users while alive;
    /// `held` is returned as is when it still matches the scene.
    pub fn for_scene(scene: &Scene, held: Option<&Arc<CasterBvh>>) -> Arc<CasterBvh> {
        static CACHE: Mutex<Vec<(u64, Weak<CasterBvh>)>> = Mutex::new(Vec::new());
        let key = super::scene_fingerprint(scene);
        if let Some(h) = held.filter(|h| h.key == key) {
            return h.clone();
        }
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        cache.retain(|(_, w)| w.strong_count() > 0);
        if let Some(b) = cache
            .iter()
            .find(|(k, _)| *k == key)
            .and_then(|(_, w)| w.upgrade())
        {
            return b;
        }
        let b = Arc::new(CasterBvh::build(scene));
        cache.push((key, Arc::downgrade(&b)));
        b
    }

    /// True when nothing blocks the segment from `origin` along `dir` (unit)
    /// up to distance `tmax`.
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let Some(bvh) = &self.bvh else { return true };
        // obvhs' traversal misses hits when a direction component is −0.0
        // (a sun along (0, −1, 0) gives the ray (−0, 1, −0)): use +0.0.
        let dir = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::ZERO, dir);
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        bvh.ray_traverse_miss(ray, |r, id| {
            self.triangles[bvh.primitive_indices[id] as usize].intersect(r)
        })
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Memory of the triangles, BVH nodes and index table.
    pub fn bytes(&self) -> u64 {
        let nodes = self.bvh.as_ref().map_or(0, |b| {
            b.nodes.len() * std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>()
                + b.primitive_indices.len() * 4
        });
        (self.triangles.len() * std::mem::size_of::<Triangle>() + nodes) as u64
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

/// `n` stratified points in [−1,1]², one in each of n strata of equal area:
/// r = round(√n) rows, row j holding c_j = ⌊n/r⌋ or ⌈n/r⌉ cells and of
/// height c_j/n, so every cell (width 1/c_j) covers 1/n of the square and
/// no part of the square is left without samples when n is not a square
/// (n = k² gives the k×k grid). Row-major; each point is jittered inside its
/// cell by `jitter` in [0,1)².
pub fn stratified_square(n: usize, mut jitter: impl FnMut() -> (f32, f32)) -> Vec<(f32, f32)> {
    if n == 0 {
        return vec![];
    }
    let rows = ((n as f64).sqrt().round() as usize).max(1);
    let mut out = Vec::with_capacity(n);
    let mut start = 0;
    for j in 0..rows {
        let cols = n / rows + usize::from(j < n % rows);
        for i in 0..cols {
            let (jx, jy) = jitter();
            let x = 2.0 * (i as f32 + jx) / cols as f32 - 1.0;
            let y = if n.is_multiple_of(rows) {
                2.0 * (j as f32 + jy) / rows as f32 - 1.0
            } else {
                2.0 * (start as f32 + jy * cols as f32) / n as f32 - 1.0
            };
            out.push((x, y));
        }
        start += cols;
    }
    out
}

/// Shirley–Chiu concentric map of [−1,1]² onto the unit disk (keeps
/// stratification).
pub fn concentric_disk(a: f32, b: f32) -> (f32, f32) {
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * phi.cos(), r * phi.sin())
}

/// Small deterministic per-pixel random numbers (PCG hash).
fn pcg(mut v: u32) -> u32 {
    v = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let w = ((v >> ((v >> 28) + 4)) ^ v).wrapping_mul(277803737);
    (w >> 22) ^ w
}

/// Visibility of `light` from the surface point `p` with geometric normal
/// `n`: 0 or 1 for hard lights, the unoccluded fraction of `samples` rays
/// for area lights.
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
    let to_point = |target: Vec3| {
        let d = target - origin;
        let len = d.length();
        len <= 0.0 || bvh.unoccluded(origin, d / len, len)
    };
    let to_dir = |dir: Vec3| bvh.unoccluded(origin, dir.normalize(), f32::INFINITY);
    let Some(area) = light.area.filter(|_| samples > 1) else {
        return match light.kind {
            LightType::Directional => to_dir(-light.direction) as u32 as f32,
            _ => to_point(light.position) as u32 as f32,
        };
    };
    let mut state = pcg(seed);
    let mut rnd = move || {
        state = pcg(state);
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let points = stratified_square(samples, || (rnd(), rnd()));
    let hits = points
        .iter()
        .filter(|&&(a, b)| {
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
        .count();
    hits as f32 / samples as f32
}

/// Computes a whole visibility mask on the CPU from G-buffer data
/// (`positions`: xyzw with w = coverage, `normals`: xyz geometric normal).
pub fn mask_from_gbuffer(
    bvh: &CasterBvh,
    light: &Light,
    positions: &[[f32; 4]],
    normals: &[Vec3],
    samples: usize,
    ulps: f32,
) -> Vec<f32> {
    positions
        .par_iter()
        .zip(normals.par_iter())
        .enumerate()
        .map(|(i, (p, n))| {
            if p[3] < 0.5 {
                1.0
            } else {
                visibility(
                    bvh,
                    light,
                    Vec3::new(p[0], p[1], p[2]),
                    *n,
                    samples,
                    ulps,
                    i as u32,
                )
            }
        })
        .collect()
}

#[derive(Default)]
pub struct RayTraced {
    bvh: Option<Arc<CasterBvh>>,
    rays: f64,
    trace_ms: f64,
    build_ms: f64,
    bvh_bytes: u64,
}

impl ShadowTechnique for RayTraced {
    fn render_mask(
        &mut self,
        ctx: &MaskContext,
        _encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        let gpu = ctx.gpu;
        let frame = ctx.frame;
        let bvh = CasterBvh::for_scene(ctx.scene, self.bvh.as_ref());
        self.bvh = Some(bvh.clone());
        self.build_ms = bvh.build_ms;
        self.bvh_bytes = bvh.bytes();
        let pos_raw = gpu.read_texture(&frame.gbuffer_position, 0, 16)?;
        let nrm_raw = gpu.read_texture(&frame.gbuffer_normal, 0, 8)?;
        let positions: &[[f32; 4]] = bytemuck::cast_slice(&pos_raw);
        let normals: Vec<Vec3> = bytemuck::cast_slice::<u8, [half::f16; 4]>(&nrm_raw)
            .iter()
            .map(|n| Vec3::new(n[0].to_f32(), n[1].to_f32(), n[2].to_f32()).normalize_or_zero())
            .collect();
        let settings = ReferenceSettings::from_params(ctx.params)?;
        let samples = settings.samples_for(ctx.light);
        let t = Instant::now();
        let mask = mask_from_gbuffer(
            &bvh,
            ctx.light,
            positions,
            &normals,
            samples,
            settings.offset_ulps,
        );
        self.trace_ms = t.elapsed().as_secs_f64() * 1e3;
        self.rays = positions.iter().filter(|p| p[3] >= 0.5).count() as f64 * samples as f64;
        crate::renderer::write_mask(gpu, frame, ctx.light_index, &mask);
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
        ]
    }

    fn resource_bytes(&self) -> u64 {
        self.bvh_bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let bvh = CasterBvh::build(&s);
        let origin = Vec3::new(0.5, 0.0, 0.0);
        for z in [0.0f32, -0.0] {
            let dir = Vec3::new(-0.9986295, 0.05233596, z);
            assert!(!bvh.unoccluded(origin, dir, f32::INFINITY), "z = {z:?}");
        }
        // A sun straight down: the ray towards it is (−0, 1, −0).
        let above = Vec3::new(0.0, -1.0, 0.0);
        let light = Light::directional(Vec3::new(0.0, -1.0, 0.0), 1.0);
        assert_eq!(visibility(&bvh, &light, above, Vec3::Y, 1, 64.0, 0), 0.0);
    }

    #[test]
    fn stratified_samples_cover_each_cell_once() {
        let pts = stratified_square(16, || (0.5, 0.5));
        let mut cells: Vec<(i32, i32)> = pts
            .iter()
            .map(|(x, y)| (((x + 1.0) * 2.0) as i32, ((y + 1.0) * 2.0) as i32))
            .collect();
        cells.sort();
        cells.dedup();
        assert_eq!(cells.len(), 16);
        // Not a square: every sample kept, one per stratum of area 1/n, and
        // the strata tile the square (no region without samples).
        for n in [2usize, 3, 5, 7, 12, 17, 30] {
            let pts = stratified_square(n, || (0.5, 0.5));
            assert_eq!(pts.len(), n);
            let lo = stratified_square(n, || (0.0, 0.0));
            let hi = stratified_square(n, || (1.0, 1.0));
            let area: f32 = lo
                .iter()
                .zip(&hi)
                .map(|(a, b)| (b.0 - a.0) * (b.1 - a.1) / 4.0)
                .sum();
            assert!((area - 1.0).abs() < 1e-5, "n = {n}: strata cover {area}");
            for ((a, b), p) in lo.iter().zip(&hi).zip(&pts) {
                assert!(
                    ((b.0 - a.0) * (b.1 - a.1) / 4.0 - 1.0 / n as f32).abs() <= 1e-5,
                    "n = {n}"
                );
                assert!(a.0 <= p.0 && p.0 <= b.0 && a.1 <= p.1 && p.1 <= b.1);
                assert!(a.0 >= -1.0 && a.1 >= -1.0 && b.0 <= 1.0 + 1e-6 && b.1 <= 1.0 + 1e-6);
            }
        }
        for (a, b) in [(1.0, 0.0), (0.0, 1.0), (-1.0, -1.0), (0.3, -0.7)] {
            let (x, y) = concentric_disk(a, b);
            assert!(x * x + y * y <= 1.0 + 1e-5);
        }
    }
}
