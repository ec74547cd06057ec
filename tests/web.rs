//! The browser build in a real browser: `out/web/` (built by
//! `scripts/web.sh`, which the test command runs first) served on
//! 127.0.0.1 and opened in headless Chromium with WebGPU, driven over its
//! DevTools protocol by `tools/web-check.mjs`. The pages' `compare=1`
//! reports, the native build's masks of the same frames, a screenshot, and
//! a bad file opened in the page.

mod common;

use common::gpu;
use shadowlab::headless::{self, HeadlessFrame};
use shadowlab::web::query::PageArgs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Most pixels whose visibility differs by more than [`SAME_WITHIN`]
/// between the page and the native build, in % of the drawn pixels (the
/// issue's bar).
const MAX_DISAGREEMENT_PCT: f64 = 0.05;

/// Visibilities this close count as the same. A depth bias is rounded as
/// the implementation defines (WebGPU and Vulkan give its unit, the
/// minimum resolvable difference, per format, not the rounding), so where
/// a filter kernel straddles a surface's own terminator SwiftShader and
/// lavapipe differ by up to 0.2 on values near ½: the same grey, which a
/// threshold at ½ would split into a mismatch.
const SAME_WITHIN: f32 = 0.25;

/// Failure demonstrations of 8-bit depth, whose false shadows fall where
/// depth rounds to the same byte as its occluder's: a pattern of rounding
/// that two rasterisers reproduce only in the large (1.6 % and 0.18 % of
/// the pixels differ on columns/sun). Printed, not bounded.
const ROUNDING_DEMONSTRATIONS: [&str; 2] = ["shadow-map:8bit", "projective:alpha-depth"];

/// What the check printed for one page.
#[derive(serde::Deserialize)]
struct PageReport {
    query: String,
    title: String,
    screenshot: PathBuf,
    mask: Option<String>,
    eval: Option<serde_json::Value>,
}

impl PageReport {
    fn assert_ok(&self) {
        assert!(
            self.title.starts_with("shadowlab: ok "),
            "{}: {}",
            self.query,
            self.title
        );
    }
}

/// Opens `queries` in one Chromium and returns their reports.
fn open_pages(out: &Path, queries: &[String]) -> Vec<PageReport> {
    open_pages_with(out, queries, None)
}

/// [`open_pages`], running the JavaScript expression `eval` (awaited) in
/// each page once its title has settled.
fn open_pages_with(out: &Path, queries: &[String], eval: Option<&str>) -> Vec<PageReport> {
    assert!(
        Path::new("out/web/shadowlab_bg.wasm").is_file(),
        "out/web/ is missing: run `bash scripts/web.sh` (scripts/test.sh runs it before the tests)"
    );
    let mut node = Command::new("node");
    if let Some(e) = eval {
        node.env("WEB_CHECK_EVAL", e);
    }
    let run = node
        .arg("--experimental-websocket")
        .arg("tools/web-check.mjs")
        .arg(out)
        .args(queries)
        .output()
        .expect("node runs (scripts/setup.sh --test installs it)");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "web-check failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let reports: Vec<PageReport> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert_eq!(reports.len(), queries.len(), "{stdout}");
    reports
}

/// A field `name=value` of a page's title.
fn title_field<'a>(title: &'a str, name: &str) -> Option<&'a str> {
    title
        .split(' ')
        .find_map(|w| w.strip_prefix(name)?.strip_prefix('='))
}

fn pairs(query: &str) -> Vec<(String, String)> {
    query
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// The native build's mask of the first light and the drawn pixels, for
/// the frame a page's `query` asks for (the page's own parser reads it).
fn native_mask(query: &str) -> (Vec<f32>, Vec<bool>) {
    let args = PageArgs::from_pairs(&pairs(query)).unwrap();
    let (scene, camera, lights) = args.view.resolve().unwrap();
    let choice = args.choice().unwrap();
    let (w, h) = args.view.size;
    let choices = vec![choice; lights.len().max(1)];
    let mut hf = HeadlessFrame::new(gpu(), &scene, &choices, w, h).unwrap();
    hf.render(gpu(), &scene, &camera, &lights, &args.view.settings())
        .unwrap();
    let img = headless::read_back(gpu(), &hf.frame, lights.len()).unwrap();
    (img.masks[0].clone(), img.coverage)
}

/// % of drawn pixels where the page's mask (bytes, 255 = lit) and the
/// native one differ by more than [`SAME_WITHIN`].
fn disagreement_pct(page: &[u8], native: &[f32], drawn: &[bool]) -> f64 {
    assert_eq!(page.len(), native.len());
    let (mut n, mut differ) = (0usize, 0usize);
    for ((&p, &v), &d) in page.iter().zip(native).zip(drawn) {
        if d {
            n += 1;
            differ += ((p as f32 / 255.0 - v).abs() > SAME_WITHIN) as usize;
        }
    }
    100.0 * differ as f64 / n.max(1) as f64
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("shadowlab-web-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The issue's two links report `ok` with a mismatch ≤ 0.05 %, and the
/// screenshot shows the frame (many distinct greys, not one colour).
#[test]
fn the_bar_links_compare_with_the_reference_in_the_page() {
    let out = tmpdir("bar");
    let queries = [
        "scene=room&light=point&technique=shadow-map:pcf&compare=1".to_string(),
        "scene=columns&light=sun&technique=shadow-volume:zfail&compare=1".to_string(),
    ];
    for r in open_pages(&out, &queries) {
        r.assert_ok();
        let mismatch: f64 = title_field(&r.title, "mismatch")
            .and_then(|m| m.strip_suffix('%'))
            .and_then(|m| m.parse().ok())
            .unwrap_or_else(|| panic!("{}", r.title));
        assert!(mismatch <= 0.05, "{}: {}", r.query, r.title);
        let fps: f64 = title_field(&r.title, "fps").unwrap().parse().unwrap();
        assert!(fps > 0.0, "{}", r.title);
        let shot = image::open(&r.screenshot).unwrap().to_rgb8();
        // The canvas (640×360 at the page's top left): a rendered frame has
        // many distinct colours; a blank or failed canvas has a few.
        let mut colours: Vec<[u8; 3]> = (20..360)
            .step_by(4)
            .flat_map(|y| (20..640).step_by(4).map(move |x| (x, y)))
            .map(|(x, y)| shot.get_pixel(x, y).0)
            .collect();
        colours.sort();
        colours.dedup();
        assert!(
            colours.len() > 100,
            "{}: {} colours",
            r.query,
            colours.len()
        );
    }
}

/// For the same frame, the page's mask equals the native build's within
/// 0.05 % of the drawn pixels, for every preset under the sun and for each
/// family's default under a point light (every preset runs in the page;
/// only the reference itself is not offered there, the page running it),
/// but the [`ROUNDING_DEMONSTRATIONS`].
#[test]
fn the_pages_masks_equal_the_native_builds() {
    let out = tmpdir("masks");
    let presets: Vec<String> = shadowlab::technique::preset_ids()
        .into_iter()
        .filter(|id| !id.starts_with("raytraced"))
        .collect();
    let mut queries: Vec<String> = presets
        .iter()
        .map(|p| format!("scene=columns&light=sun&technique={p}&size=320x180&compare=1"))
        .collect();
    for family in [
        "planar",
        "projective",
        "shadow-map",
        "shadow-volume",
        "irregular",
    ] {
        queries.push(format!(
            "scene=room&light=point&technique={family}&size=320x180&compare=1"
        ));
    }
    let mut worst = (0.0, String::new());
    for r in open_pages(&out, &queries) {
        r.assert_ok();
        use base64::Engine as _;
        let page = base64::engine::general_purpose::STANDARD
            .decode(r.mask.as_deref().expect("a compare=1 page's mask"))
            .unwrap();
        let (native, drawn) = native_mask(&r.query);
        let d = disagreement_pct(&page, &native, &drawn);
        eprintln!("{:>8.4} %  {}", d, r.query);
        if ROUNDING_DEMONSTRATIONS.iter().any(|t| r.query.contains(t)) {
            continue;
        }
        if d > worst.0 {
            worst = (d, r.query.clone());
        }
    }
    assert!(
        worst.0 <= MAX_DISAGREEMENT_PCT,
        "page and native masks differ on {:.4} % of the pixels of {}",
        worst.0,
        worst.1
    );
}

/// A bad URL parameter and a malformed file opened in the page are errors
/// in the page's title, not hangs.
#[test]
fn bad_input_in_the_page_is_a_stated_error() {
    let out = tmpdir("bad");
    let bad_file = out.join("broken.glb");
    std::fs::write(&bad_file, b"glTF\x02\x00\x00\x00garbage").unwrap();
    let queries = [
        "scene=room&technique=shadow-map:pcf&set=size=3".to_string(),
        "scene=nowhere".to_string(),
        format!("drop:{}?scene=room&size=160x90", bad_file.display()),
    ];
    let reports = open_pages(&out, &queries);
    assert!(
        reports[0].title.contains("error") && reports[0].title.contains("size"),
        "{}",
        reports[0].title
    );
    assert!(
        reports[1].title.contains("error") && reports[1].title.contains("nowhere"),
        "{}",
        reports[1].title
    );
    assert!(
        reports[2].title.starts_with("shadowlab: error") && reports[2].title.contains("broken.glb"),
        "{}",
        reports[2].title
    );
}

/// The page's panels: a technique for one light only, a light moved in the
/// light table, the mask view; the link then says it cannot name the view.
#[test]
fn the_panels_change_one_light_and_show_its_mask() {
    let out = tmpdir("panels");
    let script = r#"(async () => {
        const $ = (id) => document.getElementById(id);
        $('scope').value = '0';
        $('scope').onchange();
        $('technique').value = 'shadow-volume:zfail';
        await $('technique').onchange();
        const position = document.querySelector('#lights tbody input');
        position.value = '1,4.5,1';
        position.onchange();
        $('mask').click();
        await new Promise((r) => setTimeout(r, 1500));
        let link;
        try { link = shadowlab.link(); } catch (e) { link = String(e); }
        return { technique: JSON.parse(shadowlab.parameters(0)).technique,
                 light: JSON.parse(shadowlab.lights())[0].position, link,
                 status: $('status').textContent };
    })()"#;
    let r = &open_pages_with(
        &out,
        &["scene=room&light=point&size=320x180".to_string()],
        Some(script),
    )[0];
    r.assert_ok();
    let e = r.eval.as_ref().expect("the script's result");
    assert_eq!(e["technique"], "shadow-volume:zfail", "{e}");
    let position: Vec<f64> = serde_json::from_value(e["light"].clone()).unwrap();
    assert_eq!(position, [1.0, 4.5, 1.0], "{e}");
    assert!(
        e["link"].as_str().unwrap().contains("a light was changed"),
        "{e}"
    );
    assert!(
        e["status"].as_str().unwrap().contains("FPS"),
        "the frames go on: {e}"
    );
    // The mask view: black shadows on a white, lit room (mostly white).
    let shot = image::open(&r.screenshot).unwrap().to_rgb8();
    let (mut white, mut black, mut n) = (0, 0, 0);
    for y in (20..180).step_by(2) {
        for x in (20..320).step_by(2) {
            let p = shot.get_pixel(x, y).0;
            n += 1;
            white += p.iter().all(|&c| c > 240) as usize;
            black += p.iter().all(|&c| c < 15) as usize;
        }
    }
    assert!(
        white * 2 > n && black > n / 50,
        "white {white}, black {black} of {n}"
    );
}
