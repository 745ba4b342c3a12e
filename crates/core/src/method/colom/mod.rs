//! The `colom` method (Colom, Marques, Santos 2022, seed 000; the paper this tool rebuilds): the
//! shading points clustered by fuzzy k-means (step 4, Alg. 1 and 2, `gi::kmeans`), one shadow ray
//! per SP-cluster representative and light (step 5, `visibility`), and Eq. (6) per pixel with
//! Eq. (8) or (9) (step 6, `shade`). Its lights are the resident VPL clusters (step 2) or the VPLs.
//! Its passes are `Pass::SpCluster` → `Pass::Visibility` → `Pass::Shade` (its `ENTRY`); where K_SP
//! does not apply, the frame is the renderer's shared gather (VPL clusters) or reference.
//!
//! Its state is what temporal reuse starts from: the last frame's SP clustering (its centroids warm
//! the next k-means) and visibility matrix (rows of representatives the warm start kept are copied
//! while the lights are the same).

pub mod shade;
pub mod visibility;

use std::any::Any;

use anyhow::Result;

use super::{
    FrameInputs, IndirectMethod, Limits, Method, MethodEntry, PendingReport, Resolved, Tally,
};
use crate::gi::dispatch::Gpu;
use crate::gi::kmeans::{Clustering, KMeans, KMeansSettings, KmCounters, Points, Warm};
use crate::gi::pass::Pass;
use crate::gi::scene_gpu::SceneGpu;
use crate::gi::vpl_cluster::LightKey;
use crate::gpu::GpuContext;
use crate::settings::Weighting;
use shade::{Shade, ShadeInputs, ShadeParams};
use visibility::{Previous, VisInputs, Visibility};

/// colom's line of the registry. Its knobs are the paper's (`ClusterSettings`: K, F, γ, n_t, the
/// weighting and the adaptations), shown and swept by the viewer's and the bench's own controls.
pub const ENTRY: MethodEntry = MethodEntry {
    method: Method::Colom,
    doc: "Colom, Marques, Santos 2022: fuzzy k-means of SPs and VPLs, visibility \
          between cluster representatives, Eq. (6) shading per pixel × VPL cluster",
    passes: &[Pass::SpCluster, Pass::Visibility, Pass::Shade],
    build,
    clusters_sps: true,
    vpl_clusters: |_| true,
    limits,
    own_settings: false,
    colour: [140, 86, 75],
    about: "Colom et al. 2022: fuzzy k-means of SPs and VPLs, Eq. (6) per pixel and VPL cluster \
            (docs/methods.md)",
    label: |_| String::new(),
    series: |_| String::new(),
    short: |_| String::new(),
    report_columns: &["sp_iterations", "sp_warm_kept", "visibility_rows_reused"],
};

/// colom's counts: the stats' `counts.colom` and path.csv's columns of the same names (read back
/// from its SP clustering's counters on request, `PendingSp`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Report {
    /// Alg. 1 iterations the SP clustering ran.
    pub sp_iterations: u32,
    /// SP centroids a temporal warm start kept from the previous frame (absent: a cold start).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sp_warm_kept: Option<u32>,
    /// Rows of the visibility matrix copied from the previous frame instead of traced (kept
    /// representatives, same lights).
    pub visibility_rows_reused: u32,
}

impl Report {
    /// colom's report in a frame's (`Frame::report_of(Method::Colom)`); `None` when colom did not
    /// run or its counts were not read back.
    pub fn of(report: Option<&serde_json::Value>) -> Option<Report> {
        serde_json::from_value(report?.clone()).ok()
    }
}

/// colom's counts left on the GPU (its SP clustering's `KmCounters`): the frame's recording never
/// waits for them; `read` (on request) gives the SP clusters used, the rays the visibility pass
/// traced and colom's `Report`.
#[derive(Clone, Debug)]
pub struct PendingSp {
    /// The SP clustering's `Clustering::bounds`.
    pub bounds: wgpu::Buffer,
    /// The clustering started warm.
    pub warm: bool,
    pub visibility: VisibilityRows,
}

/// What the visibility pass did with the clustering's representatives' rows.
#[derive(Clone, Copy, Debug)]
pub struct VisibilityRows {
    /// The rows of kept representatives were copied, not traced (same lights).
    pub rows_copied: bool,
    /// The lights a traced row has a ray to.
    pub num_lights: u32,
}

impl VisibilityRows {
    /// The counts from the clustering's.
    pub fn resolve(&self, k: &KmCounters) -> Resolved {
        let rows_reused = if self.rows_copied { k.reps_kept } else { 0 };
        let report = Report {
            sp_iterations: k.iterations_run,
            sp_warm_kept: k.warm_kept,
            visibility_rows_reused: rows_reused,
        };
        Resolved {
            indirect_rays: k.reps_used.saturating_sub(rows_reused) as u64 * self.num_lights as u64,
            sp_used: Some(k.reps_used),
            report: Some(serde_json::to_value(report).expect("a plain struct")),
        }
    }
}

impl PendingReport for PendingSp {
    /// Reads them back (a wait for the frame's clustering and 68 bytes).
    fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Resolved> {
        let k = KmCounters::read(device, queue, &self.bounds, self.warm)?;
        Ok(self.visibility.resolve(&k))
    }
}

/// Bytes of the visibility bit matrix (step 5): one row per SP cluster, one bit per light, the
/// lights being the VPL clusters or, unclustered, every VPL (an upper bound: fewer may be traced or
/// used). It is one storage binding.
pub fn visibility_bytes(l: &Limits) -> u64 {
    l.cluster.sp_clusters as u64 * l.lights.div_ceil(32).max(1) as u64 * 4
}

/// Refuses a visibility bit matrix larger than one storage binding (K_SP × lights / 8 bytes:
/// 200,000 SP clusters × 8192 VPLs is 205 MB, lavapipe binds 128 MiB): the message names the
/// options.
fn limits(l: &Limits) -> Result<(), String> {
    let bytes = visibility_bytes(l);
    if bytes > l.max_binding {
        let what = match l.lights_clustered {
            true => "VPL clusters",
            false => "VPLs",
        };
        return Err(format!(
            "--sp-clusters {} with {} {what}: the visibility bit matrix (a bit per SP cluster and light) takes {bytes} bytes, more than the {} bytes of one storage binding on this adapter; use fewer SP clusters or cluster the VPLs",
            l.cluster.sp_clusters, l.lights, l.max_binding
        ));
    }
    Ok(())
}

/// A clustered frame's visibility matrix and the light list it was traced against.
pub struct LastVisibility {
    pub matrix: Previous,
    pub lights: LightKey,
}

/// What colom's passes hand on within a frame.
#[derive(Default)]
struct ColomFrame {
    clustering: Option<Clustering>,
    visibility: Option<Previous>,
    /// The previous frame's matrix when its rows may be reused (temporal).
    previous_visibility: Option<LastVisibility>,
    lights: Option<LightKey>,
}

/// colom's state: its passes' pipelines, the last frame's SP clustering and visibility, and what
/// its passes hand on within a frame.
pub struct Colom {
    kmeans: KMeans,
    visibility: Visibility,
    shade: Shade,
    /// The last frame's SP clustering (views, tests, and the next frame's warm start); `None` after
    /// a frame that clustered no shading points.
    pub clustering: Option<Clustering>,
    /// The last clustered frame's visibility matrix.
    pub last_visibility: Option<LastVisibility>,
    frame: ColomFrame,
}

/// colom's state for a scene's GPU data.
pub fn build(ctx: &GpuContext, scene: &SceneGpu) -> Box<dyn IndirectMethod> {
    Box::new(Colom::new(ctx, scene))
}

impl Colom {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        Colom {
            kmeans: KMeans::new(),
            visibility: Visibility::new(ctx, scene),
            shade: Shade::new(),
            clustering: None,
            last_visibility: None,
            frame: ColomFrame::default(),
        }
    }

    /// The shade pass's `PATTERNS` (`shade::patterns`, 0..8): its pipelines are built again.
    /// The image does not depend on it.
    pub fn set_shade_patterns(&mut self, patterns: u32) {
        self.shade = Shade::with_options(patterns, self.shade.tile_cull());
    }

    /// The shade pass's `TILE_CULL` (`shade::tile_cull`): its pipelines are built again. The
    /// image differs at most by terms whose cosine is at the rounding of the coordinates.
    pub fn set_shade_tile_cull(&mut self, on: bool) {
        self.shade = Shade::with_options(self.shade.patterns(), on);
    }

    /// Step 4: the SP clustering, warm-started from the previous frame's with temporal reuse.
    fn sp_cluster(&mut self, g: &mut Gpu, f: &FrameInputs, counts: &mut Tally) -> Result<()> {
        let previous = self.clustering.take().filter(|_| f.cluster.temporal);
        let warm = previous.as_ref().map(|c| Warm {
            centroids: &c.centroids,
            rep_points: &c.rep_points,
            k: c.k(),
            view: Some(f.cam),
        });
        let points = Points {
            data: f.gbuffer,
            count: f.pixels(),
            stride: 4,
        };
        let c = self.kmeans.run(
            g,
            Pass::SpCluster.name(),
            &points,
            &KMeansSettings::shading_points(f.cluster, f.frame.seed),
            f.scene.bounds(),
            warm.as_ref(),
        )?;
        let light_key = f.lights.expect("colom's lights").key;
        self.frame.previous_visibility = self
            .last_visibility
            .take()
            .filter(|v| f.cluster.temporal && c.warm && v.lights == light_key);
        self.frame.lights = Some(light_key);
        counts.gamma_used = Some(c.params.gamma);
        self.frame.clustering = Some(c);
        Ok(())
    }

    /// Step 5: the visibility bit matrix between SP-cluster representatives and lights; rows of
    /// representatives kept from the previous frame are copied when the lights are the same.
    fn visibility(&mut self, g: &mut Gpu, f: &FrameInputs, counts: &mut Tally) -> Result<()> {
        let lights = &f.lights.expect("colom's lights").list;
        let num_lights = lights.lights.len() as u32;
        let c = self.frame.clustering.as_ref().expect("sp_cluster ran");
        let previous = self.frame.previous_visibility.take();
        let (bits, words) = self.visibility.record(
            g,
            &VisInputs {
                rep_points: &c.rep_points,
                lights: &lights.buffer,
                num_lights,
                k_sp: c.k(),
                previous: previous.as_ref().map(|p| &p.matrix),
                facing: f.cluster.visibility_facing,
            },
        );
        // The clusters used, the rows copied and the rays traced stay on the GPU until asked for.
        counts.pending = Some(std::sync::Arc::new(PendingSp {
            bounds: c.bounds.clone(),
            warm: c.warm,
            visibility: VisibilityRows {
                rows_copied: previous.as_ref().is_some_and(|p| p.matrix.words == words),
                num_lights,
            },
        }));
        self.frame.visibility = Some(Previous {
            bits,
            rows: c.k(),
            words,
        });
        Ok(())
    }

    /// Step 6: Eq. (6) per pixel with the visibility of Eq. (8) or (9).
    fn shade(&mut self, g: &mut Gpu, f: &FrameInputs) {
        let lights = &f.lights.expect("colom's lights").list;
        let c = self.frame.clustering.as_ref().expect("sp_cluster ran");
        let v = self.frame.visibility.as_ref().expect("visibility ran");
        let d_min = f.d_min;
        self.shade.record(
            g,
            &ShadeInputs {
                gbuffer: f.gbuffer,
                lights: &lights.buffer,
                bits: &v.bits,
                assign: &c.assign,
                weights: &c.weights,
                indirect: f.indirect,
                params: ShadeParams {
                    num_lights: lights.lights.len() as u32,
                    words: v.words,
                    f: c.f(),
                    weighted: (f.cluster.weighting == Weighting::InverseDistance) as u32,
                    d_min2: d_min * d_min,
                    width: f.size.0,
                    height: f.size.1,
                    _pad: 0,
                },
                light: f.cluster.cluster_light,
            },
        );
    }
}

/// The state temporal reuse starts from (`IndirectMethod::take_past`).
struct Past {
    clustering: Option<Clustering>,
    last_visibility: Option<LastVisibility>,
}

impl IndirectMethod for Colom {
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) -> Result<()> {
        match pass {
            Pass::SpCluster => self.sp_cluster(g, f, n),
            Pass::Visibility => self.visibility(g, f, n),
            Pass::Shade => {
                self.shade(g, f);
                Ok(())
            }
            _ => unreachable!("{pass} is not colom's"),
        }
    }

    /// The frame's clustering and matrix become the last ones; a frame that clustered no shading
    /// points leaves no clustering to warm-start from (the matrix stays: it is reused only after a
    /// warm start).
    fn end_frame(&mut self) {
        let frame = std::mem::take(&mut self.frame);
        match (frame.clustering, frame.visibility, frame.lights) {
            (Some(c), Some(matrix), Some(lights)) => {
                self.last_visibility = Some(LastVisibility { matrix, lights });
                self.clustering = Some(c);
            }
            _ => self.clustering = None,
        }
    }

    fn take_past(&mut self) -> Box<dyn Any> {
        Box::new(Past {
            clustering: self.clustering.take(),
            last_visibility: self.last_visibility.take(),
        })
    }

    fn put_past(&mut self, past: Box<dyn Any>) {
        if let Ok(p) = past.downcast::<Past>() {
            (self.clustering, self.last_visibility) = (p.clustering, p.last_visibility);
        }
    }

    fn sp_clustering(&self) -> Option<&Clustering> {
        self.clustering.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// colom's report columns round-trip: its keys written as their JSON scalars (absent ones
    /// empty), read back from the cells by name; another method's row leaves them empty and reads
    /// none.
    #[test]
    fn report_columns_round_trip() {
        let cols = crate::method::report_columns();
        assert_eq!(
            cols,
            ["sp_iterations", "sp_warm_kept", "visibility_rows_reused"]
        );
        let report = serde_json::json!({"sp_iterations": 3, "visibility_rows_reused": 7});
        let cells = crate::method::report_values(Method::Colom, Some(&report));
        assert_eq!(cells, ["3", "", "7"]);
        let back = crate::method::report_of_cells(
            Method::Colom,
            cols.iter().copied().zip(cells.iter().map(String::as_str)),
        );
        assert_eq!(back, Some(report.clone()));
        // Another method's row leaves colom's columns empty, and its cells are not colom's.
        let another = Method::ALL[1];
        let other = crate::method::report_values(another, Some(&report));
        assert!(other.iter().all(String::is_empty));
        let cells = cols.iter().copied().zip(["3", "", "7"]);
        assert_eq!(crate::method::report_of_cells(another, cells), None);
        assert_eq!(
            crate::method::report_of_cells(Method::Colom, [("sp_iterations", "x")]),
            Some(serde_json::json!({"sp_iterations": "x"}))
        );
    }

    /// Hand-worked: 40 representatives of which 30 kept with their rows copied, 64 lights: 10 rows
    /// traced (640 rays); without the copy every row is traced. The report is `counts.colom`'s.
    #[test]
    fn pending_counts_resolve_to_rays_and_the_report() {
        let ctx_free = |rows_copied| VisibilityRows {
            rows_copied,
            num_lights: 64,
        };
        let k = KmCounters {
            iterations_run: 2,
            warm_kept: Some(33),
            reps_used: 40,
            reps_kept: 30,
        };
        let r = ctx_free(true).resolve(&k);
        assert_eq!((r.indirect_rays, r.sp_used), (640, Some(40)));
        assert_eq!(
            r.report,
            Some(serde_json::json!({
                "sp_iterations": 2,
                "sp_warm_kept": 33,
                "visibility_rows_reused": 30
            }))
        );
        let r = ctx_free(false).resolve(&k);
        assert_eq!(r.indirect_rays, 40 * 64);
        let cold = KmCounters {
            warm_kept: None,
            ..k
        };
        let back = Report::of(ctx_free(false).resolve(&cold).report.as_ref()).unwrap();
        assert_eq!(
            back,
            Report {
                sp_iterations: 2,
                sp_warm_kept: None,
                visibility_rows_reused: 0
            }
        );
    }
}
