#!/usr/bin/env bash
# One abi3 wheel, several CPythons: builds the wheel once, installs it beside numpy into a fresh virtual environment
# of each interpreter given (default: pyenv's 3.9 and 3.13 where present, and python3), renders the same frames in
# each and prints their hashes, which must agree. Usage: bash scripts/python_versions.sh [PYTHON...]
set -euo pipefail
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
pythons=("$@")
if [ ${#pythons[@]} -eq 0 ]; then
  for p in "$HOME"/.pyenv/versions/3.9*/bin/python "$HOME"/.pyenv/versions/3.13*/bin/python; do
    [ -x "$p" ] && pythons+=("$p")
  done
  pythons+=(python3)
fi
python3 -m pip wheel -q --no-deps ./python -w "$work/wheels"
cat > "$work/smoke.py" <<'PY'
import hashlib, sys
import numpy as np
import volcast
a = (np.arange(20 * 24 * 28) % 251).astype(np.uint8).reshape(20, 24, 28)
f = volcast.render(a, size=48, azimuth=20, shading=True)
g = volcast.render(volcast.Volume.from_array(a.astype(np.int16) - 100, spacing=(1, 1, 2)), size=40, mode="mip")
digest = hashlib.sha1(f.tobytes() + g.tobytes()).hexdigest()[:16]
print(f"CPython {sys.version.split()[0]}, numpy {np.__version__}: frames {digest}")
PY
for p in "${pythons[@]}"; do
  "$p" -m venv "$work/venv" --clear
  "$work/venv/bin/pip" install -q --disable-pip-version-check "$work"/wheels/volcast-*.whl
  "$work/venv/bin/python" "$work/smoke.py"
done
