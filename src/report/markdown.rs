//! `report.md`: the summary table, the universal-technique answer, each
//! view's Pareto front (its chart is `charts/view-N.svg`) and every cell.

use super::cells::{COLUMNS, SOURCE_VERSION, csv_row};
use super::criteria::Claim;
use super::summary::Report;
use std::fmt::Write as _;

fn cell_text(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

fn claim(c: &Claim) -> String {
    match &c.evidence {
        Some(a) => format!("{} [→](#{a})", cell_text(&c.text)),
        None => cell_text(&c.text),
    }
}

fn claims(cs: &[Claim]) -> String {
    if cs.is_empty() {
        "–".into()
    } else {
        cs.iter().map(claim).collect::<Vec<_>>().join("; ")
    }
}

/// The file name of view `i`'s chart beside `report.md`.
pub fn chart_name(i: usize) -> String {
    format!("charts/view-{i}.svg")
}

/// What the report says of its adapter, at the top and under every table.
pub fn adapter_note(report: &Report) -> String {
    let mut s = format!("Costs measured on **{}**", report.adapter);
    if report.cpu_adapter {
        s += ", a CPU rasterizer: its times rank techniques as a CPU does (filling pixels is cheap beside a GPU's, depth-only passes are not), so read cost from the work columns (fragment and compute invocations per pixel, the same on any adapter) before the times";
    }
    s + "."
}

pub fn write(report: &Report) -> String {
    let m = report.matrix;
    let adapter = adapter_note(report);
    let mut s = format!(
        "# shadowlab: every shadow technique, measured\n\n{adapter}\n\n{} technique presets × {} views at {} × {}, against {}; shadowlab {}. Mismatch: % of the pixels that receive shadows and face the light whose shadow state differs from the reference; cost: frame time × `none` in the same run, and the mask stage's invocations per pixel. `index.html` shows the same with charts and images.\n\n## Is there one universal technique?\n\n",
        m.techniques.len(),
        m.views.len(),
        m.size.0,
        m.size.1,
        m.references_label(),
        SOURCE_VERSION
    );
    for (i, line) in report.universal.iter().enumerate() {
        if i == 0 {
            let _ = writeln!(s, "**{line}**\n");
        } else {
            let _ = writeln!(s, "- {line}");
        }
    }
    s += "\n## Summary\n\n| technique | quality | cost | advantages | disadvantages | use | implementation difficulty | extensibility |";
    let criteria: Vec<&str> = report
        .rows
        .first()
        .map(|r| r.marks.iter().map(|k| k.criterion).collect())
        .unwrap_or_default();
    for c in &criteria {
        let _ = write!(s, " {c} |");
    }
    s += "\n|---|---|---|---|---|---|---|---|";
    s += &"---|".repeat(criteria.len());
    s += "\n";
    for r in &report.rows {
        let _ = write!(
            s,
            "| `{}` | {} | {} | {} | {} | {} | {} | {} |",
            r.technique,
            claim(&r.quality),
            claim(&r.cost),
            claims(&r.advantages),
            claims(&r.disadvantages),
            claims(&r.usage),
            cell_text(&r.difficulty),
            claims(&r.extensibility)
        );
        for k in &r.marks {
            let sym = match k.ok {
                Some(true) => "✔",
                Some(false) => "✗",
                None => "–",
            };
            let _ = write!(s, " {sym} |");
        }
        s += "\n";
    }
    let _ = write!(s, "\n*{adapter}*\n");
    s += "\n## Views\n\n";
    for (i, (view, front)) in report.fronts.iter().enumerate() {
        let names: Vec<String> = front
            .iter()
            .map(|&k| format!("`{}`", report.cells[k].technique()))
            .collect();
        let _ = writeln!(
            s,
            "### {}\n\n![error against cost]({})\n\nPareto front: {}\n",
            view.label(),
            chart_name(i),
            names.join(" → ")
        );
    }
    s += "## Every cell\n\n|";
    for c in COLUMNS {
        let _ = write!(s, " {c} |");
    }
    s += "\n|";
    s += &"---|".repeat(COLUMNS.len());
    s += "\n";
    for c in report.cells {
        let _ = write!(s, "| <a id=\"{}\"></a>", c.anchor());
        let values: Vec<String> = csv_row(c).iter().map(|v| cell_text(v)).collect();
        s += &values.join(" | ");
        s += " |\n";
    }
    let _ = write!(s, "\n*{adapter}*\n");
    s
}
