// wang_cluster: Wang et al. 2009 (seed 001) §3.2 on the GPU, the whole clustering of the shading
// points: the adaptive quadtree seeding, k-means with the Eq. (2) metric over a uniform grid of the
// centres, the centre updates and each cluster's sample point. Driven by src/method/wang/cluster.rs;
// CPU twin: src/cpu/wang.rs (the same steps in the same f32 arithmetic; sums in fixed point, so exact
// and independent of the order of the atomic adds). docs/methods.md, "wang".
//
// The k-means runs on the "grid image": the pixels with x and y multiples of the step g (`step`),
// gw x gh of them (src/method/wang/cluster.rs, grid_step); the last assignment labels every pixel.
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/rng.wgsl
#import common/scan.wgsl

const INVALID: u32 = 0xffffffffu;
const BIG: f32 = 3.4028235e38;
const MAX_DIM: u32 = 64u;
const MAX_CELLS: u32 = MAX_DIM * MAX_DIM * MAX_DIM;
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
// Words 0-5: the valid centres' bounds as order-preserving float bits (min xyz, max xyz); 6: the
// level the seeding steps are at (a counter, seed_next); 7: clusters with a sample point; 8-15: the
// grid (origin xyz and cell as float bits, dims xyz, cells).
@group(1) @binding(5) var<storage, read_write> state: array<atomic<u32>, 16>;
// Cell counts (0 outside a grid build), each cell's offset within its scan block, the scan blocks'
// totals.
@group(1) @binding(6) var<storage, read_write> cells: array<atomic<u32>>;
// The valid centres sorted by cell, two vec4 a slot: position with w = the centre's index (bits),
// normal.
@group(1) @binding(7) var<storage, read_write> sorted: array<vec4<f32>>;
// 16 words a cluster: six 64-bit fixed-point sums (position xyz, normal + 1 xyz), the member count,
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
@group(1) @binding(13) var<storage, read_write> offsets: array<vec2<u32>>;
// Where the search reads the grid (the result is the same). true (software adapters): the textures
// below, copied from `sorted` and `offsets` after each grid build (lavapipe fetches a texel per lane
// with vector code but reads storage per lane in a scalar loop); false (GPUs): the storage buffers.
// As colom's k-means (common/kmeans.wgsl).
override TEXTURE_SEARCH: bool = true;
@group(1) @binding(14) var sorted_tex: texture_2d<f32>;
@group(1) @binding(15) var offsets_tex: texture_2d<u32>;

// Texel i of a data texture: 4096 texels a row (DATA_ROW in src/gi/dispatch.rs).
fn texel_xy(i: u32) -> vec2<u32> {
    return vec2<u32>(i & 4095u, i >> 12u);
}

fn sorted_at(i: u32) -> vec4<f32> {
    if TEXTURE_SEARCH {
        return textureLoad(sorted_tex, texel_xy(i), 0);
    }
    return sorted[i];
}

fn cell_slots(c: u32) -> vec2<u32> {
    if TEXTURE_SEARCH {
        return textureLoad(offsets_tex, texel_xy(c), 0).xy;
    }
    return offsets[c];
}

const LEVEL: u32 = 6u;
const USED: u32 = 7u;
const GRID: u32 = 8u;
const COUNTS: u32 = 0u;
const LOCAL: u32 = MAX_CELLS;
const BLOCK_SUMS: u32 = 2u * MAX_CELLS;
const WORDS: u32 = 16u;

// Eq. (2) of §3.2 (twin: cpu::wang::eq2_error; wang.wgsl has the same).
fn eq2_error(xi: vec3<f32>, ni: vec3<f32>, xk: vec3<f32>, nk: vec3<f32>) -> f32 {
    return params.alpha * length(xi - xk) + sqrt(max(0.0, 2.0 - 2.0 * dot(ni, nk)));
}

// --- The quadtree (§3.2, "Adaptive Seeding of Sample Points").

fn level_base(l: u32) -> u32 {
    return ((1u << (2u * l)) - 1u) / 3u;
}

fn node_index(l: u32, x: u32, y: u32) -> u32 {
    return level_base(l) + (y << l) + x;
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

fn node_count(n: u32) -> u32 {
    return u32(nodes[2u * n].w);
}

// A node's mean position and normalised mean normal (zero when the normals cancel).
struct Mean {
    pos: vec3<f32>,
    nrm: vec3<f32>,
}

fn node_mean(n: u32) -> Mean {
    let s = nodes[2u * n];
    let ns = nodes[2u * n + 1u].xyz;
    let l = length(ns);
    var nrm = vec3<f32>(0.0);
    if l > 0.0 {
        nrm = ns / l;
    }
    return Mean(s.xyz / s.w, nrm);
}

// Level L - 1 (2x2 grid pixels a node): sums of the valid points, in the order (0,0), (1,0), (0,1),
// (1,1); the node's words cleared. Also starts the level counter.
@compute @workgroup_size(64)
fn seed_leaves(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    let l = params.levels - 1u;
    if i == 0u {
        atomicStore(&state[LEVEL], 0u);
    }
    if i >= (1u << (2u * l)) {
        return;
    }
    let x = i & ((1u << l) - 1u);
    let y = i >> l;
    var ps = vec3<f32>(0.0);
    var ns = vec3<f32>(0.0);
    var c = 0.0;
    for (var q = 0u; q < 4u; q++) {
        let m = valid_pixel(2u * x + (q & 1u), 2u * y + (q >> 1u));
        if m != INVALID {
            ps += gbuffer[m].pos.xyz;
            ns += gbuffer[m].nrm.xyz;
            c += 1.0;
        }
    }
    store_node(node_index(l, x, y), ps, ns, c);
}

fn store_node(n: u32, ps: vec3<f32>, ns: vec3<f32>, c: f32) {
    nodes[2u * n] = vec4<f32>(ps, c);
    nodes[2u * n + 1u] = vec4<f32>(ns, 0.0);
    for (var w = 0u; w < 4u; w++) {
        atomicStore(&tree[4u * n + w], 0u);
    }
}

// One level up (levels - 2 - the counter): a node's sums are its four children's, in order.
@compute @workgroup_size(64)
fn seed_up(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    let l = params.levels - 2u - atomicLoad(&state[LEVEL]);
    if i >= (1u << (2u * l)) {
        return;
    }
    let x = i & ((1u << l) - 1u);
    let y = i >> l;
    var ps = vec3<f32>(0.0);
    var ns = vec3<f32>(0.0);
    var c = 0.0;
    for (var q = 0u; q < 4u; q++) {
        let child = node_index(l + 1u, 2u * x + (q & 1u), 2u * y + (q >> 1u));
        let s = nodes[2u * child];
        ps += s.xyz;
        ns += nodes[2u * child + 1u].xyz;
        c += s.w;
    }
    store_node(node_index(l, x, y), ps, ns, c);
}

// The level counter's next value (one invocation between two levels' steps).
@compute @workgroup_size(1)
fn seed_next() {
    atomicAdd(&state[LEVEL], 1u);
}

// Two halves of 256 slots, used by alternate levels: a level's sums are read and cleared before the
// barrier of the next level, which adds into the other half, so one barrier a level.
var<workgroup> acc: array<atomic<u32>, 512>;

// ε_q of every stored node (§3.2: "treating all shading points belonging to quadtree node q as a
// cluster", x_k and n_k its mean position and normal): Eq. (2) of each point against the mean of
// each node holding it, in fixed point, summed first within the workgroup's 16x16 tile of grid
// pixels (a node of 16 or more pixels a side covers the tile: one global add; smaller ones lie
// inside it: one add each), then added into the node's 64-bit sum.
@compute @workgroup_size(256)
fn seed_eps(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let side = 1u << params.levels;
    let tiles_x = max(side / 16u, 1u);
    let tile = wid.x + wid.y * nwg.x;
    if tile >= tiles_x * tiles_x {
        return;
    }
    let x0 = (tile % tiles_x) * 16u;
    let y0 = (tile / tiles_x) * 16u;
    let x = x0 + (t & 15u);
    let y = y0 + (t >> 4u);
    var m = INVALID;
    if x < side && y < side {
        m = valid_pixel(x, y);
    }
    var p = vec3<f32>(0.0);
    var n = vec3<f32>(0.0);
    if m != INVALID {
        p = gbuffer[m].pos.xyz;
        n = gbuffer[m].nrm.xyz;
    }
    atomicStore(&acc[t], 0u);
    atomicStore(&acc[256u + t], 0u);
    workgroupBarrier();
    for (var l = 0u; l < params.levels; l++) {
        let shift = params.levels - l;
        let s = 1u << shift;
        let half = (l & 1u) * 256u;
        var q = 0u;
        if m != INVALID {
            let mean = node_mean(node_index(l, x >> shift, y >> shift));
            q = u32(min(eq2_error(p, n, mean.pos, mean.nrm) * EPS_SCALE, EPS_MAX));
        }
        var slot = 0u;
        var slots = 1u;
        var per_row = 1u;
        if s < 16u {
            per_row = 16u / s;
            slot = ((t >> 4u) / s) * per_row + (t & 15u) / s;
            slots = per_row * per_row;
        }
        if q != 0u {
            atomicAdd(&acc[half + slot], q);
        }
        workgroupBarrier();
        if t < slots {
            let v = atomicExchange(&acc[half + t], 0u);
            let nx = (x0 >> shift) + t % per_row;
            let ny = (y0 >> shift) + t / per_row;
            if v != 0u && nx < (1u << l) && ny < (1u << l) {
                tree_add64(4u * node_index(l, nx, ny), v);
            }
        }
    }
}

// 64-bit unsigned add into words (i, i + 1) from 32-bit atomics: the carry is exact because
// atomicAdd returns the value it added to.
fn tree_add64(i: u32, v: u32) {
    let old = atomicAdd(&tree[i], v);
    if old > 0xffffffffu - v {
        atomicAdd(&tree[i + 1u], 1u);
    }
}

fn sums_add64(i: u32, v: u32) {
    let old = atomicAdd(&sums[i], v);
    if old > 0xffffffffu - v {
        atomicAdd(&sums[i + 1u], 1u);
    }
}

fn eps_weight(n: u32) -> f32 {
    return f32(atomicLoad(&tree[4u * n + 1u])) * 4294967296.0 + f32(atomicLoad(&tree[4u * n]));
}

// Splits k seeds among four children in proportion to their weights (ε_q), each at most its cap (its
// valid points): floors first, then the largest remainders (lowest index on a tie), repeated over the
// children with room until every seed is placed; with no weight anywhere, equal shares. A round that
// leaves seeds fills a child (or, from f32 rounding of the shares, leaves fewer than one), so
// APPORTION_ROUNDS place them all. Twin: cpu::wang::apportion.
const APPORTION_ROUNDS: u32 = 8u;
fn apportion(k: u32, w: vec4<f32>, cap: vec4<u32>) -> vec4<u32> {
    var a = vec4<u32>(0u);
    var left = min(k, cap.x + cap.y + cap.z + cap.w);
    for (var round = 0u; round < APPORTION_ROUNDS; round++) {
        if left == 0u {
            break;
        }
        var wsum = 0.0;
        var open = 0u;
        for (var i = 0u; i < 4u; i++) {
            if a[i] < cap[i] {
                wsum += max(w[i], 0.0);
                open += 1u;
            }
        }
        var rem = vec4<f32>(-1.0);
        var given = 0u;
        for (var i = 0u; i < 4u; i++) {
            if a[i] < cap[i] {
                var share = 1.0 / f32(open);
                if wsum > 0.0 {
                    share = max(w[i], 0.0) / wsum;
                }
                let ideal = f32(left) * share;
                let fl = floor(ideal);
                let f = min(u32(fl), cap[i] - a[i]);
                a[i] += f;
                given += f;
                rem[i] = ideal - fl;
            }
        }
        left -= given;
        // The open children by decreasing remainder, lowest index first on a tie.
        for (var pick = 0u; pick < 4u; pick++) {
            var best = 4u;
            for (var i = 0u; i < 4u; i++) {
                if rem[i] >= 0.0 && (best == 4u || rem[i] > rem[best]) {
                    best = i;
                }
            }
            if best == 4u || left == 0u {
                break;
            }
            rem[best] = -1.0;
            if a[best] < cap[best] {
                a[best] += 1u;
                left -= 1u;
            }
        }
    }
    return a;
}

// The r-th valid point (in Z order: children (0,0), (1,0), (0,1), (1,1) at every level) of node (x, y)
// of level l.
fn nth_point(l_in: u32, x_in: u32, y_in: u32, r_in: u32) -> u32 {
    var x = x_in;
    var y = y_in;
    var r = r_in;
    for (var l = l_in + 1u; l < params.levels; l++) {
        for (var q = 0u; q < 4u; q++) {
            let cx = 2u * x + (q & 1u);
            let cy = 2u * y + (q >> 1u);
            let c = node_count(node_index(l, cx, cy));
            if r < c {
                x = cx;
                y = cy;
                break;
            }
            r -= c;
        }
    }
    for (var q = 0u; q < 4u; q++) {
        let m = valid_pixel(2u * x + (q & 1u), 2u * y + (q >> 1u));
        if m != INVALID {
            if r == 0u {
                return m;
            }
            r -= 1u;
        }
    }
    return INVALID;
}

// §3.2's seeding, one level (the counter less levels - 1) from the root down: the root gets
// min(K, valid points) seeds; a node with as many seeds as points takes them all (seed_pixels), a node
// with one seed draws it uniformly among its points ("jittered sampling ... within the quad"), a node
// of the last stored level with fewer seeds than points takes its first ones (its four points weigh
// nothing: a point is its own mean), and any other node splits its seeds among its children
// (`apportion` by ε_q), each child's seeds following its elder siblings' in the seed order.
@compute @workgroup_size(64)
fn seed_split(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    let l = atomicLoad(&state[LEVEL]) - (params.levels - 1u);
    if i >= (1u << (2u * l)) {
        return;
    }
    let x = i & ((1u << l) - 1u);
    let y = i >> l;
    let n = node_index(l, x, y);
    let count = node_count(n);
    var kn = atomicLoad(&tree[4u * n + 2u]);
    let first = atomicLoad(&tree[4u * n + 3u]);
    if l == 0u {
        kn = min(params.k, count);
        atomicStore(&tree[2u], kn);
    }
    if kn == 0u || kn >= count {
        return;
    }
    if kn == 1u {
        var st = rng_seed(params.seed, n, 0x5eedu);
        let u = rng_next(&st);
        let r = min(u32(u * f32(count)), count - 1u);
        atomicStore(&tree[params.seeds_base + first], nth_point(l, x, y, r));
        return;
    }
    if l + 1u >= params.levels {
        return;
    }
    var w = vec4<f32>(0.0);
    var cap = vec4<u32>(0u);
    var kids: array<u32, 4>;
    for (var q = 0u; q < 4u; q++) {
        kids[q] = node_index(l + 1u, 2u * x + (q & 1u), 2u * y + (q >> 1u));
        w[q] = eps_weight(kids[q]);
        cap[q] = node_count(kids[q]);
    }
    let a = apportion(kn, w, cap);
    var off = first;
    for (var q = 0u; q < 4u; q++) {
        atomicStore(&tree[4u * kids[q] + 2u], a[q]);
        atomicStore(&tree[4u * kids[q] + 3u], off);
        off += a[q];
    }
}

// Grid pixel (x, y)'s rank among the valid points of its node at level l, in Z order.
fn z_rank(l: u32, x: u32, y: u32) -> u32 {
    var r = 0u;
    for (var lc = l + 1u; lc < params.levels; lc++) {
        let shift = params.levels - lc;
        let cx = x >> shift;
        let cy = y >> shift;
        let own = (cy & 1u) * 2u + (cx & 1u);
        for (var q = 0u; q < own; q++) {
            r += node_count(node_index(lc, (cx & ~1u) + (q & 1u), (cy & ~1u) + (q >> 1u)));
        }
    }
    let own = (y & 1u) * 2u + (x & 1u);
    for (var q = 0u; q < own; q++) {
        if valid_pixel((x & ~1u) + (q & 1u), (y & ~1u) + (q >> 1u)) != INVALID {
            r += 1u;
        }
    }
    return r;
}

// The seeds of the nodes that take all their points (and of the last stored level's nodes that take
// their first kn): each valid grid pixel walks down from the root to the node that ends its descent.
// It also leaves its first assignment's hint (`nearest`) after the labels: the first seed of the
// deepest node on its way that got any.
@compute @workgroup_size(64)
fn seed_pixels(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i >= params.gw * params.gh {
        return;
    }
    let x = i % params.gw;
    let y = i / params.gw;
    let m = valid_pixel(x, y);
    if m == INVALID {
        return;
    }
    var hint = 0u;
    for (var l = 0u; l < params.levels; l++) {
        let shift = params.levels - l;
        let n = node_index(l, x >> shift, y >> shift);
        let kn = atomicLoad(&tree[4u * n + 2u]);
        let count = node_count(n);
        let first = atomicLoad(&tree[4u * n + 3u]);
        if kn == 0u {
            break;
        }
        hint = first;
        if kn >= count || l + 1u == params.levels {
            let r = z_rank(l, x, y);
            if r < kn && (kn >= count || kn > 1u) {
                atomicStore(&tree[params.seeds_base + first + r], m);
            }
            break;
        }
        if kn == 1u {
            break;
        }
    }
    labels[params.pixels + m] = hint;
}

// --- The centres.

// Order-preserving map of floats to u32 (atomicMin/Max on floats).
fn float_key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn key_float(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

// The grid's bounds grow by a valid centre (gathered where the centres are written).
fn add_to_bounds(c: vec4<f32>) {
    if c.w <= 0.0 {
        return;
    }
    for (var a = 0u; a < 3u; a++) {
        let key = float_key(c[a]);
        if key < atomicLoad(&state[a]) {
            atomicMin(&state[a], key);
        }
        if key > atomicLoad(&state[3u + a]) {
            atomicMax(&state[3u + a], key);
        }
    }
}

fn seed_count() -> u32 {
    return atomicLoad(&tree[2u]);
}

// Every pixel starts without a cluster (the assignment adds a pixel to its cluster's sums when its
// label changes).
@compute @workgroup_size(64)
fn init_labels(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == 0u {
        for (var a = 0u; a < 3u; a++) {
            atomicStore(&state[a], 0xffffffffu);
            atomicStore(&state[3u + a], 0u);
        }
    }
    if m < params.pixels {
        labels[m] = INVALID;
    }
}

// The first centres: the seeds' shading points (clusters past the seeds, where the image has fewer
// valid grid pixels than K, stay empty); the sums start at zero.
@compute @workgroup_size(64)
fn seed_centres(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    var c = vec4<f32>(0.0);
    var nrm = vec4<f32>(0.0);
    if j < seed_count() {
        let sp = gbuffer[atomicLoad(&tree[params.seeds_base + j])];
        c = vec4<f32>(sp.pos.xyz, 1.0);
        nrm = vec4<f32>(sp.nrm.xyz, 0.0);
    }
    centres[2u * j] = c;
    centres[2u * j + 1u] = nrm;
    for (var w = 0u; w < WORDS; w++) {
        atomicStore(&sums[WORDS * j + w], 0u);
    }
    add_to_bounds(c);
}

fn mean64(i: u32, count: u32) -> f32 {
    let lo = atomicLoad(&sums[i]);
    let hi = atomicLoad(&sums[i + 1u]);
    return (f32(hi) * 4294967296.0 + f32(lo)) / f32(count);
}

// §3.2: "we recompute the cluster center by averaging the position and normal of all cluster
// members": mean position, normalised mean normal (kept when the normals cancel); a cluster without
// members keeps its place but leaves the grid (w = 0).
@compute @workgroup_size(64)
fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    let base = WORDS * j;
    let count = atomicLoad(&sums[base + 12u]);
    var c = centres[2u * j];
    if count > 0u {
        let rel = vec3<f32>(mean64(base, count), mean64(base + 2u, count), mean64(base + 4u, count)) / POS_SCALE;
        let nrm = vec3<f32>(mean64(base + 6u, count), mean64(base + 8u, count), mean64(base + 10u, count)) / NRM_SCALE - 1.0;
        c = vec4<f32>(params.lo.xyz + rel * params.ext.xyz, 1.0);
        let l = length(nrm);
        if l > 1e-6 {
            centres[2u * j + 1u] = vec4<f32>(nrm / l, 0.0);
        }
    } else {
        c.w = 0.0;
    }
    centres[2u * j] = c;
    add_to_bounds(c);
}

// --- The grid over the centres (as colom's, kmeans/grid.wgsl): a counting sort of the valid centres
// into a uniform grid, cell edge 1.5x the spacing of K points spread over the surface of the
// centres' bounding box (or along its longest edge, if that is more), at most 64 cells an axis.

struct Grid {
    origin: vec3<f32>,
    cell: f32,
    dims: vec3<u32>,
    num_cells: u32,
}

fn load_grid() -> Grid {
    var g: Grid;
    for (var a = 0u; a < 3u; a++) {
        g.origin[a] = bitcast<f32>(atomicLoad(&state[GRID + a]));
        g.dims[a] = atomicLoad(&state[GRID + 4u + a]);
    }
    g.cell = bitcast<f32>(atomicLoad(&state[GRID + 3u]));
    g.num_cells = atomicLoad(&state[GRID + 7u]);
    return g;
}

fn cell_coord(g: Grid, p: vec3<f32>) -> vec3<i32> {
    let c = floor((p - g.origin) / g.cell);
    let hi = vec3<f32>(g.dims) - 1.0;
    return vec3<i32>(clamp(c, vec3<f32>(0.0), hi));
}

fn cell_index(g: Grid, c: vec3<i32>) -> u32 {
    return (u32(c.z) * g.dims.y + u32(c.y)) * g.dims.x + u32(c.x);
}

// The grid from the bounds (one invocation); resets the bounds for the next update.
@compute @workgroup_size(1)
fn grid_setup() {
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        lo[a] = key_float(atomicLoad(&state[a]));
        hi[a] = key_float(atomicLoad(&state[3u + a]));
        atomicStore(&state[a], 0xffffffffu);
        atomicStore(&state[3u + a], 0u);
    }
    if !(lo.x <= hi.x) {
        lo = params.lo.xyz;
        hi = params.lo.xyz + params.ext.xyz;
    }
    let e = max(hi - lo, vec3<f32>(0.0));
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    let emax = max(e.x, max(e.y, e.z));
    // (Centres along a line have no area: their spacing along it.)
    let spacing = max(sqrt(area / f32(max(params.k, 1u))), emax / f32(max(params.k, 1u)));
    let floor_cell = max(emax / f32(MAX_DIM), 1e-7 * max(params.ext.w, 1e-30));
    let cell = max(1.5 * spacing, floor_cell);
    let dims = clamp(vec3<u32>(ceil(e / cell)), vec3<u32>(1u), vec3<u32>(MAX_DIM));
    for (var a = 0u; a < 3u; a++) {
        atomicStore(&state[GRID + a], bitcast<u32>(lo[a]));
        atomicStore(&state[GRID + 4u + a], dims[a]);
    }
    atomicStore(&state[GRID + 3u], bitcast<u32>(cell));
    atomicStore(&state[GRID + 7u], dims.x * dims.y * dims.z);
}

// Centres per cell (the counts are 0 before every build: grid_scatter counts them back down).
@compute @workgroup_size(64)
fn grid_count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    let c = centres[2u * j];
    if c.w <= 0.0 {
        return;
    }
    let g = load_grid();
    atomicAdd(&cells[COUNTS + cell_index(g, cell_coord(g, c.xyz))], 1u);
}

// The prefix sum of the counts over blocks of SCAN_BLOCK cells (256 invocations x 4 cells), a
// workgroup taking blocks wid, wid + groups, ...: any number of workgroups gives the same sums
// (src/method/wang/cluster.rs dispatches about one a block, `gi::kmeans::scan_groups`); the
// workgroup scan is common/scan.wgsl's, shared with kmeans/grid.wgsl.
var<workgroup> wg_cells: u32;

fn workgroup_cells(t: u32) -> u32 {
    if t == 0u {
        wg_cells = atomicLoad(&state[GRID + 7u]);
    }
    return workgroupUniformLoad(&wg_cells);
}

// Each cell's offset within its block, each block's total.
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
                counts[i] = atomicLoad(&cells[COUNTS + c0 + i]);
            }
        }
        let s = counts.x + counts.y + counts.z + counts.w;
        partial[t] = s;
        scan_partial(t);
        var run = partial[t] - s;
        for (var i = 0u; i < 4u; i++) {
            if c0 + i < n {
                atomicStore(&cells[LOCAL + c0 + i], run);
            }
            run += counts[i];
        }
        if t == 255u {
            atomicStore(&cells[BLOCK_SUMS + block], partial[255]);
        }
    }
}

// Each cell's slots: from its offset within its block plus the totals of the blocks before (every
// workgroup sums those itself, at most 256), as many as it counts.
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
    for (var block = wid.x; block < blocks; block += groups.x) {
        for (var i = 0u; i < 4u; i++) {
            let c = block * SCAN_BLOCK + i * 256u + t;
            if c < n {
                var before = 0u;
                if block > 0u {
                    before = partial[block - 1u];
                }
                let first = atomicLoad(&cells[LOCAL + c]) + before;
                offsets[c] = vec2<u32>(first, first + atomicLoad(&cells[COUNTS + c]));
            }
        }
    }
}

// The valid centres into their cells' slots, each cell counted back down to 0 (the order within a
// cell does not matter: the search orders candidates by (error, index)).
@compute @workgroup_size(64)
fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    let c = centres[2u * j];
    if c.w <= 0.0 {
        return;
    }
    let g = load_grid();
    let cell = cell_index(g, cell_coord(g, c.xyz));
    let slot = offsets[cell].x + atomicSub(&cells[COUNTS + cell], 1u) - 1u;
    sorted[2u * slot] = vec4<f32>(c.xyz, bitcast<f32>(j));
    sorted[2u * slot + 1u] = centres[2u * j + 1u];
}

// --- The assignment (§3.2: "classify every shading point to its closest center using the metric
// defined in Eq 2"; the paper's kd-tree of the centres "constrain[s] the search within a small
// Euclidean distance"): the centre of least Eq. (2) error (the lower index on a tie) among the
// point's own cluster (in the first assignment the seed of its quadtree node) and those of the 27
// cells around it; without either, the first ring of cells further out that holds a centre.

struct Best {
    e: f32,
    k: u32,
}

// The candidates in sorted slots [a, b). A candidate's normal is read only when its position term
// alone does not already exceed the best error (Eq. 2 adds a non-negative term to it).
fn scan_slots(best: ptr<function, Best>, p: vec3<f32>, n: vec3<f32>, a: u32, b: u32) {
    for (var i = a; i < b; i++) {
        let s = sorted_at(2u * i);
        let k = bitcast<u32>(s.w);
        let position = params.alpha * length(p - s.xyz);
        if position > (*best).e {
            continue;
        }
        let e = position + sqrt(max(0.0, 2.0 - 2.0 * dot(n, sorted_at(2u * i + 1u).xyz)));
        if e < (*best).e || (e == (*best).e && k < (*best).k) {
            (*best).e = e;
            (*best).k = k;
        }
    }
}

// The cells x0..x1 of row (y, z): one run of slots. Skipped when the row's box lies farther from p
// than the best error allows (Eq. 2 is at least α times the distance; the margin covers the rounding
// of cell_coord at cell faces), so the result is the full scan's.
fn scan_row(best: ptr<function, Best>, g: Grid, p: vec3<f32>, n: vec3<f32>, x0: i32, x1: i32, y: i32, z: i32) {
    let lo = g.origin + vec3<f32>(f32(x0), f32(y), f32(z)) * g.cell;
    let hi = g.origin + vec3<f32>(f32(x1 + 1), f32(y + 1), f32(z + 1)) * g.cell;
    let d = max(max(lo - p, p - hi), vec3<f32>(0.0));
    if params.alpha * (length(d) - 1e-4 * g.cell) > (*best).e {
        return;
    }
    let a = cell_slots(cell_index(g, vec3<i32>(x0, y, z))).x;
    let b = cell_slots(cell_index(g, vec3<i32>(x1, y, z))).y;
    scan_slots(best, p, n, a, b);
}

// The 27 cells around c, a row (along x) at a time, the centre row first, then the rows sharing a
// face with it, then the others (so that the best error is small early and far rows are skipped).
fn scan_ring1(best: ptr<function, Best>, g: Grid, p: vec3<f32>, n: vec3<f32>, c: vec3<i32>) {
    let d = vec3<i32>(g.dims);
    let x0 = max(c.x - 1, 0);
    let x1 = min(c.x + 1, d.x - 1);
    for (var item = 0u; item < 9u; item++) {
        // (dy, dz) of item as 2-bit codes (0, 1, 2 = -1, 0, +1): (0, 0), (-1, 0), (1, 0), (0, -1),
        // (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1).
        let dy = i32((0x22161u >> (2u * item)) & 3u) - 1;
        let dz = i32((0x28215u >> (2u * item)) & 3u) - 1;
        let y = c.y + dy;
        let z = c.z + dz;
        if y >= 0 && y < d.y && z >= 0 && z < d.z {
            scan_row(best, g, p, n, x0, x1, y, z);
        }
    }
}

// The cells at Chebyshev distance exactly `ring` (2 or more) from c.
fn scan_ring(best: ptr<function, Best>, g: Grid, p: vec3<f32>, n: vec3<f32>, c: vec3<i32>, ring: i32) {
    let d = vec3<i32>(g.dims);
    let lo = max(c - vec3<i32>(ring), vec3<i32>(0));
    let hi = min(c + vec3<i32>(ring), d - 1);
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            if abs(y - c.y) == ring || abs(z - c.z) == ring {
                scan_row(best, g, p, n, lo.x, hi.x, y, z);
            } else {
                if c.x - ring >= 0 {
                    scan_row(best, g, p, n, c.x - ring, c.x - ring, y, z);
                }
                if c.x + ring < d.x {
                    scan_row(best, g, p, n, c.x + ring, c.x + ring, y, z);
                }
            }
        }
    }
}

// The nearest centre by Eq. (2) among `hint` (the point's cluster; in the first assignment the seed
// of its quadtree node; INVALID or an empty cluster for none) and the centres of the 27 cells around
// p: the hint is the best to beat, so a scan skips every row and candidate that cannot. Without a
// hint and a centre in those cells, the first ring of cells further out that holds one (INVALID
// without any valid centre).
fn nearest(p: vec3<f32>, n: vec3<f32>, hint: u32) -> u32 {
    let g = load_grid();
    let c = cell_coord(g, p);
    var best = Best(BIG, INVALID);
    if hint < params.k {
        let h = centres[2u * hint];
        if h.w > 0.0 {
            best = Best(eq2_error(p, n, h.xyz, centres[2u * hint + 1u].xyz), hint);
        }
    }
    scan_ring1(&best, g, p, n, c);
    let maxr = i32(max(g.dims.x, max(g.dims.y, g.dims.z)));
    for (var ring = 2; ring <= maxr && best.k == INVALID; ring++) {
        scan_ring(&best, g, p, n, c, ring);
    }
    return best.k;
}

// Adds (or removes) pixel m to cluster k's fixed-point sums and count.
fn add_member(k: u32, m: u32, remove: bool) {
    let sp = gbuffer[m];
    let rel = clamp((sp.pos.xyz - params.lo.xyz) / params.ext.xyz, vec3<f32>(0.0), vec3<f32>(1.0));
    let q = vec3<u32>(rel * POS_SCALE);
    let nq = vec3<u32>(clamp(sp.nrm.xyz + 1.0, vec3<f32>(0.0), vec3<f32>(2.0)) * NRM_SCALE);
    let base = WORDS * k;
    for (var a = 0u; a < 3u; a++) {
        if remove {
            sub64(base + 2u * a, q[a]);
            sub64(base + 6u + 2u * a, nq[a]);
        } else {
            sums_add64(base + 2u * a, q[a]);
            sums_add64(base + 6u + 2u * a, nq[a]);
        }
    }
    if remove {
        atomicSub(&sums[base + 12u], 1u);
    } else {
        atomicAdd(&sums[base + 12u], 1u);
    }
}

// 64-bit subtract: adds 2^64 - v (sums wrap modulo 2^64 and end exact once a pass's additions are in).
fn sub64(i: u32, v: u32) {
    if v != 0u {
        sums_add64(i, 0u - v);
        atomicAdd(&sums[i + 1u], 0xffffffffu);
    }
}

// Pixel m to its nearest centre (`hint`: see `nearest`); a pixel that changes cluster leaves the old
// one's sums and joins the new one's (integer sums: the same as summing the members afresh, whatever
// the order).
fn assign_pixel(m: u32, hint: u32) {
    let sp = gbuffer[m];
    if sp.pos.w <= 0.0 {
        return;
    }
    let k = nearest(sp.pos.xyz, sp.nrm.xyz, hint);
    let old = labels[m];
    if old != k {
        if old != INVALID {
            add_member(old, m, true);
        }
        if k != INVALID {
            add_member(k, m, false);
        }
        labels[m] = k;
    }
}

// The first assignment: the grid image's pixels, each hinted with its quadtree node's seed.
@compute @workgroup_size(64)
fn assign_first(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i >= params.gw * params.gh {
        return;
    }
    let m = grid_pixel(i % params.gw, i / params.gw);
    assign_pixel(m, labels[params.pixels + m]);
}

// The k-means iterations' assignment: the grid image's pixels, each hinted with its cluster.
@compute @workgroup_size(64)
fn assign_grid(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i >= params.gw * params.gh {
        return;
    }
    let m = grid_pixel(i % params.gw, i / params.gw);
    assign_pixel(m, labels[m]);
}

// With a grid step above 1, after assign_grid: the pixels off the grid image (without a cluster yet).
@compute @workgroup_size(64)
fn assign_rest(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m >= params.pixels {
        return;
    }
    if (m % params.width) % params.step == 0u && (m / params.width) % params.step == 0u {
        return;
    }
    assign_pixel(m, INVALID);
}

// --- The sample points (§3.2: "in each cluster, we pick the shading point with the smallest error"):
// the least error per cluster (an atomic min of its bits, non-negative floats ordering as their bits),
// then the lowest pixel with it.
@compute @workgroup_size(64)
fn sample_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j == 0u {
        atomicStore(&state[USED], 0u);
    }
    if j >= params.k {
        return;
    }
    atomicStore(&sums[WORDS * j + 13u], 0xffffffffu);
    atomicStore(&sums[WORDS * j + 14u], INVALID);
}

@compute @workgroup_size(64)
fn sample_dist(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m >= params.pixels {
        return;
    }
    let l = labels[m];
    if l == INVALID {
        return;
    }
    let sp = gbuffer[m];
    let bits = bitcast<u32>(eq2_error(sp.pos.xyz, sp.nrm.xyz, centres[2u * l].xyz, centres[2u * l + 1u].xyz));
    labels[params.pixels + m] = bits;
    if bits < atomicLoad(&sums[WORDS * l + 13u]) {
        atomicMin(&sums[WORDS * l + 13u], bits);
    }
}

@compute @workgroup_size(64)
fn sample_pick(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m >= params.pixels {
        return;
    }
    let l = labels[m];
    if l == INVALID {
        return;
    }
    if labels[params.pixels + m] == atomicLoad(&sums[WORDS * l + 13u]) {
        atomicMin(&sums[WORDS * l + 14u], m);
    }
}

// Each cluster's sample point as wang.wgsl reads it and as a shading point of albedo 1 (all zero for
// an empty cluster); counts the clusters with one.
@compute @workgroup_size(64)
fn sample_store(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j >= params.k {
        return;
    }
    let m = atomicLoad(&sums[WORDS * j + 14u]);
    var p = vec4<f32>(0.0);
    var n = vec4<f32>(0.0);
    var albedo = vec4<f32>(0.0);
    if m != INVALID {
        let sp = gbuffer[m];
        p = vec4<f32>(sp.pos.xyz, 1.0);
        n = vec4<f32>(sp.nrm.xyz, 0.0);
        albedo = vec4<f32>(1.0, 1.0, 1.0, 0.0);
        atomicAdd(&state[USED], 1u);
    }
    samples[2u * j] = p;
    samples[2u * j + 1u] = n;
    sample_gbuffer[4u * j] = p;
    sample_gbuffer[4u * j + 1u] = n;
    sample_gbuffer[4u * j + 2u] = albedo;
    sample_gbuffer[4u * j + 3u] = vec4<f32>(0.0);
}
