//! The bad-input corpus (`tests/corpus/`, listed in `expected.tsv`): every
//! malformed scene file, texture and parameter string must make every
//! command that loads scenes (`render`, `compare`, `bench`, `export`,
//! `view`) exit with code 2 within 10 s, with a message naming the file
//! (and line, field or accessor) — never a panic or a hang.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

struct Case {
    file: String,
    kind: String,
    expected: String,
}

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

fn cases() -> Vec<Case> {
    let text = std::fs::read_to_string(corpus_dir().join("expected.tsv")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            assert_eq!(f.len(), 3, "expected.tsv: '{l}'");
            Case {
                file: f[0].into(),
                kind: f[1].into(),
                expected: f[2].into(),
            }
        })
        .collect()
}

/// Runs shadowlab with a 10 s limit; returns (exit code, stderr, seconds).
fn run_bounded(args: &[String]) -> (Option<i32>, String, f64) {
    let t = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let limit = Duration::from_secs(10);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            use std::io::Read;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            return (status.code(), err, t.elapsed().as_secs_f64());
        }
        if t.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return (
                None,
                format!("killed after {limit:?}"),
                t.elapsed().as_secs_f64(),
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The command lines that load `case` for each command.
fn command_lines(case: &Case, out: &Path) -> Vec<Vec<String>> {
    let path = corpus_dir().join(&case.file).display().to_string();
    let o = |name: &str| out.join(name).display().to_string();
    let line = |parts: &[&str]| -> Vec<String> {
        parts
            .iter()
            .chain(&["--size", "32x18"])
            .map(|x| x.to_string())
            .collect()
    };
    match case.kind.as_str() {
        "scene" => {
            let (render, compare, bench) = (o("render"), o("compare"), o("bench"));
            let export: Vec<String> = ["export", "--scene", &path, "--out", &o("export.gltf")]
                .iter()
                .map(|x| x.to_string())
                .collect();
            vec![
                line(&["render", "--scene", &path, "--out", &render]),
                line(&["compare", "--scene", &path, "--out", &compare]),
                line(&["bench", "--scene", &path, "--frames", "1", "--out", &bench]),
                export,
                line(&["view", "--scene", &path, "--frames", "1"]),
            ]
        }
        "params" => {
            let spec = std::fs::read_to_string(corpus_dir().join(&case.file)).unwrap();
            let spec = spec.trim();
            let (render, compare, bench) = (o("render"), o("compare"), o("bench"));
            let scene = "floating";
            vec![
                line(&[
                    "render",
                    "--scene",
                    scene,
                    "--technique",
                    spec,
                    "--out",
                    &render,
                ]),
                line(&[
                    "compare",
                    "--scene",
                    scene,
                    "--techniques",
                    spec,
                    "--out",
                    &compare,
                ]),
                line(&[
                    "bench",
                    "--scene",
                    scene,
                    "--techniques",
                    spec,
                    "--frames",
                    "1",
                    "--out",
                    &bench,
                ]),
                line(&[
                    "view",
                    "--scene",
                    scene,
                    "--technique",
                    spec,
                    "--frames",
                    "1",
                ]),
            ]
        }
        k => panic!("{}: unknown kind '{k}'", case.file),
    }
}

#[test]
fn every_corpus_file_fails_cleanly_on_every_command() {
    let cases = cases();
    assert!(cases.len() >= 40, "only {} corpus cases", cases.len());
    let out = tmpdir("corpus");
    let jobs: Vec<(String, Vec<String>, String)> = cases
        .iter()
        .flat_map(|c| {
            command_lines(c, &out.join(&c.file))
                .into_iter()
                .map(|args| (c.file.clone(), args, c.expected.clone()))
        })
        .collect();
    let failures = std::sync::Mutex::new(vec![]);
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some((file, args, expected)) = jobs.get(i) else {
                        break;
                    };
                    let (code, err, secs) = run_bounded(args);
                    let problem = if code != Some(2) {
                        Some(format!("exit code {code:?}"))
                    } else if !err.contains(expected.as_str()) {
                        Some(format!("expected '{expected}'"))
                    } else if err.contains("panicked") {
                        Some("panicked".into())
                    } else if secs > 10.0 {
                        Some(format!("took {secs:.1} s"))
                    } else {
                        None
                    };
                    if let Some(p) = problem {
                        failures.lock().unwrap().push(format!(
                            "{file}: {} {}: {p}; stderr: {}",
                            args[0],
                            args.iter()
                                .skip(1)
                                .take(2)
                                .cloned()
                                .collect::<Vec<_>>()
                                .join(" "),
                            err.trim()
                        ));
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} runs failed:\n{}",
        failures.len(),
        jobs.len(),
        failures.join("\n")
    );
}

/// Every file in the corpus folder is either a case or a file a case uses.
#[test]
fn every_corpus_file_is_listed_or_used() {
    let cases = cases();
    let listed: Vec<&str> = cases.iter().map(|c| c.file.as_str()).collect();
    let all_text: String = cases
        .iter()
        .map(|c| std::fs::read(corpus_dir().join(&c.file)).unwrap())
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .collect::<Vec<_>>()
        .join("\n");
    let mut extra_text = String::new();
    for e in std::fs::read_dir(corpus_dir()).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".mtl") {
            extra_text += &std::fs::read_to_string(corpus_dir().join(&name)).unwrap();
        }
    }
    for e in std::fs::read_dir(corpus_dir()).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name == "expected.tsv" || listed.contains(&name.as_str()) {
            continue;
        }
        assert!(
            all_text.contains(&name) || extra_text.contains(&name),
            "{name} is neither listed in expected.tsv nor used by a listed file"
        );
    }
}
