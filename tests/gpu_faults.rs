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
