//! What the command prints, shared by the model and the animation commands: the file an export wrote, a model's
//! name and JSON lines.

use std::path::Path;

use crate::error::{Result, VoxelError};
use crate::export::{MeshStats, Written};

/// The file an export wrote, as the reports show it (JSON fields `vox`, or `gltf` and `mesh`).
#[derive(Debug, Default, serde::Serialize)]
pub(crate) struct Exported {
    /// The .vox written.
    #[serde(skip_serializing_if = "Option::is_none")]
    vox: Option<String>,
    /// Its palette's colours: fewer than the model's `colors` when more than 255 were quantized (median cut).
    #[serde(skip_serializing_if = "Option::is_none")]
    vox_colors: Option<usize>,
    /// The .glb or .gltf written.
    #[serde(skip_serializing_if = "Option::is_none")]
    gltf: Option<String>,
    /// What the glTF holds (faces before merging, rectangles after, bytes).
    #[serde(skip_serializing_if = "Option::is_none")]
    mesh: Option<MeshStats>,
}

impl Exported {
    /// What writing `path` wrote.
    pub(crate) fn new(path: &Path, written: Written) -> Self {
        let path = Some(path.display().to_string());
        match written {
            Written::Vox(summary) => Self { vox: path, vox_colors: Some(summary.colors), ..Self::default() },
            Written::Mesh(stats) => Self { gltf: path, mesh: Some(stats), ..Self::default() },
        }
    }

    /// The end of a readable line: `, wrote <path>` (with the mesh's figures for a glTF), or nothing.
    pub(crate) fn summary(&self) -> String {
        match (self.vox.as_ref().or(self.gltf.as_ref()), self.mesh) {
            (Some(p), Some(m)) => {
                format!(", wrote {p} ({} faces as {} rectangles, {} bytes)", m.faces, m.quads, m.bytes)
            }
            (Some(p), None) => format!(", wrote {p}"),
            (None, _) => String::new(),
        }
    }
}

/// The name of an input model: its file stem.
pub(crate) fn stem(input: &Path) -> String {
    input.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned())
}

/// `value` as one JSON line.
pub(crate) fn to_json(value: &impl serde::Serialize) -> Result<String> {
    serde_json::to_string(value).map_err(|e| VoxelError::Parameter(e.to_string()))
}
