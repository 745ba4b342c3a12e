// A frame's final radiance into a texture (`Renderer::render_to_texture`): emission + direct plus the
// indirect light, each scaled from render units to the scene's and saturated at the largest finite
// f32 as `GpuFrame::read` does on the CPU, alpha 1. One invocation a pixel.

struct ComposeParams {
    // Width, height.
    size: vec4<u32>,
    // x: the factor from render units to the scene's (`Renderer::output_scale`).
    scale: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: ComposeParams;
// Emission + direct light, a vec4 a pixel.
@group(0) @binding(1) var<storage, read> direct: array<vec4<f32>>;
// The indirect light at the image's size, a vec4 a pixel.
@group(0) @binding(2) var<storage, read> indirect: array<vec4<f32>>;
@group(0) @binding(3) var out_image: texture_storage_2d<rgba32float, write>;

const F32_MAX: f32 = 3.40282347e38;

// A pixel in the scene's units, saturating at the largest finite f32.
fn scene_units(p: vec3<f32>) -> vec3<f32> {
    return min(p * params.scale.x, vec3<f32>(F32_MAX));
}

@compute @workgroup_size(8, 8)
fn compose(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    let i = id.y * params.size.x + id.x;
    let d = scene_units(direct[i].xyz);
    let e = scene_units(indirect[i].xyz);
    textureStore(out_image, vec2<i32>(id.xy), vec4<f32>(min(d + e, vec3<f32>(F32_MAX)), 1.0));
}
