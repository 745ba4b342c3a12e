#!/usr/bin/env python3
"""WGSL mutation testing (docs/testing.md, "Mutation testing").

Each mutant is one edit (file, exact original snippet, replacement) to a copy of shaders-wgsl/; the
GPU test binaries run against it through FVPL_SHADER_DIR (the WGSL is read at run time, no rebuild).
A mutant is *killed* when a test fails and, rerun alone on the same mutant, the same test fails
again; *killed by compile* when its shader no longer validates (the failure names a WGSL parse /
validation error), twice; *survived* when every test passes. Not counted as killed: *timeout* (a
binary past its limit), *crash* (a binary that ends without a failed test, by a signal or an exit
code other than libtest's 101) and *flaky* (a test that failed once and passed on the rerun); the
script tries the remaining binaries after each of them, and reports the mutant so only if none
kills it.

Usage (from the repository root, after `cargo test --release --no-run`):
    python3 scripts/wgsl-mutants.py            # every mutant, stage 1 then stage 2
    python3 scripts/wgsl-mutants.py -k clamp   # mutants whose name contains "clamp"
    python3 scripts/wgsl-mutants.py -k bvh- km-   # ... "bvh-" or "km-"
    python3 scripts/wgsl-mutants.py --files common/lights.wgsl direct.wgsl   # one or more files
    python3 scripts/wgsl-mutants.py --list
First both stages run on the unmutated shaders: a failing binary stops the script with one line that
names it and its failed tests. Stage 1 is the oracle binary (tests/oracles.rs, about a second); a
mutant it misses goes to stage 2, every other test binary that uses the GPU, whole (STAGE2, about two
minutes on lavapipe for a survivor), each under its own limit (5x its baseline time, at least 30 s,
at most --timeout), stopping at the first failure. `--full` runs stage 2 always.
A snippet found other than exactly once stops the script (the shaders changed: fix the table).
"""

import argparse
import glob
import os
import shutil
import subprocess
import sys
import tempfile
import time

# (name, file under shaders-wgsl, original, replacement, paper part)
MUTANTS = [
    # --- Eq. (5): common/vpl.wgsl, one VPL term
    ("eq5-gterm-clamp-dropped", "common/vpl.wgsl", "/ max(d2, d_min2)", "/ d2", "Eq. 5"),
    ("eq5-gterm-clamp-min", "common/vpl.wgsl", "/ max(d2, d_min2)", "/ min(d2, d_min2)", "Eq. 5"),
    ("eq5-gterm-distance-not-squared", "common/vpl.wgsl", "/ max(d2, d_min2)", "/ max(sqrt(d2), d_min2)", "Eq. 5"),
    ("eq5-albedo-not-over-pi", "common/vpl.wgsl", "(albedo / PI)", "albedo", "Eq. 5"),
    ("eq5-flux-not-over-pi", "common/vpl.wgsl", "(v.flux.xyz / PI)", "v.flux.xyz", "Eq. 5"),
    ("eq5-vpl-cosine-sign", "common/vpl.wgsl", "dot(v.nrm.xyz, -wi)", "abs(dot(v.nrm.xyz, -wi))", "Eq. 5"),
    # Not `if cos_v <= 0.0` alone: with cos_v > 0 a negative cos_p makes the term negative, which every
    # caller drops (`any(t > 0)`): an equivalent mutant. Without both tests two negative cosines give
    # a positive term.
    ("eq5-cosine-tests-dropped", "common/vpl.wgsl", "if cos_p <= 0.0 || cos_v <= 0.0 {", "if false {", "Eq. 5"),
    ("eq5-direction-not-normalised", "common/vpl.wgsl", "let wi = d * inverseSqrt(d2);", "let wi = d / d2;", "Eq. 5"),
    # A VPL-cluster light's spread (eq5_cluster_radiance, not in the paper: docs/clustering.md).
    ("eq5-cluster-spread-shares-swapped", "common/vpl.wgsl", "return (1.0 - v.flux.w) + v.flux.w * (", "return v.flux.w + (1.0 - v.flux.w) * (", "Eq. 5"),
    ("eq5-cluster-spread-radius-ignored", "common/vpl.wgsl", "max(d2, max(d_min2, v.nrm.w))", "max(d2, d_min2)", "Eq. 5"),
    ("eq5-visibility-inverted", "reference.wgsl", "&& vpl_visible(p, n, v.pos.xyz, v.nrm.xyz)", "&& !vpl_visible(p, n, v.pos.xyz, v.nrm.xyz)", "Eq. 5"),
    ("eq5-shadow-ray-overshoots", "common/bvh.wgsl", "dist * (1.0 - 1e-4)", "dist * 1.5", "Eq. 5"),
    # --- common/bvh.wgsl (traversal; CPU twin crates/core/src/bvh.rs, tests/traversal.rs)
    ("bvh-safe-inverse-tiny-not-huge", "common/bvh.wgsl", "return select(-1.0, 1.0, x >= 0.0) / eps;", "return select(-1.0, 1.0, x >= 0.0) * eps;", "BVH"),
    ("bvh-box-slab-sign", "common/bvh.wgsl", "let t1 = (bmin - origin) * inv_dir;", "let t1 = (origin - bmin) * inv_dir;", "BVH"),
    ("bvh-node-second-texel-off-by-one", "common/bvh.wgsl", "texel_xy(2u * i + 1u)", "texel_xy(2u * i + 2u)", "BVH"),
    ("bvh-shear-z-scale-unsigned", "common/bvh.wgsl", "1.0 / dz)", "1.0 / abs(dz))", "BVH"),
    ("bvh-shear-x-sign", "common/bvh.wgsl", "a[sh.k.x] - sh.s.x * z", "a[sh.k.x] + sh.s.x * z", "BVH"),
    ("bvh-edge-swap-sign-dropped", "common/bvh.wgsl", "return select(e, -e, swap);", "return e;", "BVH"),
    ("bvh-tri-barycentrics-not-over-det", "common/bvh.wgsl", "return vec3<f32>(t, v / det, w / det);", "return vec3<f32>(t, v, w / det);", "BVH"),
    ("bvh-walk-missed-leaf-skips-next", "common/bvh.wgsl", "            *i += 1u;\n        } else {", "            *i += 2u;\n        } else {", "BVH"),
    ("bvh-closest-tmax-not-lowered", "common/bvh.wgsl", "if r.x < ray.tmax {\n                    ray.tmax = r.x;\n", "if r.x < ray.tmax {\n", "BVH"),
    ("bvh-leaf-skips-last-triangle", "common/bvh.wgsl", "} else {\n            for (var k = node.index; k < node.index + count; k++) {", "} else {\n            for (var k = node.index; k + 1u < node.index + count; k++) {", "BVH"),
    # --- Eq. (6), (8), (9): shade.wgsl
    ("eq8-uniform-over-F-not-used-slots", "shade.wgsl", "1.0 / f32(nf)", "1.0 / f32(F)", "Eq. 8"),
    ("eq8-eq9-switch-inverted", "shade.wgsl", "if params.weighted == 0u {", "if params.weighted != 0u {", "Eq. 8/9"),
    ("eq8-used-slot-count-off", "shade.wgsl", "nf += select(0u, 1u, (*rows)[j] != INVALID);", "nf += select(0u, 2u, (*rows)[j] != INVALID);", "Eq. 8"),
    ("eq9-visibility-bit-inverted", "shade.wgsl", "(((*rw)[j] >> b) & 1u) != 0u", "(((*rw)[j] >> b) & 1u) == 0u", "Eq. 9"),
    ("eq9-slot-loop-skips-first", "shade.wgsl", "for (var j = 0u; j < F; j++) {\n        v +=", "for (var j = 1u; j < F; j++) {\n        v +=", "Eq. 9"),
    ("eq9-weight-ignored", "shade.wgsl", "v += select(0.0, (*w)[j],", "v += select(0.0, 1.0,", "Eq. 9"),
    ("eq6-visibility-ignored", "shade.wgsl", "sum += t * v;", "sum += t;", "Eq. 6"),
    ("eq6-light-index-off-by-one", "shade.wgsl", "load_light(wd * 32u + b)", "load_light(wd * 32u + b + 1u)", "Eq. 6"),
    ("shade-light-texel-row-2048", "shade.wgsl", "vec2<u32>(i & 4095u, i >> 12u)", "vec2<u32>(i & 2047u, i >> 11u)", "Eq. 6"),
    ("shade-light-texels-swapped", "shade.wgsl", "let a = light_texel(2u * c);\n    let b = light_texel(2u * c + 1u);", "let a = light_texel(2u * c + 1u);\n    let b = light_texel(2u * c);", "Eq. 6"),
    ("oct-encode-not-projected", "shade.wgsl", "n.xy / l1, l1 > 0.0", "n.xy, l1 > 0.0", "light code"),
    # oct_wrap is shared by encode and decode and is its own inverse: a mutant of it that stays an
    # involution (signs inverted, e.yx as e.xy) gives a different code but the same decoded
    # normal, an equivalent mutant. Dropping the fold on one side is not.
    ("oct-decode-fold-dropped", "shade.wgsl", "n = vec3<f32>(oct_wrap(e), n.z);", "n = vec3<f32>(e, n.z);", "light code"),
    ("oct-decode-not-normalised", "shade.wgsl", "return n * inverseSqrt(dot(n, n));", "return n;", "light code"),
    ("spread-code-r2-truncated", "shade.wgsl", "(bitcast<u32>(max(r2, 0.0)) + 0x800u)", "(bitcast<u32>(max(r2, 0.0)))", "light code"),
    ("spread-code-s-scale-4095", "shade.wgsl", "f32(code & 0x1fffu) * (1.0 / 4096.0)", "f32(code & 0x1fffu) * (1.0 / 4095.0)", "light code"),
    ("spread-code-r2-field-shifted", "shade.wgsl", "bitcast<f32>((code >> 1u) & 0x7ffff000u)", "bitcast<f32>((code >> 2u) & 0x7ffff000u)", "light code"),
    ("pack-lights-last-light-dropped", "shade.wgsl", "if c >= params.num_lights {\n        return;\n    }\n    let v = lights_in[c];", "if c + 1u >= params.num_lights {\n        return;\n    }\n    let v = lights_in[c];", "light code"),
    # --- Eq. (7), Alg. 1: kmeans.wgsl
    ("eq7-normal-test-swapped", "common/kmeans.wgsl", "return dot(n, nc) > params.normal_threshold;", "return dot(n, nc) < params.normal_threshold;", "Eq. 7"),
    ("eq7-normal-test-dropped", "common/kmeans.wgsl", "return dot(n, nc) > params.normal_threshold;", "return true;", "Eq. 7"),
    ("alg1-order-swapped", "common/nearest.wgsl", "return r < rd || (r == rd && k < rk);", "return r > rd || (r == rd && k < rk);", "Alg. 1/2"),
    ("alg1-tie-break-swapped", "common/nearest.wgsl", "return r < rd || (r == rd && k < rk);", "return r < rd || (r == rd && k > rk);", "Alg. 1/2"),
    ("alg2-insert-loop-off-by-one", "common/nearest.wgsl", "if j < slots && before(", "if j + 1u < slots && before(", "Alg. 2"),
    ("alg1-mean-count-off-by-one", "kmeans/iterate.wgsl", "/ f32(count);\n}", "/ f32(count + 1u);\n}", "Alg. 1"),
    ("alg1-mean-normal-not-normalised", "kmeans/iterate.wgsl", "c.nrm = vec4<f32>(nrm / l, 0.0);", "c.nrm = vec4<f32>(nrm, 0.0);", "Alg. 1"),
    ("alg1-member-removal-swapped", "kmeans/iterate.wgsl", "        if remove {\n            sub64", "        if !remove {\n            sub64", "Alg. 1"),
    ("alg1-change-flag-dropped", "kmeans/iterate.wgsl", "        set_flag(6u);\n        if old != INVALID {", "        if old != INVALID {", "Alg. 1"),
    # --- common/kmeans.wgsl: point access, Eq. (7); common/grid.wgsl: the grid's cells
    ("km-texel-row-2048", "common/grid.wgsl", "vec2<u32>(i & 4095u, i >> 12u)", "vec2<u32>(i & 2047u, i >> 11u)", "Alg. 1"),
    ("km-point-stride-ignored", "common/kmeans.wgsl", "return data[m * params.stride];", "return data[m];", "Alg. 1"),
    ("km-normal-reads-next-vec4", "common/kmeans.wgsl", "data[m * params.stride + 1u].xyz", "data[m * params.stride + 2u].xyz", "Alg. 1"),
    ("km-sample-stratum-size-dropped", "common/kmeans.wgsl", "min(s * g + (h >> 8u) % g,", "min(s + (h >> 8u) % g,", "Alg. 1"),
    ("eq7-distance-squared", "common/kmeans.wgsl", "return length(p - c);", "return dot(p - c, p - c);", "Eq. 7"),
    ("km-float-key-positive-not-offset", "common/grid.wgsl", "return select(b | 0x80000000u, ~b,", "return select(b, ~b,", "grid"),
    ("km-key-float-negative-not-inverted", "common/grid.wgsl", "select(~k, k & 0x7fffffffu,", "select(k, k & 0x7fffffffu,", "grid"),
    ("km-cell-coord-upper-clamp-dropped", "common/grid.wgsl", "return vec3<i32>(clamp(c, vec3<f32>(0.0), hi));", "return vec3<i32>(max(c, vec3<f32>(0.0)));", "grid"),
    ("km-cell-index-strides-swapped", "common/grid.wgsl", "(u32(c.z) * d.y + u32(c.y)) * d.x", "(u32(c.z) * d.x + u32(c.y)) * d.y", "grid"),
    # --- common/nearest.wgsl: the search
    ("nearest-last-slot-one-early", "common/nearest.wgsl", "        if j < f {\n            last", "        if j + 1u < f {\n            last", "Alg. 2"),
    ("nearest-second-run-not-rebased", "common/nearest.wgsl", "select(b.x + (t - len_a), a.x + t, t < len_a)", "select(b.x + t, a.x + t, t < len_a)", "Alg. 2"),
    ("nearest-ring1-left-cut-uses-right-face", "common/grid.wgsl", "gyz + g_lo.x * g_lo.x <= cut2", "gyz + g_hi.x * g_hi.x <= cut2", "Alg. 2"),
    ("nearest-ring-face-row-last-cell-dropped", "common/grid.wgsl", "cell_texel(row + u32(hi.x)).z", "cell_texel(row + u32(hi.x)).y", "Alg. 2"),
    ("nearest-final-rings-off-by-one", "common/nearest.wgsl", "ring <= min(FINAL_RINGS, maxr)", "ring < min(FINAL_RINGS, maxr)", "Alg. 2"),
    ("nearest-iter-rings-off-by-one", "common/nearest.wgsl", "ring <= ITER_RINGS", "ring < ITER_RINGS", "Alg. 1"),
    # --- kmeans/iterate.wgsl: the sums and the re-seeding
    ("alg1-sum-carry-dropped", "kmeans/iterate.wgsl", "atomicAdd(&sums[i + 1u], 1u);", "atomicAdd(&sums[i + 1u], 0u);", "Alg. 1"),
    ("alg1-sub-high-word-dropped", "kmeans/iterate.wgsl", "        atomicAdd(&sums[i + 1u], 0xffffffffu);\n", "", "Alg. 1"),
    ("reseed-mix-shift-off-by-one", "kmeans/iterate.wgsl", "((h >> 28u) + 4u)", "((h >> 28u) + 3u)", "reseed"),
    ("reseed-target-index-unmixed", "kmeans/iterate.wgsl", "reseed_mix(s * 747796405u)", "reseed_mix(s)", "reseed"),
    ("reseed-draw-modulo-k", "kmeans/iterate.wgsl", "% params.num_sampled;", "% params.k;", "reseed"),
    ("reseed-proposal-highest-index", "kmeans/iterate.wgsl", "let key = ~s;", "let key = s;", "reseed"),
    ("reseed-last-empty-own-parity", "kmeans/iterate.wgsl", "((atomicLoad(&bounds[7]) + 1u) & 1u)", "(atomicLoad(&bounds[7]) & 1u)", "reseed"),
    ("reseed-name-empty-other-parity", "kmeans/iterate.wgsl", "let i = 9u + (iteration & 1u);", "let i = 9u + ((iteration + 1u) & 1u);", "reseed"),
    # --- Eq. (10), Alg. 2: kmeans.wgsl
    ("eq10-zero-distance-dropped-in-final-assign", "kmeans/assign.wgsl", "if j < b.count && b.dist[j] <= ZERO_DIST && zero == INVALID {", "if false {", "Eq. 10"),
    ("eq10-zero-distance-dropped-in-rep-weights", "kmeans/reps.wgsl", "if d[j] <= ZERO_DIST && zero == INVALID {", "if false {", "Eq. 10"),
    ("eq10-zero-takes-none", "kmeans/assign.wgsl", "(*w)[j] = select(0.0, 1.0, j == zero);", "(*w)[j] = select(1.0, 0.0, j == zero);", "Eq. 10"),
    ("eq10-ratio-inverted", "kmeans/assign.wgsl", "ratio_pow(d_min / (*d)[j], params.weight_exponent)", "ratio_pow((*d)[j] / d_min, params.weight_exponent)", "Eq. 10"),
    ("eq10-not-normalised", "kmeans/assign.wgsl", "(*w)[j] /= wsum;", "(*w)[j] /= 1.0;", "Eq. 10"),
    ("eq10-p1-shortcut-wrong", "kmeans/assign.wgsl", "    if p == 1.0 {\n        return x;", "    if p == 1.0 {\n        return x * x;", "Eq. 10"),
    ("eq10-weights-slot-off-by-one", "kmeans/assign.wgsl", "assign[m * f + j] = k;\n        weights[m * f + j] = w[j];", "assign[m * f + j] = k;\n        weights[m * f + j] = w[0];", "Eq. 10"),
    ("plane-gate-sign-kept", "kmeans/assign.wgsl", "return abs(dot(n, d)) <= params.plane_gate * length(d);", "return dot(n, d) <= params.plane_gate * length(d);", "gate"),
    ("alg2-rep-min-swapped", "kmeans/assign.wgsl", "if bits < atomicLoad(&reps[2u * k]) {", "if bits > atomicLoad(&reps[2u * k]) {", "reps"),
    ("alg2-rep-lowest-index-swapped", "kmeans/reps.wgsl", "atomicMin(&reps[2u * k + 1u], m);", "atomicMax(&reps[2u * k + 1u], m);", "reps"),
    ("reps-distance-cleared-to-zero", "kmeans/reps.wgsl", "atomicStore(&reps[2u * k], 0xffffffffu);", "atomicStore(&reps[2u * k], 0u);", "reps"),
    ("reps-kept-test-inverted", "kmeans/reps.wgsl", "c.nrm.xyz) <= 2.0 * nearest", "c.nrm.xyz) > 2.0 * nearest", "reps"),
    # --- primary rays, visibility
    ("camera-pixel-centre-dropped", "primary.wgsl", "let x = f32(px % w) + 0.5 + bitcast<f32>(cam.size.z);", "let x = f32(px % w) + bitcast<f32>(cam.size.z);", "camera"),
    # The sub-pixel jitter of anti-aliasing at rest (render::jittered_primary_rays_match_cpu_twin).
    ("camera-jitter-y-dropped", "primary.wgsl", "+ 0.5 + bitcast<f32>(cam.size.w);", "+ 0.5;", "camera"),
    ("camera-jitter-axes-swapped", "primary.wgsl", "+ 0.5 + bitcast<f32>(cam.size.z);", "+ 0.5 + bitcast<f32>(cam.size.w);", "camera"),
    ("camera-y-flipped", "primary.wgsl", "let sy = 1.0 - 2.0 * y / f32(h);", "let sy = 2.0 * y / f32(h) - 1.0;", "camera"),
    ("primary-hit-point-behind-eye", "primary.wgsl", "ray.origin + hit.t * ray.dir", "ray.origin - hit.t * ray.dir", "camera"),
    ("visibility-light-facing-test-swapped", "visibility.wgsl", "dot(l.nrm.xyz, d) >= 0.0", "dot(l.nrm.xyz, d) <= 0.0", "step 5"),
    ("visibility-bit-off-by-one", "visibility.wgsl", "word |= 1u << b;", "word |= 1u << ((b + 1u) % 32u);", "step 5"),
    ("visibility-facing-away-test-dropped", "visibility.wgsl", "(behind || dot(l.nrm.xyz, d) >= 0.0)", "behind", "step 5"),
    ("visibility-plane-test-dropped", "visibility.wgsl", "(behind || dot(l.nrm.xyz, d) >= 0.0)", "(dot(l.nrm.xyz, d) >= 0.0)", "step 5"),
    ("visibility-plane-test-not-strict", "visibility.wgsl", "let behind = dot(n, d) <= 0.0;", "let behind = dot(n, d) < 0.0;", "step 5"),
    # The early answer under a representative's plane (surface_under, shadow_ray_blocked_by): V stays
    # a plain shadow ray's.
    ("visibility-under-plane-always-blocked", "visibility.wgsl", "behind && under != INVALID && shadow_ray_blocked_by(under, p, n, l.pos.xyz, l.nrm.xyz)", "behind && under != INVALID", "step 5"),
    ("visibility-walked-light-off-by-one", "visibility.wgsl", "light_texel(3u * (c0 + b)).xyz, light_texel(3u * (c0 + b) + 1u).xyz", "light_texel(3u * (c0 + b + 1u)).xyz, light_texel(3u * (c0 + b + 1u) + 1u).xyz", "step 5"),
    ("bvh-blocked-by-any-test", "common/bvh.wgsl", "return r.x < ray.tmax && alpha_passes(slot, r.y, r.z);", "return alpha_passes(slot, r.y, r.z);", "BVH"),
    ("bvh-blocked-by-alpha-ignored", "common/bvh.wgsl", "return r.x < ray.tmax && alpha_passes(slot, r.y, r.z);", "return r.x < ray.tmax;", "BVH"),
    ("visibility-traced-without-rep", "visibility.wgsl", "    if rep.w > 0.0 {\n        let p", "    if true {\n        let p", "step 5"),
    ("visibility-reuse-kept-flag-dropped", "visibility.wgsl", " && rep_points[2u * k + 1u].w == 1.0", "", "step 5"),
    ("visibility-reuse-rows-ignored", "visibility.wgsl", "k < params.reuse_rows &&", "params.reuse_rows > 0u &&", "step 5"),
    ("visibility-reuse-without-rep", "visibility.wgsl", "k < params.reuse_rows && rep.w > 0.0 &&", "k < params.reuse_rows &&", "step 5"),
    # The light texture's rows (4096 texels, 3 a light: rows past the first from light 1366 on).
    ("visibility-light-texel-row-2048", "visibility.wgsl", "vec2<u32>(i & 4095u, i >> 12u)", "vec2<u32>(i & 2047u, i >> 11u)", "step 5"),
    # --- direct light against closed forms (tests/closed_form.rs, stage 2)
    ("triangle-sampling-not-uniform", "common/sampling.wgsl", "let s = sqrt(u1);", "let s = u1;", "direct"),
    ("emitter-pdf-area-dropped", "common/lights.wgsl", "s.pdf_area = (e.power / scene.emit_power) / e.area;", "s.pdf_area = e.power / scene.emit_power;", "direct"),
    ("spot-falloff-linear", "common/lights.wgsl", "falloff = t * t;", "falloff = t;", "direct"),
    ("spot-cone-swapped", "common/lights.wgsl", "let t = clamp((cd - co) / max(ci - co, 1e-4), 0.0, 1.0);", "let t = clamp((cd - ci) / max(co - ci, 1e-4), 0.0, 1.0);", "direct"),
    ("punctual-not-inverse-square", "common/lights.wgsl", "s.e = l.color_cos_inner.xyz * falloff / d2;", "s.e = l.color_cos_inner.xyz * falloff / s.dist;", "direct"),
    ("direct-emitter-cosine-dropped", "direct.wgsl", "area_sum += ls.le * cos_p * cos_l / (d2 * ls.pdf_area);", "area_sum += ls.le * cos_p / (d2 * ls.pdf_area);", "direct"),
    ("direct-punctual-cosine-dropped", "direct.wgsl", "sum += ps.e * cos_p;", "sum += ps.e;", "direct"),
    ("direct-albedo-not-over-pi", "direct.wgsl", "return sp.albedo.xyz / PI * sum;", "return sp.albedo.xyz * sum;", "direct"),
    ("direct-shadow-ray-overshoots", "direct.wgsl", "dist * (1.0 - 1e-4) - scene.eps", "dist * 1.5", "direct"),
    # The later sub ranges of the samples add to the pixel (render::direct_light_in_sub_ranges...).
    ("direct-sub-range-overwrites", "direct.wgsl", "radiance[i] += vec4<f32>(c, 0.0);", "radiance[i] = vec4<f32>(c, 1.0);", "direct"),
    ("emitter-search-comparison-inverted", "common/lights.wgsl", "if emitters[mid].cdf <= u {", "if emitters[mid].cdf >= u {", "direct"),
    ("cosine-sampling-not-sqrt", "common/sampling.wgsl", "let r = sqrt(u1);", "let r = u1;", "sampling"),
    ("cosine-sampling-uniform", "common/sampling.wgsl", "let local = vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u1)));", "let local = vec3<f32>(sqrt(max(0.0, u1 * (2.0 - u1))) * cos(phi), sqrt(max(0.0, u1 * (2.0 - u1))) * sin(phi), 1.0 - u1);", "sampling"),
    ("cosine-sampling-half-azimuth", "common/sampling.wgsl", "let phi = 2.0 * PI * u2;", "let phi = PI * u2;", "sampling"),
    ("onb-sign-flipped", "common/sampling.wgsl", "let s = select(-1.0, 1.0, n.z >= 0.0);", "let s = select(1.0, -1.0, n.z >= 0.0);", "sampling"),
    ("vpl-roulette-not-divided", "vpl_trace.wgsl", "            flux /= q;", "            flux /= 1.0;", "VPLs"),
    ("vpl-emitter-flux-not-times-pi", "vpl_trace.wgsl", "flux = ls.le * PI / (p_src * ls.pdf_area);", "flux = ls.le / (p_src * ls.pdf_area);", "VPLs"),
    ("pt-roulette-not-divided", "pathtrace.wgsl", "                throughput /= q;", "                throughput /= 1.0;", "path tr."),
    ("pt-nee-albedo-not-over-pi", "pathtrace.wgsl", "return albedo / PI * sum;", "return albedo * sum;", "path tr."),
    ("pt-emission-at-every-vertex", "pathtrace.wgsl", "                if v == 0u {\n                    total += surf.emission;", "                if true {\n                    total += surf.emission;", "path tr."),
    ("pt-throughput-albedo-dropped", "pathtrace.wgsl", "throughput *= surf.albedo;", "throughput *= 1.0;", "path tr."),
    # Not `dist * tmax_scale` -> `dist` (tried 2026-11-26, every binary passes): the shadow ray ends
    # at the light point moved scene.eps off the emitter towards the receiver (cl > 0), so it stops
    # short of the emitter's plane without the 1 - 1e-4 as well.
    ("pt-shadow-direction-not-normalised", "pathtrace.wgsl", "Ray(o, d / dist, 0.0, dist * tmax_scale)", "Ray(o, d, 0.0, dist * tmax_scale)", "path tr."),
    ("vpl-spot-power-whole-sphere", "vpl_trace.wgsl", "flux = intensity * (t * t) * 2.0 * PI * (1.0 - co) / p_src;", "flux = intensity * (t * t) * 4.0 * PI / p_src;", "VPLs"),
    ("vpl-spot-falloff-linear", "vpl_trace.wgsl", "flux = intensity * (t * t) * 2.0 * PI * (1.0 - co) / p_src;", "flux = intensity * t * 2.0 * PI * (1.0 - co) / p_src;", "VPLs"),
    ("vpl-spot-cone-not-uniform", "vpl_trace.wgsl", "let cz = 1.0 - rng_next(&rng) * (1.0 - co);", "let cz = 1.0 - rng_next(&rng) * rng_next(&rng) * (1.0 - co);", "VPLs"),
    ("vpl-point-power-half-sphere", "vpl_trace.wgsl", "flux = intensity * 4.0 * PI / p_src;", "flux = intensity * 2.0 * PI / p_src;", "VPLs"),
    ("vpl-point-sphere-not-uniform", "vpl_trace.wgsl", "let z = 1.0 - 2.0 * u1;", "let z = 1.0 - 2.0 * u1 * u1;", "VPLs"),
    ("vpl-sun-disc-not-uniform", "vpl_trace.wgsl", "let r = params.radius * sqrt(rng_next(&rng));", "let r = params.radius * rng_next(&rng);", "VPLs"),
    ("vpl-sun-power-radius-not-squared", "vpl_trace.wgsl", "flux = intensity * PI * params.radius * params.radius / p_src;", "flux = intensity * PI * params.radius / p_src;", "VPLs"),
    # Not listed, equivalent in expectation: Russian roulette from the first bounce on in the VPL
    # tracer, or with another survival probability in the path tracer (each divides by its own q:
    # unbiased, only noisier).
    # Not listed, equivalent for the closed-form scenes: swapping sample_triangle's two barycentrics
    # (the uniform density on a triangle is symmetric in them), and the emitter stratum's jitter
    # halved (one square emitter of two equal triangles: every stratum still picks each half
    # alike).
    # Equivalent on lavapipe, so not listed (tried 2026-11-26, both pass every oracle): dropping
    # `if i == INVALID { return; }` (an invocation past the chunk reads its representative out of
    # bounds, as zeros: no representative, and its write past the matrix is dropped by wgpu's bounds
    # checks) and `min(c0 + 32u, params.num_lights)` → `c0 + 32u` (the light texture past the last
    # light is zero-initialised: a zero normal fails the facing test, no bit).
    # --- common/rng.wgsl (PCG hash; CPU twin crates/core/src/cpu/rng.rs)
    ("rng-pcg-shift-off-by-one", "common/rng.wgsl", "((state >> 28u) + 4u)", "((state >> 28u) + 3u)", "rng"),
    ("rng-seed-middle-hash-dropped", "common/rng.wgsl", "pcg_hash(b ^ pcg_hash(c))", "pcg_hash(b ^ c)", "rng"),
    ("rng-next-half-range", "common/rng.wgsl", "f32(*state >> 8u)", "f32(*state >> 9u)", "rng"),
    # --- common/scene.wgsl
    ("scene-texel-row-2048", "common/scene.wgsl", "vec2<u32>(i & 4095u, i >> 12u)", "vec2<u32>(i & 2047u, i >> 11u)", "scene"),
    ("scene-tri-v1-reads-v2", "common/scene.wgsl", "texel_xy(3u * slot + 1u)", "texel_xy(3u * slot + 2u)", "scene"),
    ("scene-shade-n2-reads-n1", "common/scene.wgsl", "texel_xy(4u * slot + 2u)", "texel_xy(4u * slot + 1u)", "scene"),
    ("scene-offset-scale-min-axis", "common/scene.wgsl", "max(a.x, max(a.y, a.z))", "min(a.x, min(a.y, a.z))", "scene"),
    ("scene-offset-dropped", "common/scene.wgsl", "return p + n * (scene.eps + 4e-6 * max_abs3(p));", "return p;", "scene"),
    # --- common/chunk.wgsl: every pass's work item
    ("chunk-offset-dropped", "common/chunk.wgsl", "return chunk.offset + i;", "return i;", "chunk"),
    # --- common/surface.wgsl
    ("surface-srgb-linear-segment-dropped", "common/surface.wgsl", "return c / 12.92;", "return pow((c + 0.055) / 1.055, 2.4);", "surface"),
    ("surface-srgb-gamma-2.2", "common/surface.wgsl", "pow((c + 0.055) / 1.055, 2.4);\n}", "pow((c + 0.055) / 1.055, 2.2);\n}", "surface"),
    ("surface-texel-row-column-swapped", "common/surface.wgsl", "u32(yi * w + xi)", "u32(xi * w + yi)", "surface"),
    ("surface-texel-negative-wrap-dropped", "common/surface.wgsl", "let xi = ((x % w) + w) % w;", "let xi = x % w;", "surface"),
    ("surface-bilinear-centre-dropped", "common/surface.wgsl", "vec2<f32>(f32(t.width), f32(t.height)) - 0.5;", "vec2<f32>(f32(t.width), f32(t.height));", "surface"),
    ("surface-bilinear-axes-swapped", "common/surface.wgsl", "mix(mix(a, b, w.x), mix(c, d, w.x), w.y)", "mix(mix(a, b, w.y), mix(c, d, w.y), w.x)", "surface"),
    ("surface-material-reads-n0", "common/surface.wgsl", "texel_xy(4u * slot + 3u), 0).w)", "texel_xy(4u * slot), 0).w)", "surface"),
    ("surface-uv-barycentrics-swapped", "common/surface.wgsl", "(1.0 - b1 - b2) * uv0 + b1 * uv1 + b2 * uv2", "(1.0 - b1 - b2) * uv0 + b2 * uv1 + b1 * uv2", "surface"),
    ("surface-uv1-u-v-swapped", "common/surface.wgsl", "let uv1 = vec2<f32>(s.n2.w, s.extra.x);", "let uv1 = vec2<f32>(s.extra.x, s.n2.w);", "surface"),
    ("surface-geometric-normal-flipped", "common/surface.wgsl", "cross(t.v1.xyz - t.v0.xyz, t.v2.xyz - t.v0.xyz)", "cross(t.v2.xyz - t.v0.xyz, t.v1.xyz - t.v0.xyz)", "surface"),
    ("surface-shading-normal-barycentrics-swapped", "common/surface.wgsl", "b1 * s.n1.xyz + b2 * s.n2.xyz", "b2 * s.n1.xyz + b1 * s.n2.xyz", "surface"),
    ("surface-shading-normal-not-normalised", "common/surface.wgsl", "    return n / l;", "    return n;", "surface"),
    ("surface-point-barycentrics-swapped", "common/surface.wgsl", "b1 * t.v1.xyz + b2 * t.v2.xyz", "b2 * t.v1.xyz + b1 * t.v2.xyz", "surface"),
    ("surface-emissive-texture-dropped", "common/surface.wgsl", "e *= sample_texture(m.tex.y, uv).xyz;", "", "surface"),
    ("surface-vertex-colour-barycentrics-swapped", "common/surface.wgsl", "b1 * tri_colors[3u * slot + 1u] + b2 * tri_colors[3u * slot + 2u]", "b2 * tri_colors[3u * slot + 1u] + b1 * tri_colors[3u * slot + 2u]", "surface"),
    ("surface-albedo-vertex-colour-dropped", "common/surface.wgsl", "        a *= color;\n", "", "surface"),
    ("surface-emission-from-back", "common/surface.wgsl", "let front = dot(n, dir) < 0.0;", "let front = dot(n, dir) > 0.0;", "surface"),
    ("surface-shading-normal-not-faced", "common/surface.wgsl", "if dot(n, ng) < 0.0 {", "if false {", "surface"),
    # --- common/alpha.wgsl (alpha test; CPU twin AlphaMask in crates/core/src/bvh.rs)
    ("alpha-texel-row-column-swapped", "common/alpha.wgsl", "u32(yi * w + xi)", "u32(xi * w + yi)", "alpha"),
    ("alpha-bilinear-centre-dropped", "common/alpha.wgsl", "vec2<f32>(f32(t.width), f32(t.height)) - 0.5;", "vec2<f32>(f32(t.width), f32(t.height));", "alpha"),
    ("alpha-bilinear-axes-swapped", "common/alpha.wgsl", "mix(mix(a, b, w.x), mix(c, d, w.x), w.y)", "mix(mix(a, b, w.y), mix(c, d, w.y), w.x)", "alpha"),
    ("alpha-vertex-alpha-dropped", "common/alpha.wgsl", "var a = m.base_color.w * tri_vertex_color(slot, b1, b2).w;", "var a = m.base_color.w;", "alpha"),
    ("alpha-texture-alpha-dropped", "common/alpha.wgsl", "a *= sample_alpha(m.tex.x, tri_uv(slot, b1, b2));", "", "alpha"),
    ("alpha-cutoff-inverted", "common/alpha.wgsl", "return a >= m.emissive.w;", "return a < m.emissive.w;", "alpha"),
    ("alpha-flag-inverted", "common/alpha.wgsl", "texel_xy(3u * slot), 0).w == 0.0", "texel_xy(3u * slot), 0).w != 0.0", "alpha"),
    # --- raycast.wgsl (batch queries of tests/traversal.rs)
    ("raycast-u-v-swapped", "raycast.wgsl", "bitcast<u32>(h.u), bitcast<u32>(h.v)", "bitcast<u32>(h.v), bitcast<u32>(h.u)", "raycast"),
    ("raycast-mode-swapped", "raycast.wgsl", "if params.mode == 0u {", "if params.mode != 0u {", "raycast"),
    # --- lightcluster.wgsl (CPU twin crates/core/src/method/lightcluster/twin.rs)
    ("lc-disc-radius-not-sqrt", "lightcluster.wgsl", "a.w * sqrt((f32(i) + 0.5) / f32(DISC_SAMPLES))", "a.w * ((f32(i) + 0.5) / f32(DISC_SAMPLES))", "lightcl."),
    ("lc-disc-golden-angle-wrong", "lightcluster.wgsl", "let th = 2.399963 * f32(i);", "let th = 2.0 * PI * f32(i) / f32(DISC_SAMPLES);", "lightcl."),
    ("lc-disc-fraction-off-by-one", "lightcluster.wgsl", "f32(seen) / f32(DISC_SAMPLES)", "f32(seen) / f32(DISC_SAMPLES - 1u)", "lightcl."),
    ("lc-visibility-ignored", "lightcluster.wgsl", "sum += t * bitcast<f32>(vis);", "sum += t;", "lightcl."),
    # The member groups (`--lightcluster-visibility members`, the default; not in the paper).
    ("lc-member-u-ignores-vpl", "lightcluster.wgsl", "pcg_hash(pcg_hash(i) ^ j)", "pcg_hash(pcg_hash(i))", "lightcl."),
    ("lc-member-draw-inverted", "lightcluster.wgsl", "return u * total < w;", "return u * total >= w;", "lightcl."),
    ("lc-member-flush-ignores-visibility", "lightcluster.wgsl", "if vpl_visible(p, n, v.pos.xyz, v.nrm.xyz) {", "if true {", "lightcl."),
    ("lc-member-group-weight-one-channel", "lightcluster.wgsl", "let w = t.x + t.y + t.z;", "let w = t.x;", "lightcl."),
    ("lc-visibility-cache-never-refreshed", "lightcluster.wgsl", "if c != cur {", "if cur == INVALID {", "lightcl."),
    # --- wang.wgsl (CPU twin crates/core/src/method/wang/twin.rs)
    ("wang-label-texel-row-2048", "wang.wgsl", "vec2<u32>(q & 4095u, q >> 12u)", "vec2<u32>(q & 2047u, q >> 11u)", "wang"),
    ("wang-point-texel-column-even", "wang.wgsl", "vec2<u32>(i & 4095u, i >> 12u)", "vec2<u32>(i & 4094u, i >> 12u)", "wang"),
    ("wang-neighbour-bound-off-by-one", "wang.wgsl", "qx >= i32(params.width)", "qx > i32(params.width)", "wang"),
    ("wang-radius-sums-distance-not-inverse", "wang.wgsl", "sum += 1.0 / max(h.t, 1e-30);", "sum += h.t;", "wang"),
    ("wang-radius-ratio-inverted", "wang.wgsl", "r = f32(params.rays) / s;", "r = s / f32(params.rays);", "wang"),
    ("wang-interp-distance-times-radius", "wang.wgsl", "length(sp.pos.xyz - pj.xyz) / radius_of(j)", "length(sp.pos.xyz - pj.xyz) * radius_of(j)", "wang"),
    ("wang-interp-not-normalised", "wang.wgsl", "        e = sum / wsum;", "        e = sum;", "wang"),
    # --- wang_cluster.wgsl = wang/*.wgsl (CPU twin method::wang::twin::cluster): the quadtree seeding, the grid search,
    # the fixed-point updates, the sample points
    ("wang-cluster-storage-slots-empty", "common/grid.wgsl", "    return ranges[i];\n}", "    return ranges[i].yyyy;\n}", "wang"),
    ("wang-cluster-eps-normal-term-dropped", "wang/seed.wgsl", "q = u32(min(eq2_error(p, n, mean.pos, mean.nrm) * EPS_SCALE, EPS_MAX));", "q = u32(min(params.alpha * length(p - mean.pos) * EPS_SCALE, EPS_MAX));", "wang"),
    ("wang-cluster-apportion-tie-highest", "wang/seed.wgsl", "if rem[i] >= 0.0 && (best == 4u || rem[i] > rem[best]) {", "if rem[i] >= 0.0 && (best == 4u || rem[i] >= rem[best]) {", "wang"),
    ("wang-cluster-split-offset-not-advanced", "wang/seed.wgsl", "        off += a[q];\n", "        off += 0u * a[q];\n", "wang"),
    ("wang-cluster-zrank-pixel-quad-ignored", "wang/seed.wgsl", "    let own = (y & 1u) * 2u + (x & 1u);\n    for (var q = 0u; q < own; q++) {", "    let own = 0u;\n    for (var q = 0u; q < own; q++) {", "wang"),
    ("wang-cluster-jitter-first-point", "wang/seed.wgsl", "        atomicStore(&tree[params.seeds_base + first], nth_point(l, x, y, r));", "        atomicStore(&tree[params.seeds_base + first], nth_point(l, x, y, 0u));", "wang"),
    ("wang-cluster-update-normal-unnormalised", "wang/centres.wgsl", "            centres[2u * j + 1u] = vec4<f32>(nrm / l, 0.0);", "            centres[2u * j + 1u] = vec4<f32>(nrm, 0.0);", "wang"),
    ("wang-cluster-ring1-skips-z-rows", "common/grid.wgsl", "    for (var item = 0u; item < 10u; item++) {", "    for (var item = 0u; item < 4u; item++) {", "wang"),
    ("wang-cluster-cut-times-alpha", "wang/assign.wgsl", "return (*best).e / params.alpha * (1.0 + 1e-5);", "return (*best).e * params.alpha * (1.0 + 1e-5);", "wang"),
    ("wang-cluster-candidate-tie-higher-index", "wang/assign.wgsl", "        if e < (*best).e || (e == (*best).e && k < (*best).k) {", "        if e < (*best).e || (e == (*best).e && k > (*best).k) {", "wang"),
    ("wang-cluster-scan-ranges-block-before-self", "common/grid.wgsl", "        before = partial[block - 1u];", "        before = partial[block];", "wang"),
    ("wang-cluster-remove-keeps-count", "wang/assign.wgsl", "        atomicSub(&sums[base + 12u], 1u);", "        atomicSub(&sums[base + 12u], 0u);", "wang"),
    ("wang-cluster-sample-pick-max", "wang/sample.wgsl", "        atomicMin(&sums[WORDS * l + 14u], m);", "        atomicMax(&sums[WORDS * l + 14u], m);", "wang"),
    ("wang-cluster-hint-ignored", "wang/assign.wgsl", "    if hint < params.k {\n        let h = centres[2u * hint];", "    if hint < 0u {\n        let h = centres[2u * hint];", "wang"),
    ("wang-cluster-grid-spacing-line-term-dropped", "wang/grid.wgsl", "grid_build(params.k, params.lo.xyz, params.ext, true);", "grid_build(params.k, params.lo.xyz, params.ext, false);", "wang"),
    ("grid-line-guard-for-colom", "kmeans/grid.wgsl", "grid_build(params.k, params.lo.xyz, params.ext, false);", "grid_build(params.k, params.lo.xyz, params.ext, true);", "grid"),
    ("wang-cluster-rest-skips-grid-test-x", "wang/assign.wgsl", "    if (m % params.width) % params.step == 0u && (m / params.width) % params.step == 0u {", "    if (m / params.width) % params.step == 0u {", "wang"),
    ("wang-cluster-first-hint-ignored", "wang/assign.wgsl", "    assign_pixel(m, labels[params.pixels + m]);", "    assign_pixel(m, INVALID);", "wang"),
    ("wang-cluster-seed-pixels-all-nodes-skip", "wang/seed.wgsl", "            if r < kn && (kn >= count || kn > 1u) {", "            if r < kn && (kn > count || kn > 1u) {", "wang"),
    ("wang-cluster-eq2-chord-not-doubled", "wang/common.wgsl", "return params.alpha * length(xi - xk) + sqrt(max(0.0, 2.0 - 2.0 * dot(ni, nk)));", "return params.alpha * length(xi - xk) + sqrt(max(0.0, 1.0 - dot(ni, nk)));", "wang"),
    ("wang-cluster-level-base-binary-tree", "wang/seed.wgsl", "return ((1u << (2u * l)) - 1u) / 3u;", "return (1u << l) - 1u;", "wang"),
    ("wang-cluster-node-row-stride-half", "wang/seed.wgsl", "level_base(l) + (y << l) + x", "level_base(l) + (y << (l - 1u)) + x", "wang"),
    ("wang-cluster-grid-pixel-x-without-step", "wang/common.wgsl", "y * params.step * params.width + x * params.step", "y * params.step * params.width + x", "wang"),
    ("wang-cluster-node-count-reads-normal", "wang/seed.wgsl", "return u32(nodes[2u * n].w);", "return u32(nodes[2u * n + 1u].w);", "wang"),
    ("wang-cluster-node-mean-not-divided", "wang/seed.wgsl", "return Mean(s.xyz / s.w, nrm);", "return Mean(s.xyz, nrm);", "wang"),
    ("wang-cluster-leaf-sum-overwritten", "wang/seed.wgsl", "s.ps += gbuffer[m].pos.xyz;", "s.ps = gbuffer[m].pos.xyz;", "wang"),
    ("wang-cluster-node-normal-slot-gets-position", "wang/seed.wgsl", "nodes[2u * n + 1u] = vec4<f32>(s.ns, 0.0);", "nodes[2u * n + 1u] = vec4<f32>(s.ps, 0.0);", "wang"),
    ("wang-cluster-up-counts-children", "wang/seed.wgsl", "s.c += sums.w;", "s.c += 1.0;", "wang"),
    ("wang-cluster-eps-carry-dropped", "wang/seed.wgsl", "atomicAdd(&tree[i + 1u], 1u);", "atomicAdd(&tree[i + 1u], 0u);", "wang"),
    ("wang-cluster-sum-carry-dropped", "wang/assign.wgsl", "atomicAdd(&sums[i + 1u], 1u);", "atomicAdd(&sums[i + 1u], 0u);", "wang"),
    ("wang-cluster-eps-weight-high-word-dropped", "wang/seed.wgsl", "return f32(atomicLoad(&tree[4u * n + 1u])) * 4294967296.0 + f32(atomicLoad(&tree[4u * n]));", "return f32(atomicLoad(&tree[4u * n]));", "wang"),
    ("wang-cluster-nth-point-off-by-one", "wang/seed.wgsl", "if r < c {", "if r <= c {", "wang"),
    ("wang-cluster-bounds-skip-z", "common/grid.wgsl", "    for (var a = 0u; a < 3u; a++) {\n        let key = float_key(pos[a]);", "    for (var a = 0u; a < 2u; a++) {\n        let key = float_key(pos[a]);", "wang"),
    ("wang-cluster-init-labels-last-pixel", "wang/centres.wgsl", "if m < params.pixels {\n        labels[m] = INVALID;", "if m + 1u < params.pixels {\n        labels[m] = INVALID;", "wang"),
    ("wang-cluster-last-seed-dropped", "wang/centres.wgsl", "if j < seed_count() {", "if j + 1u < seed_count() {", "wang"),
    ("wang-cluster-mean-high-word-dropped", "wang/centres.wgsl", "return (f32(hi) * 4294967296.0 + f32(lo)) / f32(count);", "return f32(lo) / f32(count);", "wang"),
    ("wang-cluster-cell-clamp-off-by-one", "common/grid.wgsl", "let hi = vec3<f32>(grid.dims) - 1.0;", "let hi = vec3<f32>(grid.dims);", "wang"),
    ("wang-cluster-ring-face-rows-need-both", "common/grid.wgsl", "if abs(y - c.y) == ring || abs(z - c.z) == ring {", "if abs(y - c.y) == ring && abs(z - c.z) == ring {", "wang"),
    ("wang-cluster-sub-high-word-dropped", "wang/assign.wgsl", "        atomicAdd(&sums[i + 1u], 0xffffffffu);\n", "", "wang"),
    ("wang-cluster-assign-grid-rows-of-gh", "wang/assign.wgsl", "grid_pixel(i % params.gw, i / params.gw);\n    assign_pixel(m, labels[m]);", "grid_pixel(i % params.gh, i / params.gh);\n    assign_pixel(m, labels[m]);", "wang"),
    ("wang-cluster-sample-error-starts-at-zero", "wang/sample.wgsl", "atomicStore(&sums[WORDS * j + 13u], 0xffffffffu);", "atomicStore(&sums[WORDS * j + 13u], 0u);", "wang"),
    ("wang-cluster-sample-min-swapped", "wang/sample.wgsl", "if bits < atomicLoad(&sums[WORDS * l + 13u]) {", "if bits > atomicLoad(&sums[WORDS * l + 13u]) {", "wang"),
    ("wang-cluster-sample-albedo-slot-off-by-one", "wang/sample.wgsl", "sample_gbuffer[4u * j + 2u] = albedo;", "sample_gbuffer[4u * j + 3u] = albedo;", "wang"),
    # --- cvrtgi.wgsl (CPU twin crates/core/src/method/cvrtgi/twin.rs)
    ("cv-face-axis-sign-swapped", "cvrtgi.wgsl", "select(-1.0, 1.0, dir % 2u == 0u)", "select(1.0, -1.0, dir % 2u == 0u)", "cvrtgi"),
    ("cv-dominant-face-sign-swapped", "cvrtgi.wgsl", "select(0u, 1u, n[axis] < 0.0)", "select(1u, 0u, n[axis] < 0.0)", "cvrtgi"),
    ("cv-voxel-coord-rounded", "cvrtgi.wgsl", "floor((p - params.origin.xyz) / params.origin.w)", "floor((p - params.origin.xyz) / params.origin.w + 0.5)", "cvrtgi"),
    ("cv-voxel-key-bound-off-by-one", "cvrtgi.wgsl", "any(c >= d)", "any(c > d)", "cvrtgi"),
    ("cv-key-x-y-swapped", "cvrtgi.wgsl", "vec3<u32>(k % d.x, k / d.x % d.y,", "vec3<u32>(k / d.x % d.y, k % d.x,", "cvrtgi"),
    ("cv-binary-search-direction-swapped", "cvrtgi.wgsl", "if k < key {", "if k > key {", "cvrtgi"),
    ("cv-surface-probe-one-side", "cvrtgi.wgsl", "v = find_voxel(voxel_coord(p - d * h));", "v = find_voxel(voxel_coord(p + d * h));", "cvrtgi"),
    ("cv-face-table-off-by-one", "cvrtgi.wgsl", "return faces[6u * params.dims.w + f];", "return faces[6u * params.dims.w + f + 1u];", "cvrtgi"),
    ("cv-radical-inverse-half-range", "cvrtgi.wgsl", "reverseBits(k) >> 8u", "reverseBits(k) >> 9u", "cvrtgi"),
    ("cv-face-ray-stratum-centre-dropped", "cvrtgi.wgsl", "let cos_t = (f32(k) + 0.5) / f32(rays);", "let cos_t = f32(k) / f32(rays);", "cvrtgi"),
    ("cv-face-ray-turn-dropped", "cvrtgi.wgsl", "let phi = 2.0 * PI * fract(radical_inverse(k) + turn);", "let phi = 2.0 * PI * radical_inverse(k);", "cvrtgi"),
    # The escape rays (`--escape-rays`, not in the paper) and the conserved gather (`--cluster-gather conserved`).
    ("cv-escape-ray-turn-dropped", "cvrtgi.wgsl", "f32(rays), fract(radical_inverse(k) + turn))", "f32(rays), radical_inverse(k))", "cvrtgi"),
    ("cv-escape-reach-inverted", "cvrtgi.wgsl", "} else if hit.t >= params.escape_reach {", "} else if hit.t < params.escape_reach {", "cvrtgi"),
    ("cv-escape-fractions-swapped", "cvrtgi.wgsl", "vec4<f32>(f32(kept) / r, f32(sent) / r, 0.0, 0.0)", "vec4<f32>(f32(sent) / r, f32(kept) / r, 0.0, 0.0)", "cvrtgi"),
    ("cv-slot-flux-projection-dropped", "cvrtgi.wgsl", "return s * s * abs(dot(nv, n)) * (e.x + e.y + e.z);", "return s * s * (e.x + e.y + e.z);", "cvrtgi"),
    ("cv-gather-conservation-scale-dropped", "cvrtgi.wgsl", "ec *= cv_lights[5u * c + 2u].w;", "ec *= 1.0;", "cvrtgi"),
    ("cv-face-origin-corner-not-centre", "cvrtgi.wgsl", "(vec3<f32>(c) + 0.5) * s", "vec3<f32>(c) * s", "cvrtgi"),
    ("cv-visibility-probe-outwards", "cvrtgi.wgsl", "voxel_at_surface(o + d * hit.t, d)", "voxel_at_surface(o + d * hit.t, -d)", "cvrtgi"),
    ("cv-light-normal-flux-swapped", "cvrtgi.wgsl", "Vpl(cv_lights[i], cv_lights[i + 1u], cv_lights[i + 2u])", "Vpl(cv_lights[i], cv_lights[i + 2u], cv_lights[i + 1u])", "cvrtgi"),
    ("cv-gather-near-far-swapped", "cvrtgi.wgsl", "vec3<f32>(0.0))) < params.near", "vec3<f32>(0.0))) > params.near", "cvrtgi"),
    ("cv-gather-lit-voxel-index", "cvrtgi.wgsl", "3u * (first + j)", "3u * first + j", "cvrtgi"),
    ("cv-irradiance-albedo-not-pi", "cvrtgi.wgsl", "eq5_vpl_radiance(x, n, vec3<f32>(PI), light, params.d_min2)", "eq5_vpl_radiance(x, n, vec3<f32>(1.0), light, params.d_min2)", "cvrtgi"),
    ("cv-filter-sigma-wrong", "cvrtgi.wgsl", "exp(-f32(dot(d, d)) * params.inv_two_sigma2)", "exp(-f32(dot(d, d)) * 0.5 * params.inv_two_sigma2)", "cvrtgi"),
    ("cv-filter-not-normalised", "cvrtgi.wgsl", "out[f] = vec4<f32>(sum / wsum, 0.0);", "out[f] = vec4<f32>(sum, 0.0);", "cvrtgi"),
    ("cv-nearest-face-takes-back-faces", "cvrtgi.wgsl", "if f != INVALID && c > best {", "if f != INVALID && c < best {", "cvrtgi"),
    ("cv-lookup-centre-offset-dropped", "cvrtgi.wgsl", "/ params.origin.w - 0.5;", "/ params.origin.w;", "cvrtgi"),
    ("cv-lookup-trilinear-weights-swapped", "cvrtgi.wgsl", "select(vec3<f32>(1.0) - t, t, o == vec3<u32>(1u))", "select(t, vec3<f32>(1.0) - t, o == vec3<u32>(1u))", "cvrtgi"),
    ("cv-lookup-albedo-not-over-pi", "cvrtgi.wgsl", "sp.albedo.xyz / PI * e", "sp.albedo.xyz * e", "cvrtgi"),
    # --- common/grid.wgsl and kmeans/grid.wgsl (Alg. 1 line 5: the grid the nearest-centroid search reads)
    ("grid-bounds-min-never-lowered", "common/grid.wgsl", "if key < atomicLoad(&bounds[a]) {", "if key > atomicLoad(&bounds[a]) {", "grid"),
    ("grid-change-flag-not-reset", "kmeans/grid.wgsl", "    atomicStore(&bounds[6], 0u);\n", "", "grid"),
    ("grid-iteration-off-by-one", "kmeans/grid.wgsl", "let iteration = atomicAdd(&bounds[7], 1u) + 1u;", "let iteration = atomicAdd(&bounds[7], 1u);", "grid"),
    ("grid-dims-floor-not-ceil", "common/grid.wgsl", "vec3<u32>(ceil(e / cell))", "vec3<u32>(floor(e / cell))", "grid"),
    ("grid-count-doubled", "common/grid.wgsl", "cell_coord(grid_centre_pos(k).xyz))], 1u);", "cell_coord(grid_centre_pos(k).xyz))], 2u);", "grid"),
    ("grid-scan-step-off-by-one", "common/scan.wgsl", "if t >= d {", "if t > d {", "grid"),
    ("scan-partial-reads-own-slot", "common/scan.wgsl", "v = partial[t - d];", "v = partial[t - d + 1u];", "grid"),
    ("grid-scan-inclusive-not-exclusive", "common/grid.wgsl", "var run = partial[t] - s;", "var run = partial[t];", "grid"),
    ("grid-offset-end-off-by-one", "common/grid.wgsl", "if u >= n {", "if u > n {", "grid"),
    ("grid-block-count-floor", "common/grid.wgsl", "let blocks = (n + SCAN_BLOCK - 1u) / SCAN_BLOCK;", "let blocks = n / SCAN_BLOCK;", "grid"),
    ("grid-scatter-slot-off-by-one", "common/grid.wgsl", "atomicSub(&cells[cell], 1u) - 1u;", "atomicSub(&cells[cell], 1u);", "grid"),
    # --- kmeans/init.wgsl (Alg. 1 line 2, temporal warm start)
    ("init-stratum-takes-last-valid", "kmeans/init.wgsl", "            break;\n", "", "init"),
    ("init-empty-test-inverted", "kmeans/init.wgsl", "if c.pos.w == 0.0 {", "if c.pos.w != 0.0 {", "init"),
    ("init-warm-keeps-all-without-image-dropped", "kmeans/init.wgsl", "let seen = params.warm_size.x == 0u || (r.w > 0.0", "let seen = (r.w > 0.0", "init"),
    ("init-warm-y-flipped", "kmeans/init.wgsl", "let y = (1.0 - sy) * 0.5 * f32(h);", "let y = (sy + 1.0) * 0.5 * f32(h);", "init"),
    ("init-warm-plane-test-inverted", "kmeans/init.wgsl", "abs(dot(n, q - p.xyz)) <= tol", "abs(dot(n, q - p.xyz)) > tol", "init"),
    ("init-stratum-ceil", "kmeans/init.wgsl", "floor(f32(a) * (f32(b) / f32(c)))", "ceil(f32(a) * (f32(b) / f32(c)))", "init"),
    # --- shade.wgsl: the pattern table (PATTERNS > 0; killed by clustered.rs
    # the_pattern_table_does_not_change_the_image, PATTERNS 0/1/3/8 bit for bit)
    ("pattern-same-visibility-inverted", "shade.wgsl", "same &= select(~r, r, ((r >> b) & 1u) != 0u);", "same &= select(r, ~r, ((r >> b) & 1u) != 0u);", "patterns"),
    ("pattern-same-visibility-seen-side-only", "shade.wgsl", "same &= select(~r, r, ((r >> b) & 1u) != 0u);", "same &= r;", "patterns"),
    ("pattern-table-v-of-next-light", "shade.wgsl", "vs[k] = eq9_weighted_visibility(w, &rw, first);", "vs[k] = eq9_weighted_visibility(w, &rw, (first + 1u) % 32u);", "patterns"),
    ("pattern-pick-inverted", "shade.wgsl", "v = select(v, vs[k], ((masks[k] >> b) & 1u) != 0u);", "v = select(v, vs[k], ((masks[k] >> b) & 1u) == 0u);", "patterns"),
    ("pattern-past-the-table-dropped", "shade.wgsl", "if ((rest >> b) & 1u) != 0u {", "if false {", "patterns"),
    # --- shade.wgsl: the tile cull (TILE_CULL; killed by clustered.rs
    # the_tile_cull_does_not_change_the_image and oracles.rs gpu_tile_cull_drops_only_lights_in_the_tiles_plane)
    ("tile-cull-point-bound-dropped", "shade.wgsl", "return dot(at_light, vec3<f32>(1.0)) > slack && dot(at_point, vec3<f32>(1.0)) > slack;", "return dot(at_light, vec3<f32>(1.0)) > slack;", "tile cull"),
    ("tile-cull-light-bound-min", "shade.wgsl", "let at_light = max(n * (lo - x), n * (hi - x));", "let at_light = min(n * (lo - x), n * (hi - x));", "tile cull"),
    ("tile-mask-of-next-word", "shade.wgsl", "let c0 = (chunk.sub_offset + i % words) * 32u;", "let c0 = (chunk.sub_offset + (i + 1u) % words) * 32u;", "tile cull"),
    ("tile-box-skips-last-pixel", "shade.wgsl", "for (var i = 0u; i < TILE * TILE; i++) {\n        let m = tile_pixel", "for (var i = 0u; i + 1u < TILE * TILE; i++) {\n        let m = tile_pixel", "tile cull"),
    # --- temporal accumulation: accumulate.wgsl
    ("accumulate-bilinear-weights-swapped", "accumulate.wgsl", "let bx = select(1.0 - tx, tx, dx == 1);", "let bx = select(tx, 1.0 - tx, dx == 1);", "temporal"),
    ("accumulate-depth-test-loose", "accumulate.wgsl", "abs(pq.z - z) <= params.blend.y * z", "abs(pq.z - z) <= 10.0 * z", "temporal"),
    ("accumulate-normal-test-dropped", "accumulate.wgsl", "if q.pos.w <= 0.0 || dot(n, q.nrm.xyz) < params.blend.z {", "if q.pos.w <= 0.0 {", "temporal"),
    ("accumulate-count-uncapped", "accumulate.wgsl", "min(history.w + 1.0, 1.0 / params.blend.x)", "history.w + 1.0", "temporal"),
    ("accumulate-mean-schedule-dropped", "accumulate.wgsl", "return max(1.0 / (frames + 1.0), alpha);", "return alpha;", "temporal"),
    ("accumulate-mix-reversed", "accumulate.wgsl", "mix(history.xyz, cur, alpha)", "mix(cur, history.xyz, alpha)", "temporal"),
    ("accumulate-same-view-ignored", "accumulate.wgsl", "if params.size.w == 1u {", "if false {", "temporal"),
    ("accumulate-reprojection-y-flipped", "accumulate.wgsl", "(1.0 - sy) * 0.5 * f32(params.size.y)", "(sy + 1.0) * 0.5 * f32(params.size.y)", "temporal"),
    # --- indirect scale: upsample.wgsl
    ("upsample-normal-power-dropped", "upsample.wgsl", "pow(facing, NORMAL_POWER)", "facing", "indirect scale"),
    ("upsample-plane-distance-ignored", "upsample.wgsl", "return exp(-plane * plane) * pow", "return pow", "indirect scale"),
    ("upsample-bilinear-swapped", "upsample.wgsl", "let bx = select(1.0 - fx, fx, dx == 1);", "let bx = select(fx, 1.0 - fx, dx == 1);", "indirect scale"),
    ("upsample-fallback-farthest", "upsample.wgsl", "sq.pos.w != 0.0 && gap < best_gap", "sq.pos.w != 0.0 && gap > best_gap", "indirect scale"),
    ("upsample-representative-corner", "upsample.wgsl", "(f32(lx) + 0.5) * f32(params.size.x)", "f32(lx) * f32(params.size.x)", "indirect scale"),
    # Not listed, equivalent by argument (not run): in the pattern table, `var same = 0xffffffffu` ->
    # `0u` (every mask empty: every light runs Eq. (9)'s loop, the same V bit for bit),
    # `firstTrailingBit(rest)` -> `firstLeadingBit(rest)` (a pattern's mask and V do not depend on
    # which of its lights finds it) and dropping `rest &= ~masks[k]` (the table repeats the first
    # pattern; every other light runs the loop). In kmeans/grid.wgsl the cell size (`1.5 * spacing`,
    # the area behind it): the search is exact at any cell size, only its speed changes.
    # Not listed, equivalent by argument (not run): in wang_cluster.wgsl `level_base`'s `- 1u` dropped
    # (4^l is 1 modulo 3, so 4^l / 3 and (4^l - 1) / 3 are the same integer) and `node_index`'s x and
    # y swapped (a bijection within the level that every reader and writer shares); in
    # common/bvh.wgsl `ray_shear`'s swap of kx and ky for a ray towards -z dropped (it negates the
    # three edge functions and det together, exactly where no multiply-add is fused: the test is
    # two-sided, t and the barycentrics are the same); in common/nearest.wgsl the fallback's `ring <= maxr` as `ring < maxr` (no cell is maxr
    # rings from another: the grid is at most maxr cells an axis).
    # Not mutated, every function with arithmetic having a mutant above: common/gbuffer.wgsl and
    # kmeans.wgsl are glue (a struct, the #imports); warmup.wgsl is a busy loop whose result nobody
    # reads; `empty_nearest` (common/nearest.wgsl) only fills the list with (BIG, INVALID), and
    # `downsample` (upsample.wgsl) only copies the G-buffer at `representative(i)` (which has its
    # mutant); the loads (`sorted_at`, `cell_slots`, `cell_texel`, `seed_count`) and the
    # flag setters (`set_flag`, `seed_next`) hold no arithmetic of their own.
]

# Stage 2: every test binary that uses the GPU (tests/*.rs but NO_GPU), whole, in this order (fast or
# most likely to kill first; a binary not named here runs after these), stopping at the first that
# fails. A mutant's file may name binaries to try first (HINTS): only the order changes.
STAGE2 = ["closed_form", "accumulate", "upsample", "traversal", "cvrtgi", "gltf_features", "methods", "budget", "viewer",
          "temporal", "reference", "clustered", "kmeans", "cli", "render", "bench"]
NO_GPU = {"scene_load"}
HINTS = {
    "raycast.wgsl": ["traversal"],
    "cvrtgi.wgsl": ["cvrtgi"],
    "wang.wgsl": ["methods"],
    "wang_cluster.wgsl": ["methods"],
    "lightcluster.wgsl": ["methods"],
    "common/alpha.wgsl": ["gltf_features"],
    "common/surface.wgsl": ["gltf_features"],
    "kmeans/grid.wgsl": ["kmeans"],
    "kmeans/iterate.wgsl": ["kmeans"],
    "kmeans/assign.wgsl": ["kmeans"],
    "kmeans/reps.wgsl": ["kmeans"],
    "common/kmeans.wgsl": ["kmeans"],
    "common/nearest.wgsl": ["kmeans"],
    "common/bvh.wgsl": ["traversal"],
    "common/scan.wgsl": ["kmeans"],
    "kmeans/init.wgsl": ["kmeans", "temporal"],
    "shade.wgsl": ["clustered", "oracles"],
    "accumulate.wgsl": ["accumulate"],
    "upsample.wgsl": ["upsample"],
}

COMPILE_MARKERS = ("Shader validation error", "shader parse", "naga", "WGSL", "Validation Error")


def binaries():
    """Every test binary, built (once) by cargo: its own list of executables, name → path."""
    cmd = ["cargo", "test", "--release", "--no-run", "--tests"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(r.stderr[-3000:])
    out = {}
    for line in r.stderr.splitlines():
        line = line.strip()
        if line.startswith("Executable tests/"):
            n = line.split("tests/", 1)[1].split(".rs", 1)[0]
            out[n] = line.split("(", 1)[1].rstrip(")")
    return out


def failed_names(out):
    """The failed tests of a libtest output (`test NAME ... FAILED`)."""
    return [l.split()[1] for l in out.splitlines() if l.startswith("test ") and l.rstrip().endswith("FAILED")]


def failing_tests(out):
    return ", ".join(failed_names(out)) or "(no test named; see its output)"


def run(cmd, env, timeout):
    try:
        r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
        return r.returncode, r.stdout + r.stderr
    except subprocess.TimeoutExpired:
        return "timeout", ""


def attempt(cmd, env, timeout):
    """One run of a test binary: ("pass" | "failed" | "compile" | "timeout" | "crash", failed tests).
    A failure is a test's only when libtest names failed tests and exits 101."""
    rc, out = run(cmd, env, timeout)
    if rc == 0:
        return "pass", []
    if rc == "timeout":
        return "timeout", []
    failed = failed_names(out)
    if rc != 101 or not failed:
        return "crash", []
    tail = out.split("panicked", 1)[1][:400] if "panicked" in out else ""
    if any(m in out for m in COMPILE_MARKERS) and "panicked" in out and "assert" not in tail:
        return "compile", failed
    return "failed", failed


def judge(binary, path, env, timeout):
    """A binary on a mutant, a failure checked by a rerun of the failed tests alone: (verdict, tests).
    The verdict is "killed" or "compile" only when a test that failed fails again the same way."""
    kind, failed = attempt([path], env, timeout)
    if kind not in ("failed", "compile"):
        return (None if kind == "pass" else kind), []
    kind2, failed2 = attempt([path, *failed, "--exact"], env, timeout)
    same = [t for t in failed if t in failed2]
    if kind2 == kind and same:
        return ("killed" if kind == "failed" else "compile"), same
    return "flaky", failed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("-k", nargs="+", default=[""], metavar="NAME",
                    help="only mutants whose name contains one of these")
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--full", action="store_true", help="run stage 2 even when stage 1 kills")
    ap.add_argument("--timeout", type=int, default=300, help="seconds per test binary")
    ap.add_argument("--files", nargs="+", default=None, metavar="FILE",
                    help="only the mutants of these shader files (paths under shaders-wgsl)")
    a = ap.parse_args()
    todo = [m for m in MUTANTS if any(k in m[0] for k in a.k) and (a.files is None or m[1] in a.files)]
    if a.list:
        for m in todo:
            print(f"{m[0]:48} {m[4]:9} {m[1]}")
        return
    # Every snippet must be found exactly once before anything runs.
    for name, f, old, new, _ in MUTANTS:
        n = open(os.path.join("shaders-wgsl", f)).read().count(old)
        if n != 1:
            sys.exit(f"{name}: snippet found {n} times in shaders-wgsl/{f}: {old!r}")
    env = dict(os.environ)
    env.setdefault("XDG_RUNTIME_DIR", "/tmp/xdg")
    os.makedirs(env["XDG_RUNTIME_DIR"], exist_ok=True)
    bins = binaries()
    names = ["oracles"] + [b for b in STAGE2 if b in bins]
    names += sorted(b for b in bins if b not in names and b not in NO_GPU)
    # The unmutated shaders must pass both stages, or every verdict is noise. Each binary's time on
    # them sets its limit for the mutants: 5x that (at least 30 s), at most --timeout.
    base = tempfile.mkdtemp(prefix="wgsl-base-")
    shutil.copytree("shaders-wgsl", os.path.join(base, "s"))
    env["FVPL_SHADER_DIR"] = os.path.join(base, "s")
    limit = {}
    t_base = time.time()
    for b in names:
        t0 = time.time()
        rc, out = run([bins[b]], env, a.timeout)
        if rc != 0:
            what = f"timed out after {a.timeout} s" if rc == "timeout" else "fails: " + failing_tests(out)
            shutil.rmtree(base)
            sys.exit(f"baseline: tests/{b}.rs {what} on the unmutated shaders; no mutant run")
        limit[b] = min(a.timeout, max(30, 5 * (time.time() - t0)))
    shutil.rmtree(base)
    print(f"baseline: {len(names)} GPU test binaries pass on the unmutated shaders"
          f" ({time.time() - t_base:.0f} s)", flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--", "shaders-wgsl", "tests", "src"],
                           capture_output=True, text=True).stdout.strip()
    print(f"tree: commit {commit}{' with uncommitted changes' if dirty else ''}, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}", flush=True)
    rows = []
    for name, f, old, new, part in todo:
        d = tempfile.mkdtemp(prefix="wgsl-mutant-")
        s = os.path.join(d, "s")
        shutil.copytree("shaders-wgsl", s)
        path = os.path.join(s, f)
        src = open(path).read()
        open(path, "w").write(src.replace(old, new, 1))
        env["FVPL_SHADER_DIR"] = s
        t0 = time.time()
        first = [b for b in HINTS.get(f, []) if b in names[1:]]
        order = ["oracles"] + first + [b for b in names[1:] if b not in first]
        v, by, notes = None, "", []
        for b in order:
            v2, tests = judge(b, bins[b], env, limit[b])
            if v2 in ("killed", "compile"):
                if v is None:
                    v, by = v2, f"{b}::{tests[0]}"
                if not a.full:
                    break
            elif v2:
                notes.append(f"{v2} in {b}" + (f" ({', '.join(tests)})" if tests else ""))
        if v is None:
            # Not killed: the reason it is not a survivor either, if any binary timed out, crashed
            # or failed only once.
            v = next((k for k in ("timeout", "crash", "flaky") if any(n.startswith(k) for n in notes)),
                     "SURVIVED")
        rows.append((name, part, v, by, time.time() - t0, f))
        note = f"  [{'; '.join(notes)}]" if notes else ""
        print(f"{name:48} {part:9} {v:9} {by:40} {time.time() - t0:6.1f}s{note}", flush=True)
        shutil.rmtree(d)
    n = len(rows)
    count = {k: sum(r[2] == k for r in rows) for k in ("killed", "compile", "timeout", "crash", "flaky", "SURVIVED")}
    print(f"\n{n} mutants: {count['killed']} killed by a test (the same test failed twice), "
          f"{count['compile']} killed by compile, {count['timeout']} timed out, {count['crash']} crashed, "
          f"{count['flaky']} failed only once, {count['SURVIVED']} survived "
          f"({100.0 * (count['killed'] + count['compile']) / max(n, 1):.0f}% killed)")
    for r in rows:
        if r[2] not in ("killed", "compile"):
            print(f"  {r[2]}: {r[0]}")
    per = {}
    for r in rows:
        k, n_ = per.get(r[5], (0, 0))
        per[r[5]] = (k + (r[2] in ("killed", "compile")), n_ + 1)
    print("per file: " + ", ".join(f"{f} {k}/{n_}" for f, (k, n_) in sorted(per.items())))


if __name__ == "__main__":
    main()
