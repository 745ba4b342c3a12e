// §3.2, "Adaptive Seeding of Sample Points": the screen-space quadtree of the grid image's shading
// points, each node's ε_q, and K seeds handed down from the root in proportion to the children's.
#import wang/common.wgsl
#import common/rng.wgsl

fn level_base(l: u32) -> u32 {
    return ((1u << (2u * l)) - 1u) / 3u;
}

fn node_index(l: u32, x: u32, y: u32) -> u32 {
    return level_base(l) + (y << l) + x;
}


// Node i of level l as (x, y) (row-major within the level); INVALID past the level's nodes.
fn level_node(i: u32, l: u32) -> vec2<u32> {
    if i >= (1u << (2u * l)) {
        return vec2<u32>(INVALID);
    }
    return vec2<u32>(i & ((1u << l) - 1u), i >> l);
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

// A node's sums: positions, normals, valid points.
struct NodeSums {
    ps: vec3<f32>,
    ns: vec3<f32>,
    c: f32,
}

// Level L - 1 (2x2 grid pixels a node): sums of the valid points, in the order (0,0), (1,0), (0,1),
// (1,1); the node's words cleared. Also starts the level counter.
@compute @workgroup_size(64)
fn seed_leaves(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    let l = params.levels - 1u;
    if i == 0u {
        atomicStore(&bounds[LEVEL], 0u);
    }
    let node = level_node(i, l);
    if node.x == INVALID {
        return;
    }
    var s = NodeSums();
    for (var q = 0u; q < 4u; q++) {
        let m = valid_pixel(2u * node.x + (q & 1u), 2u * node.y + (q >> 1u));
        if m != INVALID {
            s.ps += gbuffer[m].pos.xyz;
            s.ns += gbuffer[m].nrm.xyz;
            s.c += 1.0;
        }
    }
    store_node(node_index(l, node.x, node.y), s);
}

fn store_node(n: u32, s: NodeSums) {
    nodes[2u * n] = vec4<f32>(s.ps, s.c);
    nodes[2u * n + 1u] = vec4<f32>(s.ns, 0.0);
    for (var w = 0u; w < 4u; w++) {
        atomicStore(&tree[4u * n + w], 0u);
    }
}

// One level up (levels - 2 - the counter): a node's sums are its four children's, in order.
@compute @workgroup_size(64)
fn seed_up(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    let l = params.levels - 2u - atomicLoad(&bounds[LEVEL]);
    let node = level_node(i, l);
    if node.x == INVALID {
        return;
    }
    var s = NodeSums();
    for (var q = 0u; q < 4u; q++) {
        let child = node_index(l + 1u, 2u * node.x + (q & 1u), 2u * node.y + (q >> 1u));
        let sums = nodes[2u * child];
        s.ps += sums.xyz;
        s.ns += nodes[2u * child + 1u].xyz;
        s.c += sums.w;
    }
    store_node(node_index(l, node.x, node.y), s);
}

// The level counter's next value (one invocation between two levels' steps).
@compute @workgroup_size(1)
fn seed_next() {
    atomicAdd(&bounds[LEVEL], 1u);
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


fn eps_weight(n: u32) -> f32 {
    return f32(atomicLoad(&tree[4u * n + 1u])) * 4294967296.0 + f32(atomicLoad(&tree[4u * n]));
}

// Splits k seeds among four children in proportion to their weights (ε_q), each at most its cap (its
// valid points): floors first, then the largest remainders (lowest index on a tie), repeated over the
// children with room until every seed is placed; with no weight anywhere, equal shares. A round that
// leaves seeds fills a child (or, from f32 rounding of the shares, leaves fewer than one), so
// APPORTION_ROUNDS place them all. Twin: method::wang::twin::apportion.
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
    let l = atomicLoad(&bounds[LEVEL]) - (params.levels - 1u);
    let node = level_node(i, l);
    if node.x == INVALID {
        return;
    }
    let x = node.x;
    let y = node.y;
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

