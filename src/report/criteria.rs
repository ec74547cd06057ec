//! The summary's ✔/✗ criteria ([001] §5.2): which views test each, what
//! passes, and the figure each mark quotes, with the thresholds they use;
//! and the measured statements ([`Claim`]) the summary is made of.

use super::cells::Cell;
use crate::technique::Capabilities;

/// A measured statement and the cell that shows it (its anchor).
#[derive(Clone, Debug)]
pub struct Claim {
    pub text: String,
    pub evidence: Option<String>,
}

impl Claim {
    pub fn of(text: String, cell: &Cell) -> Claim {
        Claim {
            text,
            evidence: Some(cell.anchor()),
        }
    }

    pub fn plain(text: String) -> Claim {
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
/// Interior mean absolute error within which hard shadows count as
/// ungraded (no acne or light bleeding a viewer sees as grey).
pub const EXACT_INTERIOR_MAE: f64 = 0.002;

/// Whether a cell's interior shows no graded error (acne, bleeding).
pub fn ungraded(c: &Cell) -> bool {
    c.quality.interior_mae <= EXACT_INTERIOR_MAE
}

/// Whether a cell's interior error is low enough, graded as well as
/// thresholded, to call its shadows exact.
pub fn interior_exact(c: &Cell) -> bool {
    c.quality.interior_pct <= EXACT_INTERIOR_PCT && ungraded(c)
}
/// Mean absolute visibility error within which soft shadows pass.
pub const SOFT_MAE: f64 = 0.01;
/// Frame time (× `none`) within which a technique counts as cheap.
pub const CHEAP_RATIO: f64 = 2.0;

pub fn total(c: &Cell) -> f64 {
    c.quality.total_pct
}

pub fn below_failure(c: &Cell) -> bool {
    total(c) <= FAILED_PCT
}

/// A view that tests a light type alone: not one of the views kept for
/// another criterion (open meshes, curved receivers, the camera in a
/// shadow, soft shadows).
fn plain_view(c: &Cell, kind: &str) -> bool {
    c.light_kinds.iter().any(|k| k == kind)
        && !c.area_light
        && c.key.camera != "in-shadow"
        && !["bunny", "teapot", "curved", "foliage"].contains(&c.key.scene.as_str())
}

/// Flicker (% of considered pixels per step) within which a technique
/// counts as stable (issue 15's bar).
pub const STABLE_FLICKER_PCT: f64 = 0.01;

const CRITERIA: [Criterion; 12] = [
    Criterion {
        name: "hard shadows exact",
        declared: None,
        applies: |c| !c.area_light,
        passes: |c| c.quality.interior_pct <= EXACT_INTERIOR_PCT,
        figure: |c| c.quality.interior_pct,
        unit: Unit::Percent("interior mismatch"),
    },
    Criterion {
        name: "hard shadows ungraded",
        declared: None,
        applies: |c| !c.area_light,
        passes: ungraded,
        figure: |c| c.quality.interior_mae,
        unit: Unit::Value("interior MAE"),
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
        name: "alpha-tested casters",
        declared: Some(|k| k.cutout_casters),
        applies: |c| c.key.scene == "foliage",
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

/// Each criterion's mark over a technique's cells `mine`, in
/// [`CRITERIA`]'s order.
pub fn marks(mine: &[&Cell]) -> Vec<Mark> {
    CRITERIA.iter().map(|k| mark(k, mine)).collect()
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
pub fn extensibility(caps: &Capabilities, marks: &[Mark]) -> Vec<Claim> {
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
