#!/usr/bin/env bash
# Peak memory, bytes read and bytes sent per rank of `mpirun -n N volcast render` for N = 1, 2, 4, 8, on a generated
# 512 x 512 x 384 uint16 volume (192 MiB), beside the single-process render: the table in docs/distributed.md.
#   PYTHON=.venv-tests/bin/python bash scripts/mpi_scale.sh     # needs numpy; the binary built with --features mpi
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/volcast
vol=${TMPDIR:-/tmp}/shells_512x512x384_uint16.raw
${PYTHON:-python3} - "$vol" <<'PY'
import sys, numpy as np
z, y, x = np.mgrid[0:384, 0:512, 0:512].astype(np.float32)
r = np.sqrt(((z - 192) / 180) ** 2 + ((y - 256) / 240) ** 2 + ((x - 256) / 240) ** 2)
blobs = (np.sin(x / 9) * np.sin(y / 11) * np.sin(z / 7) > 0.3) * (r < 1)
(np.clip(1 - r, 0, 1) * 40000 + 8000 * blobs).astype(np.uint16).tofile(sys.argv[1])
PY
view=(--size 512x512 --azimuth 30 --elevation 20 --texture "${TEXTURE:-float}")
lscpu | grep "Model name"
/usr/bin/time -f "one process (no mpirun): peak RSS %M KiB, wall %e s" "$bin" render "$vol" "${view[@]}" -o /tmp/mpi-scale-1.png
for n in 1 2 4 8; do
  echo "== mpirun -n $n"
  /usr/bin/time -f "wall %e s" mpirun --oversubscribe --allow-run-as-root -n "$n" -x LP_NUM_THREADS=1 \
    "$bin" render "$vol" "${view[@]}" --memory -o "/tmp/mpi-scale-$n-ranks.png" | grep -v "^gpu\|^rendered"
done
# The runtime alone: a part of about 2 MiB on 8 ranks (the CT head's 4 MiB at 64^2 would do as well).
mpirun --oversubscribe --allow-run-as-root -n 8 -x LP_NUM_THREADS=1 "$bin" render --builtin box --builtin-size 64 \
  --size 64x64 --texture "${TEXTURE:-float}" --memory -o /tmp/mpi-scale-base.png | grep -E "^ +0 "
rm -f "$vol"
