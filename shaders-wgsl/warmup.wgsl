// GPU warm-up (crates/core/src/gpu/warmup.rs): dependent multiply-adds that keep every core busy, so that the
// GPU runs at its working clock when the timed renders start. Touches nothing the renderer reads.

struct WarmupParams {
    iterations: u32,
    _a: u32,
    _b: u32,
    _c: u32,
}

@group(0) @binding(0) var<uniform> params: WarmupParams;
// One word a lane of the first workgroup's size: the result is stored so the loop is not removed.
@group(0) @binding(1) var<storage, read_write> sink: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    var x = f32(gid.x & 1023u) * 1e-3;
    var y = 1.0 - x;
    // At most a few thousand trips (crates/core/src/gpu/warmup.rs): lavapipe ends a loop after 65,535.
    for (var i = 0u; i < params.iterations; i++) {
        x = fma(x, 0.9999, y * 1e-4);
        y = fma(y, 0.9998, x * 2e-4);
    }
    sink[li] = x + y;
}
