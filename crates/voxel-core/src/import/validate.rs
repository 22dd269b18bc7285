//! Parsing and checking a document before the `gltf` crate's wrappers touch it: those wrappers (and one
//! of its validation hooks) index and unwrap freely, so everything they would follow is checked here first and
//! reported as a [`VoxelError`] naming what is wrong.

use std::borrow::Cow;

use gltf::json::validation::{Error as Problem, Validate};
use gltf::json::{Path as JsonPath, Root};

use crate::error::{Result, VoxelError};

/// The most triangles an import may produce (node instancing can multiply a small file).
pub const MAX_TRIANGLES: usize = 20_000_000;

/// Required extensions we decode (or that do not change geometry or base colour).
const TOLERATED_REQUIRED: &[&str] = &[
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    "KHR_materials_unlit",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
    "KHR_materials_dispersion",
    "KHR_lights_punctual",
    super::webp::EXTENSION,
];

/// How many validation problems an error message lists.
const LISTED_PROBLEMS: usize = 3;

fn gltf1_error() -> VoxelError {
    VoxelError::Parse("glTF 1.0 is not supported; convert it to glTF 2.0".into())
}

/// Whether a glTF JSON document is glTF 1.0: its asset version says so, or it has 1.0's shape (objects keyed
/// by id where 2.0 has arrays).
fn is_gltf1(json: &serde_json::Value) -> bool {
    let version = json.get("asset").and_then(|a| a.get("version")).and_then(|v| v.as_str());
    version.is_some_and(|v| v.starts_with("1.") || v == "1")
        || ["meshes", "accessors", "nodes", "buffers"].iter().any(|key| json.get(key).is_some_and(|v| v.is_object()))
}

/// Parses glTF or GLB bytes without the `gltf` crate's validation (see [`check`]): the document, and a GLB's
/// binary chunk, borrowed from `bytes` (not copied).
pub(super) fn parse(bytes: &[u8]) -> Result<(gltf::Document, Option<Cow<'_, [u8]>>)> {
    // The gltf crate subtracts the 12-byte header from the GLB's declared length unchecked.
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
        if length < 12 {
            return Err(VoxelError::Parse(format!("corrupt GLB (its header declares a length of {length} bytes)")));
        }
    }
    let (json, blob) = if bytes.starts_with(b"glTF") {
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| parse_error(e, bytes))?;
        (glb.json, glb.bin)
    } else {
        (Cow::Borrowed(bytes), None)
    };
    let root = Root::from_slice(&json).map_err(|e| parse_error(gltf::Error::Deserialize(e), bytes))?;
    let version = &root.asset.version;
    if version.starts_with("1.") || version == "1" {
        return Err(gltf1_error());
    }
    Ok((gltf::Document::from_json_without_validation(root), blob))
}

/// The error for a document the `gltf` crate cannot read: glTF 1.0, a corrupt GLB or bad JSON.
fn parse_error(error: gltf::Error, bytes: &[u8]) -> VoxelError {
    match error {
        gltf::Error::Binary(gltf::binary::Error::Version(1)) => gltf1_error(),
        gltf::Error::Binary(b) => VoxelError::Parse(format!("corrupt or truncated GLB ({b:?})")),
        gltf::Error::Deserialize(d) => {
            if serde_json::from_slice::<serde_json::Value>(bytes).is_ok_and(|json| is_gltf1(&json)) {
                gltf1_error()
            } else {
                VoxelError::Parse(format!("JSON: {d}"))
            }
        }
        other => VoxelError::Parse(other.to_string()),
    }
}

/// Refuses undecodable required extensions, checks what the `gltf` crate's wrappers would index or unwrap,
/// and returns the document they can then walk safely.
pub(super) fn check(document: gltf::Document) -> Result<gltf::Document> {
    let mut root = document.into_json();
    if let Some(ext) = root.extensions_required.iter().find(|e| !TOLERATED_REQUIRED.contains(&e.as_str())) {
        return Err(VoxelError::UnsupportedExtension(ext.clone()));
    }
    // The gltf crate does not list the extensions we decode ourselves as supported: validate without them.
    root.extensions_required.clear();
    super::webp::use_webp_sources(&mut root)?;
    check_position_indices(&root)?;
    let mut problems = Vec::new();
    root.validate(&root, JsonPath::new, &mut |path: &dyn Fn() -> JsonPath, problem| {
        let path = path().to_string();
        if !tolerated(&path, problem) {
            problems.push(format!("{path}: {problem}"));
        }
    });
    if !problems.is_empty() {
        let more = problems.len().saturating_sub(LISTED_PROBLEMS);
        let tail = if more > 0 { format!(" (and {more} more)") } else { String::new() };
        problems.truncate(LISTED_PROBLEMS);
        return Err(VoxelError::Invalid(format!("{}{tail}", problems.join("; "))));
    }
    check_sources(&root)?;
    Ok(gltf::Document::from_json_without_validation(root))
}

/// Validation findings that do not stop us: an accessor without a buffer view reads as zeros (or is replaced
/// by Draco data), and POSITION's `min`/`max`, which we never use, may be absent.
fn tolerated(path: &str, problem: Problem) -> bool {
    problem == Problem::Missing
        && ((path.starts_with("accessors[") && path.ends_with("].bufferView"))
            || path.ends_with("[\"POSITION\"].min")
            || path.ends_with("[\"POSITION\"].max"))
}

/// Every primitive's POSITION accessor exists (the `gltf` crate's validation hook indexes it unchecked).
fn check_position_indices(root: &Root) -> Result<()> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&gltf::json::validation::Checked::Valid(gltf::Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err(VoxelError::Invalid(format!(
                    "mesh {m} primitive {p}: POSITION refers to accessor {}, but the file has {} accessors",
                    index.value(),
                    root.accessors.len()
                )));
            }
        }
    }
    Ok(())
}

/// Every image has a source the `gltf` crate can describe (a URI, or a buffer view with a MIME type), and
/// every relative URI percent-decodes.
fn check_sources(root: &Root) -> Result<()> {
    for (i, image) in root.images.iter().enumerate() {
        let what = format!("image {i}");
        // The gltf crate reads the buffer view first when there is one.
        match (&image.buffer_view, &image.mime_type, &image.uri) {
            (Some(_), Some(_), _) => {}
            (Some(_), None, _) => {
                return Err(VoxelError::Invalid(format!("{what} is in a buffer view but has no mimeType")));
            }
            (None, _, Some(uri)) => check_uri(uri, &what)?,
            (None, _, None) => return Err(VoxelError::Invalid(format!("{what} has neither a uri nor a bufferView"))),
        }
    }
    for (i, buffer) in root.buffers.iter().enumerate() {
        if let Some(uri) = &buffer.uri {
            check_uri(uri, &format!("buffer {i}"))?;
        }
    }
    Ok(())
}

/// Checks that a relative URI percent-decodes to UTF-8 (the `gltf` crate unwraps that decoding).
fn check_uri(uri: &str, what: &str) -> Result<()> {
    if uri.contains(':') || urlencoding::decode(uri).is_ok() {
        Ok(())
    } else {
        Err(VoxelError::Invalid(format!("{what}: the URI {uri:?} does not percent-decode to UTF-8")))
    }
}
