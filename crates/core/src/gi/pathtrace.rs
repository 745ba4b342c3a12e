//! A diffuse GPU path tracer over the same BVH and materials (`shaders-wgsl/pathtrace.wgsl`), used to
//! measure the VPL reference's own bias (docs/reference.md). Progressive: each dispatch adds samples.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::dispatch::{Gpu, Run};
use super::pass::Pass;
use super::primary::CameraParams;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::GpuContext;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PtParams {
    width: u32,
    height: u32,
    max_vertices: u32,
    spp: u32,
    eye: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
}

/// Samples a pixel, and how many an invocation traces per pass.
#[derive(Clone, Copy, Debug)]
pub struct PtSamples {
    pub spp: u32,
    pub per_pass: u32,
}

pub struct PathTrace {
    kernel: Kernel,
}

impl PathTrace {
    /// The path tracer with next-event estimation (the check of the VPL reference).
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        Self::with_nee(ctx, scene, true)
    }

    /// `nee: false` samples light only by bouncing into emitters: slow to converge but independent of
    /// the light sampling it tests.
    pub fn with_nee(ctx: &GpuContext, scene: &SceneGpu, nee: bool) -> Self {
        let entries = [uniform_layout(1), storage_layout(2, false)];
        PathTrace {
            kernel: Kernel::new(
                ctx,
                scene,
                "pathtrace",
                &entries,
                &[("NEE", nee as u32 as f64)],
            ),
        }
    }

    /// Renders `samples.spp` samples per pixel (in passes of `samples.per_pass`) and returns the mean
    /// radiance.
    /// Paths have at most `bounces + 1` surface vertices: the light transport the VPLs carry (a VPL
    /// path has at most `bounces` reflections before the shading point's own).
    pub fn render(
        &self,
        g: &mut Gpu,
        cam: &CameraParams,
        samples: PtSamples,
        seed: u32,
        bounces: u32,
    ) -> Result<Vec<[f32; 3]>> {
        let ctx = g.ctx;
        let PtSamples {
            spp,
            per_pass: spp_per_pass,
        } = samples;
        let (w, h) = (cam.size[0], cam.size[1]);
        let n = w * h;
        let accum = ctx.storage("pt accum", n as u64 * 16);
        let mut done = 0;
        let mut pass = 0;
        while done < spp {
            let k = spp_per_pass.min(spp - done).max(1);
            let params = ctx.uniform(
                "pt params",
                &PtParams {
                    width: w,
                    height: h,
                    max_vertices: bounces + 1,
                    spp: k,
                    eye: cam.eye,
                    right: cam.right,
                    up: cam.up,
                    forward: cam.forward,
                },
            );
            let bg = self.kernel.bind_group(ctx, &[(1, &params), (2, &accum)]);
            let per = ((1u32 << 18) / k).max(64);
            let run = Run {
                label: Pass::PathTrace.name(),
                group: &bg,
                seed: seed.wrapping_mul(7919).wrapping_add(pass),
            };
            self.kernel.run(g, run, n, per, &mut |_, _| {});
            done += k;
            pass += 1;
        }
        let acc: Vec<[f32; 4]> = ctx.read_buffer(&accum, n as usize)?;
        Ok(acc
            .iter()
            .map(|a| {
                let c = a[3].max(1.0);
                [a[0] / c, a[1] / c, a[2] / c]
            })
            .collect())
    }
}
