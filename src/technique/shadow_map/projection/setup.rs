//! The light's matrices for one frame: perspective for spot lights, six
//! 90° cube faces or two paraboloid hemispheres for point lights, and an
//! orthographic box for directional lights fitted to the scene and clipped
//! to what the camera sees (wgpu's [0, 1] depth).

use super::convex::{box_planes, hexahedron_planes};
use super::roll::{self, AxisClearance, Supports};
use super::stable_window::{Hold, Window, stabilized, widen_for_kernels, xy_box};
use super::{FrustumParams, spot_focus};
use crate::scene::{Aabb, Camera, Light, LightType};
use crate::technique::light_space::up_for;
use crate::technique::params::choice_enum;
use glam::{Mat4, Vec2, Vec3, Vec4};

choice_enum! {
    /// How a light's map faces project (`PROJECTION_*` in the shaders):
    /// one perspective face (spot), six (point, cube), two dual-paraboloid
    /// hemispheres, or orthographic (directional: one map or cascades).
    pub enum MapProjection {
        Perspective = "perspective",
        Cube = "cube",
        Paraboloid = "paraboloid",
        Orthographic = "orthographic",
    }
}

/// The light's matrices for one frame.
#[derive(Clone, Debug)]
pub struct LightSetup {
    pub faces: Vec<Mat4>,
    pub near: f32,
    pub far: f32,
    /// How the faces project; `Paraboloid`: `faces` are the two
    /// hemispheres' view matrices.
    pub projection: MapProjection,
    /// World size of a texel at unit distance (perspective) or anywhere
    /// (orthographic), for a 1-texel map (cascades: of the first).
    pub texel_scale: f32,
    /// Cascaded maps: where each face's slice of the view ends.
    pub cascades: Option<CascadeSplit>,
    /// Warped faces (LiSPSM): texel sizes vary over the map, and depth is
    /// stored linear along the light as dot(row, (p, 1)), 0 nearest it.
    pub warp_depth: Option<Vec4>,
    /// One directional map: the window of stored depths (0 nearest the
    /// light) that the receivers the camera sees span
    /// ([`seen_depth_window`]); moment filters store and compare depth
    /// mapped from it onto [0, 1]. `None`: the map's whole range.
    pub moment_depth: Option<Vec2>,
}

/// The view-depth partition of cascaded maps, one entry per face.
#[derive(Clone, Debug, PartialEq)]
pub struct CascadeSplit {
    /// View depth at which the first cascade starts (the camera's near
    /// plane, or the nearest depth seen with SDSM).
    pub near: f32,
    /// View depth at which each cascade ends.
    pub far: Vec<f32>,
    /// Each cascade's world texel size for a 1-texel map.
    pub texel_scales: Vec<f32>,
}

/// A directional light's view (looking along `dir` from outside the scene)
/// and the scene's bounds in that view.
pub fn light_view_of_scene(dir: Vec3, scene_bounds: &Aabb) -> (Mat4, Aabb) {
    let dir = dir.normalize();
    let c = scene_bounds.center();
    let r = scene_bounds.bounding_radius();
    let view = glam::camera::rh::view::look_to_mat4(c - dir * (2.0 * r), dir, up_for(dir));
    (view, scene_bounds.transformed(view))
}

/// The part of the camera's view between view depths `z0` and `z1` that
/// lies in `scene_bounds`: the corners of that convex solid.
pub fn view_in_scene(
    camera: &Camera,
    aspect: f32,
    scene_bounds: &Aabb,
    z0: f32,
    z1: f32,
) -> Vec<Vec3> {
    clip_to_bounds(
        &camera.slice_corners(aspect, z0, z1.max(z0 * 1.001)),
        scene_bounds,
    )
}

/// The window of stored depths (0 nearest the light) of an orthographic
/// map `face` that the camera's view between view depths `z0` and `z1`
/// spans inside the scene, widened by a sixteenth of its width each way
/// (normal offsets, the kernel's reach); `None` where the view misses the
/// scene. A moment filter's exponent or variance then works on the depths
/// its receivers span, not on the scene's (a 2 km landscape's range left a
/// tree's shadow under 1 % of it).
pub fn seen_depth_window(
    face: Mat4,
    camera: &Camera,
    aspect: f32,
    scene_bounds: &Aabb,
    (z0, z1): (f32, f32),
) -> Option<Vec2> {
    let (lo, hi) = view_in_scene(camera, aspect, scene_bounds, z0, z1)
        .iter()
        .map(|p| face.project_point3(*p).z)
        .fold(None, |w: Option<(f32, f32)>, z| {
            Some(w.map_or((z, z), |(lo, hi)| (lo.min(z), hi.max(z))))
        })?;
    let pad = (hi - lo) / 16.0;
    Some(Vec2::new((lo - pad).max(0.0), (hi + pad).min(1.0)))
}

/// A spot light's view: from its position along its direction.
pub fn spot_view(light: &Light) -> Mat4 {
    glam::camera::rh::view::look_to_mat4(light.position, light.direction, up_for(light.direction))
}

/// Near/far of a local light around `bounds`, unless given. A point of the
/// scene at distance r from the light, seen in a face whose corner rays
/// make an angle with its axis of cosine `corner_cos`, lies at a depth of at
/// least r·`corner_cos` along that axis: the near plane stays below the
/// closest distance times that (a light outside the scene, off a corner or
/// an edge of its box, sees the box's nearer parts obliquely).
fn near_far(pos: Vec3, bounds: &Aabb, near: f32, far: f32, corner_cos: f32) -> (f32, f32) {
    let auto_far = bounds
        .corners()
        .iter()
        .map(|c| c.distance(pos))
        .fold(0.0f32, f32::max)
        .max(1e-3)
        * 1.01;
    let f = if far > 0.0 { far } else { auto_far };
    let closest = pos.clamp(bounds.min, bounds.max).distance(pos);
    let n = if near > 0.0 {
        near
    } else {
        (closest * 0.95 * corner_cos).max(f * 2e-3)
    };
    (n, f.max(n * 1.01))
}

/// The six 90° views of a point light: +X, −X, +Y, −Y, +Z, −Z.
pub fn cube_views(pos: Vec3) -> [Mat4; 6] {
    let v = |d: Vec3, up: Vec3| glam::camera::rh::view::look_to_mat4(pos, d, up);
    [
        v(Vec3::X, Vec3::NEG_Y),
        v(Vec3::NEG_X, Vec3::NEG_Y),
        v(Vec3::Y, Vec3::Z),
        v(Vec3::NEG_Y, Vec3::NEG_Z),
        v(Vec3::Z, Vec3::NEG_Y),
        v(Vec3::NEG_Z, Vec3::NEG_Y),
    ]
}

/// How a directional light's single map, or a focused spot light's, is
/// turned about the light.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Turn {
    /// The world's up along the map's y axis.
    #[default]
    Upright,
    /// The smallest square clear of the world's axes
    /// ([`Supports::fitted_turn`]), given last frame's turn.
    Fitted { previous: Option<usize> },
}

impl Turn {
    /// The turn (`roll::turn_angle`'s index) for a set with extents
    /// `supports`: upright, or [`Supports::fitted_turn`] clear of the
    /// world's axes (`axes`, computed only then).
    fn of(self, supports: &Supports, axes: impl FnOnce() -> Vec<AxisClearance>) -> usize {
        match self {
            Turn::Fitted { previous } => supports.fitted_turn(&axes(), previous),
            Turn::Upright => 0,
        }
    }

    /// Whether last frame's window may be kept under `turn`: a turned grid
    /// moved every texel anyway.
    pub(super) fn keeps_window(self, turn: usize) -> bool {
        match self {
            Turn::Fitted { previous } => previous == Some(turn),
            Turn::Upright => true,
        }
    }
}

/// What a directional light's single map is fitted to, within the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ViewFit {
    /// The camera's view of the scene: its frustum, up to where that view
    /// ends, clipped to the scene's bounds.
    #[default]
    Frustum,
    /// The camera's frustum between these view depths (SDSM's seen
    /// depths), clipped to the scene's bounds.
    Depths { near: f32, far: f32 },
    /// The pixels the camera saw (SDSM's samples), as their extents in the
    /// unturned light view; the box of the map's turn is widened by
    /// [`widen_for_kernels`] for a map of `size`².
    Samples { supports: Supports, size: u32 },
}

/// The points spanning the intersection of a hexahedron (corner `i` at
/// bit 0: x side, bit 1: y side, bit 2: z side, as [`Camera::slice_corners`](crate::scene::Camera::slice_corners) and
/// [`Aabb::corners`] number them; convex) with `bounds`: each solid's
/// corners inside the other and each one's edges through the other's faces.
/// Empty when they do not meet.
pub fn clip_to_bounds(corners: &[Vec3; 8], bounds: &Aabb) -> Vec<Vec3> {
    const EPS: f32 = 1e-4;
    let planes = hexahedron_planes(corners);
    let scale = (bounds.size().length() + (corners[7] - corners[0]).length()).max(1.0);
    let in_hexahedron = |p: Vec3| planes.iter().all(|(n, d)| n.dot(p) - d <= EPS * scale);
    let in_bounds = |p: Vec3| {
        let slack = Vec3::splat(EPS * scale);
        p.cmpge(bounds.min - slack).all() && p.cmple(bounds.max + slack).all()
    };
    let edges = |c: [Vec3; 8]| {
        (0..8usize).flat_map(move |i| {
            (0..3)
                .filter(move |axis| (i >> axis) & 1 == 0)
                .map(move |axis| (c[i], c[i | (1 << axis)]))
        })
    };
    let through = |(a, b): (Vec3, Vec3), n: Vec3, d: f32| {
        let (da, db) = (n.dot(a) - d, n.dot(b) - d);
        (da * db < 0.0).then(|| a + (b - a) * (da / (da - db)))
    };
    let box_planes = box_planes(bounds);
    let mut out: Vec<Vec3> = corners.iter().copied().filter(|&p| in_bounds(p)).collect();
    out.extend(bounds.corners().into_iter().filter(|&p| in_hexahedron(p)));
    for e in edges(*corners) {
        out.extend(
            box_planes
                .iter()
                .filter_map(|&(n, d)| through(e, n, d))
                .filter(|&p| in_bounds(p)),
        );
    }
    for e in edges(bounds.corners()) {
        out.extend(
            planes
                .iter()
                .filter_map(|&(n, d)| through(e, n, d))
                .filter(|&p| in_hexahedron(p)),
        );
    }
    out
}

/// The row over light-view (x, y, z, 1) that gives a warped map's stored
/// depth: linear along the light, 0 nearest it and 1 farthest over the
/// scene's light-view bounds `scene_ls` (widened by their margin each way).
pub fn linear_depth_row(scene_ls: &Aabb) -> Vec4 {
    let pad = scene_ls.margin();
    let (z_min, z_max) = (scene_ls.min.z - pad, scene_ls.max.z + pad);
    (Vec4::W * z_max - Vec4::Z) / (z_max - z_min)
}

/// A fitted window before it is stabilised: its turn, the window it needs
/// and how it is kept.
struct FittedWindow {
    turn: usize,
    need: Window,
    hold: Hold,
}

/// What a fitted single map (directional, or a focused spot) took: its
/// turn (`roll::turn_angle`'s index) and its window's half-extents, kept
/// next frame while they fit (`FrustumParams::previous_half`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapFit {
    pub turn: usize,
    pub half: Vec2,
}

/// Light matrices: spot (perspective over the cone), point (six faces),
/// directional (orthographic around the scene, its xy clipped to the
/// camera's view of the scene).
pub fn light_setup(
    light: &Light,
    scene_bounds: &Aabb,
    camera: &Camera,
    aspect: f32,
    fp: &FrustumParams,
) -> LightSetup {
    let FrustumParams {
        near,
        far,
        paraboloid,
        ..
    } = *fp;
    use glam::camera::rh::proj::directx::perspective;
    match light.kind {
        LightType::Spot => spot_setup(light, scene_bounds, fp).0,
        LightType::Point if paraboloid => {
            // Depth along the ray from the light: no corners.
            let (n, f) = near_far(light.position, scene_bounds, near, far, 1.0);
            let v = |d: Vec3| glam::camera::rh::view::look_to_mat4(light.position, d, Vec3::Z);
            LightSetup {
                faces: vec![v(Vec3::NEG_Y), v(Vec3::Y)],
                near: n,
                far: f,
                projection: MapProjection::Paraboloid,
                // At the centre of a hemisphere, uv changes by 1/2 per radian.
                texel_scale: 4.0,
                cascades: None,
                warp_depth: None,
                moment_depth: None,
            }
        }
        LightType::Point => {
            // A 90° face's corner rays: cos = 1/√3.
            let (n, f) = near_far(light.position, scene_bounds, near, far, 3f32.sqrt().recip());
            let proj = perspective(std::f32::consts::FRAC_PI_2, 1.0, n, f);
            LightSetup {
                faces: cube_views(light.position)
                    .iter()
                    .map(|v| proj * *v)
                    .collect(),
                near: n,
                far: f,
                projection: MapProjection::Cube,
                texel_scale: 2.0,
                cascades: None,
                warp_depth: None,
                moment_depth: None,
            }
        }
        LightType::Directional => directional_setup(light, scene_bounds, camera, aspect, fp).0,
    }
}

/// A spot light's map: a perspective over its cone (`fp.fov_deg`, else
/// the cone plus 4°) or, with `fp.view_fit` the samples, over the square
/// of its image they need (`spot_focus`), turned as `fp.turn` says; and
/// what it took.
pub fn spot_setup(light: &Light, scene_bounds: &Aabb, fp: &FrustumParams) -> (LightSetup, MapFit) {
    use glam::camera::rh::proj::directx::perspective;
    let fov = if fp.fov_deg > 0.0 {
        fp.fov_deg
    } else {
        (2.0 * light.outer_cone_deg + 4.0).min(170.0)
    }
    .to_radians();
    let full = (fov * 0.5).tan();
    let corner_cos = 1.0 / (1.0 + 2.0 * full * full).sqrt();
    let (n, f) = near_far(light.position, scene_bounds, fp.near, fp.far, corner_cos);
    let base = spot_view(light);
    let (turn, window) = match fp.view_fit {
        ViewFit::Samples { supports, size } => {
            let turn = fp
                .turn
                .of(&supports, || spot_focus::axes_over_seen(base, &supports));
            let kept = fp.kept_under(turn);
            let window = spot_focus::focused_window(full, &supports, size, turn, &kept);
            (turn, window)
        }
        _ => (
            0,
            Window {
                half: Vec2::splat(full),
                centre: Vec2::ZERO,
            },
        ),
    };
    let view = roll::rolled(base, roll::turn_angle(turn));
    let setup = LightSetup {
        faces: vec![spot_focus::image_window(full, window) * perspective(fov, 1.0, n, f) * view],
        near: n,
        far: f,
        projection: MapProjection::Perspective,
        texel_scale: 2.0 * window.half.max_element(),
        cascades: None,
        warp_depth: None,
        moment_depth: None,
    };
    let fit = MapFit {
        turn,
        half: window.half,
    };
    (setup, fit)
}

/// A directional light's single map: the window around `fp.view_fit` in
/// the light view turned as `fp.turn` says (stabilised with
/// `fp.stabilize_size`), and what it took. The turn is the one with the
/// smallest square around that view ([`Supports::fitted_turn`]), and the
/// window is that square's box: its shorter side needs no texels past the
/// box, so they go to finer texels along it. `texel_scale` is the longer
/// side's.
pub fn directional_setup(
    light: &Light,
    scene_bounds: &Aabb,
    camera: &Camera,
    aspect: f32,
    fp: &FrustumParams,
) -> (LightSetup, MapFit) {
    use glam::camera::rh::proj::directx::orthographic;
    let base = light_view_of_scene(light.direction, scene_bounds).0;
    let seen = |z0: f32, z1: f32| {
        Supports::of_points(
            view_in_scene(camera, aspect, scene_bounds, z0, z1)
                .iter()
                .map(|p| base.transform_point3(*p).truncate()),
        )
    };
    // The window around a set's extents in the view turned as `fp.turn`
    // says (widened for the kernels on a `size`² map where given).
    let window_of = |s: Supports, margin: Option<u32>, hold: Hold| {
        let turn = fp.turn.of(&s, || roll::world_axes_in_image(base));
        let b = s.box_at(turn);
        FittedWindow {
            turn,
            need: Window::around(margin.map_or(b, |size| widen_for_kernels(b, size))),
            hold,
        }
    };
    let frustum =
        || seen(camera.near, camera.reach(scene_bounds)).map(|s| window_of(s, None, Hold::VIEW));
    let fitted = match fp.view_fit {
        // The pixels seen, with room to grow; the view of the scene where
        // its longer side fits in that room, which is steadier (asking both
        // sides to fit took the pixels' window where the scene's was
        // better).
        ViewFit::Samples { supports, size } => {
            let samples = window_of(supports, Some(size), Hold::SAMPLES);
            let room = samples.need.half.max_element() * Hold::SAMPLES.headroom;
            match frustum() {
                Some(f) if f.need.half.max_element() <= room => Some(f),
                _ => Some(samples),
            }
        }
        ViewFit::Frustum => frustum(),
        ViewFit::Depths { near, far } => seen(near, far).map(|s| window_of(s, None, Hold::VIEW)),
    };
    let turn = fitted.as_ref().map_or(0, |f| f.turn);
    let kept = fp.kept_under(turn);
    let view = roll::rolled(base, roll::turn_angle(turn));
    let scene_ls = scene_bounds.transformed(view);
    let fitted = fitted.unwrap_or_else(|| FittedWindow {
        turn,
        need: Window::around(xy_box(&scene_ls)),
        hold: Hold::VIEW,
    });
    let Window { half, centre: c } = stabilized(fitted.need, &kept, fitted.hold);
    // View space looks down −z: depth range from the scene's z extent.
    let pad = scene_ls.margin();
    let (n, f) = (-scene_ls.max.z - pad, -scene_ls.min.z + pad);
    let (lo, hi) = (c - half, c + half);
    let setup = LightSetup {
        faces: vec![orthographic(lo.x, hi.x, lo.y, hi.y, n.max(0.0), f) * view],
        near: n.max(0.0),
        far: f,
        projection: MapProjection::Orthographic,
        texel_scale: 2.0 * half.max_element(),
        cascades: None,
        warp_depth: None,
        moment_depth: None,
    };
    (setup, MapFit { turn, half })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A low sun along a 1 km strip and a camera seeing its first 60 m: the
    /// window of stored depths holds every point of that view inside the
    /// scene (widened by a sixteenth each way), and is a small part of the
    /// map's depth range, which spans the whole strip.
    #[test]
    fn the_seen_depth_window_holds_the_view_and_little_else() {
        let bounds = Aabb {
            min: Vec3::new(-20.0, 0.0, -1000.0),
            max: Vec3::new(20.0, 10.0, 0.0),
        };
        let light = Light::directional(Vec3::new(0.0, -0.2, -1.0), 1.0);
        let mut camera = Camera::new(Vec3::new(0.0, 5.0, 0.0), Vec3::new(0.0, 0.0, -30.0));
        camera.far = 60.0;
        let (setup, _) =
            directional_setup(&light, &bounds, &camera, 1.0, &FrustumParams::default());
        let w = seen_depth_window(
            setup.faces[0],
            &camera,
            1.0,
            &bounds,
            (camera.near, camera.far),
        )
        .expect("the view lies in the scene");
        assert!(0.0 <= w.x && w.x < w.y && w.y <= 1.0, "{w}");
        assert!(w.y - w.x < 0.15, "the window spans {w} of a 1 km range");
        for p in view_in_scene(&camera, 1.0, &bounds, camera.near, camera.far) {
            let z = setup.faces[0].project_point3(p).z;
            assert!(w.x < z && z < w.y, "{p} at {z} outside {w}");
        }
        let behind = Camera::new(Vec3::new(0.0, 5.0, 100.0), Vec3::new(0.0, 5.0, 200.0));
        assert_eq!(
            seen_depth_window(setup.faces[0], &behind, 1.0, &bounds, (1.0, 50.0)),
            None,
            "a view outside the scene has no window"
        );
    }

    /// A point light off an edge of the scene's box sees the box's nearer
    /// parts obliquely in a cube face: every point of the box inside a
    /// face's frustum lies beyond that face's near plane (the near plane at
    /// 0.95 of the closest distance clipped them: the box's side at x = 0.2
    /// seen from (−1, −1, 0.5) in the +x face lies at depth 1.2, nearer
    /// than 0.95·√2 = 1.34).
    #[test]
    fn a_light_off_the_scenes_edge_keeps_the_whole_scene_beyond_the_near_plane() {
        let bounds = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let light = Light::point(Vec3::new(-1.0, -1.0, 0.5), 1.0);
        let camera = Camera::new(Vec3::new(3.0, 3.0, 3.0), Vec3::splat(0.5));
        let s = light_setup(&light, &bounds, &camera, 1.0, &FrustumParams::default());
        let steps = 20;
        let mut seen = 0;
        for i in 0..=steps {
            for j in 0..=steps {
                for k in 0..=steps {
                    let p = Vec3::new(i as f32, j as f32, k as f32) / steps as f32;
                    for face in &s.faces {
                        let c = *face * p.extend(1.0);
                        if c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w {
                            seen += 1;
                            assert!(c.z >= 0.0 && c.z <= c.w, "{p} clipped: z/w = {}", c.z / c.w);
                        }
                    }
                }
            }
        }
        assert!(seen >= 21 * 21 * 21, "{seen}");
    }

    /// The view of a camera at the origin looking down −z with a 90° field
    /// and a square frame, between depths 1 and 10.
    fn slice() -> [Vec3; 8] {
        let mut cam = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0));
        cam.fov_y_deg = 90.0;
        cam.slice_corners(1.0, 1.0, 10.0)
    }

    #[test]
    fn clipping_a_view_slice_to_bounds_keeps_what_lies_in_both() {
        // A box inside the slice: its own corners.
        let inner = Aabb {
            min: Vec3::new(-1.0, -1.0, -5.0),
            max: Vec3::new(1.0, 1.0, -2.0),
        };
        assert_eq!(Aabb::from_points(clip_to_bounds(&slice(), &inner)), inner);
        // A box the slice cuts: at depth z the slice spans |x|, |y| ≤ z, so
        // y ≥ 0 above a floor at y = 0 up to depth 10 spans x ∈ [−10, 10],
        // y ∈ [0, 10], z ∈ [−10, −1] — capped by the box's y ≤ 3.
        let floor = Aabb {
            min: Vec3::new(-100.0, 0.0, -100.0),
            max: Vec3::new(100.0, 3.0, 100.0),
        };
        let b = Aabb::from_points(clip_to_bounds(&slice(), &floor));
        let want = Aabb {
            min: Vec3::new(-10.0, 0.0, -10.0),
            max: Vec3::new(10.0, 3.0, -1.0),
        };
        assert!(
            (b.min - want.min).abs().max_element() < 1e-3
                && (b.max - want.max).abs().max_element() < 1e-3,
            "{b:?}"
        );
        // A box behind the camera: nothing.
        let behind = Aabb {
            min: Vec3::new(-1.0, -1.0, 2.0),
            max: Vec3::new(1.0, 1.0, 4.0),
        };
        assert!(clip_to_bounds(&slice(), &behind).is_empty());
    }
}
