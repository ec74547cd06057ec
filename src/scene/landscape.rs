//! The built-in `landscape`: 2 km × 2 km of rolling hills with trees and
//! rocks under a low sun — the view that needs warped and partitioned
//! shadow maps ([000] §4, [001] §3, [002] §2): a ground camera sees shadows from a metre to the
//! horizon. Deterministic: a fixed height function and a fixed-seed LCG.

use super::shapes::{cylinder, heightfield, lathe, sphere};
use super::{Camera, Light, Material, Mesh, Scene};
use glam::{Mat4, Quat, Vec2, Vec3};

/// Side of the square landscape, in metres.
pub const SIZE: f32 = 2048.0;
/// Tiles per side: the terrain and its trees and rocks are merged per tile,
/// so that a light view culls whole tiles it does not see.
const TILES: u32 = 8;
/// Terrain cells per tile side (8 m cells).
const CELLS: u32 = 32;
/// Trees spread over the whole land, and in a grove around the ground camera.
const TREES: usize = 2200;
const GROVE_TREES: usize = 900;
const GROVE_RADIUS: f32 = 160.0;
const ROCKS: usize = 1200;
/// Nothing stands nearer than this to the ground camera.
const CLEARING: f32 = 4.0;

/// Terrain height at (x, z): three octaves of sines, ±30 m of rolling hills.
pub fn height(x: f32, z: f32) -> f32 {
    18.0 * (x / 190.0 + 0.3).sin() * (z / 230.0).cos()
        + 9.0 * ((x - z) / 110.0).sin()
        + 3.0 * (x / 41.0).sin() * (z / 37.0).cos()
}

/// The terrain's unit normal at (x, z), from the analytic gradient (tiles
/// share it along their borders: no shading seams).
fn normal(x: f32, z: f32) -> Vec3 {
    let dx = 18.0 / 190.0 * (x / 190.0 + 0.3).cos() * (z / 230.0).cos()
        + 9.0 / 110.0 * ((x - z) / 110.0).cos()
        + 3.0 / 41.0 * (x / 41.0).cos() * (z / 37.0).cos();
    let dz = -18.0 / 230.0 * (x / 190.0 + 0.3).sin() * (z / 230.0).sin()
        - 9.0 / 110.0 * ((x - z) / 110.0).cos()
        - 3.0 / 37.0 * (x / 41.0).sin() * (z / 37.0).sin();
    Vec3::new(-dx, 1.0, -dz).normalize()
}

/// A deterministic uniform generator in [0, 1).
struct Lcg(u32);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(1664525).wrapping_add(1013904223);
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// The tile index of a point, row-major.
fn tile_of(x: f32, z: f32) -> usize {
    let t = |v: f32| (((v / SIZE + 0.5) * TILES as f32).floor() as i64).clamp(0, TILES as i64 - 1);
    (t(z) * TILES as i64 + t(x)) as usize
}

/// Where the ground camera stands.
const GROUND_EYE: Vec2 = Vec2::new(0.0, 0.0);

pub fn landscape() -> Scene {
    let mut s = Scene::new("landscape");
    let grass = s.add_material(Material::color("grass", Vec3::new(0.35, 0.5, 0.22)));
    let foliage = s.add_material(Material::color("foliage", Vec3::new(0.15, 0.38, 0.14)));
    let bark = s.add_material(Material::color("bark", Vec3::new(0.35, 0.25, 0.16)));
    let stone = s.add_material(Material::color("stone", Vec3::new(0.55, 0.54, 0.5)));
    let tile = SIZE / TILES as f32;
    let tiles = (TILES * TILES) as usize;
    let empty = |kind: &str| -> Vec<Mesh> {
        (0..tiles)
            .map(|i| Mesh {
                name: format!("{kind}_{i}"),
                ..Default::default()
            })
            .collect()
    };
    let (mut crowns, mut trunks, mut rocks) = (empty("crowns"), empty("trunks"), empty("rocks"));
    let crown = lathe(
        "crown",
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.55, 0.5),
            Vec2::new(0.0, 1.0),
        ],
        8,
    );
    let trunk = cylinder(1.0, 1.0, 6);
    let boulder = sphere(1.0, 7, 5);
    let mut rnd = Lcg(2024);
    let place = |rnd: &mut Lcg, grove: bool| -> Option<Vec3> {
        let (x, z) = if grove {
            let (r, a) = (
                GROVE_RADIUS * rnd.next().sqrt(),
                rnd.next() * std::f32::consts::TAU,
            );
            (GROUND_EYE.x + r * a.cos(), GROUND_EYE.y + r * a.sin())
        } else {
            (
                (rnd.next() - 0.5) * SIZE * 0.98,
                (rnd.next() - 0.5) * SIZE * 0.98,
            )
        };
        (Vec2::new(x, z).distance(GROUND_EYE) > CLEARING).then(|| Vec3::new(x, height(x, z), z))
    };
    for i in 0..TREES + GROVE_TREES {
        let at = place(&mut rnd, i >= TREES);
        let (h, r, lean) = (6.0 + 8.0 * rnd.next(), 1.8 + 1.8 * rnd.next(), rnd.next());
        let Some(p) = at else { continue };
        let k = tile_of(p.x, p.z);
        let trunk_h = h * 0.3;
        trunks[k].append(
            &trunk,
            Mat4::from_translation(p - Vec3::Y * 0.3)
                * Mat4::from_scale(Vec3::new(
                    0.25 + 0.1 * lean,
                    trunk_h + 0.3,
                    0.25 + 0.1 * lean,
                )),
        );
        crowns[k].append(
            &crown,
            Mat4::from_translation(p + Vec3::Y * trunk_h)
                * Mat4::from_rotation_y(lean * std::f32::consts::TAU)
                * Mat4::from_scale(Vec3::new(r, h - trunk_h, r)),
        );
    }
    for _ in 0..ROCKS {
        let at = place(&mut rnd, false);
        let (r, sy, turn) = (0.5 + 2.0 * rnd.next(), 0.5 + 0.4 * rnd.next(), rnd.next());
        let Some(p) = at else { continue };
        rocks[tile_of(p.x, p.z)].append(
            &boulder,
            Mat4::from_scale_rotation_translation(
                Vec3::new(r * 1.3, r * sy, r),
                Quat::from_rotation_y(turn * std::f32::consts::TAU),
                p - Vec3::Y * r * sy * 0.3,
            ),
        );
    }
    for k in 0..tiles {
        let (tx, tz) = ((k % TILES as usize) as f32, (k / TILES as usize) as f32);
        let centre = Vec2::new(
            (tx + 0.5) * tile - SIZE * 0.5,
            (tz + 0.5) * tile - SIZE * 0.5,
        );
        let mut ground = heightfield(tile, CELLS, |x, z| height(x + centre.x, z + centre.y));
        ground.normals = ground
            .positions
            .iter()
            .map(|p| normal(p.x + centre.x, p.z + centre.y))
            .collect();
        ground.name = format!("ground_{k}");
        let m = s.add_mesh(ground);
        s.add_object(
            &format!("Ground{k}"),
            m,
            grass,
            Mat4::from_translation(Vec3::new(centre.x, 0.0, centre.y)),
        );
    }
    for (meshes, material, kind) in [
        (crowns, foliage, "Crowns"),
        (trunks, bark, "Trunks"),
        (rocks, stone, "Rocks"),
    ] {
        for (k, mesh) in meshes.into_iter().enumerate() {
            if !mesh.indices.is_empty() {
                let m = s.add_mesh(mesh);
                s.add_object(&format!("{kind}{k}"), m, material, Mat4::IDENTITY);
            }
        }
    }
    add_presets(&mut s);
    s
}

/// The ground and flyover cameras, and the suns (high, across, low in
/// front and behind), a point and a spot light over the centre.
fn add_presets(s: &mut Scene) {
    let eye_height = height(GROUND_EYE.x, GROUND_EYE.y) + 1.7;
    s.camera_presets = vec![
        (
            "ground".into(),
            Camera {
                near: 0.1,
                far: 3000.0,
                ..Camera::new(
                    Vec3::new(GROUND_EYE.x, eye_height, GROUND_EYE.y),
                    Vec3::new(GROUND_EYE.x, eye_height, GROUND_EYE.y - 500.0),
                )
            },
        ),
        (
            "flyover".into(),
            Camera {
                near: 0.5,
                far: 3500.0,
                ..Camera::new(Vec3::new(-260.0, 140.0, 380.0), Vec3::new(0.0, 0.0, -150.0))
            },
        ),
    ];
    let focus = Vec3::new(0.0, height(0.0, -40.0), -40.0);
    let sun = |d: Vec3| vec![Light::directional(d, 1.0)];
    s.light_presets = vec![
        ("sun".into(), sun(Vec3::new(-0.4, -1.0, -0.3))),
        // Across the view (the camera looks along −z).
        ("sun-side".into(), sun(Vec3::new(1.0, -0.45, -0.1))),
        // Low, shining towards the camera: the "duelling frusta" case.
        ("sun-low-front".into(), sun(Vec3::new(0.1, -0.3, 1.0))),
        // Low, from behind the camera.
        ("sun-low-back".into(), sun(Vec3::new(0.1, -0.3, -1.0))),
        (
            "point".into(),
            vec![Light::point(focus + Vec3::new(0.0, 30.0, 0.0), 1.0)],
        ),
        (
            "spot".into(),
            vec![Light::spot(
                focus + Vec3::new(20.0, 40.0, 25.0),
                focus,
                1.0,
                22.0,
                32.0,
            )],
        ),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_is_the_height_gradient() {
        for (x, z) in [(0.0, 0.0), (123.0, -457.0), (-900.0, 640.0)] {
            let e = 0.01;
            let dx = (height(x + e, z) - height(x - e, z)) / (2.0 * e);
            let dz = (height(x, z + e) - height(x, z - e)) / (2.0 * e);
            let expect = Vec3::new(-dx, 1.0, -dz).normalize();
            assert!(normal(x, z).distance(expect) < 1e-3, "{x},{z}");
        }
    }

    #[test]
    fn tiles_cover_the_land_row_major() {
        assert_eq!(tile_of(-SIZE * 0.5, -SIZE * 0.5), 0);
        assert_eq!(tile_of(SIZE * 0.5 - 1.0, -SIZE * 0.5), TILES as usize - 1);
        assert_eq!(
            tile_of(-SIZE * 0.5, SIZE * 0.5 - 1.0),
            (TILES * (TILES - 1)) as usize
        );
        assert_eq!(tile_of(1e9, 1e9), (TILES * TILES) as usize - 1);
    }
}
