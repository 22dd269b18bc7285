//! Exports of a voxel model: a glTF mesh of its surface (.glb, or .gltf + .bin) and MagicaVoxel .vox.
//!
//! The model carries everything an export needs: the grid (cell sizes, with taller cells for the Lego
//! style) in normalized space and the normalization itself (`GridSpec::scale`, `GridSpec::center`), which
//! the glTF node undoes.

pub mod animated;
pub mod gltf;
pub mod mesh;

use std::path::{Path, PathBuf};

use crate::error::{Result, VoxelError};
use crate::model::VoxelModel;
use crate::vox::{VoxSummary, write_vox};

pub use gltf::{ExportOptions, MeshStats};

/// An export file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Format {
    /// MagicaVoxel.
    Vox,
    /// Binary glTF: one file.
    Glb,
    /// glTF JSON with a .bin beside it.
    Gltf,
}

impl Format {
    /// The format a file name asks for by its extension (case-insensitive): .glb, .gltf, else .vox.
    pub fn of_path(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("glb") => Format::Glb,
            Some("gltf") => Format::Gltf,
            _ => Format::Vox,
        }
    }

    /// The file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Vox => "vox",
            Format::Glb => "glb",
            Format::Gltf => "gltf",
        }
    }
}

/// What one export wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Written {
    /// A .vox file.
    Vox(VoxSummary),
    /// A .glb, or a .gltf and its .bin.
    Mesh(MeshStats),
}

/// Writes `model` to `path` in `format`.
pub fn write(model: &VoxelModel, path: &Path, format: Format, options: &ExportOptions) -> Result<Written> {
    Ok(match format {
        Format::Vox => Written::Vox(write_vox(model, path)?),
        Format::Glb => Written::Mesh(gltf::write_glb(model, path, options)?),
        Format::Gltf => Written::Mesh(gltf::write_gltf(model, path, options)?),
    })
}

/// The files [`write_vox_and_glb`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Saved {
    /// The MagicaVoxel file and what it holds.
    pub vox: (PathBuf, VoxSummary),
    /// The binary glTF file and what it holds.
    pub glb: (PathBuf, MeshStats),
}

/// Saves `model` as both `<dir>/<name>-<nx>x<ny>x<nz>.vox` and `.glb` (named after the model and its grid),
/// creating `dir` if needed. `options.name` names the mesh inside the .glb.
pub fn write_vox_and_glb(model: &VoxelModel, dir: &Path, options: &ExportOptions) -> Result<Saved> {
    std::fs::create_dir_all(dir).map_err(|e| VoxelError::Export { path: dir.to_owned(), reason: e.to_string() })?;
    let [nx, ny, nz] = model.spec.dims;
    let stem = format!("{}-{nx}x{ny}x{nz}", options.name);
    let vox = dir.join(format!("{stem}.vox"));
    let glb = dir.join(format!("{stem}.glb"));
    let vox_summary = write_vox(model, &vox)?;
    let glb_stats = gltf::write_glb(model, &glb, options)?;
    Ok(Saved { vox: (vox, vox_summary), glb: (glb, glb_stats) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::mesh::tests::model_of;

    #[test]
    fn both_files_are_named_after_the_model_and_grid_in_a_new_folder() {
        let m = model_of(1, [([0, 0, 0], [255, 0, 0]), ([1, 0, 0], [0, 255, 0])]);
        let root = std::env::temp_dir().join(format!("voxel-core-save-{}", std::process::id()));
        let dir = root.join("exports");
        let saved = write_vox_and_glb(&m, &dir, &ExportOptions { name: "duck".into() }).unwrap();
        assert_eq!(saved.vox.0, dir.join("duck-8x4x8.vox"));
        assert_eq!(saved.glb.0, dir.join("duck-8x4x8.glb"));
        assert_eq!((saved.vox.1.voxels, saved.vox.1.colors), (2, 2));
        assert_eq!((saved.glb.1.faces, saved.glb.1.quads), (10, 10));
        assert_eq!(std::fs::metadata(&saved.glb.0).unwrap().len() as usize, saved.glb.1.bytes);
        let back = crate::import::load_file(&saved.glb.0).unwrap();
        assert_eq!(back.triangle_count(), 20);
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn an_unwritable_folder_is_an_error_naming_it() {
        let file = std::env::temp_dir().join(format!("voxel-core-not-a-folder-{}", std::process::id()));
        std::fs::write(&file, b"x").unwrap();
        let dir = file.join("exports");
        let err = write_vox_and_glb(&model_of(1, []), &dir, &ExportOptions::default()).unwrap_err();
        std::fs::remove_file(&file).unwrap();
        assert!(matches!(&err, VoxelError::Export { path, .. } if *path == dir), "{err}");
        assert!(err.to_string().starts_with(&format!("cannot write {}: ", dir.display())), "{err}");
    }

    #[test]
    fn formats_follow_the_extension_case_insensitively_with_vox_otherwise() {
        assert_eq!(Format::of_path(Path::new("a/b.GLB")), Format::Glb);
        assert_eq!(Format::of_path(Path::new("b.gltf")), Format::Gltf);
        assert_eq!(Format::of_path(Path::new("b.vox")), Format::Vox);
        assert_eq!(Format::of_path(Path::new("b")), Format::Vox);
        assert_eq!(Format::Gltf.extension(), "gltf");
    }
}
