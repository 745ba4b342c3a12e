// What the k-means steps share (shaders-wgsl/kmeans.wgsl and kmeans/*.wgsl): the parameters, the
// bindings, point access and Eq. (7); the grid over the centroids is common/grid.wgsl's.
#import common/chunk.wgsl
#import common/grid.wgsl

const INVALID: u32 = 0xffffffffu;
const BIG: f32 = 3.4028235e38;
const MAX_F: u32 = 16u;
// F of the pipeline (params.f; crates/core/src/gi/kmeans.rs builds one pipeline set per F in use): loops over the
// F slots of a point have a constant trip count, so its list lives in registers.
override F: u32 = 1u;
// Where the nearest-centroid search reads the grid (the result is the same). true (software
// adapters): the textures below, and a candidate's normal only when it would enter the list (lavapipe
// fetches a texel per lane with vector code but reads storage per lane in a scalar loop, and pays for
// every fetch). false (GPUs): the storage buffers, the normal loaded with the position (both cached;
// a thread's chain of dependent loads sets the time there: 13% less in assign_sampled on an H100).
override TEXTURE_SEARCH: bool = true;
// Whether final_assign applies the plane gate (params.plane_gate <= 1; crates/core/src/gi/kmeans.rs builds the
// pipelines with it on only when asked, so the default frame pays nothing for it).
override PLANE_GATE: bool = false;
// The departures from Alg. 1 and 2, each on by default and off with --paper (crates/core/src/gi/kmeans.rs builds
// a pipeline set per combination, `settings::Adaptations`, so a switched-off one costs nothing; the
// CPU twin reads the same switches from params.adapt). docs/clustering.md, "The paper exactly".
// RESEED: an empty cluster is re-seeded at an orphan or a drawn sampled point (iterate.wgsl).
override RESEED: bool = true;
// RING_FALLBACK: with no centroid passing n_t in the 27 cells, rings further out (nearest.wgsl).
override RING_FALLBACK: bool = true;
// POSITION_FALLBACK: with none within the rings either, the nearest centroid by position alone.
override POSITION_FALLBACK: bool = true;
// NORMALISED_NORMAL: a centroid's normal is its members' mean normal at unit length (off: the plain
// mean, Alg. 1 line 18's value / counter).
override NORMALISED_NORMAL: bool = true;
// Fixed point: positions in the data frame scaled by 2^24, normals (n + 1) by 2^23.
const POS_SCALE: f32 = 16777216.0;
const NRM_SCALE: f32 = 8388608.0;

struct KmParams {
    num_points: u32,
    // vec4s per point in `data`; point m is data[m * stride] (xyz position, w > 0 when valid) and
    // data[m * stride + 1] (xyz normal).
    stride: u32,
    gamma: u32,
    num_sampled: u32,
    k: u32,
    f: u32,
    // Eq. (7) orientation threshold (cosine).
    normal_threshold: f32,
    seed: u32,
    // Fixed-point frame: lo + ext spans every point.
    lo: vec4<f32>,
    ext: vec4<f32>,
    // p of the fuzzy weights w'_f = dist^-p (Eq. 10 is p = 1; 0 is Eq. 8's plain mean).
    weight_exponent: f32,
    // The plane gate of the final assignment: sin of its angle, 2 when off (crates/core/src/gi/kmeans.rs).
    plane_gate: f32,
    // settings::Adaptations::bits (for the CPU twin; the shaders use the overrides above).
    adapt: u32,
    _p2: u32,
    // The temporal warm start (warm_centroids): the new frame's camera as primary.wgsl's
    // CameraParams (eye; image-plane axes scaled by tan(fov/2); forward), with eye.w the same-surface
    // tolerance as a fraction of the eye distance; warm_size = (width, height, previous K, 0), width 0
    // when the points are not pixels of that view (VPLs: every previous centroid is kept).
    warm_eye: vec4<f32>,
    warm_right: vec4<f32>,
    warm_up: vec4<f32>,
    warm_forward: vec4<f32>,
    warm_size: vec4<u32>,
}

struct Centroid {
    // xyz position; w = 1 when the cluster holds at least one point.
    pos: vec4<f32>,
    nrm: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: KmParams;
@group(1) @binding(2) var<storage, read> data: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read_write> centroids: array<Centroid>;
// Per cluster: 6 components x (lo, hi) words of 64-bit fixed-point sums, then the count (13 words).
@group(1) @binding(4) var<storage, read_write> sums: array<atomic<u32>>;
// Centroid bounds as order-preserving float bits: min xyz, max xyz; then per iteration whether the
// centroids changed (6), the iteration's number (7), whether it found an orphan (8), and the empty
// cluster an update left (9 + the iteration's parity; k + 1, 0 for none: `last_empty`), and the
// centroids warm_centroids kept (11). Alg. 1's loop on the GPU (`converge`): whether it has ended
// (12), the iterations asked for (13) and whether the run started warm (14), both from the host.
// The counts of the representatives (`rep_count`): clusters with one (15), and those below the
// previous K that kept the previous frame's (16). The host reads these words only when asked
// (`Clustering::counters`): never per frame.
@group(1) @binding(5) var<storage, read_write> bounds: array<atomic<u32>, BOUND_WORDS>;
const BOUND_WORDS: u32 = 17u;

// Whether Alg. 1's loop has ended (`converge`): the host records every iteration it asked for, and
// those after the end do nothing.
fn stopped() -> bool {
    return atomicLoad(&bounds[12]) != 0u;
}
@group(1) @binding(6) var<storage, read_write> grid: Grid;
// Cell counts (0 outside a grid build), then from MAX_CELLS on each cell's offset within its scan
// block, then from BLOCK_SUMS the blocks' totals. Fixed places: the next grid may have more cells, and
// its counts must start at 0.
@group(1) @binding(7) var<storage, read_write> cells: array<atomic<u32>>;
// Per point and slot, the bits of the distance final_assign found (read by rep_pick, so the comparison
// with the cluster's smallest distance is of the same number, whatever a GPU's rounding).
@group(1) @binding(8) var<storage, read_write> member_dists: array<u32>;
// Sampled-point assignment during the iterations (one per sampled point).
@group(1) @binding(9) var<storage, read_write> sample_assign: array<u32>;
// Final assignment: F cluster indices per point (INVALID past the ones found) and weights (Eq. 10).
@group(1) @binding(10) var<storage, read_write> assign: array<u32>;
@group(1) @binding(11) var<storage, read_write> weights: array<f32>;
// Representatives: per cluster the smallest member distance (float bits) and the member index.
@group(1) @binding(12) var<storage, read_write> reps: array<atomic<u32>>;

// The grid as the nearest-centroid search reads it: grid_scatter writes the valid centroids sorted by
// cell (2 texels a slot, as float bits: position with w = the centroid's index, normal),
// grid_scan_ranges each cell's offsets. On a software adapter (TEXTURE_SEARCH) crates/core/src/gi/kmeans.rs
// copies both into the textures below after each grid build and the search reads those; on a GPU it
// reads the storage buffers and the textures are one unused texel each.
@group(1) @binding(13) var<storage, read_write> sorted: array<vec4<u32>>;
@group(1) @binding(14) var<storage, read_write> ranges: array<vec4<u32>>;
@group(1) @binding(15) var sorted_tex: texture_2d<u32>;
@group(1) @binding(16) var ranges_tex: texture_2d<u32>;
// Per cluster its representative as a point (2 vec4s: position with w = 1 when the cluster has one,
// normal with w = 1 when it is the previous frame's, kept by the warm start): what the visibility
// pass traces from. rep_store writes it after rep_pick; warm_centroids marks the previous ones (which
// the host copied in) that may be kept.
@group(1) @binding(17) var<storage, read_write> rep_points: array<vec4<f32>>;

const WORDS: u32 = 13u;

fn point_pos(m: u32) -> vec4<f32> {
    return data[m * params.stride];
}

fn point_nrm(m: u32) -> vec3<f32> {
    return data[m * params.stride + 1u].xyz;
}

// The data point behind sampled point s: one per stratum of gamma points, jittered (Alg. 1 line 1).
fn sample_index(s: u32) -> u32 {
    let g = max(params.gamma, 1u);
    let h = (s * 747796405u + params.seed * 2891336453u) ^ (s >> 7u);
    return min(s * g + (h >> 8u) % g, params.num_points - 1u);
}

// Eq. (7): dist(d1, d2) = |p1 - p2| when n1 · n2 > n_t, else ∞ (BIG). CPU twin: cpu::kmeans::eq7_dist.
fn eq7_dist(p: vec3<f32>, n: vec3<f32>, c: vec3<f32>, nc: vec3<f32>) -> f32 {
    if !eq7_normals_agree(n, nc) {
        return BIG;
    }
    return length(p - c);
}

// Eq. (7)'s orientation test alone: the nearest-centroid search (scan_slots) takes the distance
// first and this test only for a candidate that would enter the list (the same result as
// `eq7_dist`, half the texel fetches).
fn eq7_normals_agree(n: vec3<f32>, nc: vec3<f32>) -> bool {
    return dot(n, nc) > params.normal_threshold;
}
