// What wang_cluster's steps share (wang_cluster.wgsl and wang/*.wgsl): the constants, the
// parameters, the bindings, the grid image and Eq. (2); the grid over the centres is
// common/grid.wgsl's.
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/grid.wgsl

const INVALID: u32 = 0xffffffffu;
const BIG: f32 = 3.4028235e38;
// Fixed point of the centre sums: positions in the scene's bounds scaled by 2^24, normals (n + 1) by
// 2^23 (as colom's k-means, common/kmeans.wgsl).
const POS_SCALE: f32 = 16777216.0;
const NRM_SCALE: f32 = 8388608.0;
// Fixed point of a node's ε_q: Eq. (2) per point scaled by 2^16, at most 2^23 - 1 (Eq. 2 is at most
// 100 + 2 with α at most 100 and positions inside the scene), so 256 points sum within 32 bits.
const EPS_SCALE: f32 = 65536.0;
const EPS_MAX: f32 = 8388607.0;

struct Params {
    // The image.
    width: u32,
    height: u32,
    // The grid image: every step-th pixel along x and y, gw x gh of them.
    step: u32,
    gw: u32,
    gh: u32,
    // The quadtree: side 2^levels grid pixels (at least 2); levels 0 .. levels - 1 are stored.
    levels: u32,
    // K: clusters asked.
    k: u32,
    seed: u32,
    // Eq. (2)'s α per unit of length (α / scene diagonal).
    alpha: f32,
    // width * height.
    pixels: u32,
    // Where the seeds start in `tree` (4 words a stored node before them).
    seeds_base: u32,
    _p: u32,
    // The scene's bounds: lo, extent (w: its diagonal); the fixed-point frame and the empty grid.
    lo: vec4<f32>,
    ext: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: Params;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
// The quadtree's sums, two vec4 a node (levels 0 .. levels - 1, level l from (4^l - 1) / 3, row-major
// within it): position sum with w = the valid points; normal sum.
@group(1) @binding(3) var<storage, read_write> nodes: array<vec4<f32>>;
// Four words a node: ε_q as 64-bit fixed point (lo, hi), the seeds it gets (kn) and the index of its
// first seed; then from params.seeds_base the K seeds' pixels.
@group(1) @binding(4) var<storage, read_write> tree: array<atomic<u32>>;
// Words 0-5: the valid centres' bounds as order-preserving float bits (min xyz, max xyz: the grid's,
// common/grid.wgsl); 6: the level the seeding steps are at (a counter, seed_next); 7: clusters with a
// sample point.
@group(1) @binding(5) var<storage, read_write> bounds: array<atomic<u32>, 8>;
// The grid over the centres, its cell counts, offsets within scan blocks and blocks' totals, and
// (below) the centres sorted by cell and each cell's ranges: common/grid.wgsl's (as colom's k-means,
// common/kmeans.wgsl).
@group(1) @binding(6) var<storage, read_write> cells: array<atomic<u32>>;
@group(1) @binding(7) var<storage, read_write> sorted: array<vec4<u32>>;
// the smallest member error (float bits) and the member with it (the sample point), one spare.
@group(1) @binding(8) var<storage, read_write> sums: array<atomic<u32>>;
// Per pixel its cluster (INVALID: none), then per pixel its Eq. (2) error to its centre (bits).
@group(1) @binding(9) var<storage, read_write> labels: array<u32>;
// Two vec4 a cluster: centre position (w = 1 while it has members), mean normal.
@group(1) @binding(10) var<storage, read_write> centres: array<vec4<f32>>;
// Two vec4 a cluster: its sample point (w = 1 when it has one), normal (what wang.wgsl reads).
@group(1) @binding(11) var<storage, read_write> samples: array<vec4<f32>>;
// Four vec4 a cluster: the sample point as a shading point of albedo 1 (what reference.wgsl gathers).
@group(1) @binding(12) var<storage, read_write> sample_gbuffer: array<vec4<f32>>;
// Each cell's slots in `sorted`: [first, end).
@group(1) @binding(13) var<storage, read_write> ranges: array<vec4<u32>>;
@group(1) @binding(16) var<storage, read_write> grid: Grid;
// Where the search reads the grid (the result is the same). true (software adapters): the textures
// below, copied from `sorted` and `ranges` after each grid build (lavapipe fetches a texel per lane
// with vector code but reads storage per lane in a scalar loop); false (GPUs): the storage buffers.
// As colom's k-means (common/kmeans.wgsl).
override TEXTURE_SEARCH: bool = true;
@group(1) @binding(14) var sorted_tex: texture_2d<u32>;
@group(1) @binding(15) var ranges_tex: texture_2d<u32>;

const LEVEL: u32 = 6u;
const USED: u32 = 7u;
const WORDS: u32 = 16u;

// Eq. (2) of §3.2 (twin: method::wang::twin::eq2_error; wang.wgsl has the same).
fn eq2_error(xi: vec3<f32>, ni: vec3<f32>, xk: vec3<f32>, nk: vec3<f32>) -> f32 {
    return params.alpha * length(xi - xk) + sqrt(max(0.0, 2.0 - 2.0 * dot(ni, nk)));
}

// The image pixel of grid pixel (x, y), INVALID outside the grid image.
fn grid_pixel(x: u32, y: u32) -> u32 {
    if x >= params.gw || y >= params.gh {
        return INVALID;
    }
    return y * params.step * params.width + x * params.step;
}

// Grid pixel (x, y)'s image pixel when it has a shading point, else INVALID.
fn valid_pixel(x: u32, y: u32) -> u32 {
    let m = grid_pixel(x, y);
    if m == INVALID || gbuffer[m].pos.w <= 0.0 {
        return INVALID;
    }
    return m;
}
