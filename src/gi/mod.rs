//! The GI passes, one module per pass, each owning its pipeline and bind-group layout and driving the
//! WGSL file of the same name. `pipeline` decides which passes run.

pub mod budget;
pub mod cvrtgi;
pub mod direct;
pub mod dispatch;
pub mod frame;
pub mod kmeans;
pub mod lightcluster;
pub mod pathtrace;
pub mod pipeline;
pub mod primary;
pub mod raycast;
pub mod reference;
pub mod resident;
pub mod scene_gpu;
pub mod shade;
pub mod upsample;
pub mod visibility;
pub mod vpl_cluster;
pub mod vpl_trace;
pub mod wang;
