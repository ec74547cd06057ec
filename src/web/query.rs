//! A page's URL parameters, read as the command line's arguments: `scene`,
//! `camera` or `eye`/`target`, `light`, `technique`, `set` (repeatable
//! `key=value`), `size` and `compare=1` mean what `shadowlab compare`'s
//! options of the same names mean, and are checked by the same parser, so
//! a link reproduces the view the command line would render.

use crate::args::ViewArgs;
use crate::technique::{self, TechniqueChoice};
use anyhow::{Result, anyhow, bail};
use clap::Parser;

/// The URL parameters a page understands, in the order a link writes them.
pub const KEYS: [&str; 9] = [
    "scene",
    "camera",
    "eye",
    "target",
    "light",
    "technique",
    "set",
    "size",
    "compare",
];

/// A page's frame size when the link gives none: a quarter of the command
/// line's 1280×720, because the page's reference runs on one thread.
pub const DEFAULT_SIZE: &str = "640x360";

/// What a link asks the page to show.
#[derive(Parser, Clone, Debug)]
#[command(name = "shadowlab-page", no_binary_name = true)]
pub struct PageArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Technique id, optionally with values in brackets.
    #[arg(long, default_value = "shadow-map:pcf")]
    pub technique: String,
    /// Parameter values `key=value` of the technique's table.
    #[arg(long = "set")]
    pub set: Vec<String>,
    /// Render, run the reference and report (`compare=1`).
    #[arg(long, value_parser = ["0", "1"], default_value = "0")]
    pub compare: String,
}

impl PageArgs {
    /// Parses the URL's `(key, value)` pairs (already percent-decoded).
    pub fn from_pairs(pairs: &[(String, String)]) -> Result<PageArgs> {
        let mut argv: Vec<String> = vec![];
        for (k, v) in pairs {
            if !KEYS.contains(&k.as_str()) {
                bail!("unknown URL parameter '{k}' (valid: {})", KEYS.join(", "));
            }
            argv.push(format!("--{k}"));
            argv.push(v.clone());
        }
        if !pairs.iter().any(|(k, _)| k == "size") {
            argv.extend(["--size".into(), DEFAULT_SIZE.into()]);
        }
        let args = PageArgs::try_parse_from(&argv).map_err(|e| {
            // clap's message names the option as `--key`; a link says `key=`.
            anyhow!(
                "{}",
                e.to_string().lines().next().unwrap_or("bad URL parameter")
            )
        })?;
        Ok(args)
    }

    /// Whether the link asks for the comparison with the reference.
    pub fn compares(&self) -> bool {
        self.compare == "1"
    }

    /// The technique with the link's `set` values applied.
    pub fn choice(&self) -> Result<TechniqueChoice> {
        let mut c = technique::parse_choice(&self.technique)?;
        technique::apply_settings(&mut c.params, &self.set)?;
        Ok(c)
    }
}

/// Percent-encodes a URL parameter's value (RFC 3986 unreserved kept).
fn encode(v: &str) -> String {
    v.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' | b',' | b':' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The query string (without `?`) of a view: `(key, value)` pairs in
/// [`KEYS`] order, each value percent-encoded.
pub fn link(pairs: &[(&str, String)]) -> String {
    let mut sorted: Vec<&(&str, String)> = pairs.iter().collect();
    sorted.sort_by_key(|(k, _)| KEYS.iter().position(|x| x == k).unwrap_or(KEYS.len()));
    sorted
        .iter()
        .map(|(k, v)| format!("{k}={}", encode(v)))
        .collect::<Vec<_>>()
        .join("&")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(q: &[(&str, &str)]) -> Vec<(String, String)> {
        q.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn a_link_reads_as_the_command_line() {
        let a = PageArgs::from_pairs(&pairs(&[
            ("scene", "columns"),
            ("light", "sun"),
            ("technique", "shadow-map:pcf"),
            ("set", "size=1024"),
            ("set", "filter=disk"),
            ("compare", "1"),
        ]))
        .unwrap();
        assert_eq!(a.view.scene, "columns");
        assert_eq!(a.view.light.as_deref(), Some("sun"));
        assert_eq!(a.view.size, (640, 360));
        assert!(a.compares());
        let c = a.choice().unwrap();
        assert_eq!(c.params.get("size").unwrap(), 1024.0);
        let eye = PageArgs::from_pairs(&pairs(&[("eye", "1,2,3"), ("size", "320x200")])).unwrap();
        assert_eq!(eye.view.eye, Some(glam::Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(eye.view.size, (320, 200));
        assert!(!eye.compares());
    }

    #[test]
    fn bad_parameters_are_errors_that_name_them() {
        let e = PageArgs::from_pairs(&pairs(&[("bogus", "1")])).unwrap_err();
        assert!(
            e.to_string().contains("unknown URL parameter 'bogus'"),
            "{e}"
        );
        let e = PageArgs::from_pairs(&pairs(&[("size", "0x5")])).unwrap_err();
        assert!(e.to_string().contains("at least 1x1"), "{e}");
        let e = PageArgs::from_pairs(&pairs(&[("eye", "1,nan,3")])).unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
        let bad_set = PageArgs::from_pairs(&pairs(&[("set", "size=-4")])).unwrap();
        assert!(bad_set.choice().is_err());
        let bad_technique = PageArgs::from_pairs(&pairs(&[("technique", "nope")])).unwrap();
        let e = bad_technique.choice().err().unwrap().to_string();
        assert!(e.contains("unknown technique"), "{e}");
    }

    #[test]
    fn a_link_encodes_what_it_reads_back() {
        let q = link(&[
            ("technique", "shadow-map:pcf[size=512]".into()),
            ("scene", "room".into()),
            ("set", "filter=disk".into()),
        ]);
        assert_eq!(
            q,
            "scene=room&technique=shadow-map:pcf%5Bsize%3D512%5D&set=filter%3Ddisk"
        );
    }
}
