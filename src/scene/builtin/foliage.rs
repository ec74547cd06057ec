//! The `foliage` scene: see-through casters made in code — two trees whose
//! crowns are alpha-tested leaf cards, a chain-link fence (a cut-out), a
//! double-sided cloth awning and a translucent glass pane — over a floor.

use super::{checker_floor, standard_lights, t};
use crate::scene::shapes::{self, cylinder, plane};
use crate::scene::{AlphaMode, Camera, Material, Mesh, Procedural, ProceduralKind, Scene, Texture};
use glam::{Mat4, Vec2, Vec3};

/// Side of the leaf-cluster texture, in texels.
const LEAF_TEXELS: u32 = 128;
/// Side of one chain-link cell's texture, in texels.
const FENCE_TEXELS: u32 = 64;
/// One chain-link cell's width in metres.
const FENCE_CELL: f32 = 0.35;
/// The glass pane's opacity.
const GLASS_ALPHA: f32 = 0.3;

/// A cluster of leaves (ellipses) on a transparent background: colour in
/// rgb, the leaves' coverage (0 or 1) in alpha.
fn leaf_texture() -> image::RgbaImage {
    // Centre (u, v), half axes, angle, shade of each leaf.
    let leaves: [(f32, f32, f32, f32, f32, u8); 6] = [
        (0.30, 0.30, 0.20, 0.09, 0.6, 0),
        (0.68, 0.28, 0.19, 0.08, -0.5, 20),
        (0.50, 0.55, 0.22, 0.10, 1.3, 10),
        (0.25, 0.75, 0.18, 0.08, -0.9, 30),
        (0.74, 0.72, 0.20, 0.09, 0.3, 15),
        (0.50, 0.18, 0.12, 0.06, 1.6, 25),
    ];
    image::RgbaImage::from_fn(LEAF_TEXELS, LEAF_TEXELS, |x, y| {
        let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) / LEAF_TEXELS as f32;
        let leaf = leaves.iter().find(|&&(cx, cy, a, b, angle, _)| {
            let d = Vec2::from_angle(-angle).rotate(p - Vec2::new(cx, cy));
            (d.x / a).powi(2) + (d.y / b).powi(2) <= 1.0
        });
        match leaf {
            Some(&(.., shade)) => image::Rgba([40 + shade, 110 + shade, 35, 255]),
            None => image::Rgba([40, 90, 30, 0]),
        }
    })
}

/// One diamond cell of a chain-link fence: wire (opaque) along both
/// diagonals' stripes, holes elsewhere.
fn fence_texture() -> image::RgbaImage {
    let n = FENCE_TEXELS as i32;
    let wire = n / 10;
    image::RgbaImage::from_fn(FENCE_TEXELS, FENCE_TEXELS, |x, y| {
        let (x, y) = (x as i32, y as i32);
        let near = |v: i32| {
            let r = v.rem_euclid(n);
            r < wire / 2 + 1 || r >= n - wire / 2
        };
        if near(x + y) || near(x - y) {
            image::Rgba([170, 172, 178, 255])
        } else {
            image::Rgba([170, 172, 178, 0])
        }
    })
}

/// `count` square cards of side `size` scattered through a ball of radius
/// `radius` around `centre`, each turned at random (a fixed sequence, so
/// the scene is the same on every run), with uvs 0..1.
fn leaf_cards(centre: Vec3, radius: f32, count: u32, size: f32, seed: u32) -> Mesh {
    let mut state = seed;
    let mut rnd = move || {
        state = state.wrapping_mul(747796405).wrapping_add(2891336453);
        let w = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
        ((w >> 22) ^ w) as f32 / u32::MAX as f32
    };
    let mut m = Mesh {
        name: "leaf cards".into(),
        ..Default::default()
    };
    for _ in 0..count {
        // A point in the ball, denser towards the shell.
        let dir = Vec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0)
            .try_normalize()
            .unwrap_or(Vec3::Y);
        let p = centre + dir * radius * rnd().sqrt() * Vec3::new(1.0, 0.75, 1.0);
        let normal = Vec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0)
            .try_normalize()
            .unwrap_or(Vec3::Z);
        let a = normal.any_orthonormal_vector() * (size * 0.5);
        let b = normal.cross(a);
        let base = m.positions.len() as u32;
        for (corner, uv) in [
            (-a - b, Vec2::new(0.0, 1.0)),
            (a - b, Vec2::new(1.0, 1.0)),
            (a + b, Vec2::new(1.0, 0.0)),
            (-a + b, Vec2::new(0.0, 0.0)),
        ] {
            m.positions.push(p + corner);
            m.normals.push(normal);
            m.uvs.push(uv);
        }
        m.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    m
}

/// A vertical rectangle `width × height` in the xy plane facing +z, its
/// lower edge at y = 0, uvs spanning `uv_extent`.
fn panel(width: f32, height: f32, uv_extent: Vec2) -> Mesh {
    let (w, h) = (width * 0.5, height);
    Mesh {
        name: "panel".into(),
        positions: vec![
            Vec3::new(-w, 0.0, 0.0),
            Vec3::new(w, 0.0, 0.0),
            Vec3::new(w, h, 0.0),
            Vec3::new(-w, h, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![
            Vec2::new(0.0, uv_extent.y),
            uv_extent,
            Vec2::new(uv_extent.x, 0.0),
            Vec2::ZERO,
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        ..Default::default()
    }
}

/// A sagging sheet of cloth `width × depth` (one-sided: its material is
/// double-sided), hanging `sag` lower at its middle.
fn cloth(width: f32, depth: f32, sag: f32) -> Mesh {
    let mut m = plane(width, depth, 16);
    for p in &mut m.positions {
        let u = p.x / width + 0.5;
        p.y -= sag * (std::f32::consts::PI * u).sin();
    }
    m.normals.clear();
    m.name = "cloth".into();
    m
}

fn texture(scene: &mut Scene, name: &str, image: image::RgbaImage) -> usize {
    scene.textures.push(Texture {
        name: name.into(),
        image,
        srgb: true,
        source: None,
        wrap: Default::default(),
    });
    scene.textures.len() - 1
}

/// A double-sided cut-out material of texture `tex`.
fn cutout(name: &str, kd: Vec3, tex: usize) -> Material {
    Material {
        diffuse_texture: Some(tex),
        alpha_texture: Some(tex),
        alpha_mode: AlphaMode::Mask,
        double_sided: true,
        ..Material::color(name, kd)
    }
}

pub fn foliage() -> Scene {
    let mut s = Scene::new("foliage");
    let floor_mat = checker_floor(&mut s);
    let floor = s.add_mesh(plane(16.0, 16.0, 16));
    s.add_object("Floor", floor, floor_mat, Mat4::IDENTITY);

    let leaves_tex = texture(&mut s, "leaves", leaf_texture());
    let leaves = s.add_material(cutout("leaves", Vec3::ONE, leaves_tex));
    let bark = s.add_material(Material::color("bark", Vec3::new(0.4, 0.28, 0.18)));
    let trunk = s.add_mesh(cylinder(0.14, 2.4, 16));
    for (i, (x, z)) in [(-1.2f32, -0.6f32), (2.6, -1.8)].into_iter().enumerate() {
        s.add_object(&format!("Trunk{i}"), trunk, bark, t(x, 0.0, z));
        let crown = leaf_cards(Vec3::new(x, 3.0, z), 1.5, 90, 0.75, 17 + i as u32);
        let crown = s.add_mesh(crown);
        s.add_object(&format!("Crown{i}"), crown, leaves, Mat4::IDENTITY);
    }

    let fence_tex = texture(&mut s, "chain-link", fence_texture());
    let fence = s.add_material(cutout("chain-link", Vec3::ONE, fence_tex));
    let (fence_w, fence_h) = (7.0, 2.0);
    let fence_mesh = s.add_mesh(panel(
        fence_w,
        fence_h,
        Vec2::new(fence_w, fence_h) / FENCE_CELL,
    ));
    s.add_object("Fence", fence_mesh, fence, t(0.0, 0.0, -4.0));
    let steel = s.add_material(Material::color("steel", Vec3::splat(0.55)));
    let post = s.add_mesh(cylinder(0.05, fence_h + 0.1, 12));
    for x in [-3.5, 0.0, 3.5] {
        s.add_object("FencePost", post, steel, t(x, 0.0, -4.05));
    }

    let canvas = s.add_material(Material {
        procedural: Some(Procedural {
            kind: ProceduralKind::Stripes,
            color_a: Vec3::new(0.85, 0.3, 0.25),
            color_b: Vec3::new(0.9, 0.88, 0.8),
            scale: 2.0,
            octaves: 1,
        }),
        double_sided: true,
        ..Material::color("canvas", Vec3::new(0.85, 0.3, 0.25))
    });
    let awning = s.add_mesh(cloth(3.0, 2.0, 0.25));
    s.add_object("Awning", awning, canvas, t(4.0, 2.3, 2.0));
    let pole = s.add_mesh(cylinder(0.04, 2.3, 10));
    for (dx, dz) in [(-1.45, -0.95), (1.45, -0.95), (-1.45, 0.95), (1.45, 0.95)] {
        s.add_object("AwningPole", pole, steel, t(4.0 + dx, 0.0, 2.0 + dz));
    }

    let glass = s.add_material(Material {
        alpha: GLASS_ALPHA,
        alpha_mode: AlphaMode::Blend,
        double_sided: true,
        shininess: 200.0,
        ks: Vec3::splat(0.6),
        ..Material::color("glass", Vec3::new(0.6, 0.8, 0.9))
    });
    let pane = s.add_mesh(panel(2.0, 1.5, Vec2::ONE));
    s.add_object(
        "GlassPane",
        pane,
        glass,
        Mat4::from_translation(Vec3::new(-4.0, 0.3, 2.0)) * Mat4::from_rotation_y(1.1),
    );
    let frame = s.add_mesh(shapes::cuboid(Vec3::new(0.1, 0.3, 0.1)));
    for d in [-0.95f32, 0.95] {
        let foot = Vec3::new(-4.0 + d * 1.1f32.cos(), 0.15, 2.0 - d * 1.1f32.sin());
        s.add_object("PaneFoot", frame, steel, Mat4::from_translation(foot));
    }

    s.camera_presets = vec![
        (
            "eye-level".into(),
            Camera::new(Vec3::new(1.5, 1.6, 9.0), Vec3::new(0.0, 1.2, 0.0)),
        ),
        (
            "overview".into(),
            Camera::new(Vec3::new(8.0, 9.0, 10.0), Vec3::new(0.0, 0.5, -0.5)),
        ),
    ];
    s.light_presets = standard_lights(
        Vec3::new(0.5, 6.5, 2.0),
        Vec3::new(3.0, 7.0, 5.0),
        Vec3::new(0.0, 1.0, -0.5),
        Vec3::new(0.35, -1.0, -0.45),
        1.0,
    );
    s
}
