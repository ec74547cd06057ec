//! The stabilised window of a directional map (one map or a cascade) or a
//! focused spot map: a rectangle of the light's image (a square for spot
//! maps and for stabilised cascades within the scene) whose half-extents are rounded up to
//! eighths of an octave and whose centre is snapped to whole texels, so that small
//! camera moves leave the texel grid in place, with last frame's kept
//! while it still holds what is needed ([`Hold`]); and the window around
//! a fitted box, widened for the kernels that read past it.

use super::FrustumParams;
use crate::scene::Aabb;
use glam::Vec2;

/// Maps fitted to the pixels the camera saw reach this many texels past
/// their box on each side (filter kernels, normal offset and blending
/// look there).
const SAMPLE_FIT_MARGIN_TEXELS: f32 = 16.0;

/// A rectangle of a light's image: half-extents along its x and y axes
/// and centre. A `size`² map over it has texels `2·half / size` wide on
/// each axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub half: Vec2,
    pub centre: Vec2,
}

impl Window {
    /// The window of a box `[min x, min y, max x, max y]` (half-extents at
    /// least 1 mm).
    pub fn around([x0, y0, x1, y1]: [f32; 4]) -> Window {
        Window {
            half: (Vec2::new(x1 - x0, y1 - y0) * 0.5).max(Vec2::splat(1e-3)),
            centre: Vec2::new(x0 + x1, y0 + y1) * 0.5,
        }
    }

    /// The square around it (square texels: the larger extent on both
    /// axes).
    pub fn square(self) -> Window {
        Window {
            half: Vec2::splat(self.half.max_element()),
            ..self
        }
    }

    /// Its centre moved down to the nearest corner of the texel grid of a
    /// `size`² map over it.
    pub fn snapped(self, size: u32) -> Window {
        let texel = 2.0 * self.half / size as f32;
        Window {
            centre: (self.centre / texel).floor() * texel,
            ..self
        }
    }
}

/// The x/y extent `[min x, min y, max x, max y]` of a light-view box.
pub fn xy_box(b: &Aabb) -> [f32; 4] {
    [b.min.x, b.min.y, b.max.x, b.max.y]
}

/// A light-view box `[min x, min y, max x, max y]` grown on each side by
/// [`SAMPLE_FIT_MARGIN_TEXELS`] texels of the `size`² map whose window
/// will hold it: on each axis, the window's half-extent h satisfies
/// h·(1 − 2m/size) = the box's half-extent.
pub fn widen_for_kernels(b: [f32; 4], size: u32) -> [f32; 4] {
    let [x0, y0, x1, y1] = b;
    let half = Window::around(b).half;
    let margin = half / (1.0 - 2.0 * SAMPLE_FIT_MARGIN_TEXELS / size as f32).max(0.5) - half;
    [x0 - margin.x, y0 - margin.y, x1 + margin.x, y1 + margin.y]
}

/// A quarter octave, 2^(1/4): the room and hysteresis of [`Hold`].
const QUARTER_OCTAVE: f32 = 1.189_207_1;

/// An eighth of an octave, 2^(1/8): the step [`quantize_up`] rounds to.
const EIGHTH_OCTAVE: f32 = 1.090_507_7;

/// `v` rounded up to the next 2^(k/8) (at most 9 % more): sizes that stay
/// put under small changes.
pub fn quantize_up(v: f32) -> f32 {
    2f32.powf((v.max(1e-6).log2() * 8.0).ceil() / 8.0)
}

/// `v` rounded down to the previous 2^(k/8).
pub fn quantize_down(v: f32) -> f32 {
    2f32.powf((v.max(1e-6).log2() * 8.0).floor() / 8.0)
}

/// How a stabilised fitted window is kept from frame to frame, on each
/// axis: a fresh fit takes `headroom` times the half-extent it needs
/// (rounded up to an eighth of an octave), and last frame's is kept while
/// it holds the one needed and is at most `kept_ratio` times larger. Every
/// change of size moves every texel edge across that axis, so every
/// shadow edge, at once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hold {
    pub headroom: f32,
    pub kept_ratio: f32,
}

impl Hold {
    /// Fits to the camera's view (frustum, seen depths, cascades): they
    /// change smoothly with the camera; a quarter octave of hysteresis
    /// (a fresh fit is at most an eighth larger) keeps a size at a
    /// rounding step from flipping.
    pub const VIEW: Hold = Hold {
        headroom: 1.0,
        kept_ratio: QUARTER_OCTAVE,
    };
    /// Fits to the pixels seen: their extents jump when a far feature comes
    /// into view or leaves it by a pixel, so a fresh fit takes a quarter
    /// octave more, and is kept through a jump of a quarter octave either
    /// way: it is up to 2^(3/8) times its need (the room, then rounding up
    /// to an eighth), so it is kept down to where it is 2^(5/8) times the
    /// need (a lower bound dropped fresh fits when the box shrank back).
    pub const SAMPLES: Hold = Hold {
        headroom: QUARTER_OCTAVE,
        kept_ratio: QUARTER_OCTAVE * QUARTER_OCTAVE * EIGHTH_OCTAVE,
    };
}

/// A fitted window (the half-extents it needs, centre) as `fp` keeps it:
/// with `stabilize_size`, on each axis last frame's half-extent
/// (`previous_half`) while `hold` keeps it, else a fresh one of
/// `hold.headroom` times the need rounded up to 2^(k/8), the centre
/// snapped to the texels that gives; unchanged otherwise.
pub fn stabilized(need: Window, fp: &FrustumParams, hold: Hold) -> Window {
    let Some(size) = fp.stabilize_size else {
        return need;
    };
    let fresh = |n: f32| quantize_up(n * hold.headroom);
    let kept = |p: f32, n: f32| {
        if p >= n && p <= n * hold.kept_ratio {
            p
        } else {
            fresh(n)
        }
    };
    let half = match fp.previous_half {
        Some(p) => Vec2::new(kept(p.x, need.half.x), kept(p.y, need.half.y)),
        None => need.half.map(fresh),
    };
    Window { half, ..need }.snapped(size)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Aabb, Camera, Light};
    use crate::technique::shadow_map::projection::FrustumParams;
    use crate::technique::shadow_map::projection::roll::Supports;
    use crate::technique::shadow_map::projection::setup::{ViewFit, directional_setup};
    use glam::{Vec2, Vec3};

    /// A sun straight down over a 200 × 200 floor and a narrow camera 10 m
    /// above it at z = `eye_z`, looking down −z and seeing 60 m: the one
    /// map's half-extents under `fp` (and its `texel_scale`, checked to be
    /// the longer side's).
    fn half_extents(eye_z: f32, fp: &FrustumParams) -> Vec2 {
        let light = Light::directional(Vec3::new(0.0, -1.0, 0.0), 1.0);
        let bounds = Aabb {
            min: Vec3::new(-100.0, 0.0, -100.0),
            max: Vec3::new(100.0, 1.0, 100.0),
        };
        let mut camera = Camera::new(
            Vec3::new(0.0, 10.0, eye_z),
            Vec3::new(0.0, 0.0, eye_z - 30.0),
        );
        camera.far = 60.0;
        camera.fov_y_deg = 30.0;
        let (setup, fit) = directional_setup(&light, &bounds, &camera, 1.0, fp);
        assert_eq!(setup.texel_scale, 2.0 * fit.half.max_element());
        fit.half
    }

    /// That map fitted to the view, stabilised for 2048² or not.
    fn fit(eye_z: f32, stabilize_size: Option<u32>, previous_half: Option<Vec2>) -> Vec2 {
        let fp = FrustumParams {
            stabilize_size,
            previous_half,
            ..Default::default()
        };
        half_extents(eye_z, &fp)
    }

    /// That map from z = 0 fitted to pixels seen over a `w` × `h` box of
    /// the light's image around its origin, stabilised for 2048².
    fn fit_to_box(w: f32, h: f32, previous_half: Option<Vec2>) -> Vec2 {
        let (x, y) = (w * 0.5, h * 0.5);
        let supports =
            Supports::of_points([(-x, -y), (x, -y), (x, y), (-x, y)].map(|(x, y)| Vec2::new(x, y)))
                .unwrap();
        let fp = FrustumParams {
            stabilize_size: Some(2048),
            previous_half,
            view_fit: ViewFit::Samples {
                supports,
                size: 2048,
            },
            ..Default::default()
        };
        half_extents(0.0, &fp)
    }

    /// The same over a `side`-wide square: its (equal) half-extents.
    fn fit_to_samples(side: f32, previous_half: Option<f32>) -> f32 {
        fit_to_box(side, side, previous_half.map(Vec2::splat)).x
    }

    /// A 16-texel margin on each side of a 2048² map: the half-extent a
    /// side needs.
    fn need(side: f32) -> f32 {
        side * 0.5 / (1.0 - 32.0 / 2048.0)
    }

    /// A map fitted to the pixels seen takes a quarter octave of room on a
    /// fresh fit, keeps its size while their box grows by less or shrinks
    /// until the map is 2^(5/8) times what it needs, and is never
    /// larger than the view of the scene needs.
    #[test]
    fn a_map_fitted_to_the_pixels_seen_keeps_its_size_through_jumps_of_their_box() {
        // A 10-wide box, widened by 16 texels a side for the kernels.
        let fresh = fit_to_samples(10.0, None);
        let roomy = need(10.0) * Hold::SAMPLES.headroom;
        assert!(
            fresh >= roomy && fresh < roomy * 1.0906,
            "{fresh} vs {roomy}"
        );
        // The box grows 15 %: kept.
        assert_eq!(fit_to_samples(11.5, Some(fresh)), fresh);
        // It shrinks: kept while the map is at most 2^(5/8) times what it
        // needs — through a shrink by a quarter octave, as far as it grew.
        let smallest_kept = 2.0 * fresh / Hold::SAMPLES.kept_ratio * (1.0 - 32.0 / 2048.0);
        assert_eq!(fit_to_samples(10.0 / QUARTER_OCTAVE, Some(fresh)), fresh);
        assert_eq!(fit_to_samples(smallest_kept * 1.01, Some(fresh)), fresh);
        assert!(fit_to_samples(smallest_kept * 0.9, Some(fresh)) < fresh);
        // Past what it holds: a fresh fit, with room again.
        let grown = fit_to_samples(13.0, Some(fresh));
        assert!(grown >= need(13.0) * Hold::SAMPLES.headroom, "{grown}");
        // Pixels over more than the camera's view of the scene (which a
        // frame-late box widened for motion can be): the view's window.
        let view = fit(0.0, Some(2048), None);
        assert_eq!(fit_to_box(500.0, 500.0, None), view);
    }

    /// A box longer one way gets a window of its shape, not the square
    /// around it: the texels along its short side are finer. Each side is
    /// rounded, given room and kept on its own.
    #[test]
    fn a_long_box_gets_finer_texels_along_its_short_side_each_side_kept_on_its_own() {
        let fresh = fit_to_box(10.0, 4.0, None);
        for (got, side) in [(fresh.x, 10.0), (fresh.y, 4.0)] {
            let roomy = need(side) * Hold::SAMPLES.headroom;
            assert!(got >= roomy && got < roomy * 1.0906, "{got} vs {roomy}");
        }
        assert!(fresh.y < 0.5 * fresh.x, "{fresh}");
        // The box grows 10 % along x and shrinks to half along y: x kept,
        // y fitted afresh (the kept one would be over √2 what it needs).
        let next = fit_to_box(11.0, 2.0, Some(fresh));
        assert_eq!(next.x, fresh.x);
        assert!(next.y <= 0.5 * fresh.y * 1.001, "{next}");
    }

    #[test]
    fn a_stabilised_map_keeps_its_window_while_it_fits_and_is_not_too_large() {
        let stable = Some(2048);
        let first = fit(0.0, stable, None);
        // A previous window too large: a fresh fit.
        assert_eq!(fit(0.0, stable, Some(Vec2::splat(f32::MAX))), first);
        // A fresh fit is the needed window, each side rounded up to an
        // eighth octave; the camera's view from above is longer than wide.
        let needed = fit(0.0, None, None);
        assert!(needed.x != needed.y, "{needed}");
        assert!(
            first.cmpge(needed).all() && first.cmplt(needed * 1.0906).all(),
            "{first} vs {needed}"
        );
        // Kept: up to a quarter octave above what the view needs.
        let kept = needed * 1.15;
        assert_eq!(fit(0.0, stable, Some(kept)), kept);
        // Not kept: too small to hold the view, or more than a quarter
        // octave larger (on one side: that side fitted afresh).
        assert_eq!(fit(0.0, stable, Some(needed * 0.99)), first);
        assert_eq!(fit(0.0, stable, Some(needed * 1.25)), first);
        let one_side = Vec2::new(kept.x, needed.y * 1.25);
        assert_eq!(fit(0.0, stable, Some(one_side)), Vec2::new(kept.x, first.y));
        // A dolly towards the floor's far edge shrinks the needed window:
        // at the first step where a fresh fit rounds to another size, the
        // previous window still holds the view and is kept.
        let z = (1..400)
            .map(|k| -0.25 * k as f32)
            .find(|&z| fit(z, stable, None) != first)
            .expect("the dolly crosses a rounding step");
        assert!(fit(z, None, None).cmple(first).all());
        assert_eq!(fit(z, stable, Some(first)), first);
    }
}
