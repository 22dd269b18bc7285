//! Finding model files: what the command line and the app accept as a model, and the models in a folder.

use std::path::{Path, PathBuf};

/// Whether a path names a glTF model (`.glb` or `.gltf`, in any case).
pub fn is_model_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb") || e.eq_ignore_ascii_case("gltf"))
}

/// Expands folders into the model files they hold (sorted, not recursing into subfolders; an unreadable
/// folder holds none); anything else is kept as given.
pub fn expand_inputs(inputs: &[PathBuf]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for input in inputs {
        if input.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(input)
                .map(|rd| {
                    rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_file() && is_model_file(p)).collect()
                })
                .unwrap_or_default();
            found.sort();
            out.extend(found);
        } else {
            out.push(input.clone());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_files_are_glb_and_gltf_in_any_case() {
        for yes in ["a.glb", "b/c.GLTF", "d.Glb"] {
            assert!(is_model_file(Path::new(yes)), "{yes}");
        }
        for no in ["a.bin", "glb", "a.glb.png", "a"] {
            assert!(!is_model_file(Path::new(no)), "{no}");
        }
    }

    #[test]
    fn folders_expand_to_their_sorted_model_files_and_files_stay_as_given() {
        let dir = std::env::temp_dir().join(format!("voxel-core-inputs-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub.glb")).unwrap();
        for name in ["b.glb", "a.GLTF", "a.bin", "notes.txt"] {
            std::fs::write(dir.join(name), b"").unwrap();
        }
        let given = dir.join("missing.vox");
        let found = expand_inputs(&[dir.clone(), given.clone()]);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(found, [dir.join("a.GLTF"), dir.join("b.glb"), given]);
    }
}
