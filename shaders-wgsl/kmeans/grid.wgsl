// Alg. 1 line 5: the uniform grid over the centroids that the nearest-centroid search reads.
#import common/kmeans.wgsl
#import common/scan.wgsl

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
    if stopped() {
        return;
    }
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
    if k == INVALID || k >= params.k || stopped() {
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
// idle, cost lavapipe 4 ms a grid build at 720 cells. The workgroup scan is common/scan.wgsl's.
// Where the blocks' totals go in `cells` (after the counts and the offsets within blocks).
const BLOCK_SUMS: u32 = 2u * MAX_CELLS;

var<workgroup> wg_cells: u32;

// The grid's cell count as a workgroup-uniform value (a storage value is not one under WGSL's rules for
// barriers, and the block loops hold barriers); 0 after Alg. 1's loop ended (`stopped`).
fn workgroup_cells(t: u32) -> u32 {
    if t == 0u {
        wg_cells = select(grid.num_cells, 0u, stopped());
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

// Step 5: scatter centroid indices into their cells' ranges, counting each cell back down to 0 (the
// order within a cell does not matter: the search orders candidates by (distance, index)).
@compute @workgroup_size(64)
fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = chunk_item(gid, nwg);
    if k == INVALID || k >= params.k || stopped() {
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
