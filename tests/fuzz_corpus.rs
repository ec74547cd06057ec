//! Replays every input under `fuzz/seeds/<target>/` — the seeds of the
//! `cargo fuzz` targets and every crash reproducer the fuzzers found —
//! through the same entry points on the stable toolchain: each must return
//! (an error or a scene) without panicking, within 10 s: each runs on its
//! own thread, so that an input that hangs fails the test instead of
//! hanging it.

use std::path::Path;
use std::time::Duration;

/// How long one input may take.
const LIMIT: Duration = Duration::from_secs(10);

fn replay(target: &str, entry: fn(&[u8]) -> bool) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/seeds")
        .join(target);
    let mut inputs: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    inputs.sort();
    assert!(inputs.len() >= 5, "{target}: only {} seeds", inputs.len());
    let (mut ok, mut errors) = (0, 0);
    for path in &inputs {
        let data = std::fs::read(path).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(std::panic::catch_unwind(|| entry(&data)));
        });
        match rx.recv_timeout(LIMIT) {
            Ok(Ok(true)) => ok += 1,
            Ok(Ok(false)) => errors += 1,
            Ok(Err(_)) => panic!("{target}: {} panicked", path.display()),
            Err(_) => panic!("{target}: {} ran past {LIMIT:?}", path.display()),
        }
    }
    // The seeds hold valid inputs as well as malformed ones.
    assert!(
        ok >= 1 && errors >= 1,
        "{target}: {ok} loaded, {errors} refused"
    );
}

#[test]
fn obj_mtl_seeds_and_crashes_replay_cleanly() {
    replay("obj_mtl", |d| shadowlab::fuzz_input::obj_and_mtl(d).is_ok());
}

#[test]
fn gltf_seeds_and_crashes_replay_cleanly() {
    replay("gltf", |d| shadowlab::fuzz_input::gltf(d).is_ok());
}

#[test]
fn toml_seeds_and_crashes_replay_cleanly() {
    replay("toml_scene", |d| {
        shadowlab::fuzz_input::toml_scene(d).is_ok()
    });
}

#[test]
fn technique_spec_seeds_and_crashes_replay_cleanly() {
    replay("technique_spec", |d| {
        shadowlab::fuzz_input::technique_spec(d).is_ok()
    });
}
