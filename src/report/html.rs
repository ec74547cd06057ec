//! `index.html`: one self-contained page — the summary table, the answer to
//! "one universal technique?", per view its error/cost chart (inline SVG)
//! and a gallery of images and heatmaps (embedded JPEG thumbnails that
//! enlarge on click), and every cell's figures as in `results.csv`.

use super::cells::{COLUMNS, Cell, SOURCE_VERSION, csv_row};
use super::charts;
use super::criteria::{Claim, EXACT_INTERIOR_MAE, FAILED_PCT, ungraded};
use super::pareto::competes;
use super::summary::Report;
use anyhow::Result;
use base64::Engine;
use std::fmt::Write as _;
use std::path::Path;

/// Width of the embedded images (their frames are scaled to it).
const THUMB_WIDTH: u32 = 400;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline code spans (`x`) of a claim's text as <code>.
fn text(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in esc(s).split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{part}</code>");
        } else {
            out += part;
        }
    }
    out
}

fn claim(c: &Claim) -> String {
    match &c.evidence {
        Some(a) => format!("{} <a class=\"ev\" href=\"#{a}\">[row]</a>", text(&c.text)),
        None => text(&c.text),
    }
}

fn claims(cs: &[Claim]) -> String {
    if cs.is_empty() {
        return "–".into();
    }
    let items: String = cs
        .iter()
        .map(|c| format!("<li>{}</li>", claim(c)))
        .collect();
    format!("<ul>{items}</ul>")
}

/// A PNG of the report's folder as an embedded JPEG `<img>`, or a note.
fn embedded(root: &Path, rel: &str, alt: &str) -> String {
    let img = match image::open(root.join(rel)) {
        Ok(i) => i,
        Err(_) => return format!("<span class=\"missing\">{} missing</span>", esc(rel)),
    };
    let h = (img.height() * THUMB_WIDTH / img.width().max(1)).max(1);
    let small = img
        .resize_exact(THUMB_WIDTH, h, image::imageops::FilterType::Triangle)
        .to_rgb8();
    let mut jpeg = vec![];
    let encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 80);
    if small.write_with_encoder(encoder).is_err() {
        return format!("<span class=\"missing\">{} unreadable</span>", esc(rel));
    }
    format!(
        "<img class=\"thumb\" alt=\"{}\" title=\"{}\" onclick=\"this.classList.toggle('big')\" src=\"data:image/jpeg;base64,{}\">",
        esc(alt),
        esc(alt),
        base64::engine::general_purpose::STANDARD.encode(&jpeg)
    )
}

const STYLE: &str = "body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;max-width:1800px}
h1{margin-top:0}table{border-collapse:collapse;margin:8px 0 24px}td,th{border:1px solid #ccc;padding:4px 6px;vertical-align:top}
th{background:#eee;position:sticky;top:0}td.num{text-align:right;font-variant-numeric:tabular-nums}
ul{margin:0;padding-left:16px}code{background:#f3f3f3;padding:0 2px}.ok{color:#080;font-weight:bold}.no{color:#c00;font-weight:bold}
.thumb{width:200px;cursor:zoom-in;border:1px solid #aaa}.thumb.big{width:800px;cursor:zoom-out}
.charts{display:flex;flex-wrap:wrap;gap:8px}.chart svg{width:540px;height:315px}
.gallery{display:flex;flex-wrap:wrap;gap:10px}.gallery figure{margin:0}figcaption{font-size:12px;max-width:200px;overflow-wrap:anywhere}
a.ev{font-size:11px}tr:target{background:#ffd}.summary td{min-width:90px}.answer{background:#eef6ff;padding:8px 16px;border-left:4px solid #36c}";

pub fn write(report: &Report, root: &Path) -> Result<String> {
    let m = report.matrix;
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>shadowlab report</title><style>{STYLE}</style></head><body>\
         <h1>shadowlab: every shadow technique, measured</h1>\
         <p class=\"answer\">{}</p>\
         <p>{} technique presets × {} views at {} × {}, against {}. Mismatch = pixels whose shadow state (visibility at 0.5) differs from the reference, in % of the pixels that receive shadows and face the light; cost = frame time as a multiple of <code>none</code> measured in the same run, and the mask stage's invocations per pixel. shadowlab {}.</p>",
        esc(&super::markdown::adapter_note(report).replace("**", "")),
        m.techniques.len(),
        m.views.len(),
        m.size.0,
        m.size.1,
        esc(&m.references_label()).replace('`', ""),
        esc(SOURCE_VERSION)
    );
    h += "<h2 id=\"universal\">Is there one universal technique?</h2><div class=\"answer\">";
    for (i, line) in report.universal.iter().enumerate() {
        if i == 0 {
            let _ = write!(h, "<p><b>{}</b></p><ul>", text(line));
        } else {
            let _ = write!(h, "<li>{}</li>", text(line));
        }
    }
    h += "</ul></div>";
    best_per_view(&mut h, report);
    h +=
        "<h2 id=\"charts\">Error against cost (the Pareto front in red)</h2><div class=\"charts\">";
    for i in 0..report.fronts.len() {
        let _ = write!(
            h,
            "<div class=\"chart\">{}</div>",
            charts::pareto_svg(report, i)?
        );
    }
    h += "</div>";
    summary_table(&mut h, report);
    h += "<h2 id=\"views\">Per view: the images and error heatmaps</h2>";
    for (i, (view, _)) in report.fronts.iter().enumerate() {
        let _ = write!(
            h,
            "<h3 id=\"view-{i}\">{}</h3><div class=\"gallery\">",
            esc(&view.label())
        );
        let view_cells: Vec<&Cell> = report.cells.iter().filter(|c| c.view() == *view).collect();
        if let Some(c) = view_cells.first() {
            let reference = format!(
                "{}/reference/image.png",
                c.image.rsplit_once('/').map_or("", |p| p.0)
            );
            let _ = write!(
                h,
                "<figure>{}<figcaption>reference</figcaption></figure>",
                embedded(root, &reference, "reference")
            );
        }
        for c in view_cells {
            let _ = write!(
                h,
                "<figure>{}{}<figcaption><a href=\"#{}\">{}</a>: {:.3} %, ×{:.2}</figcaption></figure>",
                embedded(root, &c.image, c.technique()),
                embedded(root, &c.heatmap, &format!("{} heatmap", c.technique())),
                c.anchor(),
                esc(c.technique()),
                c.quality.total_pct,
                c.cost.ratio_to_none
            );
        }
        h += "</div>";
    }
    h += "<h2 id=\"results\">Every cell (as in results.csv)</h2><table id=\"results-table\"><thead><tr>";
    for c in COLUMNS {
        let _ = write!(h, "<th>{c}</th>");
    }
    h += "</tr></thead><tbody>";
    for c in report.cells {
        let _ = write!(h, "<tr id=\"{}\">", c.anchor());
        for (i, v) in csv_row(c).into_iter().enumerate() {
            let class = if i >= 5 && i < COLUMNS.len() - 1 {
                " class=\"num\""
            } else {
                ""
            };
            let _ = write!(h, "<td{class}>{}</td>", esc(&v));
        }
        h += "</tr>";
    }
    h += "</tbody></table></body></html>\n";
    Ok(h)
}

/// Per view: the lowest mismatch, the cheapest preset under the failure
/// threshold, and the Pareto front.
fn best_per_view(h: &mut String, report: &Report) {
    *h += &format!(
        "<h2 id=\"best\">Best per view</h2><table><thead><tr><th>view</th><th>lowest mismatch (among interior MAE ≤ {EXACT_INTERIOR_MAE} where any)</th><th>cheapest under 1 % mismatch</th><th>Pareto front (cheap → exact)</th></tr></thead><tbody>"
    );
    for (view, front) in &report.fronts {
        let competing: Vec<&Cell> = report
            .cells
            .iter()
            .filter(|c| c.view() == *view && competes(c))
            .collect();
        // The best is the lowest mismatch among the ungraded, when any is.
        let ungraded: Vec<&Cell> = competing.iter().copied().filter(|c| ungraded(c)).collect();
        let pool = if ungraded.is_empty() {
            &competing
        } else {
            &ungraded
        };
        let best = pool
            .iter()
            .min_by(|a, b| a.quality.total_pct.total_cmp(&b.quality.total_pct));
        let cheapest = competing
            .iter()
            .filter(|c| c.quality.total_pct <= FAILED_PCT)
            .min_by(|a, b| a.cost.ratio_to_none.total_cmp(&b.cost.ratio_to_none));
        let show = |c: Option<&&Cell>| {
            c.map_or("–".to_string(), |c| {
                format!(
                    "<a href=\"#{}\"><code>{}</code></a> {:.3} %, ×{:.2}",
                    c.anchor(),
                    esc(c.technique()),
                    c.quality.total_pct,
                    c.cost.ratio_to_none
                )
            })
        };
        let names: Vec<String> = front
            .iter()
            .map(|&k| format!("<code>{}</code>", esc(report.cells[k].technique())))
            .collect();
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&view.label()),
            show(best),
            show(cheapest),
            names.join(" → ")
        );
    }
    *h += "</tbody></table>";
}

fn summary_table(h: &mut String, report: &Report) {
    *h += "<h2 id=\"summary\">Summary (the documents' comparison, filled from measurements)</h2>\
           <table class=\"summary\"><thead><tr><th>technique</th><th>quality</th><th>cost</th><th>advantages</th><th>disadvantages</th><th>use</th><th>implementation difficulty</th><th>extensibility</th>";
    let criteria: Vec<&str> = report
        .rows
        .first()
        .map(|r| r.marks.iter().map(|m| m.criterion).collect())
        .unwrap_or_default();
    for c in &criteria {
        let _ = write!(h, "<th>{}</th>", esc(c));
    }
    *h += "</tr></thead><tbody>";
    for r in &report.rows {
        let _ = write!(
            h,
            "<tr><td><code>{}</code><br><small>{}</small></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
            esc(&r.technique),
            esc(&r.description),
            claim(&r.quality),
            claim(&r.cost),
            claims(&r.advantages),
            claims(&r.disadvantages),
            claims(&r.usage),
            esc(&r.difficulty),
            claims(&r.extensibility)
        );
        for m in &r.marks {
            let (sym, class) = match m.ok {
                Some(true) => ("✔", "ok"),
                Some(false) => ("✗", "no"),
                None => ("–", ""),
            };
            let title = m.claim.as_ref().map_or(String::new(), |c| esc(&c.text));
            let link = m
                .claim
                .as_ref()
                .and_then(|c| c.evidence.as_ref())
                .map_or(String::new(), |a| {
                    format!(" <a class=\"ev\" href=\"#{a}\">[row]</a>")
                });
            let _ = write!(
                h,
                "<td class=\"{class}\" title=\"{title}\">{sym}{link}</td>"
            );
        }
        *h += "</tr>";
    }
    *h += "</tbody></table>";
}
