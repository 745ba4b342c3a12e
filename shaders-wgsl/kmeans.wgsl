// Algorithms 1 and 2 of the paper: GPU k-means of surface points (position, normal) with a uniform grid
// over the centroids, the distance of Eq. (7), and the final fuzzy assignment with inverse-distance
// weights (Eq. 10). One implementation for shading points and VPLs: points are read from `data` with a
// stride (in vec4s) so the G-buffer and the VPL array are both used in place. CPU twin: src/cpu/kmeans.rs.
#import common/chunk.wgsl

const INVALID: u32 = 0xffffffffu;
const BIG: f32 = 3.4028235e38;
const MAX_F: u32 = 16u;
const MAX_DIM: u32 = 64u;
const MAX_CELLS: u32 = MAX_DIM * MAX_DIM * MAX_DIM;
// F of the pipeline (params.f; src/gi/kmeans.rs builds one pipeline set per F in use): loops over the
// F slots of a point have a constant trip count, so its list lives in registers.
override F: u32 = 1u;
// Where the nearest-centroid search reads the grid (the result is the same). true (software
// adapters): the textures below, and a candidate's normal only when it would enter the list (lavapipe
// fetches a texel per lane with vector code but reads storage per lane in a scalar loop, and pays for
// every fetch). false (GPUs): the storage buffers, the normal loaded with the position (both cached;
// a thread's chain of dependent loads sets the time there: 13% less in assign_sampled on an H100).
override TEXTURE_SEARCH: bool = true;
// Whether final_assign applies the plane gate (params.plane_gate <= 1; src/gi/kmeans.rs builds the
// pipelines with it on only when asked, so the default frame pays nothing for it).
override PLANE_GATE: bool = false;
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
    // The plane gate of the final assignment: sin of its angle, 2 when off (src/gi/kmeans.rs).
    plane_gate: f32,
    _p1: u32,
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

// The grid over the centroids (written by grid_setup).
struct Grid {
    origin: vec3<f32>,
    cell: f32,
    dims: vec3<u32>,
    num_cells: u32,
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
// centroids warm_centroids kept (11).
@group(1) @binding(5) var<storage, read_write> bounds: array<atomic<u32>, 12>;
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
// grid_scan_ranges each cell's offsets. On a software adapter (TEXTURE_SEARCH) src/gi/kmeans.rs
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

// Texel i of a data texture: 4096 texels a row (DATA_ROW in src/gi/dispatch.rs).
fn texel_xy(i: u32) -> vec2<u32> {
    return vec2<u32>(i & 4095u, i >> 12u);
}

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

// Eq. (7): dist(d1, d2) = |p1 - p2| when n1 · n2 > n_t, else ∞. The search (scan_slots) takes the
// distance first and this test only for a candidate that would enter the list.
fn eq7_normals_agree(n: vec3<f32>, nc: vec3<f32>) -> bool {
    return dot(n, nc) > params.normal_threshold;
}

// Order-preserving map of floats to u32 (for atomicMin/Max on floats).
fn float_key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn key_float(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

fn cell_coord(p: vec3<f32>) -> vec3<i32> {
    let c = floor((p - grid.origin) / grid.cell);
    let hi = vec3<f32>(grid.dims) - 1.0;
    return vec3<i32>(clamp(c, vec3<f32>(0.0), hi));
}

fn cell_index(c: vec3<i32>) -> u32 {
    let d = grid.dims;
    return (u32(c.z) * d.y + u32(c.y)) * d.x + u32(c.x);
}

// --- Alg. 1 line 2: initial centroids, stratified over the (sampled) data: centroid k takes the
// first valid sampled point of stratum k of the sampled sequence.
fn stratum_centroid(k: u32) -> Centroid {
    let s0 = u32(u64_mul_div(k, params.num_sampled, params.k));
    let s1 = max(u32(u64_mul_div(k + 1u, params.num_sampled, params.k)), s0 + 1u);
    var c: Centroid;
    c.pos = vec4<f32>(0.0);
    c.nrm = vec4<f32>(0.0, 0.0, 1.0, 0.0);
    for (var s = s0; s < min(s1, params.num_sampled); s++) {
        let m = sample_index(s);
        let p = point_pos(m);
        if p.w > 0.0 {
            c.pos = vec4<f32>(p.xyz, 1.0);
            c.nrm = vec4<f32>(point_nrm(m), 0.0);
            break;
        }
    }
    return c;
}

fn set_initial(k: u32, c: Centroid) {
    if c.pos.w == 0.0 {
        name_empty(k, 0u);
    }
    centroids[k] = c;
    add_to_bounds(c);
}

@compute @workgroup_size(64)
fn init_centroids(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    set_initial(k, stratum_centroid(k));
}

// Temporal warm start (not in the paper; its §5 names temporal coherence as future work): Alg. 1
// starts from the previous frame's clusters, whose centroids and representative points the host
// copied into `centroids` and `rep_points` [0, previous K). A previous cluster is kept where the new
// view still sees its representative (a real surface point, unlike the centroid, which may float
// between parallel surfaces of one cluster): warm_keeps. Its representative becomes a candidate for
// reuse (rep_store). Every other cluster starts from its stratum as in init_centroids. Counts the
// kept ones in bounds[11].
@compute @workgroup_size(64)
fn warm_centroids(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    if k < params.warm_size.z {
        let c = centroids[k];
        let r = rep_points[2u * k];
        let rn = rep_points[2u * k + 1u];
        let seen = params.warm_size.x == 0u || (r.w > 0.0 && warm_keeps(r.xyz, rn.xyz));
        if c.pos.w > 0.0 && seen {
            atomicAdd(&bounds[11], 1u);
            rep_points[2u * k + 1u] = vec4<f32>(rn.xyz, 1.0);
            set_initial(k, c);
            return;
        }
    }
    rep_points[2u * k + 1u].w = 0.0;
    set_initial(k, stratum_centroid(k));
}

// A surface point of the previous frame (position q, normal nq) is still seen by the new view when it
// projects into the image, the pixel there has a shading point whose normal agrees with nq by Eq. (7),
// and q lies on that point's tangent plane within eye.w times the point's eye distance (a point now
// hidden behind nearer geometry lies farther off).
fn warm_keeps(q: vec3<f32>, nq: vec3<f32>) -> bool {
    let w = params.warm_size.x;
    let h = params.warm_size.y;
    let v = q - params.warm_eye.xyz;
    let z = dot(v, params.warm_forward.xyz);
    if !(z > 0.0) {
        return false;
    }
    let r = params.warm_right.xyz;
    let u = params.warm_up.xyz;
    let sx = dot(v, r) / (z * dot(r, r));
    let sy = dot(v, u) / (z * dot(u, u));
    let x = (sx + 1.0) * 0.5 * f32(w);
    let y = (1.0 - sy) * 0.5 * f32(h);
    if !(x >= 0.0 && y >= 0.0 && x < f32(w) && y < f32(h)) {
        return false;
    }
    let m = min(u32(y), h - 1u) * w + min(u32(x), w - 1u);
    if m >= params.num_points {
        return false;
    }
    let p = point_pos(m);
    if p.w <= 0.0 {
        return false;
    }
    let n = point_nrm(m);
    if !eq7_normals_agree(n, nq) {
        return false;
    }
    let tol = params.warm_eye.w * length(p.xyz - params.warm_eye.xyz);
    return abs(dot(n, q - p.xyz)) <= tol;
}

// floor(a * b / c) without 32-bit overflow for a, b < 2^32 (a < c).
fn u64_mul_div(a: u32, b: u32, c: u32) -> f32 {
    return floor(f32(a) * (f32(b) / f32(c)));
}

// --- Alg. 1 line 5: the grid over the centroids. Step 1: bounds of the valid centroids, gathered
// where the centroids are written (init_centroids, update) so the grid needs no pass of its own.
fn add_to_bounds(c: Centroid) {
    if c.pos.w <= 0.0 {
        return;
    }
    // Only the atomics that can change the bound: K atomics on six words serialise on a GPU.
    for (var a = 0u; a < 3u; a++) {
        let key = float_key(c.pos[a]);
        if key < atomicLoad(&bounds[a]) {
            atomicMin(&bounds[a], key);
        }
        if key > atomicLoad(&bounds[3u + a]) {
            atomicMax(&bounds[3u + a], key);
        }
    }
}

// Step 2 (one invocation): cell size from the centroids' spread. Centroids lie on surfaces, so the
// cell edge is 1.5x the spacing of K points spread over the bounds' surface area; at most 64 cells per
// axis. Also resets the bounds for the next iteration.
@compute @workgroup_size(1)
fn grid_setup() {
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        lo[a] = key_float(atomicLoad(&bounds[a]));
        hi[a] = key_float(atomicLoad(&bounds[3u + a]));
        atomicStore(&bounds[a], 0xffffffffu);
        atomicStore(&bounds[3u + a], 0u);
    }
    // Whether the iteration that follows changes any assignment (assign_sampled) or re-seeds a
    // cluster (update), and whether it finds an orphan.
    atomicStore(&bounds[6], 0u);
    atomicStore(&bounds[8], 0u);
    // Grid builds so far: the iteration's number (1 in the first) for the re-seeding draw.
    let iteration = atomicAdd(&bounds[7], 1u) + 1u;
    // The empty cluster this iteration's update will name (the previous update's stays readable).
    atomicStore(&bounds[9u + (iteration & 1u)], 0u);
    if !(lo.x <= hi.x) {
        // No valid centroid: one cell.
        lo = params.lo.xyz;
        hi = params.lo.xyz + params.ext.xyz;
    }
    let e = max(hi - lo, vec3<f32>(0.0));
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    let spacing = sqrt(area / f32(max(params.k, 1u)));
    let emax = max(e.x, max(e.y, e.z));
    let floor_cell = max(emax / f32(MAX_DIM), 1e-7 * max(params.ext.w, 1e-30));
    let cell = max(1.5 * spacing, floor_cell);
    let dims = clamp(vec3<u32>(ceil(e / cell)), vec3<u32>(1u), vec3<u32>(MAX_DIM));
    grid.origin = lo;
    grid.cell = cell;
    grid.dims = dims;
    grid.num_cells = dims.x * dims.y * dims.z;
}

// Step 3: count centroids per cell. The counts are 0 before every grid build: the buffer starts at
// zero and grid_scatter counts each cell back down to 0 (no clearing pass).
@compute @workgroup_size(64)
fn grid_count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    let c = centroids[k];
    if c.pos.w <= 0.0 {
        return;
    }
    atomicAdd(&cells[cell_index(cell_coord(c.pos.xyz))], 1u);
}

// Step 4: exclusive prefix sum of the counts into the offsets off[c], in blocks of SCAN_BLOCK cells
// (256 invocations x 4 cells), then per cell the texel (off[c - 1], off[c], off[c + 1], off[c + 2]) of
// `ranges` (off[-1] = 0, off[c] = the total past the last cell): one fetch gives a row run of three
// cells around c (scan_ring1). Two passes; a workgroup takes blocks wid, wid + groups, ..., so any
// number of workgroups gives the same sums. Only the GPU knows the cell count: the host dispatches
// about one workgroup a block from an estimate (src/gi/kmeans.rs, scan_groups). A single workgroup
// walking all cells cost 0.6 ms a grid build at 94k cells on an H100; a fixed 256 workgroups, mostly
// idle, cost lavapipe 4 ms a grid build at 720 cells.
const SCAN_BLOCK: u32 = 1024u;
// Where the blocks' totals go in `cells` (after the counts and the offsets within blocks).
const BLOCK_SUMS: u32 = 2u * MAX_CELLS;

var<workgroup> partial: array<u32, 256>;
var<workgroup> wg_cells: u32;

// The grid's cell count as a workgroup-uniform value (a storage value is not one under WGSL's rules for
// barriers, and the block loops hold barriers).
fn workgroup_cells(t: u32) -> u32 {
    if t == 0u {
        wg_cells = grid.num_cells;
    }
    return workgroupUniformLoad(&wg_cells);
}

// Inclusive prefix sum of partial[0..256) in place (Hillis-Steele); every invocation of the
// workgroup calls it.
fn scan_partial(t: u32) {
    workgroupBarrier();
    for (var d = 1u; d < 256u; d <<= 1u) {
        var v = 0u;
        if t >= d {
            v = partial[t - d];
        }
        workgroupBarrier();
        partial[t] += v;
        workgroupBarrier();
    }
}

// Step 4a: each cell's offset within its block (at MAX_CELLS + c) and each block's total (at
// BLOCK_SUMS + b).
@compute @workgroup_size(256)
fn grid_scan_blocks(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let n = workgroup_cells(t);
    for (var block = wid.x; block * SCAN_BLOCK < n; block += groups.x) {
        let c0 = block * SCAN_BLOCK + 4u * t;
        var counts = vec4<u32>(0u);
        for (var i = 0u; i < 4u; i++) {
            if c0 + i < n {
                counts[i] = atomicLoad(&cells[c0 + i]);
            }
        }
        let s = counts.x + counts.y + counts.z + counts.w;
        partial[t] = s;
        scan_partial(t);
        var run = partial[t] - s;
        for (var i = 0u; i < 4u; i++) {
            if c0 + i < n {
                atomicStore(&cells[MAX_CELLS + c0 + i], run);
            }
            run += counts[i];
        }
        if t == 255u {
            atomicStore(&cells[BLOCK_SUMS + block], partial[255]);
        }
        // (No barrier needed before the next block: after the scan an invocation reads only its own
        // slot, and scan_partial begins with one.)
    }
}

// off[j] once partial holds the inclusive prefix sum of the blocks' totals.
fn cell_offset(j: i32, n: u32, total: u32) -> u32 {
    if j < 0 {
        return 0u;
    }
    let u = u32(j);
    if u >= n {
        return total;
    }
    let block = u / SCAN_BLOCK;
    var before = 0u;
    if block > 0u {
        before = partial[block - 1u];
    }
    return atomicLoad(&cells[MAX_CELLS + u]) + before;
}

// Step 4b: every workgroup sums the blocks' totals itself (at most 256, so no third pass) and writes
// the texels of its blocks. It only reads the offsets within blocks, so no workgroup waits for another.
@compute @workgroup_size(256)
fn grid_scan_ranges(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let n = workgroup_cells(t);
    if wid.x * SCAN_BLOCK >= n {
        return;
    }
    let blocks = (n + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    var s = 0u;
    if t < blocks {
        s = atomicLoad(&cells[BLOCK_SUMS + t]);
    }
    partial[t] = s;
    scan_partial(t);
    let total = partial[255];
    for (var block = wid.x; block < blocks; block += groups.x) {
        for (var i = 0u; i < 4u; i++) {
            let c = block * SCAN_BLOCK + i * 256u + t;
            if c < n {
                let j = i32(c);
                ranges[c] = vec4<u32>(
                    cell_offset(j - 1, n, total),
                    cell_offset(j, n, total),
                    cell_offset(j + 1, n, total),
                    cell_offset(j + 2, n, total)
                );
            }
        }
    }
}

// Step 5: scatter centroid indices into their cells' ranges, counting each cell back down to 0 (the
// order within a cell does not matter: the search orders candidates by (distance, index)).
@compute @workgroup_size(64)
fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    let c = centroids[k];
    if c.pos.w <= 0.0 {
        return;
    }
    let cell = cell_index(cell_coord(c.pos.xyz));
    let slot = ranges[cell].y + atomicSub(&cells[cell], 1u) - 1u;
    sorted[2u * slot] = vec4<u32>(bitcast<vec3<u32>>(c.pos.xyz), k);
    sorted[2u * slot + 1u] = bitcast<vec4<u32>>(c.nrm);
}

// The F nearest centroids of a point by Eq. (7) among the 27 cells around it (Alg. 2 lines 4-17).
// Falls back, in order, to: rings of cells further out, up to FINAL_RINGS, with the same metric; then
// the nearest centroid by position alone (ignoring n_t) in the first ring that holds one, so no point
// is ever left unassigned.
struct Nearest {
    idx: array<u32, MAX_F>,
    dist: array<f32, MAX_F>,
    count: u32,
}

// Candidates are ordered by (distance, index), so the result does not depend on the order in which
// the cells' centroids are visited (the scatter's order is not deterministic).
fn before(r: f32, k: u32, rd: f32, rk: u32) -> bool {
    return r < rd || (r == rd && k < rk);
}

// Alg. 2 lines 9-17: put candidate (k, r) into the sorted list, the farthest falls off the end. Written
// as one compare-and-swap per slot over the pipeline's F slots (a constant, see `F`), so the list
// stays in registers: shifting at a run-time index made it memory on a GPU and a per-lane scatter on
// lavapipe. `slots` is F, or 1 for the fallback by position alone. Empty slots hold (BIG, INVALID),
// after every real candidate.
fn insert(best: ptr<function, Nearest>, k_in: u32, r_in: f32, slots: u32) {
    var k = k_in;
    var r = r_in;
    if (*best).count < slots {
        (*best).count += 1u;
    }
    for (var j = 0u; j < F; j++) {
        if j < slots && before(r, k, (*best).dist[j], (*best).idx[j]) {
            let tk = (*best).idx[j];
            let tr = (*best).dist[j];
            (*best).idx[j] = k;
            (*best).dist[j] = r;
            k = tk;
            r = tr;
        }
    }
}

fn empty_nearest() -> Nearest {
    var b: Nearest;
    b.count = 0u;
    for (var j = 0u; j < MAX_F; j++) {
        b.idx[j] = INVALID;
        b.dist[j] = BIG;
    }
    return b;
}

struct Slot {
    r: f32,
    k: u32,
}

// Slot f - 1 of the list: the candidate a new one must beat; (BIG, INVALID) while the list is short.
fn last_slot(best: ptr<function, Nearest>, f: u32) -> Slot {
    var last = Slot((*best).dist[0], (*best).idx[0]);
    for (var j = 1u; j < F; j++) {
        if j < f {
            last = Slot((*best).dist[j], (*best).idx[j]);
        }
    }
    return last;
}

// Cell i's texel (off[i - 1], off[i], off[i + 1], off[i + 2]) (see TEXTURE_SEARCH).
fn cell_texel(i: u32) -> vec4<u32> {
    if TEXTURE_SEARCH {
        return textureLoad(ranges_tex, texel_xy(i), 0);
    }
    return ranges[i];
}

// The candidates in sorted slots [a.x, a.y) then [b.x, b.y): runs of cells (cells along x are
// consecutive in the sorted order, so a run of a row is one range). One loop for both runs: on
// lavapipe's masked SIMD every copy of this loop costs its lanes' longest trip.
fn scan_slots(best: ptr<function, Nearest>, p: vec3<f32>, n: vec3<f32>, a: vec2<u32>, b: vec2<u32>, f: u32, use_normals: bool) {
    let len_a = a.y - a.x;
    let len = len_a + (b.y - b.x);
    for (var t = 0u; t < len; t++) {
        let i = select(b.x + (t - len_a), a.x + t, t < len_a);
        var c: vec4<u32>;
        var nk: vec4<f32>;
        if TEXTURE_SEARCH {
            c = textureLoad(sorted_tex, texel_xy(2u * i), 0);
        } else {
            c = sorted[2u * i];
            nk = bitcast<vec4<f32>>(sorted[2u * i + 1u]);
        }
        let k = c.w;
        let r = length(p - bitcast<vec3<f32>>(c.xyz));
        // Eq. (7) is the distance or nothing: a candidate that would not enter the list needs no
        // normal (half the texel fetches; the same result as testing the normal first).
        // Would it enter the list?
        let last = last_slot(best, f);
        if !(r < BIG) || !before(r, k, last.r, last.k) {
            continue;
        }
        if use_normals {
            if TEXTURE_SEARCH {
                nk = bitcast<vec4<f32>>(textureLoad(sorted_tex, texel_xy(2u * i + 1u), 0));
            }
            if !eq7_normals_agree(n, nk.xyz) {
                continue;
            }
        }
        insert(best, k, r, f);
    }
}

// Ring 1 (the 27 cells around c) nearest first, skipping every cell whose box is farther from p than
// the list's last slot: the centre cell, then the two other cells of its row, then the 8 other rows
// (the 4 sharing a face with the centre first). A skipped cell holds no centroid that could enter the
// list, so the result is the full scan's; a full list usually needs 3 of the 9 rows. The margin
// (1e-4 cell) covers the rounding of cell_coord at cell faces.
fn scan_ring1(best: ptr<function, Nearest>, p: vec3<f32>, n: vec3<f32>, c: vec3<i32>, f: u32, use_normals: bool) {
    let d = vec3<i32>(grid.dims);
    let lower = grid.origin + vec3<f32>(c) * grid.cell;
    // Distance from p to the centre cell's lower and upper faces (0 where p lies outside the grid).
    let g_lo = max(p - lower, vec3<f32>(0.0));
    let g_hi = max(lower + grid.cell - p, vec3<f32>(0.0));
    let margin = 1e-4 * grid.cell;
    for (var item = 0u; item < 10u; item++) {
        // Row offsets of items 2..9 as 2-bit codes (0, 1, 2 = -1, 0, +1): (dy, dz) = (-1, 0), (1, 0),
        // (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1).
        let j = 2u * max(item, 2u) - 4u;
        let dy = select(0, i32((0x8858u >> j) & 3u) - 1, item >= 2u);
        let dz = select(0, i32((0xa085u >> j) & 3u) - 1, item >= 2u);
        let y = c.y + dy;
        let z = c.z + dz;
        if y < 0 || y >= d.y || z < 0 || z >= d.z {
            continue;
        }
        let gy = select(select(0.0, g_hi.y, dy > 0), g_lo.y, dy < 0);
        let gz = select(select(0.0, g_hi.z, dz > 0), g_lo.z, dz < 0);
        let gyz = gy * gy + gz * gz;
        let cut = last_slot(best, f).r + margin;
        let cut2 = cut * cut;
        if gyz > cut2 {
            continue;
        }
        let left = c.x > 0 && gyz + g_lo.x * g_lo.x <= cut2;
        let right = c.x + 1 < d.x && gyz + g_hi.x * g_hi.x <= cut2;
        // (off[c - 1], off[c], off[c + 1], off[c + 2]) around the row's centre column.
        let o = cell_texel(cell_index(vec3<i32>(c.x, y, z)));
        var a = vec2<u32>(select(o.y, o.x, left), select(o.z, o.w, right));
        var b = vec2<u32>(0u);
        if item == 0u {
            a = o.yz;
        } else if item == 1u {
            a = select(vec2<u32>(0u), o.xy, left);
            b = select(vec2<u32>(0u), o.zw, right);
        }
        scan_slots(best, p, n, a, b, f, use_normals);
    }
}

// Scans the cells at Chebyshev distance exactly `ring` (2 or more; ring 1 is scan_ring1) from `c` a row
// at a time: a full run on the rows of its top, bottom, front and back faces and the two end cells of
// the other rows. The result does not depend on the visiting order (`before`).
fn scan_ring(best: ptr<function, Nearest>, p: vec3<f32>, n: vec3<f32>, c: vec3<i32>, ring: i32, f: u32, use_normals: bool) {
    let d = vec3<i32>(grid.dims);
    let lo = max(c - vec3<i32>(ring), vec3<i32>(0));
    let hi = min(c + vec3<i32>(ring), d - 1);
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            let row = cell_index(vec3<i32>(0, y, z));
            var a: vec2<u32>;
            var b = vec2<u32>(0u);
            if abs(y - c.y) == ring || abs(z - c.z) == ring {
                a = vec2<u32>(
                    cell_texel(row + u32(lo.x)).y,
                    cell_texel(row + u32(hi.x)).z
                );
            } else {
                // The row's two end cells (either may lie outside the grid: an empty run).
                a = vec2<u32>(0u);
                if c.x - ring >= 0 {
                    a = cell_texel(row + u32(c.x - ring)).yz;
                }
                if c.x + ring < d.x {
                    b = cell_texel(row + u32(c.x + ring)).yz;
                }
            }
            scan_slots(best, p, n, a, b, f, use_normals);
        }
    }
}

// Rings searched with Eq. (7) in the final assignment before the fallback by position alone. Further
// out the nearest compatible centroid is several cluster spacings away; scanning for it could visit
// the whole grid (64^3 cells), and on a GPU the few points that did set the time of the pass (213 ms
// for K = 30000 in the breakfast room at 1024x720).
const FINAL_RINGS: i32 = 4;

fn nearest(p: vec3<f32>, n: vec3<f32>, f: u32) -> Nearest {
    var best = empty_nearest();
    let c = cell_coord(p);
    scan_ring1(&best, p, n, c, f, true);
    if best.count == 0u {
        let maxr = i32(max(grid.dims.x, max(grid.dims.y, grid.dims.z)));
        for (var ring = 2; ring <= min(FINAL_RINGS, maxr) && best.count == 0u; ring++) {
            scan_ring(&best, p, n, c, ring, f, true);
        }
        if best.count == 0u {
            scan_ring1(&best, p, n, c, 1u, false);
            for (var ring = 2; ring <= maxr && best.count == 0u; ring++) {
                scan_ring(&best, p, n, c, ring, 1u, false);
            }
        }
    }
    return best;
}

// Rings searched while iterating (Alg. 1 line 8). A sampled point with no centroid passing n_t within
// ITER_RINGS rings is at distance ∞ from every centroid near it (Eq. 7) and stays out of this
// iteration's update; the final assignment still finds it one. Without the bound, a few such points
// scan the whole grid every iteration and the slowest of them sets the time of the pass on a GPU.
const ITER_RINGS: i32 = 3;

fn nearest_bounded(p: vec3<f32>, n: vec3<f32>) -> u32 {
    var best = empty_nearest();
    let c = cell_coord(p);
    scan_ring1(&best, p, n, c, 1u, true);
    for (var ring = 2; ring <= ITER_RINGS && best.count == 0u; ring++) {
        scan_ring(&best, p, n, c, ring, 1u, true);
    }
    return best.idx[0];
}

// Before the first iteration: no sampled point has a cluster yet (its sums are all zero).
@compute @workgroup_size(64)
fn init_sampled(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let s = chunk_item(gid, nwg);
    if s == INVALID || s >= params.num_sampled {
        return;
    }
    sample_assign[s] = INVALID;
}

// --- Alg. 1 lines 6-11: assign each sampled point to its nearest centroid. Lines 12-16 (the sums of
// the members' positions and normals) are kept up to date here: a point that changed cluster leaves
// the old cluster's sums and joins the new one's. Integer sums do not depend on the order of the
// additions, so they equal summing all members afresh (the CPU twin does that), and an iteration
// late in the run touches only the few points that moved.
@compute @workgroup_size(64)
fn assign_sampled(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let s = chunk_item(gid, nwg);
    if s == INVALID || s >= params.num_sampled {
        return;
    }
    let m = sample_index(s);
    let p = point_pos(m);
    var k = INVALID;
    if p.w > 0.0 {
        k = nearest_bounded(p.xyz, point_nrm(m));
    }
    if p.w > 0.0 && k == INVALID {
        propose_reseed(s);
    }
    let old = sample_assign[s];
    if old != k {
        // Alg. 1 stops early when no assignment changed: the centroids would not change either. A
        // flag, set once: an atomicAdd per moved point all on one word serialised the first
        // iterations on a GPU.
        set_flag(6u);
        if old != INVALID {
            add_member(old, m, true);
        }
        if k != INVALID {
            add_member(k, m, false);
        }
        sample_assign[s] = k;
    }
}

// Sets flag word i of `bounds` to 1. Loaded first: an atomic per point all on one word serialised
// the first iterations on a GPU.
fn set_flag(i: u32) {
    if atomicLoad(&bounds[i]) == 0u {
        atomicStore(&bounds[i], 1u);
    }
}

// 64-bit unsigned add into words (i, i + 1) from 32-bit atomics: a carry is exact because atomicAdd
// returns the value it added to.
fn add64(i: u32, v: u32) {
    let old = atomicAdd(&sums[i], v);
    if old > 0xffffffffu - v {
        atomicAdd(&sums[i + 1u], 1u);
    }
}

// 64-bit subtract: adds 2^64 - v, i.e. 2^32 - v to the low word (with its carry) and 2^32 - 1 to the
// high one. Sums wrap modulo 2^64 and end exact once every addition of a pass is in.
fn sub64(i: u32, v: u32) {
    if v != 0u {
        add64(i, 0u - v);
        atomicAdd(&sums[i + 1u], 0xffffffffu);
    }
}

// Adds (or removes) point m's position and normal to cluster k's fixed-point sums and count.
fn add_member(k: u32, m: u32, remove: bool) {
    let rel = clamp((point_pos(m).xyz - params.lo.xyz) / params.ext.xyz, vec3<f32>(0.0), vec3<f32>(1.0));
    let q = vec3<u32>(rel * POS_SCALE);
    let nq = vec3<u32>(clamp(point_nrm(m) + 1.0, vec3<f32>(0.0), vec3<f32>(2.0)) * NRM_SCALE);
    let base = k * WORDS;
    for (var a = 0u; a < 3u; a++) {
        if remove {
            sub64(base + 2u * a, q[a]);
            sub64(base + 6u + 2u * a, nq[a]);
        } else {
            add64(base + 2u * a, q[a]);
            add64(base + 6u + 2u * a, nq[a]);
        }
    }
    if remove {
        atomicSub(&sums[base + 12u], 1u);
    } else {
        atomicAdd(&sums[base + 12u], 1u);
    }
}

fn mean64(i: u32, count: u32) -> f32 {
    let lo = atomicLoad(&sums[i]);
    let hi = atomicLoad(&sums[i + 1u]);
    return (f32(hi) * 4294967296.0 + f32(lo)) / f32(count);
}

// --- Empty clusters and orphans. A sampled point with no centroid passing n_t within ITER_RINGS is
// an orphan: Eq. (7) puts it at distance ∞ from every centroid near it. Alg. 1 only moves the
// centroids it starts with, so a surface no initial centroid fell on (a narrow face, a small object)
// would keep none and its pixels would get the fallback's clusters, on surfaces facing elsewhere
// (docs/clustering.md, "Surfaces without a cluster"). So an empty cluster is re-seeded at an orphan,
// as k-means implementations re-seed empty clusters: each orphan proposes itself to one cluster
// drawn from its index and the iteration (a hash; another draw each iteration), the cluster keeps
// the lowest-index proposal (an atomic max of ~s: deterministic, whatever the order), and `update`
// re-seeds the cluster there if it is empty. The proposals live in reps[2k], free until the final
// assignment (rep_clear), as ~s with 0 for none (the buffer starts at 0).
//
// An iteration that finds no orphan re-seeds its empty clusters at sampled points drawn from the
// cluster's index and the iteration (`reseed_draw`; a draw that falls on an invalid point, the
// background, or on a cluster's only member leaves the cluster empty until a later iteration). So K clusters are K clusters: the
// strata of the initial centroids that lie on the background, and clusters that lose every member,
// are put to use (the Cornell box at 640x480, K 3072, kept 491 empty). While orphans remain, the
// empty clusters wait for them. CPU twin: cpu::kmeans::reseed_target, reseed_draw and the loop in
// cpu::kmeans::kmeans.
fn reseed_mix(x: u32) -> u32 {
    var h = x + atomicLoad(&bounds[7]) * 2891336453u + params.seed * 1442695041u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    return (h >> 22u) ^ h;
}

fn reseed_target(s: u32) -> u32 {
    return reseed_mix(s * 747796405u) % params.k;
}

fn reseed_draw(k: u32) -> u32 {
    return reseed_mix(k * 2654435761u + 1013904223u) % params.num_sampled;
}

fn propose(t: u32, s: u32) {
    let key = ~s;
    if key > atomicLoad(&reps[2u * t]) {
        atomicMax(&reps[2u * t], key);
    }
}

// Besides its drawn cluster, every orphan proposes itself to the empty cluster the last update (or
// init_centroids) named, so that one empty cluster a round goes to an orphan however few of either
// there are (a draw among K clusters rarely hits one of a few empty ones).
fn propose_reseed(s: u32) {
    set_flag(8u);
    let t = reseed_target(s);
    propose(t, s);
    let e = last_empty();
    if e != INVALID && e != t {
        propose(e, s);
    }
}

// The highest-index cluster left empty by the last update (by init_centroids before the first
// iteration), INVALID for none. Iteration i's update names its own in word 9 + (i & 1), which
// grid_setup cleared; this reads the other.
fn last_empty() -> u32 {
    return atomicLoad(&bounds[9u + ((atomicLoad(&bounds[7]) + 1u) & 1u)]) - 1u;
}

fn name_empty(k: u32, iteration: u32) {
    let i = 9u + (iteration & 1u);
    if k + 1u > atomicLoad(&bounds[i]) {
        atomicMax(&bounds[i], k + 1u);
    }
}

// --- Alg. 1 lines 17-18: centroids = mean position and normalised mean normal (the sums stay: the
// next assignment updates them). An empty cluster is re-seeded at the orphan proposed to it, or where
// no orphan was found at a drawn sampled point (above), else keeps its centroid but is marked empty
// (w = 0) and drops out of the grid. A re-seed counts as a change for Alg. 1's early end.
@compute @workgroup_size(64)
fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    let base = k * WORDS;
    let count = atomicLoad(&sums[base + 12u]);
    var c = centroids[k];
    if count > 0u {
        let rel = vec3<f32>(mean64(base, count), mean64(base + 2u, count), mean64(base + 4u, count)) / POS_SCALE;
        let nrm = vec3<f32>(mean64(base + 6u, count), mean64(base + 8u, count), mean64(base + 10u, count)) / NRM_SCALE - 1.0;
        c.pos = vec4<f32>(params.lo.xyz + rel * params.ext.xyz, 1.0);
        let l = length(nrm);
        if l > 1e-6 {
            c.nrm = vec4<f32>(nrm / l, 0.0);
        }
    } else {
        // Its sums are exactly zero (every member left), so the points that join add from 0.
        let proposal = atomicLoad(&reps[2u * k]);
        var m = INVALID;
        if proposal != 0u {
            m = sample_index(~proposal);
        } else if atomicLoad(&bounds[8]) == 0u {
            // The draw must split a cluster: an invalid point has none (in an iteration without
            // orphans every valid sampled point has one), and a cluster's only member would get a
            // second centroid on it, which with K above the valid points re-seeded every empty
            // cluster onto a duplicate every iteration (each then traced its own visibility).
            let s = reseed_draw(k);
            let owner = sample_assign[s];
            if owner != INVALID && atomicLoad(&sums[owner * WORDS + 12u]) > 1u {
                m = sample_index(s);
            }
        }
        if m != INVALID {
            c.pos = vec4<f32>(point_pos(m).xyz, 1.0);
            c.nrm = vec4<f32>(point_nrm(m), 0.0);
            set_flag(6u);
        } else {
            c.pos.w = 0.0;
            name_empty(k, atomicLoad(&bounds[7]));
        }
    }
    atomicStore(&reps[2u * k], 0u);
    centroids[k] = c;
    add_to_bounds(c);
}

// Eq. (10), generalised to w'_f = dist_f^-p (the paper's §6 asks for a faster fall-off under a
// parameter; p = 1 is Eq. 10, p = 0 Eq. 8's mean, large p tends to hard clustering). Computed as
// (d_min / d_f)^p / Σ (d_min / d_f)^p, ratios in (0, 1]: no overflow for any distance or p. Slots at
// or past `count` (and negative distances) get 0; a distance of 0 (`zero`) takes the whole weight.
// CPU twin: cpu::kmeans::inverse_distance_weights.
// A distance at or below this counts as 0 (the point sits on the centroid): below it a GPU may flush
// the quotient d_min / d to 0 / 0.
const ZERO_DIST: f32 = 1e-30;

// x^p for x in (0, 1]: exact for p = 1 (Eq. 10) and p = 0, else exp2(p log2 x).
fn ratio_pow(x: f32, p: f32) -> f32 {
    if p == 1.0 {
        return x;
    }
    if p == 0.0 {
        return 1.0;
    }
    return exp2(p * log2(x));
}

// Slots from F on are 0. Every loop runs over the pipeline's F slots (a constant) with the count as a
// guard, so the arrays stay in registers: a loop to the run-time count indexes them at run time,
// which put them in memory (on lavapipe a per-lane scatter; final_assign spent more time here than in
// its search).
fn inverse_distance_weights(d: array<f32, MAX_F>, count: u32, zero: u32) -> array<f32, MAX_F> {
    var w: array<f32, MAX_F>;
    var d_min = 3.4e38;
    for (var j = 0u; j < F; j++) {
        if j < count && d[j] >= 0.0 {
            d_min = min(d_min, d[j]);
        }
    }
    var wsum = 0.0;
    for (var j = 0u; j < F; j++) {
        if j < count && d[j] >= 0.0 {
            if zero != INVALID {
                w[j] = select(0.0, 1.0, j == zero);
            } else {
                w[j] = ratio_pow(d_min / d[j], params.weight_exponent);
            }
            wsum += w[j];
        }
    }
    if zero == INVALID && wsum > 0.0 {
        for (var j = 0u; j < F; j++) {
            w[j] /= wsum;
        }
    }
    return w;
}

// The plane gate (off unless asked; not in the paper): slot j >= 2 keeps cluster k only when its
// centroid lies within the gate's angle of the point's tangent plane, seen from the point. Eq. (7)
// gates on normals alone, so a pixel's F nearest clusters include parallel surfaces above or below
// it (a chair seat over the floor), whose visibility differs. The first slot is always kept, and a
// centroid on the point (|d| = 0) passes. CPU twin: cpu::kmeans::plane_gate_keeps.
fn plane_gate_keeps(p: vec3<f32>, n: vec3<f32>, k: u32) -> bool {
    let d = centroids[k].pos.xyz - p;
    return abs(dot(n, d)) <= params.plane_gate * length(d);
}

// --- Alg. 2: every data point to its F nearest centroids with normalised inverse-distance weights
// (Eq. 10). A point on a centroid (distance 0) takes that cluster's whole weight.
@compute @workgroup_size(64)
fn final_assign(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID || m >= params.num_points {
        return;
    }
    let f = F;
    let p = point_pos(m);
    var b = empty_nearest();
    var n = vec3<f32>(0.0);
    if p.w > 0.0 {
        n = point_nrm(m);
        b = nearest(p.xyz, n, f);
    }
    var zero = INVALID;
    // A slot the plane gate drops gets distance -1: weight 0 (inverse_distance_weights) and no
    // cluster below. (Off, the pipeline is built without the test: see PLANE_GATE.)
    var dists: array<f32, MAX_F>;
    for (var j = 0u; j < F; j++) {
        dists[j] = b.dist[j];
        if PLANE_GATE && j > 0u && j < b.count && !plane_gate_keeps(p.xyz, n, b.idx[j]) {
            dists[j] = -1.0;
        }
        if j < b.count && b.dist[j] <= ZERO_DIST && zero == INVALID {
            zero = j;
        }
    }
    let w = inverse_distance_weights(dists, b.count, zero);
    for (var j = 0u; j < f; j++) {
        var k = INVALID;
        if j < b.count && dists[j] >= 0.0 {
            k = b.idx[j];
            // Representatives, step 2 (rep_min): the smallest member distance per cluster
            // (non-negative floats order like their bits).
            let bits = bitcast<u32>(b.dist[j]);
            // Only when it can lower the minimum: every member's atomic on its cluster's one word
            // (4.4M on 1000 words at 1024x720, F 6) serialised the pass on a GPU.
            if bits < atomicLoad(&reps[2u * k]) {
                atomicMin(&reps[2u * k], bits);
            }
            member_dists[m * f + j] = bits;
        }
        assign[m * f + j] = k;
        weights[m * f + j] = w[j];
    }
}

// --- Representatives on real surfaces: the member (in any of its F slots) nearest to the centroid.
// Step 1 (before final_assign): clear. reps[2k] = smallest distance (float bits), reps[2k + 1] = member index.
@compute @workgroup_size(64)
fn rep_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    atomicStore(&reps[2u * k], 0xffffffffu);
    atomicStore(&reps[2u * k + 1u], 0xffffffffu);
}

// Step 2 is in final_assign. Step 3: the lowest-index member at that distance (the distance as
// final_assign stored it, not recomputed: a GPU may round one expression differently in two kernels).
@compute @workgroup_size(64)
fn rep_pick(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID || m >= params.num_points {
        return;
    }
    let f = F;
    for (var j = 0u; j < f; j++) {
        let k = assign[m * f + j];
        if k != INVALID && member_dists[m * f + j] == atomicLoad(&reps[2u * k]) {
            atomicMin(&reps[2u * k + 1u], m);
        }
    }
}

// Step 4: the representative as a point for the visibility pass. A cluster the warm start kept keeps
// its previous representative while that point is still one of it: its normal agrees with the
// centroid's by Eq. (7) and it lies within twice this frame's nearest member distance of the centroid
// (so it cannot drift away as the centroid moves); then its visibility stays the same from frame to
// frame. Otherwise the member rep_pick chose.
@compute @workgroup_size(64)
fn rep_store(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k {
        return;
    }
    let m = atomicLoad(&reps[2u * k + 1u]);
    if m == INVALID {
        rep_points[2u * k] = vec4<f32>(0.0);
        rep_points[2u * k + 1u] = vec4<f32>(0.0, 0.0, 1.0, 0.0);
        return;
    }
    let c = centroids[k];
    let r = rep_points[2u * k];
    let rn = rep_points[2u * k + 1u];
    if rn.w == 1.0 && r.w > 0.0 {
        let nearest = bitcast<f32>(atomicLoad(&reps[2u * k]));
        if eq7_normals_agree(rn.xyz, c.nrm.xyz) && length(r.xyz - c.pos.xyz) <= 2.0 * nearest {
            return;
        }
    }
    rep_points[2u * k] = vec4<f32>(point_pos(m).xyz, 1.0);
    rep_points[2u * k + 1u] = vec4<f32>(point_nrm(m), 0.0);
}

// Optional step 5, Eq. (10) as the paper's text states it: w'_f = 1 / dist(p, p_f) with p_f the
// representative of cluster f (a real shading point) instead of its centroid (Alg. 2's W). Replaces the
// weights of final_assign; the same exact case (distance 0 takes the whole weight).
@compute @workgroup_size(64)
fn rep_weights(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID || m >= params.num_points {
        return;
    }
    let f = F;
    let p = point_pos(m).xyz;
    var d: array<f32, MAX_F>;
    var zero = INVALID;
    for (var j = 0u; j < f; j++) {
        let k = assign[m * f + j];
        d[j] = -1.0;
        if k != INVALID {
            let r = atomicLoad(&reps[2u * k + 1u]);
            if r == INVALID {
                continue;
            }
            d[j] = length(p - point_pos(r).xyz);
            if d[j] <= ZERO_DIST && zero == INVALID {
                zero = j;
            }
        }
    }
    let w = inverse_distance_weights(d, f, zero);
    for (var j = 0u; j < f; j++) {
        weights[m * f + j] = w[j];
    }
}
