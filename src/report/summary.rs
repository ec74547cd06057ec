//! The documents' summary table ([001] §5.2), filled from measurements: per
//! technique preset its quality, cost, advantages, disadvantages, use,
//! implementation difficulty, extensibility and ✔/✗ marks
//! ([`super::criteria`]), every claim a measured figure with the cell it
//! comes from; each view's Pareto front of error against cost
//! ([`super::pareto`]); and the computed answer to "is there one universal
//! technique?".

use super::cells::Cell;
use super::criteria::{
    CHEAP_RATIO, Claim, EXACT_INTERIOR_MAE, Mark, below_failure, extensibility, interior_exact,
    marks, pct, total,
};
use super::matrix::{Matrix, View};
use super::pareto::{competes, pareto_front};
use crate::technique::FAMILIES;

include!(concat!(env!("OUT_DIR"), "/family_lines.rs"));

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

/// Everything the report pages show.
pub struct Report<'a> {
    pub matrix: &'a Matrix,
    /// The adapter that measured every cost: name, type and backend.
    pub adapter: String,
    /// The adapter is a CPU rasterizer (its times rank as a CPU's).
    pub cpu_adapter: bool,
    pub cells: &'a [Cell],
    /// Per view, the indices (into `cells`) of its Pareto front.
    pub fronts: Vec<(View, Vec<usize>)>,
    pub rows: Vec<SummaryRow>,
    pub universal: Vec<String>,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

impl<'a> Report<'a> {
    pub fn new(
        matrix: &'a Matrix,
        cells: &'a [Cell],
        adapter: String,
        cpu_adapter: bool,
    ) -> Report<'a> {
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
            adapter,
            cpu_adapter,
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
        // Work per pixel where the adapter counts it, beside the times.
        let work: Option<Vec<f64>> = mine.iter().map(|c| c.cost.mask_fragments_per_px).collect();
        let work = work.map_or(String::new(), |w| {
            format!(", {:.1} mask fragments per pixel (median)", median(w))
        });
        let cost = match dearest {
            Some(d) => Claim::of(
                format!(
                    "median ×{ratio:.2} the frame of `none`, mask stage median {:.1} ms (wall, CPU work included){work}; at most ×{:.2} on `{}`; {} of shadow resources",
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
        let advantages = self.advantages(&on_front, &mine);
        let disadvantages = disadvantages(&mine, dearest);
        let usage = self.usage(technique, &on_front, &mine);
        let difficulty = FAMILY_LINES
            .iter()
            .find(|(id, _, _)| *id == family_id)
            .map_or(String::new(), |(_, rs, wgsl)| {
                format!("{rs} lines of Rust, {wgsl} of WGSL (family `{family_id}`)")
            });
        let marks = marks(&mine);
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

    /// What a preset does well: the Pareto fronts it is on, the views where
    /// it is exact, else its best view.
    fn advantages(&self, on_front: &[&'a Cell], mine: &[&'a Cell]) -> Vec<Claim> {
        let mut advantages = vec![];
        if !on_front.is_empty() {
            advantages.push(Claim::of(
                format!(
                    "on the error/cost Pareto front of {} of {} views: {}",
                    on_front.len(),
                    self.fronts.len(),
                    labels(on_front)
                ),
                on_front[0],
            ));
        }
        let exact: Vec<&Cell> = mine
            .iter()
            .copied()
            .filter(|c| total(c) <= 0.01 && interior_exact(c))
            .collect();
        if !exact.is_empty() {
            advantages.push(Claim::of(
                format!(
                    "exact (≤ 0.01 % mismatch, interior MAE ≤ {EXACT_INTERIOR_MAE}) on {}",
                    labels(&exact)
                ),
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
        advantages
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

fn bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{:.1} MiB", b as f64 / (1 << 20) as f64)
    } else if b >= 1 << 10 {
        format!("{:.1} KiB", b as f64 / 1024.0)
    } else {
        format!("{b} B")
    }
}
/// What a preset does badly: its two worst failures, by kind, and its
/// cost where it is not cheap.
fn disadvantages(mine: &[&Cell], dearest: Option<&Cell>) -> Vec<Claim> {
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
    disadvantages
}
