// One word of each item of a buffer summed on the GPU into a 64-bit total (two u32 words, low then
// high) in one slot of a ring that stays on the GPU (crates/core/src/gi/sum.rs): a method's per-pixel counts
// (e.g. the shadow rays each pixel traced), or the items whose word is a positive f32 (the viewer's
// lit pixels: the G-buffer's `pos.w > 0`), counted without reading them back each frame. The CPU
// twin is `gi::sum::sum_words_cpu`.
#import common/chunk.wgsl

struct SumParams {
    // x: the words an item spans; y: the word of an item summed; z: the ring's slot; w: what the
    // word adds: 0 its value, 1 one where it is a positive f32 (`gi::sum::Each`).
    words: vec4<u32>,
}

@group(1) @binding(1) var<uniform> params: SumParams;
@group(1) @binding(2) var<storage, read> data: array<u32>;
@group(1) @binding(3) var<storage, read_write> ring: array<atomic<u32>>;

var<workgroup> group_lo: atomic<u32>;
var<workgroup> group_hi: atomic<u32>;

// Adds `v` to the 64-bit (lo, hi) pair with the carry: a wrap of lo (the old value above
// 2^32 - 1 - v) carries one into hi. Exact mod 2^64 whatever the order of the adds.
fn add_group(v: u32) {
    let old = atomicAdd(&group_lo, v);
    if old > 0xffffffffu - v {
        atomicAdd(&group_hi, 1u);
    }
}

@compute @workgroup_size(64)
fn sum_words(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = chunk_item(gid, nwg);
    var v = 0u;
    if i != 0xffffffffu {
        v = data[i * params.words.x + params.words.y];
        if params.words.w == 1u {
            v = select(0u, 1u, bitcast<f32>(v) > 0.0);
        }
    }
    add_group(v);
    workgroupBarrier();
    if local == 0u {
        let lo = atomicLoad(&group_lo);
        let hi = atomicLoad(&group_hi);
        let at = params.words.z * 2u;
        let old = atomicAdd(&ring[at], lo);
        var carry = 0u;
        if old > 0xffffffffu - lo {
            carry = 1u;
        }
        if hi + carry > 0u {
            atomicAdd(&ring[at + 1u], hi + carry);
        }
    }
}
