// The assignment (§3.2: "classify every shading point to its closest center using the metric
// defined in Eq 2"; the paper's kd-tree of the centres "constrain[s] the search within a small
// Euclidean distance"): the centre of least Eq. (2) error (the lower index on a tie) among the
// point's own cluster (in the first assignment the seed of its quadtree node) and those of the 27
// cells around it; without either, the first ring of cells further out that holds a centre. The
// rings are common/grid.wgsl's; this file gives them Eq. (2) as the metric (`Query`, `Search`,
// `search_cut`, `scan_slots`).
#import wang/common.wgsl

struct Best {
    e: f32,
    k: u32,
}

// The point a search is for.
struct Query {
    p: vec3<f32>,
    n: vec3<f32>,
}

// What common/grid.wgsl's rings fill.
alias Search = Best;

// How far from q.p a centre may lie and still beat the best: Eq. (2) is at least α times the
// distance, so best.e / α, widened by 1e-5 of itself so that the rounding of the division and of the
// rings' squared distances never skips a cell that holds a better centre (the result stays the full
// scan's; BIG / α may be +inf: nothing skipped).
fn search_cut(best: ptr<function, Best>, q: Query) -> f32 {
    return (*best).e / params.alpha * (1.0 + 1e-5);
}

// The candidates in sorted slots [a.x, a.y) then [b.x, b.y). A candidate's normal is read only when
// its position term alone does not already exceed the best error (Eq. 2 adds a non-negative term to
// it).
fn scan_slots(best: ptr<function, Best>, q: Query, a: vec2<u32>, b: vec2<u32>) {
    let len_a = a.y - a.x;
    let len = len_a + (b.y - b.x);
    for (var t = 0u; t < len; t++) {
        let i = select(b.x + (t - len_a), a.x + t, t < len_a);
        let c = sorted_centre(i);
        let k = c.w;
        let position = params.alpha * length(q.p - bitcast<vec3<f32>>(c.xyz));
        if position > (*best).e {
            continue;
        }
        let e = position + sqrt(max(0.0, 2.0 - 2.0 * dot(q.n, sorted_normal(i))));
        if e < (*best).e || (e == (*best).e && k < (*best).k) {
            (*best).e = e;
            (*best).k = k;
        }
    }
}

// The nearest centre by Eq. (2) among `hint` (the point's cluster; in the first assignment the seed
// of its quadtree node; INVALID or an empty cluster for none) and the centres of the 27 cells around
// p: the hint is the best to beat, so a scan skips every cell and candidate that cannot. Without a
// hint and a centre in those cells, the first ring of cells further out that holds one (INVALID
// without any valid centre).
fn nearest(p: vec3<f32>, n: vec3<f32>, hint: u32) -> u32 {
    let c = cell_coord(p);
    let q = Query(p, n);
    var best = Best(BIG, INVALID);
    if hint < params.k {
        let h = centres[2u * hint];
        if h.w > 0.0 {
            best = Best(eq2_error(p, n, h.xyz, centres[2u * hint + 1u].xyz), hint);
        }
    }
    scan_ring1(&best, q, c);
    let maxr = i32(max(grid.dims.x, max(grid.dims.y, grid.dims.z)));
    for (var ring = 2; ring <= maxr && best.k == INVALID; ring++) {
        scan_ring(&best, q, c, ring);
    }
    return best.k;
}

// 64-bit unsigned add into words (i, i + 1) of `sums` (as seed.wgsl's tree_add64).
fn sums_add64(i: u32, v: u32) {
    let old = atomicAdd(&sums[i], v);
    if old > 0xffffffffu - v {
        atomicAdd(&sums[i + 1u], 1u);
    }
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
