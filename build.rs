//! Build-time facts for `shadowlab report`: the lines of Rust and WGSL in
//! each technique family's folder (the report's implementation difficulty)
//! and a hash of every source file (the version its cached cells carry).

use std::path::{Path, PathBuf};

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files_under(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// Non-blank lines of `path`.
fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .map(|s| s.lines().filter(|l| !l.trim().is_empty()).count())
        .unwrap_or(0)
}

/// FNV-1a, 64 bits.
fn fnv1a(hash: u64, bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(hash, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3))
}

fn main() {
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.lock");
    let mut table = String::from(
        "/// Per technique family: (id, non-blank lines of Rust, of WGSL) in its folder.\npub const FAMILY_LINES: &[(&str, usize, usize)] = &[\n",
    );
    let mut families: Vec<PathBuf> = std::fs::read_dir("src/technique")
        .expect("src/technique")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    families.sort();
    for dir in families {
        let mut files = vec![];
        files_under(&dir, &mut files);
        let count = |ext: &str| -> usize {
            files
                .iter()
                .filter(|f| f.extension().is_some_and(|e| e == ext))
                .map(|f| lines(f))
                .sum()
        };
        let id = dir
            .file_name()
            .expect("a folder name")
            .to_string_lossy()
            .replace('_', "-");
        table += &format!("    ({id:?}, {}, {}),\n", count("rs"), count("wgsl"));
    }
    table += "];\n";
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    std::fs::write(out.join("family_lines.rs"), table).expect("writing family_lines.rs");

    let mut sources = vec![PathBuf::from("Cargo.lock"), PathBuf::from("Cargo.toml")];
    files_under(Path::new("src"), &mut sources);
    sources.sort();
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for f in &sources {
        hash = fnv1a(hash, f.to_string_lossy().as_bytes());
        hash = fnv1a(hash, &std::fs::read(f).unwrap_or_default());
    }
    println!("cargo:rustc-env=SHADOWLAB_SOURCE_HASH={hash:016x}");
}
