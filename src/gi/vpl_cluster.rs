//! Step 2: VPL clustering (Alg. 1 with F = 1 on the VPLs' positions and normals) and the light list
//! the frame uses: per cluster its representative VPL (a member, on a real surface) carrying the
//! summed flux of all members. Resident: rebuilt only when the VPLs or K change.

use anyhow::Result;
use glam::Vec3;

use super::dispatch::Gpu;
use super::kmeans::Points;
use super::kmeans::{Clustering, KMeans, KMeansSettings, Warm};
use super::pass::Pass;
use super::vpl_trace::{Vpl, VplKey, VplSet};
use crate::gpu::GpuContext;

pub struct LightList {
    pub buffer: wgpu::Buffer,
    pub lights: Vec<Vpl>,
    /// The VPL clustering (`None` when unclustered): where the next one starts from with temporal
    /// reuse on.
    pub clustering: Option<Clustering>,
}

/// The raw VPLs as the light list (VPL clustering off).
pub fn unclustered(ctx: &GpuContext, vpls: &VplSet) -> LightList {
    LightList {
        buffer: ctx.storage_init("lights", &vpls.vpls),
        lights: vpls.vpls.clone(),
        clustering: None,
    }
}

/// Clusters the VPLs on the GPU and builds the light list. The flux sums are done on the CPU in f64
/// from the GPU's assignment (N values, once per scene): exact and independent of the order of
/// additions, so the same seed gives the same image. With `warm`, Alg. 1 starts from the last
/// clustering's centroids (`kmeans::Warm`).
pub fn cluster(
    g: &mut Gpu,
    kmeans: &KMeans,
    vpls: &VplSet,
    settings: &KMeansSettings,
    frame: (Vec3, Vec3),
    warm: Option<&Warm>,
) -> Result<LightList> {
    let ctx = g.ctx;
    let n = vpls.vpls.len() as u32;
    let s = KMeansSettings { f: 1, ..*settings };
    let points = Points {
        data: &vpls.buffer,
        count: n,
        stride: 3,
    };
    let c = kmeans.run(g, Pass::VplCluster.name(), &points, &s, frame, warm)?;
    let assign: Vec<u32> = ctx.read_buffer(&c.assign, n as usize)?;
    let reps: Vec<u32> = ctx.read_buffer(&c.reps, c.k() as usize * 2)?;
    let mut flux = vec![[0f64; 3]; c.k() as usize];
    for (v, &k) in vpls.vpls.iter().zip(&assign) {
        if k != u32::MAX {
            for (sum, &x) in flux[k as usize].iter_mut().zip(&v.flux) {
                *sum += x as f64;
            }
        }
    }
    let lights: Vec<Vpl> = (0..c.k() as usize)
        .filter_map(|k| {
            let rep = reps[2 * k + 1];
            (rep != u32::MAX).then(|| {
                let r = vpls.vpls[rep as usize];
                Vpl {
                    pos: r.pos,
                    nrm: r.nrm,
                    flux: [flux[k][0] as f32, flux[k][1] as f32, flux[k][2] as f32, 0.0],
                }
            })
        })
        .collect();
    Ok(LightList {
        buffer: ctx.storage_init("vpl cluster lights", &lights),
        lights,
        clustering: Some(c),
    })
}

/// What a light list was built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightKey {
    /// K_VPL (0: the VPLs themselves).
    pub k: u32,
    pub normal_threshold_bits: u32,
    pub iterations: u32,
    pub seed: u32,
    /// The VPL set it clusters.
    pub vpls: VplKey,
}

/// The resident light list (VPL clusters, step 2, or the VPLs) with its key and the clustering's GPU
/// ms.
pub struct ResidentLights {
    pub list: LightList,
    pub key: LightKey,
    pub ms: f64,
}
