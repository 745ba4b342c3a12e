//! Step 2: VPL clustering (Alg. 1 with F = 1 on the VPLs' positions and normals) and the light list
//! the frame uses: per cluster its representative VPL (a member, on a real surface) carrying the
//! summed flux of all members, with the other members' share and spread (`Spread`). Resident:
//! rebuilt only when the VPLs or K change.

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
/// from the GPU's assignment (N values, once per scene, `Spread`), in the VPLs' order, so the same
/// seed gives the same image. With `warm`, Alg. 1 starts from the last
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
    let rep = |k: u32| reps[2 * k as usize + 1];
    let mut sums = vec![Spread::default(); c.k() as usize];
    for (i, (v, &k)) in vpls.vpls.iter().zip(&assign).enumerate() {
        if k != u32::MAX && rep(k) != u32::MAX {
            let r = &vpls.vpls[rep(k) as usize];
            sums[k as usize].add(v, r, i as u32 == rep(k));
        }
    }
    let lights: Vec<Vpl> = (0..c.k())
        .filter(|&k| rep(k) != u32::MAX)
        .map(|k| sums[k as usize].light(&vpls.vpls[rep(k) as usize]))
        .collect();
    Ok(LightList {
        buffer: ctx.storage_init("vpl cluster lights", &lights),
        lights,
        clustering: Some(c),
    })
}

/// A VPL cluster's sums for its light, in f64 over its members in index order (the same seed gives
/// the same image): the summed flux, and the flux (r + g + b) of the members other than the
/// representative with its moments of their squared distance from it (the representative's own is
/// the rest of the sum).
#[derive(Clone, Copy, Debug, Default)]
pub struct Spread {
    flux: [f64; 3],
    other: f64,
    other_d2: f64,
}

impl Spread {
    /// Adds member `v` of the cluster whose representative is `rep` (`is_rep`: `v` is it).
    pub fn add(&mut self, v: &Vpl, rep: &Vpl, is_rep: bool) {
        for (sum, &x) in self.flux.iter_mut().zip(&v.flux) {
            *sum += x as f64;
        }
        if !is_rep {
            let w = v.flux[..3].iter().map(|&x| x as f64).sum::<f64>();
            let d2: f64 = (0..3)
                .map(|c| (v.pos[c] as f64 - rep.pos[c] as f64).powi(2))
                .sum();
            self.other += w;
            self.other_d2 += w * d2;
        }
    }

    /// Not in the paper (docs/clustering.md, "VPL clusters as lights"): the cluster's light, its
    /// representative `rep` (position and normal) with the members' summed flux; `flux[3]` the
    /// other members' share of the flux (r + g + b) and `nrm[3]` their flux-weighted mean squared
    /// distance from `rep`, which `eq5_cluster_radiance` clamps their term's d at (both 0 for a
    /// cluster of one VPL).
    pub fn light(&self, rep: &Vpl) -> Vpl {
        let total: f64 = self.flux.iter().sum();
        let (share, r2) = if self.other > 0.0 && total > 0.0 {
            (self.other / total, self.other_d2 / self.other)
        } else {
            (0.0, 0.0)
        };
        Vpl {
            pos: rep.pos,
            nrm: [rep.nrm[0], rep.nrm[1], rep.nrm[2], r2 as f32],
            flux: [
                self.flux[0] as f32,
                self.flux[1] as f32,
                self.flux[2] as f32,
                share as f32,
            ],
        }
    }
}

/// What a light list was built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightKey {
    /// K_VPL (0: the VPLs themselves).
    pub k: u32,
    pub normal_threshold_bits: u32,
    pub iterations: u32,
    /// The k-means adaptations (`Adaptations::bits`).
    pub adapt: u32,
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

#[cfg(test)]
mod tests {
    use super::*;

    fn vpl(p: [f32; 3], flux: f32) -> Vpl {
        Vpl {
            pos: [p[0], p[1], p[2], 1.0],
            nrm: [0.0, 1.0, 0.0, 0.0],
            flux: [flux, flux, 2.0 * flux, 0.0],
        }
    }

    /// Hand-worked: the representative at the origin (flux (1, 1, 2), r + g + b = 4), members at
    /// distance 3 (flux (2, 2, 4): 8) and 4 (flux (1, 1, 2): 4). Summed flux (4, 4, 8); the other
    /// members' share (8 + 4) / 16 = 0.75; their mean squared distance (8·9 + 4·16) / 12 = 34/3.
    #[test]
    fn spread_of_three_members_by_hand() {
        let rep = vpl([0.0; 3], 1.0);
        let members = [vpl([3.0, 0.0, 0.0], 2.0), rep, vpl([0.0, 0.0, 4.0], 1.0)];
        let mut s = Spread::default();
        for (i, m) in members.iter().enumerate() {
            s.add(m, &rep, i == 1);
        }
        let l = s.light(&rep);
        assert_eq!(l.pos, rep.pos);
        assert_eq!(&l.nrm[..3], &rep.nrm[..3]);
        assert_eq!(l.flux, [4.0, 4.0, 8.0, 0.75]);
        assert_eq!(l.nrm[3], (34.0f64 / 3.0) as f32);
    }

    /// A cluster of one VPL is that VPL: no spread.
    #[test]
    fn a_single_member_is_its_vpl() {
        let rep = vpl([1.0, 2.0, 3.0], 0.5);
        let mut s = Spread::default();
        s.add(&rep, &rep, true);
        assert_eq!(s.light(&rep), rep);
    }
}
