//! CPU twins of the GPU kernels' math, used by tests to check the shaders. Ray queries use obvhs' own
//! CPU traversal (`bvh::SceneBvh::closest` / `occluded`), which is also the traversal twin.

pub mod accumulate;
pub mod cvrtgi;
pub mod display;
pub mod grid;
pub mod kmeans;
pub mod lightcluster;
pub mod reproject;
pub mod restir;
pub mod shade;
pub mod shading;
pub mod upsample;
pub mod vpl;
pub mod wang;
