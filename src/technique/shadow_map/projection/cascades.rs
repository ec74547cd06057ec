//! Cascaded (parallel-split) shadow maps for directional lights (Zhang et
//! al. 2006, [000] §4, [001] §3, [002] §2): the view depth [n, f] cut at
//! z_i = λ·n·(f/n)^(i/N) + (1−λ)·(n + (f−n)·i/N), one orthographic map per
//! slice. A stabilised cascade bounds its slice by a sphere, whose radius
//! does not change when the camera moves or turns, and snaps its centre to
//! whole texels of the light's view, so that texel edges stay in place; on
//! an axis where that square is wider than the scene, it takes the scene's
//! extent, as fixed as the sphere.

use super::depth_bounds::SeenBounds;
use super::setup::MapProjection;
use super::setup::{CascadeSplit, LightSetup, light_view_of_scene};
use super::stable_window::{Window, quantize_down, quantize_up, widen_for_kernels, xy_box};
use super::view_depths::geometry_depths;
use crate::scene::extent::SceneExtent;
use crate::scene::{Aabb, Camera};
use crate::technique::shadow_map::config::partition::{Cascades, Fit};
use glam::{Vec2, Vec3};

/// The `count + 1` split distances from `near` to `far` (view depth).
pub fn split_distances(near: f32, far: f32, count: u32, lambda: f32) -> Vec<f32> {
    (0..=count)
        .map(|i| {
            let s = i as f32 / count as f32;
            let log = near * (far / near).powf(s);
            let uniform = near + (far - near) * s;
            lambda * log + (1.0 - lambda) * uniform
        })
        .collect()
}

/// A stabilised cascade's square (light view xy): the slice's bounding
/// sphere, its radius rounded up to 1/64 of a unit (float noise must not
/// resize it) and its centre snapped to the texel grid of a `size`² map.
/// (A single map keeps its fitted window instead, made stable by
/// `stable_window::stabilized`.)
pub fn stable_square(corners_ls: &[Vec3; 8], size: u32) -> Window {
    let centre = corners_ls.iter().copied().sum::<Vec3>() / 8.0;
    let radius = corners_ls
        .iter()
        .map(|c| c.distance(centre))
        .fold(0.0f32, f32::max);
    let half = ((radius * 64.0).ceil() / 64.0).max(1.0 / 64.0);
    Window {
        half: glam::Vec2::splat(half),
        centre: centre.truncate(),
    }
    .snapped(size)
}

/// A stabilised cascade's `square`, but on each axis where it is at least
/// as wide as the scene's light-view box `scene_ls` (widened for kernels),
/// that box's extent: the scene does not move, so the window is as stable,
/// and the square's texels past the scene fall on nothing (a far cascade
/// on a small scene, or a camera that sees the whole scene). The square
/// comes snapped; a clipped window is snapped to its own texels.
fn within_scene(square: Window, scene_ls: &Aabb, size: u32) -> Window {
    let scene = Window::around(widen_for_kernels(xy_box(scene_ls), size));
    let wider = square.half.cmpge(scene.half);
    if !wider.any() {
        return square;
    }
    Window {
        half: Vec2::select(wider, scene.half, square.half),
        centre: Vec2::select(wider, scene.centre, square.centre),
    }
    .snapped(size)
}

/// The view depths the cascades partition (seen with `aspect`): stabilised,
/// from the camera's near plane, or the scene's box when the camera is
/// outside it, to the last split of `cascades` (its `max_distance`, else
/// the far side of the scene's bounding sphere), neither of which turns
/// with the camera; unstabilised, where the frustum meets the scene's
/// clusters ([`geometry_depths`]) up to the same limit; or with SDSM what
/// the camera saw within the same limit (stabilised: rounded outwards to
/// eighths of an octave).
pub fn partitioned_depths(
    camera: &Camera,
    aspect: f32,
    scene: SceneExtent,
    cascades: &Cascades,
    seen: Option<&SeenBounds>,
) -> (f32, f32) {
    let limit = cascades.far_limit(camera.far);
    let (near, far) = match seen.filter(|_| cascades.fit != Fit::Frustum) {
        Some(s) => {
            let near = s.near.max(camera.near);
            let far = s.far.min(limit);
            if cascades.stabilize && cascades.fit == Fit::Depth {
                (
                    quantize_down(near).max(camera.near),
                    quantize_up(far).min(limit),
                )
            } else {
                (near, far)
            }
        }
        None => {
            let (near, reach) = if cascades.stabilize {
                // Depths that do not turn with the camera. The reach (the
                // far side of the scene's sphere) rounded up to eighths of
                // an octave, so that the splits (and with them each
                // cascade's size) stay put while the camera's distance to
                // the scene changes a little. From a camera outside the
                // scene's box, the depths before the box hold nothing to
                // shadow: the splits start at the least view depth a point
                // of the box can have inside the frustum, its distance
                // times the cosine of the frustum's corner ray, rounded
                // down to a power of two, so that the splits stay put
                // while the camera moves, as the reach's rounding up keeps
                // them. No cascade is spent on empty space.
                let bounds = scene.bounds;
                let reach = quantize_up(camera.reach(bounds)).min(camera.far);
                let closest = camera
                    .eye
                    .clamp(bounds.min, bounds.max)
                    .distance(camera.eye);
                let gap = closest * frustum_corner_cos(camera, aspect) - bounds.margin();
                let octave = 2f32.powf(gap.max(camera.near).log2().floor());
                (octave.max(camera.near), reach)
            } else {
                // The depths that hold geometry: from a camera standing on
                // a floor, the nearest is where the floor meets the
                // frustum's lower plane, not its near plane; looking along
                // a street, the farthest is the last building's, not the
                // far side of the city's sphere. They turn with the
                // camera, so stabilised cascades do not take them.
                let reach = camera.reach(scene.bounds);
                geometry_depths(camera, aspect, scene.parts, reach).unwrap_or((camera.near, reach))
            };
            let far = if cascades.max_distance > 0.0 {
                limit
            } else {
                reach
            };
            (near.min(far), far)
        }
    };
    (near, far.max(near * 1.01))
}

/// The cosine of the angle between a camera's axis and the rays through
/// its frame's corners: a point at distance d inside the frustum lies at a
/// view depth of at least d times this.
fn frustum_corner_cos(camera: &Camera, aspect: f32) -> f32 {
    let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let tan_diagonal = tan_y * (1.0 + aspect * aspect).sqrt();
    1.0 / (1.0 + tan_diagonal * tan_diagonal).sqrt()
}

/// The light setup of a directional light travelling along `dir` with
/// `cascades.count` maps of `size`², fitted to the camera's frustum or, with
/// `seen` (SDSM), to what the camera saw.
pub fn cascade_setup(
    dir: Vec3,
    scene: SceneExtent,
    camera: &Camera,
    aspect: f32,
    cascades: &Cascades,
    size: u32,
    seen: Option<&SeenBounds>,
) -> LightSetup {
    use glam::camera::rh::proj::directx::orthographic;
    let (view, scene_ls) = light_view_of_scene(dir, scene.bounds);
    let (near, far) = partitioned_depths(camera, aspect, scene, cascades, seen);
    let splits = split_distances(near, far, cascades.count, cascades.split_lambda);
    let samples = seen
        .filter(|_| cascades.fit == Fit::Samples)
        .map(|s| s.cascades_xy.as_slice())
        .unwrap_or_default();
    // View space looks down −z: depth range from the scene's z extent, so
    // that every caster is in every cascade's depth range.
    let pad = scene_ls.margin();
    let (n, f) = ((-scene_ls.max.z - pad).max(0.0), -scene_ls.min.z + pad);
    let mut faces = vec![];
    let mut texel_scales = vec![];
    for (i, w) in splits.windows(2).enumerate() {
        let corners = camera
            .slice_corners(aspect, w[0], w[1])
            .map(|p| view.transform_point3(p));
        // Fitted cascades take the box they need (finer texels along its
        // shorter side); stabilised ones the square of a sphere, which no
        // turn of the camera changes, or the scene's side where it is
        // narrower.
        let Window { half, centre: c } = if let Some(Some(seen_box)) = samples.get(i) {
            // The box of the pixels this cascade shades, widened for kernels.
            Window::around(widen_for_kernels(*seen_box, size))
        } else if cascades.stabilize && cascades.fit != Fit::Samples {
            within_scene(stable_square(&corners, size), &scene_ls, size)
        } else {
            let b = Aabb::from_points(corners);
            let (min_x, max_x) = (b.min.x.max(scene_ls.min.x), b.max.x.min(scene_ls.max.x));
            let (min_y, max_y) = (b.min.y.max(scene_ls.min.y), b.max.y.min(scene_ls.max.y));
            Window::around(if min_x < max_x && min_y < max_y {
                [min_x, min_y, max_x, max_y]
            } else {
                xy_box(&b)
            })
        };
        let (lo, hi) = (c - half, c + half);
        faces.push(orthographic(lo.x, hi.x, lo.y, hi.y, n, f) * view);
        texel_scales.push(2.0 * half.max_element());
    }
    LightSetup {
        texel_scale: texel_scales[0],
        faces,
        near: n,
        far: f,
        projection: MapProjection::Orthographic,
        cascades: Some(CascadeSplit {
            near,
            far: splits[1..].to_vec(),
            texel_scales,
        }),
        warp_depth: None,
        moment_depth: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::shadow_map::config::partition::Select;
    use glam::{Mat4, Vec4};

    /// The NDC position of `p` in `face`.
    fn project(face: Mat4, p: Vec3) -> Vec3 {
        let c = face * Vec4::new(p.x, p.y, p.z, 1.0);
        c.truncate() / c.w
    }

    #[test]
    fn split_distances_for_uniform_practical_and_logarithmic_schemes() {
        // n = 1, f = 16, N = 4: uniform 1, 4.75, 8.5, 12.25, 16; logarithmic
        // 1, 2, 4, 8, 16; λ = 0.5 their mean.
        let uniform = split_distances(1.0, 16.0, 4, 0.0);
        let log = split_distances(1.0, 16.0, 4, 1.0);
        let half = split_distances(1.0, 16.0, 4, 0.5);
        let close = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-4);
        assert!(
            close(&uniform, &[1.0, 4.75, 8.5, 12.25, 16.0]),
            "{uniform:?}"
        );
        assert!(close(&log, &[1.0, 2.0, 4.0, 8.0, 16.0]), "{log:?}");
        assert!(close(&half, &[1.0, 3.375, 6.25, 10.125, 16.0]), "{half:?}");
    }

    #[test]
    fn slice_corners_lie_at_their_view_depths() {
        let cam = Camera::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 0.0, -2.0));
        let view = cam.view();
        let c = cam.slice_corners(1.5, 2.0, 7.0);
        for (i, p) in c.iter().enumerate() {
            let z = -view.transform_point3(*p).z;
            assert!((z - if i < 4 { 2.0 } else { 7.0 }).abs() < 1e-4, "{i}: {z}");
        }
        // The corners project onto the corners of the camera's NDC square.
        let vp = cam.projection(1.5) * view;
        let ndc = project(vp, c[7]);
        assert!(
            (ndc.x - 1.0).abs() < 1e-4 && (ndc.y - 1.0).abs() < 1e-4,
            "{ndc}"
        );
    }

    /// Texel coordinates (NDC scaled by half the map size) of `p` in `face`.
    fn texel_of(face: Mat4, p: Vec3, size: u32) -> glam::Vec2 {
        project(face, p).truncate() * 0.5 * size as f32
    }

    /// A stabilised cascade keeps its texel grid when the camera moves by a
    /// fraction of a texel: every world point keeps its texel coordinates
    /// (up to float rounding), and the map keeps its size.
    #[test]
    fn a_stabilised_cascade_keeps_its_texel_grid_under_small_camera_moves() {
        let bounds = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 20.0, 50.0),
        };
        let dir = Vec3::new(-0.5, -1.0, -0.35);
        let stable = Cascades {
            count: 3,
            split_lambda: 0.5,
            max_distance: 60.0,
            stabilize: true,
            blend: 0.0,
            select: Select::Depth,
            fit: Fit::Frustum,
        };
        let size = 512;
        let cam = Camera::new(Vec3::new(0.0, 1.7, 30.0), Vec3::new(0.0, 3.0, 0.0));
        let a = cascade_setup(
            dir,
            SceneExtent::of_box(&bounds),
            &cam,
            16.0 / 9.0,
            &stable,
            size,
            None,
        );
        let probe = Vec3::new(0.3, 0.0, 25.0);
        for step in [0.013f32, 0.21, 0.37] {
            let moved = Camera {
                eye: cam.eye + Vec3::new(step, 0.0, -step),
                target: cam.target + Vec3::new(step, 0.0, -step),
                ..cam
            };
            let b = cascade_setup(
                dir,
                SceneExtent::of_box(&bounds),
                &moved,
                16.0 / 9.0,
                &stable,
                size,
                None,
            );
            let (sa, sb) = (a.cascades.as_ref().unwrap(), b.cascades.as_ref().unwrap());
            assert_eq!(sa.texel_scales, sb.texel_scales);
            // The probe's texel coordinate in cascade 0 moves by whole texels.
            let d = texel_of(b.faces[0], probe, size) - texel_of(a.faces[0], probe, size);
            let frac = (d - d.round()).abs();
            assert!(frac.max_element() < 1e-2, "step {step}: grid moved by {d}");
        }
        // Unstabilised cascades refit and slide by fractions of a texel.
        let fitted = Cascades {
            stabilize: false,
            ..stable
        };
        let a = cascade_setup(
            dir,
            SceneExtent::of_box(&bounds),
            &cam,
            16.0 / 9.0,
            &fitted,
            size,
            None,
        );
        let moved = Camera {
            eye: cam.eye + Vec3::new(0.21, 0.0, -0.21),
            target: cam.target + Vec3::new(0.21, 0.0, -0.21),
            ..cam
        };
        let b = cascade_setup(
            dir,
            SceneExtent::of_box(&bounds),
            &moved,
            16.0 / 9.0,
            &fitted,
            size,
            None,
        );
        let d = texel_of(b.faces[0], probe, size) - texel_of(a.faces[0], probe, size);
        assert!((d - d.round()).abs().max_element() > 1e-2, "{d}");
    }

    #[test]
    fn stable_sizes_are_eighth_octaves_and_centres_whole_texels() {
        use crate::technique::shadow_map::projection::FrustumParams;
        use crate::technique::shadow_map::projection::stable_window::{
            Hold, Window, quantize_up, stabilized,
        };
        assert!((quantize_up(1.0) - 1.0).abs() < 1e-6);
        assert!((quantize_up(1.01) - 2f32.powf(0.125)).abs() < 1e-5);
        // log2 100 = 6.644: the next eighth is 54/8.
        assert!((quantize_up(100.0) - 2f32.powf(54.0 / 8.0)).abs() < 1e-3);
        // Small changes of the fitted square leave size and grid in place.
        let fit = |h: f32, x: f32, y: f32| {
            let need = Window {
                half: glam::Vec2::splat(h),
                centre: glam::Vec2::new(x, y),
            };
            let fp = FrustumParams {
                stabilize_size: Some(512),
                ..Default::default()
            };
            stabilized(need, &fp, Hold::VIEW)
        };
        let a = fit(10.0, 3.21, -7.72);
        let b = fit(10.02, 3.2101, -7.721);
        assert_eq!(a, b);
        let texel = 2.0 * a.half.x / 512.0;
        for v in a.centre.to_array() {
            assert!(((v / texel) - (v / texel).round()).abs() < 1e-3, "{v}");
        }
        assert!(a.half.x >= 10.0 && a.half.x < 10.0 * 1.091);
    }

    #[test]
    fn a_stabilised_cascade_wider_than_the_scene_takes_the_scenes_box_and_keeps_it() {
        // A 20 × 4 × 8 scene seen from 40 units away down to 100: the last
        // slice's sphere is far wider than the scene on both axes.
        let bounds = Aabb {
            min: Vec3::new(-10.0, 0.0, -4.0),
            max: Vec3::new(10.0, 4.0, 4.0),
        };
        let c = Cascades {
            count: 4,
            split_lambda: 0.9,
            max_distance: 100.0,
            stabilize: true,
            blend: 0.05,
            select: Select::Map,
            fit: Fit::Frustum,
        };
        let dir = Vec3::new(0.3, -1.0, 0.2);
        let setup = |eye: Vec3| {
            let cam = Camera::new(eye, Vec3::ZERO);
            cascade_setup(dir, SceneExtent::of_box(&bounds), &cam, 1.5, &c, 1024, None)
        };
        let a = setup(Vec3::new(0.0, 5.0, 40.0));
        let (_, scene_ls) = light_view_of_scene(dir, &bounds);
        let scene_side = (scene_ls.max - scene_ls.min).truncate();
        let last = *a.cascades.as_ref().unwrap().texel_scales.last().unwrap();
        // Its longer side is the scene's, widened by the 16 kernel texels on
        // each side (h·(1 − 32/1024) = the scene's half), not the sphere's.
        let widened = scene_side.max_element() / (1.0 - 32.0 / 1024.0);
        assert!((last - widened).abs() < 1e-3, "{last} vs {widened}");
        // Every corner of the scene lies inside it, off its border.
        let face = a.faces[3];
        for i in 0..8 {
            let p = Vec3::new(
                [bounds.min.x, bounds.max.x][i & 1],
                [bounds.min.y, bounds.max.y][(i >> 1) & 1],
                [bounds.min.z, bounds.max.z][i >> 2],
            );
            let q = project(face, p);
            assert!(q.x.abs() < 0.99 && q.y.abs() < 0.99, "{p} at {q}");
        }
        // A camera that moves keeps that cascade's window exactly: the
        // scene did not move.
        let b = setup(Vec3::new(0.37, 5.2, 40.6));
        assert_eq!(a.faces[3], b.faces[3]);
    }

    #[test]
    fn each_cascade_covers_its_slice_and_the_last_ends_at_max_distance() {
        let bounds = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 20.0, 50.0),
        };
        let cam = Camera::new(Vec3::new(0.0, 1.7, 30.0), Vec3::new(0.0, 3.0, 0.0));
        for stabilize in [false, true] {
            let c = Cascades {
                count: 4,
                split_lambda: 0.5,
                max_distance: 40.0,
                stabilize,
                blend: 0.1,
                select: Select::Depth,
                fit: Fit::Frustum,
            };
            let s = cascade_setup(
                Vec3::new(0.2, -1.0, 0.1),
                SceneExtent::of_box(&bounds),
                &cam,
                1.5,
                &c,
                1024,
                None,
            );
            let split = s.cascades.as_ref().unwrap();
            assert_eq!(s.faces.len(), 4);
            assert!((split.far[3] - 40.0).abs() < 1e-4);
            let d = split_distances(cam.near, 40.0, 4, 0.5);
            for (i, face) in s.faces.iter().enumerate() {
                for p in cam.slice_corners(1.5, d[i], d[i + 1]) {
                    let q = project(*face, p);
                    // Inside the map's square (stabilised: the sphere's)
                    // unless clipped to the scene.
                    let inside = q.x.abs() <= 1.0 + 1e-3 && q.y.abs() <= 1.0 + 1e-3;
                    let in_scene = p.x.abs() < 50.0 && p.z.abs() < 50.0 && p.y.abs() < 20.0;
                    assert!(inside || !in_scene, "cascade {i} misses {p}: {q}");
                }
            }
            // Nearer cascades have smaller texels.
            assert!(
                split.texel_scales.windows(2).all(|w| w[0] < w[1]),
                "{:?}",
                split.texel_scales
            );
        }
    }
}
