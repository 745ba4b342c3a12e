// The uniform grid over cluster centres and its ring search, one for both k-means: colom's (Alg. 1
// line 5, kmeans/grid.wgsl and common/nearest.wgsl) and wang's (§3.2, wang/grid.wgsl and
// wang/assign.wgsl). CPU twin: crates/core/src/cpu/grid.rs.
//
// The file that imports it supplies, by name:
// - the bindings `bounds` (atomic words; 0-5 the valid centres' bounds as float_key bits, min xyz
//   then max xyz), `grid: Grid`, `cells`, `sorted` and `ranges` (storage), `sorted_tex` and
//   `ranges_tex` (texture_2d<u32>), and the override TEXTURE_SEARCH;
// - the centres: `grid_centres()` (how many), `grid_centre_pos(k)` (xyz, w > 0 when it belongs in the
//   grid) and `grid_centre_nrm(k)`; `grid_live()`, false where the grid passes do nothing;
// - for the search, the metric: a struct `Query` (the point, with its position in field `p`, and
//   whatever else the metric reads), a struct `Search` (the result so far), `search_cut(s, q)` (how
//   far from q.p a centre may lie and still change the result) and `scan_slots(s, q, a, b)` (the
//   candidates in sorted slots [a.x, a.y) then [b.x, b.y) against the metric).
#import common/chunk.wgsl
#import common/scan.wgsl

const MAX_DIM: u32 = 64u;
const MAX_CELLS: u32 = MAX_DIM * MAX_DIM * MAX_DIM;
// Where the scan blocks' totals go in `cells`: after the counts (from 0) and each cell's offset within
// its block (from MAX_CELLS). Fixed places: the next grid may have more cells, and its counts must
// start at 0.
const BLOCK_SUMS: u32 = 2u * MAX_CELLS;

// The grid over the centres (written by grid_build).
struct Grid {
    origin: vec3<f32>,
    cell: f32,
    dims: vec3<u32>,
    num_cells: u32,
}

// Texel i of a data texture: 4096 texels a row (DATA_ROW in crates/core/src/gi/dispatch.rs).
fn texel_xy(i: u32) -> vec2<u32> {
    return vec2<u32>(i & 4095u, i >> 12u);
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

// --- Step 1: the bounds of the valid centres, gathered where the centres are written, so the grid
// needs no pass of its own. Only the atomics that can change the bound: K atomics on six words
// serialise on a GPU.
fn add_to_bounds(pos: vec4<f32>) {
    if pos.w <= 0.0 {
        return;
    }
    for (var a = 0u; a < 3u; a++) {
        let key = float_key(pos[a]);
        if key < atomicLoad(&bounds[a]) {
            atomicMin(&bounds[a], key);
        }
        if key > atomicLoad(&bounds[3u + a]) {
            atomicMax(&bounds[3u + a], key);
        }
    }
}

// Step 2 (one invocation, from the importer's grid_setup): the cell size from the centres' spread, the
// bounds reset for the next build. Centres lie on surfaces, so the cell edge is 1.5x the spacing of
// k points spread over the bounds' surface area; at most MAX_DIM cells per axis and no finer than
// 1e-7 of the frame's diagonal (frame_ext.w). Without a valid centre, one frame (frame_lo, frame_ext)
// of cells. `along_line`: the spacing is at least that of k points along the bounds' longest edge
// (centres along a line have no area; wang's choice, crates/core/src/cpu/grid.rs `cell_side_and_dims`: it acts
// only below 97 centres, where 1.5 / k exceeds the MAX_DIM floor's 1 / 64).
fn grid_build(k: u32, frame_lo: vec3<f32>, frame_ext: vec4<f32>, along_line: bool) {
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        lo[a] = key_float(atomicLoad(&bounds[a]));
        hi[a] = key_float(atomicLoad(&bounds[3u + a]));
        atomicStore(&bounds[a], 0xffffffffu);
        atomicStore(&bounds[3u + a], 0u);
    }
    if !(lo.x <= hi.x) {
        lo = frame_lo;
        hi = frame_lo + frame_ext.xyz;
    }
    let e = max(hi - lo, vec3<f32>(0.0));
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    var spacing = sqrt(area / f32(max(k, 1u)));
    let emax = max(e.x, max(e.y, e.z));
    if along_line {
        spacing = max(spacing, emax / f32(max(k, 1u)));
    }
    let floor_cell = max(emax / f32(MAX_DIM), 1e-7 * max(frame_ext.w, 1e-30));
    let cell = max(1.5 * spacing, floor_cell);
    let dims = clamp(vec3<u32>(ceil(e / cell)), vec3<u32>(1u), vec3<u32>(MAX_DIM));
    grid.origin = lo;
    grid.cell = cell;
    grid.dims = dims;
    grid.num_cells = dims.x * dims.y * dims.z;
}

// The centre behind invocation k of grid_count and grid_scatter when it belongs in the grid, else
// INVALID.
fn grid_item(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    let k = chunk_item(gid, nwg);
    if k >= grid_centres() || !grid_live() || grid_centre_pos(k).w <= 0.0 {
        return INVALID;
    }
    return k;
}

// Step 3: count centres per cell. The counts are 0 before every grid build: the buffer starts at zero
// and grid_scatter counts each cell back down to 0 (no clearing pass).
@compute @workgroup_size(64)
fn grid_count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = grid_item(gid, nwg);
    if k == INVALID {
        return;
    }
    atomicAdd(&cells[cell_index(cell_coord(grid_centre_pos(k).xyz))], 1u);
}

// Step 4: exclusive prefix sum of the counts into the offsets off[c], in blocks of SCAN_BLOCK cells
// (256 invocations x 4 cells), then per cell the texel (off[c - 1], off[c], off[c + 1], off[c + 2]) of
// `ranges` (off[-1] = 0, off[c] = the total past the last cell): one fetch gives a row run of three
// cells around c (scan_ring1). Two passes; a workgroup takes blocks wid, wid + groups, ..., so any
// number of workgroups gives the same sums. Only the GPU knows the cell count: the host dispatches
// about one workgroup a block from an estimate (crates/core/src/gi/kmeans.rs, scan_groups). A single workgroup
// walking all cells cost 0.6 ms a grid build at 94k cells on an H100; a fixed 256 workgroups, mostly
// idle, cost lavapipe 4 ms a grid build at 720 cells. The workgroup scan is common/scan.wgsl's.
var<workgroup> wg_cells: u32;

// The grid's cell count as a workgroup-uniform value (a storage value is not one under WGSL's rules for
// barriers, and the block loops hold barriers); 0 where the grid passes do nothing (`grid_live`).
fn workgroup_cells(t: u32) -> u32 {
    if t == 0u {
        wg_cells = select(0u, grid.num_cells, grid_live());
    }
    return workgroupUniformLoad(&wg_cells);
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

// Step 5: scatter the centres into their cells' ranges, two texels a slot as bits (position with w =
// the centre's index, normal), counting each cell back down to 0 (the order within a cell does not
// matter: the searches order candidates by (metric, index)).
@compute @workgroup_size(64)
fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = grid_item(gid, nwg);
    if k == INVALID {
        return;
    }
    let pos = grid_centre_pos(k).xyz;
    let cell = cell_index(cell_coord(pos));
    let slot = ranges[cell].y + atomicSub(&cells[cell], 1u) - 1u;
    sorted[2u * slot] = vec4<u32>(bitcast<vec3<u32>>(pos), k);
    sorted[2u * slot + 1u] = bitcast<vec4<u32>>(grid_centre_nrm(k));
}

// --- The ring search (the metric the importer's: `search_cut`, `scan_slots`).

// Cell i's texel (off[i - 1], off[i], off[i + 1], off[i + 2]) (see TEXTURE_SEARCH).
fn cell_texel(i: u32) -> vec4<u32> {
    if TEXTURE_SEARCH {
        return textureLoad(ranges_tex, texel_xy(i), 0);
    }
    return ranges[i];
}

// Sorted slot i: position bits with w = the centre's index.
fn sorted_centre(i: u32) -> vec4<u32> {
    if TEXTURE_SEARCH {
        return textureLoad(sorted_tex, texel_xy(2u * i), 0);
    }
    return sorted[2u * i];
}

// Sorted slot i's normal.
fn sorted_normal(i: u32) -> vec3<f32> {
    if TEXTURE_SEARCH {
        return bitcast<vec3<f32>>(textureLoad(sorted_tex, texel_xy(2u * i + 1u), 0).xyz);
    }
    return bitcast<vec3<f32>>(sorted[2u * i + 1u].xyz);
}

// Ring 1 (the 27 cells around c) nearest first, skipping every cell whose box is farther from q.p than
// `search_cut`: the centre cell, then the two other cells of its row, then the 8 other rows (the 4
// sharing a face with the centre first). A skipped cell holds no centre that could change the
// result, so the result is the full scan's; a full list usually needs 3 of the 9 rows. The margin
// (1e-4 cell) covers the rounding of cell_coord at cell faces.
fn scan_ring1(s: ptr<function, Search>, q: Query, c: vec3<i32>) {
    let d = vec3<i32>(grid.dims);
    let lower = grid.origin + vec3<f32>(c) * grid.cell;
    // Distance from p to the centre cell's lower and upper faces (0 where p lies outside the grid).
    let g_lo = max(q.p - lower, vec3<f32>(0.0));
    let g_hi = max(lower + grid.cell - q.p, vec3<f32>(0.0));
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
        let cut = search_cut(s, q) + margin;
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
        scan_slots(s, q, a, b);
    }
}

// Scans the cells at Chebyshev distance exactly `ring` (2 or more; ring 1 is scan_ring1) from `c` a row
// at a time: a full run on the rows of its top, bottom, front and back faces and the two end cells of
// the other rows. The result does not depend on the visiting order (the metrics break ties by index).
fn scan_ring(s: ptr<function, Search>, q: Query, c: vec3<i32>, ring: i32) {
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
            scan_slots(s, q, a, b);
        }
    }
}
