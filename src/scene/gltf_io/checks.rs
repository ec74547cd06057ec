//! A glTF file's structure checked before it is trusted to the importer:
//! the node graph a forest, accessors and attribute indices in range,
//! external files present, a GLB's chunk layout sound — and the importer
//! run under a panic guard — so that malformed input is a clear error,
//! never a panic, a hang or wrong geometry.

use anyhow::{Result, bail};
use std::path::Path;

/// Checks that the node graph is a forest, as glTF 2.0 requires (§ 3.5.4
/// "Scenes"): no node is its own descendant and no node has two parents;
/// returns each node's parent. Checked here rather than trusted to the
/// importer: a cycle would make the traversal below run forever and shared
/// children would multiply objects. (That a scene lists only roots is
/// left to [`scene_roots`].)
pub(super) fn check_node_forest(file: &str, doc: &gltf::Document) -> Result<Vec<Option<usize>>> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            if c == node.index() {
                bail!("{file}: node {c} is its own child (a cycle in the node hierarchy)");
            }
            if let Some(p) = parent[c] {
                bail!(
                    "{file}: node {c} is a child of both node {p} and node {} (glTF nodes form trees; shared children are not allowed)",
                    node.index()
                );
            }
            parent[c] = Some(node.index());
        }
    }
    // With one parent each, a cycle is a loop of parent links that never
    // reaches a root: follow them, marking nodes known to reach a root.
    let mut reaches_root = vec![false; n];
    let mut walked_from = vec![usize::MAX; n];
    for start in 0..n {
        let mut path: Vec<usize> = vec![];
        let mut at = start;
        while !reaches_root[at] {
            if walked_from[at] == start {
                let first = path.iter().position(|&i: &usize| i == at).unwrap_or(0);
                let cycle: Vec<String> = path[first..].iter().map(|i| i.to_string()).collect();
                bail!(
                    "{file}: the node hierarchy has a cycle: node {} (each the child of the next)",
                    cycle.join(" -> node ")
                );
            }
            walked_from[at] = start;
            path.push(at);
            match parent[at] {
                Some(p) => at = p,
                None => break,
            }
        }
        for i in path {
            reaches_root[i] = true;
        }
    }
    Ok(parent)
}

/// The nodes `scene` is drawn from, given each node's `parent`: the nodes
/// it lists. glTF requires them to be roots (§ 3.5.4), but exporters write
/// files that list a child (Kenney's models list the child of a
/// `tmpParent` node the scene leaves out), which Bevy and three.js draw
/// from the listed node, its parent's transform left out: so is it drawn
/// here, with a warning. A listed node that descends from another listed
/// node, or is listed twice, is drawn once (as that node's descendant).
pub(super) fn scene_roots(file: &str, scene: &gltf::Scene, parent: &[Option<usize>]) -> Vec<usize> {
    let mut listed = vec![false; parent.len()];
    for n in scene.nodes() {
        listed[n.index()] = true;
    }
    let mut drawn = vec![false; parent.len()];
    let mut roots: Vec<usize> = vec![];
    for node in scene.nodes().map(|n| n.index()) {
        if std::mem::replace(&mut drawn[node], true) {
            log::warn!(
                "{file}: scene {} lists node {node} twice; drawn once",
                scene.index()
            );
            continue;
        }
        let Some(p) = parent[node] else {
            roots.push(node);
            continue;
        };
        let mut above = Some(p);
        while let Some(a) = above.filter(|&a| !listed[a]) {
            above = parent[a];
        }
        match above {
            Some(a) => log::warn!(
                "{file}: scene {} lists node {node} as a root, but it descends from node {a}, also listed; drawn once, under node {a}",
                scene.index()
            ),
            None => {
                log::warn!(
                    "{file}: scene {} lists node {node} as a root, but it is a child of node {p}, which the scene leaves out; drawn from node {node}, without node {p}'s transform (as Bevy and three.js draw it)",
                    scene.index()
                );
                roots.push(node);
            }
        }
    }
    roots
}

/// Runs `f`, turning a panic — which the `gltf` crate raises on some
/// malformed documents that its validation lets through (found by fuzzing:
/// an attribute's accessor index out of range, an accessor whose element
/// size is not the attribute's) — into an error naming the file. The panic
/// message is not printed.
pub(super) fn without_panics<T>(file: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    r.unwrap_or_else(|payload| {
        let why = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("unknown");
        bail!("{file}: malformed glTF (the importer failed: {why})")
    })
}

/// Checks that the accessors a primitive is read through have the types
/// glTF 2.0 requires (§ 3.7.2.1): POSITION and NORMAL `VEC3` of `FLOAT`,
/// the `uv_set` read (`TEXCOORD_n` of the base colour texture) `VEC2` of
/// `FLOAT` or normalised `UNSIGNED_BYTE`/`SHORT`, indices `SCALAR` of
/// unsigned integers; in a file that uses KHR_mesh_quantization, also the
/// byte and short types it adds to each attribute.
pub(super) fn check_primitive_accessors(
    file: &str,
    mesh: &str,
    index: usize,
    prim: &gltf::Primitive,
    uv_set: u32,
    quantized: bool,
) -> Result<()> {
    use gltf::Semantic;
    use gltf::accessor::{DataType as T, Dimensions as D};
    // KHR_mesh_quantization's integer types, where the file uses it.
    let with = |core: &[T], quantization: &[T]| -> Vec<T> {
        let extra = if quantized { quantization } else { &[] };
        [core, extra].concat()
    };
    let position = with(&[T::F32], &[T::I8, T::U8, T::I16, T::U16]);
    let normal = with(&[T::F32], &[T::I8, T::I16]);
    let uv = with(&[T::F32, T::U8, T::U16], &[T::I8, T::I16]);
    let unsigned = [T::U8, T::U16, T::U32];
    let texcoord = format!("TEXCOORD_{uv_set}");
    let rules: [(&str, Option<gltf::Accessor>, D, &[T]); 4] = [
        (
            "POSITION",
            prim.get(&Semantic::Positions),
            D::Vec3,
            &position,
        ),
        ("NORMAL", prim.get(&Semantic::Normals), D::Vec3, &normal),
        (
            &texcoord,
            prim.get(&Semantic::TexCoords(uv_set)),
            D::Vec2,
            &uv,
        ),
        ("indices", prim.indices(), D::Scalar, &unsigned),
    ];
    for (what, accessor, dims, types) in rules {
        let Some(a) = accessor else { continue };
        if a.dimensions() != dims || !types.contains(&a.data_type()) {
            bail!(
                "{file}: mesh '{mesh}' primitive {index}: {what} accessor {} is {:?} of {:?}; glTF requires {dims:?} of {}",
                a.index(),
                a.dimensions(),
                a.data_type(),
                types
                    .iter()
                    .map(|t| format!("{t:?}"))
                    .collect::<Vec<_>>()
                    .join(" or ")
            );
        }
    }
    Ok(())
}

/// Checks that every mesh attribute names an existing accessor, which the
/// `gltf` crate's own validation assumes for `POSITION` (and panics on).
pub(super) fn check_attribute_indices(file: &str, root: &gltf::json::Root) -> Result<()> {
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets = primitive.targets.iter().flatten().flat_map(|t| {
                [&t.positions, &t.normals, &t.tangents]
                    .into_iter()
                    .flatten()
                    .map(|i| ("targets", i.value()))
            });
            let attributes = primitive
                .attributes
                .values()
                .map(|i| ("attributes", i.value()))
                .chain(primitive.indices.iter().map(|i| ("indices", i.value())));
            for (what, index) in attributes.chain(targets) {
                if index >= accessors {
                    bail!(
                        "{file}: meshes[{m}].primitives[{p}].{what}: accessor {index} out of range ({accessors} accessors)"
                    );
                }
            }
        }
    }
    Ok(())
}

/// Checks, before the importer reads them, that every buffer a glTF file
/// names by URI (other than `data:` URIs) exists, and that every buffer and
/// image that exists is a regular file: the importer reads whatever a URI
/// names, and `/dev/zero` or a FIFO would never end. A missing image is the
/// loader's warning, not an error.
pub(super) fn check_external_files(file: &str, dir: &Path, root: &gltf::json::Root) -> Result<()> {
    let buffers = root
        .buffers
        .iter()
        .enumerate()
        .map(|(i, b)| ("buffer", i, &b.uri));
    let images = root
        .images
        .iter()
        .enumerate()
        .map(|(i, im)| ("image", i, &im.uri));
    for (what, index, uri) in buffers.chain(images) {
        let Some(uri) = uri.as_deref().filter(|u| !u.starts_with("data:")) else {
            continue;
        };
        let target = dir.join(uri);
        if !target.exists() && what == "image" {
            continue;
        }
        if !target.exists() {
            bail!("{file}: {what} {index}: '{uri}' not found");
        }
        if !target.is_file() {
            bail!("{file}: {what} {index}: '{uri}' is not a regular file");
        }
    }
    Ok(())
}

/// Checks a binary glTF's header and chunk lengths against the file, so
/// that a truncated or inconsistent file gets a message that says which.
pub(super) fn check_glb_layout(file: &str, bytes: &[u8]) -> Result<()> {
    let word = |at: usize| -> Option<usize> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        bail!("{file}: GLB header truncated ({} bytes)", bytes.len());
    };
    if version != 2 {
        bail!("{file}: GLB version {version} (only 2 is supported)");
    }
    if length != bytes.len() {
        bail!(
            "{file}: GLB header declares {length} bytes but the file has {}",
            bytes.len()
        );
    }
    let mut at = 12;
    let mut chunk = 0;
    while at < bytes.len() {
        let Some(len) = word(at) else {
            bail!("{file}: GLB chunk {chunk} header truncated at byte {at}");
        };
        if at + 8 + len > bytes.len() {
            bail!(
                "{file}: GLB chunk {chunk} declares {len} bytes at byte {at}, past the end of the file ({} bytes)",
                bytes.len()
            );
        }
        at += 8 + len;
        chunk += 1;
    }
    Ok(())
}

/// Checks that every accessor's elements lie inside its buffer view and
/// every view inside its buffer (the importer's reader would otherwise
/// return nothing, and the message would blame a missing attribute).
pub(super) fn check_accessors(
    file: &str,
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<()> {
    for view in doc.views() {
        let have = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
        if view.offset() + view.length() > have {
            bail!(
                "{file}: buffer view {}: bytes {}..{} past the end of buffer {} ({have} bytes)",
                view.index(),
                view.offset(),
                view.offset() + view.length(),
                view.buffer().index()
            );
        }
    }
    for a in doc.accessors() {
        let Some(view) = a.view() else { continue };
        let stride = view.stride().unwrap_or(a.size());
        let need = match a.count() {
            0 => 0,
            n => a.offset() + stride * (n - 1) + a.size(),
        };
        if need > view.length() {
            bail!(
                "{file}: accessor {}: {} elements of {} bytes (stride {stride}, offset {}) need {need} bytes, buffer view {} has {}",
                a.index(),
                a.count(),
                a.size(),
                a.offset(),
                view.index(),
                view.length()
            );
        }
    }
    Ok(())
}

/// Compressed-geometry extensions: a file that requires one stores its
/// meshes only in a form the importer cannot decode.
const COMPRESSED_GEOMETRY: [&str; 3] = [
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
];

/// How many of the importer's validation errors an error message lists.
const LISTED_ERRORS: usize = 3;

/// The document, validated: a required extension the importer cannot read
/// is named as the cause (a Draco-compressed file otherwise fails with an
/// error per accessor, each "Missing data"), and of many validation errors
/// the first few are listed with how many more there are.
pub(super) fn validated(file: &str, root: gltf::json::Root) -> Result<gltf::Document> {
    let unreadable: Vec<&str> = root
        .extensions_required
        .iter()
        .map(String::as_str)
        .filter(|e| !gltf::json::extensions::ENABLED_EXTENSIONS.contains(e))
        .collect();
    if !unreadable.is_empty() {
        let hint = if unreadable.iter().any(|e| COMPRESSED_GEOMETRY.contains(e)) {
            " (compressed geometry: write the file without compression first)"
        } else {
            ""
        };
        bail!(
            "{file}: requires the glTF extension {}, which shadowlab cannot read{hint}",
            unreadable.join(", ")
        );
    }
    gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) if errors.len() > LISTED_ERRORS => {
            let first: Vec<String> = errors[..LISTED_ERRORS]
                .iter()
                .map(|(path, error)| format!("{}: {error}", path.as_str()))
                .collect();
            anyhow::anyhow!(
                "{file}: invalid glTF: {}; and {} more",
                first.join("; "),
                errors.len() - LISTED_ERRORS
            )
        }
        e => anyhow::anyhow!("{file}: {e}"),
    })
}
