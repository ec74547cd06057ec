//! The module layers of the guide (docs/book/src/contributing/architecture.md): no two top-level modules of `src/`
//! import each other, and the lower layers import nothing above them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level modules that `source` names as `crate::m` or in `crate::{m, …}`.
fn named_modules(source: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut used = BTreeSet::new();
    for (i, _) in source.match_indices("crate::") {
        let rest = &source[i + "crate::".len()..];
        let names: Vec<&str> = if let Some(group) = rest.strip_prefix('{') {
            group[..group.find('}').unwrap_or(group.len())]
                .split(',')
                .map(|n| n.trim().split("::").next().unwrap_or("").trim())
                .collect()
        } else {
            vec![
                rest.split(|c: char| !c.is_alphanumeric() && c != '_')
                    .next()
                    .unwrap_or(""),
            ]
        };
        used.extend(
            names
                .into_iter()
                .filter(|n| modules.contains(*n))
                .map(String::from),
        );
    }
    used
}

fn module_imports() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let modules: BTreeSet<String> = std::fs::read_dir(&src)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter_map(|p| {
            let name = p.file_stem()?.to_str()?.to_string();
            (p.is_dir() || p.extension().is_some_and(|e| e == "rs")).then_some(name)
        })
        .filter(|n| n != "lib" && n != "main")
        .collect();
    modules
        .iter()
        .map(|m| {
            let mut files = vec![];
            let dir = src.join(m);
            if dir.is_dir() {
                rust_files(&dir, &mut files);
            } else {
                files.push(src.join(format!("{m}.rs")));
            }
            let mut used = BTreeSet::new();
            for f in files {
                used.extend(named_modules(
                    &std::fs::read_to_string(f).unwrap(),
                    &modules,
                ));
            }
            used.remove(m);
            (m.clone(), used)
        })
        .collect()
}

#[test]
fn the_parser_finds_single_and_grouped_imports() {
    let modules: BTreeSet<String> = ["gpu", "frame", "scene"].map(String::from).into();
    let found = named_modules(
        "use crate::gpu::GpuContext;\nuse crate::{frame::X, scene};\nlet x = crate::other::y;",
        &modules,
    );
    assert_eq!(found, modules);
}

#[test]
fn no_two_modules_import_each_other() {
    let imports = module_imports();
    for (a, used) in &imports {
        for b in used {
            assert!(
                !imports[b].contains(a),
                "`{a}` and `{b}` import each other ({a} → {used:?}; {b} → {:?})",
                imports[b]
            );
        }
    }
}

#[test]
fn lower_layers_import_nothing_above_them() {
    let imports = module_imports();
    let allowed: &[(&str, &[&str])] = &[
        ("gpu", &[]),
        ("scene", &[]),
        ("frame", &["gpu", "scene"]),
        ("technique", &["gpu", "scene", "frame"]),
        ("renderer", &["gpu", "scene", "frame", "technique"]),
    ];
    for (module, may) in allowed {
        let extra: Vec<&String> = imports[*module]
            .iter()
            .filter(|m| !may.contains(&m.as_str()))
            .collect();
        assert!(extra.is_empty(), "`{module}` imports {extra:?}");
    }
}
