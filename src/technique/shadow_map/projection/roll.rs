//! The turn of a directional light's single map about the light's
//! direction (`roll=square`). An orthographic map is a square in the
//! light's image; which way that square is turned is free, and the fixed
//! choice — the world's up along the map's y axis — costs twice:
//!
//! - what the camera sees, seen from the light, is rarely an upright
//!   rectangle, and its upright bounding square can hold up to twice its
//!   area (a square turned 45°) — texels spent on nothing;
//! - every vertical edge of the world (walls, columns, trunks) then lies
//!   along a texel column, so its rasterised silhouette is a straight texel
//!   boundary whose sub-texel place no filter recovers (up to ½ texel of
//!   error along its whole length), where a slanted edge's staircase is
//!   averaged back onto the edge by the kernel.
//!
//! The same holds, less strongly, for edges along the world's horizontal
//! axes (the commonest in built scenes). So the map takes, of the turns by
//! multiples of 180°/[`DIRECTIONS`], the one with the smallest square
//! around what it must cover, among those that keep the world's vertical at
//! least [`VERTICAL_CLEARANCE_DEG`] and its x and z axes at least
//! [`HORIZONTAL_CLEARANCE_DEG`] off the texel axes (where none does, the
//! one that comes nearest); last frame's turn is kept while its square is at most
//! [`KEPT_ROLL_RATIO`] larger, so the texel grid does not spin with the
//! camera. (The map then covers that turn's box, not its square:
//! `setup::directional_setup`.) What it must cover is given as its extents along
//! [`DIRECTIONS`] directions of the light's image ([`Supports`]): from the
//! pixels the camera saw (SDSM's reduction, `depth_bounds.wgsl`), or from
//! the corners of the camera's view of the scene.

use glam::{Mat4, Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, PI};

/// Directions of the light's image the extents are taken along: k·180°/16
/// (`depth_bounds.wgsl`'s `SUPPORT_COS`/`SUPPORT_SIN`). A turn by j·11.25°
/// (j < 8) has its x axis along direction j and its y axis along j + 8.
pub const DIRECTIONS: usize = 16;

/// The turns tried: a quarter turn (the square's symmetry) in 11.25° steps.
pub const TURNS: usize = DIRECTIONS / 2;

/// Least angle between the world's vertical, seen from the light, and
/// either texel axis: vertical edges along a texel column are staircases
/// no filter smooths (the guide's shadow-map chapter has the sweep).
pub const VERTICAL_CLEARANCE_DEG: f32 = 15.0;

/// Least angle between the world's x or z axis, seen from the light, and
/// either texel axis: less than the vertical's, since horizontal edges
/// seen from a high light are shorter in the map.
pub const HORIZONTAL_CLEARANCE_DEG: f32 = 8.0;

/// Last frame's turn is kept while its square is at most this much larger
/// than the best turn's: an eighth of an octave, the step of a stabilised
/// map's size.
pub const KEPT_ROLL_RATIO: f32 = 1.090_507_7;

/// The angle of turn `j` (radians).
pub fn turn_angle(j: usize) -> f32 {
    j as f32 * PI / DIRECTIONS as f32
}

/// `view` (world → light view) turned by `roll` radians about the light's
/// direction: the turned x axis is (cos, sin) of the old image plane.
pub fn rolled(view: Mat4, roll: f32) -> Mat4 {
    Mat4::from_rotation_z(-roll) * view
}

/// A direction of the light's image that texel axes should keep clear of:
/// its angle and the clearance (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisClearance {
    pub angle: f32,
    pub clearance: f32,
}

/// The world's axes as seen in the image of the orthographic light view
/// `view`, with their clearances; an axis seen shorter than sin 10°
/// (within 10° of the light's direction, its edges shrink to points) is
/// left out.
pub fn world_axes_in_image(view: Mat4) -> Vec<AxisClearance> {
    axes_seen(view, |v| v.truncate())
}

/// The same for a perspective view (a spot light's), whose image is
/// (x/−z, y/−z): a line along view-space direction v through the point
/// seen at `at` runs along v.xy + at·v.z there (the derivative of the
/// projection), so the world's axes turn across the image, and are taken
/// where the map is centred.
pub fn world_axes_in_perspective_image(view: Mat4, at: Vec2) -> Vec<AxisClearance> {
    axes_seen(view, |v| {
        (v.truncate() + at * v.z) / (1.0 + at.length_squared()).sqrt()
    })
}

/// The world's axes whose image direction (`image` of the view-space
/// axis) is at least sin 10° long.
fn axes_seen(view: Mat4, image: impl Fn(Vec3) -> Vec2) -> Vec<AxisClearance> {
    [
        (Vec3::Y, VERTICAL_CLEARANCE_DEG),
        (Vec3::X, HORIZONTAL_CLEARANCE_DEG),
        (Vec3::Z, HORIZONTAL_CLEARANCE_DEG),
    ]
    .into_iter()
    .filter_map(|(axis, clearance)| {
        let v = image(view.transform_vector3(axis));
        (v.length() >= 10f32.to_radians().sin()).then(|| AxisClearance {
            angle: v.to_angle(),
            clearance: clearance.to_radians(),
        })
    })
    .collect()
}

/// How far texel axes turned by `roll` fall short of the clearances of
/// `axes` (radians; ≤ 0 where they keep every one).
fn shortfall(roll: f32, axes: &[AxisClearance]) -> f32 {
    axes.iter()
        .map(|a| {
            let off = (a.angle - roll).rem_euclid(FRAC_PI_2);
            a.clearance - off.min(FRAC_PI_2 - off)
        })
        .fold(f32::MIN, f32::max)
}

/// A set's extents `[least, greatest]` along each of the [`DIRECTIONS`]
/// directions k·180°/16 of an (unturned) light view's image: its support
/// function there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supports(pub [[f32; 2]; DIRECTIONS]);

impl Supports {
    /// The extents of `points` (light-view x, y); `None` when there are none.
    pub fn of_points(points: impl IntoIterator<Item = Vec2>) -> Option<Supports> {
        let directions: [Vec2; DIRECTIONS] =
            std::array::from_fn(|k| Vec2::from_angle(turn_angle(k)));
        let mut along = [[f32::MAX, f32::MIN]; DIRECTIONS];
        let mut any = false;
        for p in points {
            any = true;
            for ([lo, hi], direction) in along.iter_mut().zip(directions) {
                let d = p.dot(direction);
                *lo = lo.min(d);
                *hi = hi.max(d);
            }
        }
        any.then_some(Supports(along))
    }

    /// Each extent grown by `fraction` of its half-width on both sides.
    pub fn widened(&self, fraction: f32) -> Supports {
        Supports(self.0.map(|[lo, hi]| {
            let m = (hi - lo) * 0.5 * fraction;
            [lo - m, hi + m]
        }))
    }

    /// Each extent grown by `margin` on both sides.
    pub fn grown(&self, margin: f32) -> Supports {
        Supports(self.0.map(|[lo, hi]| [lo - margin, hi + margin]))
    }

    /// Whether the two sets' extents overlap along every direction (their
    /// 16-sided outer polygons meet).
    pub fn overlaps(&self, other: &Supports) -> bool {
        self.0
            .iter()
            .zip(&other.0)
            .all(|([lo, hi], [other_lo, other_hi])| lo <= other_hi && other_lo <= hi)
    }

    /// The box `[min x, min y, max x, max y]` in the view turned by turn `j`.
    pub fn box_at(&self, j: usize) -> [f32; 4] {
        let ([x0, x1], [y0, y1]) = (self.0[j], self.0[j + TURNS]);
        [x0, y0, x1, y1]
    }

    /// The side of the square around the box of turn `j`.
    fn square_side(&self, j: usize) -> f32 {
        let [x0, y0, x1, y1] = self.box_at(j);
        (x1 - x0).max(y1 - y0)
    }

    /// The turn (index, < [`TURNS`]) with the smallest square among those
    /// whose texel axes keep clear of `axes` (or, where none does, the
    /// nearest to doing so), or `previous` while it is one of those and its
    /// square is at most [`KEPT_ROLL_RATIO`] larger.
    pub fn fitted_turn(&self, axes: &[AxisClearance], previous: Option<usize>) -> usize {
        const ROUNDING: f32 = 1e-4;
        let least = (0..TURNS)
            .map(|j| shortfall(turn_angle(j), axes))
            .fold(f32::MAX, f32::min)
            .max(0.0);
        let clear = |j: usize| shortfall(turn_angle(j), axes) <= least + ROUNDING;
        let best = (0..TURNS)
            .filter(|&j| clear(j))
            .min_by(|&a, &b| self.square_side(a).total_cmp(&self.square_side(b)))
            .unwrap_or(0);
        match previous {
            Some(p)
                if p < TURNS
                    && clear(p)
                    && self.square_side(p) <= self.square_side(best) * KEPT_ROLL_RATIO =>
            {
                p
            }
            _ => best,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 × 2 rectangle turned by `turn` degrees about the origin.
    fn rectangle(turn: f32) -> Supports {
        let r = Vec2::from_angle(turn.to_radians());
        Supports::of_points(
            [(-5.0, -1.0), (5.0, -1.0), (5.0, 1.0), (-5.0, 1.0)]
                .map(|(x, y)| r.rotate(Vec2::new(x, y))),
        )
        .unwrap()
    }

    #[test]
    fn extents_along_the_turned_axes_are_the_turned_box() {
        // A rectangle turned 22.5° is upright in the view turned 22.5°.
        let s = rectangle(22.5);
        let [x0, y0, x1, y1] = s.box_at(2);
        for (got, want) in [(x0, -5.0), (y0, -1.0), (x1, 5.0), (y1, 1.0)] {
            assert!((got - want).abs() < 1e-5, "{:?}", s.box_at(2));
        }
        // Upright: half-widths 5 cos 22.5° + 1 sin 22.5° and 5 sin + 1 cos.
        let (c, n) = (22.5f32.to_radians().cos(), 22.5f32.to_radians().sin());
        assert!((s.box_at(0)[2] - (5.0 * c + n)).abs() < 1e-5);
        assert!((s.box_at(0)[3] - (5.0 * n + c)).abs() < 1e-5);
    }

    #[test]
    fn a_diamond_gets_the_map_turned_45_degrees() {
        let diamond = Supports::of_points(
            [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)].map(|(x, y)| Vec2::new(x, y)),
        )
        .unwrap();
        // Upright its square has side 2; turned 45°, √2.
        assert!((diamond.square_side(0) - 2.0).abs() < 1e-6);
        let j = diamond.fitted_turn(&[], None);
        assert_eq!(j, 4);
        assert!((diamond.square_side(j) - 2f32.sqrt()).abs() < 1e-5);
    }

    #[test]
    fn a_long_strip_is_held_along_the_square_diagonal() {
        // A 10 × 2 strip along x: upright needs side 10; along the
        // diagonal (10 + 2)/√2 ≈ 8.49.
        let strip = rectangle(0.0);
        let j = strip.fitted_turn(&[], None);
        assert_eq!(j, 4);
        assert!((strip.square_side(j) - 12.0 / 2f32.sqrt()).abs() < 1e-4);
    }

    #[test]
    fn turns_near_the_vertical_are_skipped() {
        // A square is tightest upright, on the vertical (the image's y
        // axis here); the nearest turns 15° or more off it are 22.5° and
        // 67.5°, equally tight.
        let square = Supports::of_points(
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec2::new(x, y)),
        )
        .unwrap();
        assert_eq!(square.fitted_turn(&[], None), 0);
        let up = AxisClearance {
            angle: FRAC_PI_2,
            clearance: VERTICAL_CLEARANCE_DEG.to_radians(),
        };
        let j = square.fitted_turn(&[up], None);
        assert!(j == 2 || j == 6, "{j}");
        // With horizontal axes at 30° and 60° too (8° clear: 22°–38° and
        // 52°–68° ruled out), only 45° is left.
        let horizontal = |deg: f32| AxisClearance {
            angle: deg.to_radians(),
            clearance: HORIZONTAL_CLEARANCE_DEG.to_radians(),
        };
        assert_eq!(
            square.fitted_turn(&[up, horizontal(30.0), horizontal(60.0)], None),
            4
        );
        // Where no turn keeps every clearance, the nearest: axes every
        // 11.25° leave none; 5.6° off is the best any turn does.
        let crowded: Vec<AxisClearance> = (0..8)
            .map(|k| horizontal(5.625 + 11.25 * k as f32))
            .collect();
        // Every turn then misses by the same 2.4°: the tightest square
        // among them, upright.
        assert_eq!(square.fitted_turn(&crowded, None), 0);
    }

    #[test]
    fn last_frames_turn_is_kept_within_an_eighth_octave() {
        // A disc's square is the same at every turn: last frame's is kept.
        let disc = Supports::of_points((0..64).map(|i| Vec2::from_angle(i as f32 * 0.1))).unwrap();
        assert_eq!(disc.fitted_turn(&[], Some(3)), 3);
        // A strip upright needs side 10 against 8.49 at 45° (18 % more):
        // replaced; at 33.75° 9.43 (11 %): replaced too.
        let strip = rectangle(0.0);
        assert_eq!(strip.fitted_turn(&[], Some(0)), 4);
        assert_eq!(strip.fitted_turn(&[], Some(3)), 4);
        // A strip 3 wide: 33.75° costs 9.98 against 9.19 (8.6 %): kept.
        let wide = Supports::of_points(
            [(-5.0, -1.5), (5.0, -1.5), (5.0, 1.5), (-5.0, 1.5)].map(|(x, y)| Vec2::new(x, y)),
        )
        .unwrap();
        assert_eq!(wide.fitted_turn(&[], None), 4);
        assert_eq!(wide.fitted_turn(&[], Some(3)), 3);
    }

    #[test]
    fn world_axes_are_seen_only_when_not_along_the_light() {
        let view = |dir: Vec3, up: Vec3| glam::camera::rh::view::look_to_mat4(Vec3::ZERO, dir, up);
        let slanted = world_axes_in_image(view(Vec3::new(-0.5, -1.0, -0.35), Vec3::Y));
        assert_eq!(slanted.len(), 3);
        assert!((slanted[0].angle - FRAC_PI_2).abs() < 1e-5, "{slanted:?}");
        // Straight down: the vertical is a point, x and z are seen.
        let overhead = world_axes_in_image(view(Vec3::NEG_Y, Vec3::Z));
        assert_eq!(overhead.len(), 2);
        assert!(
            overhead
                .iter()
                .all(|a| a.clearance == HORIZONTAL_CLEARANCE_DEG.to_radians())
        );
    }

    #[test]
    fn a_turned_view_projects_onto_turned_axes() {
        let r = turn_angle(3);
        let p = rolled(Mat4::IDENTITY, r).transform_point3(Vec3::new(r.cos(), r.sin(), 0.0));
        assert!((p - Vec3::X).length() < 1e-6, "{p}");
    }
}
