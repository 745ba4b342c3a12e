//! Shared helpers for GPU tests (they run on lavapipe in CI: `apt-get install mesa-vulkan-drivers`).
#![allow(dead_code)]

use fuzzy_vpl::cpu::kmeans::RepPoint;
use fuzzy_vpl::cpu::shading::CpuScene;
use fuzzy_vpl::gi::primary::ShadingPoint;
use fuzzy_vpl::gpu::GpuContext;
use fuzzy_vpl::render::{RenderSettings, Renderer};
use fuzzy_vpl::scene::{Camera, Scene};
use fuzzy_vpl::settings::FrameSettings;

pub fn gpu() -> GpuContext {
    GpuContext::new_headless().unwrap_or_else(|e| {
        panic!("no wgpu adapter: {e:#}. Install Mesa's software Vulkan driver: apt-get install mesa-vulkan-drivers")
    })
}

pub fn all_finite(img: &[[f32; 3]]) -> bool {
    img.iter().flatten().all(|c| c.is_finite())
}

/// Deterministic xorshift for test data.
pub struct Rand(pub u64);
impl Rand {
    pub fn next_u32(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 32) as u32
    }
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / 16777216.0
    }
}

/// A scratch directory unique to this test.
pub fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("fuzzy-vpl-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The CPU twins' view of what `r` uploaded for scene `s` (the scene as loaded: the twins shade in
/// its units, as the frames come back in them).
pub fn cpu_scene<'a>(r: &'a Renderer<'_>, s: &'a Scene) -> CpuScene<'a> {
    CpuScene {
        scene: s,
        bvh: &r.bvh,
        info: r.gpu.info,
        emitters: &r.gpu.emitters,
    }
}

/// The lines of stderr that are ours (drivers and X libraries may print their own).
pub fn error_lines(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("error: "))
        .collect()
}

/// A cold start's representative points: each cluster's member pixel's shading point (`reps`: the
/// GPU's (distance bits, member) pairs, the member `u32::MAX` for an unused cluster).
pub fn cold_rep_points(sps: &[ShadingPoint], reps: &[u32]) -> Vec<RepPoint> {
    reps.chunks(2)
        .map(|x| match x[1] {
            u32::MAX => RepPoint::NONE,
            m => RepPoint {
                pos: sps[m as usize].pos,
                valid: true,
                nrm: sps[m as usize].normal,
                previous: false,
            },
        })
        .collect()
}

/// Runs the fuzzy-vpl binary with `args`: (exit code, stdout, stderr).
pub fn run_cli(args: &[&str]) -> (i32, String, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_fuzzy-vpl"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Asserts that the CLI refuses `args` with exit 2 and one error line containing `needle`.
pub fn assert_refused(args: &[&str], needle: &str) {
    let (code, _, err) = run_cli(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    let lines = error_lines(&err);
    assert_eq!(lines.len(), 1, "{args:?}: {err}");
    assert!(lines[0].contains(needle), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

/// How far a GPU value is from its CPU twin's: the largest channel difference over 1 + the twin's
/// largest channel (relative above 1, absolute below).
pub fn twin_diff(c: glam::Vec3, g: glam::Vec3) -> f32 {
    (c - g).abs().max_element() / (1.0 + c.abs().max_element())
}

/// The driver families whose bounds `BOUNDS` holds, in its columns' order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    Lavapipe,
    Nvidia,
    Amd,
    Intel,
    Apple,
}

/// The viewer tests' small frame (`view` and `render` arguments): `builtin:cornell` at 160 × 120,
/// 512 VPLs, K_SP 64, K_VPL 64.
pub const CORNELL_160: [&str; 11] = [
    "builtin:cornell",
    "--width",
    "160",
    "--height",
    "120",
    "--vpls",
    "512",
    "--sp-clusters",
    "64",
    "--vpl-clusters",
    "64",
];

/// The Mesa release lavapipe's bounds were measured on (`.ci/run` installs it): lavapipe of another
/// release is an unmeasured adapter.
pub const MEASURED_MESA: &str = "Mesa 22.3.6";

/// The family of `ctx`'s adapter whose measured bounds apply, None where none does (lavapipe of
/// another Mesa release than `MEASURED_MESA`, another vendor). `FVPL_BOUNDS_UNMEASURED=1` treats
/// any adapter as unmeasured (to try the relative bounds on lavapipe).
pub fn family(ctx: &GpuContext) -> Option<Family> {
    if std::env::var_os("FVPL_BOUNDS_UNMEASURED").is_some() {
        return None;
    }
    if ctx.software {
        let measured = ctx.driver.contains("llvmpipe") && ctx.driver.contains(MEASURED_MESA);
        return measured.then_some(Family::Lavapipe);
    }
    match ctx.adapter.get_info().vendor {
        0x10de => Some(Family::Nvidia),
        0x1002 => Some(Family::Amd),
        0x8086 => Some(Family::Intel),
        0x106b => Some(Family::Apple),
        _ => None,
    }
}

/// The bound a comparison takes on an adapter where it is not measured: every item within this
/// relative difference (`rel_diff` for value pairs, the measure itself for the measures that are
/// relative already), and no item of a count allowed to differ.
pub const UNMEASURED_REL: f32 = 1e-4;

/// Each comparison's bound per driver family (columns: lavapipe, NVIDIA, AMD, Intel, Apple), the
/// measured maximum × 2 (2 significant digits, rounded up), 0 where the twins agree bit for bit;
/// None where it is not measured (the comparison then checks every item at `UNMEASURED_REL`).
/// Kinds: a `twin` key bounds `twin_diff` of every (CPU, GPU) pair (`assert_twins`); a `measure`
/// key a worst difference the test computes (`assert_measure`); a `differ` key the items allowed to
/// differ (`assert_differ`). Measured: lavapipe (Mesa 22.3.6, 2-core VM) 2026-11-26/28 (the
/// figures in docs/testing.md, "Twin tolerances"); NVIDIA, AMD, Intel, Apple not measured. To
/// measure on an adapter: `scripts/gpu-tests` (prints each key's maximum and the bound to paste).
#[rustfmt::skip]
pub const BOUNDS: &[(&str, [Option<f32>; 5])] = &[
    // key                                   lavapipe        NVIDIA AMD   Intel Apple
    ("accumulate::twin",                     [Some(0.0),     None, None, None, None]),
    ("clustered::shading",                   [Some(5.3e-8),  None, None, None, None]),
    ("clustered::shading_131072_lights",     [Some(2.2e-6),  None, None, None, None]),
    ("cvrtgi::visibility_lists_differ",      [Some(0.0),     None, None, None, None]),
    ("cvrtgi::escape_fractions_differ",      [Some(0.0),     None, None, None, None]),
    ("cvrtgi::slot_flux",                    [Some(4.4e-7),  None, None, None, None]),
    ("cvrtgi::gather",                       [Some(4.4e-7),  None, None, None, None]),
    ("cvrtgi::filter",                       [Some(1.1e-6),  None, None, None, None]),
    ("cvrtgi::lookup",                       [Some(0.0),     None, None, None, None]),
    ("gltf_features::alpha_hit_miss_differ", [Some(0.0),     None, None, None, None]),
    ("gltf_features::alpha_position",        [Some(5.4e-7),  None, None, None, None]),
    ("gltf_features::alpha_direct",          [Some(0.0),     None, None, None, None]),
    ("gltf_features::alpha_reference",       [Some(1.5e-8),  None, None, None, None]),
    ("gltf_features::alpha_clustered",       [Some(7.4e-9),  None, None, None, None]),
    ("kmeans::assignments_differ",           [Some(0.0),     None, None, None, None]),
    ("kmeans::objective",                    [Some(0.0),     None, None, None, None]),
    ("kmeans::rep_weights",                  [Some(0.0),     None, None, None, None]),
    ("kmeans::weight_exponent",              [Some(2.6e-6),  None, None, None, None]),
    ("kmeans::gated_rows_differ",            [Some(0.0),     None, None, None, None]),
    ("kmeans::gated_weights",                [Some(0.0),     None, None, None, None]),
    ("methods::wang_seeds_differ",           [Some(0.0),     None, None, None, None]),
    ("methods::wang_labels_differ",          [Some(0.0),     None, None, None, None]),
    ("methods::wang_samples_differ",         [Some(0.0),     None, None, None, None]),
    ("methods::wang_centres",                [Some(0.0),     None, None, None, None]),
    ("methods::wang_40x30_gather",           [Some(5.2e-8),  None, None, None, None]),
    ("methods::wang_40x30_radius",           [Some(5.2e-7),  None, None, None, None]),
    ("methods::wang_40x30_interpolation",    [Some(4.8e-8),  None, None, None, None]),
    ("methods::wang_128x96_gather",          [Some(2.9e-7),  None, None, None, None]),
    ("methods::wang_128x96_radius",          [Some(3.3e-6),  None, None, None, None]),
    ("methods::wang_128x96_interpolation",   [Some(5.2e-8),  None, None, None, None]),
    ("methods::lightcluster",                [Some(1.8e-7),  None, None, None, None]),
    ("reference::eq5",                       [Some(1.8e-7),  None, None, None, None]),
    ("reference::eq5_4096_vpls",             [Some(2.7e-7),  None, None, None, None]),
    ("render::hit_miss_differ",              [Some(0.0),     None, None, None, None]),
    ("render::sp_position",                  [Some(7.8e-7),  None, None, None, None]),
    ("render::sp_normal",                    [Some(1.2e-7),  None, None, None, None]),
    ("render::sp_albedo",                    [Some(1.2e-7),  None, None, None, None]),
    ("render::sp_emission",                  [Some(0.0),     None, None, None, None]),
    ("render::direct",                       [Some(1.4e-7),  None, None, None, None]),
    ("render::direct_8192_samples",          [Some(7.0e-7),  None, None, None, None]),
    ("render::direct_many_lights",           [Some(7.2e-7),  None, None, None, None]),
    ("temporal::warm_centroids",             [Some(0.0),     None, None, None, None]),
    ("upsample::twin",                       [Some(5.9e-7),  None, None, None, None]),
];

/// `key`'s measured bound on `ctx`'s adapter, None where not measured. Panics on a key not in
/// `BOUNDS` (every comparison has its row).
pub fn bound(ctx: &GpuContext, key: &str) -> Option<f32> {
    let row = BOUNDS
        .iter()
        .find(|(k, _)| *k == key)
        .unwrap_or_else(|| panic!("{key}: not in common::BOUNDS"));
    family(ctx).and_then(|f| row.1[f as usize])
}

/// `FVPL_MEASURE_BOUNDS=1` (`scripts/gpu-tests`): a bound exceeded is printed (`OVER`), not a
/// failure, so that one run measures every comparison.
fn measuring() -> bool {
    std::env::var_os("FVPL_MEASURE_BOUNDS").is_some()
}

/// Prints `key`'s measured figure in the form `scripts/gpu-tests` collects (`bound KEY: measured X |
/// BOUND | FAMILY | DRIVER | WHAT`), and fails (or with `FVPL_MEASURE_BOUNDS`, says OVER) when `ok`
/// is false.
fn report(ctx: &GpuContext, key: &str, measured: f64, bound: &str, ok: bool, what: &str) {
    let over = if ok { "" } else { " OVER" };
    let family = family(ctx).map_or("unmeasured".to_string(), |f| format!("{f:?}"));
    let line = format!(
        "bound {key}: measured {measured:.3e}{over} | {bound} | {family} | {} | {what}",
        ctx.driver
    );
    // To stderr past libtest's capture, so that the figure is seen in a plain `cargo test` too.
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{line}");
    assert!(ok || measuring(), "{line}");
}

fn bound_text(b: Option<f32>, unmeasured: &str) -> String {
    match b {
        Some(b) => format!("measured bound {b:.1e}"),
        None => format!("bound unmeasured on this adapter: {unmeasured}, every item checked"),
    }
}

/// Relative difference for an adapter without a measured bound: the largest channel difference
/// over the CPU value's largest channel, or over 1e-3 of the brightest CPU value if it is dimmer.
pub fn rel_diff(c: glam::Vec3, g: glam::Vec3, peak: f32) -> f32 {
    let d = (c - g).abs().max_element();
    if d == 0.0 {
        return 0.0;
    }
    d / c
        .abs()
        .max_element()
        .max(1e-3 * peak)
        .max(f32::MIN_POSITIVE)
}

/// Asserts every (CPU twin, GPU) pair finite and every one within `key`'s measured bound on
/// `twin_diff` (`BOUNDS`; docs/testing.md, "Twin tolerances"); on an adapter without one, every
/// pair within `UNMEASURED_REL` of `rel_diff`, said in the output. No pair is left unchecked.
/// Prints the worst `twin_diff` (`bound KEY: measured …`, collected by `scripts/gpu-tests`) and
/// returns it.
pub fn assert_twins(
    ctx: &GpuContext,
    name: &str,
    key: &str,
    pairs: impl IntoIterator<Item = (glam::Vec3, glam::Vec3)>,
) -> f32 {
    let pairs: Vec<_> = pairs.into_iter().collect();
    let peak = pairs
        .iter()
        .map(|(c, _)| c.abs().max_element())
        .fold(0f32, f32::max);
    let b = bound(ctx, key);
    let (mut worst, mut at, mut worst_rel, mut at_rel) = (0f32, None, 0f32, None);
    for (i, &(c, g)) in pairs.iter().enumerate() {
        assert!(
            c.is_finite() && g.is_finite(),
            "{name}: item {i}: CPU {c}, GPU {g}"
        );
        let d = twin_diff(c, g);
        if d > worst {
            (worst, at) = (d, Some((i, c, g)));
        }
        let r = rel_diff(c, g, peak);
        if r > worst_rel {
            (worst_rel, at_rel) = (r, Some((i, c, g)));
        }
    }
    let n = pairs.len();
    let (ok, at) = match b {
        Some(b) => (worst <= b, at),
        None => (worst_rel <= UNMEASURED_REL, at_rel),
    };
    let text = bound_text(
        b,
        &format!("relative {UNMEASURED_REL:.0e}, worst {worst_rel:.3e}"),
    );
    report(
        ctx,
        key,
        worst as f64,
        &text,
        ok,
        &format!("{name}, {n} items, worst at (item, CPU, GPU) {at:?}"),
    );
    worst
}

/// Asserts a worst difference the test computed (a relative or normalised measure) within `key`'s
/// measured bound, or `UNMEASURED_REL` where none is measured; prints it for `scripts/gpu-tests`.
pub fn assert_measure(ctx: &GpuContext, key: &str, what: &str, worst: f32) {
    let b = bound(ctx, key);
    let ok = worst.is_finite() && worst <= b.unwrap_or(UNMEASURED_REL);
    let text = bound_text(b, &format!("{UNMEASURED_REL:.0e}"));
    report(ctx, key, worst as f64, &text, ok, what);
}

/// Asserts that at most `key`'s measured count of `of` items differ from their twins (0 where none
/// is measured: every item must agree); prints the count for `scripts/gpu-tests`.
pub fn assert_differ(ctx: &GpuContext, key: &str, what: &str, differ: usize, of: usize) {
    let b = bound(ctx, key);
    let ok = differ as f64 <= b.unwrap_or(0.0) as f64;
    let text = bound_text(b, "none may differ");
    report(
        ctx,
        key,
        differ as f64,
        &text,
        ok,
        &format!("{what}: {differ} of {of} differ"),
    );
}

/// Writes `SKIPPED test: why` to stderr (past libtest's capture) and to the skip log that
/// `.ci/run` counts in its summary (`$FVPL_SKIP_LOG`, if set).
pub fn skipped(test: &str, why: &str) {
    use std::io::Write;
    let line = format!("SKIPPED {test}: {why}");
    let _ = writeln!(std::io::stderr(), "{line}");
    let log = std::env::var_os("FVPL_SKIP_LOG");
    let file = log.and_then(|l| {
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(l)
            .ok()
    });
    if let Some(mut f) = file {
        let _ = writeln!(f, "{line}");
    }
}

/// `../shared/scenes` (the real scenes beside the clone), or None after `skipped` when it is
/// absent; with `FVPL_REQUIRE_SCENES` set (`.ci/run`) its absence fails the test with one line
/// naming the folder.
pub fn shared_scenes(test: &str) -> Option<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var_os("FVPL_REQUIRE_SCENES").is_none(),
        "{} is absent and FVPL_REQUIRE_SCENES is set",
        dir.display()
    );
    skipped(test, &format!("{} is absent", dir.display()));
    None
}

/// The failure mode of cornell_wgpu (docs/methods.md, "Indirect light, per method") in a
/// built-in room: builtin:cornell with its ceiling light replaced by a closed emitting slab of the
/// same footprint and emission, 1.7e-3 scene diagonals thick, its top 5.9e-5 diagonals under the
/// ceiling (cornell_wgpu's 0.0058 and 0.0002 in its 3.4 diagonal). Half its light goes up into the
/// gap, where the VPLs it makes on the ceiling are hidden from the room.
pub fn slab_under_ceiling() -> Scene {
    use glam::{Vec2, Vec3, Vec4};
    let mut s = fuzzy_vpl::scene::load("builtin:cornell").unwrap();
    let emitting: Vec<bool> = s
        .materials
        .iter()
        .map(|m| m.emissive != Vec3::ZERO)
        .collect();
    let emits = |t: &fuzzy_vpl::scene::Triangle| emitting[t.material as usize];
    let lamp: Vec<_> = s.triangles.iter().filter(|t| emits(t)).copied().collect();
    assert!(!lamp.is_empty());
    let material = lamp[0].material;
    s.triangles.retain(|t| !emits(t));
    let (lo, hi) = lamp.iter().flat_map(|t| t.p).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    let (blo, bhi) = s.bounds();
    let diag = (bhi - blo).length();
    let top = bhi.y - 5.9e-5 * diag;
    let bottom = top - 1.7e-3 * diag;
    let (x0, x1, z0, z1) = (lo.x, hi.x, lo.z, hi.z);
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    // The six faces, each as a quad (a, b, c, d) wound outwards.
    let quads = [
        [
            c(x0, top, z0),
            c(x0, top, z1),
            c(x1, top, z1),
            c(x1, top, z0),
        ],
        [
            c(x0, bottom, z0),
            c(x1, bottom, z0),
            c(x1, bottom, z1),
            c(x0, bottom, z1),
        ],
        [
            c(x0, bottom, z0),
            c(x0, bottom, z1),
            c(x0, top, z1),
            c(x0, top, z0),
        ],
        [
            c(x1, bottom, z0),
            c(x1, top, z0),
            c(x1, top, z1),
            c(x1, bottom, z1),
        ],
        [
            c(x0, bottom, z0),
            c(x0, top, z0),
            c(x1, top, z0),
            c(x1, bottom, z0),
        ],
        [
            c(x0, bottom, z1),
            c(x1, bottom, z1),
            c(x1, top, z1),
            c(x0, top, z1),
        ],
    ];
    for q in quads {
        for [a, b, d] in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            let n = (b - a).cross(d - a).normalize();
            s.triangles.push(fuzzy_vpl::scene::Triangle {
                p: [a, b, d],
                n: [n; 3],
                uv: [Vec2::ZERO; 3],
                color: [Vec4::ONE; 3],
                material,
            });
        }
    }
    s.name = "slab-under-ceiling".into();
    s
}

/// colom's report in a frame (`counts.colom`: SP iterations, warm start, visibility rows reused);
/// the default where colom did not run or its counts were not read back.
pub fn colom(f: &fuzzy_vpl::render::Frame) -> fuzzy_vpl::method::colom::Report {
    fuzzy_vpl::method::colom::Report::of(f.report_of(fuzzy_vpl::method::Method::Colom))
        .unwrap_or_default()
}

/// The GPU's SP clustering of a renderer's last frame, read back.
pub struct SpClusters {
    /// The frame's shading points.
    pub sps: Vec<ShadingPoint>,
    /// Each pixel's `nf` slots' clusters.
    pub assign: Vec<u32>,
    /// Each pixel's `nf` slots' weights.
    pub weights: Vec<f32>,
    /// A cold start's representative points (`cold_rep_points` of the GPU's members).
    pub reps: Vec<RepPoint>,
    /// The clusters.
    pub k: usize,
    /// The slots a pixel.
    pub nf: usize,
}

/// `r`'s last frame's SP clustering, read back on `ctx`.
pub fn sp_clusters(ctx: &GpuContext, r: &Renderer) -> SpClusters {
    let sps = shading_points(r);
    let c = r.sp_clustering().unwrap();
    let (k, nf) = (c.k() as usize, c.f() as usize);
    let assign: Vec<u32> = ctx.read_buffer(&c.assign, sps.len() * nf).unwrap();
    let weights: Vec<f32> = ctx.read_buffer(&c.weights, sps.len() * nf).unwrap();
    let members: Vec<u32> = ctx.read_buffer(&c.reps, k * 2).unwrap();
    // A cold start: each representative point is its member pixel's shading point.
    let reps = cold_rep_points(&sps, &members);
    SpClusters {
        k,
        nf,
        sps,
        assign,
        weights,
        reps,
    }
}

impl SpClusters {
    /// Pixel `m`'s slots, as the shading twin reads them (`weighted`: inverse-distance weights).
    pub fn slots(&self, m: usize, weighted: bool) -> fuzzy_vpl::cpu::shade::Slots<'_> {
        let at = m * self.nf..m * self.nf + self.nf;
        fuzzy_vpl::cpu::shade::Slots {
            assign: &self.assign[at.clone()],
            weights: &self.weights[at],
            weighted,
        }
    }
}

/// Settings for a `width` × `height` frame with no VPLs and one direct sample (a frame rendered
/// for its G-buffer).
pub fn gbuffer_settings(width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width,
            height,
            vpls: 0,
            direct_samples: 1,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A camera named "down" at `eye` looking at `target` with vertical field of view `yfov`, the
/// image's up towards −z.
pub fn down_camera(eye: glam::Vec3, target: glam::Vec3, yfov: f32) -> Camera {
    Camera::look_at("down", eye, target, glam::Vec3::NEG_Z, yfov)
}

/// `builtin:cornell` and its upload on `ctx`.
pub fn cornell_gpu(ctx: &GpuContext) -> (Scene, fuzzy_vpl::gi::scene_gpu::SceneGpu) {
    let sc = fuzzy_vpl::scene::load("builtin:cornell").unwrap();
    let bvh = fuzzy_vpl::bvh::SceneBvh::build(&sc).unwrap();
    let gpu = fuzzy_vpl::gi::scene_gpu::SceneGpu::upload(ctx, &sc, &bvh);
    (sc, gpu)
}

/// `km` over `points` (the data, `stride` vec4s a point) with settings `s` in `frame`, on `ctx`
/// with `builtin:cornell` bound, profiled under `label`: the clustering.
pub fn kmeans_on_cornell(
    ctx: &GpuContext,
    km: &fuzzy_vpl::gi::kmeans::KMeans,
    label: &str,
    (data, stride): (&[[f32; 4]], u32),
    s: &fuzzy_vpl::gi::kmeans::KMeansSettings,
    frame: (glam::Vec3, glam::Vec3),
) -> fuzzy_vpl::gi::kmeans::Clustering {
    let (_sc, gpu) = cornell_gpu(ctx);
    let mut prof = fuzzy_vpl::gpu::profiler::Profiler::new(ctx);
    let buf = ctx.storage_init("data", data);
    let mut g = fuzzy_vpl::gi::dispatch::Gpu {
        ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let points = fuzzy_vpl::gi::kmeans::Points {
        data: &buf,
        count: data.len() as u32 / stride,
        stride,
    };
    km.run(&mut g, label, &points, s, frame, None).unwrap()
}

/// The display tests' frame: 48 × 36, 256 VPLs, 2 direct samples, K_SP 48, K_VPL 64, `weighting`.
pub fn display_frame(weighting: fuzzy_vpl::settings::Weighting) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: 48,
            height: 36,
            vpls: 256,
            direct_samples: 2,
            ..Default::default()
        },
        cluster: fuzzy_vpl::settings::ClusterSettings {
            sp_clusters: 48,
            vpl_clusters: 64,
            weighting,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Runs the display pass `d` on `inputs` and reads its texture (RGBA8) and exposure back.
pub fn draw_display(
    ctx: &GpuContext,
    d: &mut fuzzy_vpl::app::display::Display,
    inputs: &fuzzy_vpl::app::display::DisplayInputs,
) -> (Vec<u8>, f32) {
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    d.record(&ctx.device, &ctx.queue, &mut enc, inputs);
    ctx.queue.submit([enc.finish()]);
    let texture = &d.target().unwrap().texture;
    let rgba = fuzzy_vpl::gpu::read_texture(&ctx.device, &ctx.queue, texture).unwrap();
    let e: Vec<f32> = ctx.read_buffer(d.exposure_buffer(), 1).unwrap();
    (rgba, e[0])
}

/// `r`'s last frame's shading points.
pub fn shading_points(r: &Renderer) -> Vec<ShadingPoint> {
    let gbuffer = r.last_gbuffer().unwrap();
    gbuffer.chunks(4).map(ShadingPoint::from_gpu).collect()
}

/// A command line: `words` split at white space, then `rest` (paths and other arguments that
/// are not plain words).
pub fn cmd<'a>(words: &'a str, rest: &[&'a str]) -> Vec<&'a str> {
    words
        .split_whitespace()
        .chain(rest.iter().copied())
        .collect()
}

/// `p` as an argument (test paths are UTF-8).
pub fn arg(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// The JSON file at `p` (a stats file, a trace, a bench report).
pub fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}
