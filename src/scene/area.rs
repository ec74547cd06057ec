//! Sampling lights with an area (the soft shadows of [001] §3, [002] §2): stratified
//! points of the unit square, mapped onto a disk or a rectangle. The ray
//! tracer's shadow rays and the shadow maps' sample lights share them.

use super::{Light, LightArea, LightType};
use glam::Vec3;

/// `n` stratified points in [−1,1]², one in each of n strata of equal area:
/// r = round(√n) rows, row j holding c_j = ⌊n/r⌋ or ⌈n/r⌉ cells and of
/// height c_j/n, so every cell (width 1/c_j) covers 1/n of the square and
/// no part of the square is left without samples when n is not a square
/// (n = k² gives the k×k grid). Row-major; each point is jittered inside its
/// cell by `jitter` in [0,1)².
pub fn stratified_square(n: usize, mut jitter: impl FnMut() -> (f32, f32)) -> Vec<(f32, f32)> {
    if n == 0 {
        return vec![];
    }
    let rows = ((n as f64).sqrt().round() as usize).max(1);
    let mut out = Vec::with_capacity(n);
    let mut start = 0;
    for j in 0..rows {
        let cols = n / rows + usize::from(j < n % rows);
        for i in 0..cols {
            let (jx, jy) = jitter();
            let x = 2.0 * (i as f32 + jx) / cols as f32 - 1.0;
            let y = if n.is_multiple_of(rows) {
                2.0 * (j as f32 + jy) / rows as f32 - 1.0
            } else {
                2.0 * (start as f32 + jy * cols as f32) / n as f32 - 1.0
            };
            out.push((x, y));
        }
        start += cols;
    }
    out
}

/// Shirley–Chiu concentric map of [−1,1]² onto the unit disk (keeps
/// stratification).
pub fn concentric_disk(a: f32, b: f32) -> (f32, f32) {
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * phi.cos(), r * phi.sin())
}

/// Point lights standing in for an area light: `n` stratified points of its
/// disk (sphere lights, facing `towards`) or rectangle (facing its
/// direction); for directional lights, directions within its angular radius.
pub fn area_samples(light: &Light, n: usize, towards: Vec3) -> Vec<Light> {
    let Some(area) = light.area else {
        return vec![*light];
    };
    stratified_square(n, || (0.5, 0.5))
        .into_iter()
        .map(|(a, b)| {
            let ((u, v), (hu, hv)) = match area {
                LightArea::Sphere { radius } => (concentric_disk(a, b), (radius, radius)),
                LightArea::Rect { width, height } => ((a, b), (width * 0.5, height * 0.5)),
            };
            let mut l = *light;
            l.area = None;
            match light.kind {
                LightType::Directional => {
                    let d = light.direction.normalize();
                    let t = d.any_orthonormal_vector();
                    l.direction = (d + t * (u * hu) + d.cross(t) * (v * hv)).normalize();
                }
                _ => {
                    let axis = match area {
                        LightArea::Sphere { .. } => {
                            (towards - light.position).normalize_or(Vec3::NEG_Y)
                        }
                        LightArea::Rect { .. } => light.direction.normalize_or(Vec3::NEG_Y),
                    };
                    let t = axis.any_orthonormal_vector();
                    l.position += t * (u * hu) + axis.cross(t) * (v * hv);
                }
            }
            l
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stratified_samples_cover_each_cell_once() {
        let pts = stratified_square(16, || (0.5, 0.5));
        let mut cells: Vec<(i32, i32)> = pts
            .iter()
            .map(|(x, y)| (((x + 1.0) * 2.0) as i32, ((y + 1.0) * 2.0) as i32))
            .collect();
        cells.sort();
        cells.dedup();
        assert_eq!(cells.len(), 16);
        // Not a square: every sample kept, one per stratum of area 1/n, and
        // the strata tile the square (no region without samples).
        for n in [2usize, 3, 5, 7, 12, 17, 30] {
            let pts = stratified_square(n, || (0.5, 0.5));
            assert_eq!(pts.len(), n);
            let lo = stratified_square(n, || (0.0, 0.0));
            let hi = stratified_square(n, || (1.0, 1.0));
            let area: f32 = lo
                .iter()
                .zip(&hi)
                .map(|(a, b)| (b.0 - a.0) * (b.1 - a.1) / 4.0)
                .sum();
            assert!((area - 1.0).abs() < 1e-5, "n = {n}: strata cover {area}");
            for ((a, b), p) in lo.iter().zip(&hi).zip(&pts) {
                assert!(
                    ((b.0 - a.0) * (b.1 - a.1) / 4.0 - 1.0 / n as f32).abs() <= 1e-5,
                    "n = {n}"
                );
                assert!(a.0 <= p.0 && p.0 <= b.0 && a.1 <= p.1 && p.1 <= b.1);
                assert!(a.0 >= -1.0 && a.1 >= -1.0 && b.0 <= 1.0 + 1e-6 && b.1 <= 1.0 + 1e-6);
            }
        }
        for (a, b) in [(1.0, 0.0), (0.0, 1.0), (-1.0, -1.0), (0.3, -0.7)] {
            let (x, y) = concentric_disk(a, b);
            assert!(x * x + y * y <= 1.0 + 1e-5);
        }
    }
}
