//! The command line (clap): `scenes`, `techniques`, `export`, `render`,
//! `compare`, `bench`, `report`, `view` and the hidden `cli-markdown` (the
//! guide's CLI reference) and `guide-figures` (its failure figures); each
//! command parses its arguments and calls the library.

use crate::args::ViewArgs;
use crate::headless::{self, FrameRecord, HeadlessFrame};
use crate::measure;
use crate::scene;
use crate::technique::{self, TechniqueChoice};
use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "shadowlab",
    version,
    about = "Real-time shadow rendering lab: every classic shadow technique, measured against a ray-traced ground truth"
)]
pub struct Cli {
    /// Also write log messages (warnings, errors such as a malformed scene) to this file.
    #[arg(long, global = true, value_name = "FILE")]
    pub log_file: Option<PathBuf>,
    /// More log output (-v info, -vv debug).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// List the built-in scenes with their camera and light presets.
    Scenes,
    /// List technique families, presets and every parameter (default, min, max, doc).
    Techniques(TechniquesArgs),
    /// Write a scene as glTF 2.0 (world space, KHR_lights_punctual, camera, shadow flags in extras).
    Export(ExportArgs),
    /// Render one frame headless: DIR/image.png, DIR/visibility-N.png, DIR/frame.json.
    Render(Box<RenderArgs>),
    /// Measure techniques against the ray-traced reference on one frame:
    /// mismatch, visibility error, FLIP, heatmaps (DIR/quality.{md,csv,json}).
    Compare(Box<CompareArgs>),
    /// Time techniques on one frame: median/p5/p95 per pass, ratio to `none`
    /// (DIR/bench.{md,csv,json}).
    Bench(Box<BenchArgs>),
    /// The comparison: every technique preset on a matrix of views, against
    /// the reference and `none` (DIR/index.html, report.md, results.{csv,json});
    /// resumable: cells already in DIR are reused.
    Report(ReportArgs),
    /// Interactive viewer: switch and tune techniques, move camera and lights.
    View(Box<ViewCmdArgs>),
    /// The command-line reference as Markdown (the guide's CLI page).
    #[command(hide = true)]
    CliMarkdown,
    /// Renders the guide's failure figures and their captions into DIR
    /// (images/failure-*.png, generated/failure-*.md).
    #[command(hide = true)]
    GuideFigures {
        #[arg(long, default_value = "docs/book/src")]
        out: std::path::PathBuf,
    },
}

#[derive(Args)]
pub struct TechniquesArgs {
    /// Markdown tables (the guide's parameter pages) instead of text.
    #[arg(long)]
    pub markdown: bool,
}

#[derive(Args)]
pub struct ReportArgs {
    /// Size of the matrix: quick (7 views, 640×360), standard (every
    /// scene's default camera under each light preset, 1280×720), full
    /// (every camera preset too).
    #[arg(long, value_enum, default_value = "quick")]
    pub preset: crate::report::matrix::ReportPreset,
    /// Only these built-in scenes (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub scenes: Option<Vec<String>>,
    /// Technique list (as `compare --techniques`); default every registered preset.
    #[arg(long)]
    pub techniques: Option<String>,
    /// Output directory (its cells are reused by the next run).
    #[arg(long, default_value = "out/report")]
    pub out: PathBuf,
    /// Graphics backend (vulkan, metal, dx12); default: WGPU_BACKEND or all.
    #[arg(long)]
    pub backend: Option<String>,
}

#[derive(Args)]
pub struct ViewCmdArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Technique id for every light (family or family:preset).
    #[arg(long, default_value = "none")]
    pub technique: String,
    /// Set a technique parameter, key=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Save a screenshot (PNG, and its frame description as .json beside it) after --frames frames, then exit.
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// Render this many frames, then exit (with --screenshot: save it first).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: Option<u32>,
    /// Present without vsync.
    #[arg(long)]
    pub no_vsync: bool,
    /// Compute the error heatmap against raytraced at start-up (on a
    /// background thread); with --frames, exit once it is shown.
    #[arg(long)]
    pub heatmap: bool,
    /// Start with the technique debug views on (light frusta, depth map).
    #[arg(long)]
    pub debug_views: bool,
    /// Start showing light N's visibility mask in grey instead of the image
    /// (the M key toggles it). Lights count from 0 everywhere: the viewer's
    /// labels, `visibility-N.png`, the `light` column of compare and bench.
    #[arg(long, value_name = "N")]
    pub mask: Option<usize>,
    /// Start moving the camera along this path, one step per frame (the
    /// steps of `compare --path`), to watch shadows shimmer or stay put.
    #[arg(long, value_enum)]
    pub camera_path: Option<measure::flicker::CameraPath>,
}

#[derive(Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Comma-separated technique ids (optionally `id[key=value,...]`), or `all`.
    #[arg(long, default_value = "none")]
    pub techniques: String,
    /// The reference technique.
    #[arg(long, default_value = "raytraced")]
    pub reference: String,
    /// Output directory.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Measure flicker instead: follow this camera path for `--frames`
    /// frames (DIR/flicker.{md,csv,json}).
    #[arg(long, value_enum)]
    pub path: Option<measure::flicker::CameraPath>,
    /// Frames along `--path` (2 to 1000).
    #[arg(long, default_value_t = 5)]
    pub frames: u32,
}

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Comma-separated technique ids (optionally `id[key=value,...]`), or `all`; `none` is always measured.
    #[arg(long, default_value = "none")]
    pub techniques: String,
    /// Measured frames per technique.
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Warm-up frames per technique (not measured).
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Soak instead: render each technique for this many seconds (and at
    /// least --frames frames) with the camera orbiting, and report resident
    /// memory, live GPU objects and frame-time drift (DIR/soak.{md,json}).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub soak: Option<f64>,
    /// Output directory.
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
}

/// A finite, non-negative number of seconds.
fn parse_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!(
            "'{s}' is not a finite, non-negative number of seconds"
        )),
    }
}

#[derive(Args)]
pub struct ExportArgs {
    /// Built-in scene name or a scene file (.obj, .gltf, .glb, .toml).
    #[arg(long, default_value = "room")]
    pub scene: String,
    /// Output .gltf path (a .bin buffer is written beside it).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Technique id: family or family:preset (see `shadowlab techniques`).
    #[arg(long, default_value = "none")]
    pub technique: String,
    /// Set a technique parameter, key=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Render this many frames (the first compiles shaders) and report the
    /// median frame time; the last frame is written.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
}

/// Resolves a technique id (with optional `[key=value,...]`) and applies
/// `--set` values.
pub fn technique_choice(id: &str, set: &[String]) -> Result<TechniqueChoice> {
    let mut c = technique::parse_choice(id)?;
    technique::apply_settings(&mut c.params, set)?;
    Ok(c)
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Scenes => scenes(),
        Command::Techniques(a) => {
            if a.markdown {
                print!("{}", technique::listing::markdown());
            } else {
                print!("{}", technique::listing::text());
            }
            Ok(())
        }
        Command::CliMarkdown => {
            print!("{}", clap_markdown::help_markdown::<Cli>());
            Ok(())
        }
        Command::GuideFigures { out } => {
            crate::guide::write_figures(&crate::gpu::GpuContext::new(None)?, &out)
        }
        Command::Export(a) => {
            let s = scene::load(&a.scene)?;
            s.warn_default_light();
            scene::gltf_io::export(&s, &a.out)?;
            println!(
                "wrote {} ({} objects, {} triangles, {} lights)",
                a.out.display(),
                s.objects.len(),
                s.triangle_count(),
                s.lights.len()
            );
            Ok(())
        }
        Command::Render(a) => render(*a),
        Command::Compare(a) => compare(*a),
        Command::Bench(a) => bench(*a),
        Command::Report(a) => report(a),
        Command::View(a) => view(*a),
    }
}

#[cfg(feature = "viewer")]
fn view(a: ViewCmdArgs) -> Result<()> {
    crate::viewer::run(crate::viewer::ViewerOptions {
        view: a.view,
        technique: a.technique,
        set: a.set,
        screenshot: a.screenshot,
        frames: a.frames,
        vsync: !a.no_vsync,
        heatmap: a.heatmap,
        debug_views: a.debug_views,
        mask: a.mask,
        camera_path: a.camera_path,
    })
}

#[cfg(not(feature = "viewer"))]
fn view(_: ViewCmdArgs) -> Result<()> {
    anyhow::bail!(
        "this build has no viewer (built with --no-default-features, as scripts/demo.sh does); \
         build it with `cargo build --release`"
    )
}

fn scenes() -> Result<()> {
    println!("{:<10} {:>10}  description", "scene", "triangles");
    for (name, desc) in scene::builtin::NAMES
        .iter()
        .zip(scene::builtin::DESCRIPTIONS)
    {
        let s = scene::builtin::by_name(name)?.expect("built-in scene");
        println!("{:<10} {:>10}  {}", name, s.triangle_count(), desc);
        let cams: Vec<&str> = s.camera_presets.iter().map(|c| c.0.as_str()).collect();
        let lights: Vec<String> = s
            .light_presets
            .iter()
            .map(|(n, l)| {
                format!(
                    "{n} ({})",
                    l.iter()
                        .map(|l| format!("{:?}", l.kind).to_lowercase())
                        .collect::<Vec<_>>()
                        .join("+")
                )
            })
            .collect();
        println!("{:<22}cameras: {}", "", cams.join(", "));
        println!("{:<22}lights:  {}", "", lights.join(", "));
    }
    Ok(())
}

fn compare(a: CompareArgs) -> Result<()> {
    let (scene, camera, lights) = a.view.resolve()?;
    let techniques = measure::parse_technique_list(&a.techniques)?;
    let reference = measure::parse_technique_list(&a.reference)?;
    let [reference] = reference.as_slice() else {
        bail!("--reference takes one technique, got '{}'", a.reference);
    };
    if !measure::is_sub_pixel(reference) {
        for t in techniques.iter().filter(|t| measure::is_sub_pixel(t)) {
            log::warn!(
                "{} gives each pixel its covered fraction, which a reference sampling pixel centres ({}) counts as mismatch at every edge: measure it with --reference raytraced:subpixel (as `report` does)",
                measure::choice_label(t),
                measure::choice_label(reference)
            );
        }
    }
    let gpu = a.view.gpu()?;
    let view = measure::FrameRequest {
        scene: &scene,
        camera: &camera,
        lights: &lights,
        size: a.view.size,
    };
    if let Some(path) = a.path {
        let rows =
            measure::flicker::run(&gpu, view, &techniques, reference, path, a.frames, &a.out)?;
        println!(
            "{:<44} {:>5} {:>10} {:>10}",
            "technique", "light", "flicker%", "edge%"
        );
        for r in &rows {
            println!(
                "{:<44} {:>5} {:>10.4} {:>10.4}",
                r.technique, r.light, r.flicker_pct, r.edge_flicker_pct
            );
        }
        println!("wrote {}", a.out.join("flicker.md").display());
        return Ok(());
    }
    let rows = measure::compare::run(&gpu, view, &techniques, reference, &a.out)?;
    println!(
        "{:<36} {:>5} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "technique",
        "light",
        "false-sh%",
        "false-lit%",
        "total%",
        "MAE",
        "int.MAE",
        "graded%",
        "frac.MAE",
        "FLIP"
    );
    for r in &rows {
        println!(
            "{:<36} {:>5} {:>9.3} {:>9.3} {:>9.3} {:>8.4} {:>8.4} {:>8.2} {:>8} {:>8.4}",
            r.technique,
            r.light,
            r.mask.all.false_shadow_pct,
            r.mask.all.false_lit_pct,
            r.mask.all.total_pct,
            r.mask.mean_abs_error,
            r.mask.interior_mae,
            r.mask.graded_interior_pct,
            r.mask
                .fractional_mae
                .map_or("–".to_string(), |e| format!("{e:.4}")),
            r.flip.mean
        );
    }
    println!("wrote {}", a.out.join("quality.md").display());
    Ok(())
}

fn bench(a: BenchArgs) -> Result<()> {
    let (scene, camera, lights) = a.view.resolve()?;
    let techniques = measure::parse_technique_list(&a.techniques)?;
    let gpu = a.view.gpu()?;
    println!("adapter: {}", gpu.adapter_summary());
    let view = measure::FrameRequest {
        scene: &scene,
        camera: &camera,
        lights: &lights,
        size: a.view.size,
    };
    if let Some(seconds) = a.soak {
        return soak(&a, &gpu, view, &techniques, seconds);
    }
    let rows = measure::bench::run(
        &gpu,
        view,
        &a.view.settings(),
        &techniques,
        measure::bench::BenchFrames {
            warmup: a.warmup,
            measured: a.frames,
            progress: true,
            max_seconds: None,
        },
        &a.out,
    )?;
    println!(
        "{:<36} {:>10} {:>10} {:>10} {:>8} {:>12}",
        "technique", "frame ms", "GPU ms", "masks ms", "x none", "p5-p95"
    );
    for r in &rows {
        println!(
            "{:<36} {:>10.2} {:>10} {:>10.2} {:>8.2} {:>12}",
            r.technique,
            r.frame_ms.median,
            r.gpu_frame_ms
                .map_or("-".into(), |s| format!("{:.2}", s.median)),
            r.masks_ms.median,
            r.ratio_to_none,
            format!("{:.2}-{:.2}", r.ratio_spread.0, r.ratio_spread.1)
        );
    }
    println!("wrote {}", a.out.join("bench.md").display());
    Ok(())
}

/// `bench --soak`: each technique soaked in turn, its table printed and
/// written.
fn soak(
    a: &BenchArgs,
    gpu: &crate::gpu::GpuContext,
    view: measure::FrameRequest,
    techniques: &[crate::technique::TechniqueChoice],
    seconds: f64,
) -> Result<()> {
    let length = measure::soak::SoakLength {
        warmup_frames: a.warmup.max(1),
        min_frames: a.frames,
        seconds,
    };
    let rows = measure::soak::run(gpu, view, &a.view.settings(), techniques, length)?;
    let adapter = gpu.adapter_summary();
    print!("{}", measure::soak::markdown(&rows, &adapter));
    measure::soak::write(&a.out, &rows, &adapter, length)?;
    println!("wrote {}", a.out.join("soak.md").display());
    Ok(())
}

fn report(a: ReportArgs) -> Result<()> {
    let started = Instant::now();
    let matrix =
        crate::report::matrix::Matrix::of(a.preset, a.scenes.as_deref(), a.techniques.as_deref())?;
    let gpu = crate::gpu::GpuContext::new(a.backend.as_deref())?;
    let stats = crate::report::run(&gpu, &matrix, &a.out, true)?;
    println!(
        "{}, in {:.0} s; wrote {}",
        stats.counts(),
        started.elapsed().as_secs_f64(),
        a.out.join("index.html").display()
    );
    Ok(())
}

/// The frame after which `render` records the live GPU objects, to
/// compare with those after its last frame (frame.json).
const LIVE_EARLY_FRAME: u32 = 10;

fn render(a: RenderArgs) -> Result<()> {
    let t0 = Instant::now();
    let (scene, camera, lights) = a.view.resolve()?;
    let choice = technique_choice(&a.technique, &a.set)?;
    technique::warn_without_effect(&choice, &a.set, &lights);
    let t_scene = t0.elapsed();
    let gpu = a.view.gpu()?;
    let t_gpu = t0.elapsed() - t_scene;
    let (w, h) = a.view.size;
    let choices = vec![choice; lights.len().max(1)];
    let setup = Instant::now();
    let mut hf = HeadlessFrame::new(&gpu, &scene, &choices, w, h)?;
    let t_setup = setup.elapsed();
    let settings = a.view.settings();
    let mut all = vec![];
    let mut live_early = None;
    for i in 0..a.frames {
        all.push(hf.render(&gpu, &scene, &camera, &lights, &settings)?);
        if i + 1 == LIVE_EARLY_FRAME {
            live_early = Some(crate::gpu::LiveResources::of(&gpu.device));
        }
    }
    let live_last = crate::gpu::LiveResources::of(&gpu.device);
    let first_ms = all[0].total_ms;
    all.sort_by(|x, y| x.total_ms.total_cmp(&y.total_ms));
    let timings = all[all.len() / 2].clone();
    let rb = Instant::now();
    let images = headless::read_back(&gpu, &hf.frame, lights.len())?;
    headless::write_images(&a.out, &images)?;
    let t_write = rb.elapsed();
    let record = FrameRecord {
        scene: &scene,
        scene_gpu: &hf.scene_gpu,
        camera: &camera,
        lights: &lights,
        techniques: hf.techniques.iter().collect(),
        settings: &settings,
        frame: &hf.frame,
        timings: &timings,
        adapter: gpu.adapter_summary(),
        anisotropy: settings.texture_anisotropy(&gpu),
        mip_filter: settings.texture_mip_filter(&gpu),
        extra_timings: serde_json::json!({
            "scene_load": t_scene.as_secs_f64() * 1e3,
            "gpu_init": t_gpu.as_secs_f64() * 1e3,
            "scene_upload_and_pipelines": t_setup.as_secs_f64() * 1e3,
            "readback_and_write": t_write.as_secs_f64() * 1e3,
            "first_frame": first_ms,
            "frames_rendered": a.frames,
            "live_resources": {
                "after_frame_10": live_early,
                "after_last_frame": live_last,
                "pipelines_created": gpu.cache.pipelines_created(),
            },
        }),
    };
    let json = headless::frame_json(&record);
    let path = a.out.join("frame.json");
    std::fs::write(&path, serde_json::to_string_pretty(&json)?)
        .with_context(|| format!("writing {}", path.display()))?;
    println!(
        "{}: {} on {} at {}x{}, {} frame(s), first {:.1} ms, median {:.1} ms (prepass {:.1}, masks {:.1}, lighting {:.1}) -> {}",
        scene.name,
        hf.techniques[0].choice.id(),
        gpu.adapter_summary(),
        w,
        h,
        a.frames,
        first_ms,
        timings.total_ms,
        timings.prepass_ms,
        timings.masks_ms,
        timings.lighting_ms,
        a.out.display()
    );
    for (i, t) in hf.techniques.iter().enumerate().take(lights.len()) {
        let c = t.technique.counters();
        if !c.is_empty() {
            let text: Vec<String> = c.iter().map(|(k, v)| format!("{k} {v:.1}")).collect();
            println!("  light {i}: {}", text.join(", "));
        }
    }
    Ok(())
}
