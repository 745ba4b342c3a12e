// The tree sum of a workgroup of REDUCE invocations over the including shader's workgroup array
// `wg_sum` (REDUCE values of its type): each invocation has written its value at wg_sum[t]; after
// the call, which every invocation makes, wg_sum[0] holds the sum (pairs added in a fixed order,
// the same each run).
fn tree_sum(t: u32) {
    workgroupBarrier();
    for (var step = REDUCE / 2u; step > 0u; step = step / 2u) {
        if (t < step) {
            wg_sum[t] = wg_sum[t] + wg_sum[t + step];
        }
        workgroupBarrier();
    }
}
