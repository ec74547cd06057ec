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
    // `clock` (the monotonic clock of native and browser builds) is the
    // bottom layer.
    let allowed: &[(&str, &[&str])] = &[
        ("clock", &[]),
        ("gpu", &["clock"]),
        ("scene", &["clock"]),
        ("frame", &["clock", "gpu", "scene"]),
        ("technique", &["clock", "gpu", "scene", "frame"]),
        ("renderer", &["clock", "gpu", "scene", "frame", "technique"]),
    ];
    for (module, may) in allowed {
        let extra: Vec<&String> = imports[*module]
            .iter()
            .filter(|m| !may.contains(&m.as_str()))
            .collect();
        assert!(extra.is_empty(), "`{module}` imports {extra:?}");
    }
}

/// A file's module path under `src/` (`technique::shadow_map::gpu`).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let mut parts: Vec<String> = file
        .strip_prefix(src)
        .unwrap()
        .with_extension("")
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The module paths a file names with `crate::…` or `super::…` (a brace
/// group's names each), resolved against the file's own module `me`;
/// tests and comments left out.
fn named_paths(source: &str, me: &[String]) -> Vec<Vec<String>> {
    let code = source
        .split("#[cfg(test)]\nmod tests")
        .next()
        .unwrap()
        .lines()
        .map(|l| l.split("//").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n");
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut found = vec![];
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        if !code.is_char_boundary(i) {
            i += 1;
            continue;
        }
        let at_word = i == 0 || !ident(bytes[i - 1] as char);
        let rest = &code[i..];
        if !(at_word && (rest.starts_with("crate::") || rest.starts_with("super::"))) {
            i += 1;
            continue;
        }
        let len = rest
            .find(|c: char| !(ident(c) || c == ':'))
            .unwrap_or(rest.len());
        let path: Vec<&str> = rest[..len].split("::").filter(|s| !s.is_empty()).collect();
        let mut base: Vec<String> = if path[0] == "crate" {
            vec![]
        } else {
            me.to_vec()
        };
        let mut segs = &path[..];
        if path[0] == "crate" {
            segs = &segs[1..];
        }
        while segs.first() == Some(&"super") {
            base.pop();
            segs = &segs[1..];
        }
        base.extend(segs.iter().map(|s| s.to_string()));
        let after = &rest[len..];
        if let Some(group) = after.strip_prefix('{') {
            let inner = &group[..group.find('}').unwrap_or(group.len())];
            for name in inner.split(',') {
                let first = name.trim().split("::").next().unwrap().trim();
                if !first.is_empty() && first != "self" {
                    let mut p = base.clone();
                    p.push(first.to_string());
                    found.push(p);
                }
            }
        }
        found.push(base);
        i += len.max(1);
    }
    found
}

/// No two children of any module import each other, directly or around a
/// circle (children import their parent; a parent composes its children).
#[test]
fn no_sibling_modules_import_each_other_in_a_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = vec![];
    rust_files(&src, &mut files);
    let paths: Vec<(Vec<String>, Vec<Vec<String>>)> = files
        .iter()
        .map(|f| {
            let me = module_path(&src, f);
            let named = named_paths(&std::fs::read_to_string(f).unwrap(), &me);
            (me, named)
        })
        .collect();
    let modules: BTreeSet<Vec<String>> = paths.iter().map(|(m, _)| m.clone()).collect();
    let mut circles = vec![];
    for parent in modules.iter().chain(std::iter::once(&vec![])) {
        let children: BTreeSet<&String> = modules
            .iter()
            .filter(|m| m.len() == parent.len() + 1 && m.starts_with(parent))
            .map(|m| m.last().unwrap())
            .collect();
        let mut edges: BTreeMap<&String, BTreeSet<&String>> = BTreeMap::new();
        for (me, named) in &paths {
            if me.len() <= parent.len() || !me.starts_with(parent) {
                continue;
            }
            let from = &me[parent.len()];
            for p in named {
                if p.len() > parent.len()
                    && p.starts_with(parent)
                    && let Some(to) = children.get(&p[parent.len()])
                    && *to != from
                {
                    edges
                        .entry(children.get(from).unwrap())
                        .or_default()
                        .insert(to);
                }
            }
        }
        // A circle: a child that reaches itself.
        for start in &children {
            let mut seen = BTreeSet::new();
            let mut stack: Vec<&String> = edges.get(start).into_iter().flatten().copied().collect();
            while let Some(m) = stack.pop() {
                if m == *start {
                    circles.push(format!("{}::{start}", parent.join("::")));
                    break;
                }
                if seen.insert(m) {
                    stack.extend(edges.get(m).into_iter().flatten().copied());
                }
            }
        }
    }
    assert!(
        circles.is_empty(),
        "modules in an import circle with a sibling: {circles:?}"
    );
}

/// The resolver: `super` and brace groups, against the file's module.
#[test]
fn paths_resolve_against_the_module() {
    let me: Vec<String> = ["technique", "shadow_map", "gpu"]
        .map(String::from)
        .to_vec();
    let found = named_paths(
        "use super::{config::Filter, projection};\nlet x = crate::scene::Aabb::new();\n// super::ignored\n",
        &me,
    );
    let s = |p: &[&str]| p.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert!(found.contains(&s(&["technique", "shadow_map", "config"])));
    assert!(found.contains(&s(&["technique", "shadow_map", "projection"])));
    assert!(found.contains(&s(&["scene", "Aabb", "new"])));
    assert!(!found.iter().any(|p| p.contains(&"ignored".to_string())));
}

/// Lines of `code` without string and char literals and `//` comments, for
/// counting braces.
fn braces_of(line: &str) -> (i32, i32) {
    let (mut open, mut close) = (0, 0);
    let mut chars = line.chars().peekable();
    let mut in_str = false;
    while let Some(c) = chars.next() {
        match c {
            '\\' if in_str => {
                chars.next();
            }
            '"' => in_str = !in_str,
            '/' if !in_str && chars.peek() == Some(&'/') => break,
            '\'' if !in_str => {
                // A char literal ('{', '\n') or a lifetime ('a).
                let rest: String = chars.clone().take(3).collect();
                if rest.starts_with('\\') || rest.chars().nth(1) == Some('\'') {
                    let len = if rest.starts_with('\\') { 3 } else { 2 };
                    for _ in 0..len {
                        chars.next();
                    }
                }
            }
            '{' if !in_str => open += 1,
            '}' if !in_str => close += 1,
            _ => {}
        }
    }
    (open, close)
}

/// No source file over 600 lines and no function over 120 lines, outside
/// the test modules (split along the passes or steps instead).
#[test]
fn files_and_functions_stay_short() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = vec![];
    rust_files(&src, &mut files);
    let mut long = vec![];
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let code = text.split("#[cfg(test)]\nmod tests").next().unwrap();
        let lines: Vec<&str> = code.lines().collect();
        let name = f.strip_prefix(&src).unwrap().display().to_string();
        if lines.len() > 600 {
            long.push(format!("{name}: {} lines", lines.len()));
        }
        for (i, line) in lines.iter().enumerate() {
            let t = line.trim_start();
            let is_fn = [
                "fn ",
                "pub fn ",
                "pub(crate) fn ",
                "pub(super) fn ",
                "const fn ",
                "pub const fn ",
            ]
            .iter()
            .any(|p| t.starts_with(p))
                || (t.starts_with("pub(in ") && t.contains(") fn "));
            if !is_fn {
                continue;
            }
            let mut depth = 0;
            let mut opened = false;
            for (j, l) in lines[i..].iter().enumerate() {
                let (o, c) = braces_of(l);
                depth += o - c;
                opened |= o > 0;
                if !opened && l.trim_end().ends_with(';') {
                    break;
                }
                if opened && depth == 0 {
                    if j + 1 > 120 {
                        long.push(format!("{name}:{}: a function of {} lines", i + 1, j + 1));
                    }
                    break;
                }
            }
        }
    }
    assert!(long.is_empty(), "too long: {long:#?}");
}

#[test]
fn braces_skip_strings_chars_and_comments() {
    assert_eq!(braces_of(r#"let s = "{"; // }"#), (0, 0));
    assert_eq!(braces_of("match c { '{' => 1, '}' => 2 }"), (1, 1));
    assert_eq!(braces_of("fn f<'a>(x: &'a str) {"), (1, 0));
    assert_eq!(braces_of(r#"format!("{x} \" {{")"#), (0, 0));
}
