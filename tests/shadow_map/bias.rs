//! Bias and edges: the capped slope bias, edge-masked filters, second-depth
//! solids, the receiver plane and convex parts.

use super::common::*;
use shadowlab::scene::builtin;

/// The bias cap (`slope_bias_clamp`): in the half-pipe lit at grazing
/// angles, the uncapped slope bias pushes the pipe's own stored depth far
/// behind it and light leaks through onto the wall it shades; capped, the
/// interior is clean, and no acne appears elsewhere. The same holds for a
/// virtual map's clipmap levels, each capped by its own texel size (at 20
/// texel widths, not 5: it leaks a little more and keeps acne off curved
/// surfaces lit at grazing angles).
#[test]
fn capping_the_slope_bias_stops_light_leaking_at_grazing_casters() {
    let pipe = preset("curved", "pipe", "sun");
    for (technique, capped_at_most, uncapped_at_least) in [
        ("shadow-map:pcf", 0.05, 0.15),
        ("shadow-map:virtual", 0.05, 0.08),
    ] {
        let capped = compare(&pipe, technique, (320, 180)).mask;
        let uncapped = compare(
            &pipe,
            &format!("{technique}[slope_bias_clamp=0]"),
            (320, 180),
        )
        .mask;
        assert!(
            capped.interior.false_lit_pct <= capped_at_most
                && uncapped.interior.false_lit_pct >= uncapped_at_least
                && capped.interior.false_lit_pct <= 0.5 * uncapped.interior.false_lit_pct,
            "{technique}: capped {capped:?}\nuncapped {uncapped:?}"
        );
        // Capped, no acne comes back on the other scenes under the sun.
        for name in ["room", "bunny", "columns", "teapot", "floating"] {
            let mut scene = builtin::by_name(name).unwrap().unwrap();
            scene.lights = scene.light_preset("sun").unwrap();
            let m = compare(&scene, technique, (320, 180)).mask;
            assert!(
                m.interior.false_shadow_pct <= 0.1,
                "{technique} on {name}: {m:?}"
            );
        }
    }
}

/// Light 0's mask of one frame of `shadow-map` with `set`, and the frame's
/// counted work where the adapter counts it.
fn mask_and_work(
    scene: &shadowlab::scene::Scene,
    set: &[&str],
) -> (Vec<f32>, Option<shadowlab::gpu::FrameWork>) {
    let mut hf = frame_of(scene, "shadow-map", set, 240, 135);
    let work = gpu().pipeline_statistics.then(|| {
        gpu()
            .count_work(|| {
                render_again(&mut hf, scene);
                Ok(())
            })
            .unwrap()
    });
    if work.is_none() {
        eprintln!(
            "no pipeline statistics on {}: the edge mask's run is not shown",
            gpu().adapter_summary()
        );
        render_again(&mut hf, scene);
    }
    let masks = shadowlab::headless::read_back(gpu(), &hf.frame, 1)
        .unwrap()
        .masks;
    (masks[0].clone(), work)
}

#[test]
fn edge_masked_filters_equal_the_full_kernel_on_the_builtin_scenes() {
    for name in ["room", "columns", "city", "floating", "curved"] {
        let scene = builtin::by_name(name).unwrap().unwrap();
        for (filter, extra) in [
            ("grid", "samples=5"),
            ("disk", "radius=4"),
            ("pcss", "samples=4"),
            ("varwidth", "samples=3"),
            ("grid", "format=r8"),
            ("grid", "receiver_plane=true"),
        ] {
            let set = ["filter", filter].join("=");
            let (full, full_work) = mask_and_work(&scene, &[&set, extra]);
            let (masked, masked_work) = mask_and_work(&scene, &[&set, extra, "edge_mask=true"]);
            // The edge mask ran: its bounds chain is compute work the full
            // kernel's frame does not have.
            if let (Some(f), Some(m)) = (full_work, masked_work) {
                assert!(
                    m.masks.compute_invocations > f.masks.compute_invocations,
                    "{name} {filter} {extra}: no bounds chain ran ({m:?})"
                );
            }
            let differ = pixels_differing(&full, &masked);
            assert!(
                differ as f64 <= 1e-4 * full.len() as f64,
                "{name} {filter} {extra}: {differ} of {} pixels differ",
                full.len()
            );
        }
    }
}

/// `cull=solids` (the default): the columns and their lintel bound solids,
/// so the map holds their back faces unbiased and their lit faces take no
/// normal offset — the shadow edges stay where the silhouettes put them,
/// with fewer mismatched pixels than both faces biased and offset
/// (`cull=none`) and no acne on the lit faces. On the bunny, a smooth solid
/// that shadows itself near its terminators, a back face can lie too close
/// before the receiver to shadow it; the front faces stored with a pushed
/// bias (`solid_front_bias`) still do.
#[test]
fn solids_store_their_back_faces_and_keep_shadow_edges_in_place() {
    let columns = preset("columns", "default", "sun");
    let solids = compare(&columns, "shadow-map:pcf", (640, 360)).mask;
    let both = compare(&columns, "shadow-map:pcf[cull=none]", (640, 360)).mask;
    assert!(
        solids.all.total_pct <= 0.8 * both.all.total_pct && solids.interior.false_shadow_pct == 0.0,
        "solids {solids:?}\nboth faces {both:?}"
    );
    let bunny = preset("bunny", "default", "sun");
    let with_front = compare(&bunny, "shadow-map:pcf", (640, 360)).mask;
    let back_only = compare(&bunny, "shadow-map:pcf[solid_front_bias=0]", (640, 360)).mask;
    assert!(
        with_front.all.total_pct * 2.0 <= back_only.all.total_pct
            && with_front.interior.false_lit_pct <= 0.01
            && back_only.interior.false_lit_pct > 0.01,
        "front faces too {with_front:?}\nback faces only {back_only:?}"
    );
}

/// The receiver plane taken from the surface's own normal, each texel
/// compared against the plane at its centre: edges stay in place (screen
/// derivatives of the light-space position broke the plane at every pixel
/// quad that straddles an edge: 0.117 % total mismatch on columns/sun), and
/// a lit wall next to its building's corner no longer compares against the
/// back face that meets it there (the street's interior false shadow).
#[test]
fn the_receiver_plane_from_the_normal_keeps_edges_and_clears_corners() {
    let columns = preset("columns", "default", "sun");
    let plane = compare(&columns, "shadow-map:pcf", (640, 360)).mask;
    assert!(plane.all.total_pct <= 0.03, "{plane:?}");
    let city = preset("city", "street", "sun");
    let constant = compare(
        &city,
        "shadow-map:pcf[part_ids=false,receiver_plane=false]",
        (640, 360),
    )
    .mask;
    let plane = compare(&city, "shadow-map:pcf[part_ids=false]", (640, 360)).mask;
    assert!(
        plane.interior.false_shadow_pct <= 0.3 * constant.interior.false_shadow_pct,
        "plane {plane:?}\nconstant depth {constant:?}"
    );
}

/// Convex part IDs beside the depth (`part_ids`, the default), against one
/// constant depth without them: a lit wall of a building in the street
/// ignores the back faces of its own box that meet it at the corner (interior false shadow 0.123 → 0.017 % at
/// 640×360), while the buildings of one block mesh, separate parts, still
/// shadow each other and the trunks under the canopies (separate parts of
/// one tree) stay shadowed — the receiver plane's failure. A floor is a
/// flat part: it takes no normal offset, which only moved its shadow edges
/// (room under the point light: mean absolute error 0.00025 → 0.00020; the
/// thresholded mismatch, 7 and 8 pixels of 166,353, cannot tell them apart).
#[test]
fn convex_parts_ignore_their_own_texels_and_still_shadow_each_other() {
    let city = preset("city", "street", "sun");
    let parts = compare(&city, "shadow-map:pcf", (640, 360)).mask;
    let without = compare(
        &city,
        "shadow-map:pcf[part_ids=false,receiver_plane=false]",
        (640, 360),
    )
    .mask;
    assert!(
        parts.interior.false_shadow_pct <= 0.25 * without.interior.false_shadow_pct
            && parts.interior.false_shadow_pct <= 0.1
            && parts.interior.false_lit_pct <= without.interior.false_lit_pct + 0.001,
        "part IDs {parts:?}\nwithout {without:?}"
    );
    let landscape = preset("landscape", "ground", "sun");
    let parts = compare(&landscape, "shadow-map:pcf", (640, 360)).mask;
    let without = compare(
        &landscape,
        "shadow-map:pcf[part_ids=false,receiver_plane=false]",
        (640, 360),
    )
    .mask;
    assert!(
        parts.interior.false_lit_pct <= without.interior.false_lit_pct + 0.001,
        "part IDs {parts:?}\nwithout {without:?}"
    );
    let room = preset("room", "default", "point");
    let parts = compare(&room, "shadow-map:pcf", (640, 360)).mask;
    let without = compare(
        &room,
        "shadow-map:pcf[part_ids=false,receiver_plane=false]",
        (640, 360),
    )
    .mask;
    assert!(
        parts.mean_abs_error <= 0.85 * without.mean_abs_error
            && parts.interior.total_pct <= without.interior.total_pct,
        "part IDs {parts:?}\nwithout {without:?}"
    );
}

/// Near a concave surface's terminator a receiver lies within a texel of
/// its own silhouette in the map: the half-pipe's wall, lit at a grazing
/// angle, is shadowed by the wall across the pipe, but a 2×2 comparison
/// straddling the silhouette reads the ground beyond it as lit, and the
/// kernel spreads that over the wall's stretched texels. The defaults move
/// the lookup to the surface's side with a normal offset that only grazing
/// light takes (`normal_offset_power`), cap a spot map's slope bias
/// (`slope_bias_clamp_local`) and keep the kernel's ramp within two pixels
/// (`edge_ramp_pixels`): the wall is neither graded nor lit, against a band
/// of graded visibility with the earlier settings.
#[test]
fn a_concave_receivers_terminator_is_not_graded() {
    let earlier = "normal_offset_power=2,normal_offset_directional=0.25,normal_offset_local=0.5,\
                   slope_bias_clamp_local=0,edge_ramp_pixels=0";
    for light in ["sun", "spot"] {
        let pipe = preset("curved", "pipe", light);
        let now = compare(&pipe, "shadow-map:pcf", (320, 180)).mask;
        let before = compare(&pipe, &format!("shadow-map:pcf[{earlier}]"), (320, 180)).mask;
        assert!(
            now.interior_mae <= 0.002
                && now.graded_interior_pct <= 0.5
                && before.graded_interior_pct >= 2.0 * now.graded_interior_pct.max(0.1),
            "{light}: defaults {now:?}\nearlier settings {before:?}"
        );
    }
}

/// A faceted terrain (a heightfield of 0.1-unit facets with ridges and
/// hollows) under a point light overhead: where facets meet in a concave
/// crease, the next facet rises out of the receiver's plane within the
/// kernel's reach and the taps there read it as a caster, speckling the
/// lit ground with partial shadow (Bevy's `terrain.glb`: 2.2 % of interior
/// pixels graded). The crease tolerance (`crease_angle`) lets a tap sink a
/// few degrees below the plane: the ground is clean, and the terrain's own
/// shadows stay where the reference puts them.
#[test]
fn a_faceted_terrain_does_not_speckle_its_own_creases() {
    use glam::Vec3;
    let s = lit_heightfield(
        100,
        |x, z| {
            0.5 * (0.9 * x).sin() * (0.7 * z).cos() + 0.12 * (4.1 * x + 1.3 * z).sin().abs()
                - 0.08 * (3.3 * z - 2.1 * x).cos().abs()
        },
        shadowlab::scene::Light::point(Vec3::new(-1.0, 9.0, 1.5), 1.0),
        Vec3::new(6.0, 5.0, 8.0),
    );
    let now = compare(&s, "shadow-map:pcf", (320, 180)).mask;
    let plane_alone = compare(&s, "shadow-map:pcf[crease_angle=0]", (320, 180)).mask;
    assert!(
        now.interior_mae <= 0.002
            && now.graded_interior_pct <= 0.5
            && now.all.total_pct <= 0.3
            && plane_alone.graded_interior_pct >= 2.0 * now.graded_interior_pct.max(0.25),
        "defaults {now:?}\nplane alone {plane_alone:?}"
    );
}

/// Bosses rising out of an open ground mesh (walls at about 63°) under a
/// point light: on each boss's lit side the ground meets its wall at a
/// concave crease, and the taps beside a lit ground pixel read the wall as
/// a caster, ringing the base with partial shadow (Sascha Willems'
/// `retroufo`, its saucer around the domes: 0.88 % of interior pixels
/// graded at 15°). At the default crease tolerance the ring is gone.
#[test]
fn a_boss_rising_from_a_lit_receiver_does_not_ring_its_base_with_partial_shadow() {
    use glam::Vec3;
    let centres = [(-1.5, -1.0), (1.0, 0.5), (-0.5, 1.8), (2.2, -1.6)];
    let s = lit_heightfield(
        250,
        |x, z| {
            centres
                .iter()
                .map(|&(cx, cz)| {
                    let r = ((x - cx) * (x - cx) + (z - cz) * (z - cz)).sqrt();
                    0.4 * ((0.7 - r) / 0.2).clamp(0.0, 1.0)
                })
                .fold(0.0, f32::max)
        },
        shadowlab::scene::Light::point(Vec3::new(-1.0, 6.0, 1.5), 1.0),
        Vec3::new(2.5, 2.2, 3.5),
    );
    let now = compare(&s, "shadow-map:pcf", (320, 180)).mask;
    let earlier = compare(&s, "shadow-map:pcf[crease_angle=15]", (320, 180)).mask;
    assert!(
        now.graded_interior_pct <= 0.1
            && now.interior_mae <= 0.0002
            && now.all.total_pct <= 0.02
            && earlier.graded_interior_pct >= 3.0 * now.graded_interior_pct.max(0.05),
        "defaults {now:?}\nat 15° {earlier:?}"
    );
}

/// Low boxes (raised lettering, 0.06 high) standing on an open dish under
/// a point light grazing it: each box is a solid, stored by its back faces
/// just above the dish behind it, and its long shadow runs out low over
/// the dish. The crease tolerance forgives the taps only where the
/// receiver's own texel is lit, so the shadows stay: without that
/// condition, 30° took false lit from 1.24 to 1.75 % and graded interior
/// from 0.71 to 1.54 % (Sascha Willems' `vulkanscenelogos`: 0.30 → 0.82 %).
#[test]
fn low_solid_casters_under_grazing_light_keep_their_shadows_at_the_crease_tolerance() {
    use glam::{Mat4, Vec3};
    use shadowlab::scene::{Camera, Light, Material, Scene, shapes};
    let dish = |x: f32, z: f32| 0.01 * (x * x + z * z);
    let mut s = Scene::new("lettering");
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let ground = s.add_mesh(shapes::heightfield(10.0, 100, dish));
    s.add_object("Dish", ground, grey, Mat4::IDENTITY);
    let letter = s.add_mesh(shapes::cuboid(Vec3::new(0.08, 0.06, 0.5)));
    for i in -4..=4 {
        for j in -2..=2 {
            let (x, z) = (i as f32 * 0.5, j as f32 * 0.8);
            let centre = Vec3::new(x, dish(x, z) + 0.028, z);
            s.add_object("Letter", letter, grey, Mat4::from_translation(centre));
        }
    }
    s.lights = vec![Light::point(Vec3::new(-4.0, 0.8, 0.0), 1.0)];
    s.camera = Camera::new(Vec3::new(1.0, 1.5, 2.5), Vec3::ZERO);
    s.finalize().unwrap();
    let now = compare(&s, "shadow-map:pcf", (320, 180)).mask;
    let plane_alone = compare(&s, "shadow-map:pcf[crease_angle=0]", (320, 180)).mask;
    assert!(
        now.all.false_lit_pct <= 1.2 * plane_alone.all.false_lit_pct
            && now.graded_interior_pct <= 1.25 * plane_alone.graded_interior_pct.max(0.1),
        "defaults {now:?}\nplane alone {plane_alone:?}"
    );
}

/// A concave solid (a torus lying on a floor) under a sun low over it: its
/// front faces are stored pushed back by `solid_front_bias` times a capped
/// bias, which at grazing light still meets the lit face it came from, so
/// its receivers take half the normal offset open casters take (before,
/// they took none, as a convex solid's, whose lit faces the map does not
/// hold: interior false shadow 0.045 and 0.049 % at 320×180, in bands along
/// the terminator; Bevy's `Fox.glb` under a sun 1.07 → 0.20 % total at
/// 640×360).
#[test]
fn a_concave_solid_lit_at_grazing_angles_does_not_shadow_itself() {
    use glam::{Mat4, Vec3};
    use shadowlab::scene::{Camera, Light, shapes};
    for direction in [Vec3::new(-0.3, -0.2, 1.0), Vec3::new(1.0, -0.1, 0.0)] {
        let (mut s, grey) = grey_floor_scene("torus", 10.0, 8);
        let torus = s.add_mesh(shapes::torus(1.5, 0.5, 48, 16));
        s.add_object("Torus", torus, grey, Mat4::from_translation(Vec3::Y * 0.5));
        s.lights = vec![Light::directional(direction, 1.0)];
        s.camera = Camera::new(Vec3::new(4.0, 3.0, 6.0), Vec3::new(1.0, 0.5, 0.0));
        s.finalize().unwrap();
        let m = compare(&s, "shadow-map:pcf", (320, 180)).mask;
        assert!(
            m.interior.false_shadow_pct <= 0.01 && m.interior_mae <= 0.0002,
            "{direction}: {m:?}"
        );
    }
}

/// A nozzle whose rim (a flat square ring facing +z) is one mesh and whose
/// outer sides and inner tunnel walls, falling away from the rim's edges,
/// are another, as a glTF mesh's primitives split by material are (Bevy's
/// `craft_speederD.gltf`: its nozzles' rims). A receiver on the rim
/// compared the walls' texels against one depth, and along its edges,
/// where the rim's plane rises towards the light, they lay nearer the
/// light than that depth: false shadow all over a rim a few texels wide
/// (here 0.098 % total, 0.045 % interior false shadow; the ship under its
/// point light, `pcf` 0.62 → 0.16 % at 640×360). Such a part is not used,
/// and the rim is compared along its plane.
#[test]
fn a_flat_part_whose_edges_go_on_in_another_mesh_is_compared_along_its_plane() {
    use glam::{Mat4, Vec3};
    use shadowlab::scene::{Camera, Light, Mesh};
    let (mut s, grey) = grey_floor_scene("nozzle", 12.0, 4);
    // Squares of half-side 0.4 and 0.3 around (0, 1) in the plane z = z.
    let square = |half: f32, z: f32| {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y): (f32, f32)| Vec3::new(x * half, 1.0 + y * half, z))
    };
    let (outer, inner) = (square(0.4, 1.0), square(0.3, 1.0));
    let mut rim = Mesh {
        name: "rim".into(),
        positions: outer.iter().chain(&inner).copied().collect(),
        ..Default::default()
    };
    let mut walls = Mesh {
        name: "walls".into(),
        ..Default::default()
    };
    for k in 0..4u32 {
        let n = (k + 1) % 4;
        // The rim's quad between the two squares, facing +z.
        rim.indices.extend([k, n, 4 + n, k, 4 + n, 4 + k]);
        // The outer side and the tunnel wall below edge k, down to z = 0.
        for square in [outer, inner] {
            let base = walls.positions.len() as u32;
            let (a, b) = (square[k as usize], square[n as usize]);
            let back = |p: Vec3| Vec3::new(p.x, p.y, 0.0);
            walls.positions.extend([a, b, back(b), back(a)]);
            walls.indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
        }
    }
    let (rim, walls) = (s.add_mesh(rim), s.add_mesh(walls));
    s.add_object("Rim", rim, grey, Mat4::IDENTITY);
    s.add_object("Walls", walls, grey, Mat4::IDENTITY);
    s.lights = vec![Light::point(Vec3::new(-3.0, 6.0, 2.0), 1.0)];
    s.camera = Camera::new(Vec3::new(0.8, 1.6, 3.0), Vec3::new(0.0, 1.0, 1.0));
    s.finalize().unwrap();
    let m = compare(&s, "shadow-map:pcf", (320, 180)).mask;
    assert!(
        m.interior.false_shadow_pct <= 0.01 && m.all.total_pct <= 0.06,
        "{m:?}"
    );
}

/// A corrugated sheet (an open heightfield of ridges, no convex part, so
/// its receivers take the whole normal offset) under a point light low over
/// it: each crest shades the slope behind it, a receiver lit at a grazing
/// angle. The offset lifts lookups off those slopes by a share of a texel;
/// the shadow edge then moves along the slope by that share over the
/// cosine of the incidence, and the crest's thin shadows lose a band of
/// pixels (open meshes under a point light: Sascha Willems' `cerberus`
/// 3.52 → 2.47 %, `deer` 1.61 → 1.13 %, a full texel against half).
#[test]
fn a_corrugated_sheet_under_a_low_point_light_keeps_its_crests_shadows() {
    use glam::Vec3;
    let s = lit_heightfield(
        160,
        |x, z| 0.25 * (2.5 * x + 0.3 * z).sin(),
        shadowlab::scene::Light::point(Vec3::new(-7.0, 1.6, 1.0), 1.0),
        Vec3::new(3.0, 4.0, 7.0),
    );
    let now = compare(&s, "shadow-map:pcf", (320, 180)).mask;
    let full_texel = compare(&s, "shadow-map:pcf[normal_offset_local=1]", (320, 180)).mask;
    assert!(
        now.interior_mae <= 0.002
            && now.graded_interior_pct <= 0.5
            && now.all.total_pct <= 0.25
            && full_texel.all.false_lit_pct >= 1.5 * now.all.false_lit_pct,
        "defaults {now:?}\na full texel {full_texel:?}"
    );
}

/// A low-poly hill (an open heightfield of 12 × 12 cells) under a low sun:
/// its facets turned from the sun are lit at grazing angles, where the
/// virtual and adaptive maps' finest levels, a texel about a pixel wide,
/// compared each facet with its own stored depth and striped it with
/// partial shadow (Sascha Willems' `rock01`: 1.21 % of interior pixels
/// graded). Their presets move the lookup ¾ texel of the level along the
/// normal (× sin⁸θ), as the cascades' do, not ½.
#[test]
fn paged_maps_do_not_stripe_facets_a_low_sun_grazes() {
    use glam::Vec3;
    let s = lit_heightfield(
        12,
        |x, z| 2.0 * (-(x * x + z * z) / 4.0).exp() + 0.3 * (1.7 * x).sin() * (1.3 * z).cos(),
        shadowlab::scene::Light::directional(Vec3::new(1.0, -0.4, 0.2), 1.0),
        Vec3::new(6.0, 4.0, 7.0),
    );
    for technique in ["shadow-map:virtual", "shadow-map:adaptive"] {
        let now = compare(&s, technique, (320, 180)).mask;
        let half = compare(
            &s,
            &format!("{technique}[normal_offset_directional=0.5]"),
            (320, 180),
        )
        .mask;
        assert!(
            now.interior_mae <= 0.001
                && now.graded_interior_pct <= 0.3
                && now.all.total_pct <= 0.1
                && half.graded_interior_pct >= 3.0 * now.graded_interior_pct.max(0.1),
            "{technique}: defaults {now:?}\nhalf a texel {half:?}"
        );
    }
}

/// A grey open heightfield 10 units wide of `cells`² cells at `height(x, z)`
/// (no convex part: its receivers take the whole normal offset), lit by
/// `light` and seen from `eye` towards the origin.
fn lit_heightfield(
    cells: u32,
    height: impl Fn(f32, f32) -> f32,
    light: shadowlab::scene::Light,
    eye: glam::Vec3,
) -> shadowlab::scene::Scene {
    use glam::{Mat4, Vec3};
    use shadowlab::scene::{Camera, Material, Scene, shapes};
    let mut s = Scene::new("heightfield");
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let ground = s.add_mesh(shapes::heightfield(10.0, cells, height));
    s.add_object("Ground", ground, grey, Mat4::IDENTITY);
    s.lights = vec![light];
    s.camera = Camera::new(eye, Vec3::ZERO);
    s.finalize().unwrap();
    s
}
