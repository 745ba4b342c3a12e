//! The renderer's resident caches: the VPLs (step 1) and their light list (step 2: the VPL
//! clusters, or the VPLs themselves), rebuilt only when their inputs change (count, seed, bounces;
//! the clustering's settings), the clustering warm-started from the last with temporal reuse.

use anyhow::Result;

use super::plan::Plan;
use super::renderer::{Renderer, gpu};
use crate::gi::kmeans::KMeansSettings;
use crate::gi::vpl_cluster::{self, LightKey, ResidentLights};
use crate::gi::vpl_trace::{ResidentVpls, VplKey, VplSet};
use crate::render::settings::RenderSettings;

impl Renderer<'_> {
    /// Step 1: traces the VPLs unless the resident ones match (count, seed, bounces).
    pub fn ensure_vpls(&mut self, n: u32, seed: u32, bounces: u32) -> Result<&VplSet> {
        let traced = self
            .vpl_set
            .as_ref()
            .map(|v| (v.key.count, v.key.seed, v.key.bounces));
        if traced != Some((n, seed, bounces)) {
            self.vpl_traces += 1;
            let key = VplKey {
                count: n,
                seed,
                bounces,
                trace: self.vpl_traces,
            };
            let _ = self.profiler.collect(self.ctx)?;
            let set = self
                .vpl_trace
                .trace(&mut gpu!(self), &self.scene, n, seed, bounces)?;
            let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
            self.vpl_set = Some(ResidentVpls { set, key, ms });
        }
        Ok(&self.vpl_set.as_ref().unwrap().set)
    }

    /// Step 2: builds the light list (VPL clusters, or the VPLs themselves) unless the resident one
    /// matches.
    pub(super) fn ensure_lights(&mut self, s: &RenderSettings, plan: &Plan) -> Result<()> {
        let f = &s.frame;
        let c = &s.cluster;
        self.ensure_vpls(f.vpls, f.seed, f.bounces)?;
        let key = LightKey {
            k: if plan.vpl_clustering {
                c.vpl_clusters
            } else {
                0
            },
            normal_threshold_bits: c.normal_threshold.to_bits(),
            iterations: c.iterations,
            adapt: c.adaptations().bits(),
            seed: f.seed,
            vpls: self.vpl_set.as_ref().unwrap().key,
        };
        if self.lights.as_ref().map(|l| l.key) == Some(key) {
            return Ok(());
        }
        let vpls = &self.vpl_set.as_ref().unwrap().set;
        let _ = self.profiler.collect(self.ctx)?;
        let list = if plan.vpl_clustering {
            let previous = self.lights.take().filter(|_| c.temporal);
            let warm = previous
                .as_ref()
                .and_then(|l| l.list.clustering.as_ref())
                .map(|c| crate::gi::kmeans::Warm {
                    centroids: &c.centroids,
                    rep_points: &c.rep_points,
                    k: c.k(),
                    view: None,
                });
            vpl_cluster::cluster(
                &mut gpu!(self),
                &self.kmeans,
                vpls,
                &KMeansSettings::vpls(c, f.seed),
                self.scene.bounds(),
                warm.as_ref(),
            )?
        } else {
            vpl_cluster::unclustered(self.ctx, vpls)
        };
        let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
        self.lights = Some(ResidentLights { list, key, ms });
        Ok(())
    }
}
