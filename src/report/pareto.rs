//! Each view's Pareto front of error against cost: the presets no other
//! beats in both beyond the noise of the measurements.

use super::cells::Cell;
use super::criteria::total;

/// Whether a cell takes part in the trade-off: not the reference's family
/// (exact by definition) and not `none` (no shadows at all).
pub fn competes(c: &Cell) -> bool {
    c.family != "raytraced" && c.family != "none"
}

/// Frame times within this fraction of each other count as equal: the
/// run-to-run spread of `bench` medians on lavapipe.
pub const COST_NOISE: f64 = 0.10;
/// Mismatches within this many percentage points count as equal (the
/// precision of the tables).
pub const ERROR_NOISE_PCT: f64 = 0.001;

/// Whether `a` dominates `b` in (cost, error): not worse in either beyond
/// the noise, better in one beyond it.
fn dominates((ca, ea): (f64, f64), (cb, eb): (f64, f64)) -> bool {
    let same_cost = (ca - cb).abs() <= COST_NOISE * ca.max(cb);
    let same_error = (ea - eb).abs() <= ERROR_NOISE_PCT;
    let cheaper = ca < cb && !same_cost;
    let better = ea < eb && !same_error;
    (ca <= cb || same_cost) && (ea <= eb || same_error) && (cheaper || better)
}

/// Indices of `cells` on the Pareto front of (frame × none, total
/// mismatch): no other cell dominates them beyond the timing and table
/// noise, so presets with equal masks and times within 10 % share the
/// front instead of noise picking one. Sorted by cost.
pub fn pareto_front(cells: &[&Cell]) -> Vec<usize> {
    let point = |c: &Cell| (c.cost.ratio_to_none, total(c));
    let mut front: Vec<usize> = (0..cells.len())
        .filter(|&i| {
            !cells
                .iter()
                .enumerate()
                .any(|(j, o)| j != i && dominates(point(o), point(cells[i])))
        })
        .collect();
    front.sort_by(|&a, &b| point(cells[a]).0.total_cmp(&point(cells[b]).0));
    front
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::cells::{CellKey, Cost, Quality};

    fn cell(technique: &str, ratio: f64, total_pct: f64) -> Cell {
        Cell {
            key: CellKey {
                version: String::new(),
                scene: "s".into(),
                camera: "c".into(),
                light: "l".into(),
                width: 1,
                height: 1,
                technique: technique.into(),
                reference: String::new(),
                bench_frames: (0, 0),
                flicker: None,
            },
            family: "shadow-map".into(),
            preset: String::new(),
            light_kinds: vec![],
            area_light: false,
            quality: Quality {
                total_pct,
                ..Default::default()
            },
            cost: Cost {
                ratio_to_none: ratio,
                ..Default::default()
            },
            image: String::new(),
            heatmap: String::new(),
        }
    }

    /// The front by hand: (1, 5) and (2, 1) and (4, 0.5) are not
    /// dominated; (3, 2) is by (2, 1); (2, 3) by (2, 1) (same cost, worse).
    #[test]
    fn the_pareto_front_keeps_only_undominated_cells() {
        let cells = [
            cell("a", 1.0, 5.0),
            cell("b", 3.0, 2.0),
            cell("c", 2.0, 1.0),
            cell("d", 4.0, 0.5),
            cell("e", 2.0, 3.0),
        ];
        let refs: Vec<&Cell> = cells.iter().collect();
        assert_eq!(pareto_front(&refs), vec![0, 2, 3]);
        // Equal masks, times within the noise: both stay; 20 % slower goes.
        let ties = [
            cell("a", 2.0, 0.002),
            cell("b", 2.1, 0.002),
            cell("c", 2.4, 0.002),
        ];
        let refs: Vec<&Cell> = ties.iter().collect();
        assert_eq!(pareto_front(&refs), vec![0, 1]);
    }
}
