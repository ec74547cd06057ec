//! What shadowlab keeps under `extras.shadowlab` in a glTF file: a node's
//! shadow flags and a material's Phong parameters, read and written.

use anyhow::{Context, Result};
use serde_json::Value;

/// Per-node flags stored under `extras.shadowlab`.
#[derive(serde::Deserialize, serde::Serialize, Debug, Default)]
pub(super) struct ShadowFlags {
    pub casts_shadow: Option<bool>,
    pub receives_shadow: Option<bool>,
    pub shadow_plane: Option<bool>,
}

/// Phong parameters stored under a material's `extras.shadowlab`.
#[derive(serde::Deserialize, serde::Serialize, Debug)]
pub(super) struct PhongExtras {
    pub ka: [f32; 3],
    pub kd: [f32; 3],
    pub ks: [f32; 3],
    pub shininess: f32,
    pub uv_scale: f32,
    pub procedural: Option<crate::scene::Procedural>,
}

pub(super) fn extras_field<T: serde::de::DeserializeOwned>(
    extras: &gltf::json::Extras,
    what: &str,
) -> Result<Option<T>> {
    let Some(raw) = extras else { return Ok(None) };
    let v: Value = serde_json::from_str(raw.get())?;
    match v.get("shadowlab") {
        Some(s) => Ok(Some(
            serde_json::from_value(s.clone())
                .with_context(|| format!("{what}: extras.shadowlab"))?,
        )),
        None => Ok(None),
    }
}
