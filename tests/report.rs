//! `shadowlab report` on a tiny matrix: every registered preset appears,
//! the HTML shows the figures of `results.csv`, a second run reuses every
//! cell, a changed parameter recomputes only its own cells, and the page
//! opens in headless Chromium with its tables and charts drawn.

mod common;

use common::{gpu, tmpdir};
use shadowlab::measure::{self, bench::BenchFrames};
use shadowlab::report::{self, matrix::Matrix, matrix::View};
use std::path::Path;

fn tiny(techniques: &str) -> Matrix {
    let mut m = Matrix::of(
        report::matrix::ReportPreset::Quick,
        Some(&["teapot".to_string()]),
        Some(techniques),
    )
    .unwrap();
    m.views = vec![View::new("teapot", "default", "point")];
    m.size = (96, 54);
    m.bench = BenchFrames {
        warmup: 0,
        measured: 1,
        progress: false,
        max_seconds: None,
    };
    m
}

/// The text of each `<td>` of the HTML results table, row by row.
fn html_results(html: &str) -> Vec<Vec<String>> {
    let table = html
        .split("<table id=\"results-table\">")
        .nth(1)
        .expect("a results table")
        .split("</table>")
        .next()
        .unwrap();
    let body = table.split("<tbody>").nth(1).unwrap();
    body.split("<tr")
        .skip(1)
        .map(|row| {
            row.split("<td")
                .skip(1)
                .map(|td| {
                    let text = td.split_once('>').unwrap().1.split("</td>").next().unwrap();
                    text.replace("&gt;", ">")
                        .replace("&lt;", "<")
                        .replace("&quot;", "\"")
                        .replace("&amp;", "&")
                })
                .collect()
        })
        .collect()
}

fn csv_results(dir: &Path) -> Vec<Vec<String>> {
    csv::Reader::from_path(dir.join("results.csv"))
        .unwrap()
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect()
}

#[test]
fn the_report_covers_every_preset_shows_the_csv_and_resumes() {
    let out = tmpdir("report-all");
    let all = tiny("none");
    let every = report::matrix::every_preset().unwrap();
    let matrix = Matrix {
        techniques: every.clone(),
        ..all
    };
    let first = report::run(gpu(), &matrix, &out, false).unwrap();
    assert_eq!(first.computed, every.len());
    for f in [
        "index.html",
        "report.md",
        "results.csv",
        "results.json",
        "charts/view-0.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for t in &every {
        let label = measure::choice_label(t);
        assert!(
            html.contains(&format!("<code>{label}</code>")),
            "{label} not in the HTML"
        );
        assert!(
            md.contains(&format!("`{label}`")),
            "{label} not in report.md"
        );
    }
    // Self-contained: images embedded, nothing fetched.
    assert!(html.contains("src=\"data:image/jpeg;base64,") && !html.contains("src=\"http"));
    assert!(html.contains("<svg"), "inline charts");
    let csv = csv_results(&out);
    assert_eq!(csv.len(), every.len());
    assert_eq!(html_results(&html), csv, "the HTML table shows results.csv");
    // The summary table's claims come from those rows: z-pass is exact
    // here (the camera is not in a shadow), `none` misses every shadow.
    let none = csv.iter().find(|r| r[3] == "none:default").unwrap();
    let total: f64 = none[5].parse().unwrap();
    assert!(total > 1.0, "none misses the teapot's shadow: {total}");
    assert!(md.contains(&format!(
        "{} % mismatch on `teapot/default/point`",
        report::criteria::pct(total)
    )));

    // Sub-pixel presets are measured against the supersampled reference,
    // in each view's `sub-pixel/` folder, and the report says so.
    assert!(
        md.contains("(sub-pixel presets against `raytraced:default[pixel_samples=32]`"),
        "{}",
        &md[..md.len().min(800)]
    );
    // Every preset is bounded relative to the shadow `none` misses: the
    // references exact, shadow volumes within 5 % of it, the other
    // families within a quarter, and the failure
    // demonstrations that fail on this view beyond a share of it: 8-bit
    // depth, the far plane clipping z-fail's volumes and the darkening
    // composition (a lit image cannot show it) over half; silhouette
    // volumes of the open teapot (what per-triangle volumes fix) over 2 %.
    const FAILING_HERE: [(&str, f64); 5] = [
        ("shadow-map:8bit", 0.5),
        ("shadow-volume:zfail-far-clip", 0.5),
        ("planar:darken", 0.5),
        ("shadow-volume:darken", 0.5),
        ("shadow-volume:edges", 0.02),
    ];
    let mut out_of_bounds = vec![];
    for row in &csv {
        let (label, t): (&str, f64) = (&row[3], row[5].parse().unwrap());
        let share = t / total;
        let failing = FAILING_HERE.iter().find(|(l, _)| *l == label);
        let ok = if let Some((_, least)) = failing {
            share > *least
        } else if label.starts_with("raytraced:") {
            // The references measured against themselves: the point-sampled
            // one, and the supersampled one of the sub-pixel presets.
            t == 0.0
        } else if label.starts_with("shadow-volume:") {
            share <= 0.05
        } else if label.starts_with("none:") {
            true
        } else {
            share <= 0.25
        };
        if !ok {
            out_of_bounds.push(format!(
                "{label}: {t:.3} % ({:.1} % of none's)",
                share * 100.0
            ));
        }
    }
    assert!(
        out_of_bounds.is_empty(),
        "out of bounds: {out_of_bounds:#?}"
    );

    // A second run measures nothing.
    let second = report::run(gpu(), &matrix, &out, false).unwrap();
    assert_eq!((second.computed, second.reused), (0, every.len()));
    // One changed parameter: only its cell is measured again.
    let mut changed = matrix.clone();
    let pcf = every
        .iter()
        .position(|t| t.id() == "shadow-map:pcf")
        .unwrap();
    changed.techniques[pcf] = measure::parse_technique_list("shadow-map:pcf[depth_bias=7]")
        .unwrap()
        .remove(0);
    let third = report::run(gpu(), &changed, &out, false).unwrap();
    assert_eq!((third.computed, third.reused), (1, every.len() - 1));
}

/// The page in a real browser: headless Chromium's screenshot of its top
/// shows text, the tables' rules and the charts' red front, not a blank page.
#[test]
fn the_html_report_renders_in_chromium() {
    let out = tmpdir("report-browser");
    let mut matrix = tiny("none,planar,shadow-volume,shadow-map[size=256]");
    matrix.flicker = Some((measure::flicker::CameraPath::Strafe, 2));
    report::run(gpu(), &matrix, &out, false).unwrap();
    // Flicker measured for every cell; exact shadow volumes do not flicker.
    let csv = csv_results(&out);
    let flicker = shadowlab::report::cells::COLUMNS
        .iter()
        .position(|c| *c == "flicker_pct")
        .unwrap();
    assert!(csv.iter().all(|r| !r[flicker].is_empty()), "{csv:?}");
    let volumes = csv.iter().find(|r| r[3] == "shadow-volume:auto").unwrap();
    assert_eq!(volumes[flicker].parse::<f64>().unwrap(), 0.0);
    let shot = out.join("shot.png");
    let page = format!(
        "file://{}",
        out.join("index.html").canonicalize().unwrap().display()
    );
    let status = std::process::Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--window-size=1200,1100",
            &format!("--screenshot={}", shot.display()),
            &page,
        ])
        .output()
        .expect("chromium runs (scripts/setup.sh --test installs it)");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let img = image::open(&shot).unwrap().to_rgb8();
    let px = img.pixels().count() as f64;
    let ink = img
        .pixels()
        .filter(|p| p.0.iter().all(|&c| c < 128))
        .count() as f64;
    let red = img
        .pixels()
        .filter(|p| p.0[0] > 200 && p.0[1] < 60 && p.0[2] < 60)
        .count();
    let grey_rules = img
        .pixels()
        .filter(|p| p.0.iter().all(|&c| (190..=215).contains(&c)))
        .count() as f64;
    assert!(
        ink / px > 0.01,
        "text: {:.4} of the pixels are dark",
        ink / px
    );
    // At least one front point (a red disc of radius 5 drawn at ¾ scale).
    assert!(red > 30, "the Pareto front in red: {red} pixels");
    assert!(
        grey_rules / px > 0.002,
        "table borders: {:.4}",
        grey_rules / px
    );
}

/// `shadowlab report` stopped in the middle of a view (killed as soon as
/// the first technique's `compare` rows are kept): the next run reuses
/// those rows, leaves their images untouched and measures the rest.
#[test]
fn a_run_stopped_mid_view_keeps_the_measured_cells() {
    let out = tmpdir("report-stopped");
    let args = [
        "report",
        "--scenes",
        "teapot",
        "--techniques",
        "shadow-map:pcf,shadow-volume:auto,shadow-map:csm",
        "--out",
    ];
    let bin = env!("CARGO_BIN_EXE_shadowlab");
    let files = |ext: &str| -> Vec<std::path::PathBuf> {
        let mut found = vec![];
        for view in std::fs::read_dir(out.join("cells")).into_iter().flatten() {
            for f in std::fs::read_dir(view.unwrap().path()).unwrap() {
                let p = f.unwrap().path();
                if p.to_string_lossy().ends_with(ext) {
                    found.push(p);
                }
            }
        }
        found
    };
    let mut child = std::process::Command::new(bin)
        .args(args)
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while files(".quality.json").is_empty() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before keeping any rows"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = files(".quality.json");
    let cells = files(".json").len() - kept.len();
    assert_eq!(cells, 0, "stopped before the first view's bench");
    let image = |q: &std::path::Path| {
        let png = q.to_string_lossy().replace(".quality.json", ".png");
        std::fs::metadata(png).unwrap().modified().unwrap()
    };
    let before: Vec<_> = kept.iter().map(|q| image(q)).collect();
    let o = std::process::Command::new(bin)
        .args(args)
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains(&format!(
            "9 cells measured ({} from the compare rows a stopped run kept), 0 reused",
            kept.len()
        )),
        "{stdout}"
    );
    let after: Vec<_> = kept.iter().map(|q| image(q)).collect();
    assert_eq!(before, after, "kept cells' images not rendered again");
}
