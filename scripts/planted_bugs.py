#!/usr/bin/env python3
"""Plants plausible bugs in a scratch copy of volcast, one at a time, and reports which tests catch each.

A test suite proves something only if it fails when the code is wrong. Each bug below is a small, realistic
source change (a wrong sign, a dropped factor, an edge off by one); for each, this script applies it to a scratch
copy of the committed tree, runs `cargo test` there, and records the failing tests. A bug
that no test catches is a *survivor*: a hole in the proof. A run writes its table to target/planted-bugs.md;
docs/testing.md, "Planted bugs", states the rules.

Runs by hand, not in CI. Each bug rebuilds the crate incrementally (profile `planted`, which the script adds to the
scratch copy: release code, incremental) and runs the test binaries one by one, cheapest first (ORDER), until the
first that fails, the viewer's X tests only for bugs in the viewer. The whole table takes hours on 2 cores, so a run records each verdict as it goes
and can be resumed, on the same commit, in a later session:

    python3 scripts/planted_bugs.py               # every bug on HEAD; writes target/planted-bugs.md
    python3 scripts/planted_bugs.py --record R.tsv --commit 602609e   # resumable: skips the bugs R.tsv has
    python3 scripts/planted_bugs.py --record R.tsv --hints OLD.tsv   # runs first what caught each bug in OLD.tsv
    python3 scripts/planted_bugs.py --list        # the bugs, without running
    python3 scripts/planted_bugs.py --check       # that every bug still applies to the working tree (seconds, no build)
    python3 scripts/planted_bugs.py --only srgb-twice --only no-opacity-correction

Exits 1 if any bug survives or no longer applies (its source line changed: update the bug).
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

# name, what it breaks, [(file, exact text, replacement)]: each text must occur exactly once in its file.
BUGS = [
    ("colour-by-value", "the colormap is indexed by the value instead of its position in the window",
     [("src/transfer/function.rs", "let c = (v - lo) / span;", "let c = v;")]),
    ("no-opacity-correction", "opacity is not corrected for the segment length",
     [("src/transfer/preintegrate.rs", "1.0 - (-sigma * steps).exp()", "1.0 - (-sigma).exp()"),
      ("shaders/march.glsl", ": 1.0 - exp(-sigma * seg_steps);", ": 1.0 - exp(-sigma);")]),
    ("half-texel-offset", "texel centres at i/n instead of (i + 0.5)/n in the corner-texture sampler",
     [("shaders/volume.glsl", "vec3 q = p * b.scale + b.offset - 0.5;", "vec3 q = p * b.scale + b.offset;")]),
    ("gradient-scaling-dropped", "shading normals ignore the voxel's world size (wrong on non-cubic voxels)",
     [("shaders/shade.glsl", "vec3 gw = mat3(frame.gradient_to_world) * g;", "vec3 gw = g;")]),
    ("window-upper-edge", "the value window's upper edge is ignored on the GPU",
     [("src/render/uniforms.rs", "s.colour.window[0], s.colour.window[1]],", "s.colour.window[0], 1.0],")]),
    ("brick-apron-dropped", "bricks' value ranges miss the voxels beside them, so a brick that is not empty is skipped",
     [("src/render/skip.rs", "crate::volume::cells::extremes(&volume.data, dims, BRICK, 1)",
       "crate::volume::cells::extremes(&volume.data, dims, BRICK, 0)")]),
    ("wrong-face-culled", "the entry pass culls front faces and the exit pass back faces",
     [("src/render/init.rs", "[vk::CullModeFlags::BACK, vk::CullModeFlags::FRONT]",
       "[vk::CullModeFlags::FRONT, vk::CullModeFlags::BACK]")]),
    ("near-plane-ignored", "the analytic setup starts rays behind the near plane",
     [("shaders/analytic.glsl", "max(max(max(t_min.x, t_min.y), t_min.z), frame.ray_forward.w)",
       "max(max(max(t_min.x, t_min.y), t_min.z), 0.0)")]),
    ("srgb-twice", "the output is sRGB-encoded twice",
     [("shaders/march.glsl", "return vec4(linear_to_srgb(rgb), 1.0);",
       "return vec4(linear_to_srgb(linear_to_srgb(rgb)), 1.0);")]),
    ("jitter-hash", "the shader's jitter hash uses another constant than the rule",
     [("shaders/march.glsl", "seed * 26699u", "seed * 26701u")]),
    ("early-termination-ignored", "rays never stop early",
     [("shaders/march.glsl", "        if (opacity >= frame.alpha.z) {\n            done = true;",
       "        if (opacity >= 1.0) {\n            done = true;")]),
    ("density-step-ignored", "the density model forgets the segment length",
     [("src/transfer/preintegrate.rs", "(sigma * steps).min(1.0)", "sigma.min(1.0)"),
      ("shaders/march.glsl", "min(1.0, sigma * seg_steps)", "min(1.0, sigma)")]),
    ("no-bisection", "the isosurface is not refined between samples",
     [("shaders/march.glsl", "for (int b = 0; b < 8; b++) {", "for (int b = 0; b < 0; b++) {")]),
    ("int16-bias-sign", "signed 16-bit data are un-biased with the wrong sign",
     [("src/volume/mod.rs", "((intercept - slope * offset - min) / span) as f32,",
       "((intercept + slope * offset - min) / span) as f32,")]),
    ("ortho-aspect", "orthographic rays ignore the image's aspect ratio",
     [("src/render/uniforms.rs", "origin_dx: v4(to_tex * (right * (spread * tan * aspect)), 0.0),",
       "origin_dx: v4(to_tex * (right * (spread * tan)), 0.0),")]),
    ("slab-upper-ignored", "the slab box's upper corner is ignored",
     [("src/render/uniforms.rs", "slab_hi: v4(s.cut.slab_hi.as_dvec3(), 0.0),", "slab_hi: v4(DVec3::ONE, 0.0),")]),
    ("multiplied-alpha-ignored", "the multiplied-alpha model is ignored",
     [("src/transfer/function.rs", "if *multiplied { c * step_alpha } else { *step_alpha },", "*step_alpha,")]),
    ("data-units-offset", "transfer functions in data units forget the range's minimum",
     [("src/transfer/function.rs", "TfUnits::Data => (range[0] + v as f64 * (range[1] - range[0])) as f32,",
       "TfUnits::Data => (v as f64 * (range[1] - range[0])) as f32,")]),
    ("corner-next-row-missed", "the corner texture's y + 1 values are taken from the texel's own row",
     [("src/render/texels.rs", "[at(r.this[x]), at(r.this[x1]), at(r.next[x]), at(r.next[x1])]",
       "[at(r.this[x]), at(r.this[x1]), at(r.this[x]), at(r.this[x1])]")]),
    ("mip-minimum", "maximum intensity projection keeps the minimum",
     [("shaders/march.glsl", "m = mode == MODE_MIP ? max(m, v) : min(m, v);", "m = mode == MODE_MIP ? min(m, v) : min(m, v);")]),
    ("gradient-texture-scale", "the gradient texture's gradients are twice too large (gradient opacity saturates)",
     [("shaders/volume.glsl", "return 0.5 * g.xyz * (b.scale.x / frame.dims.x);",
       "return g.xyz * (b.scale.x / frame.dims.x);")]),
    ("segment-one-step", "every segment is taken as one step long (the ray's first, strided segments)",
     [("shaders/march.glsl", "frame.alpha.y * (t - t_prev) / ray.h,", "frame.alpha.y,")]),
    ("counter-counts-visible", "the sample counter counts only composited segments, not every sample taken",
     [("shaders/march.glsl", "taken += 1u;\n            composite(color, opacity, c.rgb, c.a);",
       "composite(color, opacity, c.rgb, c.a);\n            taken += c.a > 0.0 ? 1u : 0u;")]),
    ("stride-spread-dropped", "brick strides ignore how much the brick's extinction varies (leap over edges)",
     [("src/render/skip.rs", " && spread_b * length <= spread", "")]),
    ("reach-one-too-far", "a brick's reach is the distance to another class, not one less: spans run into the next class",
     [("src/render/skip.rs", "*r = d - 1;", "*r = d;")]),
    ("parallel-read-no-bias", "the parallel reader forgets signed 16-bit data's bias",
     [("src/formats/decode.rs", "v.par_iter_mut().for_each(|w| *w ^= 0x8000);", "v.par_iter_mut().for_each(|w| *w ^= 0);")]),
    ("integer-gradients-sobel", "integer data take the float data's Sobel gradient (terraces shade again)",
     [("src/render/gradients.rs", "            _ => GradientFilter::Gaussian,", "            _ => GradientFilter::Sobel,")]),
    ("iso-falling-ignored", "iso-surfaces are met only where the values rise (a layer's far side is lost)",
     [("shaders/march.glsl", "if (below_before == (v < iso)) {", "if (!below_before || below_before == (v < iso)) {")]),
    ("light-grid-window-ignored", "the light grid absorbs outside the value window (the table's edge entries)",
     [("src/render/light_volume.rs", "if v < s.colour.window[0] || v > s.colour.window[1] {", "if v < 0.0 || v > 1.0 {")]),
    ("shadow-read-in-place", "shadows are read at the lit point itself, not 1.5 cells towards the light",
     [("shaders/shade.glsl", "p + frame.light_grid.xyz, 0.0).x;", "p, 0.0).x;")]),
    ("occlusion-ignored", "ambient occlusion is computed but never applied",
     [("shaders/shade.glsl", "ambient *= textureLod(sampler3D(light_tex, linear_smp), p, 0.0).y;", "ambient *= 1.0;")]),
    ("stride-misaligned", "a strided span starts at its first sample instead of the first multiple of its stride",
     [("shaders/walk.glsl", "w.k = (w.k + w.stride - 1) & ~(w.stride - 1);", "w.k = w.k + 0;")]),
    ("value-not-clamped", "the normalised sample is not clamped to [0, 1] (a rescaled maximum falls out of the window)",
     [("shaders/volume.glsl", "return isnan(v) ? v : clamp(v, 0.0, 1.0);", "return v;")]),
    ("qfac-ignored", "a NIfTI qform's qfac −1 is ignored (a mirrored brain)",
     [("src/volume/geometry.rs", "let qfac = if qfac < 0.0 { -1.0 } else { 1.0 };", "let qfac = 1.0;")]),
    ("dicom-lps-as-ras", "DICOM's LPS patient coordinates are taken as RAS",
     [("src/formats/dicom/geometry.rs", "Geometry::anatomical(geometry::LPS_TO_RAS * geometry::from_columns(columns, origin))",
       "Geometry::anatomical(geometry::from_columns(columns, origin))")]),
    ("nrrd-lps-as-ras", "an NRRD in left-posterior-superior space is read as RAS",
     [("src/formats/nrrd.rs", "Space::Lps => flip(-1.0, -1.0),", "Space::Lps => DMat4::IDENTITY,")]),
    ("metaimage-matrix-rows", "MetaImage's TransformMatrix is read row by row instead of axis by axis",
     [("src/formats/metaimage.rs", "DVec3::new(m[n * i], m[n * i + 1], m[n * i + 2])", "DVec3::new(m[i], m[i + n], m[i + 2 * n])")]),
    ("mirror-cull-not-swapped", "a mirrored placement keeps the entry pass culling back faces",
     [("src/render/record.rs", "self.pipelines.position[pi][j ^ flip]", "self.pipelines.position[pi][j + flip * 0]")]),
    ("normals-not-inverse-transposed", "gradients go to the world by the placement itself, not its inverse transpose",
     [("src/render/uniforms.rs", "gradient_to_world: m4(DMat4::from_mat3(index_to_world.inverse().transpose())),",
       "gradient_to_world: m4(DMat4::from_mat3(index_to_world)),")]),
    ("uneven-not-resampled", "an unevenly spaced DICOM series is not resampled (slices past a gap misplaced)",
     [("src/formats/dicom/geometry.rs", "const UNEVEN_TOLERANCE: f64 = 0.05;", "const UNEVEN_TOLERANCE: f64 = 50.0;")]),
    ("clip-plane-caps-iso", "the clipping plane caps iso-surfaces (the first sample meets them) instead of cutting them open",
     [("shaders/march.glsl", "int meets = ((cut_start && !has_prev) || !owned(ray.a + ray.dir * t)) ? 0 : count;",
       "int meets = !owned(ray.a + ray.dir * t) ? 0 : count;")]),
    ("clip-normal-not-transposed", "the clipping plane's normal goes to texture space by the placement, not its transpose",
     [("src/scene/clip.rs", "let m = DMat3::from_mat4(to_world).transpose() * n;",
       "let m = DMat3::from_mat4(to_world) * n;")]),
    ("turntable-short-turn", "a turntable's frames turn by 360°/(N + 1) instead of 360°/N (the loop does not close)",
     [("src/movie/path.rs", "let angle = std::f64::consts::TAU * f64::from(k) / f64::from(n);",
       "let angle = std::f64::consts::TAU * f64::from(k) / f64::from(n + 1);")]),
    ("keyframe-long-way", "keyframed cameras may turn the long way round (slerp without the shorter-arc sign flip)",
     [("src/movie/path.rs", "let q = qa.slerp(qb, t);", "let q = qa.slerp_long(qb, t);")]),
    ("keyframe-last-missed", "a keyframed path's frames spread over N instead of N − 1 steps (it never reaches its last state)",
     [("src/movie/path.rs", "let u = f64::from(k.min(n - 1)) * segments as f64 / f64::from(n - 1);",
       "let u = f64::from(k.min(n - 1)) * segments as f64 / f64::from(n);")]),
    ("gif-plays-once", "the movie's GIF plays once instead of looping",
     [("src/movie/gif.rs", "e.set_repeat(::gif::Repeat::Infinite)?;", "e.set_repeat(::gif::Repeat::Finite(0))?;")]),
    ("colorbar-upside-down", "the colour bar puts the window's lower end at the top",
     [("src/transfer/colorbar.rs", "        hi - t * (hi - lo)\n", "        lo + t * (hi - lo)\n")]),
    ("colorbar-unit-dropped", "render --colorbar labels a CT's ticks without HU",
     [("src/render/figure.rs", "unit: VolumeFacts::of(volume).kind().unit(),", "unit: None,")]),
    ("auto-ct-needs-huge-max", "the auto preset misses CT without a modality tag (bone threshold 10x too high)",
     [("src/transfer/auto.rs", "max >= 1000.0", "max >= 10000.0")]),
    ("viewer-redraws-forever", "the viewer honours egui-winit's repaint on every RedrawRequested (it never goes idle)",
     [("src/viewer/app/mod.rs", "let repaint = repaint && !matches!(event, WindowEvent::RedrawRequested);",
       "let repaint = repaint;")]),
    ("typing-after-click-lost", "keys typed in the frame of the click that focused a text field are delivered with it",
     [("src/viewer/app/input.rs",
       "Event::Text(_) | Event::Paste(_) | Event::Key { pressed: true, .. } if after_click.is_some() => {",
       "Event::Text(_) | Event::Paste(_) | Event::Key { pressed: true, .. } if after_click.is_some() && false => {")]),
    ("tf-drag-picks-at-pointer", "a drag in the transfer-function editor picks the point under the pointer when egui starts it, not under the press",
     [("src/viewer/widgets/tf_editor/mod.rs", "let origin = press_origin(ctx, pos);", "let origin = pos;")]),
    ("pyramid-mean-over-eight", "convert's pyramid divides every block's sum by 8, so partial blocks at odd edges come out dark",
     [("src/pyramid/reduce.rs", "sum::<f64>() / block.len() as f64),", "sum::<f64>() / 8.0),")]),
    ("pyramid-translation-not-centred", "convert's coarser levels keep level 0's translation instead of their blocks' centres",
     [("src/convert/layout.rs", "self.translation[i] + (f[i] - 1.0) / 2.0 * self.scale[i]", "self.translation[i]")]),
    ("zarr-micrometre-as-mm", "an OME-Zarr axis in micrometres is read as millimetres",
     [("src/formats/zarr/metadata.rs", "U::Micrometer => 1e-3,", "U::Micrometer => 1.0,")]),
    ("zarr-own-placement-ignored", "the reader ignores the exact affine that convert writes (a flipped axis and the RAS frame are lost)",
     [("src/formats/zarr/metadata.rs", "let json = multiscale\n        .and_then(|m| m.get(\"volcast\"))\n        .or_else(|| metadata.and_then(|m| m.get(\"volcast\")))",
       "let json = multiscale\n        .and_then(|m| m.get(\"volcast-\"))\n        .or_else(|| metadata.and_then(|m| m.get(\"volcast-\")))")]),
    ("metaimage-not-lps", "a MetaImage is placed as if its world were RAS, not ITK's LPS (mirrored in x and y against Slicer)",
     [("src/formats/metaimage.rs", "geometry::LPS_TO_RAS * geometry::from_columns(columns, origin),", "geometry::from_columns(columns, origin),")]),
    ("pool-border-own-edge", "a brick's border in its slot repeats the brick's own edge voxels instead of holding its neighbours'",
     [("src/render/pool.rs", "v.clamp(0, i64::from(dims[a]) - 1) as usize",
       "v.clamp(i64::from(r.brick[a] * self.brick[a]), (i64::from((r.brick[a] + 1) * self.brick[a]) - 1).min(i64::from(dims[a]) - 1)) as usize")]),
    ("span-crosses-bricks", "the walk's spans do not end at the pool's brick faces, so samples past a face read another slot",
     [("shaders/walk.glsl", "    Brick pb = brick_box_at(p, lo, hi, shown);", "    Brick pb = brick_box_at(p, lo, hi, shown);\n    lo = vec3(-1e30);\n    hi = vec3(1e30);")]),
    ("page-table-slot-axes", "the page table's slot position is decoded with y and z swapped",
     [("shaders/volume.glsl", "uvec3(e.x, e.x >> 10u, e.x >> 20u)", "uvec3(e.x, e.x >> 20u, e.x >> 10u)")]),
    ("level-brick-not-shifted", "the page table's level-L brick is taken as the level-0 brick's own index instead of b >> L",
     [("shaders/volume.glsl", "- vec3(b >> level) * frame.pool_brick.xyz;", "- vec3(b) * frame.pool_brick.xyz;")]),
    ("level-scale-ignored", "a brick of level L is sampled at level-0 voxel coordinates (no 2^-L)",
     [("shaders/volume.glsl", "float s = exp2(-float(level));", "float s = 1.0 + 0.0 * float(level);")]),
    ("level-gradient-unscaled", "the gradient texture of a level-L brick is read per voxel of its level, not of level 0",
     [("shaders/volume.glsl", "return 0.5 * g.xyz * (b.scale.x / frame.dims.x);", "return 0.5 * g.xyz;")]),
    ("skip-levels-ignored", "the skip grid's ranges ignore the coarser levels a brick may show",
     [("src/render/levels.rs", "let l = cut.level[(x + cut.grid[0] * (y + cut.grid[1] * z)) as usize];",
       "let l = 0 * cut.level[(x + cut.grid[0] * (y + cut.grid[1] * z)) as usize];")]),
    ("skip-straddle-ignored", "a skip brick over two pool bricks takes the ranges of the first one's level alone",
     [("src/render/levels.rs", "let hi = [0, 1, 2].map(|a| ((at[a] * s + s - 1) / brick[a]).min(cut.grid[a] - 1));",
       "let hi = lo;")]),
    ("screen-rule-far-side", "the screen rule measures a brick's distance to its far side instead of its near side",
     [("src/render/levels.rs", "let d = ((wl + wh) / 2.0 - view.eye).length() - (wh - wl).length() / 2.0;",
       "let d = ((wl + wh) / 2.0 - view.eye).length() + (wh - wl).length() / 2.0;")]),
    ("stream-top-evicted", "the stream may evict the top level's brick, every missing brick's last fallback",
     [("src/render/stream.rs", "(key != top && want.binary_search(&key).is_err())", "(want.binary_search(&key).is_err())")]),
    ("stream-evicts-wanted", "the stream evicts a wanted resident brick to upload another wanted one",
     [("src/render/stream.rs", "(key != top && want.binary_search(&key).is_err())", "(key != top)")]),
    ("stream-fallback-coarsest", "a missing brick shows the coarsest resident brick over it instead of the finest",
     [("src/render/stream.rs", ".find(|&level| self.is_resident((level, covering(b, level))))",
       ".rev().find(|&level| self.is_resident((level, covering(b, level))))")]),
    ("brick-upload-slot-y", "a streamed brick is copied to its slot's x position along y",
     [("src/render/brick_upload.rs", "y: (at[1] * side[1]) as i32,", "y: (at[0] * side[1]) as i32,")]),
    ("stream-page-table-stale", "a stream step writes the page table of the cut shown before it",
     [("src/render/resident.rs", "stream.write(&mut self.pool, &step.shown);", "stream.write(&mut self.pool, &self.cut);")]),
    ("viewer-refine-once", "the viewer stops streaming once a cut is reached, so a turned view keeps the old view's levels",
     [("src/viewer/present/volume_pass.rs", "if reached.cut.as_ref() == Some(&wanted) {", "if reached.cut.is_some() {")]),
    ("placement-gpu-budget-ignored", "a volume over the GPU budget whole is uploaded whole instead of streamed",
     [("src/render/placement.rs", "misfit(&shape, 0, &gpu_only).is_none()", "misfit(&shape, 0, &gpu_only).is_none() || gpu_only.host > 0")]),
    ("figure-uploads-whole", "Export figure uploads a streamed volume whole, so the figure shows finer levels than the view",
     [("src/viewer/present/figure.rs", "headless.renderer.place_volume(gpu, volume, budgets)?;", "headless.set_volume(gpu, volume)?;")]),
    ("stream-skip-ignored", "a .nii.gz decoded as a stream reads its header and extensions as voxels",
     [("src/convert/source.rs", "s.skip_to(v, inflate.skip)?;", "s.skip_to(v, 0)?;")]),
    ("cut-bound-off-by-one", "the bounded screen rule counts a refined brick's replacement as one more brick than it is",
     [("src/render/levels.rs", "if count - 1 + children.len() > bricks {", "if count + children.len() > bricks {")]),
    ("level-not-centred", "a pyramid level read within the budgets keeps level 0's voxel positions instead of its blocks' centres",
     [("src/pyramid/geometry.rs", "g.downsampled(f.map(|v| v as u32))",
       "Geometry { affine: g.affine * glam::DMat4::from_scale(glam::DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64)), ..g }")]),
    ("level-budget-upload-ignored", "the level rule lets a texture take the whole GPU budget, leaving nothing for its upload",
     [("src/pyramid/budget.rs", "(texture > gpu.bytes / 2).then(|| {", "(texture > gpu.bytes).then(|| {")]),
    ("level-int16-bias", "a pyramid level of int16 data is re-biased by 32767 instead of 32768",
     [("src/scale/read.rs", "(i32::from(v) + 32768) as u16", "(i32::from(v) + 32767) as u16")]),
    ("preview-not-strided", "the strided preview is placed as if its voxels were the file's, so it fills a corner of the box",
     [("src/scale/preview.rs", "affine: place.geometry.affine * DMat4::from_diagonal(DVec4::new(kf, kf, kf, 1.0)),",
       "affine: place.geometry.affine * DMat4::from_diagonal(DVec4::new(1.0, 1.0, 1.0, 1.0 + 0.0 * kf)),")]),
    ("preview-series-every-slice", "a DICOM series' preview decodes its first slices instead of every k-th one, so it shows only the near end",
     [("src/scale/preview.rs", "series.read_at(u64::from(z) * u64::from(k) * plane as u64, &mut bytes)?;",
       "series.read_at(u64::from(z) * plane as u64, &mut bytes)?;")]),
    ("loading-frames-unpaced", "while a load is under way, slow frames of its preview follow each other at the loading interval, taking the cores from the load",
     [("src/viewer/app/pacing.rs", "let at = self.frame_end + LOADING_INTERVAL.max(2 * self.frame_took);",
       "let at = self.frame_end + LOADING_INTERVAL;")]),
    ("view-marched-every-frame", "every frame marches the view again, though only the panel changed (0.4 s of both cores per frame on lavapipe)",
     [("src/viewer/present/reuse.rs", "if *g == self.generation && m == s)", "if *g == self.generation && m == s && s.width == 0)")]),
    ("view-reuse-ignores-volume", "a frame shows the last march again when only its volume changed (bricks refined, a step, a new volume), so a still streamed view keeps its coarser bricks",
     [("src/viewer/present/reuse.rs", "if *g == self.generation && m == s)", "if { let _ = g; m == s })")]),
    ("cache-stamp-ignored", "the pyramid cache uses an entry made from the file before it changed",
     [("src/scale/cache.rs", '(Some(f), Some(n)) if f != n => "the file changed since it was made",',
       '(Some(f), Some(n)) if f.version != n.version => "the file changed since it was made",')]),
    ("finer-box-short", "a brick read from the file leaves out its upper border, so filtering at its far faces repeats its last voxel",
     [("src/render/brick_upload.rs", "(r.brick[a] * pool.brick[a] + pool.brick[a] + BORDER).min(dims[a])",
       "(r.brick[a] * pool.brick[a] + pool.brick[a]).min(dims[a])")]),
    ("finer-level-at-level-0", "a finer level's box is read from level 0 at the level's own coordinates",
     [("src/pyramid/bricks.rs", "let lo0 = lo.map(|v| to_level0(v, level));", "let lo0 = lo;")]),
    ("level-own-range", "a level read from a file normalises by its own (narrower) range, so bricks later read from the file map differently",
     [("src/scale/read.rs", "v = v.with_stored_range(stored.unwrap_or([0.0, 0.0]));", "let _ = stored;")]),
    ("step-level-ignored", "a cut of coarser levels is marched at level 0's step",
     [("src/render/uniforms.rs", "s.sampling.step_length * (1u32 << self.step_level) as f32",
       "s.sampling.step_length * (1u32 << (self.step_level * 0)) as f32")]),
    ("strides-at-coarse-steps", "strides are taken where the step is coarser than the held level's voxel (the reference takes none)",
     [("src/render/uniforms.rs", "if self.step_level > self.held {\n            stepped", "if self.step_level > self.held + 9 {\n            stepped")]),
    ("level-stride-ignored", "coarser bricks of a mixed cut are sampled at the finest level's pace (rule 2's level stride dropped)",
     [("shaders/walk.glsl", "(1 << (3 - span.level)) * span.coarser;", "(1 << (3 - span.level));")]),
    ("stride-tolerance-ignored", "the GPU's strides ignore the quality's tolerance on the spread bound (draft strides as normal does)",
     [("src/render/skip.rs", "let (depth, spread) = (s.stride_depth(), s.stride_spread());",
       "let (depth, spread) = (s.stride_depth(), crate::scene::settings::STRIDE_SPREAD);")]),
    ("shading-fade-ignored", "the GPU lights flat regions fully although --shading-fade asks for flat light there",
     [("shaders/shade.glsl", "float width = frame.voxel_world.x;", "float width = 0.0;")]),
    ("finer-bricks-take-the-held-range", "a brick read from the file takes the held level's skip range, narrower than its own voxels'",
     [("src/render/levels.rs", "let Some(l) = l.checked_sub(held).map(|l| l as usize) else {",
       "let Some(l) = Some(l.saturating_sub(held) as usize) else {")]),
    ("pyramid-whole-block-quarter", "the pyramid's whole-block path divides the 2x2x2 sum by 4",
     [("src/pyramid/sample.rs", "integer_sample!(u8, VoxelType::U8, u16, |s| (s + 4) / 8);",
       "integer_sample!(u8, VoxelType::U8, u16, |s| (s + 4) / 4);"),
      ("src/pyramid/sample.rs", "integer_sample!(u16, VoxelType::U16, u32, |s| (s + 4) / 8);",
       "integer_sample!(u16, VoxelType::U16, u32, |s| (s + 4) / 4);"),
      ("src/pyramid/sample.rs", "integer_sample!(i16, VoxelType::I16, i32, |s| (s + if s < 0 { -4 } else { 4 }) / 8);",
       "integer_sample!(i16, VoxelType::I16, i32, |s| (s + if s < 0 { -4 } else { 4 }) / 4);"),
      ("src/pyramid/sample.rs", "*slot = Self::from_f64(sum / 8.0);", "*slot = Self::from_f64(sum / 4.0);")]),
    ("histogram-element-raw", "the parallel histogram bins 8/16-bit elements by their raw value, not their normalised one",
     [("src/transfer/auto.rs", "let v = volume.normalize_element(e as f64);", "let v = e as f64 / 65535.0;")]),
    ("refine-apron-dropped", "a brick's refinement test reads only the cells under its box, not the 2^L voxels its samples reach beyond it",
     [("src/render/refinable.rs", "let lo = [0, 1, 2].map(|a| (b[a] * side[a]).saturating_sub(apron));",
       "let lo = [0, 1, 2].map(|a| b[a] * side[a]);"),
      ("src/render/refinable.rs", "let hi = [0, 1, 2].map(|a| (b[a] + 1) * side[a] + apron);",
       "let hi = [0, 1, 2].map(|a| (b[a] + 1) * side[a]);")]),
    ("refine-everything", "bricks that show nothing are refined all the same (the refinement test ignores the classes)",
     [("src/render/refinable.rs", ".is_none_or(|&c| c > 0)", ".is_none_or(|&c| c < 9)")]),
    ("refine-by-held-level", "which finer bricks can show anything is judged by the held level's ranges, whose means hide a thin sheet",
     [("src/render/resident.rs", "Some(f) => volume.cells.as_deref().filter(|c| c.dims == f.dims())?,",
       "Some(f) => {\n                        made = CellRanges { cell: CellRanges::SIDE << f.held(), dims: f.dims(), ..CellRanges::of(volume) };\n                        &made\n                    }")]),
    ("vti-base64-groups", "a base64 range of an appended .vti array is read from character 3k instead of 4k for byte 3k",
     [("src/formats/vtk/vti_blocks.rs", "let chars = self.bytes(self.start + 4 * first, 4 * (last - first))?;",
       "let chars = self.bytes(self.start + 3 * first, 4 * (last - first))?;")]),
    ("vti-blocks-after-three-words", "a raw compressed .vti array's blocks are taken to start after the first three header words",
     [("src/formats/vtk/vti_blocks.rs", "Text::Raw => (at, header),", "Text::Raw => (at, 3 * word as u64),")]),
    ("cells-layer-misplaced", "the read pass merges each slab's level-0 ranges into the layer of cells below its own",
     [("src/scale/read.rs", "for (oz, layer) in layers {\n                cells.merge_layer((oz / cells_per_layer) as u32, &layer);",
       "for (oz, layer) in layers {\n                cells.merge_layer((oz / cells_per_layer).saturating_sub(1) as u32, &layer);")]),
    ("cells-not-kept", "the pyramid cache keeps a level without level 0's ranges beside it",
     [("src/scale/cache.rs", "Some(c) => std::fs::write(&cells_path, c.to_bytes())", "Some(c) => std::fs::write(&cells_path, &c.to_bytes()[..8])")]),
    ("dicom-slices-biased", "a signed DICOM series read slice by slice keeps volcast's bias in the values it gives the level",
     [("src/formats/dicom/slices.rs", "let flip = if self.voxel_type == VoxelType::I16 { 0x8000 } else { 0 };",
       "let flip = 0;")]),
    ("dicom-slices-resample-window", "an unevenly spaced series read slice by slice decodes one sorted slice too few past a run",
     [("src/formats/dicom/slices.rs", "let hi = (at[z0 + n - 1].floor() as usize + 1).min(last);",
       "let hi = (at[z0 + n - 1].floor() as usize).min(last);")]),
    ("dicom-slices-stamp-first-file", "the pyramid cache stamps a DICOM series' level by its first file alone",
     [("src/formats/dicom/slices.rs", "self.files.iter().try_fold(", "self.files.iter().take(1).try_fold(")]),
    ("zarr-boxes-axes-reversed", "an OME-Zarr store's level-0 boxes are read with x and z swapped",
     [("src/formats/zarr/boxes.rs", "space: [space[2], space[1], space[0]],", "space: [space[0], space[1], space[2]],")]),
    ("zarr-finer-placement-unchecked", "a store's level 0 streams behind a held level placed otherwise",
     [("src/formats/zarr/boxes.rs", "if !placed.affine.abs_diff_eq(v.geometry.affine, tolerance) {", "if false {")]),
    ("box-span-rows-packed", "a box read as one span per slice takes its rows as if they lay next to each other in the file",
     [("src/convert/source.rs", "convert(&bytes[r * row_bytes..][..sx * vsize], d);", "convert(&bytes[r * sx * vsize..][..sx * vsize], d);")]),
    ("finer-cells-apron-dropped", "a skip cell over a brick read from the file takes its own voxels without the one around it that a sample reads",
     [("src/render/finer_cells.rs", "let from = (c[a] * side).max(ilo[a]).saturating_sub(1).max(lo[a]);",
       "let from = (c[a] * side).max(ilo[a]).max(lo[a]);")]),
    ("finer-cells-first-for-all", "every skip cell over a brick read from the file takes the range of the brick's first cell",
     [("src/render/levels.rs", ".and_then(|cells| cells.at(at))", ".and_then(|cells| cells.ranges.first().copied())")]),
    ("slot-row-run-shifted", "a streamed brick's rows copied as runs of its level start one voxel to the right",
     [("src/render/brick_upload.rs", "return run(level, first + x0, row);", "return run(level, first + x0 + 1, row);")]),
    ("slot-run-u16-widened-as-8-bit", "a streamed brick's 16-bit rows copied as runs into a float pool are divided by 255",
     [("src/render/texels.rs", "widen(&v[l as usize][i..i + out.len()], 65535.0, out)", "widen(&v[l as usize][i..i + out.len()], 255.0, out)")]),
    ("slot-box-corner-ignored", "a brick read from the file as a box is indexed as if the box started at the level's corner",
     [("src/render/brick_upload.rs", "let lo = self.within.map_or(0, |b| b.lo[a]);", "let lo = self.within.map_or(0, |_| 0);")]),
    ("reach-one-sided", "the skip grid's reach along y and z looks only at the bricks before, not after",
     [("src/render/skip.rs", "*o = (*o).min(x.min(y).max(d8));", "*o = (*o).min(x.max(d8));")]),
    ("level0-at-the-stream-offset", "a decoded file's kept level 0 is read from where its voxels start in the file, "
     "not from the kept file's first byte",
     [("src/scale/level0.rs", "        offset: 0,\n        voxel_type: kept_type", "        voxel_type: kept_type")]),
    ("level0-cut-trusted", "a kept level 0 shorter than its stamp says is used as it is",
     [("src/scale/cache.rs", "Some(true) if self.kept_level0(place, level).is_none() =>", "Some(true) if false =>")]),
    ("level0-slab-at-its-level-slice", "a slab of a decoded file is kept at its output slice's place in level 0, not "
     "its own",
     [("src/scale/read.rs", "keep.write_at(u64::from(z0) * slice0_bytes, bytemuck::cast_slice(buf));",
       "keep.write_at(oz as u64 * slice0_bytes, bytemuck::cast_slice(buf));")]),
    ("cache-rescale-dropped", "a rescaled file's level is cached as stored values without its rescale",
     [("src/convert/mod.rs", "s if opts.stored => (Scaling::IDENTITY, Some(s).filter(|s| !s.is_identity())),",
       "s if opts.stored => (Scaling::IDENTITY, None::<Scaling>),")]),
    ("cache-stores-rescaled-values", "a rescaled file's level is cached in rescaled values, not in the stored ones its "
     "finer bricks are read in",
     [("src/scale/cache.rs", "            stored: true,\n", "            stored: false,\n")]),
    ("pool-short-of-its-pyramid", "a pool that the budget lets hold every brick of the pyramid is rounded down to the "
     "most slots its count arranges, so some bricks never refine",
     [("src/render/resident.rs", ".filter(|&n| n <= fit)", ".filter(|&n| n <= fit.min(bricks_in_pyramid))")]),
    ("frames-in-file-order", "a multi-frame file's frames are read in the order they are stored, not sorted along the "
     "slice normal",
     [("src/formats/dicom/slices.rs", "Some((frames, order)) => frames.append(order[k], &mut data)?,",
       "Some((frames, _)) => frames.append(k, &mut data)?,")]),
    ("shuffled-frames-read-in-place", "native frames stored out of slice order are read in place as a raw volume",
     [("src/formats/dicom/slices.rs", "let plain = frames.plain_at().filter(|_| in_order);",
       "let plain = frames.plain_at();")]),
    ("spaced-rays-framed-at-their-own-aspect", "spaced rays (rule 12) are projected with the marched image's aspect, "
     "not the output's",
     [("src/render/uniforms.rs", "    s.width as f32 / s.height as f32\n",
       "    s.marched_size().0 as f32 / s.marched_size().1 as f32\n")]),
    ("spaced-rays-stretched-nearest", "the marched image is stretched over the output by its nearest pixel, not "
     "bilinearly",
     [("src/render/spacing.rs", "vk::Filter::LINEAR,", "vk::Filter::NEAREST,")]),
    ("draft-spaces-sharp-edges", "draft spaces its rays whatever the classification, blurring sharp edges past its "
     "target",
     [("src/scene/quality.rs", "\n                && opacity_edge(s, range) <= SOFT_EDGE\n", "\n")]),
    ("draft-casts-every-ray", "draft casts a ray for every pixel even where its classification is soft (the spacing "
     "it is fast by dropped)",
     [("src/scene/quality.rs", "if self == Quality::Draft && soft() {\n            2", "if self == Quality::Draft && soft() {\n            1")]),
    ("clicks-share-a-frame", "a click and a click elsewhere share a slow frame, where egui gives both to the widget "
     "under the last",
     [("src/viewer/app/input.rs", "Event::PointerButton { pos, .. } if left(released, pos) => {",
       "Event::PointerButton { pos, .. } if left(released, pos) && false => {")]),
    ("triple-click-ignored", "a double click soon after a click elsewhere, which egui counts as a triple click, does "
     "nothing (the file chooser's Open… then a file)",
     [("src/viewer/widgets/clicks.rs", "let double = response.double_clicked() || (response.triple_clicked() && !after_double);",
       "let double = response.double_clicked();")]),
    ("triple-click-opens-twice", "the third click of a real triple click counts as a second double click (a folder "
     "entered, then the row under the third click opened)",
     [("src/viewer/widgets/clicks.rs", "(response.triple_clicked() && !after_double);", "response.triple_clicked();")]),
    ("slow-frame-splits-double-click", "the second click of a double click that waited while a slow frame was drawn "
     "is timed after that frame: no double click",
     [("src/viewer/app/clock.rs", "(Some((_, true)), Some(began)) => since(began) + 1e-3,",
       "(Some((_, true)), Some(_)) => since(now),")]),
    ("stand-in-depth-dropped", "a stand-in (a preview, a level under a budget, --max-dim) takes its opacity per voxel "
     "of its own: a fraction of the volume's optical depth",
     [("src/render/uniforms.rs", "step_length * v.source_voxels,", "step_length,")]),
    ("scale-bar-full-fov", "the scale bar takes the whole field of view for the half angle: bars twice too short",
     [("src/render/scale_bar.rs", "let half = (f64::from(c.fov_y_deg) / 2.0).to_radians().tan();",
       "let half = f64::from(c.fov_y_deg).to_radians().tan();")]),
    ("measurement-in-voxels", "a saved measurement's ends are voxel indices, not world millimetres",
     [("src/viewer/model/measurements.rs", "let (start, end) = (affine.transform_point3(a), affine.transform_point3(b));",
       "let (start, end) = (a, b);")]),
    ("four-up-views-touch", "the four-up views touch: one view's edge label reads as a pair with the next one's",
     [("src/viewer/widgets/layout.rs", "pub const SEPARATOR: f32 = 4.0;", "pub const SEPARATOR: f32 = 0.0;")]),
    ("mr-default-translucent", "the MR auto transfer function tops out at a fog's opacity",
     [("src/transfer/auto.rs", "[0.5, 0.3, 0.7], [1.0, 0.375, 0.9]];", "[0.5, 0.03, 0.7], [1.0, 0.08, 0.9]];")]),
    ("spacing-printed-long", "spacing prints every digit of its f32 rounding (0.85937506)",
     [("src/volume/geometry.rs", "    (0..=12)\n        .map(|p| format!(\"{x:.p$}\"))", "    (12..=12)\n        .map(|p| format!(\"{x:.p$}\"))")]),
    ("label-sampled-linearly", "a label map's dense ids are interpolated between neighbours along x, as a linear filter would",
     [("shaders/layers.glsl", "    uint id = texelFetch(usampler3D(layer_labels, linear_smp), v, 0).r;",
       "    ivec3 w = clamp(ivec3(floor(x)), ivec3(0), ivec3(L.dims.xyz) - 1);\n"
       "    w.z += int(L.dims.w);\n"
       "    uint id = uint(mix(float(texelFetch(usampler3D(layer_labels, linear_smp), w, 0).r),\n"
       "                       float(texelFetch(usampler3D(layer_labels, linear_smp), w + ivec3(1, 0, 0), 0).r),\n"
       "                       fract(x.x)) + 0.5);")]),
    ("layer-other-affine", "a layer is placed with the base volume's affine instead of its own",
     [("src/render/layers.rs", "let to_index = p.geometry.affine.inverse() * base.affine * tex_to_index;",
       "let to_index = base.affine.inverse() * base.affine * tex_to_index;")]),
    ("layer-bricks-unmarked", "a layered frame leaps over the base's empty bricks even where a layer shows something",
     [("src/render/layer_bricks.rs", "levels[i as usize] = 1;", "levels[i as usize] = levels[i as usize].max(0);")]),
    ("layer-strides-kept", "a base brick where a layer shows something keeps the base's stride, so the layer is "
     "sampled at every fourth step",
     [("src/render/layer_bricks.rs", "levels[i as usize] = 1;", "levels[i as usize] = levels[i as usize].max(1);")]),
    ("nrrd-list-axis-as-time", "a NRRD's leading list axis (a Slicer segmentation's layers) is read as steps stored one "
     "after another",
     [("src/formats/format.rs", "let mut steps = if self.interleaved {", "let mut steps = if !self.interleaved {")]),
    ("layers-blended-whole", "layers are composited along the ray on their own and blended whole over the base, "
     "as napari and neuroglancer do: depth is lost",
     [("shaders/march.glsl", "                c = mix_layers(c, ray.a + ray.dir * t, 1.0 - opacity, light);",
       "                vec4 l = mix_layers(vec4(0.0), ray.a + ray.dir * t, 1.0 - opacity, light);\n"
       "                composite(lcolor, lopacity, l.rgb, l.a);"),
      ("shaders/march.glsl", "    Walk w = walk;\n    for (;;) {",
       "    Walk w = walk;\n    vec3 lcolor = m.lcolor;\n    float lopacity = m.lopacity;\n    for (;;) {"),
      ("shaders/march.glsl", "    m = Absorb(color, opacity, t_prev, v_prev, i_prev, taken);",
       "    m = Absorb(color, opacity, t_prev, v_prev, i_prev, taken, lcolor, lopacity);"),
      ("shaders/march.glsl", "    uint taken;\n};", "    uint taken;\n    vec3 lcolor;\n    float lopacity;\n};"),
      ("shaders/march.glsl", "v0, i0, 0u);", "v0, i0, 0u, vec3(0.0), 0.0);"),
      ("shaders/march.glsl", "    return share_or_finish(m.color, m.opacity, m.taken);\n}\n#endif",
       "    m.color = m.lcolor + (1.0 - m.lopacity) * m.color;\n"
       "    m.opacity = m.lopacity + (1.0 - m.lopacity) * m.opacity;\n"
       "    return share_or_finish(m.color, m.opacity, m.taken);\n}\n#endif")]),
    ("layer-span-short", "a ray mixes the layers only up to where it enters their span's box, not across it: layers "
     "vanish",
     [("shaders/layers.glsl", "    float t_out = min(min(far.x, far.y), far.z);",
       "    float t_out = max(max(near.x, near.y), near.z);")]),
    ("layer-blend-unattenuated", "an overlay blended by maximum or addition shows through what lies in front of it: "
     "its light is not dimmed by the ray's transmittance",
     [("shaders/march.glsl", "c = mix_layers(c, ray.a + ray.dir * t, 1.0 - opacity, light);",
       "c = mix_layers(c, ray.a + ray.dir * t, 1.0, light);")]),
    ("layer-add-absorbs", "an overlay blended by addition is composited in depth too: it absorbs what lies behind it",
     [("shaders/layers.glsl", "        if (gathered(i, l, front)) {\n            l = vec4(0.0);\n        }",
       "        gathered(i, l, front);")]),
    ("slice-layer-base-affine", "the slice views place a layer by the volume's affine instead of its own",
     [("src/scene/slice_layers.rs", "    layer.affine.inverse() * base.affine * mm_from_index.inverse()",
       "    let _ = layer;\n    base.affine.inverse() * base.affine * mm_from_index.inverse()")]),
    ("slice-labels-unoutlined", "the slice views fill labels at their opacity but draw no outline on their edges",
     [("src/scene/slice_layers.rs", "let a = if edge { table } else { table * opacity };",
       "let a = if edge && false { table } else { table * opacity };")]),
    ("label-normals-faceted", "a label's normal is the nearest corner's difference (facets per voxel), not interpolated over the cell",
     [("shaders/layers.glsl", "    vec3 f = c - lo;\n    ivec3 a = ivec3(lo);\n    ivec3 b = min(a + 1, ivec3(top));",
       "    vec3 f = round(c - lo);\n    ivec3 a = ivec3(lo);\n    ivec3 b = min(a + 1, ivec3(top));")]),
    ("labels-unlit", "label maps are not lit where shading is on",
     [("shaders/layers.glsl", "rgb = shade(rgb, label_gradient(L, x, id), light, p, 1.0);", "rgb = rgb;")]),
    ("label-normals-cell-only", "the reference's label normal is the cell's own difference (a staircase), not the corners' central differences",
     [("tests/common/layers.rs", "g[a] += w * (holds(up) - holds(down)) / 2.0;",
       "g[a] += w * (holds([up[0].min(lo[0] as i64 + 1), up[1].min(lo[1] as i64 + 1), up[2].min(lo[2] as i64 + 1)]) - holds([down[0].max(lo[0] as i64), down[1].max(lo[1] as i64), down[2].max(lo[2] as i64)]));")]),
    ("python-view-drops-layers", "volcast.view takes overlay= and labels= arrays but shows the volume without them",
     [("python/volcast/__init__.py", "_volcast.view(native, argv, layers)", "_volcast.view(native, argv)")]),
    ("units-taken-as-fractions", "a value typed in the data's units is taken as a fraction of the range (the old meaning)",
     [("src/scene/values.rs", "DataValue::Units(v) if range[1] > range[0] => ((v - range[0]) / (range[1] - range[0])) as f32,",
       "DataValue::Units(v) if range[1] > range[0] => v as f32,")]),
    ("stand-in-range-narrowed", "a volume reduced by --max-dim normalises by its means' narrower range: the window moves",
     [("src/pyramid/max_dim.rs", "(volume.range, volume.stored_range) = ranges;", "let _ = ranges;")]),
]

# The Python module's rules (python/): run against its pytest suite (test_commands).
BUGS += [
    ("array-axes-reversed", "an array of shape (z, y, x) is taken as x, y, z dims (numpy's order not reversed)",
     [("python/src/volume.rs", "let dims = [too_big(shape[2])?, too_big(shape[1])?, too_big(shape[0])?];",
       "let dims = [too_big(shape[0])?, too_big(shape[1])?, too_big(shape[2])?];")]),
    ("nibabel-not-transposed", "a nibabel image's (x, y, z) array is taken as (z, y, x) under its affine",
     [("python/volcast/_inputs.py", "return Volume.from_array(data.T, affine=", "return Volume.from_array(data, affine=")]),
    ("sitk-lps-kept", "a SimpleITK image's LPS placement is used as RAS",
     [("python/volcast/_inputs.py", "ras = np.diag([-1.0, -1.0, 1.0, 1.0]) @ lps", "ras = lps")]),
    ("size-keyword-as-list", "size=(w, h) becomes '--size w,h', which the command line refuses",
     [("python/volcast/_options.py", 'sep = "x" if keyword == "size"', 'sep = "," if keyword == "size"')]),
]

# Sort-last rendering over MPI (src/distributed, rule 11 in src/render/part.rs and march.glsl): run against
# tests/mpi under mpirun (test_commands), with the feature `mpi`.
BUGS += [
    ("kd-order-reversed", "the shares are composited back to front (the k-d tree's sides swapped)",
     [("src/distributed/decompose.rs", "let (first, second) = if below_first { (below, above) } else { (above, below) };",
       "let (first, second) = if below_first { (above, below) } else { (below, above) };")]),
    ("no-ghost-layer", "a rank holds only its own box: filtering, gradients and segments at its faces read clamped voxels",
     [("src/render/part.rs", "pub const GHOST_BELOW: u32 = 2 * BRICK;", "pub const GHOST_BELOW: u32 = 0;"),
      ("src/render/part.rs", "pub const GHOST_ABOVE: u32 = BRICK + 2;", "pub const GHOST_ABOVE: u32 = 0;")]),
    ("no-ring-of-bricks", "the bricks around a rank's box are empty in its skip grid: a strided segment entering the box "
     "starts at the wrong sample",
     [("src/render/part.rs", "let first = [0, 1, 2].map(|a| (part.lo[a] / BRICK).saturating_sub(1));",
       "let first = [0, 1, 2].map(|a| part.lo[a] / BRICK);"),
      ("src/render/part.rs", "let end = [0, 1, 2].map(|a| (part.hi[a].div_ceil(BRICK) + 1).min(bricks[a]));",
       "let end = [0, 1, 2].map(|a| part.hi[a].div_ceil(BRICK).min(bricks[a]));")]),
    ("segments-not-owned", "every rank composites every segment it walks, its ring's included",
     [("shaders/march.glsl", "if (step == WALK_SAMPLE && owned(ray.a + ray.dir * t)) {", "if (step == WALK_SAMPLE) {")]),
    ("projection-samples-not-owned", "MIP/MinIP/average count the samples of the ghost layer too",
     [("shaders/march.glsl", "if (!visible(v) || !owned(p)) {", "if (!visible(v)) {")]),
]

ROOT = Path(__file__).resolve().parent.parent
SCRATCH = Path(os.environ.get("PLANTED_SCRATCH", "/tmp/volcast-planted"))


def run(cmd, cwd, env=None, log=None):
    out = subprocess.run(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if log:
        log.write_text(out.stdout)
    return out


# Release code rebuilt incrementally: a one-line bug then costs seconds of compiling, not the crate's minutes.
# Codegen units change no float result (Rust has no fast-math), so the tests see what a release build computes.
PLANTED_PROFILE = """
[profile.planted]
inherits = "release"
incremental = true
codegen-units = 256
"""


def scratch_copy(commit):
    """The tree of `commit` in SCRATCH/main, beside ../shared, with its own target folder kept across runs."""
    tree = SCRATCH / "main"
    if tree.exists():
        shutil.rmtree(tree)
    tree.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, stdout=subprocess.PIPE, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    with open(tree / "Cargo.toml", "a") as f:
        f.write(PLANTED_PROFILE)
    # The tests' pinned Python (`bash .ci/python-env` made it in the checkout): with CI=true a test that needs it
    # fails rather than skips, so the scratch tree uses the checkout's.
    venv = ROOT / ".venv-tests"
    if not venv.exists():
        raise SystemExit(f"{venv} is missing: run `bash .ci/python-env` first")
    (tree / ".venv-tests").symlink_to(venv)
    shared = SCRATCH / "shared"
    if not shared.exists() and (ROOT.parent / "shared").exists():
        shared.symlink_to(ROOT.parent / "shared")
    return tree


def python_env(tree, env):
    """SCRATCH/venv with the Python tests' pinned packages (made once)."""
    venv = SCRATCH / "venv"
    if not (venv / "bin" / "python").exists():
        run([sys.executable, "-m", "venv", str(venv)], tree, env)
        run([str(venv / "bin" / "pip"), "install", "-q", "-r", "python/tests/requirements.txt"], tree, env)
    return venv


# The order the suite's binaries run in for a bug, cheapest first: each `cargo test --test B` builds only the library
# and B, so a bug the unit tests catch links no other binary, and one `reference` catches never waits on `gpu`.
ORDER = ["--lib", "--bins", "house", "reference", "formats", "cli", "gpu"]


def test_commands(edits, tree=None, env=None, hinted=()):
    """The commands a bug is run against, in turn until one fails: every test binary, except the viewer's X tests
    (about half the suite's run) where the bug lies outside the viewer. Those compare the window with `render
    --state`, which draws through the same renderer, so a bug in the renderer, a reader or the transfer function
    shows in both alike. A bug in the Python module (python/) is run against its pytest suite, the module built from
    the scratch tree."""
    if all(rel.startswith("python/") for rel, _, _ in edits):
        venv = python_env(tree, env)
        return [["bash", "-c", f"cargo build --profile planted 2>&1 && {venv}/bin/pip install -q ./python 2>&1 && "
                 f"{venv}/bin/python -m pytest -q -rf python/tests 2>&1"]]
    cmd = ["cargo", "test", "--profile", "planted"]
    # Rule 11's bugs: in the MPI code, or a march edit that drops an ownership test (owned()).
    if all(rel.startswith(("src/distributed/", "src/render/part.rs")) for rel, _, _ in edits) or any(
            "owned(" in text and "owned(" not in new for _, text, new in edits):
        return [cmd + ["--features", "mpi", "--test", "mpi"]]
    binaries = sorted(p.parent.name for p in (ROOT / "tests").glob("*/main.rs") if p.parent.name not in ("viewer", "mpi"))
    order = [b for b in ORDER if b.startswith("--") or b in binaries] + [b for b in binaries if b not in ORDER]
    if any(rel.startswith(("src/viewer/", "tests/viewer/")) for rel, _, _ in edits):
        order.append("viewer")
    first = [b for b in hinted if b in order]
    order = first + [b for b in order if b not in first]
    return [cmd + ([b] if b.startswith("--") else ["--test", b]) for b in order]


def hinted_binaries(verdict):
    """The test binaries an earlier verdict names (`caught by `gpu::x``...), as ORDER writes them: a bug is run
    against those first, so that one caught before costs one binary's build and run rather than the suite's."""
    names = re.findall(r"`([A-Za-z0-9_]+)::", verdict)
    seen = []
    for n in names:
        b = {"unittests": "--lib", "src": "--bins"}.get(n, n)
        if b not in seen:
            seen.append(b)
    return seen


def run_until_failure(commands, tree, env, log):
    """Runs `commands` in turn, stopping at the first that fails; the output of all that ran, as one."""
    outs = []
    for cmd in commands:
        out = run(cmd, tree, env)
        outs.append(out)
        if out.returncode != 0:
            break
    log.write_text("".join(o.stdout for o in outs))
    return subprocess.CompletedProcess(commands, outs[-1].returncode, "".join(o.stdout for o in outs))


def failing_tests(output):
    failed, binary = [], "?"
    for line in output.splitlines():
        m = re.match(r"\s*Running (\S+)", line)
        if m:
            # `unittests` for the library's own tests; the folder of tests/KIND/main.rs for the test binaries.
            source = Path(m.group(1))
            binary = source.parent.name if source.name == "main.rs" else source.stem
        m = re.match(r"test (\S+) \.\.\. FAILED", line)
        if m:
            failed.append(f"{binary}::{m.group(1)}")
        m = re.match(r"FAILED python/tests/(\S+)", line)
        if m:
            failed.append(m.group(1).replace(".py::", "::"))
    return failed


def problems(tree, edits):
    """Why `edits` would not apply to `tree`, applied one after another as a run applies them: [] if they do."""
    texts, out = {}, []
    for rel, old, new in edits:
        path = tree / rel
        if rel not in texts:
            if not path.exists():
                out.append(f"{rel}: no such file")
                continue
            texts[rel] = path.read_text()
        n = texts[rel].count(old)
        if n != 1:
            out.append(f"{rel}: the text to change occurs {n} times")
        else:
            texts[rel] = texts[rel].replace(old, new)
    return out


def check(tree):
    """Exit 0 if every bug applies to `tree`; prints each one that does not."""
    bad = [(name, p) for name, _, edits in BUGS for p in problems(tree, edits)]
    for name, p in bad:
        print(f"{name}: does not apply ({p})")
    print(f"{len(BUGS) - len({n for n, _ in bad})} of {len(BUGS)} bugs apply")
    return 1 if bad else 0


def read_record(path, commit):
    """The verdicts already in `path` for `commit`: {bug: (what, verdict)}. A record of another commit is refused."""
    if not path.exists():
        path.write_text(f"# planted bugs run on commit {commit}\n")
        return {}
    lines = path.read_text().splitlines()
    if not lines or lines[0] != f"# planted bugs run on commit {commit}":
        raise SystemExit(f"{path} records a run on another commit ({lines[0] if lines else 'empty'}); "
                         f"pass that commit, or a new file")
    return {n: (w, v) for n, w, v in (line.split("\t") for line in lines[1:] if line)}


def read_hints(path):
    """{bug: verdict} from a record of any commit."""
    rows = (line.split("\t") for line in path.read_text().splitlines()[1:] if line)
    return {r[0]: r[2] for r in rows if len(r) == 3}


def plant(tree, edits):
    """Applies `edits` to `tree`; returns the files' original texts, or raises ValueError (nothing left changed)."""
    originals = {}
    try:
        for rel, old, new in edits:
            path = tree / rel
            originals.setdefault(rel, path.read_text())
            current = path.read_text()
            if current.count(old) != 1:
                raise ValueError(f"{rel}: the text to change occurs {current.count(old)} times")
            path.write_text(current.replace(old, new))
    except ValueError:
        restore(tree, originals)
        raise
    return originals


def restore(tree, originals):
    for rel, text in originals.items():
        (tree / rel).write_text(text)


def verdict_of(out):
    failed = failing_tests(out.stdout)
    if "could not compile" in out.stdout:
        return "does not build (fix the bug's edit)"
    if failed:
        return "caught by " + ", ".join(f"`{t}`" for t in failed)
    if out.returncode != 0:
        return f"run failed without a failing test (exit {out.returncode}; see its log)"
    return "**SURVIVES**"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--list", action="store_true", help="list the bugs and exit")
    ap.add_argument("--only", action="append", default=[], help="run only this bug (repeatable)")
    ap.add_argument("--check", action="store_true",
                    help="check that every bug's texts occur exactly once in the working tree, build nothing")
    ap.add_argument("--commit", default="HEAD", help="the commit to plant the bugs in (default HEAD)")
    ap.add_argument("--hints", type=Path,
                    help="an earlier record (any commit): each bug first runs the binaries that caught it there")
    ap.add_argument("--record", type=Path,
                    help="a TSV that each verdict is appended to as it comes; bugs it already has are skipped")
    args = ap.parse_args()
    if args.list:
        for name, what, _ in BUGS:
            print(f"{name:28} {what}")
        return 0
    if args.check:
        return check(ROOT)
    commit = run(["git", "rev-parse", args.commit], ROOT).stdout.strip()
    done = read_record(args.record, commit) if args.record else {}
    bugs = [b for b in BUGS if (not args.only or b[0] in args.only) and b[0] not in done]
    tree = scratch_copy(commit)
    env = dict(os.environ, CARGO_TARGET_DIR=str(SCRATCH / "target"), CI="true")
    env["VOLCAST_BIN"] = str(SCRATCH / "target" / "planted" / "volcast")
    env.setdefault("XDG_RUNTIME_DIR", str(SCRATCH / "xdg"))
    Path(env["XDG_RUNTIME_DIR"]).mkdir(parents=True, exist_ok=True)
    logs = SCRATCH / "logs"
    logs.mkdir(exist_ok=True)

    print(f"commit {commit}: building the unchanged tree and running its tests once (they must pass)...", flush=True)
    clean = run(["cargo", "test", "--profile", "planted", "--no-fail-fast"], tree, env, logs / "clean.log")
    if clean.returncode != 0:
        print(f"the unchanged tree fails its tests: see {logs / 'clean.log'}", file=sys.stderr)
        return 2

    rows = dict(done)
    hints = read_hints(args.hints) if args.hints else {}
    for name, what, edits in bugs:
        try:
            originals = plant(tree, edits)
        except ValueError as e:
            verdict = f"does not apply ({e})"
        else:
            start = time.time()
            out = run_until_failure(test_commands(edits, tree, env, hinted_binaries(hints.get(name, ""))), tree, env, logs / f"{name}.log")
            restore(tree, originals)
            verdict = verdict_of(out)
            print(f"{name}: {verdict} ({time.time() - start:.0f} s)", flush=True)
        rows[name] = (what, verdict)
        if args.record:
            with open(args.record, "a") as f:
                f.write(f"{name}\t{what}\t{verdict}\n")

    order = [n for n, _, _ in BUGS if n in rows]
    table = f"Planted bugs on commit {commit}\n\n| bug | what it breaks | result |\n|---|---|---|\n"
    table += "".join(f"| `{n}` | {rows[n][0]} | {rows[n][1]} |\n" for n in order)
    report = ROOT / "target" / "planted-bugs.md"
    report.parent.mkdir(exist_ok=True)
    report.write_text(table)
    print("\n" + table)
    print(f"written to {report}; logs in {logs}")
    bad = [n for n in order if not rows[n][1].startswith("caught by")]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
