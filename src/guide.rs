//! The user guide's generated figures (the hidden `shadowlab guide-figures`):
//! each technique family's failure case is rendered, measured against the
//! reference and written as an image and a Markdown caption with its
//! measured figures, which the chapters include. So no figure in the guide
//! is typed by hand, and a change that moves one shows in the diff.

use crate::gpu::GpuContext;
use crate::measure::compare::{self, QualityRow};
use crate::measure::{self, FrameRequest};
use crate::scene::builtin;
use anyhow::{Context, Result, anyhow};
use image::{Rgba, RgbaImage, imageops};
use std::fmt::Write as _;
use std::path::Path;

/// One failure case: the view, the technique that fails, the one that
/// does not on the same frame, and the figure's file name
/// (`images/failure-NAME.png`, `generated/failure-NAME.md`).
struct FailureCase {
    name: &'static str,
    scene: &'static str,
    camera: &'static str,
    light: &'static str,
    failing: &'static str,
    contrast: &'static str,
}

const CASES: &[FailureCase] = &[
    FailureCase {
        name: "8bit",
        scene: "teapot",
        camera: "default",
        light: "sun",
        failing: "shadow-map:8bit",
        contrast: "shadow-map:pcf",
    },
    FailureCase {
        name: "hard-staircase",
        scene: "city",
        camera: "street",
        light: "spot",
        failing: "shadow-map:hard",
        contrast: "shadow-map:pcf",
    },
    FailureCase {
        name: "planar-curved",
        scene: "curved",
        camera: "default",
        light: "sun",
        failing: "planar:default",
        contrast: "shadow-map:pcf",
    },
    FailureCase {
        name: "projective-self",
        scene: "bunny",
        camera: "default",
        light: "spot",
        failing: "projective:default",
        contrast: "projective:alpha-depth",
    },
    FailureCase {
        name: "vsm-bleeding",
        scene: "foliage",
        camera: "eye-level",
        light: "spot",
        failing: "shadow-map:vsm",
        contrast: "shadow-map:pcf",
    },
    FailureCase {
        name: "volume-cutouts",
        scene: "foliage",
        camera: "eye-level",
        light: "sun",
        failing: "shadow-volume:auto",
        contrast: "irregular:default",
    },
    FailureCase {
        name: "zpass",
        scene: "columns",
        camera: "in-shadow",
        light: "sun",
        failing: "shadow-volume:zpass",
        contrast: "shadow-volume:auto",
    },
];

/// The frames' size; the figure shows each image at half of it.
const SIZE: (u32, u32) = (640, 360);
/// White pixels between the figure's three images.
const GAP: u32 = 4;

/// Renders every failure case and writes its figure and caption under
/// `book_src` (the guide's `src/`).
pub fn write_figures(gpu: &GpuContext, book_src: &Path) -> Result<()> {
    let images = book_src.join("images");
    let captions = book_src.join("generated");
    for dir in [&images, &captions] {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let work = std::env::temp_dir().join(format!("shadowlab-guide-{}", std::process::id()));
    for case in CASES {
        let out = work.join(case.name);
        let rows = measure_case(gpu, case, &out)?;
        let stem = measure::file_stem(case.failing);
        let figure = side_by_side(&[
            out.join(format!("{stem}.png")),
            out.join(format!("heatmap-{stem}.png")),
            out.join("reference").join("image.png"),
        ])?;
        let image = images.join(format!("failure-{}.png", case.name));
        figure
            .save(&image)
            .with_context(|| format!("writing {}", image.display()))?;
        let caption = caption(case, &rows, &gpu.adapter_summary());
        let page = captions.join(format!("failure-{}.md", case.name));
        std::fs::write(&page, caption).with_context(|| format!("writing {}", page.display()))?;
        println!("wrote {} and {}", image.display(), page.display());
    }
    std::fs::remove_dir_all(&work).ok();
    Ok(())
}

/// The case's two techniques measured against the ray-traced reference.
fn measure_case(gpu: &GpuContext, case: &FailureCase, out: &Path) -> Result<Vec<QualityRow>> {
    let scene = builtin::by_name(case.scene)?.ok_or_else(|| {
        anyhow!(
            "guide figure {}: no built-in scene {}",
            case.name,
            case.scene
        )
    })?;
    let camera = scene.camera_preset(case.camera)?;
    let lights = scene.light_preset(case.light)?;
    let techniques = measure::parse_technique_list(&format!("{},{}", case.failing, case.contrast))?;
    let reference = crate::technique::resolve("raytraced")?;
    let view = FrameRequest {
        scene: &scene,
        camera: &camera,
        lights: &lights,
        size: SIZE,
    };
    compare::run(gpu, view, &techniques, &reference, out)
}

/// The images at `paths`, each at half size, in a row with white gaps.
fn side_by_side(paths: &[std::path::PathBuf]) -> Result<RgbaImage> {
    let (w, h) = (SIZE.0 / 2, SIZE.1 / 2);
    let n = paths.len() as u32;
    let mut figure = RgbaImage::from_pixel(n * w + (n - 1) * GAP, h, Rgba([255; 4]));
    for (i, path) in paths.iter().enumerate() {
        let img = image::open(path)
            .with_context(|| format!("reading {}", path.display()))?
            .to_rgba8();
        let half = imageops::resize(&img, w, h, imageops::FilterType::Triangle);
        imageops::replace(&mut figure, &half, (i as u32 * (w + GAP)) as i64, 0);
    }
    Ok(figure)
}

/// The figure's Markdown: the image, what it shows and how it was made,
/// and the two techniques' measured mismatch.
fn caption(case: &FailureCase, rows: &[QualityRow], adapter: &str) -> String {
    let row = |id: &str| rows.iter().find(|r| r.technique == id && r.light == 0);
    let mut md = format!(
        "<!-- generated by `shadowlab guide-figures` (scripts/book.sh --figures); do not edit -->\n\
         ![{failing} on {scene}/{camera}/{light}](../images/failure-{name}.png)\n\n\
         *Left: `{failing}`; middle: its error against the reference (red: false shadow, \
         blue: false lit); right: the ray-traced reference. `shadowlab compare --scene {scene} \
         --camera {camera} --light {light}` at {w}×{h} on {adapter}, shown at half size.*",
        failing = case.failing,
        scene = case.scene,
        camera = case.camera,
        light = case.light,
        name = case.name,
        w = SIZE.0,
        h = SIZE.1,
    );
    if let Some(r) = row(case.failing) {
        let m = &r.mask.all;
        let _ = write!(
            md,
            " `{}`: {:.1} % false shadow, {:.1} % false lit, {:.1} % of the pixels wrong",
            case.failing, m.false_shadow_pct, m.false_lit_pct, m.total_pct
        );
    }
    if let Some(r) = row(case.contrast) {
        let _ = write!(
            md,
            "; `{}` on the same frame: {:.3} %",
            case.contrast, r.mask.all.total_pct
        );
    }
    md.push_str(".\n");
    md
}
