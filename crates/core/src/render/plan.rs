//! Which passes a frame runs, for a scene and its settings, in what order (the paper's Fig. 2): the
//! one place that decides it. `Plan::new` lists them; `Renderer::render` (`record.rs`) runs exactly
//! that list, in order.
//!
//! Resident (per scene / light change, `resident.rs`): the VPLs (step 1) and their clusters (step 2).
//! Per frame: primary (step 3) → direct + emission → indirect, one of
//! - a method's own passes (its entry's `passes`, `method::REGISTRY`); the paper's are `sp_cluster` (step 4)
//!   → `visibility` (step 5) → `shade` (step 6, Eq. 6 with Eq. 8 or 9), the lights being VPL
//!   clusters ("both") or the VPLs ("SPs only");
//! - where no method's passes apply (the reference, or a method that clusters the SPs without
//!   0 < K_SP < pixels), the shared gather: `reference`, every pixel × every VPL (Eq. 5), the paper's
//!   "no clustering", or `gather`, every pixel × every VPL cluster ("VPLs only");
//!
//! then the upsampling of a render-scale indirect light and the temporal accumulation.

use crate::gi::pass::Pass;
use crate::method::Method;
use crate::render::settings::RenderSettings;
use crate::scene::Scene;

/// Which passes a frame runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    pub indirect: bool,
    /// Step 2 (the resident VPL clustering: the lights of a method whose `vpl_clusters` asks for it).
    pub vpl_clustering: bool,
    /// The method whose own passes (its entry's `passes`) compute the indirect light: the one asked
    /// where it applies; `None` for the reference and where the method asked does not apply (one
    /// that clusters SPs without 0 < K_SP < pixels), whose frame is the shared gather (`reference`,
    /// or `gather` over the VPL clusters).
    pub method: Option<Method>,
    /// The render-scale size the indirect light is computed at when it is upsampled to the image
    /// (`--indirect-scale` below 1, not for the reference); `None`: at the image's size.
    pub low: Option<(u32, u32)>,
    /// Temporal accumulation of the indirect light (`--temporal on` with α below 1, clustered
    /// frames: `gi::accumulate`).
    pub accumulate: bool,
}

impl Plan {
    pub fn new(scene: &Scene, s: &RenderSettings) -> Plan {
        let (f, c) = (&s.frame, &s.cluster);
        let indirect = f.vpls > 0 && scene.has_light();
        let clustered = indirect && !s.reference;
        let low = Some(crate::gi::upsample::indirect_size(
            f.width,
            f.height,
            f.indirect_scale,
        ))
        .filter(|&l| clustered && l != (f.width, f.height));
        let pixels = low.map_or(f.width * f.height, |(w, h)| w * h);
        let sp = clustered && c.sp_clusters > 0 && c.sp_clusters < pixels;
        // A method's own passes run where they apply (one clustering SPs needs 0 < K_SP < pixels);
        // elsewhere the shared gather does.
        let entry = Some(s.method.entry()).filter(|r| clustered && (sp || !r.clusters_sps));
        Plan {
            indirect,
            vpl_clustering: clustered
                && entry.is_none_or(|r| (r.vpl_clusters)(&s.method))
                && c.vpl_clusters > 0
                && c.vpl_clusters < f.vpls,
            method: entry.map(|r| r.method),
            low,
            accumulate: clustered && c.temporal && c.temporal_alpha < 1.0,
        }
    }

    /// The lights the method's passes see: the VPL clusters asked, or every VPL (an upper bound:
    /// fewer may be traced or used).
    pub fn lights(&self, s: &RenderSettings) -> u32 {
        match self.vpl_clustering {
            true => s.cluster.vpl_clusters,
            false => s.frame.vpls,
        }
    }

    /// The passes, in the order they run.
    pub fn passes(&self) -> Vec<Pass> {
        let mut p = vec![];
        if self.indirect {
            p.push(Pass::VplTrace);
        }
        if self.vpl_clustering {
            p.push(Pass::VplCluster);
        }
        p.extend([Pass::Primary, Pass::Direct]);
        if self.indirect {
            p.extend_from_slice(match self.method {
                Some(m) => crate::method::entry(m).passes,
                None if self.vpl_clustering => &[Pass::Gather],
                None => &[Pass::Reference],
            });
        }
        if self.low.is_some() {
            p.push(Pass::Upsample);
        }
        if self.accumulate {
            p.push(Pass::Accumulate);
        }
        p
    }
}
