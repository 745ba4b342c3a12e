//! Scenes: the flattened, world-space triangle soup the renderer consumes.
//!
//! A `Scene` is produced by the glTF loader (`gltf_load`), from a built-in asset (`builtin`), and then
//! optionally extended with command-line lights (`extra_lights`). Everything downstream (BVH, GPU upload,
//! VPL tracing) reads only this structure.

pub mod builtin;
pub mod extra_lights;
pub mod gltf_load;

use glam::{Mat4, Vec2, Vec3, Vec4};
use std::path::PathBuf;

/// One triangle in world space with its shading attributes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// World-space vertex positions.
    pub p: [Vec3; 3],
    /// World-space unit shading normals (generated from the face when the file has none or they are invalid).
    pub n: [Vec3; 3],
    /// Texture coordinates (TEXCOORD_0), zero when absent.
    pub uv: [Vec2; 3],
    /// Linear vertex colours (COLOR_0, RGBA in [0, 1]), multiplying the base colour and its alpha;
    /// white when absent.
    pub color: [Vec4; 3],
    /// Index into `Scene::materials`.
    pub material: u32,
}

impl Triangle {
    pub fn area(&self) -> f32 {
        0.5 * (self.p[1] - self.p[0])
            .cross(self.p[2] - self.p[0])
            .length()
    }
    pub fn geometric_normal(&self) -> Vec3 {
        (self.p[1] - self.p[0])
            .cross(self.p[2] - self.p[0])
            .normalize_or_zero()
    }
}

/// A diffuse material (the paper's system handles diffuse surfaces only).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear base colour factor (RGBA). Its alpha matters only with an alpha test.
    pub base_color: Vec4,
    pub base_color_texture: Option<u32>,
    /// The alpha test's cutoff (glTF `alphaMode` MASK, `alphaCutoff`, default 0.5; BLEND is treated
    /// as MASK at 0.5): a ray hit whose alpha (factor × texture × vertex colour) is below it is no
    /// hit. `None`: opaque.
    pub alpha_cutoff: Option<f32>,
    /// Emitted radiance factor: glTF `emissiveFactor` × `KHR_materials_emissive_strength`.
    pub emissive: Vec3,
    pub emissive_texture: Option<u32>,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            alpha_cutoff: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
        }
    }
}

/// An 8-bit RGBA texture. Base colour and emissive textures are sRGB-encoded (glTF spec); the GPU
/// decodes on fetch. Sampling wraps (repeat).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// `width * height` texels, row-major, RGBA8.
    pub rgba8: Vec<[u8; 4]>,
}

impl Texture {
    /// The smallest texel alpha, in [0, 1]: no bilinear sample of the texture is below it.
    pub fn min_alpha(&self) -> f32 {
        self.rgba8.iter().map(|c| c[3]).min().unwrap_or(255) as f32 / 255.0
    }
}

/// Set (to anything) to render every material opaque: the alpha test's cost is measured against it
/// (docs/scenes.md). Not for ordinary use.
pub const NO_ALPHA_TEST_ENV: &str = "FVPL_NO_ALPHA_TEST";

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Intensity in W/sr-like units (glTF: candela).
    Point,
    /// Cone angles in radians.
    Spot { inner_cone: f32, outer_cone: f32 },
    /// Irradiance at normal incidence (glTF: lux).
    Directional,
}

/// A `KHR_lights_punctual` light (or one added from the command line), in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PunctualLight {
    pub kind: LightKind,
    pub position: Vec3,
    /// Unit direction the light travels along (spot axis / sun rays). Unused for point lights.
    pub direction: Vec3,
    /// Linear RGB colour; the emitted quantity is `color × intensity`.
    pub color: Vec3,
    pub intensity: f32,
}

impl PunctualLight {
    /// Whether it emits anything (colour × intensity above zero somewhere).
    pub fn emits(&self) -> bool {
        (self.color * self.intensity).max_element() > 0.0
    }
}

/// A perspective camera in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    /// Camera-to-world transform; the camera looks down its local -Z with +Y up (glTF convention).
    pub transform: Mat4,
    /// Vertical field of view in radians.
    pub yfov: f32,
}

impl Camera {
    /// The same camera in a frame scaled by `k` about the origin (its eye moved, in f64, its axes and
    /// field of view kept): `Renderer::to_render_units` with the renderer's `geometry_scale`.
    pub fn with_eye_scaled(&self, k: f64) -> Camera {
        let mut c = self.clone();
        if k != 1.0 {
            let eye = c.transform.w_axis.truncate().as_dvec3() * k;
            c.transform.w_axis = eye.as_vec3().extend(1.0);
        }
        c
    }

    pub fn eye(&self) -> Vec3 {
        self.transform.w_axis.truncate()
    }
    pub fn forward(&self) -> Vec3 {
        (-self.transform.z_axis.truncate()).normalize()
    }
    pub fn up(&self) -> Vec3 {
        self.transform.y_axis.truncate().normalize()
    }
    pub fn look_at(name: &str, eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Camera {
        let f = (target - eye).normalize();
        let right = f.cross(up).normalize();
        let up = right.cross(f);
        Camera {
            name: name.to_string(),
            transform: Mat4::from_cols(
                right.extend(0.0),
                up.extend(0.0),
                (-f).extend(0.0),
                eye.extend(1.0),
            ),
            yfov,
        }
    }
}

/// What the loader saw and did, for `info` and warnings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadReport {
    /// glTF extensions the file declares as used.
    pub extensions_used: Vec<String>,
    /// Degenerate or zero-area triangles dropped (not an error).
    pub dropped_degenerate: usize,
    /// Triangles whose normals were generated (absent, NaN or zero in the file).
    pub generated_normals: usize,
    /// Non-triangle primitives (points, lines) skipped.
    pub skipped_primitives: usize,
    /// Human-readable warnings (printed to stderr by the CLI).
    pub warnings: Vec<String>,
    /// The external files (buffers, images) the scene's URIs name, resolved: inputs that no output
    /// of the run may overwrite.
    pub files: Vec<PathBuf>,
}

/// A loaded scene, flattened to world space.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// `builtin:NAME` or the file path as given.
    pub name: String,
    pub path: Option<PathBuf>,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<PunctualLight>,
    pub cameras: Vec<Camera>,
    pub report: LoadReport,
}

impl Scene {
    /// Axis-aligned bounds of all triangles; `(ZERO, ZERO)` for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &self.triangles {
            for p in t.p {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if lo.x > hi.x {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (lo, hi)
        }
    }

    /// Length of the bounds' diagonal, at least a tiny positive number.
    pub fn extent(&self) -> f32 {
        let (lo, hi) = self.bounds();
        (hi - lo).length().max(1e-30)
    }

    pub fn is_emissive(&self, t: &Triangle) -> bool {
        let m = &self.materials[t.material as usize];
        m.emissive.max_element() > 0.0
    }

    pub fn emissive_triangle_count(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| self.is_emissive(t))
            .count()
    }

    /// Whether anything emits: an emissive triangle or a punctual light of non-zero power (a light
    /// scaled to 0 with `--light-scale 0`, or given intensity 0, is none).
    pub fn has_light(&self) -> bool {
        self.lights.iter().any(PunctualLight::emits) || self.emissive_triangle_count() > 0
    }

    /// Per triangle: whether rays alpha-test it. A triangle is tested when its material has an alpha
    /// cutoff and its alpha can fall below it: the lowest alpha it can show (factor × the texture's
    /// smallest texel alpha × its smallest vertex alpha; bilinear filtering and barycentric
    /// interpolation never go below their inputs) is under the cutoff. Every other triangle keeps
    /// the opaque fast path. All false with `FVPL_NO_ALPHA_TEST` set.
    pub fn alpha_test_flags(&self) -> Vec<bool> {
        if std::env::var_os(NO_ALPHA_TEST_ENV).is_some() {
            return vec![false; self.triangles.len()];
        }
        // Per material: the lowest alpha its factor and texture allow, and its cutoff.
        let bound: Vec<Option<(f32, f32)>> = self
            .materials
            .iter()
            .map(|m| {
                let cutoff = m.alpha_cutoff?;
                let tex = m
                    .base_color_texture
                    .and_then(|t| self.textures.get(t as usize))
                    .map_or(1.0, Texture::min_alpha);
                Some((m.base_color.w * tex, cutoff))
            })
            .collect();
        self.triangles
            .iter()
            .map(|t| match bound[t.material as usize] {
                Some((lo, cutoff)) => {
                    let v = t.color.iter().map(|c| c.w).fold(1.0f32, f32::min);
                    lo * v < cutoff
                }
                None => false,
            })
            .collect()
    }

    /// Whether any triangle is alpha-tested (`alpha_test_flags`).
    pub fn uses_alpha_test(&self) -> bool {
        self.alpha_test_flags().into_iter().any(|f| f)
    }

    /// Whether any triangle has a vertex colour other than white.
    pub fn uses_vertex_colors(&self) -> bool {
        self.triangles
            .iter()
            .any(|t| t.color.iter().any(|&c| c != Vec4::ONE))
    }

    pub fn uses_textures(&self) -> bool {
        self.materials
            .iter()
            .any(|m| m.base_color_texture.is_some() || m.emissive_texture.is_some())
    }

    /// The default view: the first glTF camera, else a view framing the bounds from the +Z side
    /// (looking down -Z, +Y up), slightly raised.
    pub fn default_camera(&self) -> Camera {
        if let Some(c) = self.cameras.first() {
            return c.clone();
        }
        let (lo, hi) = self.bounds();
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-30);
        let yfov = 45f32.to_radians();
        let dist = radius / (0.5 * yfov).sin();
        let dir = Vec3::new(0.0, 0.25, 1.0).normalize();
        Camera::look_at("default", center + dir * dist, center, Vec3::Y, yfov)
    }

    /// Multiplies every emitter (emissive materials and punctual lights) by `factor` (in f64, so a factor below f32's normal range still
    /// scales emitters whose product is representable).
    pub fn scale_light_power(&mut self, factor: f64) {
        for m in &mut self.materials {
            m.emissive = (m.emissive.as_dvec3() * factor).as_vec3();
        }
        for l in &mut self.lights {
            scale_intensity(l, factor);
        }
    }

    /// The largest emitted quantity (emissive radiance component, light colour × intensity), in f64:
    /// it may lie beyond f32's range.
    pub fn max_emission(&self) -> f64 {
        let m = self
            .materials
            .iter()
            .map(|m| m.emissive.as_dvec3().max_element())
            .fold(0.0f64, f64::max);
        self.lights
            .iter()
            .map(|l| (l.color.as_dvec3() * l.intensity as f64).max_element())
            .fold(m, f64::max)
    }

    /// The power of two the renderer scales the geometry by (`scale_geometry`): 1 when the
    /// bounds' diagonal lies in 2^-10..2^10, else 2^-round(log2 diagonal), which brings it into
    /// [0.7, 1.42]. A power of two scales every f32 coordinate exactly. In f64: a room 1e-40 across
    /// needs 2^133, beyond f32.
    pub fn geometry_scale(&self) -> f64 {
        // In f64: the f32 diagonal overflows beyond ~1.8e19 (its square does).
        let (lo, hi) = self.bounds();
        let e = (hi.as_dvec3() - lo.as_dvec3()).length();
        if !e.is_finite() || e <= 0.0 || (2f64.powi(-10)..=2f64.powi(10)).contains(&e) {
            return 1.0;
        }
        2f64.powi(-(e.log2().round() as i32))
    }

    /// Scales the scene by `f` (positions of triangles, lights and cameras) keeping its image: a point
    /// or spot light's irradiance I / d² stays the same with I × f² (in f64, folded into the colour
    /// when I alone leaves f32's normal range, as in `scale_light_power`); emitted radiance and
    /// directional irradiance do not depend on the unit. Normals and angles are unchanged.
    pub fn scale_geometry(&mut self, f: f64) {
        let s = |p: Vec3| (p.as_dvec3() * f).as_vec3();
        for t in &mut self.triangles {
            for p in &mut t.p {
                *p = s(*p);
            }
        }
        self.scale_lights(f);
        for c in &mut self.cameras {
            c.transform.w_axis = s(c.transform.w_axis.truncate()).extend(1.0);
        }
    }

    /// The punctual-light part of `scale_geometry`: positions × `f`, point and spot intensities × f².
    pub fn scale_lights(&mut self, f: f64) {
        if f == 1.0 {
            return;
        }
        for l in &mut self.lights {
            l.position = (l.position.as_dvec3() * f).as_vec3();
            if !matches!(l.kind, LightKind::Directional) {
                scale_intensity(l, f * f);
            }
        }
    }

    /// Whether the emitters need `normalize_emission`: their largest is outside 1e-6..1e6.
    pub fn emission_out_of_range(&self) -> bool {
        out_of_range(self.max_emission())
    }

    /// Light transport is linear in emitted power: a scene whose emitters are extreme (beyond 1e±6)
    /// is rendered with its emitters scaled into range, and the image scaled back by the returned
    /// factor. This keeps every intermediate (VPL fluxes, sums, products) finite in f32. The scaling
    /// runs in f64: 1 / m overflows f32 for m below 2.9e-39.
    pub fn normalize_emission(&mut self) -> f32 {
        let m = self.max_emission();
        if !out_of_range(m) {
            return 1.0;
        }
        self.scale_light_power(1.0 / m);
        m as f32
    }

    /// Features the scene uses, for `info` and for choosing passes.
    pub fn features(&self) -> Vec<&'static str> {
        let mut f = Vec::new();
        if self.emissive_triangle_count() > 0 {
            f.push("emissive-triangles");
        }
        if !self.lights.is_empty() {
            f.push("punctual-lights");
        }
        if self.uses_textures() {
            f.push("textures");
        }
        if self
            .materials
            .iter()
            .any(|m| m.emissive_texture.is_some() && m.emissive.max_element() > 0.0)
        {
            f.push("emissive-textures");
        }
        if self.uses_alpha_test() {
            f.push("alpha-test");
        }
        if self.uses_vertex_colors() {
            f.push("vertex-colors");
        }
        if !self.cameras.is_empty() {
            f.push("cameras");
        }
        if self.report.generated_normals > 0 {
            f.push("generated-normals");
        }
        f
    }
}

/// Multiplies a light's emitted quantity (colour × intensity) by `factor`, in f64.
fn scale_intensity(l: &mut PunctualLight, factor: f64) {
    let i = l.intensity as f64 * factor;
    if (i as f32).is_finite() && (i == 0.0 || (i as f32).is_normal()) {
        l.intensity = i as f32;
    } else {
        // The intensity alone leaves f32's normal range (a tiny colour scaled up, a huge one down):
        // keep the product, with the colour's largest component at 1.
        let e = l.color.as_dvec3() * i;
        let peak = e.max_element();
        if peak > 0.0 {
            l.color = (e / peak).as_vec3();
            l.intensity = peak as f32;
        } else {
            l.intensity = 0.0;
        }
    }
}

/// A largest emission that `Scene::normalize_emission` scales into 1e-6..1e6.
fn out_of_range(m: f64) -> bool {
    m.is_finite() && m > 0.0 && !(1e-6..=1e6).contains(&m)
}

/// A scene that could not be used: names the file and the problem in one line.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {problem}")]
pub struct SceneError {
    pub file: String,
    pub problem: String,
}

impl SceneError {
    pub fn new(file: impl Into<String>, problem: impl Into<String>) -> Self {
        SceneError {
            file: file.into(),
            problem: problem.into(),
        }
    }
}

/// How to load a scene file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Required glTF extensions the loader does not know that the user declares safe to ignore
    /// (`--allow-extension NAME`): they must change neither geometry nor diffuse colour.
    pub allow_extensions: Vec<String>,
    /// Whether buffer and image URIs may name files outside the scene file's folder
    /// (`--allow-outside-uris`; README, "URI policy").
    pub allow_outside_uris: bool,
}

/// Loads `builtin:NAME` or a `.gltf`/`.glb` path.
pub fn load(spec: &str) -> Result<Scene, SceneError> {
    load_with(spec, &LoadOptions::default())
}

/// `load` with options.
pub fn load_with(spec: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        builtin::load(name)
    } else {
        gltf_load::load_path_with(std::path::Path::new(spec), opts)
    }
}
