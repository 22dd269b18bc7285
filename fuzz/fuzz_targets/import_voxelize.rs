//! Any bytes through the importer and, when they import, the voxelizer at a small grid: every input must
//! give a model or a `VoxelError`, never a panic, a hang or a runaway allocation.

#![no_main]

use libfuzzer_sys::fuzz_target;
use voxel_core::{GridSize, VoxelizeOptions, load_slice, voxelize};

fuzz_target!(|data: &[u8]| {
    if let Ok(soup) = load_slice(data, None) {
        // 8..=16 cells along the longest axis, picked by the input's length so seeds stay whole files.
        let resolution = 8 + (data.len() % 9) as u32;
        let _ = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(resolution), ..Default::default() });
    }
});
