#!/usr/bin/env bash
# Renders a fixed matrix of images (the gallery's commands, the bench scenes under every ray setup and shading,
# every mode, texture layout, quality and the clipping and slicing options) with one volcast binary into a folder,
# so that a refactoring can be checked bit for bit:
#
#     scripts/image_snapshot.sh target/release/volcast /tmp/before    # on the old commit
#     scripts/image_snapshot.sh target/release/volcast /tmp/after     # on the new one
#     diff -r /tmp/before /tmp/after && echo identical
#
# Needs ../shared/data. About three minutes on 2 cores.
set -euo pipefail
bin=$(realpath "$1")
out=$2
cd "$(dirname "$0")/.."
mkdir -p "$out"
data=../shared/data
ct=$data/raw/cranium_ct_256x256x108_int16.raw
mri=$data/raw/colin27_t1_181x217x181_uint8.raw
brain=$data/native/colin27_t1/ch2.nii.gz
fmri=$data/raw/motor_zmap_53x63x46_float32.raw
ctspacing=(--spacing 0.957031 0.957031 1.5)
r() { local name=$1; shift; "$bin" render --size "${SIZE:-256x256}" "$@" -o "$out/$name.png" >/dev/null 2>"$out/$name.log" \
  || { echo "failed: $name: $*" >&2; cat "$out/$name.log" >&2; exit 1; }; rm -f "$out/$name.log"; }

# The bench scenes (src/measure/bench/scenes.rs) in render's terms, under each ray setup and shading.
declare -A scene=(
  [helix]="--builtin helix"
  [dense]="--builtin colormap --window 0%,100% --step-alpha 0.02"
  [ct-head]="$ct ${ctspacing[*]} --window 33%,90% --colormap plasma --step-alpha 0.6 --azimuth 25 --elevation 10"
  [mri-brain]="$mri --window 20%,100% --colormap grayscale --step-alpha 0.05"
  [vtk-helix]="--builtin helix --colormap viridis --window 8%,100% --multiplied-alpha --step-alpha 0.2 --azimuth 215 --elevation 25"
)
for name in "${!scene[@]}"; do
  for method in faces analytic compute; do
    # shellcheck disable=SC2086
    r "$name-$method" ${scene[$name]} --method $method
    # shellcheck disable=SC2086
    r "$name-$method-shaded" ${scene[$name]} --method $method --shading
  done
  # shellcheck disable=SC2086
  r "$name-shadows" ${scene[$name]} --shadows --ambient-occlusion
  for q in draft fast converged; do
    # shellcheck disable=SC2086
    r "$name-$q" ${scene[$name]} --quality $q
  done
done

# Modes, on the CT and the helix.
for mode in emission mip minip average iso density; do
  r "ct-$mode" "$ct" "${ctspacing[@]}" --mode $mode --preset ct-bone
  r "helix-$mode" --builtin helix --mode $mode --method analytic
done
r ct-iso-shaded "$ct" "${ctspacing[@]}" --mode iso --iso 45% --surface 20%,0.95,0.72,0.62,0.3 --shading
r ct-iso-samples "$ct" "${ctspacing[@]}" --mode iso --iso 45% --gradients samples --shading
r ct-density-shadows "$ct" "${ctspacing[@]}" --mode density --preset ct-bone --density 3 --shadows
r helix-gradient-opacity --builtin helix --gradient-opacity 0.05 --shading
r helix-no-jitter --builtin helix --no-jitter --ortho
r helix-no-skip --builtin helix --no-skip --max-stride 1
r helix-step --builtin helix --step-length 6
r helix-rgba16f --builtin helix --positions rgba16f
r lobb --builtin marschner-lobb --mode iso --shading

# Texture layouts.
for t in native float corners; do
  r "ct-texture-$t" "$ct" "${ctspacing[@]}" --preset ct-soft-tissue --shading --texture $t
  r "mri-texture-$t" "$mri" --window 20%,100% --texture $t --method compute
done

# Clipping, slabs, world space, the gallery.
r ct-clip "$ct" "${ctspacing[@]}" --preset ct-bone --clip-plane 0,1,0,10 --colorbar
r brain-slab "$brain" --mode iso --iso 45% --surface 12%,0.95,0.75,0.65,0.35 --slice z:0.35:0.7 --azimuth 0 \
  --elevation 40 --light -1,1,1 --distance 2.0
r brain-view-left "$brain" --view left --preset auto
r brain-shadows "$brain" --mode iso --iso 35% --shadows --ambient-occlusion
r fmri-mip "$fmri" --spacing 3 3 3 --mode mip --window 55%,100% --colormap plasma --elevation 90
r ct-lung "$ct" "${ctspacing[@]}" --preset ct-lung --azimuth 25 --elevation 10 --distance 1.85
SIZE=512x512 r ct-512 "$ct" "${ctspacing[@]}" --preset ct-bone
echo "$(find "$out" -name '*.png' | wc -l) images in $out"
