// The pixels of a frame whose primary ray hit a surface, counted on the GPU into one slot of a ring
// of counters (crates/core/src/gi/count_lit.rs): the viewer's `motion.lit_fraction_min` without reading the
// G-buffer back. The CPU twin is `app::motion::lit_fraction` over the read-back positions.
#import common/chunk.wgsl
#import common/gbuffer.wgsl

struct CountParams {
    // x: the ring's slot this frame counts into.
    slot: vec4<u32>,
}

@group(1) @binding(1) var<uniform> params: CountParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
@group(1) @binding(3) var<storage, read_write> ring: array<atomic<u32>>;

@compute @workgroup_size(64)
fn count_lit(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == 0xffffffffu {
        return;
    }
    if gbuffer[i].pos.w > 0.0 {
        atomicAdd(&ring[params.slot.x], 1u);
    }
}
