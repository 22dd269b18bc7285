//! The colour stage after sampling: a palette maps the visible cells' colours (interior cells copy them),
//! `max_colors` keeps at most that many, and `dither` mixes neighbouring palette colours in an ordered 3-D
//! pattern where a colour falls between them.
//!
//! * `original`: the colours as sampled; `pastel`: the article's remap of them ([`crate::color::pastel`]).
//!   With `max_colors` N, N of those colours chosen by a weighted k-means in Oklab (module `reduce`).
//! * A fixed palette (built-in, or a `.hex`, `.png` or `.vox` file): each colour becomes the nearest palette
//!   colour in Oklab; with `max_colors` N, only the N palette colours most used that way are kept.
//!
//! Deterministic: the result depends on the colours and cells only.

mod builtin;
mod dither;
pub mod file;
mod oklab;
mod reduce;

use std::path::Path;

use rustc_hash::FxHashMap;

use crate::color::pastel;
use crate::error::{Result, VoxelError};
use crate::model::VoxelModel;

pub use builtin::FIXED_NAMES;

/// Where the colours come from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Palette {
    /// The colours as sampled.
    Original,
    /// The article's pastel remap of the sampled colours.
    Pastel,
    /// A fixed list of sRGB colours (distinct), with the name it was given by.
    Fixed {
        /// The built-in's name or the file's path.
        name: String,
        /// The colours.
        colors: Vec<[u8; 3]>,
    },
}

impl Palette {
    /// The palette `arg` names: `original`, `pastel`, a built-in ([`FIXED_NAMES`]), else a palette file's
    /// path ([`file::read`]). A file's error is [`VoxelError::Palette`] or [`VoxelError::Io`] (the caller
    /// names the file).
    pub fn from_arg(arg: &str) -> Result<Self> {
        match arg {
            "original" => Ok(Self::Original),
            "pastel" => Ok(Self::Pastel),
            name => match builtin::colors(name) {
                Some(colors) => Ok(Self::Fixed { name: name.into(), colors }),
                None if Path::new(arg).extension().is_none() => Err(VoxelError::Palette(format!(
                    "no palette named {arg:?} (built-in: original, pastel, {}; or a .hex, .png or .vox file)",
                    FIXED_NAMES.join(", ")
                ))),
                None => Ok(Self::Fixed { name: arg.into(), colors: file::read(Path::new(arg))? }),
            },
        }
    }
}

/// The colour stage: a palette, a colour limit and dithering.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColorStage {
    /// Where the colours come from.
    pub palette: Palette,
    /// Keep at most this many colours (≥ 1).
    pub max_colors: Option<usize>,
    /// Dither between palette colours (an ordered 3-D pattern) instead of taking the nearest.
    pub dither: bool,
}

impl Default for ColorStage {
    /// The sampled colours, unchanged.
    fn default() -> Self {
        Self { palette: Palette::Original, max_colors: None, dither: false }
    }
}

impl ColorStage {
    /// Whether the stage leaves every colour as it is.
    pub fn is_identity(&self) -> bool {
        self.palette == Palette::Original && self.max_colors.is_none()
    }

    /// Recolours `model`'s voxels (sampled colours, e.g. voxelized without `pastel`) and recounts
    /// [`VoxelModel::color_count`] as the distinct RGB colours shown. The alpha of each voxel is kept.
    pub fn apply(&self, model: &mut VoxelModel) -> Result<()> {
        self.apply_keeping(model, &mut None)
    }

    /// [`ColorStage::apply`] to `model`, mapping to `*chosen` when it is set, else to the colours chosen for
    /// `model` (the palette, its most used, or the model's own N), which it then keeps in `*chosen`.
    fn apply_keeping(&self, model: &mut VoxelModel, chosen: &mut Option<Vec<[u8; 3]>>) -> Result<()> {
        if self.max_colors == Some(0) {
            return Err(VoxelError::Parameter("--colors must be at least 1".into()));
        }
        if self.is_identity() {
            return Ok(());
        }
        if self.palette == Palette::Pastel {
            model.recolor(|v| pastel(v.color));
        }
        if chosen.is_none() {
            *chosen = match &self.palette {
                Palette::Fixed { colors, .. } => Some(self.most_used(model, colors)),
                Palette::Original | Palette::Pastel => {
                    self.max_colors.map(|n| reduce::representatives(&histogram(model), n))
                }
            };
        }
        if let Some(targets) = chosen.as_deref() {
            let labs: Vec<oklab::Lab> = targets.iter().map(|&c| oklab::from_srgb(c)).collect();
            let mut nearest: FxHashMap<[u8; 3], usize> = FxHashMap::default();
            model.recolor(|v| {
                let rgb = [v.color[0], v.color[1], v.color[2]];
                let k = if self.dither {
                    dither::pick(&labs, &oklab::from_srgb(rgb), dither::threshold(v.cell))
                } else {
                    *nearest.entry(rgb).or_insert_with(|| oklab::nearest(&labs, &oklab::from_srgb(rgb)))
                };
                let [r, g, b] = targets[k];
                [r, g, b, v.color[3]]
            });
        }
        // The colours the exports show: RGB (a voxel keeps its alpha, which no export writes).
        model.set_color_count(histogram(model).len());
        Ok(())
    }

    /// The stage for the frames of one animation: the colours chosen for the first frame (`--colors N`'s) are
    /// kept for every later one, so a colour does not change from frame to frame.
    pub fn for_frames(&self) -> FrameColors<'_> {
        FrameColors { stage: self, chosen: None }
    }

    /// The colours of `palette` kept: all, or with `max_colors` N the N that the visible cells' colours are
    /// nearest to most often (in palette order; the first of equal counts).
    fn most_used(&self, model: &VoxelModel, palette: &[[u8; 3]]) -> Vec<[u8; 3]> {
        let Some(n) = self.max_colors.filter(|&n| n < palette.len()) else {
            return palette.to_vec();
        };
        let labs: Vec<oklab::Lab> = palette.iter().map(|&c| oklab::from_srgb(c)).collect();
        let mut uses = vec![0usize; palette.len()];
        for (color, count) in histogram(model) {
            uses[oklab::nearest(&labs, &oklab::from_srgb(color))] += count;
        }
        let mut ranked: Vec<usize> = (0..palette.len()).collect();
        ranked.sort_by_key(|&i| std::cmp::Reverse(uses[i]));
        ranked.truncate(n);
        ranked.sort_unstable();
        ranked.into_iter().map(|i| palette[i]).collect()
    }
}

/// A [`ColorStage`] applied to the frames of one animation in turn ([`ColorStage::for_frames`]).
#[derive(Debug)]
pub struct FrameColors<'a> {
    stage: &'a ColorStage,
    /// The colours the first frame was mapped to, when the stage maps to chosen colours.
    chosen: Option<Vec<[u8; 3]>>,
}

impl FrameColors<'_> {
    /// Recolours the next frame as [`ColorStage::apply`] does, to the colours chosen for the first.
    pub fn apply(&mut self, frame: &mut VoxelModel) -> Result<()> {
        self.stage.apply_keeping(frame, &mut self.chosen)
    }
}

/// The visible cells' distinct RGB colours, ascending, with how many cells show each.
fn histogram(model: &VoxelModel) -> Vec<([u8; 3], usize)> {
    let mut counts: FxHashMap<[u8; 3], usize> = FxHashMap::default();
    for v in model.visible_voxels() {
        *counts.entry([v.color[0], v.color[1], v.color[2]]).or_insert(0) += 1;
    }
    let mut histogram: Vec<_> = counts.into_iter().collect();
    histogram.sort_unstable();
    histogram
}

#[cfg(test)]
mod tests {
    use rustc_hash::FxHashSet;

    use super::*;
    use crate::grid::{GridSize, GridSpec};

    /// A 16 × 2 × 2 bar: a grey ramp along x (`16·x` in every channel) but for a bright red slice at x = 7.
    fn ramp() -> VoxelModel {
        let spec =
            GridSpec::fit_bounds(([0.0; 3], [16.0, 2.0, 2.0]), 9.0, GridSize::Resolution(16), 1.0, 1 << 20).unwrap();
        assert_eq!(spec.dims, [16, 2, 2]);
        let cells = (0..16u16).flat_map(|x| {
            (0..2u16).flat_map(move |y| {
                (0..2u16).map(move |z| {
                    let grey = (16 * x) as u8;
                    ([x, y, z], if x == 7 { [250, 10, 30, 255] } else { [grey, grey, grey, 255] })
                })
            })
        });
        VoxelModel::from_cells(spec, cells)
    }

    fn colors_of(model: &VoxelModel) -> FxHashSet<[u8; 3]> {
        model.voxels().map(|v| [v.color[0], v.color[1], v.color[2]]).collect()
    }

    fn stage(palette: &str, max_colors: Option<usize>, dither: bool) -> ColorStage {
        ColorStage { palette: Palette::from_arg(palette).unwrap(), max_colors, dither }
    }

    #[test]
    fn a_fixed_palette_leaves_only_its_colors_and_counts_them() {
        let mut model = ramp();
        stage("gameboy", None, false).apply(&mut model).unwrap();
        let gameboy: FxHashSet<[u8; 3]> = builtin::colors("gameboy").unwrap().into_iter().collect();
        let shown = colors_of(&model);
        assert!(shown.is_subset(&gameboy), "{shown:?}");
        assert_eq!(shown.len(), 4, "a ramp from black to white uses all four");
        assert_eq!(model.color_count(), 4);
    }

    #[test]
    fn colors_n_keeps_the_most_used_palette_colors_or_the_models_own() {
        let mut model = ramp();
        stage("pico8", Some(3), false).apply(&mut model).unwrap();
        assert!(colors_of(&model).len() <= 3);
        let mut model = ramp();
        let before = colors_of(&model);
        stage("original", Some(4), false).apply(&mut model).unwrap();
        let after = colors_of(&model);
        assert_eq!(after.len(), 4);
        assert!(after.is_subset(&before), "the model's own colours");
        assert!(after.contains(&[250, 10, 30]), "the small bright slice keeps its colour: {after:?}");
    }

    #[test]
    fn pastel_is_the_remap_and_original_without_a_limit_changes_nothing() {
        let mut model = ramp();
        let untouched = model.clone();
        ColorStage::default().apply(&mut model).unwrap();
        assert_eq!(model, untouched);
        stage("pastel", None, false).apply(&mut model).unwrap();
        let remapped: Vec<[u8; 4]> = untouched.voxels().map(|v| pastel(v.color)).collect();
        assert_eq!(model.voxels().map(|v| v.color).collect::<Vec<_>>(), remapped);
    }

    #[test]
    fn dithering_mixes_the_two_nearest_colors_and_stays_in_the_palette() {
        let mut plain = ramp();
        let mut dithered = ramp();
        stage("gameboy", None, false).apply(&mut plain).unwrap();
        stage("gameboy", None, true).apply(&mut dithered).unwrap();
        let gameboy: FxHashSet<[u8; 3]> = builtin::colors("gameboy").unwrap().into_iter().collect();
        assert!(colors_of(&dithered).is_subset(&gameboy));
        let differing = plain.voxels().zip(dithered.voxels()).filter(|(a, b)| a.color != b.color).count();
        assert!(differing > 4, "some greys mix two greens: {differing}");
    }

    #[test]
    fn the_frames_of_an_animation_keep_the_first_frames_colors() {
        let stage = stage("original", Some(3), false);
        let mut frames = stage.for_frames();
        let mut first = ramp();
        frames.apply(&mut first).unwrap();
        // The next frame's greys are darker: alone it would choose other colours.
        let mut darker = ramp();
        darker.recolor(|v| v.color.map(|c| c / 2));
        let mut alone = darker.clone();
        stage.apply(&mut alone).unwrap();
        frames.apply(&mut darker).unwrap();
        assert!(colors_of(&darker).is_subset(&colors_of(&first)), "{:?} {:?}", colors_of(&darker), colors_of(&first));
        assert_ne!(colors_of(&alone), colors_of(&first));
    }

    #[test]
    fn unknown_names_and_zero_colors_are_errors() {
        let err = Palette::from_arg("vga").unwrap_err().to_string();
        assert!(
            err.starts_with("not a usable palette: no palette named \"vga\" (built-in: original, pastel, pico8"),
            "{err}"
        );
        let err = stage("pico8", Some(0), false).apply(&mut ramp()).unwrap_err().to_string();
        assert_eq!(err, "invalid parameter: --colors must be at least 1");
    }
}
