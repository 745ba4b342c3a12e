//! Ray throughput: the WGSL traversal (GPU timestamps) against obvhs' CPU traversal on all cores
//! (rayon, wall clock), on the same rays in the same process. Also times obvhs' CWBVH on the CPU, the
//! measurement behind choosing BVH2 for the shader (docs/bvh.md).

use std::time::{Duration, Instant};

use anyhow::Result;
use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::builder::build_cwbvh_from_tris,
    ray::{Ray, RayHit},
};
use rayon::prelude::*;

use crate::bvh::SceneBvh;
use crate::gi::primary::CameraParams;
use crate::gi::raycast::{GpuRay, Raycast};
use crate::gi::rng::{rng_next, rng_seed};
use crate::gi::scene_gpu::SceneGpu;
use crate::gpu::{GpuContext, profiler::Profiler};
use crate::scene::{Camera, Scene};

#[derive(Clone, Debug, serde::Serialize)]
pub struct RayBenchRow {
    pub scene: String,
    pub kind: &'static str,
    pub triangles: usize,
    pub rays: usize,
    pub gpu_mrays_s: f64,
    pub cpu_bvh2_mrays_s: f64,
    pub cpu_cwbvh_mrays_s: f64,
    /// GPU ÷ CPU (BVH2), the figure the foundation issue targets (≥ 0.5 on lavapipe).
    pub ratio: f64,
}

/// Primary rays through every pixel centre.
pub fn primary_rays(cam: &Camera, w: u32, h: u32) -> Vec<GpuRay> {
    let c = CameraParams::new(cam, w, h);
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    (0..w * h)
        .map(|i| {
            let sx = 2.0 * ((i % w) as f32 + 0.5) / w as f32 - 1.0;
            let sy = 1.0 - 2.0 * ((i / w) as f32 + 0.5) / h as f32;
            let d = (v(c.forward) + sx * v(c.right) + sy * v(c.up)).normalize();
            GpuRay {
                o: c.eye,
                d: [d.x, d.y, d.z, f32::MAX],
            }
        })
        .collect()
}

/// Incoherent shadow rays: from each primary hit towards a random point on a random triangle.
pub fn shadow_rays(scene: &Scene, bvh: &SceneBvh, primary: &[GpuRay]) -> Vec<GpuRay> {
    let eps = 1e-5 * scene.extent();
    primary
        .par_iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let o = Vec3::new(r.o[0], r.o[1], r.o[2]);
            let d = Vec3::new(r.d[0], r.d[1], r.d[2]);
            let hit = bvh.closest(o.into(), d.into(), 0.0, f32::MAX)?;
            let tri = &scene.triangles[hit.triangle as usize];
            let mut n = tri.geometric_normal();
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let p = o + d * hit.t + n * (eps + 4e-6 * (o + d * hit.t).abs().max_element());
            let mut s = rng_seed(i as u32, 0xb5297a4d, 17);
            let t = &scene.triangles[(rng_next(&mut s) * scene.triangles.len() as f32) as usize
                % scene.triangles.len()];
            let (u1, u2) = (rng_next(&mut s).sqrt(), rng_next(&mut s));
            let q = t.p[0] * (1.0 - u1) + t.p[1] * (u1 * (1.0 - u2)) + t.p[2] * (u1 * u2);
            let to = q - p;
            let dist = to.length();
            (dist > 0.0).then(|| {
                let dir = to / dist;
                GpuRay {
                    o: [p.x, p.y, p.z, 0.0],
                    d: [dir.x, dir.y, dir.z, dist * (1.0 - 1e-4)],
                }
            })
        })
        .collect()
}

fn best_of(n: usize, mut f: impl FnMut() -> Result<Duration>) -> Result<Duration> {
    let mut best = Duration::MAX;
    for _ in 0..n {
        best = best.min(f()?);
    }
    Ok(best)
}

fn mrays(n: usize, d: Duration) -> f64 {
    n as f64 / d.as_secs_f64().max(1e-12) / 1e6
}

/// Times both kinds of rays for one scene.
pub fn run(
    ctx: &GpuContext,
    scene: &Scene,
    cam: &Camera,
    w: u32,
    h: u32,
) -> Result<Vec<RayBenchRow>> {
    let bvh = SceneBvh::build(scene)?;
    let otris: Vec<obvhs::triangle::Triangle> = scene
        .triangles
        .iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: t.p[0].into(),
            v1: t.p[1].into(),
            v2: t.p[2].into(),
        })
        .collect();
    let mut core = Duration::ZERO;
    let cw = build_cwbvh_from_tris(&otris, BvhBuildParams::medium_build(), &mut core);
    let cw_tris: Vec<_> = cw
        .primitive_indices
        .iter()
        .map(|&i| otris[i as usize])
        .collect();
    let gpu = SceneGpu::upload(ctx, scene, &bvh);
    let rc = Raycast::new(ctx, &gpu);
    let mut prof = Profiler::new(ctx);
    let primary = primary_rays(cam, w, h);
    let shadow = shadow_rays(scene, &bvh, &primary);
    let mut rows = Vec::new();
    for (kind, rays) in [("primary", &primary), ("shadow", &shadow)] {
        let any = kind == "shadow";
        let gpu_t = best_of(3, || {
            if any {
                rc.occluded(ctx, &gpu, &mut prof, rays)?;
            } else {
                rc.closest(ctx, &gpu, &mut prof, rays)?;
            }
            let ms: f64 = prof.collect(ctx)?.values().sum();
            Ok(Duration::from_secs_f64(ms / 1e3))
        })?;
        let to_ray = |r: &GpuRay| {
            Ray::new(
                Vec3A::new(r.o[0], r.o[1], r.o[2]),
                Vec3A::new(r.d[0], r.d[1], r.d[2]),
                r.o[3],
                r.d[3],
            )
        };
        // Wall time of all rays on every CPU core, best of 3.
        let on_cpu = |trace: &(dyn Fn(Ray) -> usize + Sync)| {
            best_of(3, || {
                let t0 = Instant::now();
                let n: usize = rays.par_iter().map(|r| trace(to_ray(r))).sum();
                std::hint::black_box(n);
                Ok(t0.elapsed())
            })
        };
        let cpu_t = on_cpu(&|ray| {
            if any {
                bvh.occluded_obvhs(ray.origin, ray.direction, ray.tmin, ray.tmax) as usize
            } else {
                bvh.closest_obvhs(ray.origin, ray.direction, ray.tmin, ray.tmax)
                    .is_some() as usize
            }
        })?;
        let cw_t = on_cpu(&|ray| {
            if any {
                !cw.ray_traverse_miss(ray, |r, i| cw_tris[i].intersect(r)) as usize
            } else {
                let mut hit = RayHit::none();
                cw.ray_traverse(ray, &mut hit, |r, i| cw_tris[i].intersect(r)) as usize
            }
        })?;
        let g = mrays(rays.len(), gpu_t);
        let c = mrays(rays.len(), cpu_t);
        rows.push(RayBenchRow {
            scene: scene.name.clone(),
            kind,
            triangles: scene.triangles.len(),
            rays: rays.len(),
            gpu_mrays_s: g,
            cpu_bvh2_mrays_s: c,
            cpu_cwbvh_mrays_s: mrays(rays.len(), cw_t),
            ratio: g / c,
        });
    }
    Ok(rows)
}
