//! The room's procedural textures: brick and tile patterns with their
//! height fields, and normal maps derived from those heights.

use crate::scene::{Scene, Texture};
use glam::Vec3;

/// A brick pattern (colour) and its height field, `size × size`.
pub(super) fn bricks(size: u32) -> (image::RgbaImage, image::GrayImage) {
    let (bw, bh, mortar) = (size / 4, size / 8, (size / 64).max(1));
    let colour = image::RgbaImage::from_fn(size, size, |x, y| {
        let row = y / bh;
        let xs = x + if row % 2 == 1 { bw / 2 } else { 0 };
        let (bx, by) = (xs % bw, y % bh);
        if bx < mortar || by < mortar {
            image::Rgba([200, 195, 185, 255])
        } else {
            let k = ((xs / bw * 37 + row * 17) % 5) as u8 * 8;
            image::Rgba([150 + k, 70 + k / 2, 50, 255])
        }
    });
    let height = image::GrayImage::from_fn(size, size, |x, y| {
        let row = y / bh;
        let xs = x + if row % 2 == 1 { bw / 2 } else { 0 };
        image::Luma([if xs % bw < mortar || y % bh < mortar {
            0
        } else {
            255
        }])
    });
    (colour, height)
}

/// Square tiles with bevelled grout (colour and height).
pub(super) fn tiles(size: u32) -> (image::RgbaImage, image::GrayImage) {
    let tile = size / 4;
    let grout = (size / 48).max(1);
    let h = |x: u32, y: u32| -> u8 {
        let (tx, ty) = (x % tile, y % tile);
        let d = tx.min(ty).min(tile - 1 - tx).min(tile - 1 - ty);
        if d < grout {
            0
        } else {
            (((d - grout) * 64).min(255)) as u8
        }
    };
    let colour = image::RgbaImage::from_fn(size, size, |x, y| {
        if h(x, y) == 0 {
            image::Rgba([90, 90, 95, 255])
        } else if (x / tile + y / tile).is_multiple_of(2) {
            image::Rgba([205, 200, 185, 255])
        } else {
            image::Rgba([120, 140, 165, 255])
        }
    });
    (
        colour,
        image::GrayImage::from_fn(size, size, |x, y| image::Luma([h(x, y)])),
    )
}

/// Tangent-space normal map from a height map by central differences
/// (bump mapping, [004]): `n = normalize(−s·∂h/∂x, −s·∂h/∂y, 1)`.
fn normal_map_from_height(h: &image::GrayImage, strength: f32) -> image::RgbaImage {
    let (w, ht) = h.dimensions();
    let at = |x: i64, y: i64| {
        h.get_pixel(
            x.rem_euclid(w as i64) as u32,
            y.rem_euclid(ht as i64) as u32,
        )[0] as f32
            / 255.0
    };
    image::RgbaImage::from_fn(w, ht, |x, y| {
        let (x, y) = (x as i64, y as i64);
        let dx = (at(x + 1, y) - at(x - 1, y)) * 0.5;
        // Image rows go down while v goes up in the tangent frame.
        let dy = (at(x, y - 1) - at(x, y + 1)) * 0.5;
        let n = Vec3::new(-strength * dx, -strength * dy, 1.0).normalize();
        let e = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
        image::Rgba([e(n.x), e(n.y), e(n.z), 255])
    })
}

pub(super) fn add_textures(
    scene: &mut Scene,
    name: &str,
    (colour, height): (image::RgbaImage, image::GrayImage),
) -> (usize, usize) {
    scene.textures.push(Texture {
        name: format!("{name}_color"),
        image: colour,
        srgb: true,
        source: None,
        wrap: Default::default(),
    });
    scene.textures.push(Texture {
        name: format!("{name}_normal"),
        image: normal_map_from_height(&height, 6.0),
        srgb: false,
        source: None,
        wrap: Default::default(),
    });
    (scene.textures.len() - 2, scene.textures.len() - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_map_of_a_ramp_tilts_against_the_slope() {
        let h = image::GrayImage::from_fn(8, 8, |x, _| image::Luma([(x * 30) as u8]));
        let n = normal_map_from_height(&h, 4.0);
        let p = n.get_pixel(4, 4);
        // Height rises along +x, so the normal leans towards −x.
        assert!(p[0] < 128 && p[2] > 128, "{p:?}");
        assert!((p[1] as i32 - 128).abs() <= 1);
    }
}
