//! Parameter tables (bgfx style: value, min, max, step, doc). One table per
//! technique family drives the CLI (`--set key=value`), `shadowlab
//! techniques` and the viewer's panels.

use anyhow::{Result, bail};
use serde::Serialize;

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
}

impl ParamSpec {
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
        }
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

    /// How the lighting pass uses the mask ([`crate::renderer::Compose`]).
    pub const COMPOSE: ParamSpec = ParamSpec::choice(
        "compose",
        &["relight", "darken"],
        0,
        "relight: ambient + masked direct light (an ambient pass, lit where the shadow test passes); darken: the lit image times the mask (one lit pass and a darkening pass, the documents' way)",
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
    pub fn get_f32(&self, name: &str) -> Result<f32> {
        self.get(name).map(|v| v as f32)
    }
    pub fn get_bool(&self, name: &str) -> Result<bool> {
        self.get(name).map(|v| v != 0.0)
    }
    pub fn get_usize(&self, name: &str) -> Result<usize> {
        self.get(name).map(|v| v as usize)
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
        ParamSpec::choice("mode", &["relight", "darken"], 0, "compose"),
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
        assert!(!p.get_bool("stencil").unwrap());
        p.set("mode", "darken").unwrap();
        assert_eq!(p.get_usize("mode").unwrap(), 1);
        let e = p.set("mode", "blend").unwrap_err().to_string();
        assert!(e.contains("relight, darken"), "{e}");
        let e = p.set("nope", "1").unwrap_err().to_string();
        assert!(e.contains("valid: bias, size, stencil, mode"), "{e}");
        let e = p.get("nope").unwrap_err().to_string();
        assert!(e.contains("unknown parameter 'nope'"), "{e}");
        assert!(p.get_f32("Bias").is_err() && p.get_usize("").is_err());
    }

    #[test]
    fn json_uses_readable_values() {
        let p = ParamValues::defaults(SPECS);
        let j = p.to_json();
        assert_eq!(j["mode"], "relight");
        assert_eq!(j["stencil"], true);
        assert_eq!(j["size"], 1024);
    }
}
