//! The documents' summary table (SEEDS §7), filled from measurements: per
//! technique preset its quality, cost, advantages, disadvantages, use,
//! implementation difficulty, extensibility and ✔/✗ marks, every claim a
//! measured figure with the cell it comes from; each view's Pareto front
//! of error against cost; and the computed answer to "is there one
//! universal technique?".

use super::cells::Cell;
use super::matrix::{Matrix, View};
use crate::technique::{Capabilities, FAMILIES};

include!(concat!(env!("OUT_DIR"), "/family_lines.rs"));

/// A measured statement and the cell that shows it (its anchor).
#[derive(Clone, Debug)]
pub struct Claim {
    pub text: String,
    pub evidence: Option<String>,
}

impl Claim {
    fn of(text: String, cell: &Cell) -> Claim {
        Claim {
            text,
            evidence: Some(cell.anchor()),
        }
    }

    fn plain(text: String) -> Claim {
        Claim {
            text,
            evidence: None,
        }
    }
}

/// One ✔/✗ criterion of the summary.
#[derive(Clone, Debug)]
pub struct Mark {
    pub criterion: &'static str,
    /// None where the matrix has no view that tests it.
    pub ok: Option<bool>,
    /// The worst figure over the views that test it.
    pub claim: Option<Claim>,
}

/// One row of the summary table: a technique preset.
#[derive(Clone, Debug)]
pub struct SummaryRow {
    pub technique: String,
    pub family: String,
    pub description: String,
    pub quality: Claim,
    pub cost: Claim,
    pub advantages: Vec<Claim>,
    pub disadvantages: Vec<Claim>,
    pub usage: Vec<Claim>,
    pub difficulty: String,
    pub extensibility: Vec<Claim>,
    pub marks: Vec<Mark>,
}

/// What the criteria test: which views, and what passes.
struct Criterion {
    name: &'static str,
    declared: Option<fn(&Capabilities) -> bool>,
    applies: fn(&Cell) -> bool,
    passes: fn(&Cell) -> bool,
    figure: fn(&Cell) -> f64,
    unit: Unit,
}

/// How a criterion's figure is written.
#[derive(Clone, Copy)]
enum Unit {
    /// A percentage, followed by what it is a percentage of.
    Percent(&'static str),
    /// A multiple of `none`'s frame time.
    TimesNone,
    /// A plain value to 4 decimals, followed by its name.
    Value(&'static str),
}

impl Unit {
    fn format(self, v: f64) -> String {
        match self {
            Unit::Percent(of) => format!("{} % {of}", pct(v)),
            Unit::TimesNone => format!("×{v:.2}"),
            Unit::Value(name) => format!("{v:.4} {name}"),
        }
    }
}

/// Mismatch (% of considered pixels) above which a view counts as failed.
pub const FAILED_PCT: f64 = 1.0;
/// Interior mismatch within which hard shadows count as exact.
pub const EXACT_INTERIOR_PCT: f64 = 0.1;
/// Mean absolute visibility error within which soft shadows pass.
pub const SOFT_MAE: f64 = 0.01;
/// Frame time (× `none`) within which a technique counts as cheap.
pub const CHEAP_RATIO: f64 = 2.0;

fn total(c: &Cell) -> f64 {
    c.quality.total_pct
}

fn below_failure(c: &Cell) -> bool {
    total(c) <= FAILED_PCT
}

/// A view that tests a light type alone: not one of the views kept for
/// another criterion (open meshes, curved receivers, the camera in a
/// shadow, soft shadows).
fn plain_view(c: &Cell, kind: &str) -> bool {
    c.light_kinds.iter().any(|k| k == kind)
        && !c.area_light
        && c.key.camera != "in-shadow"
        && !["bunny", "teapot", "curved"].contains(&c.key.scene.as_str())
}

/// Flicker (% of considered pixels per step) within which a technique
/// counts as stable (issue 15's bar).
pub const STABLE_FLICKER_PCT: f64 = 0.01;

const CRITERIA: [Criterion; 10] = [
    Criterion {
        name: "hard shadows exact",
        declared: None,
        applies: |c| !c.area_light,
        passes: |c| c.quality.interior_pct <= EXACT_INTERIOR_PCT,
        figure: |c| c.quality.interior_pct,
        unit: Unit::Percent("interior mismatch"),
    },
    Criterion {
        name: "point lights",
        declared: Some(|k| k.point_lights),
        applies: |c| plain_view(c, "point"),
        passes: below_failure,
        figure: total,
        unit: Unit::Percent("mismatch"),
    },
    Criterion {
        name: "spot lights",
        declared: Some(|k| k.spot_lights),
        applies: |c| plain_view(c, "spot"),
        passes: below_failure,
        figure: total,
        unit: Unit::Percent("mismatch"),
    },
    Criterion {
        name: "directional lights",
        declared: Some(|k| k.directional_lights),
        applies: |c| plain_view(c, "directional"),
        passes: below_failure,
        figure: total,
        unit: Unit::Percent("mismatch"),
    },
    Criterion {
        name: "soft shadows",
        declared: Some(|k| k.soft_shadows),
        applies: |c| c.area_light,
        passes: |c| c.quality.mean_abs_error <= SOFT_MAE,
        figure: |c| c.quality.mean_abs_error,
        unit: Unit::Value("mean visibility error"),
    },
    Criterion {
        name: "open meshes",
        declared: Some(|k| k.open_meshes),
        applies: |c| c.key.scene == "bunny" || c.key.scene == "teapot",
        passes: below_failure,
        figure: total,
        unit: Unit::Percent("mismatch"),
    },
    Criterion {
        name: "curved receivers",
        declared: Some(|k| k.curved_receivers),
        applies: |c| c.key.scene == "curved",
        passes: below_failure,
        figure: total,
        unit: Unit::Percent("mismatch"),
    },
    Criterion {
        name: "camera in a shadow",
        declared: None,
        applies: |c| c.key.camera == "in-shadow",
        passes: below_failure,
        figure: total,
        unit: Unit::Percent("mismatch"),
    },
    Criterion {
        name: "stable under motion",
        declared: None,
        applies: |c| c.quality.flicker_pct.is_some(),
        passes: |c| c.quality.flicker_pct.unwrap_or(0.0) <= STABLE_FLICKER_PCT,
        figure: |c| c.quality.flicker_pct.unwrap_or(0.0),
        unit: Unit::Percent("flicker per step"),
    },
    Criterion {
        name: "cheap",
        declared: None,
        applies: |_| true,
        passes: |c| c.cost.ratio_to_none <= CHEAP_RATIO,
        figure: |c| c.cost.ratio_to_none,
        unit: Unit::TimesNone,
    },
];

/// Everything the report pages show.
pub struct Report<'a> {
    pub matrix: &'a Matrix,
    pub cells: &'a [Cell],
    /// Per view, the indices (into `cells`) of its Pareto front.
    pub fronts: Vec<(View, Vec<usize>)>,
    pub rows: Vec<SummaryRow>,
    pub universal: Vec<String>,
}

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

/// A percentage with the precision the report's prose uses.
pub fn pct(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.1}")
    } else if v >= 0.1 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

impl<'a> Report<'a> {
    pub fn new(matrix: &'a Matrix, cells: &'a [Cell]) -> Report<'a> {
        let fronts: Vec<(View, Vec<usize>)> = matrix
            .views
            .iter()
            .map(|v| {
                let idx: Vec<usize> = (0..cells.len())
                    .filter(|&i| cells[i].view() == *v && competes(&cells[i]))
                    .collect();
                let view_cells: Vec<&Cell> = idx.iter().map(|&i| &cells[i]).collect();
                let front = pareto_front(&view_cells)
                    .into_iter()
                    .map(|k| idx[k])
                    .collect();
                (v.clone(), front)
            })
            .collect();
        let mut report = Report {
            matrix,
            cells,
            fronts,
            rows: vec![],
            universal: vec![],
        };
        report.rows = matrix
            .techniques
            .iter()
            .map(|t| report.summary_row(&crate::measure::choice_label(t)))
            .collect();
        report.universal = report.universal_answer();
        report
    }

    fn cells_of(&self, technique: &str) -> Vec<&'a Cell> {
        self.cells
            .iter()
            .filter(|c| c.technique() == technique)
            .collect()
    }

    /// Views whose front holds `technique`.
    fn fronts_with(&self, technique: &str) -> Vec<&'a Cell> {
        self.fronts
            .iter()
            .flat_map(|(_, f)| f.iter().map(|&i| &self.cells[i]))
            .filter(|c| c.technique() == technique)
            .collect()
    }

    fn summary_row(&self, technique: &str) -> SummaryRow {
        let mine = self.cells_of(technique);
        let family_id = mine.first().map_or_else(
            || technique.split(':').next().unwrap_or("").to_string(),
            |c| c.family.clone(),
        );
        let family = FAMILIES.iter().find(|f| f.id == family_id);
        let description = family
            .and_then(|f| {
                let preset = technique.split(':').nth(1)?.split('[').next()?;
                f.presets.iter().find(|p| p.name == preset)
            })
            .map_or(String::new(), |p| p.summary.to_string());
        let n = mine.len();
        let worst = mine
            .iter()
            .copied()
            .max_by(|a, b| total(a).total_cmp(&total(b)));
        let quality = match worst {
            Some(w) => Claim::of(
                format!(
                    "mean {} % mismatch over {n} views; worst {} % on `{}`",
                    pct(mine.iter().map(|c| total(c)).sum::<f64>() / n as f64),
                    pct(total(w)),
                    w.view().label()
                ),
                w,
            ),
            None => Claim::plain("not measured".into()),
        };
        let ratio = median(mine.iter().map(|c| c.cost.ratio_to_none).collect());
        let dearest = mine
            .iter()
            .copied()
            .max_by(|a, b| a.cost.ratio_to_none.total_cmp(&b.cost.ratio_to_none));
        let cost = match dearest {
            Some(d) => Claim::of(
                format!(
                    "median ×{ratio:.2} the frame of `none`, mask stage median {:.1} ms (wall, CPU work included); at most ×{:.2} on `{}`; {} of shadow resources",
                    median(mine.iter().map(|c| c.cost.mask_ms).collect()),
                    d.cost.ratio_to_none,
                    d.view().label(),
                    bytes(mine.iter().map(|c| c.cost.shadow_bytes).max().unwrap_or(0))
                ),
                d,
            ),
            None => Claim::plain("not measured".into()),
        };
        let on_front = self.fronts_with(technique);
        let mut advantages = vec![];
        if !on_front.is_empty() {
            advantages.push(Claim::of(
                format!(
                    "on the error/cost Pareto front of {} of {} views: {}",
                    on_front.len(),
                    self.fronts.len(),
                    labels(&on_front)
                ),
                on_front[0],
            ));
        }
        let exact: Vec<&Cell> = mine.iter().copied().filter(|c| total(c) <= 0.01).collect();
        if !exact.is_empty() {
            advantages.push(Claim::of(
                format!("exact (≤ 0.01 % mismatch) on {}", labels(&exact)),
                exact[0],
            ));
        }
        if let Some(best) = mine
            .iter()
            .copied()
            .min_by(|a, b| total(a).total_cmp(&total(b)))
            && exact.is_empty()
        {
            advantages.push(Claim::of(
                format!("best: {} % on `{}`", pct(total(best)), best.view().label()),
                best,
            ));
        }
        let mut failed: Vec<&Cell> = mine.iter().copied().filter(|c| !below_failure(c)).collect();
        failed.sort_by(|a, b| total(b).total_cmp(&total(a)));
        let mut disadvantages: Vec<Claim> = failed
            .iter()
            .take(2)
            .map(|c| {
                let q = &c.quality;
                let kind = if q.false_lit_pct > 2.0 * q.false_shadow_pct {
                    "missing shadows (light leaks)"
                } else if q.false_shadow_pct > 2.0 * q.false_lit_pct {
                    "false shadows"
                } else {
                    "wrong shadows"
                };
                Claim::of(
                    format!(
                        "{kind}: {} % mismatch on `{}` ({} % false shadow, {} % false lit)",
                        pct(q.total_pct),
                        c.view().label(),
                        pct(q.false_shadow_pct),
                        pct(q.false_lit_pct)
                    ),
                    c,
                )
            })
            .collect();
        if let Some(d) = dearest.filter(|d| d.cost.ratio_to_none > CHEAP_RATIO) {
            disadvantages.push(Claim::of(
                format!(
                    "costly: ×{:.2} the frame of `none` on `{}`",
                    d.cost.ratio_to_none,
                    d.view().label()
                ),
                d,
            ));
        }
        let usage = self.usage(technique, &on_front, &mine);
        let difficulty = FAMILY_LINES
            .iter()
            .find(|(id, _, _)| *id == family_id)
            .map_or(String::new(), |(_, rs, wgsl)| {
                format!("{rs} lines of Rust, {wgsl} of WGSL (family `{family_id}`)")
            });
        let marks: Vec<Mark> = CRITERIA.iter().map(|k| mark(k, &mine)).collect();
        let extensibility = family
            .map(|f| extensibility(&f.capabilities, &marks))
            .unwrap_or_default();
        SummaryRow {
            technique: technique.to_string(),
            family: family_id,
            description,
            quality,
            cost,
            advantages,
            disadvantages,
            usage,
            difficulty,
            extensibility,
            marks,
        }
    }

    fn usage(&self, technique: &str, on_front: &[&'a Cell], mine: &[&'a Cell]) -> Vec<Claim> {
        if mine.first().is_some_and(|c| !competes(c)) {
            let text = if technique.starts_with("none") {
                "the cost baseline: every ratio is to its frame"
            } else {
                "the ground truth every mask is measured against"
            };
            return vec![Claim::plain(text.into())];
        }
        if !on_front.is_empty() {
            return vec![Claim::of(
                format!("choose it for views like {}", labels(on_front)),
                on_front[0],
            )];
        }
        // Dominated everywhere: name what dominates it where it does best.
        let Some(best) = mine
            .iter()
            .copied()
            .min_by(|a, b| total(a).total_cmp(&total(b)))
        else {
            return vec![];
        };
        let view = best.view();
        let better = self
            .fronts
            .iter()
            .find(|(v, _)| *v == view)
            .and_then(|(_, f)| {
                f.iter().map(|&i| &self.cells[i]).find(|o| {
                    o.cost.ratio_to_none <= best.cost.ratio_to_none && total(o) <= total(best)
                })
            });
        match better {
            Some(o) => vec![Claim::of(
                format!(
                    "dominated on every view; even on `{}`, `{}` is as cheap (×{:.2}) and as right ({} %)",
                    view.label(),
                    o.technique(),
                    o.cost.ratio_to_none,
                    pct(total(o))
                ),
                o,
            )],
            None => vec![Claim::plain("dominated on every view".into())],
        }
    }

    /// The answer to "is there one universal technique?": the presets on
    /// every view's front, or none and who comes closest.
    fn universal_answer(&self) -> Vec<String> {
        let views = self.fronts.len();
        let mut counts: Vec<(String, usize)> = self
            .rows
            .iter()
            .map(|r| (r.technique.clone(), self.fronts_with(&r.technique).len()))
            .filter(|(_, k)| *k > 0)
            .collect();
        counts.sort_by_key(|c| std::cmp::Reverse(c.1));
        let universal: Vec<&(String, usize)> = counts.iter().filter(|(_, k)| *k == views).collect();
        let mut lines = vec![];
        if views == 0 {
            return lines;
        }
        if universal.is_empty() {
            lines.push(format!(
                "No. No preset is on the error/cost Pareto front of all {views} views (the reference and `none` left out), as the documents conclude: combine techniques."
            ));
        } else {
            lines.push(format!(
                "On these {views} views, yes: {} {} on every view's front.",
                universal
                    .iter()
                    .map(|(t, _)| format!("`{t}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                if universal.len() == 1 { "is" } else { "are" }
            ));
        }
        for (t, k) in counts.iter().take(6) {
            lines.push(format!("`{t}`: on {k} of {views} fronts"));
        }
        lines
    }
}

fn labels(cells: &[&Cell]) -> String {
    cells
        .iter()
        .map(|c| format!("`{}`", c.view().label()))
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{:.1} MiB", b as f64 / (1 << 20) as f64)
    } else if b >= 1 << 10 {
        format!("{:.1} KiB", b as f64 / 1024.0)
    } else {
        format!("{b} B")
    }
}

fn mark(k: &Criterion, mine: &[&Cell]) -> Mark {
    let tested: Vec<&Cell> = mine.iter().copied().filter(|c| (k.applies)(c)).collect();
    let worst = tested
        .iter()
        .copied()
        .max_by(|a, b| (k.figure)(a).total_cmp(&(k.figure)(b)));
    Mark {
        criterion: k.name,
        ok: worst.map(|_| tested.iter().all(|c| (k.passes)(c))),
        claim: worst.map(|w| {
            let v = (k.figure)(w);
            Claim::of(
                format!("worst {} on `{}`", k.unit.format(v), w.view().label()),
                w,
            )
        }),
    }
}

/// The family's declared capabilities, and each one its measurements
/// contradict (declared but failed, or not declared yet passed).
fn extensibility(caps: &Capabilities, marks: &[Mark]) -> Vec<Claim> {
    let declared: Vec<(&Criterion, &Mark, bool)> = CRITERIA
        .iter()
        .zip(marks)
        .filter_map(|(k, m)| Some((k, m, (k.declared?)(caps))))
        .collect();
    let names: Vec<&str> = declared
        .iter()
        .filter(|(_, _, d)| *d)
        .map(|(k, _, _)| k.name)
        .collect();
    let mut out = vec![Claim::plain(if names.is_empty() {
        "declares nothing".into()
    } else {
        format!("declares {}", names.join(", "))
    })];
    for (k, m, d) in declared {
        if let (Some(ok), Some(c)) = (m.ok, &m.claim)
            && ok != d
        {
            out.push(Claim {
                text: format!(
                    "{} {}, yet measured {}: {}",
                    k.name,
                    if d { "declared" } else { "not declared" },
                    if ok { "✔" } else { "✗" },
                    c.text
                ),
                evidence: c.evidence.clone(),
            });
        }
    }
    out
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
