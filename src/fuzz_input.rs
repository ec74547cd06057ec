//! Entry points that feed raw bytes to each loader and parser: the
//! `cargo fuzz` targets in `fuzz/` call them, and `tests/fuzz_corpus.rs`
//! replays the fuzzers' seed corpora and every crash they found through
//! them on the stable toolchain. Each must return (an error is fine) for
//! any input: never panic, hang or allocate without bound.

use crate::{measure, scene, technique};
use anyhow::Result;
use std::path::{Path, PathBuf};

/// Separates the OBJ text from the MTL text in an [`obj_and_mtl`] input.
pub const MTL_SEPARATOR: u8 = 0;

/// A per-process scratch folder holding the files an input is written to,
/// and a small valid `box.obj` that TOML inputs may include; in memory
/// (`/dev/shm`) where there is one, since writing and reading the files
/// dominates the time of an execution.
fn scratch() -> &'static Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let shm = Path::new("/dev/shm");
        let base = if shm.is_dir() {
            shm.to_path_buf()
        } else {
            std::env::temp_dir()
        };
        let d = base.join(format!("shadowlab-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("creating the fuzz scratch folder");
        std::fs::write(
            d.join("box.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
        )
        .expect("writing box.obj");
        d
    })
}

fn load(name: &str, bytes: &[u8]) -> Result<scene::Scene> {
    let path = scratch().join(name);
    std::fs::write(&path, bytes)?;
    scene::load_file(&path)
}

/// An OBJ file and, after the first NUL byte, the `fuzz.mtl` it may name.
pub fn obj_and_mtl(data: &[u8]) -> Result<scene::Scene> {
    let (obj, mtl) = match data.iter().position(|&b| b == MTL_SEPARATOR) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    std::fs::write(scratch().join("fuzz.mtl"), mtl)?;
    load("fuzz.obj", obj)
}

/// A glTF file: binary (`.glb`) when it starts with the GLB magic.
pub fn gltf(data: &[u8]) -> Result<scene::Scene> {
    let name = if data.starts_with(b"glTF") {
        "fuzz.glb"
    } else {
        "fuzz.gltf"
    };
    load(name, data)
}

/// A TOML scene file (it may include `box.obj` or itself).
pub fn toml_scene(data: &[u8]) -> Result<scene::Scene> {
    load("fuzz.toml", data)
}

/// The text both as a technique list, as `compare` and `bench` take it, and
/// as one technique, as `render` and `view` take it: Ok when either parses.
pub fn technique_spec(data: &[u8]) -> Result<()> {
    let text = String::from_utf8_lossy(data);
    let as_one = technique::parse_choice(&text).map(|_| ());
    measure::parse_technique_list(&text).map(|_| ()).or(as_one)
}
