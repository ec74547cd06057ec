//! The levels of a virtual map and the pages they are cut into. A
//! directional light gets a clipmap: one orthographic view over the scene's
//! light-space square, level l a window of `size`² texels whose side doubles
//! per level, centred on the camera and snapped to whole pages, so that a
//! page always covers the same part of the world (what lets it be cached);
//! the coarsest window covers the whole square. A spot light gets one
//! perspective view, a point light six cube faces, each a mip chain: level l
//! covers the whole view with `size`/2^l texels, down to one page.

use super::atlas::GUARD_TEXELS;
use crate::scene::{Aabb, Camera, Light, LightType};
use crate::technique::shadow_map::gpu::pipelines::{MapProjection, MapShape};
use crate::technique::shadow_map::projection::{FrustumParams, setup};
use glam::{DMat4, IVec2, Mat4, Vec2, Vec3};

/// One level: a window of `pages`² pages over its view's uv square.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Level {
    pub view: u32,
    /// uv of the window's first texel corner.
    pub origin: Vec2,
    /// Clipmaps: the camera's texel coordinates in the window.
    pub eye_texel: Vec2,
    /// uv per texel.
    pub texel: f32,
    /// Absolute index of the window's first page (pages of a level are
    /// numbered from uv 0 of the view).
    pub origin_page: IVec2,
    pub pages: u32,
    /// First page-table entry.
    pub table: u32,
    /// World size of a texel (orthographic) or of one at unit distance.
    pub texel_world: f32,
    /// The next coarser level of the same view (itself for the coarsest).
    pub parent: u32,
}

/// A page by its level and absolute page indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PageKey {
    pub level: u32,
    pub x: i32,
    pub y: i32,
}

/// What a virtual map is cut into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VirtualParams {
    /// Texels per side of a level's window (clipmap) or of level 0 (mips).
    pub size: u32,
    /// Texels per page side.
    pub page: u32,
    /// Clipmap levels of a directional light.
    pub clipmap_levels: u32,
}

/// One light's virtual views and levels for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct VirtualLayout {
    /// World → clip of each view.
    pub views: Vec<DMat4>,
    /// The point the GPU's matrices take positions relative to (the
    /// frame's camera: fine levels need the precision).
    pub eye: Vec3,
    /// Clipmaps: the world directions of the view's u and v axes.
    pub axis_u: Vec3,
    pub axis_v: Vec3,
    pub levels: Vec<Level>,
    pub view_levels: u32,
    pub orthographic: bool,
    pub near: f32,
    pub far: f32,
    pub page: u32,
    /// Page-table entries over all levels.
    pub table_len: u32,
}

impl VirtualLayout {
    /// The layout for `light`, its clipmap centred on `fit_camera`, its
    /// matrices relative to `eye`.
    pub fn new(
        light: &Light,
        scene_bounds: &Aabb,
        fit_camera: &Camera,
        eye: Vec3,
        fp: &FrustumParams,
        p: VirtualParams,
    ) -> VirtualLayout {
        let pages = p.size / p.page;
        if light.kind == LightType::Directional {
            return Self::clipmap(light.direction, scene_bounds, fit_camera.eye, eye, p);
        }
        let camera = fit_camera;
        // Spot and point lights: the shadow map's own views, as mip chains.
        let setup = setup::light_setup(light, scene_bounds, camera, 1.0, fp);
        let view_levels = pages.trailing_zeros() + 1;
        let mut levels = vec![];
        let mut table = 0;
        for view in 0..setup.faces.len() as u32 {
            for mip in 0..view_levels {
                let texel = (1u32 << mip) as f32 / p.size as f32;
                let side = pages >> mip;
                let index = view * view_levels + mip;
                levels.push(Level {
                    view,
                    origin: Vec2::ZERO,
                    eye_texel: Vec2::ZERO,
                    texel,
                    origin_page: IVec2::ZERO,
                    pages: side,
                    table,
                    texel_world: setup.texel_scale * texel,
                    parent: if mip + 1 < view_levels {
                        index + 1
                    } else {
                        index
                    },
                });
                table += side * side;
            }
        }
        VirtualLayout {
            views: setup.faces.iter().map(|f| f.as_dmat4()).collect(),
            eye,
            axis_u: Vec3::ZERO,
            axis_v: Vec3::ZERO,
            levels,
            view_levels,
            orthographic: false,
            near: setup.near,
            far: setup.far,
            page: p.page,
            table_len: table,
        }
    }

    /// A directional light's clipmap around the camera at `centre_eye`.
    fn clipmap(
        dir: Vec3,
        scene_bounds: &Aabb,
        centre_eye: Vec3,
        eye: Vec3,
        p: VirtualParams,
    ) -> VirtualLayout {
        let (view, scene_ls) = setup::light_view_of_scene(dir, scene_bounds);
        let (centre, size) = (scene_ls.center(), scene_ls.max - scene_ls.min);
        let pad = scene_ls.margin();
        let half = 0.5 * size.x.max(size.y) as f64 + pad as f64;
        let (near, far) = (-scene_ls.max.z - pad, -scene_ls.min.z + pad);
        let (cx, cy) = (centre.x as f64, centre.y as f64);
        let proj = glam::dcamera::rh::proj::directx::orthographic(
            cx - half,
            cx + half,
            cy - half,
            cy + half,
            near as f64,
            far as f64,
        );
        let view_proj = proj * view.as_dmat4();
        let pages = p.size / p.page;
        let n = p.clipmap_levels;
        let uv_of = |w: Vec3| {
            let c = view_proj.project_point3(w.as_dvec3());
            glam::DVec2::new(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5)
        };
        // The window centre in the view's uv, kept inside the square so
        // that the coarsest window (two squares wide) covers all of it.
        let margin = 1.0 / 32.0;
        let centre_uv =
            uv_of(centre_eye).clamp(glam::DVec2::splat(margin), glam::DVec2::splat(1.0 - margin));
        let eye_uv = uv_of(eye);
        let levels = (0..n)
            .map(|l| {
                let texel = 2.0 * 2f64.powi(l as i32 + 1 - n as i32) / p.size as f64;
                let page_uv = texel * p.page as f64;
                let origin_page = ((centre_uv - glam::DVec2::splat(0.5 * texel * p.size as f64))
                    / page_uv)
                    .floor();
                let origin = origin_page * page_uv;
                Level {
                    view: 0,
                    origin: origin.as_vec2(),
                    eye_texel: ((eye_uv - origin) / texel).as_vec2(),
                    texel: texel as f32,
                    origin_page: origin_page.as_ivec2(),
                    pages,
                    table: l * pages * pages,
                    texel_world: (texel * 2.0 * half) as f32,
                    parent: (l + 1).min(n - 1),
                }
            })
            .collect();
        // uv grows along the view's x and against its y (rows go down).
        let inverse = view.inverse();
        VirtualLayout {
            views: vec![view_proj],
            eye,
            axis_u: inverse.transform_vector3(Vec3::X),
            axis_v: -inverse.transform_vector3(Vec3::Y),
            levels,
            view_levels: n,
            orthographic: true,
            near,
            far,
            page: p.page,
            table_len: n * pages * pages,
        }
    }

    /// The shape of the views, as the shaders' constants: a clipmap is
    /// orthographic, a point light's six views a cube; never cascaded or
    /// warped.
    pub fn shape(&self) -> MapShape {
        MapShape {
            // A point light's pages are its six cube faces' (never paraboloid).
            projection: if self.orthographic {
                MapProjection::Orthographic
            } else if self.views.len() == 6 {
                MapProjection::Cube
            } else {
                MapProjection::Perspective
            },
            cascaded: false,
            warped: false,
        }
    }

    /// World (relative to [`Self::eye`]) → clip of view `i`.
    pub fn view_relative(&self, i: usize) -> Mat4 {
        (self.views[i] * DMat4::from_translation(self.eye.as_dvec3())).as_mat4()
    }

    /// The page one level coarser that covers `key`'s page.
    pub fn parent(&self, key: PageKey) -> Option<PageKey> {
        let parent = self.levels[key.level as usize].parent;
        (parent != key.level).then_some(PageKey {
            level: parent,
            x: key.x.div_euclid(2),
            y: key.y.div_euclid(2),
        })
    }

    /// The page-table entry of `key` when its level's window holds it.
    pub fn entry(&self, key: PageKey) -> Option<u32> {
        let l = &self.levels[key.level as usize];
        let g = l.pages as i32;
        let rel = IVec2::new(key.x, key.y) - l.origin_page;
        if rel.cmplt(IVec2::ZERO).any() || rel.cmpge(IVec2::splat(g)).any() {
            return None;
        }
        let w = IVec2::new(key.x.rem_euclid(g), key.y.rem_euclid(g));
        Some(l.table + (w.y * g + w.x) as u32)
    }

    /// The page of a page-table entry (the inverse of [`Self::entry`]).
    pub fn key_of_entry(&self, entry: u32) -> PageKey {
        let level = self
            .levels
            .partition_point(|l| l.table <= entry)
            .saturating_sub(1);
        let l = &self.levels[level];
        let g = l.pages as i32;
        let i = (entry - l.table) as i32;
        let (wx, wy) = (i % g, i / g);
        // The absolute index in the window that wraps to (wx, wy).
        let unwrap = |w: i32, o: i32| o + (w - o).rem_euclid(g);
        PageKey {
            level: level as u32,
            x: unwrap(wx, l.origin_page.x),
            y: unwrap(wy, l.origin_page.y),
        }
    }

    /// World (relative to [`Self::eye`]) → clip of a page's pool slot: its
    /// level's view with the uv square of the page and its guard texels
    /// stretched over the whole clip square (what renders it into its
    /// slot), composed in double precision.
    pub fn page_view_proj(&self, key: PageKey) -> Mat4 {
        let l = &self.levels[key.level as usize];
        let page_uv = l.texel as f64 * self.page as f64;
        let slot_uv = l.texel as f64 * (self.page + GUARD_TEXELS) as f64;
        let (u0, v0) = (key.x as f64 * page_uv, key.y as f64 * page_uv);
        // uv → NDC: x = 2u − 1, y = 1 − 2v.
        let cx = 2.0 * (u0 + 0.5 * slot_uv) - 1.0;
        let cy = 1.0 - 2.0 * (v0 + 0.5 * slot_uv);
        let s = 1.0 / slot_uv;
        let stretch = DMat4::from_cols_array(&[
            s,
            0.0,
            0.0,
            0.0, //
            0.0,
            s,
            0.0,
            0.0, //
            0.0,
            0.0,
            1.0,
            0.0, //
            -s * cx,
            -s * cy,
            0.0,
            1.0,
        ]);
        let relative = DMat4::from_translation(self.eye.as_dvec3());
        (stretch * self.views[l.view as usize] * relative).as_mat4()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn params() -> VirtualParams {
        VirtualParams {
            size: 1024,
            page: 128,
            clipmap_levels: 4,
        }
    }

    fn sun_over_box() -> (Light, Aabb, Camera) {
        let light = Light::directional(Vec3::new(0.0, -1.0, 0.0), 1.0);
        let bounds = Aabb {
            min: Vec3::new(-8.0, 0.0, -8.0),
            max: Vec3::new(8.0, 2.0, 8.0),
        };
        let camera = Camera::new(Vec3::new(1.0, 5.0, 2.0), Vec3::new(0.0, 0.0, -3.0));
        (light, bounds, camera)
    }

    fn layout_of(light: &Light, bounds: &Aabb, camera: &Camera) -> VirtualLayout {
        VirtualLayout::new(
            light,
            bounds,
            camera,
            camera.eye,
            &FrustumParams::default(),
            params(),
        )
    }

    #[test]
    fn clipmap_windows_double_and_cover_the_scene_at_the_coarsest_level() {
        let (light, bounds, camera) = sun_over_box();
        let l = layout_of(&light, &bounds, &camera);
        assert_eq!(l.levels.len(), 4);
        for w in l.levels.windows(2) {
            assert!((w[1].texel / w[0].texel - 2.0).abs() < 1e-6);
            assert!((w[1].texel_world / w[0].texel_world - 2.0).abs() < 1e-5);
        }
        // The scene's square is 16 + 2 mm wide; the coarsest window two squares.
        let top = l.levels[3];
        assert!((top.texel * 1024.0 - 2.0).abs() < 1e-6);
        assert!(top.origin.cmple(Vec2::ZERO).all());
        assert!((top.origin + Vec2::splat(2.0)).cmpge(Vec2::ONE).all());
        // Windows start on whole pages and hold the camera.
        let cam = l.views[0].project_point3(camera.eye.as_dvec3()).as_vec3();
        let cam = Vec2::new(cam.x * 0.5 + 0.5, 0.5 - cam.y * 0.5);
        for lv in &l.levels {
            let page_uv = lv.texel * 128.0;
            assert_eq!(lv.origin, lv.origin_page.as_vec2() * page_uv);
            let rel = (cam - lv.origin) / (lv.texel * 1024.0);
            assert!(
                rel.cmpgt(Vec2::splat(0.4)).all() && rel.cmplt(Vec2::splat(0.6)).all(),
                "{rel}"
            );
            assert!((lv.eye_texel / 1024.0 - rel).length() < 1e-4);
        }
    }

    #[test]
    fn a_page_matrix_maps_the_page_onto_the_clip_square() {
        let (light, bounds, camera) = sun_over_box();
        let l = layout_of(&light, &bounds, &camera);
        let lv = l.levels[1];
        let key = PageKey {
            level: 1,
            x: lv.origin_page.x + 3,
            y: lv.origin_page.y + 5,
        };
        let page_uv = lv.texel as f64 * 128.0;
        let slot_uv = lv.texel as f64 * (128 + GUARD_TEXELS) as f64;
        let world_at = |u: f64, v: f64| {
            let ndc = DVec3::new(2.0 * u - 1.0, 1.0 - 2.0 * v, 0.5);
            l.views[0].inverse().project_point3(ndc).as_vec3()
        };
        let page = l.page_view_proj(key);
        let clip = |w: Vec3| page.project_point3(w - l.eye);
        // The centre of the slot (the page and its guard texels) goes to the
        // clip centre, the page's first texel corner to (−1, 1).
        let c = clip(world_at(
            key.x as f64 * page_uv + 0.5 * slot_uv,
            key.y as f64 * page_uv + 0.5 * slot_uv,
        ));
        assert!(c.truncate().length() < 1e-3, "{c}");
        let c = clip(world_at(key.x as f64 * page_uv, key.y as f64 * page_uv));
        assert!(
            (c.truncate() - glam::Vec2::new(-1.0, 1.0)).length() < 1e-3,
            "{c}"
        );
        // The clipmap's texel formula agrees: that corner is texel 128·(3, 5).
        let d = world_at(key.x as f64 * page_uv, key.y as f64 * page_uv) - l.eye;
        let t = Vec2::new(l.axis_u.dot(d), l.axis_v.dot(d)) / lv.texel_world + lv.eye_texel;
        assert!((t - Vec2::new(384.0, 640.0)).length() < 1e-2, "{t}");
    }

    #[test]
    fn entries_wrap_and_invert_and_parents_halve() {
        let (light, bounds, camera) = sun_over_box();
        let l = layout_of(&light, &bounds, &camera);
        let o = l.levels[2].origin_page;
        for (dx, dy) in [(0, 0), (7, 0), (3, 6), (7, 7)] {
            let key = PageKey {
                level: 2,
                x: o.x + dx,
                y: o.y + dy,
            };
            let e = l.entry(key).unwrap();
            assert!(e >= l.levels[2].table && e < l.levels[2].table + 64);
            assert_eq!(l.key_of_entry(e), key);
        }
        assert_eq!(
            l.entry(PageKey {
                level: 2,
                x: o.x + 8,
                y: o.y
            }),
            None
        );
        assert_eq!(
            l.entry(PageKey {
                level: 2,
                x: o.x - 1,
                y: o.y
            }),
            None
        );
        let p = l
            .parent(PageKey {
                level: 0,
                x: -3,
                y: 5,
            })
            .unwrap();
        assert_eq!(
            p,
            PageKey {
                level: 1,
                x: -2,
                y: 2
            }
        );
        assert_eq!(
            l.parent(PageKey {
                level: 3,
                x: 0,
                y: 0
            }),
            None
        );
    }

    #[test]
    fn local_lights_get_mip_chains_per_view() {
        let (_, bounds, camera) = sun_over_box();
        let point = Light::point(Vec3::new(0.0, 4.0, 0.0), 1.0);
        let l = layout_of(&point, &bounds, &camera);
        // 1024 / 128 = 8 pages: mips of 8, 4, 2, 1 pages per side, per cube face.
        assert_eq!(l.view_levels, 4);
        assert_eq!(l.levels.len(), 24);
        assert_eq!(l.table_len, 6 * (64 + 16 + 4 + 1));
        assert_eq!(l.levels[5].view, 1);
        assert_eq!(l.levels[5].pages, 4);
        assert_eq!(l.levels[3].parent, 3);
        assert_eq!(l.levels[4].parent, 5);
        // A 90° face is 2 units wide at unit distance.
        assert!((l.levels[0].texel_world - 2.0 / 1024.0).abs() < 1e-7);
    }
}
