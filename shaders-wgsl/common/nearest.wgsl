// The nearest-centroid search over the grid (Alg. 1 lines 6-11 and Alg. 2 lines 4-17): shared by
// the iterations (kmeans/iterate.wgsl) and the final assignment (kmeans/assign.wgsl). The rings of
// cells are common/grid.wgsl's; this file gives them Eq. (7) as the metric (`Query`, `Search`,
// `search_cut`, `scan_slots`).
#import common/kmeans.wgsl

// The F nearest centroids of a point by Eq. (7) among the 27 cells around it (Alg. 2 lines 4-17).
// Falls back, in order, to: rings of cells further out, up to FINAL_RINGS, with the same metric
// (RING_FALLBACK); then the nearest centroid by position alone (ignoring n_t) in the first ring that
// holds one (POSITION_FALLBACK), so no point is left unassigned. With both off (--paper) a point with
// no centroid passing n_t in its 27 cells gets none: Eq. (7) puts it at distance ∞ from them all.
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

// The point a search is for: its position and normal, the slots it fills (F, or 1 for the
// iterations' search and the fallback by position alone) and whether Eq. (7)'s normal test applies.
struct Query {
    p: vec3<f32>,
    n: vec3<f32>,
    f: u32,
    use_normals: bool,
}

// What common/grid.wgsl's rings fill.
alias Search = Nearest;

// How far from q.p a centroid may lie and still enter the list: its last slot's distance.
fn search_cut(best: ptr<function, Nearest>, q: Query) -> f32 {
    return last_slot(best, q.f).r;
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

// The candidates in sorted slots [a.x, a.y) then [b.x, b.y): runs of cells (cells along x are
// consecutive in the sorted order, so a run of a row is one range). One loop for both runs: on
// lavapipe's masked SIMD every copy of this loop costs its lanes' longest trip.
fn scan_slots(best: ptr<function, Nearest>, q: Query, a: vec2<u32>, b: vec2<u32>) {
    let p = q.p;
    let n = q.n;
    let f = q.f;
    let use_normals = q.use_normals;
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

// Rings searched with Eq. (7) in the final assignment before the fallback by position alone. Further
// out the nearest compatible centroid is several cluster spacings away; scanning for it could visit
// the whole grid (64^3 cells), and on a GPU the few points that did set the time of the pass (213 ms
// for K = 30000 in the breakfast room at 1024x720).
const FINAL_RINGS: i32 = 4;

fn nearest(p: vec3<f32>, n: vec3<f32>, f: u32) -> Nearest {
    var best = empty_nearest();
    let c = cell_coord(p);
    let q = Query(p, n, f, true);
    scan_ring1(&best, q, c);
    if best.count == 0u {
        let maxr = i32(max(grid.dims.x, max(grid.dims.y, grid.dims.z)));
        if RING_FALLBACK {
            for (var ring = 2; ring <= min(FINAL_RINGS, maxr) && best.count == 0u; ring++) {
                scan_ring(&best, q, c, ring);
            }
        }
        if POSITION_FALLBACK && best.count == 0u {
            let by_position = Query(p, n, 1u, false);
            scan_ring1(&best, by_position, c);
            for (var ring = 2; ring <= maxr && best.count == 0u; ring++) {
                scan_ring(&best, by_position, c, ring);
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
    let q = Query(p, n, 1u, true);
    scan_ring1(&best, q, c);
    if RING_FALLBACK {
        for (var ring = 2; ring <= ITER_RINGS && best.count == 0u; ring++) {
            scan_ring(&best, q, c, ring);
        }
    }
    return best.idx[0];
}
