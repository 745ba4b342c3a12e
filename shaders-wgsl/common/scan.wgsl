// The workgroup prefix sum of the grid passes' block scans (kmeans/grid.wgsl, wang_cluster.wgsl):
// blocks of SCAN_BLOCK cells, 256 invocations x 4 cells.
const SCAN_BLOCK: u32 = 1024u;

var<workgroup> partial: array<u32, 256>;

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
