// The pinhole camera of the primary rays (`gi::primary::CameraParams`, render units): what
// primary.wgsl traces from and accumulate.wgsl projects the previous frame's points with.
struct CameraParams {
    eye: vec4<f32>,
    // Image-plane axes at unit distance, scaled by tan(fov/2) (and the aspect ratio for `right`).
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
    // width, height, and the rays' sub-pixel jitter (x, y as f32 bits; 0: pixel centres).
    size: vec4<u32>,
}
