//! The instruments: `compare` (quality against the ray-traced reference),
//! `bench` (frame and pass timings, ratios to `none`), flicker along camera
//! paths, and the soak (memory and frame-time drift over many frames).

#[cfg(not(target_arch = "wasm32"))]
pub mod bench;
#[cfg(not(target_arch = "wasm32"))]
pub mod compare;
#[cfg(not(target_arch = "wasm32"))]
pub mod flicker;
pub mod quality;
#[cfg(not(target_arch = "wasm32"))]
pub mod soak;

use crate::scene::{Camera, Light, Scene};
use crate::technique::{self, TechniqueChoice};
use anyhow::{Result, bail};

/// One frame to render: the scene, the camera, the lights and the size.
#[derive(Clone, Copy)]
pub struct FrameRequest<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub lights: &'a [Light],
    pub size: (u32, u32),
}

/// `part` as a percentage of `whole` (0 when `whole` is 0).
pub fn percent(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        0.0
    } else {
        100.0 * part as f64 / whole as f64
    }
}

/// The `q`-quantile (0 to 1) of ascending `sorted` values, nearest rank:
/// the value at index round((n − 1)·q). `sorted` must not be empty.
pub fn percentile<T: Copy>(sorted: &[T], q: f64) -> T {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

#[cfg(not(target_arch = "wasm32"))]
/// A progress bar of `len` steps drawn with `template` (indicatif's), or a
/// hidden one when `show` is false (a caller that draws its own).
pub fn progress_bar(show: bool, len: u64, template: &str) -> indicatif::ProgressBar {
    let bar = if show {
        indicatif::ProgressBar::new(len)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar
}

/// Parses a technique list: `all`, or comma-separated ids, each optionally
/// with parameter values in brackets: `none,raytraced:reference[samples=64]`.
/// `all` is every preset of every family except the reference itself.
pub fn parse_technique_list(spec: &str) -> Result<Vec<TechniqueChoice>> {
    if spec.trim() == "all" {
        return technique::preset_ids()
            .iter()
            .map(|id| technique::resolve(id))
            .filter(|c| c.as_ref().map_or(true, |c| c.family.id != "raytraced"))
            .collect();
    }
    let mut items = vec![];
    let (mut depth, mut start) = (0i32, 0usize);
    for (i, c) in spec.char_indices() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&spec[start..i]);
                start = i + 1;
            }
            _ => {}
        }
        if depth < 0 {
            bail!("unbalanced ']' in technique list '{spec}'");
        }
    }
    if depth != 0 {
        bail!("unbalanced '[' in technique list '{spec}'");
    }
    items.push(&spec[start..]);
    items
        .into_iter()
        .map(|item| {
            if item.trim().is_empty() {
                bail!("empty entry in technique list '{spec}'");
            }
            technique::parse_choice(item)
        })
        .collect()
}

/// Whether `t` gives each pixel the covered fraction of several sub-pixel
/// samples (`pixel_samples` above 1, `irregular:subpixel`): a point-sampled
/// reference charges it for the edges it resolves.
pub fn is_sub_pixel(t: &TechniqueChoice) -> bool {
    t.params
        .get(crate::technique::raytraced::PIXEL_SAMPLES.name)
        .is_ok_and(|n| n > 1.0)
}

/// A label for a technique choice: its id plus any parameter that differs
/// from the preset, e.g. `raytraced:default[samples=64]`.
pub fn choice_label(c: &TechniqueChoice) -> String {
    let preset = technique::resolve(&c.id()).expect("a resolved id resolves again");
    let diffs: Vec<String> = c
        .params
        .specs
        .iter()
        .zip(c.params.values.iter().zip(&preset.params.values))
        .filter(|(_, (a, b))| a != b)
        .map(|(s, (a, _))| format!("{}={}", s.name, s.format(*a)))
        .collect();
    if diffs.is_empty() {
        c.id()
    } else {
        format!("{}[{}]", c.id(), diffs.join(","))
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// Writes a CSV file through the `csv` crate, which quotes fields such as
/// the label `x[a=1,b=2]`.
pub fn write_csv(
    path: &std::path::Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<String>>,
) -> Result<()> {
    use anyhow::Context;
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("writing {}", path.display()))?;
    w.write_record(header)?;
    for r in rows {
        w.write_record(&r)?;
    }
    w.flush()?;
    Ok(())
}

/// A file-name-safe form of a label.
pub fn file_stem(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn technique_lists_parse_with_parameters() {
        let l =
            parse_technique_list("none, raytraced:reference[samples=64,offset_ulps=100]").unwrap();
        assert_eq!(l.len(), 2);
        assert_eq!(l[1].params.get("samples").unwrap(), 64.0);
        assert_eq!(
            choice_label(&l[1]),
            "raytraced:reference[samples=64,offset_ulps=100]"
        );
        assert_eq!(choice_label(&l[0]), "none:default");
        assert!(parse_technique_list("none,,raytraced").is_err());
        assert!(parse_technique_list("none[").is_err());
        assert!(
            parse_technique_list("bogus")
                .err()
                .unwrap()
                .to_string()
                .contains("valid")
        );
        assert!(parse_technique_list("raytraced[samples=0]").is_err());
        let all = parse_technique_list("all").unwrap();
        assert!(all.iter().all(|c| c.family.id != "raytraced") && !all.is_empty());
        assert_eq!(file_stem("a:b[c=1]"), "a_b_c_1_");
    }
}
