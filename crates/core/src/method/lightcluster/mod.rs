//! The `lightcluster` method (LightCluster, seed 002; docs/methods.md): the VPLs clustered by the
//! minimum-distance (leader) algorithm on the CPU each frame (§3.1; the paper's §4 runs it on the CPU
//! too, `cluster::cluster`), then every pixel × every VPL with the visibility of its cluster: by
//! default (not in the paper) each member group's terms count when a member drawn in proportion to
//! its term is visible, one ray a group, at most `MEMBER_TARGETS` a cluster; with
//! `--lightcluster-visibility disc` every VPL takes its cluster's disc's visibility from
//! `DISC_SAMPLES` shadow rays (§3.2) (`shaders-wgsl/lightcluster.wgsl`, CPU twin
//! `twin`). The passes are `CLUSTER` → `SHADE` (`ENTRY`).

pub mod cluster;
pub mod settings;
/// The CPU twin of this module's shader, for tests only: no production code calls it.
pub mod twin;

use std::time::Instant;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use self::cluster::LightClusters;
use self::settings::LcVisibility;
use super::Method;
use super::{FrameInputs, IndirectMethod, MethodEntry, PendingRays, Tally};
use crate::gi::dispatch::{Gpu, Kernel, Run};
use crate::gi::pass::Pass;
use crate::gi::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gi::sum::{Each, WordSum, Words};
use crate::gpu::GpuContext;

pub use settings::{LightClusterLists as Lists, LightClusterSettings as Settings};

/// §3.1: the VPLs clustered by the minimum-distance algorithm (CPU).
pub const CLUSTER: Pass = Pass::Method("lightcluster_cluster");
/// §3.2: every pixel × every VPL with its cluster's disc visibility.
pub const SHADE: Pass = Pass::Method("lightcluster_shade");

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LcParams {
    d_min2: f32,
    num_vpls: u32,
    /// 0: `members`, 1: `disc` (`LcVisibility`).
    mode: u32,
    _pad: u32,
}

/// The most sorted VPLs one invocation walks per dispatch: at most this many clusters'
/// `DISC_SAMPLES` rays (256), within lavapipe's loop budget (docs/architecture.md).
pub const VPLS_PER_DISPATCH: u32 = 32;

/// The kernel of `lightcluster.wgsl`, built the first time a frame uses it.
pub struct LightCluster {
    kernel: Kernel,
}

/// What §3.2's shading reads and writes.
pub struct ShadeInputs<'a> {
    pub gbuffer: &'a wgpu::Buffer,
    pub clusters: &'a LightClusters,
    /// vec4 a pixel, added to.
    pub indirect: &'a wgpu::Buffer,
    pub pixels: u32,
    /// The G-term clamp distance in the rendered scene's units.
    pub d_min: f32,
    /// What the shadow rays aim at.
    pub visibility: LcVisibility,
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
            storage_layout(7, false),
        ];
        LightCluster {
            kernel: Kernel::new(ctx, scene, "lightcluster", &entries, &[]),
        }
    }

    /// §3.2: adds every pixel's light from every VPL, shadowed as its cluster's visibility says
    /// (its member group's drawn member or its cluster's disc), to `indirect`. Returns the per-pixel state
    /// buffer (`lightcluster.wgsl`: 8 u32 a pixel, the third the shadow rays it traced; `None` when
    /// nothing ran).
    pub fn record(&self, g: &mut Gpu, i: &ShadeInputs) -> Option<wgpu::Buffer> {
        let c = i.clusters;
        let n = c.sorted.len() as u32;
        if n == 0 || i.pixels == 0 {
            return None;
        }
        let ctx = g.ctx;
        let params = LcParams {
            d_min2: i.d_min * i.d_min,
            num_vpls: n,
            mode: match i.visibility {
                LcVisibility::Members => 0,
                LcVisibility::Disc => 1,
            },
            _pad: 0,
        };
        let params = ctx.uniform("lightcluster params", &params);
        let vpls = ctx.storage_init("lightcluster vpls", &c.sorted);
        let cluster_of = ctx.storage_init("lightcluster cluster_of", &c.packed_groups());
        let discs: Vec<[[f32; 4]; 2]> = c.discs.iter().map(|d| d.to_gpu()).collect();
        let discs = ctx.storage_init("lightcluster discs", &discs);
        let state = ctx.storage("lightcluster state", i.pixels as u64 * 32);
        let buffers = [
            (1, &params),
            (2, i.gbuffer),
            (3, &vpls),
            (4, &cluster_of),
            (5, &discs),
            (6, i.indirect),
            (7, &state),
        ];
        let bg = self.kernel.bind_group(ctx, &buffers);
        let run = Run {
            label: SHADE.name(),
            group: &bg,
            seed: 0,
        };
        let pixels = (i.pixels, i.pixels.min(1 << 14));
        self.kernel
            .run_2d(g, run, pixels, (n, VPLS_PER_DISPATCH), &mut |_, _| true);
        Some(state)
    }
}

/// z_far of §3.1.2, the largest view distance: from `eye` to the farthest corner of the bounds.
pub fn z_far(eye: Vec3, (lo, hi): (Vec3, Vec3)) -> f32 {
    (0..8)
        .map(|i| {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            corner.distance(eye)
        })
        .fold(0.0f32, f32::max)
}

/// lightcluster in the registry.
pub const ENTRY: MethodEntry = MethodEntry {
    method: Method::LightCluster,
    doc: "LightCluster (Wiesenhütter, Klein, Nischwitz): the VPLs clustered by the minimum-distance (leader) algorithm \
          (§3.1, d_min = d_init (1 − |C_pos| / z_far)), each cluster a disc light of radius d_min \
          whose visibility a few shadow rays over the disc estimate (§3.2), every VPL shaded with \
          its cluster's visibility",
    passes: &[CLUSTER, SHADE],
    build: |ctx, gpu| Box::new(LightClusterMethod::new(ctx, gpu)),
    clusters_sps: false,
    vpl_clusters: |_| false,
    limits: super::no_limits,
    own_settings: true,
    colour: [23, 190, 207],
    about: "LightCluster: VPLs in minimum-distance clusters whose visibility a few rays estimate \
            (to member VPLs, or to the paper's disc); every VPL shaded (docs/methods.md)",
    label: |m| {
        let l = &m.lightcluster;
        match l.lightcluster_visibility {
            LcVisibility::Members => format!("d{}", l.d_init),
            LcVisibility::Disc => format!("d{} disc", l.d_init),
        }
    },
    series: |m| format!("d_init {}", m.lightcluster.d_init),
    short: |m| format!("d{}", m.lightcluster.d_init),
    report_columns: &[],
};

/// lightcluster's state: its kernel and the frame's clusters (from `CLUSTER` to `SHADE`).
pub struct LightClusterMethod {
    kernel: LightCluster,
    clusters: Option<LightClusters>,
    /// The pixels' rays summed on the GPU (the state's third word).
    rays: WordSum,
}

impl LightClusterMethod {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        LightClusterMethod {
            kernel: LightCluster::new(ctx, scene),
            clusters: None,
            rays: WordSum::new(ctx),
        }
    }
}

impl IndirectMethod for LightClusterMethod {
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) -> Result<()> {
        let extent = f.scene.extent();
        match pass {
            // §3.1: the VPLs clustered for this camera on the CPU, as the paper's §4 (its time is
            // the pass's); d_init is in scene diagonals.
            CLUSTER => {
                let t = Instant::now();
                let eye = f.cam.eye_point();
                let far = z_far(eye, f.scene.bounds());
                let c = cluster::cluster(
                    &f.vpls.set.vpls,
                    eye,
                    far,
                    f.method.lightcluster.d_init * extent,
                );
                n.cpu_ms.push((pass, t.elapsed().as_secs_f64() * 1e3));
                n.vpl_clusters_used = c.discs.len() as u32;
                self.clusters = Some(c);
            }
            // §3.2: every pixel × every VPL with its cluster's disc visibility.
            SHADE => {
                let inputs = ShadeInputs {
                    gbuffer: f.gbuffer,
                    clusters: self.clusters.as_ref().expect("lightcluster_cluster ran"),
                    indirect: f.indirect,
                    pixels: f.pixels(),
                    d_min: f.d_min,
                    visibility: f.method.lightcluster.lightcluster_visibility,
                };
                // The rays traced, as each pixel counted them: a disc's DISC_SAMPLES where one of
                // its cluster's terms is positive, once; one a member group where one of its
                // group's terms is positive. Summed on the GPU and read only on request.
                if let Some(state) = self.kernel.record(g, &inputs) {
                    let words = Words {
                        items: f.pixels(),
                        stride: 8,
                        word: 2,
                        each: Each::Value,
                    };
                    let sum = self.rays.record(g, SHADE.name(), &state, words);
                    n.pending = Some(std::sync::Arc::new(PendingRays(sum)));
                }
            }
            _ => unreachable!("{pass} is not lightcluster's"),
        }
        Ok(())
    }
}
