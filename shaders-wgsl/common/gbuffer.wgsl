// A shading point (SP): what the primary pass leaves per pixel.
struct ShadingPoint {
    // xyz position; w = 1 for a valid SP, 0 where the pixel sees nothing.
    pos: vec4<f32>,
    // xyz shading normal facing the camera; w = material index (bitcast).
    nrm: vec4<f32>,
    albedo: vec4<f32>,
    // rgb emitted radiance towards the camera.
    emission: vec4<f32>,
}
