//! The built-in scenes, each with named camera and light presets. Every
//! scene has the light presets `point`, `spot` and `sun` (directional) so
//! that each technique can be measured under all three light types.

mod foliage;
#[cfg(test)]
mod preset_clearance;
mod textures;

use super::shapes::{self, cuboid, cuboid_subdivided, lathe, plane, sphere, torus};
use super::{Camera, Light, LightArea, Material, Mesh, Procedural, ProceduralKind, Scene};
use anyhow::Result;
use glam::{Mat4, Quat, Vec2, Vec3};
use textures::{add_textures, bricks, tiles};

pub const NAMES: &[&str] = &[
    "room",
    "bunny",
    "floating",
    "curved",
    "teapot",
    "columns",
    "city",
    "landscape",
    "foliage",
];

/// One-line descriptions, in the order of [`NAMES`].
pub const DESCRIPTIONS: &[&str] = &[
    "seed 000's room: floor, walls that cast no shadow (WallsNS), chair, vase, spheres",
    "Stanford bunny (open mesh) on a textured, normal-mapped floor",
    "a sphere and a torus floating over a floor",
    "casters over curved receivers: a wavy ground and a half-pipe",
    "the open Utah teapot on a floor",
    "a colonnade under a roof; preset camera `in-shadow` stands inside the roof's shadow",
    "procedural city of >1,000,000 triangles under a directional sun",
    "2 km x 2 km of rolling hills with trees and rocks; a ground camera sees shadows from 1 m to the horizon",
    "see-through casters: trees of alpha-tested leaf cards, a chain-link fence, a double-sided cloth awning, a glass pane (translucent)",
];

/// Builds a built-in scene, or `Ok(None)` when `name` is not one.
pub fn by_name(name: &str) -> Result<Option<Scene>> {
    let mut s = match name {
        "room" => room(),
        "bunny" => bunny()?,
        "floating" => floating(),
        "curved" => curved(),
        "teapot" => teapot()?,
        "columns" => columns(),
        "city" => city(),
        "landscape" => super::landscape::landscape(),
        "foliage" => foliage::foliage(),
        _ => return Ok(None),
    };
    s.source = format!("builtin:{name}");
    s.lights = s.light_presets[0].1.clone();
    s.camera = s.camera_presets[0].1;
    s.finalize()?;
    Ok(Some(s))
}

fn t(x: f32, y: f32, z: f32) -> Mat4 {
    Mat4::from_translation(Vec3::new(x, y, z))
}

fn procedural(name: &str, kind: ProceduralKind, a: Vec3, b: Vec3, scale: f32) -> Material {
    Material {
        procedural: Some(Procedural {
            kind,
            color_a: a,
            color_b: b,
            scale,
            octaves: 5,
        }),
        ..Material::color(name, a)
    }
}

fn checker_floor(scene: &mut Scene) -> usize {
    scene.add_material(procedural(
        "floor",
        ProceduralKind::Checker,
        Vec3::new(0.75, 0.75, 0.72),
        Vec3::new(0.45, 0.45, 0.45),
        1.0,
    ))
}

/// Light presets `point`, `spot`, `sun` aimed at `focus`.
fn standard_lights(
    point: Vec3,
    spot: Vec3,
    focus: Vec3,
    sun_dir: Vec3,
    intensity: f32,
) -> Vec<(String, Vec<Light>)> {
    vec![
        ("point".into(), vec![Light::point(point, intensity)]),
        (
            "spot".into(),
            vec![Light::spot(spot, focus, intensity, 22.0, 32.0)],
        ),
        ("sun".into(), vec![Light::directional(sun_dir, intensity)]),
    ]
}

/// The room of seed 000: a floor, three walls that cast no shadow
/// (`WallsNS`), a chair, a vase and spheres; the floor is also a
/// `ShadowPlane`.
pub fn room() -> Scene {
    let mut s = Scene::new("room");
    let floor_mat = checker_floor(&mut s);
    let floor = s.add_mesh(plane(10.0, 10.0, 10));
    s.add_object("Floor", floor, floor_mat, Mat4::IDENTITY);
    let sp = s.add_mesh(plane(10.0, 10.0, 1));
    s.add_object("ShadowPlaneFloor", sp, floor_mat, Mat4::IDENTITY);

    let (bc, bn) = add_textures(&mut s, "bricks", bricks(256));
    let wall_mat = s.add_material(Material {
        diffuse_texture: Some(bc),
        normal_map: Some(bn),
        uv_scale: 3.0,
        ks: Vec3::splat(0.05),
        ..Material::color("bricks", Vec3::ONE)
    });
    let mut walls = Mesh {
        name: "walls".into(),
        ..Default::default()
    };
    let wall = plane(10.0, 5.0, 4);
    let up = |m: Mat4| m * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
    walls.append(&wall, up(t(0.0, 2.5, -5.0)));
    walls.append(
        &wall,
        up(t(-5.0, 2.5, 0.0) * Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2)),
    );
    walls.append(
        &wall,
        up(t(5.0, 2.5, 0.0) * Mat4::from_rotation_y(-std::f32::consts::FRAC_PI_2)),
    );
    let walls = s.add_mesh(walls);
    s.add_object("WallsNS", walls, wall_mat, Mat4::IDENTITY);

    // Chair: seat, four legs, backrest.
    let mut chair = Mesh {
        name: "chair".into(),
        ..Default::default()
    };
    chair.append(&cuboid(Vec3::new(1.2, 0.12, 1.2)), t(0.0, 1.0, 0.0));
    for (x, z) in [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)] {
        chair.append(&cuboid(Vec3::new(0.12, 1.0, 0.12)), t(x, 0.5, z));
    }
    chair.append(&cuboid(Vec3::new(1.2, 1.2, 0.12)), t(0.0, 1.66, -0.54));
    let chair = s.add_mesh(chair);
    let wood = s.add_material(Material {
        shininess: 16.0,
        ..Material::color("wood", Vec3::new(0.55, 0.33, 0.18))
    });
    s.add_object(
        "Chair",
        chair,
        wood,
        t(-1.5, 0.0, -1.0) * Mat4::from_rotation_y(0.4),
    );

    let vase_profile: Vec<Vec2> = [
        (0.0, 0.0),
        (0.35, 0.0),
        (0.5, 0.3),
        (0.55, 0.7),
        (0.4, 1.1),
        (0.22, 1.4),
        (0.25, 1.7),
        (0.3, 1.8),
    ]
    .iter()
    .map(|&(r, y)| Vec2::new(r, y))
    .collect();
    let vase = s.add_mesh(lathe("vase", &vase_profile, 40));
    let marble = s.add_material(procedural(
        "marble",
        ProceduralKind::Marble,
        Vec3::new(0.92, 0.92, 0.95),
        Vec3::new(0.25, 0.3, 0.4),
        2.0,
    ));
    s.add_object("Vase", vase, marble, t(1.8, 0.0, -1.8));

    let ball = s.add_mesh(sphere(0.6, 48, 24));
    let stripes = s.add_material(procedural(
        "stripes",
        ProceduralKind::Stripes,
        Vec3::new(0.85, 0.2, 0.2),
        Vec3::new(0.95, 0.9, 0.8),
        3.0,
    ));
    let turb = s.add_material(procedural(
        "turbulence",
        ProceduralKind::Turbulence,
        Vec3::new(0.2, 0.5, 0.9),
        Vec3::new(0.9, 0.95, 1.0),
        2.5,
    ));
    s.add_object("SphereA", ball, stripes, t(1.2, 0.6, 1.2));
    s.add_object("SphereB", ball, turb, t(-0.2, 2.2, 1.0));

    s.camera_presets = vec![
        (
            "default".into(),
            Camera::new(Vec3::new(0.0, 4.0, 11.0), Vec3::new(0.0, 1.2, 0.0)),
        ),
        (
            "top".into(),
            Camera::new(Vec3::new(0.5, 12.0, 4.0), Vec3::new(0.0, 0.0, 0.0)),
        ),
        (
            "low".into(),
            Camera::new(Vec3::new(3.5, 0.6, 4.0), Vec3::new(-1.0, 0.8, -1.0)),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(0.5, 4.5, 1.5),
        Vec3::new(4.0, 4.8, 4.0),
        Vec3::new(-0.5, 0.5, -0.5),
        Vec3::new(-0.4, -1.0, -0.5),
        1.0,
    );
    s
}

fn load_asset_obj(name: &str, text: &str) -> Result<Mesh> {
    let mut m = super::obj::parse_single_mesh(name, text)?;
    m.name = name.into();
    Ok(m)
}

/// Stanford bunny (open mesh) on a tiled, normal-mapped floor.
pub fn bunny() -> Result<Scene> {
    let mut s = Scene::new("bunny");
    let (tc, tn) = add_textures(&mut s, "tiles", tiles(512));
    let floor_mat = s.add_material(Material {
        diffuse_texture: Some(tc),
        normal_map: Some(tn),
        uv_scale: 4.0,
        ..Material::color("tiles", Vec3::ONE)
    });
    let floor = s.add_mesh(plane(8.0, 8.0, 8));
    s.add_object("Floor", floor, floor_mat, Mat4::IDENTITY);
    let bunny = s.add_mesh(load_asset_obj(
        "bunny",
        include_str!("../../../assets/bunny.obj"),
    )?);
    let fur = s.add_material(Material {
        shininess: 24.0,
        ..Material::color("bunny", Vec3::new(0.85, 0.8, 0.7))
    });
    s.add_object("Bunny", bunny, fur, Mat4::from_scale(Vec3::splat(0.22)));
    s.camera_presets = vec![
        (
            "default".into(),
            Camera::new(Vec3::new(2.5, 2.6, 5.0), Vec3::new(0.0, 0.9, 0.0)),
        ),
        (
            "side".into(),
            Camera::new(Vec3::new(5.5, 1.2, 0.2), Vec3::new(0.0, 0.9, 0.0)),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(-1.5, 4.0, 2.0),
        Vec3::new(-3.0, 4.5, 3.0),
        Vec3::new(0.0, 0.8, 0.0),
        Vec3::new(0.5, -1.0, -0.6),
        1.0,
    );
    Ok(s)
}

/// A sphere and a torus floating over a floor; preset `area` is a spherical
/// area light for soft shadows.
pub fn floating() -> Scene {
    let mut s = Scene::new("floating");
    let fm = checker_floor(&mut s);
    let floor = s.add_mesh(plane(12.0, 12.0, 12));
    s.add_object("Floor", floor, fm, Mat4::IDENTITY);
    let ball = s.add_mesh(sphere(0.7, 48, 24));
    let red = s.add_material(Material::color("red", Vec3::new(0.8, 0.2, 0.15)));
    s.add_object("Sphere", ball, red, t(-1.1, 1.6, 0.0));
    let ring = s.add_mesh(torus(0.7, 0.22, 64, 24));
    let gold = s.add_material(Material {
        ks: Vec3::splat(0.6),
        shininess: 64.0,
        ..Material::color("gold", Vec3::new(0.8, 0.6, 0.2))
    });
    s.add_object(
        "Torus",
        ring,
        gold,
        t(1.2, 1.2, 0.3) * Mat4::from_quat(Quat::from_rotation_x(0.6)),
    );
    s.camera_presets = vec![
        (
            "default".into(),
            Camera::new(Vec3::new(0.0, 4.0, 7.5), Vec3::new(0.0, 0.8, 0.0)),
        ),
        (
            "top".into(),
            Camera::new(Vec3::new(0.0, 9.0, 0.5), Vec3::ZERO),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(0.5, 5.0, 1.0),
        Vec3::new(2.0, 5.5, 3.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(0.3, -1.0, -0.2),
        1.0,
    );
    let mut area = Light::point(Vec3::new(0.3, 5.0, 0.5), 1.0);
    area.area = Some(LightArea::Sphere { radius: 0.5 });
    s.light_presets.push(("area".into(), vec![area]));
    s
}

/// Casters over curved receivers: a wavy ground and a half-pipe.
pub fn curved() -> Scene {
    let mut s = Scene::new("curved");
    let sand = s.add_material(procedural(
        "sand",
        ProceduralKind::Turbulence,
        Vec3::new(0.85, 0.75, 0.55),
        Vec3::new(0.65, 0.55, 0.4),
        1.5,
    ));
    let ground = s.add_mesh(shapes::heightfield(14.0, 96, |x, z| {
        0.35 * (x * 0.9).sin() * (z * 0.7).cos()
    }));
    s.add_object("Ground", ground, sand, t(0.0, -0.4, 0.0));
    let mut pipe = shapes::half_pipe(1.6, 5.0, 48, 12);
    pipe.normals = super::smooth_normals(&pipe.positions, &pipe.indices);
    pipe.make_double_sided();
    let pipe = s.add_mesh(pipe);
    let concrete = s.add_material(Material::color("concrete", Vec3::splat(0.7)));
    let mut pipe_obj = super::Object::from_name("HalfPipe", pipe, concrete, t(2.5, 0.05, -0.5));
    pipe_obj.casts_shadow = true;
    s.objects.push(pipe_obj);
    let ball = s.add_mesh(sphere(0.5, 40, 20));
    let blue = s.add_material(Material::color("blue", Vec3::new(0.2, 0.35, 0.85)));
    s.add_object("Ball", ball, blue, t(2.5, 1.0, 0.0));
    let ring = s.add_mesh(torus(0.6, 0.18, 48, 16));
    let green = s.add_material(Material::color("green", Vec3::new(0.25, 0.7, 0.3)));
    s.add_object(
        "Ring",
        ring,
        green,
        t(-2.0, 1.3, 0.5) * Mat4::from_rotation_z(0.5),
    );
    let box_mesh = s.add_mesh(cuboid(Vec3::new(0.8, 1.6, 0.8)));
    s.add_object("Pillar", box_mesh, blue, t(-0.5, 0.5, -2.0));
    s.camera_presets = vec![
        (
            "default".into(),
            Camera::new(Vec3::new(-1.0, 5.0, 8.5), Vec3::new(0.5, 0.0, -0.5)),
        ),
        (
            "pipe".into(),
            Camera::new(Vec3::new(2.5, 3.5, 5.0), Vec3::new(2.5, 0.3, -0.5)),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(0.0, 5.0, 1.5),
        Vec3::new(-3.0, 5.5, 3.0),
        Vec3::new(0.5, 0.0, -0.5),
        Vec3::new(-0.5, -1.0, -0.3),
        1.0,
    );
    s
}

/// The open Utah teapot (no bottom) on a floor.
pub fn teapot() -> Result<Scene> {
    let mut s = Scene::new("teapot");
    let fm = checker_floor(&mut s);
    let floor = s.add_mesh(plane(10.0, 10.0, 10));
    s.add_object("Floor", floor, fm, Mat4::IDENTITY);
    let pot = load_asset_obj("teapot", include_str!("../../../assets/teapot.obj"))?;
    let min_y = pot.bounds().min.y;
    let pot = s.add_mesh(pot);
    let porcelain = s.add_material(Material {
        ks: Vec3::splat(0.7),
        shininess: 96.0,
        ..Material::color("porcelain", Vec3::new(0.9, 0.9, 0.95))
    });
    s.add_object(
        "Teapot",
        pot,
        porcelain,
        Mat4::from_scale(Vec3::splat(0.12)) * t(0.0, -min_y, 0.0),
    );
    s.camera_presets = vec![
        (
            "default".into(),
            Camera::new(Vec3::new(2.5, 3.0, 5.0), Vec3::new(0.0, 0.8, 0.0)),
        ),
        (
            "top".into(),
            Camera::new(Vec3::new(0.2, 6.0, 1.0), Vec3::new(0.0, 0.5, 0.0)),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(-2.0, 4.0, 1.0),
        Vec3::new(-3.0, 4.0, 3.0),
        Vec3::new(0.0, 0.7, 0.0),
        Vec3::new(0.6, -1.0, -0.4),
        1.0,
    );
    Ok(s)
}

/// A colonnade: two rows of columns carrying a roof slab. The camera preset
/// `in-shadow` stands under the roof, inside its shadow for every light
/// preset.
pub fn columns() -> Scene {
    let mut s = Scene::new("columns");
    let fm = checker_floor(&mut s);
    let floor = s.add_mesh(plane(30.0, 30.0, 30));
    s.add_object("Floor", floor, fm, Mat4::IDENTITY);
    let stone = s.add_material(procedural(
        "stone",
        ProceduralKind::Marble,
        Vec3::new(0.85, 0.83, 0.78),
        Vec3::new(0.55, 0.5, 0.45),
        1.0,
    ));
    let mut colonnade = Mesh {
        name: "colonnade".into(),
        ..Default::default()
    };
    let shaft = shapes::cylinder(0.3, 3.6, 24);
    for row in [-1.5f32, 1.5] {
        for k in 0..6 {
            let z = -7.5 + 3.0 * k as f32;
            colonnade.append(&cuboid(Vec3::new(0.9, 0.2, 0.9)), t(row, 0.1, z));
            colonnade.append(&shaft, t(row, 0.2, z));
            colonnade.append(&cuboid(Vec3::new(0.9, 0.2, 0.9)), t(row, 3.9, z));
        }
    }
    let colonnade = s.add_mesh(colonnade);
    s.add_object("Columns", colonnade, stone, Mat4::IDENTITY);
    let roof = s.add_mesh(cuboid(Vec3::new(4.6, 0.4, 17.0)));
    s.add_object("Roof", roof, stone, t(0.0, 4.2, 0.0));
    s.camera_presets = vec![
        (
            "default".into(),
            Camera::new(Vec3::new(9.0, 5.0, 12.0), Vec3::new(0.0, 1.5, 0.0)),
        ),
        (
            "in-shadow".into(),
            Camera::new(Vec3::new(0.0, 1.7, 6.0), Vec3::new(0.3, 1.2, -4.0)),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(3.0, 9.0, 2.0),
        Vec3::new(6.0, 10.0, 6.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(-0.35, -1.0, -0.25),
        1.0,
    );
    s
}

/// A procedural city of 1600 buildings (each a box subdivided 8×8 per face,
/// 768 triangles) on a ground plane: 1,228,802 triangles.
pub fn city() -> Scene {
    let mut s = Scene::new("city");
    let asphalt = s.add_material(Material::color("asphalt", Vec3::splat(0.35)));
    let ground = s.add_mesh(plane(90.0, 90.0, 1));
    s.add_object("Ground", ground, asphalt, Mat4::IDENTITY);
    let facade = s.add_material(procedural(
        "facade",
        ProceduralKind::Stripes,
        Vec3::new(0.75, 0.72, 0.68),
        Vec3::new(0.35, 0.45, 0.55),
        1.5,
    ));
    let unit = cuboid_subdivided(Vec3::ONE, 8);
    // Deterministic LCG so that the city is the same on every machine.
    let mut seed: u32 = 12345;
    let mut rnd = move || {
        seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let n = 40;
    let pitch = 2.0;
    // Buildings merged in blocks of 2 × 2 (400 objects): few draws, and
    // bounds small enough for a light view to cull what it does not see.
    let block = 2;
    let blocks = n / block;
    let mut meshes: Vec<Mesh> = (0..blocks * blocks)
        .map(|b| Mesh {
            name: format!("block_{}_{}", b / blocks, b % blocks),
            ..Default::default()
        })
        .collect();
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (
                (i as f32 - n as f32 / 2.0 + 0.5) * pitch,
                (j as f32 - n as f32 / 2.0 + 0.5) * pitch,
            );
            let r = ((x * x + z * z).sqrt() / 40.0).min(1.0);
            let h = 1.0 + rnd() * (10.0 * (1.0 - r) + 2.0);
            let w = 1.0 + rnd() * 0.5;
            let d = 1.0 + rnd() * 0.5;
            meshes[(i / block) * blocks + j / block].append(
                &unit,
                t(x, h * 0.5, z) * Mat4::from_scale(Vec3::new(w, h, d)),
            );
        }
    }
    for mesh in meshes {
        let name = format!("Buildings_{}", &mesh.name["block_".len()..]);
        let m = s.add_mesh(mesh);
        s.add_object(&name, m, facade, Mat4::IDENTITY);
    }
    // Near planes suited to the scale: depth precision of a 24-bit buffer
    // goes as distance² / near, and the stencil techniques compare volume
    // depths against it at every shadow boundary.
    s.camera_presets = vec![
        (
            "default".into(),
            Camera {
                near: 0.5,
                far: 300.0,
                ..Camera::new(Vec3::new(30.0, 28.0, 48.0), Vec3::new(0.0, 0.0, 0.0))
            },
        ),
        // In the street along x = 0 (buildings stand at odd x), at the
        // crossing with the street along z = 30, looking down it; the
        // nearest wall is 0.37 away, beyond the near plane.
        (
            "street".into(),
            Camera {
                near: 0.3,
                far: 300.0,
                ..Camera::new(Vec3::new(0.0, 1.7, 30.0), Vec3::new(0.0, 3.0, 0.0))
            },
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(0.0, 30.0, 0.0),
        Vec3::new(30.0, 35.0, 30.0),
        Vec3::ZERO,
        Vec3::new(-0.5, -1.0, -0.35),
        1.0,
    );
    s.light_presets.rotate_left(2); // the sun is the city's default light
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_loads_with_presets() {
        for name in NAMES {
            let s = by_name(name).unwrap().unwrap();
            assert!(s.triangle_count() > 0, "{name}");
            for lt in ["point", "spot", "sun"] {
                s.light_preset(lt).unwrap();
            }
            assert!(s.caster_triangle_count() > 0);
        }
        assert!(by_name("nope").unwrap().is_none());
    }

    #[test]
    fn city_has_over_a_million_triangles() {
        let s = by_name("city").unwrap().unwrap();
        assert!(s.triangle_count() >= 1_000_000, "{}", s.triangle_count());
    }

    #[test]
    fn room_follows_seed_conventions() {
        let s = by_name("room").unwrap().unwrap();
        let walls = s.objects.iter().find(|o| o.name == "WallsNS").unwrap();
        assert!(!walls.casts_shadow && walls.receives_shadow && !walls.shadow_plane);
        let sp = s
            .objects
            .iter()
            .find(|o| o.name == "ShadowPlaneFloor")
            .unwrap();
        assert!(sp.shadow_plane && !sp.casts_shadow);
        let chair = s.objects.iter().find(|o| o.name == "Chair").unwrap();
        assert!(chair.casts_shadow);
    }
}
