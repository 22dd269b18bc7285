//! Mouse repel: voxels near the cursor ray are pushed away from it and spring back (critically damped) when
//! the cursor leaves. Works in every style; not while the pointer is over the panel (no cursor ray then).
//! The push and the spring are `instancing::spring`'s, drawn by the GPU; `place` tells the GPU where the cursor
//! is and marks the voxels it catches and lets go.

use bevy::prelude::*;

/// Whether the cursor pulled a voxel last frame (so placing must go on without a cursor, to let it go).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct RepelActive(pub bool);
