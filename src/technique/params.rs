//! Parameter tables (bgfx style: value, min, max, step, doc). One table per
//! technique family drives the CLI (`--set key=value`), `shadowlab
//! techniques` and the viewer's panels.

use crate::scene::{AlphaMode, LightType};
use anyhow::{Result, bail};
use serde::Serialize;

/// A choice parameter's values as a Rust enum, declared with
/// [`choice_enum!`]: the enum gives the table its option names, and a
/// family reads the value back as the enum ([`ParamValues::choice`]).
pub trait Choice: Copy + Sized + 'static {
    /// The option names, in the enum's order.
    const NAMES: &'static [&'static str];
    /// Every variant, in the same order.
    const ALL: &'static [Self];

    /// Position of `self` in [`Choice::ALL`].
    fn index(self) -> usize;

    /// WGSL constants `const PREFIX_NAME: u32 = index;` for shaders that
    /// branch on the choice (names upper-cased, `-` as `_`).
    fn wgsl_constants(prefix: &str) -> String {
        Self::NAMES
            .iter()
            .enumerate()
            .map(|(i, n)| {
                format!(
                    "const {prefix}_{}: u32 = {i}u;\n",
                    n.to_ascii_uppercase().replace('-', "_")
                )
            })
            .collect()
    }
}

/// Declares an enum of a choice parameter with its option names:
/// `choice_enum! { pub enum Cull { Back = "back", Front = "front" } }`.
macro_rules! choice_enum {
    ($(#[$meta:meta])* $vis:vis enum $name:ident {
        $($(#[$vmeta:meta])* $variant:ident = $text:literal),+ $(,)?
    }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        $vis enum $name {
            $($(#[$vmeta])* $variant),+
        }
        impl $crate::technique::params::Choice for $name {
            const NAMES: &'static [&'static str] = &[$($text),+];
            const ALL: &'static [Self] = &[$(Self::$variant),+];
            fn index(self) -> usize {
                Self::ALL.iter().position(|&v| v == self).expect("every variant is listed")
            }
        }
    };
}
pub(crate) use choice_enum;

impl Choice for crate::frame::Compose {
    const NAMES: &'static [&'static str] = &["relight", "darken"];
    const ALL: &'static [Self] = &[Self::Relight, Self::Darken];
    fn index(self) -> usize {
        self as usize
    }
}

choice_enum! {
    /// How a technique's caster passes draw translucent (glTF `BLEND`)
    /// casters, which the reference traces as fractional transmittance.
    pub enum BlendedCasters {
        Cutout = "cutout",
        Hashed = "hashed",
        Opaque = "opaque",
        Ignore = "ignore",
        Transmit = "transmit",
    }
}

impl BlendedCasters {
    /// How a caster pass draws a caster of `mode`: opaque, as a cut-out
    /// ([`AlphaMode::Mask`]; blended ones solid where opacity ≥ ½), or not
    /// at all (`None`; `transmit` draws blended casters in passes of their
    /// own).
    pub fn draws_as(self, mode: AlphaMode) -> Option<AlphaMode> {
        match (mode, self) {
            (AlphaMode::Blend, BlendedCasters::Cutout | BlendedCasters::Hashed) => {
                Some(AlphaMode::Mask)
            }
            (AlphaMode::Blend, BlendedCasters::Opaque) => Some(AlphaMode::Opaque),
            (AlphaMode::Blend, BlendedCasters::Ignore | BlendedCasters::Transmit) => None,
            (m, _) => Some(m),
        }
    }
}

/// How a technique's caster passes treat see-through casters: alpha-tested
/// (`alpha_test`) or every caster solid, and the translucent ones as
/// `blended` says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CasterAlpha {
    pub alpha_test: bool,
    pub blended: BlendedCasters,
}

impl CasterAlpha {
    /// How a caster of `mode` is drawn: opaque, as a cut-out
    /// ([`AlphaMode::Mask`]) or not at all.
    pub fn draws_as(self, mode: AlphaMode) -> Option<AlphaMode> {
        if self.alpha_test {
            self.blended.draws_as(mode)
        } else {
            Some(AlphaMode::Opaque)
        }
    }
}

/// What kind of value a parameter holds. Every value is stored as `f64`:
/// booleans as 0/1, choices as the index into their names.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ParamKind {
    Float,
    Int,
    Bool,
    Choice(&'static [&'static str]),
}

/// One row of a parameter table.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: f64,
    pub min: f64,
    pub max: f64,
    pub step: f64,
    pub doc: &'static str,
    /// When the parameter has an effect.
    pub applies: Applies,
}

/// The light types a parameter applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct LightKinds {
    pub point: bool,
    pub spot: bool,
    pub directional: bool,
}

impl LightKinds {
    pub const ALL: LightKinds = LightKinds {
        point: true,
        spot: true,
        directional: true,
    };
    pub const DIRECTIONAL: LightKinds = LightKinds {
        point: false,
        spot: false,
        directional: true,
    };
    /// Point and spot lights.
    pub const LOCAL: LightKinds = LightKinds {
        point: true,
        spot: true,
        directional: false,
    };
    pub const POINT: LightKinds = LightKinds {
        point: true,
        spot: false,
        directional: false,
    };
    pub const SPOT: LightKinds = LightKinds {
        point: false,
        spot: true,
        directional: false,
    };

    pub fn holds(self, kind: LightType) -> bool {
        match kind {
            LightType::Point => self.point,
            LightType::Spot => self.spot,
            LightType::Directional => self.directional,
        }
    }

    fn describe(self) -> Option<String> {
        let names: Vec<&str> = [
            (self.point, "point"),
            (self.spot, "spot"),
            (self.directional, "directional"),
        ]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, n)| *n)
        .collect();
        (names.len() < 3).then(|| format!("{} lights", names.join(" and ")))
    }
}

/// A condition on another parameter of the same table: its value (as
/// [`ParamSpec::format`] writes it) is one of `values`, or none of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Condition {
    Is(&'static str, &'static [&'static str]),
    IsNot(&'static str, &'static [&'static str]),
}

/// When a parameter has an effect: for lights of `lights`, and where
/// `when` holds (the filter it tunes is chosen, paging is on, …).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Applies {
    pub lights: LightKinds,
    pub when: Option<Condition>,
}

impl Applies {
    pub const ALWAYS: Applies = Applies {
        lights: LightKinds::ALL,
        when: None,
    };

    /// What the condition says, for listings (`None`: always).
    pub fn describe(&self) -> Option<String> {
        let when = self.when.map(|c| match c {
            Condition::Is(p, v) => format!("{p}={}", v.join("|")),
            Condition::IsNot(p, v) => format!("{p}≠{}", v.join("|")),
        });
        let parts: Vec<String> = self.lights.describe().into_iter().chain(when).collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }
}

impl ParamSpec {
    /// The same parameter, applying only to lights of `lights`.
    pub const fn for_lights(self, lights: LightKinds) -> Self {
        ParamSpec {
            applies: Applies {
                lights,
                when: self.applies.when,
            },
            ..self
        }
    }

    /// The same parameter, applying only where `when` holds.
    pub const fn when(self, when: Condition) -> Self {
        ParamSpec {
            applies: Applies {
                lights: self.applies.lights,
                when: Some(when),
            },
            ..self
        }
    }

    pub const fn float(
        name: &'static str,
        default: f64,
        min: f64,
        max: f64,
        step: f64,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Float,
            default,
            min,
            max,
            step,
            doc,
            applies: Applies::ALWAYS,
        }
    }
    pub const fn int(
        name: &'static str,
        default: i64,
        min: i64,
        max: i64,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Int,
            default: default as f64,
            min: min as f64,
            max: max as f64,
            step: 1.0,
            doc,
            applies: Applies::ALWAYS,
        }
    }
    pub const fn boolean(name: &'static str, default: bool, doc: &'static str) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Bool,
            default: if default { 1.0 } else { 0.0 },
            min: 0.0,
            max: 1.0,
            step: 1.0,
            doc,
            applies: Applies::ALWAYS,
        }
    }
    /// A choice among the variants of `T`, defaulting to variant `default`
    /// (its index: `Filter::Grid as usize`).
    pub const fn choice_of<T: Choice>(
        name: &'static str,
        default: usize,
        doc: &'static str,
    ) -> Self {
        Self::choice(name, T::NAMES, default, doc)
    }

    pub const fn choice(
        name: &'static str,
        options: &'static [&'static str],
        default: usize,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Choice(options),
            default: default as f64,
            min: 0.0,
            max: (options.len() - 1) as f64,
            step: 1.0,
            doc,
            applies: Applies::ALWAYS,
        }
    }

    /// Shadow darkness of the techniques that mark shadowed pixels with a
    /// constant (planar, shadow volumes): the mask value there is 1 − darkening.
    pub const DARKENING: ParamSpec = ParamSpec::float(
        "darkening",
        1.0,
        0.0,
        1.0,
        0.05,
        "shadow darkness: 0 invisible … 1 black (mask value 1 − darkening)",
    );

    /// How the lighting pass uses the mask ([`crate::frame::Compose`]).
    pub const COMPOSE: ParamSpec = ParamSpec::choice_of::<crate::frame::Compose>(
        "compose",
        crate::frame::Compose::Relight as usize,
        "relight: ambient + masked direct light (an ambient pass, lit where the shadow test passes); darken: the lit image times the mask (one lit pass and a darkening pass, the documents' way)",
    );

    /// How caster passes draw translucent casters ([`BlendedCasters`]).
    pub const BLENDED_CASTERS: ParamSpec = ParamSpec::choice_of::<BlendedCasters>(
        "blended_casters",
        BlendedCasters::Cutout as usize,
        "translucent (glTF BLEND) casters: cutout — solid where opacity ≥ ½; hashed — solid where opacity ≥ a hash of the texel, its depth and the object (Wyman & McGuire 2017), so filtered lookups see fractional visibility and stacked surfaces, the two sides of one glass among them, multiply their transmittances; opaque — solid everywhere; ignore — cast no shadow (the reference lets 1 − opacity of the light through); transmit — transmittance maps beside each face's depth (or each page's): the product of 1 − opacity over the translucent surfaces before the nearest opaque one, and the nearest one's depth; a receiver behind it takes that share of the light (a double-sided surface counted once; exact where each receiver also casts, since the opaque depth stops the product at it; 5 more bytes per texel)",
    );

    /// Parses a textual value (`1.5`, `true`, a choice name) for this
    /// parameter, checking the range.
    pub fn parse(&self, text: &str) -> Result<f64> {
        let v = match self.kind {
            ParamKind::Bool => match text {
                "true" | "on" | "1" | "yes" => 1.0,
                "false" | "off" | "0" | "no" => 0.0,
                _ => bail!(
                    "parameter '{}' is a boolean: use true or false, not '{text}'",
                    self.name
                ),
            },
            ParamKind::Choice(opts) => match opts.iter().position(|o| *o == text) {
                Some(i) => i as f64,
                None => bail!(
                    "parameter '{}' must be one of {}, not '{text}'",
                    self.name,
                    opts.join(", ")
                ),
            },
            ParamKind::Int => {
                let v: i64 = text.parse().map_err(|_| {
                    anyhow::anyhow!("parameter '{}' needs an integer, not '{text}'", self.name)
                })?;
                v as f64
            }
            ParamKind::Float => {
                let v: f64 = text.parse().map_err(|_| {
                    anyhow::anyhow!("parameter '{}' needs a number, not '{text}'", self.name)
                })?;
                if !v.is_finite() {
                    bail!("parameter '{}' must be finite", self.name);
                }
                v
            }
        };
        if v < self.min || v > self.max {
            bail!(
                "parameter '{}' = {text} is out of range [{}, {}]",
                self.name,
                self.min,
                self.max
            );
        }
        Ok(v)
    }

    /// Formats a stored value the way [`parse`](Self::parse) reads it.
    pub fn format(&self, v: f64) -> String {
        match self.kind {
            ParamKind::Bool => (v != 0.0).to_string(),
            ParamKind::Choice(opts) => opts.get(v as usize).unwrap_or(&"?").to_string(),
            ParamKind::Int => format!("{}", v as i64),
            ParamKind::Float => format!("{v}"),
        }
    }
}

/// The current values of one technique instance's parameters.
#[derive(Clone, Debug)]
pub struct ParamValues {
    pub specs: &'static [ParamSpec],
    pub values: Vec<f64>,
}

impl ParamValues {
    pub fn defaults(specs: &'static [ParamSpec]) -> Self {
        ParamValues {
            specs,
            values: specs.iter().map(|s| s.default).collect(),
        }
    }

    /// Whether `spec` has an effect with these values, for a light of
    /// `kind` (any light when `None`). A condition on a parameter the table
    /// lacks holds (a table built of shared rows).
    pub fn applies(&self, spec: &ParamSpec, kind: Option<LightType>) -> bool {
        if kind.is_some_and(|k| !spec.applies.lights.holds(k)) {
            return false;
        }
        let value_of = |name: &str| {
            self.specs
                .iter()
                .zip(&self.values)
                .find(|(s, _)| s.name == name)
                .map(|(s, v)| s.format(*v))
        };
        match spec.applies.when {
            None => true,
            Some(Condition::Is(p, vals)) => value_of(p).is_none_or(|v| vals.contains(&v.as_str())),
            Some(Condition::IsNot(p, vals)) => {
                value_of(p).is_none_or(|v| !vals.contains(&v.as_str()))
            }
        }
    }

    /// The parameters named in `settings` (`key=value`) that have no effect
    /// with these values for a light of `kind`, each with its condition.
    pub fn without_effect(&self, settings: &[String], kind: LightType) -> Vec<String> {
        settings
            .iter()
            .filter_map(|kv| kv.split_once('=').map(|(k, _)| k.trim()))
            .filter_map(|k| self.specs.iter().find(|s| s.name == k))
            .filter(|s| !self.applies(s, Some(kind)))
            .map(|s| {
                format!(
                    "{} (applies to {})",
                    s.name,
                    s.applies.describe().unwrap_or_default()
                )
            })
            .collect()
    }

    fn index(&self, name: &str) -> Result<usize> {
        self.specs
            .iter()
            .position(|s| s.name == name)
            .ok_or_else(|| {
                let valid: Vec<&str> = self.specs.iter().map(|s| s.name).collect();
                anyhow::anyhow!(
                    "unknown parameter '{name}' (valid: {})",
                    if valid.is_empty() {
                        "none".to_string()
                    } else {
                        valid.join(", ")
                    }
                )
            })
    }

    /// Sets `name` from text, with range and type checks.
    pub fn set(&mut self, name: &str, text: &str) -> Result<()> {
        let i = self.index(name)?;
        self.values[i] = self.specs[i].parse(text)?;
        Ok(())
    }

    /// Sets a numeric value directly (viewer sliders), clamped to the range.
    pub fn set_value(&mut self, name: &str, v: f64) -> Result<()> {
        let i = self.index(name)?;
        self.values[i] = v.clamp(self.specs[i].min, self.specs[i].max);
        Ok(())
    }

    /// The value of `name`; an error (not a panic) for a name that is not
    /// in the table.
    pub fn get(&self, name: &str) -> Result<f64> {
        self.index(name).map(|i| self.values[i])
    }

    /// The value of the parameter `spec` (a family's named constant, so a
    /// misspelt parameter does not compile); an error when the values
    /// belong to another table.
    fn value(&self, spec: &ParamSpec) -> Result<f64> {
        let i = self.index(spec.name)?;
        if self.specs[i].kind != spec.kind {
            bail!("parameter '{}' has another type in this table", spec.name);
        }
        Ok(self.values[i])
    }

    /// A float parameter's value.
    pub fn float(&self, spec: &ParamSpec) -> Result<f32> {
        self.value(spec).map(|v| v as f32)
    }

    /// An integer parameter's value.
    pub fn int(&self, spec: &ParamSpec) -> Result<u32> {
        self.value(spec).map(|v| v as u32)
    }

    /// A boolean parameter's value.
    pub fn flag(&self, spec: &ParamSpec) -> Result<bool> {
        self.value(spec).map(|v| v != 0.0)
    }

    /// A choice parameter's value as its enum.
    pub fn choice<T: Choice>(&self, spec: &ParamSpec) -> Result<T> {
        if spec.kind != ParamKind::Choice(T::NAMES) {
            bail!(
                "parameter '{}' is not a choice of {:?}",
                spec.name,
                T::NAMES
            );
        }
        let v = self.value(spec)?;
        T::ALL
            .get(v as usize)
            .copied()
            .ok_or_else(|| anyhow::anyhow!("parameter '{}' holds no valid choice", spec.name))
    }

    /// `name → formatted value`, for frame.json.
    pub fn to_json(&self) -> serde_json::Value {
        let map: serde_json::Map<String, serde_json::Value> = self
            .specs
            .iter()
            .zip(&self.values)
            .map(|(s, &v)| {
                let j = match s.kind {
                    ParamKind::Bool => serde_json::json!(v != 0.0),
                    ParamKind::Choice(_) => serde_json::json!(s.format(v)),
                    ParamKind::Int => serde_json::json!(v as i64),
                    ParamKind::Float => serde_json::json!(v),
                };
                (s.name.to_string(), j)
            })
            .collect();
        serde_json::Value::Object(map)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static SPECS: &[ParamSpec] = &[
        ParamSpec::float("bias", 0.5, 0.0, 1.0, 0.01, "a bias"),
        ParamSpec::int("size", 1024, 16, 8192, "map size"),
        ParamSpec::boolean("stencil", true, "use stencil"),
        ParamSpec::COMPOSE,
    ];

    #[test]
    fn parse_checks_type_and_range() {
        let mut p = ParamValues::defaults(SPECS);
        p.set("bias", "0.25").unwrap();
        assert_eq!(p.get("bias").unwrap(), 0.25);
        assert!(
            p.set("bias", "2")
                .unwrap_err()
                .to_string()
                .contains("out of range [0, 1]")
        );
        assert!(p.set("bias", "NaN").is_err());
        assert!(p.set("size", "1.5").is_err());
        p.set("stencil", "false").unwrap();
        assert!(!p.flag(&SPECS[2]).unwrap());
        p.set("compose", "darken").unwrap();
        assert_eq!(
            p.choice::<crate::frame::Compose>(&SPECS[3]).unwrap(),
            crate::frame::Compose::Darken
        );
        let e = p.set("compose", "blend").unwrap_err().to_string();
        assert!(e.contains("relight, darken"), "{e}");
        let e = p.set("nope", "1").unwrap_err().to_string();
        assert!(e.contains("valid: bias, size, stencil, compose"), "{e}");
        let e = p.get("nope").unwrap_err().to_string();
        assert!(e.contains("unknown parameter 'nope'"), "{e}");
        assert!(p.get("Bias").is_err() && p.get("").is_err());
        // A spec of another table, or of another type, is an error.
        let other = ParamSpec::float("compose", 0.0, 0.0, 1.0, 0.1, "x");
        assert!(p.float(&other).is_err());
        assert!(
            p.float(&ParamSpec::float("nope", 0.0, 0.0, 1.0, 0.1, "x"))
                .is_err()
        );
    }

    #[test]
    fn json_uses_readable_values() {
        let p = ParamValues::defaults(SPECS);
        let j = p.to_json();
        assert_eq!(j["compose"], "relight");
        assert_eq!(j["stencil"], true);
        assert_eq!(j["size"], 1024);
    }
}
