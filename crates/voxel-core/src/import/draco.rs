//! KHR_draco_mesh_compression: a primitive's Draco stream decoded (by the pure-Rust `draco-core`) into the
//! triangle indices and the attributes it replaces. As the extension says, the accessors it names still give
//! each attribute's element type and normalization; the indices come from the Draco mesh.

use std::collections::HashMap;

use draco_core::{DecodeLimits, DecoderBuffer, Mesh, MeshDecoder};
use gltf::accessor::Accessor;
use serde::Deserialize;

use super::accessor::{component_count, normalize};
use super::buffers::Buffers;
use super::validate::MAX_TRIANGLES;
use crate::error::{Result, VoxelError};

/// The extension's name.
pub(crate) const DRACO: &str = "KHR_draco_mesh_compression";

/// The most points one Draco primitive may decode to (attributes are read per point, whatever the stream).
const MAX_POINTS: usize = 1 << 24;

/// The most components of an attribute we read (POSITION, TEXCOORD_n and COLOR_0 have 2 to 4).
const MAX_COMPONENTS: usize = 4;

/// The extension object of a primitive.
#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct DracoExtension {
    buffer_view: usize,
    attributes: HashMap<String, u32>,
}

/// A decoded Draco mesh and which of its attributes stands for which glTF attribute.
pub(crate) struct DracoPrimitive {
    mesh: Mesh,
    /// glTF attribute name (`POSITION`, `TEXCOORD_0`, ...) to Draco attribute unique id.
    attributes: HashMap<String, u32>,
}

impl DracoPrimitive {
    /// Decodes the Draco stream of `prim`, or `None` when the primitive is not compressed.
    pub fn decode(
        prim: &gltf::Primitive<'_>,
        document: &gltf::Document,
        buffers: &Buffers<'_>,
        what: &str,
    ) -> Result<Option<Self>> {
        let Some(ext) = prim.extension_value(DRACO) else { return Ok(None) };
        let invalid = |reason: String| VoxelError::Invalid(format!("{what} ({DRACO}): {reason}"));
        let ext = DracoExtension::deserialize(ext).map_err(|e| invalid(e.to_string()))?;
        let view = document
            .views()
            .nth(ext.buffer_view)
            .ok_or_else(|| invalid(format!("buffer view {} does not exist", ext.buffer_view)))?;
        let limits = DecodeLimits::default()
            .with_max_faces(MAX_TRIANGLES as u64)
            .with_max_points(MAX_POINTS as u64)
            .with_max_decoded_bytes(1 << 30);
        let mut stream = DecoderBuffer::new(buffers.view_bytes(&view, what)?).with_limits(limits);
        let mut mesh = Mesh::new();
        MeshDecoder::new().decode(&mut stream, &mut mesh).map_err(|e| invalid(format!("cannot decode ({e})")))?;
        Ok(Some(Self { mesh, attributes: ext.attributes }))
    }

    /// The triangles' point indices, three per face.
    pub fn indices(&self) -> Vec<u32> {
        self.mesh.faces().iter().flat_map(|face| face.map(|p| p.0)).collect()
    }

    /// The decoded values of glTF attribute `semantic` (as [`super::accessor::read_accessor`] gives them,
    /// typed by its `accessor`), or `None` when the Draco stream does not carry it.
    pub fn attribute(&self, semantic: &str, accessor: &Accessor<'_>, what: &str) -> Result<Option<(Vec<f64>, usize)>> {
        let Some(&id) = self.attributes.get(semantic) else { return Ok(None) };
        let attribute = self
            .mesh
            .attribute_by_unique_id(id)
            .ok_or_else(|| VoxelError::Invalid(format!("{what} ({DRACO}): the Draco stream has no attribute {id}")))?;
        let ncomp = component_count(accessor.dimensions());
        if ncomp > MAX_COMPONENTS {
            return Err(VoxelError::Invalid(format!("{what} ({DRACO}): {ncomp} components per element")));
        }
        if usize::from(attribute.num_components()) != ncomp {
            return Err(VoxelError::Invalid(format!(
                "{what} ({DRACO}): the Draco attribute has {} components, the accessor {ncomp}",
                attribute.num_components()
            )));
        }
        let raw = attribute.read_f32s(self.mesh.num_points(), ncomp);
        let ty = accessor.data_type();
        let values =
            raw.into_iter().map(f64::from).map(|v| if accessor.normalized() { normalize(v, ty) } else { v }).collect();
        Ok(Some((values, ncomp)))
    }
}
