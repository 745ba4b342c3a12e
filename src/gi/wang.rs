//! The `wang` method (Wang et al. 2009, seed 001; docs/methods.md): the shading points clustered
//! by §3.2's adaptively seeded k-means with the Eq. (2) metric, the indirect irradiance gathered only
//! at each cluster's sample point (every VPL cluster with its own shadow ray: `reference.wgsl`),
//! §3.4's R_j traced there, and every pixel interpolating from the sample points around it with
//! §3.4's weight. Shaders: `shaders-wgsl/wang.wgsl` (`assign`, `radius`, `interp`); the CPU twin
//! and the CPU steps (seeding, centre updates, sample points) are `cpu::wang`.

use std::time::Instant;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::dispatch::{Kernel, copy_to_texture, data_texture};
use super::scene_gpu::{SceneGpu, data_texture_layout, storage_layout, uniform_layout};
use crate::cpu::shading::ShadingPoint;
use crate::cpu::wang as twin;
use crate::gpu::{GpuContext, profiler::Profiler};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub struct WangParams {
    pub width: u32,
    pub height: u32,
    pub k: u32,
    pub stride: u32,
    pub alpha: f32,
    pub seed: u32,
    pub r_min: f32,
    pub r_max: f32,
    pub rays: u32,
    pub step: u32,
    pub _pad: [u32; 2],
}

/// A frame's clustering: the labels on the GPU, the sample points, and what the CPU steps took.
pub struct WangClustering {
    pub clusters: twin::WangClusters,
    /// Per pixel its cluster (u32, `INVALID` for none).
    pub labels: wgpu::Buffer,
    /// Per cluster two vec4: the sample point (position, w = 1 when the cluster has one; normal).
    pub samples: wgpu::Buffer,
    /// The sample points as shading points of albedo 1 (what the gather reads).
    pub sample_gbuffer: wgpu::Buffer,
    /// Clusters with a sample point.
    pub used: u32,
    /// Milliseconds of the CPU steps (G-buffer read-back, seeding, centre updates, sample points),
    /// added to the pass's GPU time.
    pub cpu_ms: f64,
}

impl WangClustering {
    pub fn k(&self) -> u32 {
        self.clusters.centers.len() as u32
    }
}

/// The last wang frame's clustering and what its gather left at the sample points (for tests and
/// views).
pub struct WangFrame {
    pub clustering: WangClustering,
    /// vec4 a sample point: its gathered irradiance times 1/π.
    pub irradiance: wgpu::Buffer,
    /// vec4 a sample point: x the summed 1/t of its R_j rays (`cpu::wang::radius_from_sum`).
    pub radius: wgpu::Buffer,
}

pub struct Wang {
    assign: Kernel,
    radius: Kernel,
    interp: Kernel,
}

fn entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    vec![
        uniform_layout(1),
        storage_layout(2, true),
        data_texture_layout(3, wgpu::TextureSampleType::Uint),
        storage_layout(4, false),
        data_texture_layout(5, wgpu::TextureSampleType::Float { filterable: false }),
        storage_layout(6, true),
        storage_layout(7, false),
        storage_layout(8, false),
    ]
}

impl Wang {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let k = |entry| Kernel::with_entries(ctx, Some(scene), "wang", &[entry], &entries(), &[]);
        Wang {
            assign: k("assign"),
            radius: k("radius"),
            interp: k("interp"),
        }
    }

    /// Group 1 of `kernel`: `buffers` for the storage bindings 2, 4, 6, 7, 8 and the sources of
    /// the two data textures, (buffer, texels): the labels (binding 3, u32) and the points
    /// (binding 5, two vec4 a cluster), copied into textures first. A binding the entry point does not
    /// use gets its own small buffer or texture (one buffer may not be bound both read-only and
    /// writable in one dispatch).
    fn bind(
        &self,
        kernel: &Kernel,
        ctx: &GpuContext,
        params: &WangParams,
        buffers: [Option<&wgpu::Buffer>; 5],
        labels: Option<(&wgpu::Buffer, u32)>,
        points: Option<(&wgpu::Buffer, u32)>,
    ) -> wgpu::BindGroup {
        let p = ctx.uniform("wang params", params);
        let dummies: Vec<wgpu::Buffer> = (0..5).map(|_| ctx.storage("wang unused", 16)).collect();
        let mut list: Vec<(u32, &wgpu::Buffer)> = vec![(1, &p)];
        for (i, b) in buffers.iter().enumerate() {
            list.push(([2, 4, 6, 7, 8][i], b.unwrap_or(&dummies[i])));
        }
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let mut texture =
            |src: Option<(&wgpu::Buffer, u32)>, format: wgpu::TextureFormat, bytes| {
                let texels = src.map_or(1, |s| s.1.max(1)) as u64;
                let t = data_texture(ctx, "wang data", format, texels);
                if let Some((b, n)) = src
                    && n > 0
                {
                    copy_to_texture(&mut enc, b, &t, n as u64 * bytes);
                }
                t.create_view(&Default::default())
            };
        let lt = texture(labels, wgpu::TextureFormat::R32Uint, 4);
        let pt = texture(points, wgpu::TextureFormat::Rgba32Float, 16);
        ctx.queue.submit([enc.finish()]);
        kernel.bind_group_with_textures(ctx, &list, &[(3, &lt), (5, &pt)])
    }

    /// Assignment passes (`assign`) on the GPU, one per stride in order, with the same centres:
    /// `labels` in, the labels after the last pass out (read back once). The passes ping-pong
    /// between two label buffers.
    #[allow(clippy::too_many_arguments)]
    pub fn assign_passes(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        label: &str,
        gbuffer: &wgpu::Buffer,
        (width, height): (u32, u32),
        labels: &[u32],
        centers: &[twin::Center],
        strides: &[u32],
        step: u32,
        alpha: f32,
    ) -> Result<Vec<u32>> {
        let n = width * height;
        // Both start as `labels`: a pass writes the grid's pixels only, the others keep theirs.
        let mut a = ctx.storage_init("wang labels a", labels);
        let mut b = ctx.storage_init("wang labels b", labels);
        let g = step.max(1);
        let items = width.div_ceil(g) * height.div_ceil(g);
        let pts: Vec<[[f32; 4]; 2]> = centers.iter().map(|c| c.to_gpu()).collect();
        let pts = ctx.storage_init("wang centres", &pts_or_one(&pts));
        for &stride in strides {
            let params = WangParams {
                width,
                height,
                k: centers.len() as u32,
                stride,
                alpha,
                step: g,
                ..Default::default()
            };
            let bg = self.bind(
                &self.assign,
                ctx,
                &params,
                [Some(gbuffer), Some(&b), None, None, None],
                Some((&a, n)),
                Some((&pts, 2 * centers.len() as u32)),
            );
            self.assign.run(
                ctx,
                profiler,
                label,
                scene,
                &bg,
                items,
                1 << 18,
                0,
                &mut |_, _| {},
            );
            std::mem::swap(&mut a, &mut b);
        }
        ctx.read_buffer(&a, n as usize)
    }

    /// §3.2: the clustering of the frame's shading points into `k` clusters, the GPU doing the
    /// assignment passes and the CPU the rest (`cpu::wang::cluster`); `alpha` is α per unit of length.
    #[allow(clippy::too_many_arguments)]
    pub fn cluster(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        label: &str,
        gbuffer: &wgpu::Buffer,
        (width, height): (u32, u32),
        k: u32,
        alpha: f32,
        iterations: u32,
        seed: u32,
    ) -> Result<WangClustering> {
        let n = width * height;
        let mut cpu = std::time::Duration::ZERO;
        let t = Instant::now();
        let raw: Vec<[f32; 4]> = ctx.read_buffer(gbuffer, n as usize * 4)?;
        let sps: Vec<ShadingPoint> = raw.chunks(4).map(ShadingPoint::from_gpu).collect();
        cpu += t.elapsed();
        let mut clock = Instant::now();
        let clusters = twin::cluster(
            width,
            height,
            &sps,
            k,
            alpha,
            iterations,
            seed,
            &mut |labels, centers, strides, step| {
                cpu += clock.elapsed();
                let out = self.assign_passes(
                    ctx,
                    scene,
                    profiler,
                    label,
                    gbuffer,
                    (width, height),
                    labels,
                    centers,
                    strides,
                    step,
                    alpha,
                );
                clock = Instant::now();
                out
            },
        )?;
        let t = Instant::now();
        let samples = twin::sample_to_gpu(&sps, &clusters.samples);
        let sample_gbuffer = twin::sample_gbuffer(&sps, &clusters.samples);
        let used = clusters
            .samples
            .iter()
            .filter(|&&s| s != twin::INVALID)
            .count() as u32;
        let out = WangClustering {
            labels: ctx.storage_init("wang labels", &labels_or_one(&clusters.labels)),
            samples: ctx.storage_init("wang samples", &pts_or_one(&samples)),
            sample_gbuffer: ctx.storage_init("wang sample gbuffer", &gbuf_or_one(&sample_gbuffer)),
            used,
            cpu_ms: 0.0,
            clusters,
        };
        cpu += clock.elapsed() + t.elapsed();
        Ok(WangClustering {
            cpu_ms: cpu.as_secs_f64() * 1e3,
            ..out
        })
    }

    /// §3.4's R_j at every sample point: `RADIUS_RAYS` rays each, `RADIUS_RAYS_PER_DISPATCH` an
    /// invocation per dispatch. Returns the summed inverse distances (vec4 a sample, x).
    pub fn radius(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        label: &str,
        c: &WangClustering,
        seed: u32,
    ) -> wgpu::Buffer {
        let k = c.k().max(1);
        let sums = ctx.storage("wang radius", k as u64 * 16);
        let params = WangParams {
            k,
            seed,
            ..Default::default()
        };
        let bg = self.bind(
            &self.radius,
            ctx,
            &params,
            [None, None, None, None, Some(&sums)],
            None,
            Some((&c.samples, 2 * c.k())),
        );
        self.radius.run_2d(
            ctx,
            profiler,
            label,
            scene,
            &bg,
            (k, 1 << 14),
            (twin::RADIUS_RAYS, twin::RADIUS_RAYS_PER_DISPATCH),
            0,
            &mut |_, _| true,
        );
        sums
    }

    /// §3.4's interpolation into `indirect` (vec4 a pixel, written).
    #[allow(clippy::too_many_arguments)]
    pub fn interp(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        label: &str,
        gbuffer: &wgpu::Buffer,
        (width, height): (u32, u32),
        c: &WangClustering,
        irradiance: &wgpu::Buffer,
        radius: &wgpu::Buffer,
        diagonal: f32,
        indirect: &wgpu::Buffer,
    ) {
        let n = width * height;
        let params = WangParams {
            width,
            height,
            k: c.k(),
            stride: twin::interp_stride(n, c.k()),
            r_min: twin::RADIUS_MIN * diagonal,
            r_max: diagonal,
            rays: twin::RADIUS_RAYS,
            ..Default::default()
        };
        let bg = self.bind(
            &self.interp,
            ctx,
            &params,
            [
                Some(gbuffer),
                None,
                Some(irradiance),
                Some(indirect),
                Some(radius),
            ],
            Some((&c.labels, n)),
            Some((&c.samples, 2 * c.k())),
        );
        self.interp.run(
            ctx,
            profiler,
            label,
            scene,
            &bg,
            n,
            1 << 18,
            0,
            &mut |_, _| {},
        );
    }
}

/// A storage buffer may not be empty: at least one element.
fn pts_or_one(v: &[[[f32; 4]; 2]]) -> Vec<[[f32; 4]; 2]> {
    if v.is_empty() {
        vec![[[0.0; 4]; 2]]
    } else {
        v.to_vec()
    }
}

fn gbuf_or_one(v: &[[[f32; 4]; 4]]) -> Vec<[[f32; 4]; 4]> {
    if v.is_empty() {
        vec![[[0.0; 4]; 4]]
    } else {
        v.to_vec()
    }
}

fn labels_or_one(v: &[u32]) -> Vec<u32> {
    if v.is_empty() {
        vec![twin::INVALID]
    } else {
        v.to_vec()
    }
}
