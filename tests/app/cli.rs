//! `voxel-art voxelize`: exit status, JSON lines, error lines, .vox output.

use std::process::Command;

use crate::common::{models_dir, scratch_dir};

fn voxelize(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_voxel-art")).arg("voxelize").args(args).output().unwrap()
}

fn write_cube_glb(dir: &std::path::Path) -> std::path::PathBuf {
    let cube = voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]);
    let soup = voxel_core::TriangleSoup::from_mesh(&cube, [1.0; 4]);
    let path = dir.join("cube.glb");
    std::fs::write(&path, voxel_core::glb::soup_to_glb(&soup).unwrap()).unwrap();
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
    let out =
        voxelize(&[junk.to_str().unwrap(), missing.to_str().unwrap(), cube.to_str().unwrap(), "--json", "-r", "8"]);
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
fn folders_expand_to_their_models_compressed_ones_voxelize_and_a_bad_file_is_named() {
    let Some(models) = models_dir() else { return };
    let junk = scratch_dir("cli-junk").join("junk.glb");
    std::fs::write(&junk, b"glTF but not really").unwrap();
    let out = voxelize(&[
        models.to_str().unwrap(),
        models.join("khronos-cesiummilktruck-draco").to_str().unwrap(),
        junk.to_str().unwrap(),
        "--json",
        "-r",
        "24",
    ]);
    assert_eq!(out.status.code(), Some(1), "the junk file fails");
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.lines().count() >= 12, "{stdout}");
    for compressed in ["khronos-box-draco.glb", "CesiumMilkTruck.gltf", "khronos-duck-meshopt-quantized.glb"] {
        assert!(stdout.lines().any(|l| l.contains(compressed)), "{compressed} missing from:\n{stdout}");
    }
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains(&format!("error: {}: ", junk.display())), "{stderr}");
    assert!(!stderr.contains("panic"), "{stderr}");
}

#[test]
fn bad_arguments_are_usage_errors() {
    let out = voxelize(&["--resolution", "5", "--grid-size", "0.2", "x.glb"]);
    assert_eq!(out.status.code(), Some(2));
    let out = voxelize(&["x.glb", "--fill", "sideways"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8(out.stderr).unwrap().contains("sideways"));
}

#[test]
fn grid_size_and_solid_set_the_starting_voxel_settings() {
    use voxel_art::config::Cli;
    use voxel_art::settings::VoxelSettings;
    let parse = |args: &[&str]| {
        Cli::parse_args(std::iter::once("voxel-art").chain(args.iter().copied()).map(Into::into).collect())
    };
    let Ok(Cli { app: args, .. }) = parse(&["--grid-size", "0.03", "--solid"]) else { panic!("rejected") };
    let app = crate::harness::test_app(voxel_art::config::AppArgs { no_shipped: true, ..args });
    let settings = app.world().resource::<VoxelSettings>();
    assert_eq!((settings.grid_size, settings.hollow), (0.03, false));
    let defaults = crate::harness::test_app(voxel_art::config::AppArgs { no_shipped: true, ..Default::default() });
    assert_eq!(*defaults.world().resource::<VoxelSettings>(), VoxelSettings::default());
    // Outside the panel's range: a usage error (status 2), not a panic.
    assert_eq!(parse(&["--grid-size", "0.001"]).err(), Some(2));
    assert_eq!(parse(&["--grid-size", "fine"]).err(), Some(2));
}
