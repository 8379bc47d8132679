#!/usr/bin/env python3
"""What volcast.render costs over `volcast render`'s own frame time, both measured in one run, alternating.

`volcast render --timings --frames N` reports the median wall time of N frames after its first (the frame drawn,
read back and turned into an image); the Python side times `volcast.render(volume, ...)` of a Volume already
placed, from the call to the numpy array in hand. Usage: python scripts/python_overhead.py [VOLCAST_BIN]
(the `volcast` module installed: pip install ./python).
"""

import platform
import re
import statistics
import subprocess
import sys
import time

import volcast

BIN = sys.argv[1] if len(sys.argv) > 1 else "target/release/volcast"
SCENES = [
    ("helix 256³, 512²", ["--builtin", "helix", "--size", "512x512"], dict(builtin="helix", size=512)),
    ("helix 256³, 1024² shaded", ["--builtin", "helix", "--size", "1024x1024", "--shading"],
     dict(builtin="helix", size=1024, shading=True)),
]
FRAMES, ROUNDS = 10, 3


def cli_ms(argv):
    out = subprocess.run([BIN, "render", *argv, "--timings", "--frames", str(FRAMES), "-o", "/tmp/overhead.png"],
                         check=True, capture_output=True, text=True).stdout
    return float(re.search(r"median of \d+ frames: ([0-9.]+) ms wall", out).group(1))


def python_ms(volume, options):
    volcast.render(volume, **options)
    times = []
    for _ in range(FRAMES):
        t = time.perf_counter()
        volcast.render(volume, **options)
        times.append((time.perf_counter() - t) * 1e3)
    return statistics.median(times)


def cpu():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        return re.search(r"Model name:\s*(.*)", out).group(1).strip()
    except Exception:  # noqa: BLE001 - a label only
        return platform.processor()


print(f"machine: {cpu()}; device: {volcast.device()}")
print("| scene | volcast render (ms) | volcast.render (ms) | Python / CLI |")
print("|---|---|---|---|")
for name, argv, options in SCENES:
    builtin = options.pop("builtin")
    volume = volcast.builtin(builtin)
    pairs = [(cli_ms(argv), python_ms(volume, options)) for _ in range(ROUNDS)]
    c = statistics.median(p[0] for p in pairs)
    p = statistics.median(p[1] for p in pairs)
    print(f"| {name} | {c:.1f} | {p:.1f} | {p / c:.3f} |")
