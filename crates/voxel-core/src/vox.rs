//! MagicaVoxel .vox export (through dot_vox): colours quantized to at most 255 palette entries (median cut),
//! grids over 256 cells per axis split into several models placed by a scene graph.

use std::path::Path;

use dot_vox::{Color, DotVoxData, Frame, Model, SceneNode, ShapeModel, Size, Voxel as VoxVoxel};
use rustc_hash::FxHashMap;

use crate::error::{Result, VoxelError};
use crate::model::VoxelModel;

/// The largest model edge the format allows.
pub const MAX_MODEL_EDGE: u32 = 256;
/// Usable palette entries (index 0 is reserved by the format).
pub const MAX_COLORS: usize = 255;

/// A box of colours for median cut: the colours with their voxel counts, and its widest channel with that
/// channel's range.
struct ColorBox {
    colors: Vec<([u8; 3], usize)>,
    widest: (usize, u8),
}

impl ColorBox {
    fn new(colors: Vec<([u8; 3], usize)>) -> Self {
        let range = |channel: usize| {
            let (lo, hi) =
                colors.iter().fold((255u8, 0u8), |(lo, hi), (c, _)| (lo.min(c[channel]), hi.max(c[channel])));
            hi.saturating_sub(lo)
        };
        let widest = (0..3).map(|c| (c, range(c))).max_by_key(|&(c, r)| (r, std::cmp::Reverse(c))).unwrap_or((0, 0));
        Self { colors, widest }
    }

    fn mean(&self) -> [u8; 3] {
        let total: usize = self.colors.iter().map(|(_, n)| n).sum::<usize>().max(1);
        std::array::from_fn(|ch| {
            let sum: usize = self.colors.iter().map(|(c, n)| usize::from(c[ch]) * n).sum();
            ((sum + total / 2) / total) as u8
        })
    }
}

/// Reduces `histogram` (distinct colours in ascending order, each with its voxel count) to at most `max`
/// colours by median cut. Returns the palette and the palette index of every input colour. Deterministic;
/// exact when there are few enough colours.
pub fn quantize(histogram: &[([u8; 3], usize)], max: usize) -> (Vec<[u8; 3]>, FxHashMap<[u8; 3], usize>) {
    if histogram.len() <= max {
        let palette: Vec<[u8; 3]> = histogram.iter().map(|&(c, _)| c).collect();
        let index = palette.iter().enumerate().map(|(i, &c)| (c, i)).collect();
        return (palette, index);
    }
    let mut boxes = vec![ColorBox::new(histogram.to_vec())];
    while boxes.len() < max {
        // Split the box with the widest channel range (ties: the most populous), at its weighted median.
        let Some((k, (channel, range))) = boxes
            .iter()
            .enumerate()
            .filter(|(_, b)| b.colors.len() > 1)
            .map(|(k, b)| (k, b.widest))
            .max_by_key(|&(k, (_, r))| (r, std::cmp::Reverse(k)))
        else {
            break;
        };
        if range == 0 {
            break;
        }
        let mut colors = std::mem::take(&mut boxes[k].colors);
        colors.sort_by_key(|(c, _)| (c[channel], *c));
        let total: usize = colors.iter().map(|(_, n)| n).sum();
        let mut acc = 0;
        let mut cut = 1;
        for (i, (_, n)) in colors.iter().enumerate() {
            acc += n;
            if acc * 2 >= total {
                cut = (i + 1).clamp(1, colors.len() - 1);
                break;
            }
        }
        let upper = colors.split_off(cut);
        boxes[k] = ColorBox::new(colors);
        boxes.push(ColorBox::new(upper));
    }
    let palette: Vec<[u8; 3]> = boxes.iter().map(ColorBox::mean).collect();
    let index = boxes.iter().enumerate().flat_map(|(i, b)| b.colors.iter().map(move |(c, _)| (*c, i))).collect();
    (palette, index)
}

/// What an export wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxSummary {
    /// Models in the file (one per 256³ block that holds voxels).
    pub models: usize,
    /// Palette entries used.
    pub colors: usize,
    /// Voxels written.
    pub voxels: usize,
}

/// Converts a voxel model to MagicaVoxel data (z up: our y becomes MagicaVoxel's z).
pub fn to_dot_vox(model: &VoxelModel) -> (DotVoxData, VoxSummary) {
    // The voxels once (interior colours are found on demand): their cells and colours, then the colours' counts.
    let voxels: Vec<([u16; 3], [u8; 3])> =
        model.voxels().map(|v| (v.cell, [v.color[0], v.color[1], v.color[2]])).collect();
    // Consecutive voxels mostly share a colour (a run's interior cells take its ends'): count by such stretches.
    let mut counts: FxHashMap<[u8; 3], usize> = FxHashMap::default();
    for same in voxels.chunk_by(|a, b| a.1 == b.1) {
        *counts.entry(same[0].1).or_insert(0) += same.len();
    }
    let mut histogram: Vec<([u8; 3], usize)> = counts.into_iter().collect();
    histogram.sort_unstable();
    let (palette, index) = quantize(&histogram, MAX_COLORS);
    // Group voxels into 256³ blocks, numbered in (x, y, z) block order.
    let dims = [model.spec.dims[0], model.spec.dims[2], model.spec.dims[1]];
    let per_axis = dims.map(|d| d.div_ceil(MAX_MODEL_EDGE) as usize);
    let mut blocks: Vec<Vec<VoxVoxel>> = vec![Vec::new(); per_axis.iter().product()];
    for same in voxels.chunk_by(|a, b| a.1 == b.1) {
        let i = index[&same[0].1] as u8;
        for (cell, _) in same {
            let [x, y, z] = [cell[0], cell[2], cell[1]].map(u32::from);
            let [bx, by, bz] = [x, y, z].map(|c| (c / MAX_MODEL_EDGE) as usize);
            blocks[(bx * per_axis[1] + by) * per_axis[2] + bz].push(VoxVoxel {
                x: (x % MAX_MODEL_EDGE) as u8,
                y: (y % MAX_MODEL_EDGE) as u8,
                z: (z % MAX_MODEL_EDGE) as u8,
                i,
            });
        }
    }
    let mut models = Vec::new();
    let mut scenes = vec![
        SceneNode::Transform {
            attributes: Default::default(),
            frames: vec![Frame::new(Default::default())],
            child: 1,
            layer_id: u32::MAX,
        },
        SceneNode::Group { attributes: Default::default(), children: Vec::new() },
    ];
    for (block, voxels) in blocks.into_iter().enumerate().filter(|(_, voxels)| !voxels.is_empty()) {
        let key = [block / (per_axis[1] * per_axis[2]), block / per_axis[2] % per_axis[1], block % per_axis[2]]
            .map(|k| k as u32);
        let size: [u32; 3] = std::array::from_fn(|a| (dims[a] - key[a] * MAX_MODEL_EDGE).min(MAX_MODEL_EDGE));
        // MagicaVoxel places a model by its centre; keep the whole grid centred on the origin.
        let t: [i64; 3] =
            std::array::from_fn(|a| i64::from(key[a] * MAX_MODEL_EDGE + size[a] / 2) - i64::from(dims[a] / 2));
        let transform_id = scenes.len() as u32;
        if let SceneNode::Group { children, .. } = &mut scenes[1] {
            children.push(transform_id);
        }
        let frame = Frame::new([("_t".to_string(), format!("{} {} {}", t[0], t[1], t[2]))].into_iter().collect());
        scenes.push(SceneNode::Transform {
            attributes: Default::default(),
            frames: vec![frame],
            child: transform_id + 1,
            layer_id: 0,
        });
        scenes.push(SceneNode::Shape {
            attributes: Default::default(),
            models: vec![ShapeModel { model_id: models.len() as u32, attributes: Default::default() }],
        });
        models.push(Model { size: Size { x: size[0], y: size[1], z: size[2] }, voxels });
    }
    let mut colors: Vec<Color> = palette.iter().map(|c| Color { r: c[0], g: c[1], b: c[2], a: 255 }).collect();
    colors.resize(256, Color { r: 0, g: 0, b: 0, a: 255 });
    let summary = VoxSummary { models: models.len(), colors: palette.len(), voxels: model.len() };
    let data = DotVoxData {
        version: 150,
        index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
        models,
        palette: colors,
        materials: Vec::new(),
        scenes,
        layers: vec![dot_vox::Layer { attributes: Default::default() }],
    };
    (data, summary)
}

/// Writes `model` as a .vox file.
pub fn write_vox(model: &VoxelModel, path: &Path) -> Result<VoxSummary> {
    let (data, summary) = to_dot_vox(model);
    let export_error = |reason: String| VoxelError::Export { path: path.to_owned(), reason };
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes).map_err(|e| export_error(e.to_string()))?;
    std::fs::write(path, bytes).map_err(|e| export_error(e.to_string()))?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_colors_are_kept_exactly() {
        let h = [([1, 2, 3], 5), ([200, 0, 0], 1)];
        let (palette, index) = quantize(&h, 255);
        assert_eq!(palette.len(), 2);
        assert_eq!(palette[index[&[200, 0, 0]]], [200, 0, 0]);
    }

    #[test]
    fn many_colors_are_cut_to_the_limit_and_stay_close() {
        let mut h: Vec<([u8; 3], usize)> =
            (0..4096u32).map(|i| ([(i % 16 * 16) as u8, (i / 16 % 16 * 16) as u8, (i / 256 * 16) as u8], 1)).collect();
        h.sort_unstable();
        let (palette, index) = quantize(&h, 255);
        assert!(palette.len() <= 255 && palette.len() > 200, "{}", palette.len());
        for (c, &i) in &index {
            let err: i32 = (0..3).map(|k| (i32::from(c[k]) - i32::from(palette[i][k])).abs()).max().unwrap();
            assert!(err <= 24, "{c:?} → {:?}", palette[i]);
        }
    }
}
