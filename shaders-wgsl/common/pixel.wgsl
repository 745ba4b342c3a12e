// The pixel of this invocation (`chunk_item`) when it shows a surface: its index, else INVALID
// (past the chunk's range, or a pixel that sees nothing). Reads the including pass's `gbuffer`.
#import common/chunk.wgsl
#import common/gbuffer.wgsl

fn surface_item(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    let i = chunk_item(gid, nwg);
    if i == INVALID || gbuffer[i].pos.w <= 0.0 {
        return INVALID;
    }
    return i;
}
