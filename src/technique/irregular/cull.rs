//! Which casters can shadow what the camera sees: a caster shadows a
//! sample only on the sample's ray to the light, so it meets the convex
//! hull of the light (or, for a directional light, the view swept towards
//! it across the scene) and the camera's view up to the far side of the
//! scene — Bittner et al. 2011's shadow caster culling volume. Clusters of
//! caster triangles outside it are not dispatched.

use super::casters::CasterCluster;
use crate::scene::hull::ConvexHull;
use crate::scene::{Aabb, Camera, Light, LightType};

/// The volume every shadow ray of the camera's samples lies in, seen with
/// frame `aspect` and `height` pixels, in a scene bounded by `scene`.
pub fn shadowing_hull(
    camera: &Camera,
    aspect: f32,
    height: u32,
    scene: &Aabb,
    light: &Light,
) -> ConvexHull {
    // Every visible point lies on the scene's geometry, within this view
    // depth.
    let reach = camera.reach(scene).max(camera.near * 1.001);
    let view = camera.slice_corners(aspect, camera.near, reach);
    let mut points = view.to_vec();
    match light.kind {
        // A ray towards the sun leaves the scene within its diagonal.
        LightType::Directional => {
            let sweep = light.direction.normalize() * scene.size().length();
            points.extend(view.map(|p| p - sweep));
        }
        LightType::Point | LightType::Spot => points.push(light.position),
    }
    // A sample may lie off its pixel's ray by about a pixel's footprint at
    // the far end (sub-pixel samples on the pixel's plane, lifted origins).
    let pixel = 2.0 * (camera.fov_y_deg.to_radians() * 0.5).tan() / height.max(1) as f32;
    let slack = 2.0 * reach * pixel + scene.margin();
    ConvexHull::of_points(&points, slack)
}

/// The caster triangles a frame tests: per run of the list (the opaque
/// casters', then the see-through ones'), ranges of consecutive kept
/// triangles as (the run's thread that starts it, its first triangle).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KeptCasters {
    pub ranges: Vec<[u32; 2]>,
    /// How many of `ranges` belong to the opaque run (they lead).
    pub opaque_ranges: u32,
    /// The kept triangles of each run: its threads.
    pub opaque: u32,
    pub see_through: u32,
}

/// The clusters of `clusters` that `keep` accepts, as ranges of the caster
/// list (whose first `opaque` triangles are the opaque run), adjacent kept
/// clusters merged.
pub fn kept_casters(
    clusters: &[CasterCluster],
    opaque: u32,
    keep: impl Fn(&Aabb) -> bool,
) -> KeptCasters {
    let mut kept = KeptCasters::default();
    // The end of the last range, in the list.
    let mut end = u32::MAX;
    for c in clusters.iter().filter(|c| keep(&c.bounds)) {
        let see_through = c.first >= opaque;
        // Adjacent clusters merge, but not across the runs' meeting point.
        if c.first != end || c.first == opaque {
            let start = if see_through {
                kept.see_through
            } else {
                kept.opaque
            };
            kept.ranges.push([start, c.first]);
            kept.opaque_ranges += u32::from(!see_through);
        }
        if see_through {
            kept.see_through += c.count;
        } else {
            kept.opaque += c.count;
        }
        end = c.first + c.count;
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cluster(first: u32, count: u32, x: f32) -> CasterCluster {
        CasterCluster {
            first,
            count,
            bounds: Aabb {
                min: Vec3::new(x, 0.0, 0.0),
                max: Vec3::new(x + 1.0, 1.0, 1.0),
            },
        }
    }

    /// Kept clusters become ranges per run, adjacent ones merged but not
    /// across the opaque run's end; each range starts at the run's thread
    /// that follows the kept triangles before it.
    #[test]
    fn kept_clusters_become_ranges_per_run() {
        // Opaque: [0, 10) [10, 15) [15, 30); see-through: [30, 34) [34, 40).
        let clusters = [
            cluster(0, 10, 0.0),
            cluster(10, 5, 10.0),
            cluster(15, 15, 2.0),
            cluster(30, 4, 3.0),
            cluster(34, 6, 4.0),
        ];
        let kept = kept_casters(&clusters, 30, |b| b.min.x < 5.0);
        assert_eq!(kept.ranges, vec![[0, 0], [10, 15], [0, 30]]);
        assert_eq!(
            (kept.opaque_ranges, kept.opaque, kept.see_through),
            (2, 25, 10)
        );
        let all = kept_casters(&clusters, 30, |_| true);
        assert_eq!(all.ranges, vec![[0, 0], [0, 30]]);
        assert_eq!(
            (all.opaque_ranges, all.opaque, all.see_through),
            (1, 30, 10)
        );
        assert_eq!(
            kept_casters(&clusters, 30, |_| false),
            KeptCasters::default()
        );
    }

    /// A camera at the origin looking along −z over a 100 m box, a point
    /// light above the view: boxes behind the camera or beside the view are
    /// culled, one under the light and one in the view are kept; under a
    /// sun from +x, a box sunward of the view is kept and one on the far
    /// side is not.
    #[test]
    fn the_hull_keeps_casters_between_the_light_and_the_view() {
        let scene = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 20.0, 50.0),
        };
        let camera = Camera::new(Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 2.0, -10.0));
        let at = |x: f32, y: f32, z: f32| Aabb {
            min: Vec3::new(x - 0.5, y, z - 0.5),
            max: Vec3::new(x + 0.5, y + 1.0, z + 0.5),
        };
        let point = Light::point(Vec3::new(0.0, 15.0, -10.0), 1.0);
        let hull = shadowing_hull(&camera, 1.0, 100, &scene, &point);
        assert!(!hull.excludes(&at(0.0, 0.0, -20.0)), "in the view");
        assert!(!hull.excludes(&at(0.0, 12.0, -10.0)), "under the light");
        assert!(hull.excludes(&at(0.0, 0.0, 20.0)), "behind the camera");
        assert!(hull.excludes(&at(-40.0, 0.0, -5.0)), "beside the view");
        let sun = Light::directional(Vec3::new(-1.0, -1.0, 0.0), 1.0);
        let hull = shadowing_hull(&camera, 1.0, 100, &scene, &sun);
        assert!(
            !hull.excludes(&at(25.0, 12.0, -30.0)),
            "sunward of the view"
        );
        assert!(
            hull.excludes(&at(45.0, 10.0, -30.0)),
            "sunward, off every ray"
        );
        assert!(hull.excludes(&at(-45.0, 0.0, -5.0)), "away from the sun");
    }
}
