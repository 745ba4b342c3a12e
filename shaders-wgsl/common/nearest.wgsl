// The nearest-centroid search over the grid (Alg. 1 lines 6-11 and Alg. 2 lines 4-17): shared by
// the iterations (kmeans/iterate.wgsl) and the final assignment (kmeans/assign.wgsl).
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
        if RING_FALLBACK {
            for (var ring = 2; ring <= min(FINAL_RINGS, maxr) && best.count == 0u; ring++) {
                scan_ring(&best, p, n, c, ring, f, true);
            }
        }
        if POSITION_FALLBACK && best.count == 0u {
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
    if RING_FALLBACK {
        for (var ring = 2; ring <= ITER_RINGS && best.count == 0u; ring++) {
            scan_ring(&best, p, n, c, ring, 1u, true);
        }
    }
    return best.idx[0];
}
