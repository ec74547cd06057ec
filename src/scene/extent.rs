//! The scene's extent as the light's views are fitted to it: its box, and
//! its drawn clusters' boxes, which a camera standing in the scene meets
//! far later than the one box around everything.

use super::Aabb;

/// The scene as the light's views are fitted to it: its bounds and the
/// world bounds of its drawn clusters.
#[derive(Clone, Copy, Debug)]
pub struct SceneExtent<'a> {
    pub bounds: &'a Aabb,
    pub parts: &'a [Aabb],
}

impl SceneExtent<'_> {
    /// A scene known only by its box: one cluster filling it.
    pub fn of_box(bounds: &Aabb) -> SceneExtent<'_> {
        SceneExtent {
            bounds,
            parts: std::slice::from_ref(bounds),
        }
    }
}
