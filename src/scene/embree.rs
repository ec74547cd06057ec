//! Embree 3 (Intel's ray-tracing kernels, Debian package `libembree3-3`),
//! loaded at run time by `libloading` so that shadowlab builds and runs
//! without it: a triangle scene of the shadow casters and occlusion
//! queries for shadow rays (`rtcOccluded1`), with a context filter that
//! asks [`CasterOpacity`] about every candidate hit on a see-through
//! triangle (cut-out holes pass, translucent surfaces attenuate). Declarations follow Embree
//! 3.13's `rtcore.h` (RTCIntersectContext with one instance level and no
//! curve min-width, as Debian builds it).

use super::opacity::{CasterOpacity, Transmittance};
use glam::Vec3;
use std::ffi::{c_char, c_int, c_uint, c_void};
use std::sync::OnceLock;

type Device = *mut c_void;
type Scene = *mut c_void;
type Geometry = *mut c_void;

const GEOMETRY_TYPE_TRIANGLE: c_int = 0;
const BUFFER_TYPE_INDEX: c_int = 0;
const BUFFER_TYPE_VERTEX: c_int = 1;
const FORMAT_UINT3: c_int = 0x5003;
const FORMAT_FLOAT3: c_int = 0x9003;
const BUILD_QUALITY_HIGH: c_int = 2;
const SCENE_FLAG_ROBUST: c_int = 1 << 2;
const SCENE_FLAG_CONTEXT_FILTER_FUNCTION: c_int = 1 << 3;
const INVALID_GEOMETRY_ID: c_uint = u32::MAX;

/// `struct RTCIntersectContext` (RTC_MAX_INSTANCE_LEVEL_COUNT 1, RTC_MIN_WIDTH 0).
#[repr(C)]
struct IntersectContext {
    flags: c_int,
    filter: *const c_void,
    inst_id: [c_uint; 1],
}

/// `struct RTCFilterFunctionNArguments`.
#[repr(C)]
struct FilterArguments {
    valid: *mut c_int,
    geometry_user_ptr: *mut c_void,
    context: *const IntersectContext,
    ray: *mut c_void,
    hit: *mut c_void,
    n: c_uint,
}

/// An intersect context followed by what the filter needs: Embree hands
/// the filter the context pointer it was given.
#[repr(C)]
struct FilterContext<'a> {
    base: IntersectContext,
    opacity: &'a CasterOpacity,
    transmittance: Transmittance,
}

/// The context filter of see-through casters (N = 1: `rtcOccluded1`):
/// rejects the candidate hit unless the ray is now blocked.
unsafe extern "C" fn see_through_filter(args: *const FilterArguments) {
    // SAFETY: Embree passes valid arguments for one ray; the context is the
    // `FilterContext` `transmittance` built; `RTCHit` (N = 1) holds Ng,
    // then u and v as floats, then primID.
    unsafe {
        let args = &*args;
        if *args.valid == 0 {
            return;
        }
        let context = &mut *(args.context as *mut FilterContext);
        let hit = args.hit as *const f32;
        let (u, v) = (*hit.add(3), *hit.add(4));
        let prim = *(hit.add(5) as *const c_uint) as usize;
        if !context
            .transmittance
            .cross(context.opacity.crossing(prim, u, v))
        {
            *args.valid = 0;
        }
    }
}

/// `struct RTCRay`.
#[repr(C, align(16))]
struct Ray {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: c_uint,
    id: c_uint,
    flags: c_uint,
}

/// The entry points shadowlab uses.
struct Api {
    new_device: unsafe extern "C" fn(*const c_char) -> Device,
    release_device: unsafe extern "C" fn(Device),
    new_scene: unsafe extern "C" fn(Device) -> Scene,
    set_scene_flags: unsafe extern "C" fn(Scene, c_int),
    set_scene_build_quality: unsafe extern "C" fn(Scene, c_int),
    new_geometry: unsafe extern "C" fn(Device, c_int) -> Geometry,
    set_new_geometry_buffer:
        unsafe extern "C" fn(Geometry, c_int, c_uint, c_int, usize, usize) -> *mut c_void,
    commit_geometry: unsafe extern "C" fn(Geometry),
    attach_geometry: unsafe extern "C" fn(Scene, Geometry) -> c_uint,
    release_geometry: unsafe extern "C" fn(Geometry),
    commit_scene: unsafe extern "C" fn(Scene),
    release_scene: unsafe extern "C" fn(Scene),
    occluded1: unsafe extern "C" fn(Scene, *mut IntersectContext, *mut Ray),
    // Keeps the functions above loaded.
    #[cfg(not(target_arch = "wasm32"))]
    _library: libloading::Library,
}

#[cfg(not(target_arch = "wasm32"))]
/// File names of the Embree 3 library per platform.
const LIBRARY_NAMES: [&str; 4] = [
    "libembree3.so.3",
    "libembree3.so",
    "libembree3.dylib",
    "embree3.dll",
];

impl Api {
    /// In the browser there is no library to load: the reference traces
    /// with the pure-Rust kernel.
    #[cfg(target_arch = "wasm32")]
    fn load() -> Result<Api, String> {
        Err("Embree 3 is not in the browser build; it traces with the pure-Rust kernel (kernel=obvhs)".into())
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn load() -> Result<Api, String> {
        let mut errors = vec![];
        for name in LIBRARY_NAMES {
            // SAFETY: loading Embree runs its initialisers, which have no
            // preconditions.
            match unsafe { libloading::Library::new(name) } {
                Ok(lib) => return Api::from_library(lib),
                Err(e) => errors.push(e.to_string()),
            }
        }
        Err(format!(
            "Embree 3 not found ({}); install it (Debian: libembree3-3)",
            errors.join("; ")
        ))
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn from_library(lib: libloading::Library) -> Result<Api, String> {
        macro_rules! symbol {
            ($name:literal) => {
                // SAFETY: the types are those of Embree 3's rtcore.h.
                *unsafe { lib.get($name) }.map_err(|e| format!("Embree 3: {e}"))?
            };
        }
        Ok(Api {
            new_device: symbol!(b"rtcNewDevice\0"),
            release_device: symbol!(b"rtcReleaseDevice\0"),
            new_scene: symbol!(b"rtcNewScene\0"),
            set_scene_flags: symbol!(b"rtcSetSceneFlags\0"),
            set_scene_build_quality: symbol!(b"rtcSetSceneBuildQuality\0"),
            new_geometry: symbol!(b"rtcNewGeometry\0"),
            set_new_geometry_buffer: symbol!(b"rtcSetNewGeometryBuffer\0"),
            commit_geometry: symbol!(b"rtcCommitGeometry\0"),
            attach_geometry: symbol!(b"rtcAttachGeometry\0"),
            release_geometry: symbol!(b"rtcReleaseGeometry\0"),
            commit_scene: symbol!(b"rtcCommitScene\0"),
            release_scene: symbol!(b"rtcReleaseScene\0"),
            occluded1: symbol!(b"rtcOccluded1\0"),
            _library: lib,
        })
    }
}

fn api() -> Result<&'static Api, String> {
    static API: OnceLock<Result<Api, String>> = OnceLock::new();
    API.get_or_init(Api::load).as_ref().map_err(Clone::clone)
}

/// Whether Embree can be loaded here.
pub fn available() -> Result<(), String> {
    api().map(|_| ())
}

/// A committed Embree scene of triangles (one device per scene).
pub struct EmbreeScene {
    api: &'static Api,
    device: Device,
    scene: Scene,
    triangles: usize,
    opacity: Option<CasterOpacity>,
}

// SAFETY: a committed Embree scene may be queried from any number of
// threads at once (Embree's API guarantees), and it is only released on drop.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// The scene of `triangles` (world space), robust arithmetic, high
    /// build quality; `opacity` says which of them are see-through.
    pub fn build(
        triangles: &[[Vec3; 3]],
        opacity: Option<CasterOpacity>,
    ) -> Result<EmbreeScene, String> {
        let api = api()?;
        let count = triangles.len();
        // SAFETY: every call follows rtcore.h; the buffers Embree returns
        // have room for `count` items of the given stride.
        unsafe {
            let device = (api.new_device)(std::ptr::null());
            if device.is_null() {
                return Err("Embree 3: rtcNewDevice failed".into());
            }
            let scene = (api.new_scene)(device);
            let filter = if opacity.is_some() {
                SCENE_FLAG_CONTEXT_FILTER_FUNCTION
            } else {
                0
            };
            (api.set_scene_flags)(scene, SCENE_FLAG_ROBUST | filter);
            (api.set_scene_build_quality)(scene, BUILD_QUALITY_HIGH);
            let out = EmbreeScene {
                api,
                device,
                scene,
                triangles: count,
                opacity,
            };
            if count == 0 {
                (api.commit_scene)(scene);
                return Ok(out);
            }
            let geometry = (api.new_geometry)(device, GEOMETRY_TYPE_TRIANGLE);
            let vertices = (api.set_new_geometry_buffer)(
                geometry,
                BUFFER_TYPE_VERTEX,
                0,
                FORMAT_FLOAT3,
                12,
                count * 3,
            ) as *mut f32;
            let indices = (api.set_new_geometry_buffer)(
                geometry,
                BUFFER_TYPE_INDEX,
                0,
                FORMAT_UINT3,
                12,
                count,
            ) as *mut u32;
            if vertices.is_null() || indices.is_null() {
                (api.release_geometry)(geometry);
                return Err("Embree 3: buffer allocation failed".into());
            }
            let vertices = std::slice::from_raw_parts_mut(vertices, count * 9);
            let indices = std::slice::from_raw_parts_mut(indices, count * 3);
            for (i, tri) in triangles.iter().enumerate() {
                for (k, v) in tri.iter().enumerate() {
                    vertices[i * 9 + k * 3..i * 9 + k * 3 + 3].copy_from_slice(&v.to_array());
                    indices[i * 3 + k] = (i * 3 + k) as u32;
                }
            }
            (api.commit_geometry)(geometry);
            (api.attach_geometry)(scene, geometry);
            (api.release_geometry)(geometry);
            (api.commit_scene)(scene);
            Ok(out)
        }
    }

    /// Memory of the scene's vertex and index buffers. Embree's BVH is
    /// not counted: its threaded build allocates a different amount on each
    /// run, and frame.json must not change between runs.
    pub fn bytes(&self) -> u64 {
        (self.triangles * (9 + 3) * 4) as u64
    }

    /// The light that reaches `origin` along `dir` (unit) from distance
    /// `tmax` (infinite for directional lights): 1 unblocked, 0 blocked,
    /// between for translucent casters.
    pub fn transmittance(&self, origin: Vec3, dir: Vec3, tmax: f32) -> f32 {
        let mut ray = Ray {
            org: origin.to_array(),
            tnear: 0.0,
            dir: dir.to_array(),
            time: 0.0,
            tfar: tmax,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        };
        let base = |filter: *const c_void| IntersectContext {
            flags: 0,
            filter,
            inst_id: [INVALID_GEOMETRY_ID],
        };
        let Some(opacity) = &self.opacity else {
            let mut context = base(std::ptr::null());
            // SAFETY: a committed scene, a context and a ray laid out as rtcore.h's.
            unsafe { (self.api.occluded1)(self.scene, &mut context, &mut ray) };
            // Embree sets tfar to −∞ on a hit.
            return (ray.tfar >= 0.0) as u32 as f32;
        };
        let mut context = FilterContext {
            base: base(see_through_filter as *const c_void),
            opacity,
            transmittance: Transmittance::default(),
        };
        // SAFETY: as above; the context starts with an RTCIntersectContext
        // and outlives the call, as the filter requires.
        unsafe {
            (self.api.occluded1)(
                self.scene,
                &mut context as *mut FilterContext as *mut IntersectContext,
                &mut ray,
            )
        };
        if ray.tfar >= 0.0 {
            context.transmittance.value
        } else {
            0.0
        }
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both were created by this value and are released once.
        unsafe {
            (self.api.release_scene)(self.scene);
            (self.api.release_device)(self.device);
        }
    }
}
