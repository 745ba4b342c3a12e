//! The unclustered reference (Eq. 5, `shaders-wgsl/reference.wgsl`): every shading point gathers every
//! VPL with its own shadow ray, in bounded dispatches over pixel ranges × VPL ranges. With VPL clusters
//! as the lights and no SP clustering it is also the paper's "VPLs only" mode (label `gather`).

use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::dispatch::{Gpu, Run};
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::settings::ClusterLight;

/// Shadow rays per submission: about a second of lavapipe work.
pub const RAYS_PER_SUBMISSION: u32 = 1 << 20;
/// The most VPLs one invocation gathers per dispatch (the sub range of `run_2d`).
pub const VPLS_PER_DISPATCH: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct RefParams {
    pub d_min2: f32,
    pub _pad: [u32; 3],
}

pub struct Reference {
    /// With the VPL-cluster lights' spread (`override CLUSTER_SPREAD`, the default; VPLs have none,
    /// so the reference is the same either way).
    kernel: Kernel,
    /// With point cluster lights (`--cluster-light point`), built the first time it gathers.
    point: std::cell::OnceCell<Kernel>,
}

/// What a gather reads and writes.
#[derive(Clone, Copy)]
pub struct GatherInputs<'a> {
    /// The shading points (`common/gbuffer.wgsl`).
    pub gbuffer: &'a wgpu::Buffer,
    /// The lights: VPLs (`reference`) or VPL-cluster representatives (`gather`).
    pub lights: &'a wgpu::Buffer,
    pub num_lights: u32,
    /// vec4 per pixel, added to.
    pub indirect: &'a wgpu::Buffer,
    pub pixels: u32,
    /// The G-term clamp distance in the rendered scene's units.
    pub d_min: f32,
    /// The profiler label: the pass's name.
    pub label: &'a str,
    /// How VPL-cluster lights reach a point (`--cluster-light`; VPLs are points either way).
    pub light: ClusterLight,
}

fn entries() -> [wgpu::BindGroupLayoutEntry; 4] {
    [
        uniform_layout(1),
        storage_layout(2, true),
        storage_layout(3, true),
        storage_layout(4, false),
    ]
}

impl Reference {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        Reference {
            kernel: Kernel::new(ctx, scene, "reference", &entries(), &[]),
            point: Default::default(),
        }
    }

    /// Adds the lights' light to `indirect` (vec4 per pixel, zeroed by the caller).
    pub fn record(
        &self,
        g: &mut Gpu,
        inputs: &GatherInputs,
        progress: &mut dyn FnMut(u64, u64) -> bool,
    ) {
        let GatherInputs {
            gbuffer,
            lights: vpls,
            num_lights: num_vpls,
            indirect,
            pixels,
            d_min,
            label,
            light,
        } = *inputs;
        if num_vpls == 0 || pixels == 0 {
            return;
        }
        let ctx = g.ctx;
        let params = ctx.uniform(
            "reference params",
            &RefParams {
                d_min2: d_min * d_min,
                _pad: [0; 3],
            },
        );
        let kernel = match light {
            ClusterLight::Spread => &self.kernel,
            ClusterLight::Point => self.point.get_or_init(|| {
                let spread_off = [("CLUSTER_SPREAD", 0.0)];
                Kernel::new(ctx, g.scene, "reference", &entries(), &spread_off)
            }),
        };
        let bg = kernel.bind_group(ctx, &[(1, &params), (2, gbuffer), (3, vpls), (4, indirect)]);
        let px_chunk = pixels.min(1 << 14);
        // At most VPLS_PER_DISPATCH shadow rays an invocation: lavapipe stops all loops of a SIMD
        // batch after 65,535 trips (docs/architecture.md), and a small image would otherwise give each pixel
        // thousands of VPLs per dispatch.
        let vpl_chunk = (RAYS_PER_SUBMISSION / px_chunk).clamp(1, num_vpls.min(VPLS_PER_DISPATCH));
        let run = Run {
            label,
            group: &bg,
            seed: 0,
        };
        kernel.run_2d(g, run, (pixels, px_chunk), (num_vpls, vpl_chunk), progress);
    }
}
