//! The passes of the frame graph by name: `Pass::name()` keys the GPU timings (profiler labels), the
//! stats JSON's `passes` and `timings_ms`, and the bench CSV's `<stage>_ms` columns.

/// A pass of the frame graph. Its name keys the GPU timings (profiler labels), the stats JSON's
/// `passes` and `timings_ms`, and the bench CSV's `<stage>_ms` columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Pass {
    /// Step 1: light paths from the emitters deposit VPLs (resident).
    VplTrace,
    /// Step 2: k-means of the VPLs into a light list of representatives (resident).
    VplCluster,
    /// Step 3: primary rays to shading points.
    Primary,
    /// Emission and direct light.
    Direct,
    /// Step 4: fuzzy k-means of the shading points (Alg. 1 and 2).
    SpCluster,
    /// Step 5: visibility between SP-cluster representatives and lights.
    Visibility,
    /// Step 6: Eq. (6) with Eq. (8) or (9).
    Shade,
    /// Every pixel × every VPL cluster with its own shadow ray (VPL clustering only).
    Gather,
    /// Every pixel × every VPL (Eq. 5): no clustering.
    Reference,
    /// The diffuse path tracer (`--path-trace`), instead of every pass above.
    PathTrace,
    /// A pass of one of the other methods (`crates/core/src/method/<name>/`), by the name its module gives it
    /// (its registry entry's `passes`, consts of its module): a method adds its passes in its own
    /// folder, not here. Its name keys its timings as any pass's does.
    Method(&'static str),
    /// `--indirect-scale` below 1: the render-scale indirect light brought to the image's pixels
    /// (`gi::upsample`; the render-scale G-buffer it is computed on is timed under `primary`). Not
    /// in `TIMED`: its key is in `timings_ms` only when it ran, so frames at scale 1 keep theirs.
    Upsample,
    /// `--temporal on`: the indirect light blended with the previous frames' at the same surface
    /// points (`gi::accumulate`). Not in `TIMED`, like `Upsample`.
    Accumulate,
}

impl Pass {
    /// The shared passes whose times the stats report (the other methods' passes follow from
    /// their modules: `render::timed::timing_keys`). The first `STAGES`, in this order, are the
    /// bench CSV's `<stage>_ms` columns (a contract: `bench::csv::stage_passes`); the unclustered
    /// reference has its own column and the other methods' passes are summed in `indirect_ms`.
    pub const TIMED: [Pass; 9] = [
        Pass::VplTrace,
        Pass::VplCluster,
        Pass::Primary,
        Pass::SpCluster,
        Pass::Visibility,
        Pass::Shade,
        Pass::Gather,
        Pass::Direct,
        Pass::Reference,
    ];

    /// How many of `TIMED` are the CSV's stage columns.
    pub const STAGES: usize = 8;

    pub const fn name(self) -> &'static str {
        match self {
            Pass::VplTrace => "vpl_trace",
            Pass::VplCluster => "vpl_cluster",
            Pass::Primary => "primary",
            Pass::Direct => "direct",
            Pass::SpCluster => "sp_cluster",
            Pass::Visibility => "visibility",
            Pass::Shade => "shade",
            Pass::Gather => "gather",
            Pass::Reference => "reference",
            Pass::PathTrace => "pathtrace",
            Pass::Method(name) => name,
            Pass::Upsample => "upsample",
            Pass::Accumulate => "accumulate",
        }
    }

    /// Resident passes run only when their inputs change; their times are not in `frame`.
    pub fn resident(self) -> bool {
        matches!(self, Pass::VplTrace | Pass::VplCluster)
    }
}

impl std::fmt::Display for Pass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
