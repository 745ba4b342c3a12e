// Sampling helpers; mirrored by crates/core/src/cpu/sampling.rs.

// An orthonormal basis around unit n (Duff et al. 2017).
fn onb(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}

// Cosine-distributed direction around unit n (pdf = cos / pi).
fn cosine_hemisphere(n: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    let local = vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u1)));
    return normalize(onb(n) * local);
}

// Uniform barycentrics (b1, b2) on a triangle.
fn sample_triangle(u1: f32, u2: f32) -> vec2<f32> {
    let s = sqrt(u1);
    return vec2<f32>(1.0 - s, u2 * s);
}
