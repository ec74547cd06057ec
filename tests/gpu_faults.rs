//! GPU faults: a lost device is an error naming what failed (never a panic
//! or a hang); a missing adapter and an unknown backend exit with code 2.

mod common;
use common::*;
use shadowlab::gpu::GpuContext;
use shadowlab::scene::builtin;

#[test]
fn a_lost_device_is_an_error_not_a_panic() {
    // A context of its own: destroying the device loses it for good.
    let gpu = GpuContext::new(None).unwrap();
    let scene = builtin::by_name("floating").unwrap().unwrap();
    let choice = shadowlab::technique::resolve("shadow-map").unwrap();
    let mut hf =
        shadowlab::frame::HeadlessFrame::new(&gpu, &scene, std::slice::from_ref(&choice), 64, 36)
            .unwrap();
    hf.render(
        &gpu,
        &scene,
        &scene.camera,
        &scene.lights,
        &Default::default(),
    )
    .unwrap();
    gpu.device.destroy();
    gpu.wait_idle().ok();
    let e = hf
        .render(
            &gpu,
            &scene,
            &scene.camera,
            &scene.lights,
            &Default::default(),
        )
        .unwrap_err();
    assert!(
        format!("{e:#}").contains("the GPU device was lost"),
        "{e:#}"
    );
    let e = shadowlab::frame::HeadlessFrame::new(&gpu, &scene, &[choice], 64, 36)
        .err()
        .unwrap();
    assert!(
        format!("{e:#}").contains("the GPU device was lost"),
        "{e:#}"
    );
}

#[test]
fn unknown_backends_and_missing_adapters_exit_2() {
    let o = shadowlab(&["render", "--backend", "glide", "--out", "/nonexistent"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unknown backend 'glide' (valid: vulkan, gl, metal, dx12, auto)"),
        "{}",
        stderr(&o)
    );
}

/// `--backend gl` renders where the adapter can, and otherwise says why not:
/// no GL adapter, or one that cannot render to a format shadowlab needs.
#[test]
fn the_gl_backend_works_or_says_why_not() {
    let out = tmpdir("gl");
    let o = shadowlab(&[
        "render",
        "--backend",
        "gl",
        "--scene",
        "floating",
        "--size",
        "64x36",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{err}");
    if o.status.success() {
        assert!(out.join("visibility-0.png").exists());
    } else {
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("no graphics adapter found for backend(s) GL")
                || (err.contains("the Gl adapter") && err.contains("cannot render to")),
            "{err}"
        );
    }
}
