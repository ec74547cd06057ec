//! What a report measures: the views (scene, camera preset, light preset),
//! the frame size, the benchmark's frame counts and the technique presets.

use crate::measure;
use crate::scene;
use crate::technique::{self, TechniqueChoice};
use anyhow::{Result, bail};

/// The size of the matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ReportPreset {
    /// Six views chosen to show each family's strengths and failure cases, 640×360.
    Quick,
    /// Every built-in scene's default camera under each of its light presets, 1280×720.
    Standard,
    /// Every camera preset under every light preset, 1280×720.
    Full,
}

/// One frame of the matrix.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct View {
    pub scene: String,
    pub camera: String,
    pub light: String,
}

impl View {
    pub fn new(scene: &str, camera: &str, light: &str) -> View {
        View {
            scene: scene.into(),
            camera: camera.into(),
            light: light.into(),
        }
    }

    /// `scene/camera/light`.
    pub fn label(&self) -> String {
        format!("{}/{}/{}", self.scene, self.camera, self.light)
    }
}

/// Everything a report measures.
#[derive(Clone)]
pub struct Matrix {
    pub views: Vec<View>,
    pub size: (u32, u32),
    pub bench: measure::bench::BenchFrames,
    pub techniques: Vec<TechniqueChoice>,
    pub reference: TechniqueChoice,
    /// Flicker along this camera path over this many frames (`compare
    /// --path`); `quick` leaves it out.
    pub flicker: Option<(measure::flicker::CameraPath, u32)>,
}

/// The quick preset's views: a point light over a colonnade (z-fail's
/// open-volume and far-plane failures), the camera inside the roof's shadow
/// (z-pass's failure), a room, an open mesh under a spot, curved receivers
/// 2 km of landscape seen from the ground (perspective aliasing: the
/// warped and partitioned maps) and the see-through casters of `foliage`. The million-triangle city (a second a
/// frame on lavapipe for several families) is left to `standard`, so that
/// `quick` stays within 7 minutes on a 2-core machine without a GPU.
const QUICK_VIEWS: [(&str, &str, &str); 7] = [
    ("columns", "default", "point"),
    ("columns", "in-shadow", "sun"),
    ("room", "default", "point"),
    ("bunny", "default", "spot"),
    ("curved", "default", "sun"),
    ("landscape", "ground", "sun-side"),
    ("foliage", "eye-level", "spot"),
];

/// A technique's benchmark stops after this many seconds (at least one
/// measured frame): the 1024-sample reference takes minutes a frame on a
/// CPU.
pub const MAX_BENCH_SECONDS: f64 = 5.0;
/// Frames along the strafe path for the flicker measure (`standard`, `full`).
pub const FLICKER_FRAMES: u32 = 3;

/// The same for `quick`, which times 1 + 3 frames per technique.
pub const QUICK_BENCH_SECONDS: f64 = 2.0;

/// Presets the quick report leaves to `standard`: the adaptive map refines
/// its first frame in up to `refine_steps` read-back passes (nine on the
/// landscape), which on lavapipe makes its cells twice as slow as the
/// virtual map's (about 35 s of the quick report's time).
const LEFT_TO_STANDARD: [&str; 1] = ["shadow-map:adaptive"];

/// Every registered preset of every family, the reference's too.
pub fn every_preset() -> Result<Vec<TechniqueChoice>> {
    technique::preset_ids()
        .iter()
        .map(|id| technique::resolve(id))
        .collect()
}

impl Matrix {
    /// The reference a technique is measured against: the matrix's, or for
    /// a `sub_pixel` one (`measure::is_sub_pixel`) the matrix's supersampled
    /// to the most sub-pixel samples (`raytraced:subpixel`), as issue 52
    /// scores them, where the reference has that parameter.
    pub fn reference(&self, sub_pixel: bool) -> TechniqueChoice {
        let mut reference = self.reference.clone();
        if sub_pixel {
            let samples = crate::technique::raytraced::PIXEL_SAMPLES;
            if reference
                .params
                .set_value(samples.name, samples.max)
                .is_err()
            {
                return self.reference.clone();
            }
        }
        reference
    }

    /// The references, as the report's header names them: the matrix's,
    /// and the supersampled one where it measures sub-pixel techniques.
    pub fn references_label(&self) -> String {
        let main = crate::measure::choice_label(&self.reference);
        if self.techniques.iter().any(measure::is_sub_pixel) {
            format!(
                "`{main}` (sub-pixel presets against `{}`, in each view's `sub-pixel/`)",
                crate::measure::choice_label(&self.reference(true))
            )
        } else {
            format!("`{main}`")
        }
    }

    /// The matrix of `preset`, restricted to `scenes` when given, over
    /// `techniques` (a technique list, default every preset).
    pub fn of(
        preset: ReportPreset,
        scenes: Option<&[String]>,
        techniques: Option<&str>,
    ) -> Result<Matrix> {
        let mut views = vec![];
        match preset {
            ReportPreset::Quick => {
                views.extend(QUICK_VIEWS.iter().map(|(s, c, l)| View::new(s, c, l)));
            }
            ReportPreset::Standard | ReportPreset::Full => {
                for name in scene::builtin::NAMES {
                    let s = scene::builtin::by_name(name)?.expect("a built-in scene");
                    let cameras: Vec<&str> = match preset {
                        ReportPreset::Full => {
                            s.camera_presets.iter().map(|c| c.0.as_str()).collect()
                        }
                        _ => vec![s.camera_presets[0].0.as_str()],
                    };
                    for c in cameras {
                        for (l, _) in &s.light_presets {
                            views.push(View::new(name, c, l));
                        }
                    }
                }
            }
        }
        if let Some(names) = scenes {
            for n in names {
                if !views.iter().any(|v| &v.scene == n) {
                    let known: Vec<&str> = scene::builtin::NAMES.to_vec();
                    if !known.contains(&n.as_str()) {
                        bail!("unknown scene '{n}' (built-in: {})", known.join(", "));
                    }
                    // A scene outside the preset's views: its default
                    // camera under each of its lights.
                    let s = scene::builtin::by_name(n)?.expect("a built-in scene");
                    for (l, _) in &s.light_presets {
                        views.push(View::new(n, &s.camera_presets[0].0, l));
                    }
                }
            }
            views.retain(|v| names.contains(&v.scene));
        }
        let (size, bench) = match preset {
            ReportPreset::Quick => (
                (640, 360),
                measure::bench::BenchFrames {
                    warmup: 1,
                    measured: 3,
                    progress: false,
                    max_seconds: Some(QUICK_BENCH_SECONDS),
                },
            ),
            _ => (
                (1280, 720),
                measure::bench::BenchFrames {
                    warmup: 3,
                    measured: 10,
                    progress: false,
                    max_seconds: Some(MAX_BENCH_SECONDS),
                },
            ),
        };
        let techniques = match techniques {
            Some(list) => measure::parse_technique_list(list)?,
            None => {
                let mut all = every_preset()?;
                if preset == ReportPreset::Quick {
                    all.retain(|t| !LEFT_TO_STANDARD.contains(&t.id().as_str()));
                }
                all
            }
        };
        let flicker = (preset != ReportPreset::Quick)
            .then_some((measure::flicker::CameraPath::Strafe, FLICKER_FRAMES));
        Ok(Matrix {
            views,
            size,
            bench,
            techniques,
            reference: technique::resolve("raytraced")?,
            flicker,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::FAMILIES;

    /// Sub-pixel presets are measured against the reference supersampled
    /// to 32 samples a pixel; every other preset against the reference.
    #[test]
    fn sub_pixel_presets_get_the_supersampled_reference() {
        let m = Matrix::of(ReportPreset::Quick, None, None).unwrap();
        let samples = |id: &str| {
            let t = technique::resolve(id).unwrap();
            let reference = m.reference(measure::is_sub_pixel(&t));
            reference.params.get("pixel_samples").unwrap()
        };
        assert_eq!(samples("irregular:subpixel"), 32.0);
        assert_eq!(samples("raytraced:subpixel"), 32.0);
        assert_eq!(samples("irregular:default"), 1.0);
        assert_eq!(samples("shadow-map:pcf"), 1.0);
    }

    #[test]
    fn presets_grow_and_scenes_filter() {
        let quick = Matrix::of(ReportPreset::Quick, None, None).unwrap();
        let standard = Matrix::of(ReportPreset::Standard, None, None).unwrap();
        let full = Matrix::of(ReportPreset::Full, None, None).unwrap();
        assert_eq!(quick.views.len(), QUICK_VIEWS.len());
        assert!(
            quick.views.len() < standard.views.len() && standard.views.len() < full.views.len()
        );
        // Every preset of every family, the reference's included; quick
        // without those it leaves to standard.
        let count: usize = FAMILIES.iter().map(|f| f.presets.len()).sum();
        assert_eq!(standard.techniques.len(), count);
        assert_eq!(quick.techniques.len(), count - LEFT_TO_STANDARD.len());
        assert!(
            standard
                .techniques
                .iter()
                .any(|t| t.id() == "shadow-map:adaptive")
                && !quick
                    .techniques
                    .iter()
                    .any(|t| t.id() == "shadow-map:adaptive")
        );
        let only =
            Matrix::of(ReportPreset::Quick, Some(&["columns".into()]), Some("none")).unwrap();
        assert!(only.views.iter().all(|v| v.scene == "columns") && only.views.len() == 2);
        assert_eq!(only.techniques.len(), 1);
        // A scene outside the quick views comes with its lights.
        let floating = Matrix::of(ReportPreset::Quick, Some(&["floating".into()]), None).unwrap();
        assert!(floating.views.iter().any(|v| v.light == "area"));
        assert!(Matrix::of(ReportPreset::Quick, Some(&["nowhere".into()]), None).is_err());
    }
}
