//! `--palette NAME|FILE`, `--pastel` (its alias for `pastel`), `--colors N` and `--dither` of `voxel-art
//! voxelize`: the colour stage ([`crate::palette`]) applied to every voxelization (and every frame of a clip).

use crate::error::VoxelError;
use crate::palette::{ColorStage, Palette};

/// The colour options of `voxel-art voxelize`.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct PaletteArgs {
    /// Colour palette: original (as sampled), pastel, pico8, gameboy, magicavoxel, endesga32, sweetie16, or a
    /// palette file: .hex (one rrggbb a line, `;` comments), .png (its distinct pixels) or .vox (its palette).
    #[arg(long, value_name = "NAME|FILE")]
    palette: Option<String>,
    /// Apply the pastel colour remap (the same as --palette pastel).
    #[arg(long, conflicts_with = "palette")]
    pastel: bool,
    /// Keep at most N colours: for original and pastel, N of the model's own (chosen in Oklab), for a fixed
    /// palette its N most used.
    #[arg(long = "colors", value_name = "N")]
    colors: Option<usize>,
    /// Dither between palette colours with an ordered 3-D pattern instead of taking the nearest.
    #[arg(long)]
    dither: bool,
}

impl PaletteArgs {
    /// The colour stage asked for, or the failing palette argument with the reason.
    pub fn stage(&self) -> Result<ColorStage, (String, VoxelError)> {
        self.stage_or(Palette::Original)
    }

    /// The colour stage asked for, with `default` when no palette is named (the app's is pastel), or the
    /// failing palette argument with the reason.
    pub fn stage_or(&self, default: Palette) -> Result<ColorStage, (String, VoxelError)> {
        let palette = match (&self.palette, self.pastel) {
            (Some(arg), _) => Palette::from_arg(arg).map_err(|e| (arg.clone(), e))?,
            (None, true) => Palette::Pastel,
            (None, false) => default,
        };
        if self.colors == Some(0) {
            return Err(("--colors".into(), VoxelError::Parameter("--colors must be at least 1".into())));
        }
        Ok(ColorStage { palette, max_colors: self.colors, dither: self.dither })
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;
    use std::path::{Path, PathBuf};

    use clap::Parser;

    use crate::cli::{VoxelizeArgs, process};
    use crate::shapes::cuboid;
    use crate::soup::TriangleSoup;
    use crate::srgb::linear_to_srgb;

    /// A scratch folder for one test.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("voxel-core-cli-palette-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A row of eight boxes in eight colours (a bright red one among greys and blues), as a .glb in `dir`.
    fn boxes(dir: &Path) -> PathBuf {
        let colors: [[f32; 3]; 8] = [
            [0.05, 0.05, 0.05],
            [0.2, 0.2, 0.2],
            [0.4, 0.4, 0.45],
            [0.7, 0.7, 0.7],
            [0.9, 0.9, 0.95],
            [0.1, 0.2, 0.6],
            [0.3, 0.5, 0.9],
            [0.95, 0.02, 0.02],
        ];
        let mut soup = TriangleSoup::default();
        for (k, [r, g, b]) in colors.into_iter().enumerate() {
            let x = k as f32;
            soup.add_mesh(&cuboid([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0]), [r, g, b, 1.0], &format!("box {k}"));
        }
        let path = dir.join("boxes.glb");
        std::fs::write(&path, crate::glb::soup_to_glb(&soup).unwrap()).unwrap();
        path
    }

    /// Runs `voxel-art voxelize` on `input` with `extra` arguments and returns its JSON line.
    fn report(input: &Path, extra: &[&str]) -> serde_json::Value {
        let mut args = vec!["voxelize", input.to_str().unwrap(), "-r", "16", "--json"];
        args.extend(extra);
        let args = VoxelizeArgs::try_parse_from(args).unwrap();
        let stage = args.palette.stage().unwrap();
        serde_json::from_str(&process(input, &args, &args.options(), &stage, false).unwrap()).unwrap()
    }

    /// The colours of the voxels of a .vox file.
    fn vox_colors(path: &Path) -> HashSet<[u8; 3]> {
        let data = dot_vox::load(path.to_str().unwrap()).unwrap();
        let palette = &data.palette;
        data.models.iter().flat_map(|m| &m.voxels).map(|v| palette[usize::from(v.i)]).map(|c| [c.r, c.g, c.b]).collect()
    }

    /// The colours of a .glb's vertices, back in sRGB (COLOR_0 is linear).
    fn glb_colors(path: &Path) -> HashSet<[u8; 3]> {
        let soup = crate::import::load_file(path).unwrap();
        soup.colors().iter().map(|c| [0, 1, 2].map(|k| linear_to_srgb(c[k]))).collect()
    }

    /// Exports the boxes with `palette` as .vox and .glb; the colours in both are the JSON's `colors` many and
    /// all from `allowed`.
    fn assert_limited(dir: &Path, palette: &str, allowed: &HashSet<[u8; 3]>) {
        let input = boxes(dir);
        let vox = dir.join("out.vox");
        let glb = dir.join("out.glb");
        let line = report(&input, &["--palette", palette, "--out", vox.to_str().unwrap()]);
        report(&input, &["--palette", palette, "--out", glb.to_str().unwrap()]);
        let (in_vox, in_glb) = (vox_colors(&vox), glb_colors(&glb));
        assert!(in_vox.is_subset(allowed) && in_glb.is_subset(allowed), "{palette}: {in_vox:?} {in_glb:?}");
        assert_eq!(in_vox, in_glb, "{palette}");
        assert_eq!(line["colors"], in_vox.len(), "{palette}: {line}");
        assert_eq!(line["vox_colors"], in_vox.len(), "{palette}: {line}");
        assert!(in_vox.len() >= 2, "{palette}: {in_vox:?}");
    }

    #[test]
    fn a_palette_limits_the_exported_vox_and_glb_to_its_colors() {
        let dir = scratch("limits");
        let set = |colors: &[[u8; 3]]| colors.iter().copied().collect::<HashSet<_>>();
        let pico8 = crate::palette::Palette::from_arg("pico8").unwrap();
        let crate::palette::Palette::Fixed { colors, .. } = &pico8 else { panic!("fixed") };
        assert_limited(&dir, "pico8", &set(colors));
        // A .hex file.
        let hex = dir.join("four.hex");
        std::fs::write(&hex, "; four colours\n101010\nf0f0f0\n2040c0\nff2020\n").unwrap();
        let four = [[16, 16, 16], [240, 240, 240], [32, 64, 192], [255, 32, 32]];
        assert_limited(&dir, hex.to_str().unwrap(), &set(&four));
        // A .png strip of three colours, one repeated.
        let png = dir.join("strip.png");
        let strip = [[200, 30, 30], [30, 200, 30], [200, 30, 30], [30, 30, 200]];
        image::RgbImage::from_fn(4, 1, |x, _| image::Rgb(strip[x as usize])).save(&png).unwrap();
        assert_limited(&dir, png.to_str().unwrap(), &set(&strip));
        // A .vox's palette: two colours, the rest of its 255 black.
        let vox = dir.join("two.vox");
        let mut data = dot_vox::DotVoxData {
            version: 150,
            index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
            models: vec![dot_vox::Model {
                size: dot_vox::Size { x: 1, y: 1, z: 1 },
                voxels: vec![dot_vox::Voxel { x: 0, y: 0, z: 0, i: 0 }],
            }],
            palette: vec![dot_vox::Color { r: 0, g: 0, b: 0, a: 255 }; 256],
            materials: Vec::new(),
            scenes: Vec::new(),
            layers: Vec::new(),
        };
        data.palette[0] = dot_vox::Color { r: 250, g: 250, b: 250, a: 255 };
        data.palette[1] = dot_vox::Color { r: 90, g: 20, b: 120, a: 255 };
        let mut bytes = Vec::new();
        data.write_vox(&mut bytes).unwrap();
        std::fs::write(&vox, bytes).unwrap();
        assert_limited(&dir, vox.to_str().unwrap(), &set(&[[250, 250, 250], [90, 20, 120], [0, 0, 0]]));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn colors_n_gives_at_most_n_colors_and_keeps_the_bright_one() {
        let dir = scratch("colors");
        let input = boxes(&dir);
        assert_eq!(report(&input, &[])["colors"], 8);
        let vox = dir.join("three.vox");
        let line = report(&input, &["--colors", "3", "--out", vox.to_str().unwrap()]);
        assert_eq!(line["colors"], 3, "{line}");
        let shown = vox_colors(&vox);
        assert_eq!(shown.len(), 3);
        let red = [0.95f32, 0.02, 0.02].map(linear_to_srgb);
        assert!(shown.contains(&red), "the one bright box keeps its colour: {shown:?}");
        for palette in ["magicavoxel", "pico8", "pastel"] {
            let line = report(&input, &["--palette", palette, "--colors", "4", "--dither"]);
            assert!(line["colors"].as_u64().unwrap() <= 4, "{palette}: {line}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn pastel_is_the_palette_and_the_old_flag() {
        let dir = scratch("pastel");
        let input = boxes(&dir);
        let (plain, a, b) = (dir.join("plain.vox"), dir.join("a.vox"), dir.join("b.vox"));
        report(&input, &["--out", plain.to_str().unwrap()]);
        report(&input, &["--pastel", "--out", a.to_str().unwrap()]);
        report(&input, &["--palette", "pastel", "--out", b.to_str().unwrap()]);
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let remapped: HashSet<[u8; 3]> = vox_colors(&plain)
            .into_iter()
            .map(|[r, g, b]| {
                let [r, g, b, _] = crate::color::pastel([r, g, b, 255]);
                [r, g, b]
            })
            .collect();
        assert_eq!(vox_colors(&a), remapped);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_palettes_are_errors_naming_the_file() {
        let dir = scratch("bad");
        let stage = |arg: &str| {
            let args = VoxelizeArgs::try_parse_from(["voxelize", "x.glb", "--palette", arg]).unwrap();
            let (what, e) = args.palette.stage().unwrap_err();
            format!("error: {what}: {e}")
        };
        let hex = dir.join("bad.hex");
        std::fs::write(&hex, "ff0000\nnot a colour\n").unwrap();
        let hex = hex.to_str().unwrap();
        assert_eq!(
            stage(hex),
            format!("error: {hex}: not a usable palette: line 2: \"not a colour\" is not a colour rrggbb")
        );
        let png = dir.join("bad.png");
        std::fs::write(&png, b"GIF89a").unwrap();
        let png = png.to_str().unwrap();
        assert!(
            stage(png).starts_with(&format!("error: {png}: not a usable palette: not a readable PNG")),
            "{}",
            stage(png)
        );
        let missing = dir.join("missing.vox");
        let missing = missing.to_str().unwrap();
        assert!(
            stage(missing).starts_with(&format!("error: {missing}: cannot read {missing}: ")),
            "{}",
            stage(missing)
        );
        assert!(stage("nes").starts_with("error: nes: not a usable palette: no palette named \"nes\""));
        let args = VoxelizeArgs::try_parse_from(["voxelize", "x.glb", "--colors", "0"]).unwrap();
        assert_eq!(args.palette.stage().unwrap_err().1.to_string(), "invalid parameter: --colors must be at least 1");
        assert!(VoxelizeArgs::try_parse_from(["voxelize", "x.glb", "--pastel", "--palette", "pico8"]).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
