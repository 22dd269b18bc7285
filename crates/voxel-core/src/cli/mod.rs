//! The headless `voxel-art voxelize` command: batch voxelization with stats and .vox or glTF export.

use std::ffi::OsString;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Parser;

use crate::error::{Result, VoxelError};
use crate::export::{self, ExportOptions, Format};
use crate::files::expand_inputs;
use crate::grid::GridSize;
use crate::options::{FillMode, Method, ShellMode, VoxelizeOptions};
use crate::palette::ColorStage;
use crate::voxelize::voxelize;
use report::{Exported, stem, to_json};

pub mod animation;
pub mod palette;
mod process;
mod report;

pub use process::{prepare_process, with_workers_awake};

/// The arguments of `voxel-art voxelize`: a clap subcommand of the app's command line, or a command of its own
/// through [`run`].
#[derive(Debug, Parser)]
#[command(
    name = "voxel-art voxelize",
    bin_name = "voxel-art voxelize",
    version,
    about = "Voxelize glTF/GLB models headless: stats (optionally JSON lines), .vox and glTF export",
    long_about = None
)]
pub struct VoxelizeArgs {
    /// Model files (.glb/.gltf) or folders holding them.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Cells along the longest axis of the model.
    #[arg(long, short = 'r', conflicts_with = "grid_size")]
    resolution: Option<u32>,
    /// Cell width in model units (the model's diagonal is scaled to --model-size).
    #[arg(long, short = 'g')]
    grid_size: Option<f32>,
    /// Length of the model's bounding-box diagonal after normalization.
    #[arg(long, default_value_t = 9.0)]
    model_size: f32,
    /// Cell height as a multiple of the cell width (1.2 for Lego bricks).
    #[arg(long, default_value_t = 1.0)]
    cell_height: f32,
    /// How the interior is found.
    #[arg(long, value_enum, default_value = "winding")]
    fill: FillMode,
    /// Which surface cells join the solid.
    #[arg(long, value_enum, default_value = "auto")]
    shell: ShellMode,
    /// Keep only voxels with an empty face neighbour.
    #[arg(long)]
    hollow: bool,
    /// The colour stage: --palette, --pastel, --colors, --dither.
    #[command(flatten)]
    pub(crate) palette: palette::PaletteArgs,
    /// Parity implementation (all give the same cells; reference is the slow per-point algorithm).
    #[arg(long, value_enum, default_value = "fast")]
    method: Method,
    /// Export: a file for one input (.glb, .gltf + .bin, else MagicaVoxel .vox, by extension), a folder
    /// (one <name>.<format> each) for several.
    #[arg(long, short = 'o')]
    out: Option<PathBuf>,
    /// Export format, overriding the --out extension (the format of a folder's files, --animation's frames
    /// included; default vox).
    #[arg(long, value_enum)]
    format: Option<Format>,
    /// Print one JSON object per line per file instead of a readable summary.
    #[arg(long)]
    json: bool,
    /// The most memory a voxelization may take, in MB (default: what the system has available); a grid that
    /// would need more is refused with the memory it needs.
    #[arg(long, value_name = "MB")]
    max_memory: Option<u64>,
    /// Voxelize an animation clip (name or index) frame by frame in one grid; `list` prints the clips.
    /// --out is then one animated file when it ends in .glb or .gltf, else a folder of
    /// <name>-<frame>.<format> files.
    #[arg(long)]
    animation: Option<String>,
    /// Frames per second of --animation.
    #[arg(long, default_value_t = 12.0, requires = "animation")]
    fps: f32,
    /// Seconds of --animation to voxelize (default: one clip length).
    #[arg(long, requires = "animation")]
    duration: Option<f32>,
}

impl VoxelizeArgs {
    pub(crate) fn options(&self) -> VoxelizeOptions {
        VoxelizeOptions {
            model_size: self.model_size,
            grid: match (self.resolution, self.grid_size) {
                (Some(r), _) => GridSize::Resolution(r),
                (None, Some(g)) => GridSize::Cell(g),
                (None, None) => GridSize::default(),
            },
            cell_height_ratio: self.cell_height,
            fill: self.fill,
            shell: self.shell,
            hollow: self.hollow,
            method: self.method,
            // The colour stage applies the remap (`palette`).
            pastel: false,
            max_memory: self.max_memory.map(|mb| mb.saturating_mul(1_000_000)),
        }
    }

    /// The export format: --format, else the extension of a single output file, else .vox.
    fn format(&self, several: bool) -> Format {
        match (self.format, &self.out) {
            (Some(format), _) => format,
            (None, Some(out)) if !several => Format::of_path(out),
            (None, _) => Format::Vox,
        }
    }
}

/// The JSON line printed per file.
#[derive(serde::Serialize)]
struct Report<'a> {
    file: &'a str,
    triangles: usize,
    grid: [u32; 3],
    voxels: usize,
    surface: usize,
    visible: usize,
    colors: usize,
    output_voxels: usize,
    load_ms: f64,
    voxelize_ms: f64,
    /// Time to write the export, when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    write_ms: Option<f64>,
    #[serde(flatten)]
    exported: Exported,
}

fn export_path(out: &Path, input: &Path, several: bool, format: Format) -> PathBuf {
    if several { out.join(format!("{}.{}", stem(input), format.extension())) } else { out.to_owned() }
}

pub(crate) fn process(
    file: &Path,
    args: &VoxelizeArgs,
    options: &VoxelizeOptions,
    colors: &ColorStage,
    several: bool,
) -> Result<String> {
    if let Some(animation) = &args.animation {
        if several && args.out.as_deref().is_some_and(|out| Format::of_path(out) != Format::Vox) {
            return Err(VoxelError::Parameter(
                "one animated .glb/.gltf holds one model's clip: with several models, --out is a folder".into(),
            ));
        }
        let request = animation::ClipRequest {
            animation,
            fps: args.fps,
            duration: args.duration,
            out: args.out.as_deref(),
            format: args.format(true),
            json: args.json,
            colors,
        };
        return animation::voxelize_clip(file, &request, options).map(|lines| lines.join("\n"));
    }
    let t0 = Instant::now();
    let soup = crate::import::load_file(file)?;
    let load_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    let mut model = voxelize(&soup, options)?;
    colors.apply(&mut model)?;
    let voxelize_ms = t1.elapsed().as_secs_f64() * 1e3;
    let t2 = Instant::now();
    let exported = match &args.out {
        Some(out) => {
            if several {
                std::fs::create_dir_all(out)
                    .map_err(|e| VoxelError::Export { path: out.clone(), reason: e.to_string() })?;
            }
            let format = args.format(several);
            let path = export_path(out, file, several, format);
            let written = export::write(&model, &path, format, &ExportOptions { name: stem(file) })?;
            Exported::new(&path, written)
        }
        None => Exported::default(),
    };
    let write_ms = args.out.as_ref().map(|_| t2.elapsed().as_secs_f64() * 1e3);
    let s = model.stats;
    let name = file.display().to_string();
    if args.json {
        let report = Report {
            file: &name,
            triangles: s.triangles,
            grid: s.grid,
            voxels: s.voxels,
            surface: s.surface,
            visible: s.visible,
            colors: model.color_count(),
            output_voxels: model.len(),
            load_ms,
            voxelize_ms,
            write_ms,
            exported,
        };
        to_json(&report)
    } else {
        let [nx, ny, nz] = s.grid;
        let written = exported.summary();
        Ok(format!(
            "{name}: {} triangles -> {nx}x{ny}x{nz} grid, {} voxels ({} surface, {} visible, {} output), {} colours; load {load_ms:.1} ms, voxelize {voxelize_ms:.1} ms{written}",
            s.triangles,
            s.voxels,
            s.surface,
            s.visible,
            model.len(),
            model.color_count()
        ))
    }
}

/// Parses `args` as `voxel-art voxelize` on its own (the first item is the program name) and runs it. Returns
/// the exit status: 2 on bad usage (0 for `--help`), else that of [`execute`].
pub fn run(args: impl IntoIterator<Item = OsString>) -> i32 {
    match VoxelizeArgs::try_parse_from(args) {
        Ok(args) => execute(&args),
        Err(e) => report_parse_error(&e),
    }
}

/// Prints what parsing a command line gave instead of arguments (a usage error, or the `--help` or
/// `--version` text) and returns the exit status for it: 2 for an error, else 0. The one place that maps
/// parse errors to exit statuses: `voxel-art`'s own command line uses it too.
pub fn report_parse_error(error: &clap::Error) -> i32 {
    let _ = error.print();
    if error.use_stderr() { 2 } else { 0 }
}

/// Voxelizes (and exports) every file `args` names. Returns the exit status: 0 when every file succeeded, 1
/// when any failed (each named on stderr as `error: <file>: <reason>`, after processing the others).
pub fn execute(args: &VoxelizeArgs) -> i32 {
    let options = args.options();
    let colors = match args.palette.stage() {
        Ok(stage) => stage,
        Err((what, e)) => {
            eprintln!("error: {what}: {e}");
            return 1;
        }
    };
    let files = expand_inputs(&args.files);
    if files.is_empty() {
        eprintln!("error: no .glb or .gltf files found in the given folders");
        return 1;
    }
    let several = files.len() > 1;
    let progress = if several && std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(files.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    let stdout = std::io::stdout();
    // The pool's other workers are kept awake from before the first read to the end of the last file: a worker woken
    // when a voxelization starts may take milliseconds to join it where the hypervisor has parked its idle core.
    let failed = with_workers_awake(|| {
        let mut failed = false;
        for file in &files {
            progress.set_message(file.display().to_string());
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                process(file, args, &options, &colors, several)
            }));
            match outcome {
                Ok(Ok(line)) => {
                    progress.suspend(|| {
                        let _ = writeln!(stdout.lock(), "{line}");
                    });
                }
                Ok(Err(e)) => {
                    failed = true;
                    progress.suspend(|| eprintln!("error: {}: {e}", file.display()));
                }
                Err(_) => {
                    failed = true;
                    progress
                        .suspend(|| eprintln!("error: {}: internal error (panic); please report it", file.display()));
                }
            }
            progress.inc(1);
        }
        failed
    });
    progress.finish_and_clear();
    i32::from(failed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::cuboid;
    use crate::soup::TriangleSoup;

    #[test]
    fn max_memory_is_in_megabytes_and_a_grid_over_it_is_refused_naming_the_memory_needed() {
        let dir = std::env::temp_dir().join(format!("voxel-core-cli-memory-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("block.glb");
        let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [2.0, 1.0, 1.0]), [1.0; 4]);
        std::fs::write(&input, crate::glb::soup_to_glb(&soup).unwrap()).unwrap();
        let args = |extra: &[&str]| {
            let mut args = vec!["voxelize", input.to_str().unwrap(), "-r", "256"];
            args.extend(extra);
            VoxelizeArgs::try_parse_from(args).unwrap()
        };
        assert_eq!(args(&[]).options().max_memory, None);
        let tight = args(&["--max-memory", "1"]);
        assert_eq!(tight.options().max_memory, Some(1_000_000));
        let err = process(&input, &tight, &tight.options(), &ColorStage::default(), false).unwrap_err().to_string();
        assert!(err.contains("grid 256x128x128 needs about") && err.contains("more than the 1 MB available"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_json_line_times_the_write_only_when_there_is_one() {
        let dir = std::env::temp_dir().join(format!("voxel-core-cli-write-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("block.glb");
        let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [2.0, 1.0, 1.0]), [1.0; 4]);
        std::fs::write(&input, crate::glb::soup_to_glb(&soup).unwrap()).unwrap();
        let report = |extra: &[&str]| -> serde_json::Value {
            let mut args = vec!["voxelize", input.to_str().unwrap(), "-r", "4", "--json"];
            args.extend(extra);
            let args = VoxelizeArgs::try_parse_from(args).unwrap();
            serde_json::from_str(&process(&input, &args, &args.options(), &ColorStage::default(), false).unwrap())
                .unwrap()
        };
        let plain = report(&[]);
        assert_eq!(plain["voxels"], 4 * 2 * 2);
        assert!(plain.get("write_ms").is_none() && plain.get("vox").is_none(), "{plain}");
        let vox = dir.join("block.vox");
        let written = report(&["--out", vox.to_str().unwrap()]);
        assert!(written["write_ms"].as_f64().unwrap() >= 0.0, "{written}");
        assert_eq!(written["vox"], vox.display().to_string());
        assert!(vox.is_file());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
