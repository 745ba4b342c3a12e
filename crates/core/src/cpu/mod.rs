//! CPU twins of the GPU kernels' math, used by tests to check the shaders: here those of the shared
//! passes and those several modules use; a method's own twin lives in its module (`method::<name>::twin`).
//! Ray queries use obvhs' own CPU traversal (`bvh::SceneBvh::closest` / `occluded`), which is also
//! the traversal twin.

pub mod accumulate;
pub mod grid;
pub mod kmeans;
pub mod reproject;
pub mod shade;
pub mod shading;
pub mod upsample;
pub mod vpl;
