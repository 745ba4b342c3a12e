// Bounded dispatches: a heavy pass runs as several dispatches over ranges of its items, each told its
// range here (crates/core/src/gi/dispatch.rs writes it before each submission).
struct Chunk {
    offset: u32,
    count: u32,
    seed: u32,
    _pad: u32,
    // A second range for two-dimensional work (e.g. pixels x VPLs): [sub_offset, sub_offset + sub_count).
    sub_offset: u32,
    sub_count: u32,
    _pad2: vec2<u32>,
}

@group(1) @binding(0) var<uniform> chunk: Chunk;

// The item this invocation handles, or INVALID past the chunk's end.
fn chunk_item(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    let i = gid.x + gid.y * nwg.x * 64u;
    if i >= chunk.count {
        return 0xffffffffu;
    }
    return chunk.offset + i;
}
