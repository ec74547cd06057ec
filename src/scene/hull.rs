//! The convex hull of a few points as its bounding planes, and whether a
//! box lies wholly outside it: the volume a caster must meet to shadow
//! what a camera sees (the hull of the light and the view, Bittner et al.
//! 2011's shadow caster culling).

use super::Aabb;
use glam::Vec3;

/// A convex solid as the planes that bound it: a point `p` lies inside
/// where `n · p ≤ d` for every plane `(n, d)` (`n` unit, pointing out).
#[derive(Clone, Debug, Default)]
pub struct ConvexHull {
    planes: Vec<(Vec3, f32)>,
}

impl ConvexHull {
    /// The hull of `points`, each plane pushed `slack` outwards. Every
    /// plane through three of the points that has all of them on one side
    /// is a face's (brute force: meant for tens of points). Points that
    /// span no volume (fewer than four, or all in one plane) give no
    /// planes: a hull that excludes nothing.
    pub fn of_points(points: &[Vec3], slack: f32) -> ConvexHull {
        let scale = points
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f32::max);
        let tolerance = scale * 1e-5;
        let mut planes: Vec<(Vec3, f32)> = vec![];
        for (i, &a) in points.iter().enumerate() {
            for (j, &b) in points.iter().enumerate().skip(i + 1) {
                for &c in &points[j + 1..] {
                    let n = (b - a).cross(c - a).normalize_or_zero();
                    if n == Vec3::ZERO {
                        continue;
                    }
                    let d = n.dot(a);
                    let (below, above) = points.iter().fold((false, false), |(lo, hi), p| {
                        let s = n.dot(*p) - d;
                        (lo || s < -tolerance, hi || s > tolerance)
                    });
                    let face = match (below, above) {
                        (true, false) => (n, d),
                        (false, true) => (-n, -d),
                        _ => continue,
                    };
                    let same = |(m, e): &(Vec3, f32)| {
                        m.dot(face.0) > 1.0 - 1e-6 && (e - face.1).abs() <= tolerance
                    };
                    if !planes.iter().any(same) {
                        planes.push(face);
                    }
                }
            }
        }
        if planes.len() < 4 {
            planes.clear();
        }
        ConvexHull {
            planes: planes.into_iter().map(|(n, d)| (n, d + slack)).collect(),
        }
    }

    /// Whether `bounds` lies wholly outside one of the hull's planes (then
    /// it misses the hull; a box that misses it only across an edge is
    /// kept: the test is conservative).
    pub fn excludes(&self, bounds: &Aabb) -> bool {
        self.planes.iter().any(|&(n, d)| {
            // The box's corner farthest inside the plane.
            let inner = Vec3::select(n.cmplt(Vec3::ZERO), bounds.max, bounds.min);
            n.dot(inner) > d
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    /// The hull of a unit cube's corners and an apex above it: boxes
    /// beside the cube or past the apex are outside, boxes inside or
    /// straddling a face are kept.
    #[test]
    fn a_box_outside_the_hull_is_excluded_and_one_meeting_it_is_kept() {
        let mut points: Vec<Vec3> = cube(Vec3::ZERO, Vec3::ONE).corners().to_vec();
        points.push(Vec3::new(0.5, 3.0, 0.5));
        let hull = ConvexHull::of_points(&points, 0.0);
        // 4 sides, the bottom and 4 faces of the roof.
        assert_eq!(hull.planes.len(), 9, "{:?}", hull.planes);
        let small = |c: Vec3| cube(c - Vec3::splat(0.1), c + Vec3::splat(0.1));
        assert!(!hull.excludes(&small(Vec3::splat(0.5))));
        assert!(!hull.excludes(&small(Vec3::new(0.5, 2.5, 0.5))));
        assert!(!hull.excludes(&small(Vec3::new(1.05, 0.5, 0.5))));
        assert!(hull.excludes(&small(Vec3::new(1.5, 0.5, 0.5))));
        assert!(hull.excludes(&small(Vec3::new(0.5, -0.5, 0.5))));
        assert!(hull.excludes(&small(Vec3::new(0.5, 4.0, 0.5))));
        // Just over the apex it misses the hull across edges only: kept.
        assert!(!hull.excludes(&small(Vec3::new(0.5, 3.3, 0.5))));
        // Beside the roof: inside the cube's side planes' extension but
        // outside a roof face.
        assert!(hull.excludes(&small(Vec3::new(0.9, 2.8, 0.9))));
        // Slack widens the hull.
        let wide = ConvexHull::of_points(&points, 0.5);
        assert!(!wide.excludes(&small(Vec3::new(1.5, 0.5, 0.5))));
        // Flat or too few points: nothing is excluded.
        let flat = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::ONE.with_y(0.0)];
        assert!(!ConvexHull::of_points(&flat, 0.0).excludes(&small(Vec3::splat(5.0))));
    }
}
