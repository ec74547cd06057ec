//! Paged shadow maps: the virtual map's page marking, cache, lookups
//! across page borders and degradation, and the adaptive map's refinement
//! at shadow edges.

mod common;
use common::*;
use glam::{Mat4, Vec3};
use shadowlab::scene::shapes;
use shadowlab::scene::{Light, Scene, builtin};

/// A sun straight down on the 20×20 floor, the camera 8 above looking
/// down (50° square view): every pixel sees 7.46/256 = 0.0291 of floor.
/// With 1024² windows of 128² pages and 6 clipmap levels over the scene's
/// 20.002-wide square, level 4's texel (0.0195) is the coarsest at most a
/// pixel wide (level 5's is 0.039); its pages are 2.5005 wide from
/// x = −10.001, so the seen ±3.73 (plus the 3×3 grid's 2.5 texels) crosses
/// the page borders at −2.4985, 0.0020 and 2.5025: 4 × 4 = 16 pages.
#[test]
fn virtual_pages_marked_for_a_known_view_match_the_hand_count_and_stay_cached() {
    let scene = square_under_the_sun(Vec3::new(0.0, 1.0, 0.0));
    let set = SMALL_CLIPMAP;
    let mut hf = rendered_frame(&scene, "shadow-map:virtual", &set, 256, 256);
    assert_eq!(counter(&hf, "pages_needed"), 16.0);
    assert_eq!(counter(&hf, "pages_rendered"), 16.0);
    // A still camera and light: nothing to render, everything cached.
    render_again(&mut hf, &scene);
    assert_eq!(counter(&hf, "pages_rendered"), 0.0);
    assert_eq!(counter(&hf, "pages_cached"), 16.0);
    assert_eq!(counter(&hf, "pages_resident"), 16.0);
}

/// Texels read across page borders are the texels of one map: the same
/// virtual map of a spot light (a mip chain over the whole view, the same
/// levels whatever the pages) cut into 32² pages and into 512² pages (each
/// the full-resolution map of a quarter of the view) gives the same mask,
/// filtered over a wide kernel — and over one wider than a 32² page (taps
/// beyond the 2×2 pages of its least corner).
#[test]
fn virtual_lookups_across_page_borders_match_one_full_map() {
    let scene = squares_over_floor(
        &[
            (Vec3::new(0.5, 1.0, 0.2), 0.7),
            (Vec3::new(-1.5, 2.0, -1.0), 0.5),
        ],
        Light::spot(Vec3::new(1.0, 5.0, 1.0), Vec3::ZERO, 1.0, 30.0, 40.0),
        false,
    );
    let mask = |page: &str, pool: &str, radius: &str| {
        mask_of(
            &scene,
            "shadow-map:virtual",
            &[
                "virtual_size=1024",
                page,
                pool,
                "clipmap_levels=6",
                "filter=disk",
                radius,
                "samples=5",
                // The slope bias this test was measured with: the kernels
                // reach 6 and 20 texels, past what any slope bias holds off
                // the floor, so a few floor pixels compare their own depth
                // at the threshold, where the last bits of two renders
                // differ (with the family's 2: 8 such pixels at radius 20).
                "slope_bias=1",
                // The level each pixel reads as measured then (one texel
                // per pixel): the 512² pages' pool of 64 holds it whole.
                "texels_per_pixel=1",
            ],
            256,
            256,
        )
    };
    for radius in ["radius=6", "radius=20"] {
        let paged = mask("page_size=32", "pool=4096", radius);
        let whole = mask("page_size=512", "pool=64", radius);
        let shadowed = whole.iter().filter(|v| **v < 0.5).count();
        assert!(shadowed > 1000, "{radius}: {shadowed}");
        let differ = pixels_differing(&paged, &whole);
        assert!(
            differ <= 6,
            "{radius}: {differ} of {} pixels differ",
            paged.len()
        );
    }
}

/// A pool far too small for the view: finer levels give way to coarser
/// ones (counted), the mask stays a shadow of the right casters.
#[test]
fn a_virtual_pool_too_small_degrades_to_coarser_pages_without_garbage() {
    let scene = builtin::by_name("columns").unwrap().unwrap();
    let full = rendered_frame(&scene, "shadow-map:virtual", &[], 320, 180);
    let needed = counter(&full, "pages_needed");
    let small = rendered_frame(&scene, "shadow-map:virtual", &["pool=16"], 320, 180);
    assert!(needed > 16.0, "{needed}");
    assert!(counter(&small, "pages_degraded") > 0.0);
    assert!(counter(&small, "pages_resident") <= 16.0);
    let row = compare(&scene, "shadow-map:virtual[pool=16]", (320, 180));
    let good = compare(&scene, "shadow-map:virtual", (320, 180));
    // Both bounded by the reference's shadow, so that two broken maps
    // cannot pass by agreeing: the full pool within 0.5 % of it, the
    // degraded one within 1 %, and never better.
    let shadow = row.mask.reference_shadowed_pct;
    assert!(shadow > 5.0);
    assert!(good.mask.all.total_pct <= 0.005 * shadow, "{:?}", good.mask);
    assert!(row.mask.all.total_pct <= 0.01 * shadow, "{:?}", row.mask);
    assert!(good.mask.all.total_pct <= row.mask.all.total_pct + 1e-9);
}

/// A pixel takes its level from its own surface, not from its G-buffer
/// neighbours. The hand count's view with one more square, half size 0.01
/// at height 4, 4 below the camera: there a pixel spans 0.0291 × 4/8 =
/// 0.01455, so the square is 1.37 pixels wide and its pixels need level 3
/// (texel 0.00977; level 4's 0.0195 is wider than them), pages no floor
/// pixel asks for. Their neighbours are floor pixels, 4 farther: measured
/// from those, the square's pixels took coarser texels than they need.
#[test]
fn a_pixel_whose_neighbours_lie_on_another_surface_keeps_its_own_level() {
    let mut scene = square_under_the_sun(Vec3::new(0.0, 1.0, 0.0));
    // Facing the camera (the helper's squares face the floor).
    let quad = scene.add_mesh(shapes::plane(2.0, 2.0, 1));
    let grey = scene.objects[0].material;
    let speck =
        Mat4::from_translation(Vec3::new(0.3, 4.0, 0.3)) * Mat4::from_scale(Vec3::splat(0.01));
    scene.add_object("Speck", quad, grey, speck);
    scene.finalize().unwrap();
    let floor_only = rendered_frame(
        &square_under_the_sun(Vec3::new(0.0, 1.0, 0.0)),
        "shadow-map:virtual",
        &SMALL_CLIPMAP,
        256,
        256,
    );
    assert_eq!(counter(&floor_only, "pages_needed"), 16.0);
    let hf = rendered_frame(&scene, "shadow-map:virtual", &SMALL_CLIPMAP, 256, 256);
    assert!(counter(&hf, "pages_needed") > 16.0);
    let id = format!("shadow-map:virtual[{}]", SMALL_CLIPMAP.join(","));
    let row = compare(&scene, &id, (256, 256));
    let footprint = row.aliasing.expect("a footprint");
    // Every pixel's texel spans 0.67 of it: the floor's level-4 texels
    // 0.0195 / 0.0291 and the square's level-3 texels 0.00977 / 0.01457
    // (a level too coarse would read 1.34 or more there; the neighbours'
    // rule gave 0.95 at the square's edge).
    assert!((footprint.max - 0.670).abs() < 0.005, "{footprint:?}");
}

/// The clipmap of the hand counts: 1024² windows of 128² pages, 6 levels.
const SMALL_CLIPMAP: [&str; 3] = ["virtual_size=1024", "page_size=128", "clipmap_levels=6"];

/// The floor of the hand counts under a sun straight down, with one square
/// of half size 0.7 centred at `centre`.
fn square_under_the_sun(centre: Vec3) -> Scene {
    squares_over_floor(
        &[(centre, 0.7)],
        Light::directional(Vec3::NEG_Y, 1.0),
        false,
    )
}

/// The sun straight down on the floor of the hand count above, its one
/// square far outside the view (its shadow at x, z = 7.3 … 8.7): no shadow
/// edge in view, so an adaptive map stays at its root, the coarsest
/// clipmap level (1024 texels over 20.002 × 2, pages 5.0005 wide from
/// x = −10.001, a border at 0.000 on each axis): 2 × 2 pages, rendered by
/// the first pass; the second finds nothing to refine.
#[test]
fn an_adaptive_map_without_shadow_edges_stays_at_its_root() {
    let scene = square_under_the_sun(Vec3::new(8.0, 1.0, 8.0));
    let set = SMALL_CLIPMAP;
    let mut hf = rendered_frame(&scene, "shadow-map:adaptive", &set, 256, 256);
    assert_eq!(counter(&hf, "pages_needed"), 4.0);
    assert_eq!(counter(&hf, "pages_rendered"), 4.0);
    assert_eq!(counter(&hf, "refine_passes"), 2.0);
    render_again(&mut hf, &scene);
    assert_eq!(counter(&hf, "pages_rendered"), 0.0);
    assert_eq!(counter(&hf, "pages_cached"), 4.0);
    assert_eq!(counter(&hf, "refine_passes"), 1.0);
}

/// One square over that floor: its shadow's edges (x, z = ±0.7) lie in
/// the 2 × 2 pages of level 4 (the finest the pixels need, pages 2.5005
/// wide with borders at 0.002) around the centre, so the adaptive map
/// refines those 4 pages and keeps the 4 root pages for the rest — 8, where
/// the virtual map needs level 4's 16 — and its mask is the virtual map's.
#[test]
fn an_adaptive_map_refines_only_at_shadow_edges_and_matches_the_virtual_map() {
    let scene = square_under_the_sun(Vec3::new(0.0, 1.0, 0.0));
    let set = SMALL_CLIPMAP;
    let hf = rendered_frame(&scene, "shadow-map:adaptive", &set, 256, 256);
    assert_eq!(counter(&hf, "pages_needed"), 8.0);
    assert_eq!(counter(&hf, "refine_passes"), 3.0);
    let adaptive = mask_of(&scene, "shadow-map:adaptive", &set, 256, 256);
    let virtual_map = mask_of(&scene, "shadow-map:virtual", &set, 256, 256);
    let shadowed = virtual_map.iter().filter(|v| **v < 0.5).count();
    assert!(shadowed > 2000, "{shadowed}");
    assert_eq!(pixels_differing(&adaptive, &virtual_map), 0);
}

/// On the built-in scenes' default views (point, spot and sun lights, cube
/// seams included) the adaptive map shades like the virtual map: it
/// refines wherever the virtual map's finer pages would change a pixel.
#[test]
fn adaptive_maps_agree_with_virtual_maps_on_the_builtin_scenes() {
    for name in ["room", "columns", "floating", "curved"] {
        let scene = builtin::by_name(name).unwrap().unwrap();
        let adaptive = compare(&scene, "shadow-map:adaptive", (320, 180));
        let virtual_map = compare(&scene, "shadow-map:virtual", (320, 180));
        // The virtual map itself within 2 % of the reference's shadow, so
        // that the two cannot agree on a broken mask.
        let shadow = virtual_map.mask.reference_shadowed_pct;
        assert!(shadow > 1.0, "{name}: {shadow}");
        assert!(
            virtual_map.mask.all.total_pct <= 0.02 * shadow,
            "{name}: virtual {:?}",
            virtual_map.mask
        );
        assert!(
            adaptive.mask.all.total_pct <= virtual_map.mask.all.total_pct + 0.05,
            "{name}: adaptive {:?} virtual {:?}",
            adaptive.mask,
            virtual_map.mask
        );
    }
}

/// In the viewer the marks arrive a frame late, so an adaptive map refines
/// a pass per frame: it starts coarser, and a few frames later it has the
/// pages and the mask that waiting for every pass gives in one frame.
#[test]
fn an_adaptive_map_refined_a_frame_late_converges_to_the_waited_one() {
    let scene = square_under_the_sun(Vec3::new(0.0, 1.0, 0.0));
    let set = SMALL_CLIPMAP;
    let waited = mask_of(&scene, "shadow-map:adaptive", &set, 256, 256);
    let mut hf = frame_of(&scene, "shadow-map:adaptive", &set, 256, 256);
    let settings = shadowlab::renderer::RenderSettings {
        show_light_icons: false,
        feedback: shadowlab::technique::Feedback::PreviousFrame,
        ..Default::default()
    };
    let mut needed = vec![];
    for _ in 0..12 {
        hf.render(gpu(), &scene, &scene.camera, &scene.lights, &settings)
            .unwrap();
        needed.push(counter(&hf, "pages_needed"));
    }
    assert_eq!(needed[0], 0.0, "nothing to allocate before marks arrive");
    assert_eq!(*needed.last().unwrap(), 8.0, "{needed:?}");
    let late = shadowlab::headless::read_back(gpu(), &hf.frame, 1)
        .unwrap()
        .masks
        .remove(0);
    assert_eq!(pixels_differing(&late, &waited), 0);
}

/// A local light's virtual map read one texel per pixel leaves a pixel of
/// staircase along every shadow edge; the default four texels per pixel
/// (two levels finer) halves the mismatch or better, on a point and a spot
/// light's view, while a directional clipmap keeps its level.
#[test]
fn finer_levels_for_local_lights_cut_the_edge_mismatch() {
    for (scene, light) in [("floating", "point"), ("room", "spot")] {
        let mut s = builtin::by_name(scene).unwrap().unwrap();
        s.lights = s.light_preset(light).unwrap();
        let coarse = compare(&s, "shadow-map:virtual[texels_per_pixel=1]", (320, 180));
        let fine = compare(&s, "shadow-map:virtual", (320, 180));
        let (c, f) = (coarse.mask.all.total_pct, fine.mask.all.total_pct);
        assert!(
            c > 0.0 && f <= 0.5 * c,
            "{scene}/{light}: {c:.4} % → {f:.4} %"
        );
    }
    let mut sun = builtin::by_name("columns").unwrap().unwrap();
    sun.lights = sun.light_preset("sun").unwrap();
    let pages = |tpp: &str| {
        let hf = rendered_frame(&sun, "shadow-map:virtual", &[tpp], 320, 180);
        counter(&hf, "pages_needed")
    };
    assert_eq!(pages("texels_per_pixel=1"), pages("texels_per_pixel=4"));
}

/// A low view of the room's floor, which its point light grazes far from
/// it: the receiver plane of the virtual map (and of the adaptive map's
/// finest levels) was measured from points each moved along the normal
/// again, by an offset that changes along the floor with the distance to
/// the light and as sinⁿθ, which tilted the plane: 0.8 % of the interior
/// floor speckled with partial shadow (interior MAE 0.0018) at this size.
#[test]
fn a_floor_a_point_light_grazes_is_not_speckled() {
    let mut room = preset("room", "default", "point");
    room.camera = shadowlab::scene::Camera::new(
        Vec3::new(6.767, 1.090, -3.922),
        Vec3::new(-1.544, 1.026, -0.766),
    );
    for id in ["shadow-map:virtual", "shadow-map:adaptive"] {
        let m = compare(&room, id, (240, 135)).mask;
        assert!(
            m.interior_mae <= 0.0005 && m.graded_interior_pct <= 0.1,
            "{id}: {m:?}"
        );
    }
}
