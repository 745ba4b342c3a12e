//! The clustered frame (steps 2, 4, 5, 6) against its CPU twins, the paper's MSE ordering, and the
//! numerical extremes of docs/design.md, "Numerical stability".

mod common;

use fuzzy_vpl::cpu::kmeans::RepPoint;
use fuzzy_vpl::cpu::shade;
use fuzzy_vpl::method::Method;
use fuzzy_vpl::method::colom::Colom;
use fuzzy_vpl::metrics::{mean_luminance, mse};
use fuzzy_vpl::render::{Frame, RenderSettings, Renderer};
use fuzzy_vpl::scene::{self, Scene};
#[allow(unused_imports)]
use fuzzy_vpl::settings::{ClusterSettings, FrameSettings, Gamma, Weighting};
use glam::{Mat4, Vec3};

fn clustered(w: u32, h: u32) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: w,
            height: h,
            vpls: 1024,
            direct_samples: 4,
            ..Default::default()
        },
        cluster: ClusterSettings {
            vpl_clusters: 128,
            sp_clusters: 48,
            fuzziness: 6,
            gamma: Gamma::Fixed(4),
            iterations: 8,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// (CPU twin, GPU) indirect light of every pixel of the clustered frame `f` that `r` rendered with
/// `fs`: the CPU twins of visibility and shading run on the GPU's own clustering and light list.
fn shading_pairs(
    ctx: &fuzzy_vpl::gpu::GpuContext,
    r: &Renderer,
    s: &Scene,
    f: &Frame,
    fs: &RenderSettings,
) -> Vec<(Vec3, Vec3)> {
    let g = common::sp_clusters(ctx, r);
    let (sps, reps) = (&g.sps, &g.reps[..]);
    let c = r.sp_clustering().unwrap();
    let on_gpu = RepPoint::from_vec4s(&ctx.read_buffer(&c.rep_points, g.k * 2).unwrap());
    assert_eq!(on_gpu, reps, "representative points");
    let lights = &r.lights.as_ref().unwrap().list.lights;
    let cpu = common::cpu_scene(r, s);
    let facing = fs.cluster.visibility_facing;
    let (bits, words) = shade::visibility_bits(&cpu, reps, lights, facing);
    let d_min = fs.frame.clamp * s.extent();
    let width = fs.frame.width;
    let tiles = shade::tile_bounds(sps, width, fs.frame.height);
    sps.iter()
        .enumerate()
        .map(|(m, sp)| {
            let c = shade::eq6_indirect(
                sp,
                lights,
                &shade::Bits { bits: &bits, words },
                &g.slots(m, fs.cluster.weighting == Weighting::InverseDistance),
                d_min * d_min,
                fs.cluster.cluster_light,
                tiles[shade::tile_of(m, width)].as_ref(),
            );
            (c, Vec3::from(f.indirect[m]))
        })
        .collect()
}

/// GPU visibility + shading equal the CPU twins given the GPU's clustering and light list.
#[test]
fn clustered_shading_matches_cpu_twin() {
    let ctx = common::gpu();
    let s = scene::load("builtin:conference").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (w, h) = (40u32, 30u32);
    // The three modes with the paper's pure visibility (the default), and the facing test.
    for (weighting, facing) in [
        (Weighting::Hard, false),
        (Weighting::Uniform, false),
        (Weighting::InverseDistance, false),
        (Weighting::InverseDistance, true),
    ] {
        let fs = {
            let mut rs = clustered(w, h);
            rs.cluster.weighting = weighting;
            rs.cluster.visibility_facing = facing;
            rs
        };
        let f = r.render(&s.default_camera(), &fs).unwrap();
        // Every pixel, at the measured maximum × 2 on software (docs/testing.md, "Twin
        // tolerances": 2.6e-8 at most over the three modes).
        let pairs = shading_pairs(&ctx, &r, &s, &f, &fs);
        let name = format!("shading {weighting:?} facing {facing}");
        common::assert_twins(&ctx, &name, "clustered::shading", pairs);
    }
}

/// SP clustering with 131,072 unclustered VPLs as the lights: each pixel walks far more lights than
/// lavapipe's loop budget of 65,535 trips a SIMD batch allows in one dispatch, so the shading runs
/// in ranges of `WORDS_PER_DISPATCH` bit words; it equals the CPU twin on every pixel (with the
/// whole walk in one dispatch the last lights were dropped).
#[test]
fn shading_131072_lights_matches_cpu_twin() {
    let ctx = common::gpu();
    let s = scene::load("builtin:conference").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let fs = {
        let mut rs = clustered(8, 6);
        rs.frame.vpls = 131_072;
        rs.cluster.vpl_clusters = 0;
        rs.cluster.sp_clusters = 4;
        rs
    };
    let f = r.render(&s.default_camera(), &fs).unwrap();
    assert_eq!(r.lights.as_ref().unwrap().list.lights.len(), 131_072);
    // Every pixel, at the measured maximum × 2 on software (1.04e-6; docs/testing.md).
    let pairs = shading_pairs(&ctx, &r, &s, &f, &fs);
    common::assert_twins(
        &ctx,
        "shading 131,072 lights",
        "clustered::shading_131072_lights",
        pairs,
    );
}

/// The paper's ordering at equal K where the measurement supports it: weighted (Eq. 9) below
/// uniform (Eq. 8) in MSE against the reference by at least 5% (measured on lavapipe: hard 5.61e-5,
/// uniform 6.30e-5, weighted 5.52e-5, weighted 12% below uniform). Weighted against hard is not
/// asserted: their 1.6% apart is less than what the seed and the adapter's rounding move (uniform
/// against hard goes either way once the VPL clusters' error is small, docs/clustering.md). The
/// GPU-time speed-up over the reference is printed, not asserted (a clock: `bench` reports it).
#[test]
fn mse_order_on_the_conference_room() {
    let ctx = common::gpu();
    let s = scene::load("builtin:conference").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let (w, h) = (80, 60);
    let base = {
        let mut rs = clustered(w, h);
        rs.frame.vpls = 2048;
        rs.cluster.vpl_clusters = 256;
        rs.cluster.sp_clusters = 96;
        rs
    };
    let reference = r
        .render(
            &cam,
            &RenderSettings {
                reference: true,
                ..base.clone()
            },
        )
        .unwrap();
    let mut errs = Vec::new();
    for weighting in [
        Weighting::Hard,
        Weighting::Uniform,
        Weighting::InverseDistance,
    ] {
        let f = r
            .render(
                &cam,
                &RenderSettings {
                    cluster: ClusterSettings {
                        weighting,
                        ..base.clone().cluster.clone()
                    },
                    ..base.clone()
                },
            )
            .unwrap();
        assert!(common::all_finite(&f.radiance));
        let e = mse(&f.radiance, &reference.radiance);
        let speedup = reference.timings_ms["frame"] / f.timings_ms["frame"];
        println!("{weighting:?}: mse {e:.3e}, speed-up {speedup:.1}x (not asserted)");
        errs.push(e);
    }
    assert!(
        errs[2] <= errs[1] * 0.95,
        "MSE hard, uniform, weighted: {errs:?}"
    );
    assert!(errs[2] < 5e-3, "{errs:?}");
}

/// `s` turned by `r` about the origin: triangles, normals, lights and cameras.
fn rotated(mut s: Scene, r: glam::Quat) -> Scene {
    for t in &mut s.triangles {
        for (p, n) in t.p.iter_mut().zip(&mut t.n) {
            *p = r * *p;
            *n = r * *n;
        }
    }
    for l in &mut s.lights {
        l.position = r * l.position;
        l.direction = r * l.direction;
    }
    for c in &mut s.cameras {
        c.transform = Mat4::from_quat(r) * c.transform;
    }
    s
}

fn scaled(mut s: Scene, k: f32) -> Scene {
    for t in &mut s.triangles {
        for p in &mut t.p {
            *p *= k;
        }
    }
    for c in &mut s.cameras {
        let t = c.transform.w_axis.truncate() * k;
        c.transform = Mat4::from_cols(
            c.transform.x_axis,
            c.transform.y_axis,
            c.transform.z_axis,
            t.extend(1.0),
        );
    }
    s
}

/// docs/design.md, "Numerical stability" on the whole clustered frame: every output finite and the image sane.
#[test]
fn clustered_extremes_stay_finite() {
    let ctx = common::gpu();
    let base = scene::load("builtin:cornell").unwrap();
    let (w, h) = (32, 24);
    let b = clustered(w, h);
    let cases: Vec<(&str, RenderSettings)> = vec![
        (
            "K_sp=1",
            RenderSettings {
                cluster: ClusterSettings {
                    sp_clusters: 1,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "K_vpl=1",
            RenderSettings {
                cluster: ClusterSettings {
                    vpl_clusters: 1,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "K far above the points",
            RenderSettings {
                cluster: ClusterSettings {
                    sp_clusters: w * h - 1,
                    vpl_clusters: 1023,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "F > K",
            RenderSettings {
                cluster: ClusterSettings {
                    sp_clusters: 3,
                    fuzziness: 8,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "F = 16",
            RenderSettings {
                cluster: ClusterSettings {
                    fuzziness: 16,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "huge gamma",
            RenderSettings {
                cluster: ClusterSettings {
                    gamma: Gamma::Fixed(1_000_000),
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "n_t = 1",
            RenderSettings {
                cluster: ClusterSettings {
                    normal_threshold: 1.0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "n_t = 1, one SP cluster",
            RenderSettings {
                cluster: ClusterSettings {
                    sp_clusters: 1,
                    normal_threshold: 1.0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "n_t = 1, one VPL cluster",
            RenderSettings {
                cluster: ClusterSettings {
                    vpl_clusters: 1,
                    normal_threshold: 1.0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "n_t = -1",
            RenderSettings {
                cluster: ClusterSettings {
                    normal_threshold: -1.0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "one VPL",
            RenderSettings {
                frame: FrameSettings {
                    vpls: 1,
                    ..b.clone().frame
                },
                cluster: ClusterSettings {
                    vpl_clusters: 1,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "zero iterations",
            RenderSettings {
                cluster: ClusterSettings {
                    iterations: 0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "200 iterations",
            RenderSettings {
                cluster: ClusterSettings {
                    iterations: 200,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "SPs only",
            RenderSettings {
                cluster: ClusterSettings {
                    vpl_clusters: 0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "VPLs only",
            RenderSettings {
                cluster: ClusterSettings {
                    sp_clusters: 0,
                    ..b.clone().cluster.clone()
                },
                ..b.clone()
            },
        ),
        (
            "no clamp",
            RenderSettings {
                frame: FrameSettings {
                    clamp: 0.0,
                    ..b.clone().frame
                },
                ..b.clone()
            },
        ),
    ];
    let mut r = Renderer::new(&ctx, &base).unwrap();
    let cam = base.default_camera();
    let ind0 = mean_luminance(&r.render(&cam, &b).unwrap().indirect);
    for (name, fs) in cases {
        let f = r.render(&cam, &fs).unwrap();
        assert!(common::all_finite(&f.radiance), "{name}: non-finite pixels");
        let lum = mean_luminance(&f.radiance);
        let ind = mean_luminance(&f.indirect);
        println!(
            "{name}: mean luminance {lum:.4}, indirect {ind:.4} (default settings {ind0:.4}), passes {:?}",
            f.passes
        );
        assert!(lum > 0.05 && lum < 1.0, "{name}: mean luminance {lum}");
        // Consistent: every case still lights the room indirectly (a γ near the pixel count, and
        // n_t = 1 with one cluster, once left no cluster, hence no indirect light, silently).
        assert!(
            ind > 0.5 * ind0 && ind < 2.0 * ind0,
            "{name}: indirect light {ind} against {ind0} with the default settings"
        );
    }
    // Scenes at 1e-4 and 1e4 scale render the same clustered image.
    let mut lums = Vec::new();
    for k in [1.0, 1e-4, 1e4] {
        let s = scaled(base.clone(), k);
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let f = r.render(&s.default_camera(), &b).unwrap();
        assert!(common::all_finite(&f.radiance), "scale {k}");
        lums.push(mean_luminance(&f.radiance));
    }
    println!("clustered mean luminance at scale 1, 1e-4, 1e4: {lums:?}");
    for l in &lums[1..] {
        assert!((l / lums[0] - 1.0).abs() < 0.02, "{lums:?}");
    }
}

/// A camera that sees only sky (no valid SP) and a camera inside a block: finite, and black or dim.
#[test]
fn no_valid_shading_points() {
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (lo, hi) = s.bounds();
    let c = 0.5 * (lo + hi);
    let away = fuzzy_vpl::scene::Camera::look_at(
        "away",
        c - Vec3::Z * 5.0,
        c - Vec3::Z * 10.0,
        Vec3::Y,
        0.6,
    );
    let f = r.render(&away, &clustered(16, 12)).unwrap();
    assert_eq!(f.shading_points, 0);
    assert!(f.radiance.iter().flatten().all(|x| *x == 0.0));
    // Inside the tall block (≈ x 0.27..0.43, z 0.25..0.41, y 0..0.33 in metres).
    let inside = fuzzy_vpl::scene::Camera::look_at(
        "inside",
        Vec3::new(0.35, 0.15, 0.33),
        Vec3::new(0.35, 0.15, 0.0),
        Vec3::Y,
        0.6,
    );
    let f = r.render(&inside, &clustered(16, 12)).unwrap();
    assert!(common::all_finite(&f.radiance));
}

/// The work per submission (`GpuContext::work_scale`: 1 on lavapipe, 256 on a GPU) changes how a pass
/// is split into dispatches, never the image: the reference and the clustered frame come out
/// bit-identical at scale 1 and at scale 64. At scale 1 this size splits the reference into 12
/// submissions (3 pixel ranges × 4 VPL ranges) and the shading into 2 (2^22 terms); at 64 into 4 and 1.
#[test]
fn work_per_submission_does_not_change_the_image() {
    let s = scene::load("builtin:conference").unwrap();
    let cam = s.default_camera();
    let base = {
        let mut rs = clustered(200, 180);
        rs.frame.vpls = 256;
        rs
    };
    let reference = RenderSettings {
        reference: true,
        ..base.clone()
    };
    let mut images = Vec::new();
    for scale in [1, 64] {
        let mut ctx = common::gpu();
        ctx.work_scale = scale;
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let a = r.render(&cam, &reference).unwrap();
        let b = r.render(&cam, &base).unwrap();
        assert!(common::all_finite(&a.radiance) && common::all_finite(&b.radiance));
        images.push((a.radiance, b.radiance));
    }
    assert!(
        images[0].0 == images[1].0,
        "reference differs with the work scale"
    );
    assert!(
        images[0].1 == images[1].1,
        "clustered frame differs with the work scale"
    );
}

/// The shade pass's pattern table (`PATTERNS`, method::colom::shade::patterns) changes how Ṽ is found, never
/// the image: with 0 (Ṽ per light), 1, 3 and 8 patterns a word the indirect light is bit-identical,
/// in Eq. (9) and Eq. (8) mode, at F 6 and F 16 (more patterns than the table holds), on the
/// conference room (shadow edges under the table and chairs give words several patterns).
#[test]
fn the_pattern_table_does_not_change_the_image() {
    let ctx = common::gpu();
    let s = scene::load("builtin:conference").unwrap();
    let cam = s.default_camera();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    for (weighting, f) in [
        (Weighting::InverseDistance, 6),
        (Weighting::Uniform, 6),
        (Weighting::InverseDistance, 16),
    ] {
        let mut rs = clustered(120, 90);
        rs.cluster.weighting = weighting;
        rs.cluster.fuzziness = f;
        let mut images = Vec::new();
        for patterns in [0, 1, 3, 8] {
            let colom = r.method_state_mut::<Colom>(Method::Colom).unwrap();
            colom.set_shade_patterns(patterns);
            let frame = r.render(&cam, &rs).unwrap();
            assert!(common::all_finite(&frame.radiance));
            images.push(frame.indirect);
        }
        assert!(
            images[0].iter().any(|c| c[0] > 0.0),
            "{weighting:?} F {f}: no indirect light"
        );
        for (i, p) in [1, 3, 8].iter().enumerate() {
            let differ = images[0]
                .iter()
                .zip(&images[i + 1])
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(
                differ, 0,
                "{weighting:?} F {f}: {p} patterns: {differ} pixels differ"
            );
        }
    }
}

/// The shade pass's tile cull (`TILE_CULL`, method::colom::shade::tile_cull) skips only lights that
/// add nothing: with it on and off the indirect light is bit-identical on the conference room and
/// the Cornell box (axis-aligned walls: a light in a tile's plane is culled) at a size whose edge
/// tiles are partly outside the image, in Eq. (9) and Eq. (8) mode; on the conference room turned
/// off the axes (no box is flat, a light in a tile's plane is kept) too, and the cull skips lights
/// there as well (the pass is faster with it: docs/results.md).
#[test]
fn the_tile_cull_does_not_change_the_image() {
    let ctx = common::gpu();
    let turned = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, -0.2);
    for (name, turn) in [
        ("builtin:conference", false),
        ("builtin:cornell", false),
        ("builtin:conference", true),
    ] {
        let mut s = scene::load(name).unwrap();
        if turn {
            s = rotated(s, turned);
        }
        let cam = s.default_camera();
        let mut r = Renderer::new(&ctx, &s).unwrap();
        for weighting in [Weighting::InverseDistance, Weighting::Uniform] {
            let mut rs = clustered(100, 75);
            rs.cluster.weighting = weighting;
            let mut images = Vec::new();
            for on in [false, true] {
                let colom = r.method_state_mut::<Colom>(Method::Colom).unwrap();
                colom.set_shade_tile_cull(on);
                let frame = r.render(&cam, &rs).unwrap();
                assert!(common::all_finite(&frame.radiance));
                images.push(frame.indirect);
            }
            let lit = images[0].iter().filter(|c| c[0] > 0.0).count();
            assert!(lit > 100 * 75 / 2, "{name} {weighting:?}: {lit} pixels lit");
            let differ = images[0]
                .iter()
                .zip(&images[1])
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(
                differ, 0,
                "{name} turned {turn} {weighting:?}: {differ} pixels differ"
            );
        }
    }
}
