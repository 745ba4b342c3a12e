//! The `lightcluster` method (LightCluster, seed 002; docs/methods.md): the VPLs clustered by the
//! minimum-distance (leader) algorithm on the CPU each frame (§3.1; the paper's §4 runs it on the CPU
//! too, `cpu::lightcluster::cluster`), then every pixel × every VPL with the visibility of its
//! cluster's disc from `DISC_SAMPLES` shadow rays (§3.2; `shaders-wgsl/lightcluster.wgsl`).

use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::dispatch::Kernel;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::cpu::lightcluster::{self as twin, LightClusters};
use crate::gi::vpl_trace::Vpl;
use crate::gpu::{GpuContext, profiler::Profiler};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LcParams {
    d_min2: f32,
    num_vpls: u32,
    _pad: [u32; 2],
}

/// The most sorted VPLs one invocation walks per dispatch: at most this many clusters'
/// `DISC_SAMPLES` rays (256), within lavapipe's loop budget (docs/architecture.md).
pub const VPLS_PER_DISPATCH: u32 = 32;

pub struct LightCluster {
    kernel: Kernel,
}

impl LightCluster {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, true),
            storage_layout(4, true),
            storage_layout(5, true),
            storage_layout(6, false),
        ];
        LightCluster {
            kernel: Kernel::new(ctx, scene, "lightcluster", &entries, &[]),
        }
    }

    /// §3.1 on the CPU: the clusters of `vpls` for a camera at `eye` seeing as far as `z_far`
    /// (`d_init` in the scene's units), and the milliseconds it took.
    pub fn cluster(vpls: &[Vpl], eye: Vec3, z_far: f32, d_init: f32) -> (LightClusters, f64) {
        let t = Instant::now();
        let c = twin::cluster(vpls, eye, z_far, d_init);
        (c, t.elapsed().as_secs_f64() * 1e3)
    }

    /// §3.2: adds every pixel's light from every VPL, shadowed by its cluster's disc, to `indirect`
    /// (vec4 a pixel, zeroed by the caller).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        label: &str,
        gbuffer: &wgpu::Buffer,
        c: &LightClusters,
        indirect: &wgpu::Buffer,
        pixels: u32,
        d_min: f32,
    ) {
        let n = c.sorted.len() as u32;
        if n == 0 || pixels == 0 {
            return;
        }
        let params = ctx.uniform(
            "lightcluster params",
            &LcParams {
                d_min2: d_min * d_min,
                num_vpls: n,
                _pad: [0; 2],
            },
        );
        let vpls = ctx.storage_init("lightcluster vpls", &c.sorted);
        let cluster_of = ctx.storage_init("lightcluster cluster_of", &c.cluster_of);
        let discs: Vec<[[f32; 4]; 2]> = c.discs.iter().map(|d| d.to_gpu()).collect();
        let discs = ctx.storage_init("lightcluster discs", &discs);
        let bg = self.kernel.bind_group(
            ctx,
            &[
                (1, &params),
                (2, gbuffer),
                (3, &vpls),
                (4, &cluster_of),
                (5, &discs),
                (6, indirect),
            ],
        );
        let px_chunk = pixels.min(1 << 14);
        self.kernel.run_2d(
            ctx,
            profiler,
            label,
            scene,
            &bg,
            (pixels, px_chunk),
            (n, VPLS_PER_DISPATCH),
            0,
            &mut |_, _| true,
        );
    }
}
