#!/usr/bin/env bash
# Renders the README's gallery into docs/gallery/ with the commands the README lists (needs ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
v="cargo run --release -q -- render"
ct=../shared/data/raw/cranium_ct_256x256x108_int16.raw
common=(--spacing 0.957031 0.957031 1.5 --azimuth 25 --elevation 10 --size 220x220)
out=docs/gallery
$v "$ct" "${common[@]}" --preset ct-bone --shading -o $out/ct-bone-shaded.png
$v "$ct" "${common[@]}" --preset ct-soft-tissue --shading -o $out/ct-soft-tissue-shaded.png
$v "$ct" "${common[@]}" --preset ct-lung -o $out/ct-lung.png
$v "$ct" "${common[@]}" --preset qt-example -o $out/qt-example.png
$v "$ct" "${common[@]}" --mode mip --window 0.3,1 --colormap grayscale -o $out/ct-mip.png
$v "$ct" "${common[@]}" --mode iso --iso 0.33 --colormap grayscale --window 0,1 -o $out/ct-iso.png
$v "$ct" "${common[@]}" --mode density --preset ct-bone --density 3 -o $out/ct-density.png
$v ../shared/data/raw/motor_zmap_53x63x46_float32.raw --spacing 3 3 3 --mode mip --window 0.55,1 \
  --colormap plasma --elevation 90 --size 220x220 -o $out/fmri-mip.png
