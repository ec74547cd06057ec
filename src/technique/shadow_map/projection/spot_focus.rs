//! A spot light's map focused on what the camera sees of its cone
//! (`fit=samples`, the one-map default): the map's square in the light's
//! image — the plane z = −1 of its view, where a point sits at
//! (x/−z, y/−z) — is fitted around the pixels the light reaches, from
//! SDSM's reduction (`depth_bounds.wgsl`), instead of the whole cone.
//! Seen from inside a scene a spot covers, the camera sees a small part of
//! the cone, and every texel spent on the rest is lost. Casters need no
//! room of their own: one that shades a seen pixel lies on the ray from the
//! light to it, so at the same place in the image. The window is the
//! square around the pixels' box, stabilised as a directional map's window
//! is (its side in eighths of an octave, its centre on whole texels, last
//! frame's kept while it fits), so that it does not slide its texel grid as
//! the camera moves. It stays square: a spot seen along a street covers a
//! strip of its image, and texels much finer across the strip narrow the
//! PCF kernel, which then averages a staircase across a grazing wall over
//! fewer steps.

use super::FrustumParams;
use super::convex::{box_planes, from_view, hexahedron_planes, polytope_vertices};
use super::roll::{AxisClearance, Supports, TURNS, turn_angle, world_axes_in_perspective_image};
use super::stable_window::{Hold, Window, stabilized, widen_for_kernels};
use crate::scene::{Aabb, Camera};
use glam::{Mat4, Vec2, Vec3};

/// The focused square in the light's image turned by `turn`
/// (`roll::turn_angle`'s index): its window (x/−z, y/−z), inside the
/// cone's square of half-extent `full`; the cone's square itself where the
/// seen pixels need most of it.
pub fn focused_window(
    full: f32,
    supports: &Supports,
    size: u32,
    turn: usize,
    fp: &FrustumParams,
) -> Window {
    let need = Window::around(widen_for_kernels(supports.box_at(turn), size)).square();
    let fitted = stabilized(need, fp, Hold::SAMPLES);
    // Inside the cone's square: the centre moved in (whole texels of the
    // rounded size, so that the grid stays where it was).
    let half = fitted.half.min(Vec2::splat(full));
    let room = Vec2::splat(full) - half;
    let inside = Window {
        half,
        centre: fitted.centre.clamp(-room, room),
    };
    match fp.stabilize_size {
        Some(size) => inside.snapped(size),
        None => inside,
    }
}

/// The world's axes as seen over the pixels the map is focused on: in a
/// spot's perspective image they turn from place to place (edges along
/// the vertical radiate from its vanishing point), so they are taken at
/// the corners and the centre of the tightest box around the samples —
/// the box of least area among the turns, which hugs a strip (a street
/// seen along its length) where an upright one would not. A turn then
/// keeps clear of them everywhere, or comes nearest to
/// ([`Supports::fitted_turn`]).
pub fn axes_over_seen(view: Mat4, supports: &Supports) -> Vec<AxisClearance> {
    let area = |j: usize| {
        let [x0, y0, x1, y1] = supports.box_at(j);
        (x1 - x0) * (y1 - y0)
    };
    let tight = (0..TURNS)
        .min_by(|&a, &b| area(a).total_cmp(&area(b)))
        .unwrap_or(0);
    let [x0, y0, x1, y1] = supports.box_at(tight);
    let unturn = Vec2::from_angle(turn_angle(tight));
    [
        (x0, y0),
        (x1, y0),
        (x0, y1),
        (x1, y1),
        ((x0 + x1) * 0.5, (y0 + y1) * 0.5),
    ]
    .into_iter()
    .flat_map(|(x, y)| world_axes_in_perspective_image(view, unturn.rotate(Vec2::new(x, y))))
    .collect()
}

/// `fit=frustum` under a spot light: the extents, in the image of its view
/// `view` (x/−z, y/−z), of what the camera's view can hold of its cone —
/// the view up to where it leaves the scene, inside the scene and inside
/// the pyramid of half-extent `cone_tan` — in place of the pixels seen
/// that `fit=samples` reduces. `None` where the view holds none of it.
pub fn frustum_supports(
    view: Mat4,
    cone_tan: f32,
    (camera, aspect): (&Camera, f32),
    scene: &Aabb,
) -> Option<Supports> {
    let reach = camera.reach(scene).max(camera.near * 1.01);
    let corners = camera.slice_corners(aspect, camera.near, reach);
    let scale = (scene.size().length() + (corners[7] - corners[0]).length()).max(1.0);
    // The pyramid's four sides through the apex, a·v ≤ 0 in the light's
    // view, and a plane just before the apex (the image is x/−z), ten
    // times farther than `polytope_vertices` lets a vertex stray.
    let sides = [
        Vec3::new(1.0, 0.0, cone_tan),
        Vec3::new(-1.0, 0.0, cone_tan),
        Vec3::new(0.0, 1.0, cone_tan),
        Vec3::new(0.0, -1.0, cone_tan),
    ]
    .map(|a| (a, 0.0));
    let before_apex = (Vec3::Z, -1e-3 * scale);
    let mut planes = hexahedron_planes(&corners);
    planes.extend(box_planes(scene));
    planes.extend(
        sides
            .into_iter()
            .chain([before_apex])
            .map(|half_space| from_view(view, half_space)),
    );
    let image = |p: &Vec3| {
        let v = view.transform_point3(*p);
        Vec2::new(v.x, v.y) / -v.z
    };
    Supports::of_points(polytope_vertices(&planes, scale).iter().map(image))
}

/// The clip-space window that turns a perspective over the square of
/// half-extent `full` into one over the window `w`:
/// x' = (full·x − centre.x·w)/half.x (and y alike), so that x'/w =
/// (x/−z − centre.x)/half.x.
pub fn image_window(full: f32, w: Window) -> Mat4 {
    let s = full / w.half;
    Mat4::from_cols(
        glam::Vec4::new(s.x, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, s.y, 0.0, 0.0),
        glam::Vec4::Z,
        (-w.centre / w.half).extend(0.0).extend(1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec3, Vec4};

    /// The supports of a box of the light's image.
    fn seen(x0: f32, y0: f32, x1: f32, y1: f32) -> Supports {
        Supports::of_points([(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| Vec2::new(x, y)))
            .unwrap()
    }

    #[test]
    fn the_window_maps_the_focused_window_onto_the_map() {
        // A 90° perspective (full = 1) focused on the window of
        // half-extents 0.25 × 0.125 around (0.5, −0.25): its corners go to
        // the map's corners, at any depth.
        let proj =
            glam::camera::rh::proj::directx::perspective(90f32.to_radians(), 1.0, 0.1, 100.0);
        let window = Window {
            half: Vec2::new(0.25, 0.125),
            centre: Vec2::new(0.5, -0.25),
        };
        let m = image_window(1.0, window) * proj;
        for z in [0.5f32, 7.0] {
            for (u, v, want) in [
                (0.25, -0.375, (-1.0, -1.0)),
                (0.75, -0.125, (1.0, 1.0)),
                (0.5, -0.25, (0.0, 0.0)),
            ] {
                let c = m * Vec4::new(u * z, v * z, -z, 1.0);
                let ndc = Vec3::new(c.x, c.y, c.z) / c.w;
                assert!(
                    (ndc.x - want.0).abs() < 1e-5 && (ndc.y - want.1).abs() < 1e-5,
                    "{ndc}"
                );
                // Depth is the full perspective's.
                let d = proj * Vec4::new(0.0, 0.0, -z, 1.0);
                assert!((ndc.z - d.z / d.w).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn a_small_view_of_the_cone_gets_a_small_square_inside_it() {
        let fp = FrustumParams::default();
        // The seen pixels span 0.2 × 0.1 near the cone's edge (full 0.7):
        // the square holds them with the kernels' margin and stays inside.
        let w = focused_window(0.7, &seen(0.4, 0.1, 0.6, 0.2), 2048, 0, &fp);
        let (half, c) = (w.half, w.centre);
        assert!(half.x > 0.1 && half.x < 0.1 * 1.02, "{half}");
        assert_eq!(half.x, half.y);
        assert!(
            (c - half).cmple(Vec2::new(0.4, 0.1)).all()
                && (c + half).cmpge(Vec2::new(0.6, 0.2)).all(),
            "{c} {half}"
        );
        // Near the edge: moved in to stay inside the cone's square.
        let w = focused_window(0.7, &seen(0.55, -0.1, 0.75, 0.1), 2048, 0, &fp);
        assert!((w.centre.x + w.half.x - 0.7).abs() < 1e-5, "{w:?}");
        // Seen everywhere: the cone's square, centred.
        assert_eq!(
            focused_window(0.7, &seen(-0.7, -0.7, 0.7, 0.7), 2048, 0, &fp),
            Window {
                half: Vec2::splat(0.7),
                centre: Vec2::ZERO
            }
        );
    }

    #[test]
    fn the_frustum_fit_holds_what_the_view_sees_of_the_cone() {
        // A spot 10 above the ground looking straight down (cone ±1 in
        // its image: ±10 on the ground); a camera on the ground at x = 6
        // looking along +x sees the part of the cone past it.
        // Its image's x is the world's x.
        let view =
            glam::camera::rh::view::look_to_mat4(Vec3::new(0.0, 10.0, 0.0), -Vec3::Y, Vec3::NEG_Z);
        let scene = Aabb {
            min: Vec3::new(-20.0, 0.0, -20.0),
            max: Vec3::new(20.0, 12.0, 20.0),
        };
        let mut camera = Camera::new(Vec3::new(6.0, 1.0, 0.0), Vec3::new(20.0, 1.0, 0.0));
        camera.near = 0.1;
        let s = frustum_supports(view, 1.0, (&camera, 1.5), &scene).unwrap();
        let [x0, _, x1, _] = s.box_at(0);
        // Nothing behind the camera's near plane: the least x/−z is at its
        // nearest and lowest point, 6.1 along x and 1 − 0.1·tan 25° high,
        // 6.1/9.047; the cone's side bounds the far end.
        assert!((x0 - 6.1 / 9.0466).abs() < 1e-3, "{x0}");
        assert!((x1 - 1.0).abs() < 1e-3, "{x1}");
        // Looking away from the cone: nothing.
        camera.eye = Vec3::new(12.0, 1.0, 0.0);
        camera.target = Vec3::new(30.0, 1.0, 0.0);
        assert!(frustum_supports(view, 1.0, (&camera, 1.5), &scene).is_none());
    }

    #[test]
    fn a_stabilised_square_keeps_its_texel_grid_under_a_small_move() {
        let fp = FrustumParams {
            stabilize_size: Some(1024),
            ..Default::default()
        };
        let a = focused_window(1.0, &seen(0.1, 0.1, 0.3, 0.2), 1024, 0, &fp);
        // A tenth of a texel further: the same size, and the centre on the
        // same grid (whole texels apart).
        let texel = 2.0 * a.half / 1024.0;
        let d = texel.x * 0.1;
        let b = focused_window(1.0, &seen(0.1 + d, 0.1, 0.3 + d, 0.2), 1024, 0, &fp);
        assert_eq!(a.half, b.half);
        let steps = (b.centre - a.centre) / texel;
        assert!(
            (steps - steps.round()).abs().max_element() < 1e-3,
            "{steps}"
        );
    }
}
