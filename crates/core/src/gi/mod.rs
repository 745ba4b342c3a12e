//! The shared GI passes, one module per pass, each owning its pipeline and bind-group layout and
//! driving the WGSL file of the same name: the scene on the GPU, VPLs (step 1) and their clustering
//! (step 2), primary rays (step 3), direct light, the unclustered gather (Eq. 5) and the k-means.
//! The methods' own passes are in their modules (`method`); `render::Plan` decides which passes run.

pub mod accumulate;
pub mod compose;
pub mod direct;
pub mod dispatch;
pub mod kmeans;
pub mod pass;
pub mod pathtrace;
pub mod primary;
pub mod raycast;
pub mod reference;
pub mod refine;
pub mod rng;
pub mod scene_gpu;
pub mod sum;
pub mod upsample;
pub mod vpl_cluster;
pub mod vpl_trace;
