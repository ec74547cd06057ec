//! Trapezoidal shadow maps, TSM (Martin & Tan 2004; [000] §4, [001] §3, [002] §2): in the
//! light's image plane, the trapezoid around the camera's view (clipped to
//! the scene) whose top and base are perpendicular to the view's centre
//! line is mapped projectively onto the square map. Its apex is placed so
//! that the focus region — the view up to `focus` of its depth range, or
//! by default up to √(z_n·z_f) —
//! fills 80 % of the map (their "80 % rule"), so the near part of the view
//! gets most of the texels. With the map's y = a + b/T for T from η (top)
//! to η + λ (base) mapped to [−1, 1], the focus end at T = η + δ' lands on
//! ξ = 0.6 when η = λδ'(1 − ξ) / ((1 + ξ)λ − 2δ') (their η with the sign
//! of ξ flipped: their y runs the other way).

use super::Warped;
use crate::scene::{Aabb, Camera};
use crate::technique::shadow_map::projection::setup::linear_depth_row;
use glam::{Mat4, Vec2, Vec3, Vec4};

/// Where the focus region's far end lands in the map's [−1, 1] (80 %).
const FOCUS_LINE: f32 = 0.6;
/// Below this centre-line length (light-view units per unit of view
/// depth) the light runs along the view: no trapezoid (uniform map).
const MIN_CENTRE_LINE: f32 = 1e-3;

/// The TSM matrix covering `body` (world points the map must cover, the
/// view inside the scene) for a camera whose view spans depths `z_near` to
/// `z_far` in it, with the focus region ending at `focus` of that range;
/// `light_view` looks along the light; `focus` 0 ends it at √(z_n·z_f). `None` when the light runs along
/// the view or the trapezoid degenerates (use the uniform map).
pub fn tsm(
    camera: &Camera,
    light_view: Mat4,
    scene: &Aabb,
    body: &[Vec3],
    (z_near, z_far): (f32, f32),
    focus: f32,
) -> Option<Warped> {
    if body.is_empty() {
        return None;
    }
    let forward = (camera.target - camera.eye).normalize();
    let image = |p: Vec3| light_view.transform_point3(p).truncate();
    // The centre line, from the near plane's centre towards the far one's.
    let (c0, c1) = (
        image(camera.eye + forward * z_near),
        image(camera.eye + forward * z_far),
    );
    if (c1 - c0).length() < MIN_CENTRE_LINE * (z_far - z_near) {
        return None;
    }
    let u = (c1 - c0).normalize();
    let v = Vec2::new(-u.y, u.x);
    // The body along (t) and across (s) the centre line.
    let ts: Vec<Vec2> = body
        .iter()
        .map(|p| {
            let d = image(*p) - c0;
            Vec2::new(d.dot(u), d.dot(v))
        })
        .collect();
    let t_min = ts.iter().map(|p| p.x).fold(f32::MAX, f32::min);
    let t_max = ts.iter().map(|p| p.x).fold(f32::MIN, f32::max);
    let lambda = t_max - t_min;
    if lambda <= 1e-6 {
        return None;
    }
    // δ': the focus region's far end along the centre line, from the top.
    let focus_depth = if focus > 0.0 {
        z_near + focus.min(1.0) * (z_far - z_near)
    } else {
        (z_near * z_far).sqrt()
    };
    let delta =
        ((image(camera.eye + forward * focus_depth) - c0).dot(u) - t_min).clamp(0.0, lambda);
    // A focus region past 80 % of the trapezoid would need the opposite
    // warp: uniform instead.
    let denominator = (1.0 + FOCUS_LINE) * lambda - 2.0 * delta;
    if denominator <= 1e-6 * lambda {
        return None;
    }
    let eta = lambda * delta * (1.0 - FOCUS_LINE) / denominator;
    if !(eta.is_finite() && eta > 1e-6 * lambda) {
        return None;
    }
    // From the apex q = t_min − η on the centre line, T = t − (t_min − η)
    // runs from η (top) to η + λ (base); the sides are the body's extreme
    // slopes s / T.
    let apex = t_min - eta;
    let (slope_min, slope_max) = ts.iter().fold((f32::MAX, f32::MIN), |(a, b), p| {
        let k = p.y / (p.x - apex);
        (a.min(k), b.max(k))
    });
    let (mid, half) = (
        (slope_max + slope_min) * 0.5,
        ((slope_max - slope_min) * 0.5).max(1e-6),
    );
    // Clip coordinates, all with w = T:
    //   x = (s − mid·T) / half            (s / T from mid − half to mid + half → ±1)
    //   y = a·T + b, a + b/η = −1, a + b/(η + λ) = 1
    //   z = depth·η: z/w ≤ depth, positive and ordered along each light ray
    //   (the map stores linear depth, written by its fragment stage).
    let b = -2.0 * eta * (eta + lambda) / lambda;
    let a = -1.0 - b / eta;
    // T and s as rows over the light view's (x, y, z, 1).
    let t_row = Vec4::new(u.x, u.y, 0.0, -c0.dot(u) - apex);
    let s_row = Vec4::new(v.x, v.y, 0.0, -c0.dot(v));
    let depth_row_ls = linear_depth_row(&scene.transformed(light_view));
    let rows = [
        (s_row - t_row * mid) / half,
        t_row * a + Vec4::W * b,
        depth_row_ls * eta,
        t_row,
    ];
    let trapezoid = Mat4::from_cols_array_2d(&rows.map(|r| r.to_array())).transpose();
    Some(Warped {
        view_proj: trapezoid * light_view,
        depth_row: light_view.transpose() * depth_row_ls,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::shadow_map::projection::setup::{clip_to_bounds, light_view_of_scene};
    use crate::technique::shadow_map::projection::warp::tests::{
        assert_magnifies_near_the_camera, ndc,
    };

    fn setting() -> (Camera, Aabb, Vec3) {
        let scene = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 10.0, 50.0),
        };
        let cam = Camera::new(Vec3::new(0.0, 2.0, 40.0), Vec3::new(0.0, 0.0, 0.0));
        (cam, scene, Vec3::new(1.0, -1.0, 0.2))
    }

    /// The trapezoid holds the body inside the map, puts the focus
    /// region's end on the 80 % line, gives the ground near the camera more
    /// texels than far away, and stores depth linear along the light.
    #[test]
    fn the_trapezoid_covers_the_body_and_maps_the_focus_to_eighty_percent() {
        let (cam, scene, light) = setting();
        let body = clip_to_bounds(&cam.slice_corners(1.5, 0.5, 80.0), &scene);
        let (view, _) = light_view_of_scene(light, &scene);
        let w = tsm(&cam, view, &scene, &body, (0.5, 80.0), 0.3).unwrap();
        for p in &body {
            let q = ndc(w.view_proj, *p);
            assert!(
                q.x.abs() <= 1.0 + 1e-3 && q.y.abs() <= 1.0 + 1e-3 && q.z >= 0.0 && q.z <= 1.0,
                "{p} → {q}"
            );
        }
        // The focus point on the centre line lands on y = 0.6.
        let forward = (cam.target - cam.eye).normalize();
        let focus = cam.eye + forward * (0.5 + 0.3 * 79.5);
        let y = ndc(w.view_proj, focus).y;
        assert!((y - FOCUS_LINE).abs() < 1e-3, "{y}");
        assert_magnifies_near_the_camera(w.view_proj);
        // Points on one light ray share a texel; the stored depth grows
        // linearly along the ray.
        let ground = Vec3::new(5.0, 0.0, 10.0);
        let lin = |p: Vec3| w.depth_row.dot(p.extend(1.0));
        let up = ground - light.normalize() * 3.0;
        assert!(
            (ndc(w.view_proj, up) - ndc(w.view_proj, ground))
                .truncate()
                .length()
                < 1e-4
        );
        let step = lin(ground) - lin(up);
        let ls = scene.transformed(view);
        let extent = ls.size().z + 2.0 * ls.margin();
        assert!((step - 3.0 / extent).abs() < 1e-4, "{step}");
        // The light along the view: no trapezoid.
        let (view_along, _) = light_view_of_scene(cam.target - cam.eye, &scene);
        assert!(tsm(&cam, view_along, &scene, &body, (0.5, 80.0), 0.3).is_none());
    }
}
