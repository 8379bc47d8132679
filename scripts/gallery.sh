#!/usr/bin/env bash
# Renders the gallery of docs/rendering.md into docs/gallery/ with the commands it lists (needs ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
v="target/release/volcast render"
ct=../shared/data/raw/cranium_ct_256x256x108_int16.raw
brain=../shared/data/native/colin27_t1/ch2.nii.gz
common=(--spacing 0.957031 0.957031 1.5 --azimuth 25 --elevation 10 --distance 1.85 --size 256x256)
out=docs/gallery
mkdir -p $out
# Lighting (docs/rendering.md, Lighting): shadows and ambient occlusion, layered iso-surfaces, the terracing fix.
$v "$ct" "${common[@]}" --preset ct-bone --shadows --ambient-occlusion -o $out/ct-bone-shadows-ao.png
$v "$ct" "${common[@]}" --preset ct-bone --shading -o $out/ct-bone-shaded.png
$v "$ct" "${common[@]}" --mode iso --iso 45% --surface 20%,0.95,0.72,0.62,0.3 --shadows --ambient-occlusion \
  -o $out/ct-skin-over-bone.png
$v "$brain" --mode iso --iso 45% --surface 12%,0.95,0.75,0.65,0.35 --slice z:0.35:0.7 --azimuth 0 \
  --elevation 40 --light -1,1,1 --distance 2.0 --size 256x256 -o $out/brain-skin-over-cortex.png
$v "$brain" --mode iso --iso 35% --gradients samples --distance 2.0 --size 256x256 -o $out/brain-iso-central-differences.png
$v "$brain" --mode iso --iso 35% --distance 2.0 --size 256x256 -o $out/brain-iso-filtered.png
# Transfer functions and modes.
$v "$ct" "${common[@]}" --preset ct-soft-tissue --shading -o $out/ct-soft-tissue-shaded.png
$v "$ct" "${common[@]}" --preset ct-lung -o $out/ct-lung.png
$v "$ct" "${common[@]}" --mode mip --window 30%,100% --colormap grayscale -o $out/ct-mip.png
$v "$ct" "${common[@]}" --mode density --preset ct-bone --density 3 -o $out/ct-density.png
$v ../shared/data/raw/motor_zmap_53x63x46_float32.raw --spacing 3 3 3 --mode mip --window 55%,100% \
  --colormap plasma --elevation 90 --size 256x256 -o $out/fmri-mip.png
# Layers (docs/layers.md): the T1 with the motor z-map at |z| >= 3 and the AAL precentral and postcentral gyri.
$v "$brain" --overlay ../shared/data/native/motor_zmap/image_10426.nii.gz --threshold 3 \
  --labels ../shared/data/native/aal_labels/aal.nii.gz --label-ids 1,2,57,58 --view superior \
  --clip-plane 0,0,-1,-38 --size 400x400 -o $out/layers-t1-zmap-aal.png
# What each shared volume opens with, no options given (docs/rendering.md, Auto): one strip of five.
d=../shared/data/native
defaults=("$d/colin27_t1/ch2.nii.gz" "$d/brain_pd_mr" "$ct --spacing 0.957031 0.957031 1.5" \
  "$d/motor_zmap/image_10426.nii.gz" "$d/dwi_b0_ascm/ascm_out_test.nii.gz")
tiles=()
for i in "${!defaults[@]}"; do
  # shellcheck disable=SC2086 # the CT's entry carries its spacing as separate words
  $v ${defaults[$i]} --size 200x200 -o "$out/default-$i.png"
  tiles+=("$out/default-$i.png")
done
"${VOLCAST_TEST_PYTHON:-.venv-tests/bin/python}" - "$out/defaults.png" "${tiles[@]}" <<'PY'
import sys
from PIL import Image
tiles = [Image.open(p).convert("RGB") for p in sys.argv[2:]]
strip = Image.new("RGB", (sum(t.width for t in tiles), tiles[0].height))
for i, t in enumerate(tiles):
    strip.paste(t, (i * t.width, 0))
strip.save(sys.argv[1], optimize=True)
PY
rm -f "${tiles[@]}"
