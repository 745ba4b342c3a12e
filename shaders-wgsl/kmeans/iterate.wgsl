// Alg. 1 lines 6-18: assign the sampled points, keep the clusters' sums, re-seed empty clusters,
// update the centroids.
#import common/kmeans.wgsl
#import common/nearest.wgsl

// --- Alg. 1 lines 6-11: assign each sampled point to its nearest centroid. Lines 12-16 (the sums of
// the members' positions and normals) are kept up to date here: a point that changed cluster leaves
// the old cluster's sums and joins the new one's. Integer sums do not depend on the order of the
// additions, so they equal summing all members afresh (the CPU twin does that), and an iteration
// late in the run touches only the few points that moved.
@compute @workgroup_size(64)
fn assign_sampled(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let s = chunk_item(gid, nwg);
    if s == INVALID || s >= params.num_sampled || stopped() {
        return;
    }
    let m = sample_index(s);
    let p = point_pos(m);
    var k = INVALID;
    if p.w > 0.0 {
        k = nearest_bounded(p.xyz, point_nrm(m));
    }
    if RESEED && p.w > 0.0 && k == INVALID {
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

// --- Alg. 1 lines 17-18: centroids = mean position and normalised mean normal (the plain mean
// without NORMALISED_NORMAL; the sums stay: the next assignment updates them). An empty cluster is
// re-seeded at the orphan proposed to it, or where no orphan was found at a drawn sampled point
// (above; RESEED), else keeps its centroid but is marked empty (w = 0) and drops out of the grid. A
// re-seed counts as a change for Alg. 1's early end.
@compute @workgroup_size(64)
fn update(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k || stopped() {
        return;
    }
    let base = k * WORDS;
    let count = atomicLoad(&sums[base + 12u]);
    var c = centroids[k];
    if count > 0u {
        let rel = vec3<f32>(mean64(base, count), mean64(base + 2u, count), mean64(base + 4u, count)) / POS_SCALE;
        let nrm = vec3<f32>(mean64(base + 6u, count), mean64(base + 8u, count), mean64(base + 10u, count)) / NRM_SCALE - 1.0;
        c.pos = vec4<f32>(params.lo.xyz + rel * params.ext.xyz, 1.0);
        if NORMALISED_NORMAL {
            let l = length(nrm);
            if l > 1e-6 {
                c.nrm = vec4<f32>(nrm / l, 0.0);
            }
        } else {
            c.nrm = vec4<f32>(nrm, 0.0);
        }
    } else if RESEED {
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
    } else {
        // Without re-seeding (the paper) an empty cluster keeps its centroid, out of the grid.
        c.pos.w = 0.0;
    }
    atomicStore(&reps[2u * k], 0u);
    centroids[k] = c;
    add_to_bounds(c.pos);
}

// Alg. 1's loop, decided on the GPU so that the host reads nothing back (one invocation, after
// `update`): it ends after an iteration that changed no assignment and re-seeded no cluster (not
// after the first, whose "previous" assignment was never used: the centroids would stay as they are),
// or once it ran its count: the iterations asked for (bounds[13]), after a warm start (bounds[14])
// their share of re-seeded centroids (`warm_iterations`). The host records every iteration asked for;
// those after the end do nothing (`stopped`).
@compute @workgroup_size(1)
fn converge() {
    if stopped() {
        return;
    }
    let done = atomicLoad(&bounds[7]);
    var limit = atomicLoad(&bounds[13]);
    if atomicLoad(&bounds[14]) != 0u {
        limit = warm_iterations(limit, atomicLoad(&bounds[11]), params.k);
    }
    if (done >= 2u && atomicLoad(&bounds[6]) == 0u) || done >= limit {
        atomicStore(&bounds[12], 1u);
    }
}

// After the loop (one invocation): the final grid (Alg. 2) is built whether or not the loop ended
// early.
@compute @workgroup_size(1)
fn loop_end() {
    atomicStore(&bounds[12], 0u);
}

// Iterations of Alg. 1 after a warm start that kept `kept` of `k` centroids: the share of re-seeded
// centroids of `iterations`, rounded up, at least 1. CPU twin: gi::kmeans::warm_iterations (the same
// ceil(iterations * new / k), here without 64-bit products: the least n with n k >= iterations new).
fn warm_iterations(iterations: u32, kept: u32, k: u32) -> u32 {
    if iterations == 0u {
        return 0u;
    }
    let kk = max(k, 1u);
    let want = mul_wide(iterations, kk - min(kept, kk));
    for (var n = 1u; n < iterations; n++) {
        let have = mul_wide(n, kk);
        if have.y > want.y || (have.y == want.y && have.x >= want.x) {
            return n;
        }
    }
    return iterations;
}

// x y as 64 bits (lo, hi).
fn mul_wide(x: u32, y: u32) -> vec2<u32> {
    let ll = (x & 0xffffu) * (y & 0xffffu);
    let lh = (x & 0xffffu) * (y >> 16u);
    let hl = (x >> 16u) * (y & 0xffffu);
    let hh = (x >> 16u) * (y >> 16u);
    let mid = lh + (ll >> 16u) + (hl & 0xffffu);
    return vec2<u32>((mid << 16u) | (ll & 0xffffu), hh + (mid >> 16u) + (hl >> 16u));
}
