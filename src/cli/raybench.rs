//! `fuzzy-vpl raybench`: ray throughput of the WGSL traversal against obvhs on the CPU.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::gpu::GpuContext;
use crate::{export, scene};

#[derive(Args)]
pub struct RaybenchArgs {
    /// Scenes to measure.
    #[arg(default_values_t = ["builtin:cornell".to_string(), "builtin:conference".to_string()])]
    scenes: Vec<String>,
    #[arg(long, default_value_t = 640, value_parser = crate::settings::parse_side)]
    width: u32,
    #[arg(long, default_value_t = 480, value_parser = crate::settings::parse_side)]
    height: u32,
    /// Also write the rows as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

pub fn run(a: RaybenchArgs) -> Result<()> {
    if let Some(p) = &a.json {
        export::check_writable(p).map_err(crate::input::bad)?;
    }
    let ctx = GpuContext::new_headless()?;
    println!(
        "adapter: {}; CPU: {} threads (rayon)",
        ctx.adapter_name,
        rayon::current_num_threads()
    );
    println!(
        "{:<40} {:>8} {:>9} {:>9} {:>12} {:>12} {:>12} {:>7}",
        "scene", "rays", "triangles", "kind", "GPU Mray/s", "CPU BVH2", "CPU CWBVH", "GPU/CPU"
    );
    let mut rows = Vec::new();
    for spec in &a.scenes {
        let s = scene::load(spec)?;
        let cam = s.default_camera();
        for r in crate::raybench::run(&ctx, &s, &cam, a.width, a.height)? {
            println!(
                "{:<40} {:>8} {:>9} {:>9} {:>12.3} {:>12.3} {:>12.3} {:>7.2}",
                r.scene,
                r.rays,
                r.triangles,
                r.kind,
                r.gpu_mrays_s,
                r.cpu_bvh2_mrays_s,
                r.cpu_cwbvh_mrays_s,
                r.ratio
            );
            rows.push(r);
        }
    }
    if let Some(p) = &a.json {
        export::write_json(p, &rows)?;
    }
    Ok(())
}
