#!/usr/bin/env python3
"""volcast's quality levels against VTK's fixed-point ray caster on the vtk-helix scene, in one run.

Alternates, round by round, `../shared/tools/vtk_bench.py` (VTK's vtkFixedPointVolumeRayCastMapper at its 1-voxel
default) with `volcast bench --scene vtk-helix` at every quality level, so that both see the same machine load;
and measures VTK's error the way the bench measures volcast's (each against its own converged image, 1/8-voxel
steps: mean and p99 of the largest channel difference over object pixels, in 1/255). Prints a markdown table.

Needs a Python with vtk, numpy and pillow (../shared/tools/README.md, "Set up"), make_volume.py's helix, and a
release build of volcast:

    vtkpeer/bin/python scripts/vtk_peer.py --raw helix_256x256x256_uint8.raw --rounds 3
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VTK_BENCH = os.path.join(ROOT, "..", "shared", "tools", "vtk_bench.py")
QUALITIES = ["draft", "fast", "normal"]


def vtk_run(raw, size, shading, frames, sample_distance=None, png_dir=None):
    """VTK fixed-point median ms per shading variant."""
    cmd = [sys.executable, VTK_BENCH, "--raw", raw, "--dims", "256", "256", "256", "--type", "uint8",
           "--size", str(size), "--mappers", "fixed", "--shading", *shading, "--frames", str(frames),
           "--warmup", "2" if frames > 1 else "0", "--no-baseline"]
    if sample_distance:
        cmd += ["--sample-distance", str(sample_distance)]
    if png_dir:
        cmd += ["--png-dir", png_dir]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return {line.split()[1]: float(line.split()[3]) for line in out.splitlines() if line.startswith("fixed ")}


def error(frame, converged):
    """The bench's fidelity measure (src/measure/image_diff.rs diff_stats) on two PNGs."""
    import numpy as np
    from PIL import Image
    a = np.asarray(Image.open(frame).convert("RGB")).astype(int)
    b = np.asarray(Image.open(converged).convert("RGB")).astype(int)
    e = np.abs(a - b).max(axis=2)
    v = np.sort(e[(a.max(axis=2) > 0) | (b.max(axis=2) > 0)])
    n = len(v)
    return float(v.mean()), int(v[-(-99 * n // 100) - 1])


def volcast_run(binary, raw, size, shading, frames):
    """volcast's GPU median ms, error and step per (shading, quality)."""
    cmd = [binary, "bench", "--scene", "vtk-helix", "--vtk-raw", raw, "--size", str(size), "--method", "faces",
           "--frames", str(frames), "--warmup", "1", "--json"]
    for s in shading:
        cmd += ["--shading", s]
    for q in QUALITIES:
        cmd += ["--quality", q]
    report = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    out = {}
    for r in report["results"]:
        ms = (r["gpu_ms"] or r["wall_ms"])["median"]
        out[(r["shading"], r["quality"])] = (ms, r["error"]["mean"], r["error"]["p99"], r["step_length"])
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--raw", required=True, help="make_volume.py's helix_256x256x256_uint8.raw")
    p.add_argument("--volcast", default=os.path.join(ROOT, "target", "release", "volcast"))
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--shading", nargs="+", default=["off", "on"])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--frames", type=int, default=10)
    a = p.parse_args()
    raw = os.path.abspath(a.raw)
    with tempfile.TemporaryDirectory() as tmp:
        pngs = {sd: os.path.join(tmp, sd) for sd in ("1", "0.125")}
        for sd, d in pngs.items():
            vtk_run(raw, a.size, a.shading, 1, sample_distance=float(sd), png_dir=d)
        vtk_err = {s: error(os.path.join(pngs["1"], f"fixed_{s}_{a.size}.png"),
                            os.path.join(pngs["0.125"], f"fixed_{s}_{a.size}.png")) for s in a.shading}
    vtk_ms, ours = {s: [] for s in a.shading}, {}
    for i in range(a.rounds):
        for s, ms in vtk_run(raw, a.size, a.shading, a.frames).items():
            vtk_ms[s].append(ms)
        for key, value in volcast_run(a.volcast, raw, a.size, a.shading, a.frames // 2).items():
            ours.setdefault(key, []).append(value)
        print(f"# round {i + 1} of {a.rounds} done", file=sys.stderr)
    print(f"vtk-helix at {a.size}², {a.rounds} rounds alternating (median of the rounds' medians, ms; error mean / p99 "
          f"in 1/255 against each renderer's own converged image)\n")
    print("| shading | renderer | step (voxels) | ms | error | VTK ms ÷ this |")
    print("|---|---|---|---|---|---|")
    for s in a.shading:
        vtk = statistics.median(vtk_ms[s])
        print(f"| {s} | VTK fixed-point | 1 | {vtk:.0f} ({min(vtk_ms[s]):.0f}–{max(vtk_ms[s]):.0f}) | "
              f"{vtk_err[s][0]:.2f} / {vtk_err[s][1]} | 1.00 |")
        for q in QUALITIES:
            runs = ours[(s, q)]
            ms = statistics.median(r[0] for r in runs)
            mean, p99, step = runs[-1][1], runs[-1][2], runs[-1][3]
            print(f"| {s} | volcast `{q}` | {step:.2f} | {ms:.0f} ({min(r[0] for r in runs):.0f}–"
                  f"{max(r[0] for r in runs):.0f}) | {mean:.2f} / {p99:.0f} | {vtk / ms:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
