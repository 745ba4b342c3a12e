//! fuzzy-vpl's core: interactive VPL global illumination with fuzzy k-means clustering of shading points and
//! VPLs (Colom, Marques, Santos 2022), on wgpu with a software BVH traversal shader.
//!
//! Data flows one way: scene → BVH → VPLs → clusters → frame → image.
//!
//! # As a library
//!
//! Another wgpu program renders fuzzy-vpl's GI into a texture of its own device:
//!
//! ```no_run
//! use fuzzy_vpl_core::{GpuContext, RenderSettings, Renderer};
//! # fn host(instance: wgpu::Instance, adapter: wgpu::Adapter, device: wgpu::Device,
//! #         queue: wgpu::Queue, texture: &wgpu::Texture) -> anyhow::Result<()> {
//! // The host's device, requested with `gpu::required_limits` and `gpu::wanted_features()`.
//! let ctx = GpuContext::from_device(instance, adapter, device, queue)?;
//! let scene = fuzzy_vpl_core::scene::load("builtin:cornell")?;
//! let mut renderer = Renderer::new(&ctx, &scene)?;
//! let settings = RenderSettings::default(); // 640×480, 8192 VPLs, the paper's fuzzy clustering
//! // `texture`: Rgba32Float, 640×480, STORAGE_BINDING (or COPY_DST). Written on the GPU.
//! let frame = renderer.render_to_texture(&scene.default_camera(), &settings, texture)?;
//! println!("{:.1} ms", frame.meta.frame_ms());
//! // The images stay on the GPU; read them only when needed:
//! let on_cpu = frame.read(&ctx)?;
//! println!("{} pixels", on_cpu.radiance.len());
//! # Ok(()) }
//! ```
//!
//! `examples/embed.rs` does this end to end with its own headless device and writes a PNG
//! (`cargo run --release -p fuzzy-vpl-core --example embed`): it compiles this crate alone, with
//! no window, UI or command-line crate.
//!
//! The layers, bottom up: `settings`, `scene`, `bvh`, `gpu`; the shared passes (`gi`: VPLs,
//! primary rays, direct light, the unclustered gather, the paper's clustering, visibility and shading);
//! the methods (`method`); the frame (`render`); the metrics and the stats. The application crate
//! (`fuzzy-vpl`: `bench`, `app` (the viewer) and `cli`) is built on them. `cpu` holds the CPU twins
//! the tests check the shaders against. With the feature `cli`, the settings types are also clap
//! `Args` (the application's command line).

// First, so that the crate's `eprintln!` and `eprint!` are these macros, which never panic on a
// full or closed stream.
#[macro_use]
pub mod stdio;

pub mod bvh;
pub mod cpu;
pub mod export;
pub mod exposure;
pub mod files;
pub mod gi;
pub mod gpu;
pub mod input;
pub mod method;
pub mod metrics;
pub mod panic_guard;
pub mod raybench;
pub mod render;
pub mod scene;
pub mod settings;
pub mod stats;
#[cfg(test)]
mod test_rng;

pub use gpu::GpuContext;
pub use method::{Method, MethodSettings};
pub use render::{Frame, GpuFrame, RenderSettings, Renderer};
pub use scene::{Camera, Scene};
pub use settings::{ClusterSettings, FrameSettings, Weighting};
