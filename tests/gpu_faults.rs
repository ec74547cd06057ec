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
    let mut hf = shadowlab::headless::HeadlessFrame::new(
        &gpu,
        &scene,
        std::slice::from_ref(&choice),
        64,
        36,
    )
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
    let e = shadowlab::headless::HeadlessFrame::new(&gpu, &scene, &[choice], 64, 36)
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
        stderr(&o).contains("unknown backend 'glide' (valid: vulkan, metal, dx12, auto)"),
        "{}",
        stderr(&o)
    );
}

/// `--backend gl` says why shadowlab has no GL backend (wgpu's cannot
/// render to the G-buffer's format), with exit code 2.
#[test]
fn the_gl_backend_is_refused_with_the_reason() {
    let o = shadowlab(&[
        "render",
        "--backend",
        "gl",
        "--scene",
        "floating",
        "--size",
        "64x36",
        "--out",
        "/nonexistent",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the OpenGL backend is not built into shadowlab")
            && err.contains("Rgba32Float"),
        "{err}"
    );
}

/// An allocation the device cannot satisfy (here 16384² × 2048 layers of
/// RGBA32F, 8 TiB, within every per-texture limit) is an out-of-memory
/// error, not a panic or an abort.
#[test]
fn an_allocation_past_the_device_memory_is_an_out_of_memory_error() {
    let gpu = gpu();
    let layers = gpu.device.limits().max_texture_array_layers.min(2048);
    let side = gpu.max_texture_size().min(16384);
    let e = gpu
        .checked("allocating a huge texture", || {
            let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("huge"),
                size: wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            drop(t);
            Ok(())
        })
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("allocating a huge texture: the GPU is out of memory"),
        "{e}"
    );
}
