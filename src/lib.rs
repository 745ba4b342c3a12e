//! fuzzy-vpl: interactive VPL global illumination with fuzzy k-means clustering of shading points and
//! VPLs (Colom, Marques, Santos 2022), on wgpu with a software BVH traversal shader.
//!
//! Data flows one way: scene → BVH → VPLs → clusters → frame → image.

pub mod app;
pub mod bench;
pub mod bvh;
pub mod cli;
pub mod cpu;
pub mod export;
pub mod exposure;
pub mod gi;
pub mod gpu;
pub mod method;
pub mod metrics;
pub mod panic_guard;
pub mod raybench;
pub mod render;
pub mod scene;
pub mod settings;
pub mod stats;
