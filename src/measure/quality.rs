//! Mask and image quality metrics against the ray-traced reference.

use crate::scene::Light;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Per light, the pixels that count: geometry drawn that receives shadows
/// and that the light's direct light reaches (facing it, inside a spot's
/// cone, within range), from the G-buffer's positions (`w` > 0.5 where a
/// surface was drawn) and normals (`w` > 0.5 where it receives shadows).
pub fn considered_from_gbuffer(
    positions: &[[f32; 4]],
    normals: &[[half::f16; 4]],
    lights: &[Light],
) -> Vec<Vec<bool>> {
    lights
        .iter()
        .map(|l| {
            positions
                .iter()
                .zip(normals)
                .map(|(p, n)| {
                    let normal = Vec3::new(n[0].to_f32(), n[1].to_f32(), n[2].to_f32());
                    p[3] > 0.5
                        && n[3].to_f32() > 0.5
                        && l.reaches(Vec3::new(p[0], p[1], p[2]), normal)
                })
                .collect()
        })
        .collect()
}

/// Mismatch counts as percentages of the considered pixels.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Mismatch {
    /// Technique says shadow (< 0.5), reference says lit.
    pub false_shadow_pct: f64,
    /// Technique says lit, reference says shadow.
    pub false_lit_pct: f64,
    pub total_pct: f64,
}

/// Quality of one technique's mask for one light.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct MaskMetrics {
    /// Pixels showing shadow-receiving geometry that faces the light.
    pub considered_pixels: usize,
    /// Of those, pixels the reference puts in shadow (visibility < 0.5).
    pub reference_shadowed_pct: f64,
    /// Pixels within [`EDGE_RADIUS`] px of a reference shadow boundary.
    pub edge_pixels: usize,
    pub all: Mismatch,
    /// Mismatches inside the edge band (percent of all considered pixels).
    pub edge: Mismatch,
    /// Mismatches outside the edge band (percent of all considered pixels).
    pub interior: Mismatch,
    pub mean_abs_error: f64,
    pub rms_error: f64,
    /// Mean absolute error over the considered pixels outside the edge
    /// band: graded acne, light bleeding and dimmed floors, which the
    /// mismatch at ½ cannot see.
    pub interior_mae: f64,
    /// Of the interior pixels where the reference is exactly lit or
    /// shadowed (a hard light's), the % whose visibility lies strictly
    /// between [`GRADED_LOW`] and [`GRADED_HIGH`].
    pub graded_interior_pct: f64,
    /// Mean absolute error over the interior pixels where the reference
    /// itself is fractional (strictly between [`GRADED_LOW`] and
    /// [`GRADED_HIGH`]): light through translucent casters under a hard
    /// light, penumbrae under an area light; `None` where there is none.
    pub fractional_mae: Option<f64>,
}

/// Visibility above this and below [`GRADED_HIGH`] is neither shadow nor
/// light: graded.
pub const GRADED_LOW: f32 = 0.05;
/// See [`GRADED_LOW`].
pub const GRADED_HIGH: f32 = 0.95;

/// Whether a test visibility is graded where the reference's is `reference`
/// (only counted where the reference is exactly 0 or 1).
fn graded(reference: f32, test: f32) -> Option<bool> {
    (reference == 0.0 || reference == 1.0).then_some(test > GRADED_LOW && test < GRADED_HIGH)
}

/// Screen pixels per shadow-map texel (the aliasing measure) over the
/// considered pixels where a map was looked up.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct FootprintStats {
    pub mean: f64,
    pub p95: f64,
    pub max: f64,
}

/// [`FootprintStats`] of `footprint` (0 where no map was looked up) over
/// the `considered` pixels; `None` when no considered pixel has one.
pub fn footprint_stats(considered: &[bool], footprint: &[f32]) -> Option<FootprintStats> {
    let mut v: Vec<f64> = considered
        .iter()
        .zip(footprint)
        .filter(|(c, f)| **c && **f > 0.0 && f.is_finite())
        .map(|(_, f)| *f as f64)
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(FootprintStats {
        mean: v.iter().sum::<f64>() / v.len() as f64,
        p95: super::percentile(&v, 0.95),
        max: v[v.len() - 1],
    })
}

/// Pixels within Chebyshev distance `radius` of a considered pixel whose
/// reference class (shadow/lit at 0.5) differs.
pub fn edge_band(
    width: usize,
    height: usize,
    considered: &[bool],
    reference: &[f32],
    radius: usize,
) -> Vec<bool> {
    let class = |i: usize| considered[i].then_some(reference[i] < 0.5);
    band_where_class_changes(width, height, radius, class)
}

/// Pixels of some class (`class(i)` is `Some`) within Chebyshev distance
/// `radius` of a pixel of another class.
fn band_where_class_changes<K: PartialEq>(
    width: usize,
    height: usize,
    radius: usize,
    class: impl Fn(usize) -> Option<K>,
) -> Vec<bool> {
    let mut band = vec![false; width * height];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let Some(own) = class(i) else {
                continue;
            };
            let (x0, x1) = (x.saturating_sub(radius), (x + radius).min(width - 1));
            let (y0, y1) = (y.saturating_sub(radius), (y + radius).min(height - 1));
            band[i] = (y0..=y1)
                .any(|yy| (x0..=x1).any(|xx| class(yy * width + xx).is_some_and(|k| k != own)));
        }
    }
    band
}

/// Mismatch near the borders between a map's partitions (cascades, cube
/// faces) against the mismatch elsewhere, in % of each region's considered
/// pixels.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct SeamStats {
    /// Considered pixels within [`SEAM_RADIUS`] px of another partition.
    pub seam_pixels: usize,
    pub seam_mismatch_pct: f64,
    pub elsewhere_mismatch_pct: f64,
    /// What the seam band would show if each of its pixels failed as often
    /// as the pixels of its own partition outside the band: the seam's
    /// effect without the partitions' different resolutions (a far cascade
    /// is coarser everywhere, not only at its border).
    pub same_partitions_pct: f64,
    /// The same two regions split by distance to the reference's shadow
    /// edges: mismatch in % of each region's pixels within [`EDGE_RADIUS`]
    /// px of one (where a map's texels show: the seam's effect without how
    /// many edges each region holds — cascade borders lie far off, where
    /// shadow edges crowd), and of its pixels farther off (the dark or
    /// light bands users report at cascade borders).
    pub seam_at_edges_pct: f64,
    pub elsewhere_at_edges_pct: f64,
    pub seam_interior_pct: f64,
    pub elsewhere_interior_pct: f64,
}

/// The seam band's half-width in pixels.
pub const SEAM_RADIUS: usize = 4;

/// The half-width in pixels of the band around the reference's shadow
/// edges that [`MaskMetrics`] counts as edge, not interior.
pub const EDGE_RADIUS: usize = 2;

/// [`SeamStats`] of `test` against `reference`, where `partition` is the
/// map partition each pixel looked up (0: none) and `edges` the
/// reference's [`edge_band`] over `considered` at [`EDGE_RADIUS`] (the
/// same for every technique); `None` when no considered pixel lies near a
/// partition border.
pub fn seam_stats(
    width: usize,
    height: usize,
    considered: &[bool],
    partition: &[u32],
    reference: &[f32],
    edges: &[bool],
    test: &[f32],
) -> Option<SeamStats> {
    let class = |i: usize| (partition[i] > 0).then_some(partition[i]);
    let band = band_where_class_changes(width, height, SEAM_RADIUS, class);
    // [in seam band?][near an edge?]: [pixels, mismatched].
    let mut counts = [[[0usize; 2]; 2]; 2];
    // Outside the band, per partition: [pixels, mismatched].
    let mut per_partition = std::collections::HashMap::<u32, [usize; 2]>::new();
    for i in (0..width * height).filter(|&i| considered[i]) {
        let wrong = ((reference[i] < 0.5) != (test[i] < 0.5)) as usize;
        let region = &mut counts[band[i] as usize][edges[i] as usize];
        region[0] += 1;
        region[1] += wrong;
        if !band[i] {
            let p = per_partition.entry(partition[i]).or_default();
            p[0] += 1;
            p[1] += wrong;
        }
    }
    let rate = |p: u32| {
        per_partition
            .get(&p)
            .map_or(0.0, |c| c[1] as f64 / c[0] as f64)
    };
    let expected: f64 = (0..width * height)
        .filter(|&i| considered[i] && band[i])
        .map(|i| rate(partition[i]))
        .sum();
    let pct = |c: [usize; 2]| super::percent(c[1], c[0]);
    let both = |r: [[usize; 2]; 2]| [r[0][0] + r[1][0], r[0][1] + r[1][1]];
    let [elsewhere, seam] = counts;
    let seam_pixels = both(seam)[0];
    (seam_pixels > 0).then(|| SeamStats {
        seam_pixels,
        seam_mismatch_pct: pct(both(seam)),
        elsewhere_mismatch_pct: pct(both(elsewhere)),
        same_partitions_pct: 100.0 * expected / seam_pixels as f64,
        seam_at_edges_pct: pct(seam[1]),
        elsewhere_at_edges_pct: pct(elsewhere[1]),
        seam_interior_pct: pct(seam[0]),
        elsewhere_interior_pct: pct(elsewhere[0]),
    })
}

/// Compares `test` against `reference` over the `considered` pixels.
pub fn mask_metrics(
    width: usize,
    height: usize,
    considered: &[bool],
    reference: &[f32],
    test: &[f32],
) -> MaskMetrics {
    let band = edge_band(width, height, considered, reference, EDGE_RADIUS);
    let (mut n, mut ref_shadow, mut edge_n) = (0usize, 0usize, 0usize);
    let mut counts = [[0usize; 2]; 2]; // [edge?][false_shadow, false_lit]
    let (mut abs, mut sq) = (0.0f64, 0.0f64);
    // Interior pixels, their absolute error, hard-reference pixels, graded.
    let (mut interior_n, mut interior_abs) = (0usize, 0.0f64);
    let (mut hard_n, mut graded_n) = (0usize, 0usize);
    let (mut fractional_n, mut fractional_abs) = (0usize, 0.0f64);
    for i in 0..width * height {
        if !considered[i] {
            continue;
        }
        n += 1;
        let (r, t) = (reference[i] < 0.5, test[i] < 0.5);
        ref_shadow += r as usize;
        edge_n += band[i] as usize;
        if t && !r {
            counts[band[i] as usize][0] += 1;
        } else if r && !t {
            counts[band[i] as usize][1] += 1;
        }
        let d = (test[i] - reference[i]) as f64;
        abs += d.abs();
        sq += d * d;
        if !band[i] {
            interior_n += 1;
            interior_abs += d.abs();
            if let Some(g) = graded(reference[i], test[i]) {
                hard_n += 1;
                graded_n += g as usize;
            }
            if reference[i] > GRADED_LOW && reference[i] < GRADED_HIGH {
                fractional_n += 1;
                fractional_abs += d.abs();
            }
        }
    }
    let pct = |c: usize| super::percent(c, n);
    let mm = |fs: usize, fl: usize| Mismatch {
        false_shadow_pct: pct(fs),
        false_lit_pct: pct(fl),
        total_pct: pct(fs + fl),
    };
    MaskMetrics {
        considered_pixels: n,
        reference_shadowed_pct: pct(ref_shadow),
        edge_pixels: edge_n,
        all: mm(counts[0][0] + counts[1][0], counts[0][1] + counts[1][1]),
        edge: mm(counts[1][0], counts[1][1]),
        interior: mm(counts[0][0], counts[0][1]),
        mean_abs_error: if n == 0 { 0.0 } else { abs / n as f64 },
        rms_error: if n == 0 { 0.0 } else { (sq / n as f64).sqrt() },
        interior_mae: if interior_n == 0 {
            0.0
        } else {
            interior_abs / interior_n as f64
        },
        graded_interior_pct: super::percent(graded_n, hard_n),
        fractional_mae: (fractional_n > 0).then(|| fractional_abs / fractional_n as f64),
    }
}

/// FLIP statistics over all pixels of the frame.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct FlipStats {
    pub mean: f64,
    pub p95: f64,
    pub p99: f64,
}

#[cfg(not(target_arch = "wasm32"))]
/// ꟻLIP (the `nv-flip` crate) between two sRGB RGBA8 images of one size.
pub fn flip(reference_rgba: &[u8], test_rgba: &[u8], width: u32, height: u32) -> FlipStats {
    let rgb = |rgba: &[u8]| -> Vec<u8> {
        rgba.chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect()
    };
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(reference_rgba));
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(test_rgba));
    let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut v = err.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    FlipStats {
        mean: v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64,
        p95: super::percentile(&v, 0.95) as f64,
        p99: super::percentile(&v, 0.99) as f64,
    }
}

/// The heatmap's colour of a pixel flipped to shadow.
const FALSE_SHADOW: [u8; 4] = [230, 30, 30, 255];
/// The heatmap's colour of a pixel flipped to light.
const FALSE_LIT: [u8; 4] = [40, 80, 240, 255];

/// Heatmap: false shadow red, false lit blue; a visibility off by more
/// than [`GRADED_LOW`] without flipping, the grey tinted toward red (too
/// dark) or blue (too bright) by its error; agreeing pixels the grey
/// luminance of the reference image.
pub fn heatmap(
    reference_rgba: &[u8],
    considered: &[bool],
    reference: &[f32],
    test: &[f32],
) -> Vec<u8> {
    reference_rgba
        .chunks_exact(4)
        .enumerate()
        .flat_map(|(i, p)| {
            let (r, t) = (reference[i] < 0.5, test[i] < 0.5);
            let l = 0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32;
            let d = test[i] - reference[i];
            if considered[i] && t && !r {
                FALSE_SHADOW
            } else if considered[i] && r && !t {
                FALSE_LIT
            } else if considered[i] && d.abs() > GRADED_LOW {
                // Graded error: the grey tinted toward the flipped colour of
                // its sign, fully at a visibility error of ½.
                let towards = if d < 0.0 { FALSE_SHADOW } else { FALSE_LIT };
                let a = (2.0 * d.abs()).min(1.0);
                let mix = |c: u8| (l + (c as f32 - l) * a) as u8;
                [mix(towards[0]), mix(towards[1]), mix(towards[2]), 255]
            } else {
                [l as u8, l as u8, l as u8, 255]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edge band of a 10×10 reference, every pixel considered.
    fn edges_of(reference: &[f32]) -> Vec<bool> {
        edge_band(10, 10, &[true; 100], reference, EDGE_RADIUS)
    }

    /// `seam_stats` of a 10×10 frame, every pixel considered.
    fn seams_of(partition: &[u32], reference: &[f32], test: &[f32]) -> Option<SeamStats> {
        seam_stats(
            10,
            10,
            &[true; 100],
            partition,
            reference,
            &edges_of(reference),
            test,
        )
    }

    /// Two partitions split at column 5: the band holds columns 1 to 8
    /// (within 4 px of the other side), elsewhere columns 0 and 9.
    #[test]
    fn seam_stats_split_mismatch_at_partition_borders_from_the_rest() {
        let partition: Vec<u32> = (0..100).map(|i| if i % 10 < 5 { 1 } else { 2 }).collect();
        let reference = vec![1.0; 100];
        let mut test = reference.clone();
        for row in 0..10 {
            test[row * 10 + 5] = 0.0; // on the border: 10 of 80 band pixels
        }
        test[0] = 0.0; // column 0: 1 of 20 pixels elsewhere
        let s = seams_of(&partition, &reference, &test).unwrap();
        assert_eq!(s.seam_pixels, 80);
        assert!((s.seam_mismatch_pct - 12.5).abs() < 1e-9, "{s:?}");
        assert!((s.elsewhere_mismatch_pct - 5.0).abs() < 1e-9, "{s:?}");
        // Partition 1 fails on 1 of its 10 outside pixels, partition 2 on
        // none of its 10: 40 band pixels at 10 %, 40 at 0 %.
        assert!((s.same_partitions_pct - 5.0).abs() < 1e-9, "{s:?}");
        let one = vec![1u32; 100];
        assert_eq!(seams_of(&one, &reference, &test), None);
    }

    /// The same two partitions over a reference shadowed on its top five
    /// rows: rows 3 to 6 lie within 2 px of its edge, so the band (columns
    /// 1 to 8) holds 32 edge pixels and 48 interior ones, elsewhere 8 and
    /// 12.
    #[test]
    fn seam_stats_split_each_region_at_the_references_shadow_edges() {
        let partition: Vec<u32> = (0..100).map(|i| if i % 10 < 5 { 1 } else { 2 }).collect();
        let reference: Vec<f32> = (0..100).map(|i| if i < 50 { 0.0 } else { 1.0 }).collect();
        let mut test = reference.clone();
        test[4 * 10 + 3] = 1.0; // band, at the edge
        test[4] = 1.0; // band, interior
        test[5 * 10] = 0.0; // elsewhere, at the edge
        let s = seams_of(&partition, &reference, &test).unwrap();
        assert!((s.seam_at_edges_pct - 100.0 / 32.0).abs() < 1e-9, "{s:?}");
        assert!(
            (s.elsewhere_at_edges_pct - 100.0 / 8.0).abs() < 1e-9,
            "{s:?}"
        );
        assert!((s.seam_interior_pct - 100.0 / 48.0).abs() < 1e-9, "{s:?}");
        assert_eq!(s.elsewhere_interior_pct, 0.0);
        assert!(
            (s.seam_mismatch_pct - 100.0 * 2.0 / 80.0).abs() < 1e-9,
            "{s:?}"
        );
    }

    /// Pixels that looked up no map (partition 0) border nothing and lie in
    /// no band; pixels not considered count nowhere.
    #[test]
    fn seam_stats_leave_out_unmapped_and_unconsidered_pixels() {
        let reference = vec![1.0; 100];
        let mut test = reference.clone();
        // One partition beside unmapped pixels: no seam at all.
        let half: Vec<u32> = (0..100).map(|i| if i % 10 < 5 { 1 } else { 0 }).collect();
        assert_eq!(seams_of(&half, &reference, &test), None);
        // Partitions 1 and 2 with two unmapped columns (4, 5) between:
        // the band is columns 2, 3 (within 4 px of column 6) and 6, 7.
        let split: Vec<u32> = (0..100)
            .map(|i| match i % 10 {
                0..=3 => 1,
                4 | 5 => 0,
                _ => 2,
            })
            .collect();
        test[4] = 0.0; // an unmapped pixel: elsewhere, not in the band
        let s = seams_of(&split, &reference, &test).unwrap();
        assert_eq!(s.seam_pixels, 40);
        assert_eq!(s.seam_mismatch_pct, 0.0);
        assert!(
            (s.elsewhere_mismatch_pct - 100.0 / 60.0).abs() < 1e-9,
            "{s:?}"
        );
        // The top row not considered: its band pixels and its mismatch go.
        let mut considered = [true; 100];
        considered[..10].fill(false);
        let edges = edge_band(10, 10, &considered, &reference, EDGE_RADIUS);
        let s = seam_stats(10, 10, &considered, &split, &reference, &edges, &test).unwrap();
        assert_eq!(s.seam_pixels, 36);
        assert_eq!(s.elsewhere_mismatch_pct, 0.0);
    }

    /// A 10×10 frame whose left half is in shadow in the reference.
    fn half_shadow() -> (Vec<bool>, Vec<f32>) {
        let reference: Vec<f32> = (0..100)
            .map(|i| if i % 10 < 5 { 0.0 } else { 1.0 })
            .collect();
        (vec![true; 100], reference)
    }

    #[test]
    fn identical_masks_have_no_error() {
        let (c, r) = half_shadow();
        let m = mask_metrics(10, 10, &c, &r, &r);
        assert_eq!(m.all, Mismatch::default());
        assert_eq!(m.mean_abs_error, 0.0);
        assert_eq!(m.reference_shadowed_pct, 50.0);
        // Columns 3..=6 lie within 2 px of the boundary between 4 and 5.
        assert_eq!(m.edge_pixels, 40);
    }

    #[test]
    fn all_lit_test_reports_the_shadowed_fraction_as_false_lit() {
        let (c, r) = half_shadow();
        let lit = vec![1.0; 100];
        let m = mask_metrics(10, 10, &c, &r, &lit);
        assert_eq!(m.all.false_lit_pct, 50.0);
        assert_eq!(m.all.false_shadow_pct, 0.0);
        // Shadowed columns 0..=4, of which 3 and 4 are in the edge band.
        assert_eq!(m.edge.false_lit_pct, 20.0);
        assert_eq!(m.interior.false_lit_pct, 30.0);
        assert!((m.mean_abs_error - 0.5).abs() < 1e-12);
        assert!((m.rms_error - 0.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn shifted_boundary_is_an_edge_error_and_unconsidered_pixels_are_ignored() {
        let (mut c, r) = half_shadow();
        // The test's shadow reaches one column further: column 5 false shadow.
        let t: Vec<f32> = (0..100)
            .map(|i| if i % 10 < 6 { 0.0 } else { 1.0 })
            .collect();
        let m = mask_metrics(10, 10, &c, &r, &t);
        assert_eq!(m.all.false_shadow_pct, 10.0);
        assert_eq!(m.edge.false_shadow_pct, 10.0);
        assert_eq!(m.interior.total_pct, 0.0);
        // Ignore the first row: 90 pixels, 9 mismatches.
        c[..10].fill(false);
        let m = mask_metrics(10, 10, &c, &r, &t);
        assert_eq!(m.considered_pixels, 90);
        assert!((m.all.false_shadow_pct - 10.0).abs() < 1e-9);
        // Soft values: 0.25 everywhere against 0/1.
        let soft = vec![0.25; 100];
        let m = mask_metrics(10, 10, &[true; 100], &r, &soft);
        assert!(
            (m.mean_abs_error - 0.5).abs() < 1e-9,
            "{}",
            m.mean_abs_error
        );
        assert_eq!(m.all.false_shadow_pct, 50.0);
    }

    #[test]
    fn the_heatmap_tints_graded_error_and_colours_flips() {
        let grey = [100u8, 100, 100, 255].repeat(4);
        let reference = [1.0, 1.0, 0.0, 0.0];
        let test = [0.7, 0.2, 0.0, 0.03];
        let h = heatmap(&grey, &[true; 4], &reference, &test);
        // Dimmed by 0.3: 60 % of the way from the grey to red.
        let near = |a: &[u8], b: [u8; 4]| a.iter().zip(b).all(|(x, y)| x.abs_diff(y) <= 1);
        assert!(near(&h[0..4], [178, 58, 58, 255]), "{:?}", &h[0..4]);
        assert_eq!(h[4..8], FALSE_SHADOW);
        // Exact, and off by less than GRADED_LOW: the grey.
        assert_eq!(h[8..16], [100, 100, 100, 255, 100, 100, 100, 255]);
    }

    #[test]
    fn graded_error_away_from_edges_is_measured_where_the_mismatch_sees_none() {
        let (c, r) = half_shadow();
        // The lit half dimmed to 0.7 (acne a viewer sees as grey bands):
        // no pixel flips at ½, yet every lit interior pixel is graded.
        let dimmed: Vec<f32> = r
            .iter()
            .map(|&v| if v == 1.0 { 0.7 } else { 0.0 })
            .collect();
        let m = mask_metrics(10, 10, &c, &r, &dimmed);
        assert_eq!(m.all.total_pct, 0.0);
        // Interior: columns 0..=2 (shadow, exact) and 7..=9 (lit, 0.3 off).
        assert!((m.interior_mae - 0.15).abs() < 1e-6, "{}", m.interior_mae);
        assert!((m.graded_interior_pct - 50.0).abs() < 1e-9);
        assert_eq!(m.fractional_mae, None, "a hard reference");
        // Seen through a pane passing 0.7, the dimmed half is exact there.
        let through_pane: Vec<f32> = r.iter().map(|&v| v * 0.7).collect();
        let m = mask_metrics(10, 10, &c, &through_pane, &dimmed);
        assert!(m.fractional_mae.is_some_and(|e| e < 1e-6), "{m:?}");
        let m = mask_metrics(10, 10, &c, &through_pane, &r);
        assert!(m.fractional_mae.is_some_and(|e| (e - 0.3).abs() < 1e-6));
        // The edge band's own error counts in the MAE, not the interior's.
        let mut edge_only = r.clone();
        for y in 0..10 {
            edge_only[y * 10 + 4] = 0.5;
        }
        let m = mask_metrics(10, 10, &c, &r, &edge_only);
        assert_eq!(m.interior_mae, 0.0);
        assert_eq!(m.graded_interior_pct, 0.0);
        assert!(m.mean_abs_error > 0.0);
        // A soft reference (an area light's 0.4) is not counted as hard.
        let soft_ref = vec![0.4; 100];
        let m = mask_metrics(10, 10, &c, &soft_ref, &vec![0.5; 100]);
        assert_eq!(m.graded_interior_pct, 0.0);
        assert!((m.interior_mae - 0.1).abs() < 1e-6);
    }

    #[test]
    fn flip_of_identical_images_is_zero_and_grows_with_difference() {
        let a: Vec<u8> = (0..64 * 64)
            .flat_map(|i| [(i % 251) as u8, 100, 50, 255])
            .collect();
        assert_eq!(flip(&a, &a, 64, 64).mean, 0.0);
        let b: Vec<u8> = a
            .chunks_exact(4)
            .flat_map(|p| [p[0] / 2, p[1], p[2], 255])
            .collect();
        let c: Vec<u8> = a
            .chunks_exact(4)
            .flat_map(|p| [p[0] / 8, p[1], p[2], 255])
            .collect();
        let (fb, fc) = (flip(&a, &b, 64, 64), flip(&a, &c, 64, 64));
        assert!(fb.mean > 0.0 && fc.mean > fb.mean);
        assert!(fc.p99 >= fc.p95);
    }

    #[test]
    fn footprint_stats_over_considered_looked_up_pixels() {
        let considered = [true, true, true, true, false, true];
        let footprint = [1.0, 3.0, 2.0, 0.0, 100.0, 4.0];
        let s = footprint_stats(&considered, &footprint).unwrap();
        assert_eq!(s.mean, 2.5);
        assert_eq!(s.p95, 4.0);
        assert_eq!(s.max, 4.0);
        assert!(footprint_stats(&[false; 6], &footprint).is_none());
        assert!(footprint_stats(&considered, &[0.0; 6]).is_none());
    }
}
