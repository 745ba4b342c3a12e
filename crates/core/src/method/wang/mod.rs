//! The `wang` method (Wang et al. 2009, seed 001; docs/methods.md): the shading points clustered
//! by §3.2's adaptively seeded k-means with the Eq. (2) metric, the indirect irradiance gathered only
//! at each cluster's sample point (every light with its own shadow ray: `reference.wgsl`), §3.4's
//! R_j traced there, and every pixel interpolating from the sample points around it with §3.4's
//! weight. Shaders: `shaders-wgsl/wang_cluster.wgsl` (the clustering, `cluster`; its steps in
//! `shaders-wgsl/wang/`) and
//! `shaders-wgsl/wang.wgsl` (`radius`, `interp`); CPU twins `twin`.
//! The passes are `CLUSTER` → `GATHER` → `INTERP` (`ENTRY`).

pub mod cluster;
pub mod settings;
/// The CPU twin of this module's shaders, for tests only: no production code calls it.
pub mod twin;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use self::cluster::{ClusterParams, WangCluster, WangClustering};
use super::Method;
use super::{FrameInputs, IndirectMethod, MethodEntry, PendingReport, Resolved, Tally};
use crate::gi::dispatch::{Gpu, Kernel, Run, copy_to_texture, data_texture};
use crate::gi::pass::Pass;
use crate::gi::reference::GatherInputs;
use crate::gi::scene_gpu::{SceneGpu, data_texture_layout, storage_layout, uniform_layout};
use crate::gpu::GpuContext;

pub use settings::{WangLists as Lists, WangSettings as Settings};

/// §3.2: the adaptively seeded k-means of the SPs with Eq. (2), and the sample points.
pub const CLUSTER: Pass = Pass::Method("wang_cluster");
/// The irradiance at the sample points (every light with its own shadow ray) and §3.4's R_j.
pub const GATHER: Pass = Pass::Method("wang_gather");
/// §3.4: every pixel interpolates the sample points' irradiance.
pub const INTERP: Pass = Pass::Method("wang_interp");

/// Rays a sample point traces for its harmonic mean distance R_j (§3.4), two dispatches of 16.
pub const RADIUS_RAYS: u32 = 32;
/// Rays one invocation traces per dispatch (lavapipe's loop budget, docs/architecture.md).
pub const RADIUS_RAYS_PER_DISPATCH: u32 = 16;
/// R_j is at least this fraction of the scene diagonal (a sample in a corner whose rays all hit at
/// once would otherwise weigh nothing but itself) and at most the diagonal (every ray missed).
pub const RADIUS_MIN: f32 = 1e-3;

/// The stride of the interpolation's neighbourhood: about the spacing of K clusters over the pixels.
pub fn interp_stride(pixels: u32, k: u32) -> u32 {
    ((pixels as f32 / k.max(1) as f32).sqrt().round() as u32).max(1)
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub struct WangParams {
    pub width: u32,
    pub height: u32,
    pub stride: u32,
    pub _p: [u32; 2],
    pub seed: u32,
    pub r_min: f32,
    pub r_max: f32,
    pub rays: u32,
    pub _pad: [u32; 3],
}

/// A wang frame's clustering and what its gather left at the sample points (the last frame's is
/// `WangMethod::last`, for tests and views).
pub struct WangFrame {
    pub clustering: WangClustering,
    /// vec4 a sample point: its gathered irradiance times 1/π.
    pub irradiance: wgpu::Buffer,
    /// vec4 a sample point: x the summed 1/t of its R_j rays (`twin::radius_from_sum`).
    pub radius: wgpu::Buffer,
}

/// What wang's passes hand on within a frame.
#[derive(Default)]
struct WangState {
    clustering: Option<WangClustering>,
    frame: Option<WangFrame>,
}

/// The frame's shading points on the GPU and the image's size.
#[derive(Clone, Copy)]
pub struct Image<'a> {
    pub gbuffer: &'a wgpu::Buffer,
    pub width: u32,
    pub height: u32,
}

/// Group 1 of a wang kernel: the parameters, the storage bindings 2, 6, 7, 8 (`None`: a small
/// buffer of its own, as one buffer may not be bound both read-only and writable in one dispatch)
/// and the sources of the two data textures as (buffer, texels): the labels (binding 3, u32) and
/// the points (binding 5, two vec4 a cluster), copied into textures first.
struct Bindings<'a> {
    params: WangParams,
    buffers: [Option<&'a wgpu::Buffer>; 4],
    labels: Option<(&'a wgpu::Buffer, u32)>,
    points: Option<(&'a wgpu::Buffer, u32)>,
}

/// The kernels of `wang_cluster.wgsl` and `wang.wgsl`, built the first time a frame uses them.
pub struct Wang {
    cluster: WangCluster,
    radius: Kernel,
    interp: Kernel,
}

impl Wang {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            data_texture_layout(3, wgpu::TextureSampleType::Uint),
            data_texture_layout(5, wgpu::TextureSampleType::Float { filterable: false }),
            storage_layout(6, true),
            storage_layout(7, false),
            storage_layout(8, false),
        ];
        let k = |entry| Kernel::with_entries(ctx, Some(scene), "wang", &[entry], &entries, &[]);
        Wang {
            cluster: WangCluster::new(ctx),
            radius: k("radius"),
            interp: k("interp"),
        }
    }

    fn bind(&self, kernel: &Kernel, ctx: &GpuContext, b: &Bindings) -> wgpu::BindGroup {
        let p = ctx.uniform("wang params", &b.params);
        let dummies: Vec<wgpu::Buffer> = (0..4).map(|_| ctx.storage("wang unused", 16)).collect();
        let mut list: Vec<(u32, &wgpu::Buffer)> = vec![(1, &p)];
        for (i, buf) in b.buffers.iter().enumerate() {
            list.push(([2, 6, 7, 8][i], buf.unwrap_or(&dummies[i])));
        }
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let mut texture =
            |src: Option<(&wgpu::Buffer, u32)>, format: wgpu::TextureFormat, bytes| {
                let texels = src.map_or(1, |s| s.1.max(1)) as u64;
                let t = data_texture(ctx, "wang data", format, texels);
                if let Some((buf, n)) = src
                    && n > 0
                {
                    copy_to_texture(&mut enc, buf, &t, n as u64 * bytes);
                }
                t.create_view(&Default::default())
            };
        let lt = texture(b.labels, wgpu::TextureFormat::R32Uint, 4);
        let pt = texture(b.points, wgpu::TextureFormat::Rgba32Float, 16);
        ctx.queue.submit([enc.finish()]);
        kernel.bind_group_with_textures(ctx, &list, &[(3, &lt), (5, &pt)])
    }

    /// §3.4's R_j at every sample point: `RADIUS_RAYS` rays each, `RADIUS_RAYS_PER_DISPATCH` an
    /// invocation per dispatch. Returns the summed inverse distances (vec4 a sample, x).
    pub fn radius(&self, g: &mut Gpu, c: &WangClustering, seed: u32) -> wgpu::Buffer {
        let ctx = g.ctx;
        let k = c.k().max(1);
        let sums = ctx.storage("wang radius", k as u64 * 16);
        let bg = self.bind(
            &self.radius,
            ctx,
            &Bindings {
                params: WangParams {
                    seed,
                    ..Default::default()
                },
                buffers: [None, None, None, Some(&sums)],
                labels: None,
                points: Some((&c.samples, 2 * c.k())),
            },
        );
        let run = Run {
            label: GATHER.name(),
            group: &bg,
            seed: 0,
        };
        let rays = (RADIUS_RAYS, RADIUS_RAYS_PER_DISPATCH);
        self.radius
            .run_2d(g, run, (k, 1 << 14), rays, &mut |_, _| true);
        sums
    }

    /// §3.4's interpolation of `f`'s sample points into `indirect` (vec4 a pixel, written);
    /// `diagonal` bounds R_j (`twin::radius_from_sum`).
    pub fn interp(
        &self,
        g: &mut Gpu,
        img: Image,
        f: &WangFrame,
        diagonal: f32,
        indirect: &wgpu::Buffer,
    ) {
        let n = img.width * img.height;
        let c = &f.clustering;
        let bg = self.bind(
            &self.interp,
            g.ctx,
            &Bindings {
                params: WangParams {
                    width: img.width,
                    height: img.height,
                    stride: interp_stride(n, c.k()),
                    r_min: RADIUS_MIN * diagonal,
                    r_max: diagonal,
                    rays: RADIUS_RAYS,
                    ..Default::default()
                },
                buffers: [
                    Some(img.gbuffer),
                    Some(&f.irradiance),
                    Some(indirect),
                    Some(&f.radius),
                ],
                labels: Some((&c.labels, n)),
                points: Some((&c.samples, 2 * c.k())),
            },
        );
        let run = Run {
            label: INTERP.name(),
            group: &bg,
            seed: 0,
        };
        self.interp.run(g, run, n, 1 << 18, &mut |_, _| {});
    }
}

/// wang in the registry.
pub const ENTRY: MethodEntry = MethodEntry {
    method: Method::Wang,
    doc: "Wang et al. 2009: adaptively seeded k-means of the SPs (§3.2, Eq. 2), \
          irradiance gathered only at the cluster centres, interpolated per pixel with the §3.4 \
          weight",
    passes: &[CLUSTER, GATHER, INTERP],
    build: |ctx, gpu| Box::new(WangMethod::new(ctx, gpu)),
    clusters_sps: true,
    vpl_clusters: |_| true,
    limits: super::no_limits,
    own_settings: true,
    colour: [140, 86, 75],
    about: "Wang et al. 2009: irradiance only at the SP clusters' sample points, interpolated per \
            pixel (docs/methods.md)",
    label: |m| format!("a{}", m.wang.wang_alpha),
    series: |m| format!("α {}", m.wang.wang_alpha),
    short: |m| format!("a{}", m.wang.wang_alpha),
    report_columns: &[],
};

/// wang's state: its pipelines, what its passes hand on within a frame, and the last frame's
/// clustering, irradiance and R_j sums.
pub struct WangMethod {
    wang: Wang,
    state: WangState,
    pub last: Option<WangFrame>,
}

impl WangMethod {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        WangMethod {
            wang: Wang::new(ctx, scene),
            state: WangState::default(),
            last: None,
        }
    }
}

/// wang's counts left on the GPU: its clustering's clusters with a sample point, each of which
/// traced a ray to every light and `RADIUS_RAYS` more; read on request.
#[derive(Debug)]
struct PendingUsed {
    bounds: wgpu::Buffer,
    rays_per_cluster: u64,
}

impl PendingReport for PendingUsed {
    fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Resolved> {
        let used = cluster::used_of(device, queue, &self.bounds)?;
        Ok(Resolved {
            indirect_rays: used as u64 * self.rays_per_cluster,
            sp_used: Some(used),
            report: None,
        })
    }
}

impl IndirectMethod for WangMethod {
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) -> Result<()> {
        let ctx = g.ctx;
        let wang = &self.wang;
        let img = Image {
            gbuffer: f.gbuffer,
            width: f.size.0,
            height: f.size.1,
        };
        let extent = f.scene.extent();
        match pass {
            // §3.2: the SP clustering and its sample points.
            CLUSTER => {
                let c = f.cluster;
                let alpha = f.method.wang.wang_alpha / extent;
                let (w, h) = (img.width, img.height);
                let bounds = f.scene.bounds();
                let p = ClusterParams::new(w, h, c.sp_clusters, alpha, f.frame.seed, bounds);
                let w = wang.cluster.run(g, img, &p, c.iterations)?;
                self.state.clustering = Some(w);
            }
            // The irradiance at the sample points (every light with its own shadow ray: the gather
            // of `reference.wgsl` on shading points of albedo 1) and §3.4's R_j there.
            GATHER => {
                let c = self.state.clustering.take().expect("wang_cluster ran");
                let lights = &f.lights.expect("wang's lights").list;
                let num_lights = lights.lights.len() as u32;
                let irradiance = ctx.storage("wang irradiance", c.k().max(1) as u64 * 16);
                f.reference.record(
                    g,
                    &GatherInputs {
                        gbuffer: &c.sample_gbuffer,
                        lights: &lights.buffer,
                        num_lights,
                        indirect: &irradiance,
                        pixels: c.k(),
                        d_min: f.d_min,
                        label: pass.name(),
                        light: f.cluster.cluster_light,
                    },
                    &mut |_, _| true,
                );
                let radius = wang.radius(g, &c, f.frame.seed);
                // The clusters used and the rays their sample points traced stay on the GPU.
                n.pending = Some(std::sync::Arc::new(PendingUsed {
                    bounds: c.bounds.clone(),
                    rays_per_cluster: (num_lights + RADIUS_RAYS) as u64,
                }));
                self.state.frame = Some(WangFrame {
                    clustering: c,
                    irradiance,
                    radius,
                });
            }
            // §3.4: every pixel interpolates the sample points' irradiance; the frame's clustering
            // stays as `last`.
            INTERP => {
                let w = self.state.frame.take().expect("wang_gather ran");
                wang.interp(g, img, &w, extent, f.indirect);
                self.last = Some(w);
            }
            _ => unreachable!("{pass} is not wang's"),
        }
        Ok(())
    }
}
