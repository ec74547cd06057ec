//! Procedural mesh generators used by the built-in scenes. Every closed shape
//! is closed after welding by position (boxes have split normals per face).

use super::Mesh;
use glam::{Mat4, Vec2, Vec3};
use std::f32::consts::{PI, TAU};

fn mesh(name: &str) -> Mesh {
    Mesh {
        name: name.into(),
        ..Default::default()
    }
}

/// A grid over `f(u, v)` for u, v in [0,1], `nu × nv` quads, with uvs
/// `(u, v)·uv_scale`. Normals are derived later from the triangles unless
/// `normal` is given.
fn grid(
    name: &str,
    nu: u32,
    nv: u32,
    f: impl Fn(f32, f32) -> Vec3,
    normal: Option<&dyn Fn(f32, f32) -> Vec3>,
) -> Mesh {
    let mut m = mesh(name);
    for j in 0..=nv {
        for i in 0..=nu {
            let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
            m.positions.push(f(u, v));
            m.uvs.push(Vec2::new(u, v));
            if let Some(n) = normal {
                m.normals.push(n(u, v));
            }
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let a = j * row + i;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            for t in [[a, c, b], [b, c, d]] {
                // Pole and axis quads collapse to slivers: leave them out.
                let p = t.map(|k| m.positions[k as usize]);
                if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() > 1e-14 {
                    m.indices.extend_from_slice(&t);
                }
            }
        }
    }
    m
}

/// Horizontal plane at y = 0 facing +y, `size_x × size_z`, subdivided.
pub fn plane(size_x: f32, size_z: f32, subdiv: u32) -> Mesh {
    grid(
        "plane",
        subdiv,
        subdiv,
        |u, v| Vec3::new((u - 0.5) * size_x, 0.0, (v - 0.5) * size_z),
        Some(&|_, _| Vec3::Y),
    )
}

/// Axis-aligned box centred at the origin with per-face normals; each face
/// is an `n × n` grid.
pub fn cuboid_subdivided(size: Vec3, n: u32) -> Mesh {
    let h = size * 0.5;
    let mut out = mesh("box");
    // (normal, u axis, v axis) with u × v = normal so faces wind CCW outward.
    let faces = [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ];
    for (nrm, ua, va) in faces {
        let face = grid(
            "face",
            n,
            n,
            |u, v| (nrm + ua * (2.0 * u - 1.0) + va * (2.0 * v - 1.0)) * h,
            Some(&|_, _| nrm),
        );
        // grid winds (a, c, b): with u along ua and v along va that is
        // clockwise seen from +normal, so flip.
        let mut face = face;
        for t in face.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        out.append(&face, Mat4::IDENTITY);
    }
    out
}

pub fn cuboid(size: Vec3) -> Mesh {
    cuboid_subdivided(size, 1)
}

/// The angle of a periodic grid parameter: u = 1 lands exactly on u = 0
/// (sin 2π is not 0 in f32), so that seams weld.
fn turn(u: f32) -> f32 {
    if u >= 1.0 { 0.0 } else { u * TAU }
}

/// UV sphere of radius `r`; the seam and the poles weld exactly.
pub fn sphere(r: f32, segments: u32, rings: u32) -> Mesh {
    let s = |u: f32, v: f32| {
        let th = turn(u);
        let (sin_ph, cos_ph) = match v {
            v if v <= 0.0 => (0.0, 1.0),
            v if v >= 1.0 => (0.0, -1.0),
            v => (v * PI).sin_cos(),
        };
        Vec3::new(-sin_ph * th.cos(), cos_ph, sin_ph * th.sin())
    };
    grid("sphere", segments, rings, |u, v| s(u, v) * r, Some(&s))
}

/// Torus in the xz plane: major radius `big_r`, tube radius `r`.
pub fn torus(big_r: f32, r: f32, segments: u32, sides: u32) -> Mesh {
    let n = |u: f32, v: f32| {
        let (a, b) = (turn(u), turn(v));
        Vec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos())
    };
    let p = |u: f32, v: f32| {
        let a = turn(u);
        Vec3::new(a.cos(), 0.0, a.sin()) * big_r + n(u, v) * r
    };
    grid("torus", segments, sides, p, Some(&n))
}

/// Surface of revolution around +y of the profile `(radius, y)` points
/// (bottom to top); open where the profile does not reach the axis.
pub fn lathe(name: &str, profile: &[Vec2], segments: u32) -> Mesh {
    let n = profile.len() as u32 - 1;
    let mut m = grid(
        name,
        segments,
        n,
        |u, v| {
            let k = ((v * n as f32).round() as usize).min(profile.len() - 1);
            let a = turn(u);
            Vec3::new(a.cos() * profile[k].x, profile[k].y, a.sin() * profile[k].x)
        },
        None,
    );
    m.name = name.into();
    m
}

/// Closed cylinder along +y from y = 0 to y = h.
pub fn cylinder(r: f32, h: f32, segments: u32) -> Mesh {
    let mut m = lathe(
        "cylinder",
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(r, 0.0),
            Vec2::new(r, h),
            Vec2::new(0.0, h),
        ],
        segments,
    );
    // Hard edges at the rims: flat shading per face group is approximated by
    // splitting normals; smooth normals are computed later.
    m.normals.clear();
    m
}

/// Heightfield `y = f(x, z)` over `size × size` centred at the origin.
pub fn heightfield(size: f32, n: u32, f: impl Fn(f32, f32) -> f32) -> Mesh {
    grid(
        "heightfield",
        n,
        n,
        |u, v| {
            let (x, z) = ((u - 0.5) * size, (v - 0.5) * size);
            Vec3::new(x, f(x, z), z)
        },
        None,
    )
}

/// Inside of a half cylinder (a half-pipe) along z, radius `r`, length `len`,
/// the open side up; the inner surface faces the axis.
pub fn half_pipe(r: f32, len: f32, nu: u32, nv: u32) -> Mesh {
    grid(
        "half_pipe",
        nu,
        nv,
        |u, v| {
            let a = PI + u * PI;
            Vec3::new(a.cos() * r, a.sin() * r + r, (v - 0.5) * len)
        },
        None,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's winding agrees with its vertex normals (outward).
    fn assert_outward(m: &Mesh) {
        for t in m.indices.chunks_exact(3) {
            let p: Vec<Vec3> = t.iter().map(|&i| m.positions[i as usize]).collect();
            let fnrm = (p[1] - p[0]).cross(p[2] - p[0]);
            if fnrm.length_squared() < 1e-12 {
                continue;
            }
            let n = m.normals[t[0] as usize] + m.normals[t[1] as usize] + m.normals[t[2] as usize];
            assert!(fnrm.dot(n) > 0.0, "{}: inward triangle {:?}", m.name, p);
        }
    }

    #[test]
    fn generated_shapes_wind_outward() {
        for mut m in [
            cuboid(Vec3::new(1.0, 2.0, 3.0)),
            sphere(1.0, 16, 8),
            torus(1.0, 0.3, 16, 8),
            plane(2.0, 2.0, 2),
            cylinder(1.0, 2.0, 12),
        ] {
            m.finalize().unwrap();
            assert_outward(&m);
        }
    }

    #[test]
    fn cuboid_faces_have_expected_normals() {
        let m = cuboid(Vec3::ONE);
        assert_eq!(m.triangle_count(), 12);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            // Every vertex lies on the face its normal names.
            assert!((p.dot(*n) - 0.5).abs() < 1e-6);
        }
    }
}
