//! No camera preset of a built-in scene stands inside a mesh or nearer to
//! one than its near plane (a camera 0.34 units behind a wall saw through
//! the building only because the wall was nearer than the near plane).

use super::*;

/// Closest distance from `p` to triangle `t` (Ericson, Real-Time
/// Collision Detection §5.1.5).
fn point_triangle_distance(p: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return p.distance(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return p.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return p.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return p.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return p.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    p.distance(a + ab * (vb * denom) + ac * (vc * denom))
}

/// Whether the ray `o + t·d`, t > 0, crosses triangle `t` (Möller–Trumbore).
fn ray_crosses(o: Vec3, d: Vec3, [a, b, c]: [Vec3; 3]) -> bool {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return false;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(q) / det > 0.0
}

#[test]
fn point_triangle_distance_and_crossings_match_hand_values() {
    let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert!((point_triangle_distance(Vec3::new(0.2, 0.2, 3.0), t) - 3.0).abs() < 1e-6);
    assert!((point_triangle_distance(Vec3::new(-1.0, -1.0, 0.0), t) - 2f32.sqrt()).abs() < 1e-6);
    assert!((point_triangle_distance(Vec3::new(1.0, 1.0, 0.0), t) - 0.5f32.sqrt()).abs() < 1e-6);
    assert!(ray_crosses(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z, t));
    assert!(!ray_crosses(Vec3::new(0.2, 0.2, 1.0), Vec3::Z, t));
    assert!(!ray_crosses(Vec3::new(0.8, 0.8, 1.0), Vec3::NEG_Z, t));
}

/// No camera preset stands inside a mesh (an odd number of surfaces
/// crossed along all six axis directions) or nearer to a surface than
/// its near plane (which would clip into view what stands beside it).
#[test]
fn no_camera_preset_is_inside_or_too_near_a_mesh() {
    let mut problems = vec![];
    for name in NAMES {
        let s = by_name(name).unwrap().unwrap();
        let tris = s.world_triangles(|_| true);
        for (preset, cam) in &s.camera_presets {
            let nearest = tris
                .iter()
                .map(|t| point_triangle_distance(cam.eye, *t))
                .fold(f32::INFINITY, f32::min);
            let dirs = [
                Vec3::X,
                Vec3::NEG_X,
                Vec3::Y,
                Vec3::NEG_Y,
                Vec3::Z,
                Vec3::NEG_Z,
            ];
            let inside = dirs.iter().all(|d| {
                tris.iter()
                    .filter(|t| ray_crosses(cam.eye, *d, **t))
                    .count()
                    % 2
                    == 1
            });
            if inside || nearest < cam.near {
                problems.push(format!(
                    "{name}/{preset}: eye {} inside: {inside}, nearest surface {nearest:.3} (near {})",
                    cam.eye, cam.near
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{problems:#?}");
}
