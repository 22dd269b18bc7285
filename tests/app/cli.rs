//! `voxel-art voxelize`: exit status, JSON lines, error lines, .vox output.

use std::process::Command;

use crate::common::{models_dir, scratch_dir};

fn voxelize(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_voxel-art")).arg("voxelize").args(args).output().unwrap()
}

fn write_cube_glb(dir: &std::path::Path) -> std::path::PathBuf {
    // A cube built by the library and written as a minimal .glb (one buffer, one node).
    let mesh = voxel_art::voxel::shapes::cuboid([0.0; 3], [1.0; 3]);
    let mut bin = Vec::new();
    for p in &mesh.positions {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let positions = bin.len();
    for t in &mesh.triangles {
        for &i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{len}}}],
        "bufferViews":[{{"buffer":0,"byteLength":{positions}}},{{"buffer":0,"byteOffset":{positions},"byteLength":144}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
                     {{"bufferView":1,"componentType":5125,"count":36,"type":"SCALAR"}}]}}"#,
        len = bin.len()
    );
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let path = dir.join("cube.glb");
    std::fs::write(&path, glb).unwrap();
    path
}

#[test]
fn json_lines_report_every_field() {
    let dir = scratch_dir("json");
    let cube = write_cube_glb(&dir);
    let out = voxelize(&[cube.to_str().unwrap(), "--resolution", "12", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    let line: serde_json::Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
    assert_eq!(line["file"], cube.to_str().unwrap());
    assert_eq!(line["triangles"], 12);
    assert_eq!(line["grid"], serde_json::json!([12, 12, 12]));
    assert_eq!(line["voxels"], 1728);
    assert_eq!(line["visible"], 1728 - 1000);
    assert_eq!(line["colors"], 1);
    assert!(line["surface"].as_u64().unwrap() >= 728);
    assert!(line["load_ms"].as_f64().unwrap() >= 0.0 && line["voxelize_ms"].as_f64().unwrap() >= 0.0);
}

#[test]
fn a_bad_file_fails_the_call_but_not_the_others() {
    let dir = scratch_dir("bad");
    let cube = write_cube_glb(&dir);
    let junk = dir.join("junk.glb");
    std::fs::write(&junk, b"definitely not a model").unwrap();
    let missing = dir.join("missing.glb");
    let out = voxelize(&[junk.to_str().unwrap(), missing.to_str().unwrap(), cube.to_str().unwrap(), "--json", "-r", "8"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains(&format!("error: {}: not a valid glTF file", junk.display())), "{stderr}");
    assert!(stderr.contains(&format!("error: {}: cannot read", missing.display())), "{stderr}");
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1, "the good file is still processed: {stdout}");
    assert!(stdout.contains("\"voxels\":512"));
}

#[test]
fn vox_export_reads_back() {
    let dir = scratch_dir("vox");
    let cube = write_cube_glb(&dir);
    let vox = dir.join("cube.vox");
    let out = voxelize(&[cube.to_str().unwrap(), "-r", "20", "--hollow", "--out", vox.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8(out.stdout).unwrap().contains("wrote"));
    let data = dot_vox::load(vox.to_str().unwrap()).unwrap();
    assert_eq!(data.models.len(), 1);
    assert_eq!(data.models[0].voxels.len(), 20 * 20 * 20 - 18 * 18 * 18);
}

#[test]
fn folders_expand_to_their_models_and_the_draco_truck_is_refused() {
    let Some(models) = models_dir() else { return };
    let out = voxelize(&[models.to_str().unwrap(), models.join("khronos-cesiummilktruck-draco").to_str().unwrap(), "--json", "-r", "24"]);
    assert_eq!(out.status.code(), Some(1), "the Draco and meshopt files fail");
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.lines().count() >= 8, "{stdout}");
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("KHR_draco_mesh_compression"), "{stderr}");
    assert!(stderr.contains("EXT_meshopt_compression"), "{stderr}");
    assert!(!stderr.contains("panic"));
}

#[test]
fn bad_arguments_are_usage_errors() {
    let out = voxelize(&["--resolution", "5", "--grid-size", "0.2", "x.glb"]);
    assert_eq!(out.status.code(), Some(2));
    let out = voxelize(&["x.glb", "--fill", "sideways"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8(out.stderr).unwrap().contains("sideways"));
}
