//! Loader conventions, glTF export round trip and validation, and clear
//! errors (exit code 2, file and line) on bad input.

mod common;
use common::*;
use shadowlab::scene::{self, builtin};
use std::path::Path;

const ROOM_OBJ: &str = "\
mtllib room.mtl
v -5 0 -5\nv 5 0 -5\nv 5 0 5\nv -5 0 5
v -5 0 -5\nv 5 0 -5\nv 5 5 -5\nv -5 5 -5
v 0 1 0\nv 1 1 0\nv 0 2 0\nv 0 1 1
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1
vn 0 1 0
o Floor
usemtl floor
f 1/1/1 4/4/1 3/3/1 2/2/1
o WallsNS
usemtl wall
f 5/1 6/2 7/3 8/4
o ShadowPlaneFloor
f 1 4 3
o Pyramid
s off
f 9 10 11\nf 9 11 12\nf 9 12 10\nf 10 12 11
";

const ROOM_MTL: &str = "\
newmtl floor
Ka 0.1 0.1 0.1
Kd 0.8 0.7 0.6
Ks 0.2 0.2 0.2
Ns 50
d 1
map_Kd missing.png
newmtl wall
Kd 0.5 0.5 0.9
";

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn obj_naming_conventions_and_materials() {
    let dir = tmpdir("obj");
    let obj = write(&dir, "room.obj", ROOM_OBJ);
    write(&dir, "room.mtl", ROOM_MTL);
    let s = scene::load(obj.to_str().unwrap()).unwrap();
    let find = |n: &str| {
        s.objects
            .iter()
            .find(|o| o.name == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    assert!(find("Floor").casts_shadow);
    assert!(!find("WallsNS").casts_shadow && !find("WallsNS").shadow_plane);
    assert!(find("ShadowPlaneFloor").shadow_plane && !find("ShadowPlaneFloor").casts_shadow);
    let floor_mat = &s.materials[find("Floor").material];
    assert_eq!(floor_mat.kd, glam::Vec3::new(0.8, 0.7, 0.6));
    assert_eq!(floor_mat.shininess, 50.0);
    // The missing texture falls back to the flat colour.
    assert!(floor_mat.diffuse_texture.is_none());
    // The quad was triangulated; `s off` made the pyramid flat (unwelded).
    assert_eq!(s.meshes[find("Floor").mesh].triangle_count(), 2);
    let pyr = &s.meshes[find("Pyramid").mesh];
    assert_eq!(pyr.positions.len(), 12);
    // Shadow planes are not drawn.
    assert_eq!(s.triangle_count(), 2 + 2 + 4);
}

/// `shadowlab render` of the scene file `scene` at `size` into `out`, with
/// `extra` arguments.
fn render_file(scene: &str, size: &str, out: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["render", "--scene", scene, "--size", size, "--out", out];
    args.extend_from_slice(extra);
    shadowlab(&args)
}

#[test]
fn missing_texture_warns_and_renders() {
    let dir = tmpdir("missing-tex");
    let obj = write(&dir, "room.obj", ROOM_OBJ);
    write(&dir, "room.mtl", ROOM_MTL);
    let out = dir.join("out");
    let o = render_file(obj.to_str().unwrap(), "64x36", out.to_str().unwrap(), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("missing.png"), "{}", stderr(&o));
    assert!(out.join("image.png").exists());
}

/// Textures that cannot be decoded (`tests/bad_textures/`: a corrupt PNG,
/// one past the decoder's memory limit, a truncated JPEG) leave their
/// material its flat colour with a warning naming the file; the scene
/// renders.
#[test]
fn undecodable_textures_warn_and_render() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_textures");
    let out = tmpdir("bad-textures");
    for (obj, texture) in [
        ("texture-corrupt-png.obj", "texture-corrupt.png"),
        ("texture-huge-png.obj", "texture-huge.png"),
        ("texture-truncated-jpeg.obj", "texture-truncated.jpg"),
    ] {
        let path = dir.join(obj);
        let s = scene::load(path.to_str().unwrap()).unwrap();
        assert!(s.textures.is_empty(), "{obj}");
        let o = render_file(path.to_str().unwrap(), "16x16", out.to_str().unwrap(), &[]);
        assert!(o.status.success(), "{obj}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("{texture}: cannot decode")),
            "{obj}: {}",
            stderr(&o)
        );
    }
}

/// A glTF of one triangle at y = 0 with texture coordinates (0, 0), (1, 0),
/// (0, 1) and material 0 of `materials`, its buffer at `buffer_uri` (the
/// bytes are [`uv_triangle_bytes`]), with `images` and one texture per image.
fn uv_triangle_gltf(
    materials: serde_json::Value,
    images: serde_json::Value,
    buffer_uri: &str,
) -> String {
    let textures: Vec<serde_json::Value> = (0..images.as_array().map_or(0, Vec::len))
        .map(|i| serde_json::json!({ "source": i }))
        .collect();
    serde_json::json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_texture_transform"],
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "material": 0 }] }],
        "materials": materials,
        "textures": textures,
        "images": images,
        "buffers": [{ "byteLength": uv_triangle_bytes().len(), "uri": buffer_uri }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 24 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
              "min": [0, 0, 0], "max": [1, 0, 1] },
            { "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" }
        ]
    })
    .to_string()
}

/// The positions and texture coordinates of [`uv_triangle_gltf`].
fn uv_triangle_bytes() -> Vec<u8> {
    let floats: Vec<f32> = vec![0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 1., 0., 0., 1.];
    floats.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// [`uv_triangle_bytes`] as a data URI.
fn uv_triangle_data_uri() -> String {
    use base64::Engine as _;
    format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(uv_triangle_bytes())
    )
}

/// A glTF whose images are missing loads with a warning naming each and
/// renders its material's flat colour; a missing buffer stays an error.
#[test]
fn missing_gltf_images_warn_and_render() {
    let dir = tmpdir("missing-gltf-image");
    let gltf = |uri: &str| {
        uv_triangle_gltf(
            serde_json::json!([{
                "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } },
                "normalTexture": { "index": 1 }
            }]),
            serde_json::json!([{ "uri": "textures/base.png" }, { "uri": "textures/normal_1.png" }]),
            uri,
        )
    };
    let path = write(&dir, "tri.gltf", &gltf(&uv_triangle_data_uri()));
    let s = scene::load(path.to_str().unwrap()).unwrap();
    assert!(s.textures.is_empty());
    let m = &s.materials[s.objects[0].material];
    assert!(m.diffuse_texture.is_none() && m.normal_map.is_none());
    let out = dir.join("out");
    let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["textures/base.png", "textures/normal_1.png"] {
        assert!(
            stderr(&o).contains(name),
            "{name} not named: {}",
            stderr(&o)
        );
    }
    assert!(out.join("image.png").exists());
    // The file has no light: said when its default light is used, not when
    // --light-type replaces it.
    assert!(
        stderr(&o).contains("placed a default point light"),
        "{}",
        stderr(&o)
    );
    let o = render_file(
        path.to_str().unwrap(),
        "32x32",
        out.to_str().unwrap(),
        &["--light-type", "point", "--light-pos", "0,3,0"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("default point light"),
        "{}",
        stderr(&o)
    );
    let gone = write(&dir, "gone.gltf", &gltf("gone.bin"));
    let err = scene::load(gone.to_str().unwrap()).unwrap_err().to_string();
    assert!(err.contains("'gone.bin' not found"), "{err}");
}

#[test]
fn toml_scene_places_models_and_flags() {
    let dir = tmpdir("toml");
    write(&dir, "room.obj", ROOM_OBJ);
    write(&dir, "room.mtl", ROOM_MTL);
    let toml = write(
        &dir,
        "s.toml",
        r#"
name = "t"
[[model]]
path = "room.obj"
translate = [1.0, 0.0, 0.0]
[[model]]
shape = "sphere"
size = [0.5]
name = "BallNS"
translate = [0.0, 2.0, 0.0]
receives_shadow = false
[[light]]
type = "spot"
position = [0.0, 5.0, 0.0]
direction = [0.0, -1.0, 0.0]
inner_cone_deg = 20.0
outer_cone_deg = 30.0
[camera]
eye = [0.0, 3.0, 8.0]
target = [0.0, 0.0, 0.0]
fov = 45.0
"#,
    );
    let s = scene::load(toml.to_str().unwrap()).unwrap();
    assert_eq!(s.name, "t");
    let ball = s.objects.iter().find(|o| o.name == "BallNS").unwrap();
    assert!(!ball.casts_shadow && !ball.receives_shadow);
    let floor = s.objects.iter().find(|o| o.name == "Floor").unwrap();
    assert_eq!(floor.transform.w_axis.x, 1.0);
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.camera.fov_y_deg, 45.0);
}

#[test]
fn malformed_files_fail_with_file_line_and_exit_2() {
    let dir = tmpdir("bad");
    let cases = [
        (
            "bad.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
            "bad.obj:4:",
        ),
        (
            "nan.obj",
            "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
            "nan.obj:2:",
        ),
        ("bad.toml", "name = \"x\"\n[[model]]\nshape = 3\n", "line 3"),
        (
            "typo.toml",
            "[[model]]\nshape = \"box\"\ncolour = [1,0,0]\n",
            "unknown field `colour`",
        ),
        (
            "bad.gltf",
            "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [ {\"mesh\": 5} ]",
            "bad.gltf: EOF while parsing an object at line 1 column 54",
        ),
        (
            "badindex.gltf",
            "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [ {\"mesh\": 5} ]}",
            "badindex.gltf: invalid glTF: nodes[0].mesh: Index out of bounds",
        ),
    ];
    for (name, text, expect) in cases {
        let p = write(&dir, name, text);
        let o = render_file(
            p.to_str().unwrap(),
            "32x32",
            dir.join("o").to_str().unwrap(),
            &[],
        );
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(expect),
            "{name}: expected '{expect}' in: {}",
            stderr(&o)
        );
        assert!(!stderr(&o).contains("panicked"), "{name}");
    }
    let p = write(
        &dir,
        "badmtl.obj",
        "mtllib badmtl.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    write(&dir, "badmtl.mtl", "newmtl a\nKd 1 x 0\n");
    let o = shadowlab(&[
        "render",
        "--scene",
        p.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("badmtl.mtl:2:"), "{}", stderr(&o));
}

#[test]
fn no_adapter_names_the_driver_package_and_exits_2() {
    // No DX12 adapter exists on Linux: the same path as a machine without a Vulkan driver.
    if cfg!(target_os = "linux") {
        let o = shadowlab(&[
            "render",
            "--backend",
            "dx12",
            "--size",
            "16x16",
            "--out",
            tmpdir("noadapter").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        assert!(stderr(&o).contains("mesa-vulkan-drivers"), "{}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
}

#[test]
fn degenerate_triangles_are_skipped_and_counted() {
    let dir = tmpdir("degenerate");
    let p = write(
        &dir,
        "d.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n",
    );
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.triangle_count(), 1);
    let o = render_file(
        p.to_str().unwrap(),
        "32x32",
        dir.join("o").to_str().unwrap(),
        &[],
    );
    assert!(o.status.success());
    assert!(
        stderr(&o).contains("skipped 1 degenerate triangle"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_cli_values_list_the_valid_ones() {
    let checks: [(&[&str], &str); 7] = [
        (&["render", "--technique", "nope"], "none:default"),
        (
            &["render", "--technique", "none:nope"],
            "valid: none:default",
        ),
        (&["render", "--set", "bias=1"], "unknown parameter 'bias'"),
        (&["render", "--scene", "nowhere"], "room, bunny, floating"),
        (&["render", "--camera", "nope"], "valid: default, top, low"),
        (&["render", "--light", "nope"], "valid: point, spot, sun"),
        (&["render", "--size", "0x10"], "at least 1x1"),
    ];
    for (args, expect) in checks {
        let o = shadowlab(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(
            stderr(&o).contains(expect),
            "{args:?}: expected '{expect}' in {}",
            stderr(&o)
        );
    }
}

/// The binary's listing and measuring commands succeed and say what they
/// wrote: every built-in scene and every preset listed, `render`,
/// `compare` (a frame and a path) and `bench` write their tables, print no
/// line with "error" (headless runs do not probe the window system), and
/// `bench` names its adapter first.
#[test]
fn listing_and_measuring_commands_succeed_and_write_their_tables() {
    let o = shadowlab(&["scenes"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let listed = String::from_utf8_lossy(&o.stdout).to_string();
    for name in shadowlab::scene::builtin::NAMES {
        assert!(
            listed.lines().any(|l| l.starts_with(name)),
            "{name} not in scenes"
        );
    }
    let o = shadowlab(&["techniques"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let listed = String::from_utf8_lossy(&o.stdout).to_string();
    for id in shadowlab::technique::preset_ids() {
        assert!(listed.contains(&id), "{id} not in techniques");
    }
    let dir = tmpdir("measuring-commands");
    let run = |args: &[&str], wrote: &str| {
        let out = dir.join(args[0]);
        let mut all = args.to_vec();
        all.extend([
            "--scene",
            "floating",
            "--size",
            "32x24",
            "--out",
            out.to_str().unwrap(),
        ]);
        let o = shadowlab(&all);
        assert!(o.status.success(), "{all:?}: {}", stderr(&o));
        assert!(out.join(wrote).is_file(), "{all:?}: no {wrote}");
        let said = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
        assert!(
            !said.to_lowercase().contains("error"),
            "{all:?} succeeded but said: {said}"
        );
        String::from_utf8_lossy(&o.stdout).to_string()
    };
    run(&["render", "--technique", "shadow-map"], "image.png");
    let table = run(
        &["compare", "--techniques", "none,shadow-volume"],
        "quality.md",
    );
    assert!(
        table.contains("int.MAE") && table.contains("shadow-volume:auto"),
        "{table}"
    );
    run(
        &[
            "compare",
            "--techniques",
            "shadow-map",
            "--path",
            "strafe",
            "--frames",
            "2",
        ],
        "flicker.md",
    );
    let bench = run(
        &["bench", "--techniques", "shadow-map", "--frames", "2"],
        "bench.md",
    );
    assert!(bench.starts_with("adapter: "), "{bench}");
    assert!(bench.contains("shadow-map:pcf"), "{bench}");
}

/// Bad arguments and places the run cannot write: exit code 2 and an error
/// that names what was wrong, before any frame is rendered.
#[test]
fn bad_arguments_and_unwritable_places_exit_2_naming_them() {
    let dir = tmpdir("bad-arguments");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let lights = "[[model]]\nshape = \"sphere\"\nsize = [0.5]\n".to_string()
        + &"[[light]]\ntype = \"point\"\nposition = [0.0, 3.0, 0.0]\n".repeat(5);
    let five = write(&dir, "five-lights.toml", &lights);
    let five_lights = format!("{}: 5 lights; at most 4 are supported", five.display());
    let checks: [(&[&str], &str); 7] = [
        (
            &["render", "--scene", five.to_str().unwrap(), "--out", out],
            &five_lights,
        ),
        (
            &[
                "render",
                "--light-type",
                "directional",
                "--light-dir",
                "0,0,0",
                "--out",
                out,
            ],
            "directional light has no direction: it is zero",
        ),
        (
            &["render", "--eye", "1,2", "--out", out],
            "expected three finite numbers",
        ),
        (
            &["render", "--eye", "1,2,nan", "--out", out],
            "expected three finite numbers",
        ),
        (
            &["render", "--size", "16x16", "--out", "/proc/none/x"],
            "creating /proc/none/x",
        ),
        (
            &[
                "render",
                "--log-file",
                "/nonexistent/dir/x.log",
                "--out",
                out,
            ],
            "cannot open log file /nonexistent/dir/x.log",
        ),
        (
            &[
                "compare", "--size", "16x16", "--path", "strafe", "--frames", "1", "--out", out,
            ],
            "--frames 1: a path needs 2",
        ),
    ];
    for (args, expect) in checks {
        let o = shadowlab(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(expect),
            "{args:?}: expected '{expect}' in {}",
            stderr(&o)
        );
    }
}

/// Triangles of the drawn objects in world space, each as sorted vertex
/// tuples rounded to 1e-4 (order-independent comparison).
fn triangle_set(s: &scene::Scene) -> Vec<[[i64; 3]; 3]> {
    let q = |v: glam::Vec3| {
        [
            (v.x * 1e4).round() as i64,
            (v.y * 1e4).round() as i64,
            (v.z * 1e4).round() as i64,
        ]
    };
    let mut t: Vec<[[i64; 3]; 3]> = s
        .world_triangles(|_| true)
        .into_iter()
        .map(|t| {
            let mut v = t.map(q);
            v.sort();
            v
        })
        .collect();
    t.sort();
    t
}

#[test]
fn export_round_trip_keeps_triangles_flags_lights_and_camera() {
    let dir = tmpdir("export");
    for name in builtin::NAMES.iter().filter(|n| **n != "city") {
        let s = builtin::by_name(name).unwrap().unwrap();
        let path = dir.join(format!("{name}.gltf"));
        scene::gltf_io::export(&s, &path).unwrap();
        let back = scene::load(path.to_str().unwrap()).unwrap();
        assert_eq!(triangle_set(&s), triangle_set(&back), "{name}");
        let flags = |s: &scene::Scene| {
            s.objects
                .iter()
                .map(|o| {
                    (
                        o.name.clone(),
                        o.casts_shadow,
                        o.receives_shadow,
                        o.shadow_plane,
                    )
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(flags(&s), flags(&back), "{name}");
        assert_eq!(s.lights.len(), back.lights.len());
        for (a, b) in s.lights.iter().zip(&back.lights) {
            assert_eq!(a.kind, b.kind);
            assert!(
                (a.direction - b.direction).length() < 1e-4,
                "{name}: {a:?} {b:?}"
            );
            if a.kind != shadowlab::scene::LightType::Directional {
                assert!((a.position - b.position).length() < 1e-4);
            }
        }
        assert!((s.camera.eye - back.camera.eye).length() < 1e-4);
        let dir_a = (s.camera.target - s.camera.eye).normalize();
        let dir_b = (back.camera.target - back.camera.eye).normalize();
        assert!((dir_a - dir_b).length() < 1e-4, "{name}");
        assert_eq!(
            s.materials.iter().map(|m| m.kd).collect::<Vec<_>>(),
            back.materials[..s.materials.len()]
                .iter()
                .map(|m| m.kd)
                .collect::<Vec<_>>()
        );
    }
}

/// Runs the Khronos glTF validator (npm package `gltf-validator`, installed
/// into tools/ by the test script) on every built-in scene's export, and on
/// one binary export.
#[test]
fn khronos_validator_finds_no_errors_in_exports() {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools");
    assert!(
        tools.join("node_modules/gltf-validator").exists(),
        "gltf-validator is not installed: run `npm ci --prefix tools` (scripts/test.sh does)"
    );
    let dir = tmpdir("validator");
    let files = builtin::NAMES
        .iter()
        .map(|name| (*name, "gltf"))
        .chain([("foliage", "glb")]);
    for (name, ext) in files {
        let path = dir.join(format!("{name}.{ext}"));
        let o = shadowlab(&["export", "--scene", name, "--out", path.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v = std::process::Command::new("node")
            .arg(tools.join("validate-gltf.mjs"))
            .arg(&path)
            .output()
            .expect("node");
        let report = String::from_utf8_lossy(&v.stdout);
        assert!(
            v.status.success(),
            "{name}: {report} {}",
            String::from_utf8_lossy(&v.stderr)
        );
        let j: serde_json::Value = serde_json::from_str(report.trim()).unwrap();
        assert_eq!(j["errors"], 0, "{name}: {report}");
    }
}

/// A FIFO (or a device) named as a scene, an MTL library or a model to
/// include would block a reader forever: refused or skipped, never a hang.
#[test]
fn special_files_never_hang_a_loader() {
    let dir = tmpdir("fifo");
    let fifo = dir.join("pipe.obj");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let e = format!("{:#}", scene::load(fifo.to_str().unwrap()).unwrap_err());
    assert!(e.contains("pipe.obj: not a regular file"), "{e}");
    // An OBJ whose MTL library is a FIFO loads with the grey default.
    std::process::Command::new("mkfifo")
        .arg(dir.join("pipe.mtl"))
        .status()
        .unwrap();
    let obj = write(
        &dir,
        "m.obj",
        "mtllib pipe.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    scene::load(obj.to_str().unwrap()).unwrap();
    // A TOML file including a FIFO.
    let toml = write(&dir, "t.toml", "[[model]]\npath = \"pipe.obj\"\n");
    let e = format!("{:#}", scene::load(toml.to_str().unwrap()).unwrap_err());
    assert!(e.contains("pipe.obj: not a regular file"), "{e}");
}

/// TOML models override their materials' opacity and sidedness; an
/// opacity out of range is an error naming the field.
#[test]
fn toml_models_set_alpha_and_double_sidedness() {
    let dir = tmpdir("toml-alpha");
    let good = write(
        &dir,
        "glass.toml",
        "[[model]]\nshape = \"plane\"\nsize = [4.0]\n[[model]]\nshape = \"box\"\nalpha_mode = \"blend\"\nalpha = 0.3\ndouble_sided = true\n",
    );
    let s = scene::load(good.to_str().unwrap()).unwrap();
    let glass = &s.materials[s.objects[1].material];
    assert_eq!(glass.alpha_mode, scene::AlphaMode::Blend);
    assert_eq!(glass.alpha, 0.3);
    assert!(glass.double_sided);
    let mesh = &s.meshes[s.objects[1].mesh];
    assert!(mesh.sides_doubled);
    assert_eq!(
        mesh.triangle_count(),
        24,
        "a box's 12 triangles and their back faces"
    );
    assert_eq!(
        s.materials[s.objects[0].material].alpha_mode,
        scene::AlphaMode::Opaque
    );
    let bad = write(
        &dir,
        "bad.toml",
        "[[model]]\nshape = \"plane\"\nalpha_mode = \"mask\"\nalpha_cutoff = 1.5\n",
    );
    let e = format!("{:#}", scene::load(bad.to_str().unwrap()).unwrap_err());
    assert!(e.contains("alpha_cutoff must be in 0..=1, got 1.5"), "{e}");
    let unknown = write(
        &dir,
        "unknown.toml",
        "[[model]]\nshape = \"plane\"\nalpha_mode = \"glass\"\n",
    );
    let e = format!("{:#}", scene::load(unknown.to_str().unwrap()).unwrap_err());
    assert!(e.contains("unknown variant `glass`"), "{e}");
}

/// `export --out x.glb` writes one binary glTF (magic, version 2, JSON and
/// BIN chunks), which loads back as the same scene.
#[test]
fn export_to_glb_writes_one_binary_file() {
    let dir = tmpdir("glb-export");
    let path = dir.join("room.glb");
    let o = shadowlab(&[
        "export",
        "--scene",
        "foliage",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );
    assert_eq!(&bytes[16..20], b"JSON");
    assert!(!dir.join("room.bin").exists(), "no buffer beside it");
    let back = scene::load(path.to_str().unwrap()).unwrap();
    let original = scene::builtin::by_name("foliage").unwrap().unwrap();
    assert_eq!(back.triangle_count(), original.triangle_count());
    assert_eq!(back.textures.len(), original.textures.len());
}

/// `--set` of a parameter that does nothing for the chosen light or
/// values warns (and the run goes on); one that acts does not.
#[test]
fn set_of_a_parameter_without_effect_warns() {
    let dir = tmpdir("set-without-effect");
    let out = dir.to_str().unwrap();
    let run = |set: &str| {
        let o = shadowlab(&[
            "render",
            "--scene",
            "room",
            "--light",
            "point",
            "--technique",
            "shadow-map",
            "--size",
            "32x24",
            "--set",
            set,
            "--out",
            out,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let e = run("cascades=4");
    assert!(
        e.contains("--set cascades (applies to directional lights): it has no effect on light 0"),
        "{e}"
    );
    let e = run("omni=dual-paraboloid");
    assert!(!e.contains("no effect"), "{e}");
}

/// KHR_texture_transform on the base colour texture (offset, rotation,
/// scale, as the extension's matrix T·R·S) is baked into the primitive's
/// texture coordinates.
#[test]
fn gltf_texture_transforms_are_baked_into_the_uvs() {
    let dir = tmpdir("texture-transform");
    let gltf = uv_triangle_gltf(
        serde_json::json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0,
            "extensions": { "KHR_texture_transform": {
                "offset": [0.5, 0.25], "rotation": std::f32::consts::FRAC_PI_2, "scale": [2.0, 3.0] } } } } }]),
        serde_json::json!([{ "uri": "missing.png" }]),
        &uv_triangle_data_uri(),
    );
    let path = write(&dir, "tri.gltf", &gltf);
    let s = scene::load(path.to_str().unwrap()).unwrap();
    let uvs = &s.meshes[s.objects[0].mesh].uvs;
    // uv (1, 0): scaled (2, 0), turned a quarter (0, 2), offset (0.5, 2.25);
    // uv (0, 1): (0, 3) → (−3, 0) → (−2.5, 0.25); (0, 0) → the offset.
    for (got, want) in uvs.iter().zip([[0.5, 0.25], [0.5, 2.25], [-2.5, 0.25]]) {
        assert!(
            (got.x - want[0]).abs() < 1e-5 && (got.y - want[1]).abs() < 1e-5,
            "{uvs:?}"
        );
    }
}

/// A glTF scene that lists a child as a root (glTF forbids it; Kenney's
/// models do it): each node is drawn once, with a warning — a child listed
/// beside its parent under the parent, one whose parent the scene leaves
/// out from itself, without the parent's transform (as Bevy and three.js
/// draw it).
#[test]
fn scenes_listing_children_as_roots_draw_each_node_once() {
    let dir = tmpdir("root-is-child");
    let buffer = "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=";
    for (listed, x) in [("[0, 1]", 5.0), ("[1]", 0.0)] {
        let text = format!(
            r#"{{"asset": {{"version": "2.0"}},
            "buffers": [{{"uri": "{buffer}", "byteLength": 44}}],
            "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
            "nodes": [{{"name": "tmpParent", "children": [1], "translation": [5, 0, 0]}}, {{"mesh": 0, "translation": [0, 0, 1]}}],
            "scenes": [{{"nodes": {listed}}}], "scene": 0}}"#
        );
        let path = write(&dir, "child.gltf", &text);
        let s = scene::load(path.to_str().unwrap()).unwrap();
        assert_eq!(s.objects.len(), 1, "scene {listed}");
        let at = s.objects[0].transform.w_axis;
        assert_eq!((at.x, at.z), (x, 1.0), "scene {listed}");
        let out = dir.join("out");
        let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("lists node 1 as a root"),
            "{}",
            stderr(&o)
        );
    }
}

/// A glTF whose caster, a unit quad standing at z = 0, is drawn as
/// `mode` (4 triangles, 5 a strip, 6 a fan) with its four vertices in
/// `order` (of (−1, 1), (1, 1), (1, 2), (−1, 2) in x, y).
fn quad_gltf(mode: u32, order: [usize; 4]) -> String {
    use base64::Engine as _;
    let corners = [[-1f32, 1., 0.], [1., 1., 0.], [1., 2., 0.], [-1., 2., 0.]];
    let mut bytes: Vec<u8> = order
        .iter()
        .flat_map(|&i| corners[i])
        .flat_map(f32::to_le_bytes)
        .collect();
    let indices: &[u16] = if mode == 4 {
        &[0, 1, 2, 0, 2, 3]
    } else {
        &[0, 1, 2, 3]
    };
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    serde_json::json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "mode": mode }] }],
        "buffers": [{ "byteLength": bytes.len(), "uri": uri }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": indices.len() * 2 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-1, 1, 0], "max": [1, 2, 0] },
            { "bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR" }
        ]
    })
    .to_string()
}

/// Triangle strips and fans are drawn as the triangles they describe (not
/// skipped): the same quad as a strip, a fan and a triangle list covers the
/// same area, every triangle facing +z as the list's do.
#[test]
fn gltf_strips_and_fans_draw_their_triangles() {
    let dir = tmpdir("strips-fans");
    let faces = |mode: u32, order: [usize; 4]| {
        let path = write(&dir, &format!("quad{mode}.gltf"), &quad_gltf(mode, order));
        let s = scene::load(path.to_str().unwrap()).unwrap();
        let mesh = &s.meshes[s.objects[0].mesh];
        mesh.indices
            .chunks(3)
            .map(|t| {
                let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
                (b - a).cross(c - a)
            })
            .collect::<Vec<_>>()
    };
    // Strip order: bottom left, bottom right, top left, top right.
    for (mode, order) in [(4, [0, 1, 2, 3]), (5, [0, 1, 3, 2]), (6, [0, 1, 2, 3])] {
        let normals = faces(mode, order);
        assert_eq!(normals.len(), 2, "mode {mode}");
        let area: f32 = normals.iter().map(|n| 0.5 * n.length()).sum();
        assert!((area - 2.0).abs() < 1e-6, "mode {mode}: area {area}");
        assert!(
            normals.iter().all(|n| n.z > 0.0),
            "mode {mode}: {normals:?}"
        );
    }
}

/// The one texture coordinate set a mesh keeps is the one its base colour
/// texture reads (`texCoord`, or its KHR_texture_transform's), whose alpha
/// cuts a cut-out's holes: not always `TEXCOORD_0`.
#[test]
fn gltf_meshes_keep_the_uv_set_of_their_base_colour_texture() {
    let dir = tmpdir("uv-set");
    // The triangle with a TEXCOORD_1 of `component`s: the first 24 bytes
    // of the positions, as floats three pairs (0, 0), (0, 1), (0, 0).
    let gltf = |texture: serde_json::Value, component: u32, view: u32| {
        let text = uv_triangle_gltf(
            serde_json::json!([{ "pbrMetallicRoughness": { "baseColorTexture": texture } }]),
            serde_json::json!([{ "uri": "missing.png" }]),
            &uv_triangle_data_uri(),
        );
        let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
        doc["accessors"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({
            "bufferView": view, "componentType": component, "count": 3, "type": "VEC2" }));
        doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = serde_json::json!(2);
        write(&dir, "tri.gltf", &doc.to_string())
    };
    let uvs_of = |path: std::path::PathBuf| {
        let s = scene::load(path.to_str().unwrap()).unwrap();
        let uvs = &s.meshes[s.objects[0].mesh].uvs;
        uvs.iter().map(|v| [v.x, v.y]).collect::<Vec<_>>()
    };
    let load = |texture: serde_json::Value| uvs_of(gltf(texture, 5126, 0));
    let set0 = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let set1 = [[0.0, 0.0], [0.0, 1.0], [0.0, 0.0]];
    assert_eq!(load(serde_json::json!({ "index": 0 })), set0);
    assert_eq!(load(serde_json::json!({ "index": 0, "texCoord": 1 })), set1);
    let transformed = serde_json::json!({ "index": 0,
        "extensions": { "KHR_texture_transform": { "texCoord": 1 } } });
    assert_eq!(load(transformed), set1);
    // Unsigned shorts are normalised, as core glTF requires, also where the
    // file forgets the flag: the first 12 bytes of TEXCOORD_0's floats (0,
    // 0, 1) read as (0, 0), (0, 0), (0, 0x3f80).
    let ushorts = uvs_of(gltf(
        serde_json::json!({ "index": 0, "texCoord": 1 }),
        5123,
        1,
    ));
    assert_eq!(ushorts, [[0.0, 0.0], [0.0, 0.0], [0.0, 16256.0 / 65535.0]]);
    // The set read is checked as TEXCOORD_0 is: signed shorts are refused.
    let shorts = gltf(serde_json::json!({ "index": 0, "texCoord": 1 }), 5122, 0);
    let e = format!("{:#}", scene::load(shorts.to_str().unwrap()).unwrap_err());
    assert!(e.contains("TEXCOORD_1 accessor 2 is Vec2 of I16"), "{e}");
}

/// A glTF of one quad under KHR_mesh_quantization (as gltfpack writes
/// them): positions normalised signed shorts (stride 8), normals
/// normalised signed bytes (stride 4), the extension required when
/// `required`.
fn quantized_quad_gltf(required: bool) -> String {
    use base64::Engine as _;
    let corners: [[i16; 3]; 4] = [
        [-32767, 16384, 0],
        [32767, 16384, 0],
        [32767, 32767, 0],
        [-32767, 32767, 0],
    ];
    let mut bytes: Vec<u8> = corners
        .iter()
        .flat_map(|c| [c[0], c[1], c[2], 0])
        .flat_map(i16::to_le_bytes)
        .collect();
    bytes.extend([0u8, 0, 127, 0].repeat(4));
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    let required: &[&str] = if required {
        &["KHR_mesh_quantization"]
    } else {
        &[]
    };
    serde_json::json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": required,
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "scale": [2.0, 2.0, 2.0] }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1 }, "indices": 2 }] }],
        "buffers": [{ "byteLength": bytes.len(), "uri": uri }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 32, "byteStride": 8 },
            { "buffer": 0, "byteOffset": 32, "byteLength": 16, "byteStride": 4 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5122, "normalized": true, "count": 4, "type": "VEC3",
              "min": [-32767, 16384, 0], "max": [32767, 32767, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    })
    .to_string()
}

/// KHR_mesh_quantization (gltfpack's default output) loads, required or
/// not: normalised shorts and bytes become floats in [−1, 1], the node's
/// scale places them, normals are unit. Integer positions in a file that
/// does not use the extension stay an error.
#[test]
fn gltf_quantized_attributes_load_as_floats() {
    let dir = tmpdir("quantized");
    for required in [true, false] {
        let path = write(&dir, "quad.gltf", &quantized_quad_gltf(required));
        let s = scene::load(path.to_str().unwrap()).unwrap();
        let mesh = &s.meshes[s.objects[0].mesh];
        let half = 16384.0 / 32767.0;
        let want = [
            [-1.0, half, 0.0],
            [1.0, half, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ];
        for (got, want) in mesh.positions.iter().zip(want) {
            assert!(got.distance(want.into()) < 1e-6, "{:?}", mesh.positions);
        }
        assert!(
            mesh.normals
                .iter()
                .all(|n| n.distance(glam::Vec3::Z) < 1e-6)
        );
        let world = s.objects[0].transform.transform_point3(mesh.positions[2]);
        assert!(
            world.distance(glam::Vec3::new(2.0, 2.0, 0.0)) < 1e-5,
            "{world}"
        );
    }
    let mut plain: serde_json::Value = serde_json::from_str(&quantized_quad_gltf(false)).unwrap();
    plain.as_object_mut().unwrap().remove("extensionsUsed");
    let path = write(&dir, "plain.gltf", &plain.to_string());
    let e = format!("{:#}", scene::load(path.to_str().unwrap()).unwrap_err());
    assert!(e.contains("POSITION accessor 0 is Vec3 of I16"), "{e}");
}

/// `compare` warns where a sub-pixel technique is measured against pixel
/// centres, naming the supersampled reference, and not where it is
/// measured against that reference.
#[test]
fn compare_points_sub_pixel_techniques_to_the_supersampled_reference() {
    let dir = tmpdir("sub-pixel-reference");
    let out = dir.to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "compare",
            "--scene",
            "room",
            "--size",
            "16x16",
            "--techniques",
            "irregular:subpixel",
            "--out",
            out,
        ];
        args.extend_from_slice(extra);
        let o = shadowlab(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let hint = "measure it with --reference raytraced:subpixel";
    assert!(run(&[]).contains(hint));
    assert!(!run(&["--reference", "raytraced:subpixel"]).contains(hint));
}

/// A file that requires KHR_texture_basisu, its texture a KTX2 image only
/// (which the `image` crate cannot decode), loads and renders: the image is
/// warned about and the material keeps its flat colour, as for a missing
/// one; it was refused ("Unsupported extension").
#[test]
fn ktx2_only_textures_warn_and_render_flat() {
    let dir = tmpdir("ktx2-texture");
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    std::fs::write(
        dir.join("textures/base.ktx2"),
        b"\xABKTX 20\xBB\r\n\x1A\n not a real one",
    )
    .unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&uv_triangle_gltf(
        serde_json::json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]),
        serde_json::json!([{ "uri": "textures/base.ktx2", "mimeType": "image/ktx2" }]),
        &uv_triangle_data_uri(),
    ))
    .unwrap();
    doc["extensionsUsed"] = serde_json::json!(["KHR_texture_basisu"]);
    doc["extensionsRequired"] = serde_json::json!(["KHR_texture_basisu"]);
    doc["textures"] =
        serde_json::json!([{ "extensions": { "KHR_texture_basisu": { "source": 0 } } }]);
    let path = write(&dir, "tri.gltf", &doc.to_string());
    let s = scene::load(path.to_str().unwrap()).unwrap();
    assert!(s.textures.is_empty());
    assert!(s.materials[s.objects[0].material].diffuse_texture.is_none());
    let out = dir.join("out");
    let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("image 0"), "{}", stderr(&o));
}

/// The mean red and green of the drawn pixels of `scene` (shadows off), as
/// linear values.
fn mean_red_green(scene: &scene::Scene) -> (f64, f64) {
    let img = render(scene, "none", 96, 96);
    let drawn: Vec<&[u8]> = img
        .color
        .chunks_exact(4)
        .zip(&img.coverage)
        .filter(|(_, c)| **c)
        .map(|(p, _)| p)
        .collect();
    let linear = |c: u8| ((c as f64 / 255.0 + 0.055) / 1.055).powf(2.4);
    let mean = |k: usize| drawn.iter().map(|p| linear(p[k])).sum::<f64>() / drawn.len() as f64;
    (mean(0), mean(1))
}

/// Vertex colours (glTF `COLOR_0`, OBJ `v x y z r g b`) multiply the
/// material's colour: a grey floor whose vertices are pure red renders red
/// (its green is the specular highlight's and the ambient's alone), and
/// keeps its colours through export → import.
#[test]
fn vertex_colours_tint_the_material_and_survive_export() {
    use glam::Vec3;
    let sun = scene::Light::directional(Vec3::new(0.3, -1.0, 0.2), 1.0);
    let white = squares_over_floor(&[], sun, false);
    let mut red = white.clone();
    let floor = red.objects[0].mesh;
    let n = red.meshes[floor].positions.len();
    red.meshes[floor].colors = vec![Vec3::new(1.0, 0.0, 0.0); n];
    let (wr, wg) = mean_red_green(&white);
    let (rr, rg) = mean_red_green(&red);
    assert!(
        (wg - wr).abs() < 0.05 * wr,
        "white floor: red {wr}, green {wg}"
    );
    assert!(
        rg < 0.15 * wg && (rr - wr).abs() < 0.05 * wr,
        "red floor: red {rr}, green {rg}; white floor: {wr}, {wg}"
    );

    let path = tmpdir("vertex-colours").join("red.glb");
    scene::gltf_io::export(&red, &path).unwrap();
    let back = scene::load_file(&path).unwrap();
    let coloured: Vec<&scene::Mesh> = back
        .meshes
        .iter()
        .filter(|m| !m.colors.is_empty())
        .collect();
    assert_eq!(coloured.len(), 1);
    assert!(
        coloured[0]
            .colors
            .iter()
            .all(|&c| c == Vec3::new(1.0, 0.0, 0.0))
    );

    let dir = tmpdir("vertex-colours-obj");
    std::fs::write(
        dir.join("tri.obj"),
        "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 0 1 0 0 1\nf 1 2 3\n",
    )
    .unwrap();
    let obj = scene::load_file(&dir.join("tri.obj")).unwrap();
    let m = &obj.meshes[obj.objects[0].mesh];
    assert_eq!(m.colors.len(), 3, "{:?}", m.colors);
    assert!(m.colors.contains(&Vec3::new(0.0, 1.0, 0.0)));
}

/// A file that requires material extensions loads: KHR_materials_
/// pbrSpecularGlossiness's diffuse is its base colour and alpha, and each
/// extension the lab does not read (unlit, transmission) is named in a
/// warning, the material taken as its core glTF one; both used to refuse
/// the file ("Unsupported extension"; 5 of the 67 glTF files of Khronos'
/// glTF-Blender-IO tests). A required extension that changes geometry
/// (meshopt compression) is still refused, naming it as the cause (a
/// Draco-compressed file used to fail with one "Missing data" per accessor).
#[test]
fn required_material_extensions_load_with_their_core_material() {
    let dir = tmpdir("material-extensions");
    let mut doc: serde_json::Value = serde_json::from_str(&uv_triangle_gltf(
        serde_json::json!([{
            "alphaMode": "MASK",
            "alphaCutoff": 0.25,
            "extensions": {
                "KHR_materials_pbrSpecularGlossiness": { "diffuseFactor": [0.2, 0.4, 0.6, 0.3] },
                "KHR_materials_unlit": {},
                "KHR_materials_transmission": { "transmissionFactor": 1.0 }
            }
        }]),
        serde_json::json!([]),
        &uv_triangle_data_uri(),
    ))
    .unwrap();
    let required = [
        "KHR_materials_pbrSpecularGlossiness",
        "KHR_materials_unlit",
        "KHR_materials_transmission",
    ];
    doc["extensionsUsed"] = serde_json::json!(required);
    doc["extensionsRequired"] = serde_json::json!(required);
    let path = write(&dir, "tri.gltf", &doc.to_string());
    let s = scene::load(path.to_str().unwrap()).unwrap();
    let m = &s.materials[s.objects[0].material];
    assert!(
        (m.kd - glam::Vec3::new(0.2, 0.4, 0.6)).abs().max_element() < 1e-6
            && (m.alpha - 0.3).abs() < 1e-6
            && m.alpha_mode == scene::AlphaMode::Mask
            && (m.alpha_cutoff - 0.25).abs() < 1e-6,
        "{m:?}"
    );
    let out = dir.join("out");
    let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("requires KHR_materials_unlit")
            && err.contains("requires KHR_materials_transmission")
            && !err.contains("requires KHR_materials_pbrSpecularGlossiness"),
        "{err}"
    );
    doc["extensionsUsed"] = serde_json::json!(["EXT_meshopt_compression"]);
    doc["extensionsRequired"] = serde_json::json!(["EXT_meshopt_compression"]);
    let path = write(&dir, "meshopt.gltf", &doc.to_string());
    let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("requires the glTF extension EXT_meshopt_compression")
            && stderr(&o).contains("compressed geometry"),
        "{}",
        stderr(&o)
    );
}

/// A glTF without scenes draws every node without a parent, and one whose
/// animations the `gltf` crate cannot parse (a KHR_animation_pointer
/// channel targets no node) loads its rest pose, each with a warning; both
/// were refused ("no scene", "missing field `node`": Khronos' glTF-Blender-IO
/// tests `00_no_scenes` and `24_animation_pointer`).
#[test]
fn files_without_scenes_or_with_pointer_animations_load_with_a_warning() {
    let dir = tmpdir("no-scene-pointer-animation");
    let triangle = || -> serde_json::Value {
        serde_json::from_str(&uv_triangle_gltf(
            serde_json::json!([{}]),
            serde_json::json!([]),
            &uv_triangle_data_uri(),
        ))
        .unwrap()
    };
    let mut no_scene = triangle();
    let o = no_scene.as_object_mut().unwrap();
    o.remove("scene");
    o.remove("scenes");
    let mut animated = triangle();
    animated["animations"] = serde_json::json!([{
        "channels": [{ "sampler": 0, "target": { "path": "pointer",
            "extensions": { "KHR_animation_pointer": { "pointer": "/materials/0/alphaCutoff" } } } }],
        "samplers": [{ "input": 0, "output": 0 }]
    }]);
    for (name, doc, warning) in [
        ("no-scene.gltf", no_scene, "no scene; drawing every node"),
        ("animated.gltf", animated, "animations cannot be read"),
    ] {
        let path = write(&dir, name, &doc.to_string());
        let s = scene::load(path.to_str().unwrap()).unwrap();
        assert_eq!(s.objects.len(), 1, "{name}");
        let out = dir.join("out");
        let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        assert!(stderr(&o).contains(warning), "{name}: {}", stderr(&o));
    }
}

/// A mesh with morph targets is drawn at its rest pose: each target's
/// displacements added at the mesh's default weight (glTF 2.0 § 3.7.2.2).
/// They were ignored, drawing the base geometry (Khronos' `SimpleMorph` and
/// `MorphPrimitivesTest` weigh their targets ½). Here the one target is the
/// triangle's own positions at weight ½: every vertex moves to 1.5 times
/// itself. A target whose displacements do not match the vertices is
/// skipped with a warning.
#[test]
fn gltf_morph_targets_are_drawn_at_their_default_weights() {
    let dir = tmpdir("morph");
    let mut doc: serde_json::Value = serde_json::from_str(&uv_triangle_gltf(
        serde_json::json!([{}]),
        serde_json::json!([]),
        &uv_triangle_data_uri(),
    ))
    .unwrap();
    doc["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{ "POSITION": 0 }]);
    doc["meshes"][0]["weights"] = serde_json::json!([0.5]);
    let path = write(&dir, "morph.gltf", &doc.to_string());
    let s = scene::load(path.to_str().unwrap()).unwrap();
    let expected = vec![[[0, 0, 0], [0, 0, 15000], [15000, 0, 0]]];
    assert_eq!(triangle_set(&s), expected);
    // A target of two displacements for three vertices is left out.
    doc["accessors"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!(
        { "bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3",
          "min": [0, 0, 0], "max": [1, 0, 0] }));
    doc["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{ "POSITION": 2 }]);
    let path = write(&dir, "short.gltf", &doc.to_string());
    let out = dir.join("out");
    let o = render_file(path.to_str().unwrap(), "32x32", out.to_str().unwrap(), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("morph target 0's displacements do not match its vertices"),
        "{}",
        stderr(&o)
    );
}
