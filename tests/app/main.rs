//! Integration tests of the voxel-art binary and app (one test binary).

mod ambiguity;
mod animation;
mod big;
mod cli;
mod common;
mod export;
mod flight;
mod harness;
mod logic;
mod modules;
mod palette;
mod render;
mod slider;
mod styles;
mod transition;
