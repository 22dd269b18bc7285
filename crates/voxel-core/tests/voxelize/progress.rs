//! A watched voxelization: its stages, its result, and stopping when cancelled.

use voxel_core::shapes::uv_sphere;
use voxel_core::{Progress, Stage, TriangleSoup, VoxelError, voxelize, voxelize_watched};

use crate::common::at_resolution;

fn sphere() -> TriangleSoup {
    TriangleSoup::from_mesh(&uv_sphere(1.0, 24), [0.2, 0.6, 0.9, 1.0])
}

#[test]
fn a_watched_voxelization_reaches_done_with_the_same_voxels() {
    let soup = sphere();
    let progress = Progress::new();
    let watched = voxelize_watched(&soup, &at_resolution(40), &progress).unwrap();
    assert_eq!(progress.stage(), Stage::Done);
    assert_eq!(progress.stage().fraction(), 1.0);
    assert_eq!(watched, voxelize(&soup, &at_resolution(40)).unwrap());
}

#[test]
fn a_cancelled_voxelization_stops_with_an_error_at_its_next_stage() {
    let progress = Progress::new();
    progress.cancel();
    let err = voxelize_watched(&sphere(), &at_resolution(40), &progress).unwrap_err();
    assert!(matches!(err, VoxelError::Cancelled), "{err}");
    assert_eq!(err.to_string(), "cancelled");
    assert_eq!(progress.stage(), Stage::Waiting, "no stage was entered");
}
