"""volcast.view on an array, under its own Xvfb, driven by real X input (xdotool): the window opens with the
array's name, a drag turns the view, and closing its input ends the call cleanly; arrays given as layers show."""

import json
import os
import shutil
import subprocess
import sys
import time

import numpy as np
from PIL import Image as PILImage

from conftest import need

VIEW = """
import numpy as np, volcast
z, y, x = np.mgrid[:40, :48, :56]
a = ((x * 3 + y * 2) % 60 * (z > 8) * (z < 32)).astype(np.uint8)
volcast.view(a, size=(900, 600), script="frames:3;screenshot:before.png;hold;frames:3;screenshot:after.png;exit")
"""


def xdotool(display, *args):
    return subprocess.run(["xdotool", *args], env={**os.environ, "DISPLAY": display}, check=True,
                          capture_output=True, text=True, timeout=60).stdout


def wait_for(path, seconds):
    deadline = time.monotonic() + seconds
    while not path.exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    return path.exists()


def test_the_viewer_shows_an_array_and_answers_a_drag(tmp_path):
    need(shutil.which("Xvfb") is not None and shutil.which("xdotool") is not None, "Xvfb and xdotool")
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "1024x768x24", "-nolisten", "tcp",
                             "-noreset"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    viewer = None
    try:
        display = ":" + xvfb.stdout.readline().strip()
        env = {**os.environ, "DISPLAY": display}
        env.pop("WAYLAND_DISPLAY", None)
        log = open(tmp_path / "viewer.log", "w")
        viewer = subprocess.Popen([sys.executable, "-c", VIEW], cwd=tmp_path, env=env, stdin=subprocess.PIPE,
                                  stdout=log, stderr=log)
        window = xdotool(display, "search", "--sync", "--name", "^array .+ volcast$").split()[0]
        assert wait_for(tmp_path / "before.png", 120), "the viewer drew no first frame"
        xdotool(display, "mousemove", "--window", window, "600", "300", "mousedown", "1")
        for step in range(1, 9):
            xdotool(display, "mousemove", "--window", window, str(600 + 15 * step), "300")
            time.sleep(0.05)
        xdotool(display, "mouseup", "1")
        viewer.stdin.close()  # ends the script's hold
        viewer.wait(timeout=120)
        assert viewer.returncode == 0, (tmp_path / "viewer.log").read_text()
        before = np.asarray(PILImage.open(tmp_path / "before.png").convert("RGB")).astype(int)
        after = np.asarray(PILImage.open(tmp_path / "after.png").convert("RGB")).astype(int)
        assert before.max() > 40, "the array is shown"
        assert np.abs(before - after).mean() > 1, "the drag turned the view"
    finally:
        if viewer is not None and viewer.poll() is None:
            viewer.kill()
        xvfb.terminate()
        xvfb.wait()


def test_the_viewer_opens_again_in_the_same_process(tmp_path):
    need(shutil.which("Xvfb") is not None, "Xvfb")
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "640x480x24", "-nolisten", "tcp", "-noreset"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        env = {**os.environ, "DISPLAY": ":" + xvfb.stdout.readline().strip()}
        code = ("import numpy as np, volcast\na = np.full((16, 16, 16), 200, np.uint8)\n"
                "for k in range(2):\n    volcast.view(a, size=(320, 240), script=f'frames:2;screenshot:v{k}.png;exit')\n")
        out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                             timeout=120, stdin=subprocess.DEVNULL)
        assert out.returncode == 0, out.stderr
        assert (tmp_path / "v0.png").exists() and (tmp_path / "v1.png").exists()
    finally:
        xvfb.terminate()
        xvfb.wait()


def test_the_viewer_shows_arrays_as_layers(tmp_path):
    """``labels=`` and ``overlay=`` take arrays in ``view`` as in ``render``: the frame mixes them (the screenshot's
    view state lists them) and they change the picture."""
    need(shutil.which("Xvfb") is not None, "Xvfb")
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "640x480x24", "-nolisten", "tcp", "-noreset"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        env = {**os.environ, "DISPLAY": ":" + xvfb.stdout.readline().strip()}
        code = ("import numpy as np, volcast\nz, y, x = np.mgrid[:24, :24, :24]\n"
                "a = (120 * ((x - 12) ** 2 + (y - 12) ** 2 + (z - 12) ** 2 < 100)).astype(np.uint8)\n"
                "lab = np.zeros(a.shape, np.uint8)\nlab[4:20, 4:20, 12:20] = 5\n"
                "zmap = np.where(x > 16, 4.0, 0.0).astype(np.float32)\n"
                "volcast.view(a, size=(320, 240), script='frames:3;screenshot:plain.png;exit')\n"
                "volcast.view(a, labels=[lab], overlay=[zmap], threshold=2, size=(320, 240),\n"
                "             script='frames:3;screenshot:layered.png;exit')\n")
        out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                             timeout=180, stdin=subprocess.DEVNULL)
        assert out.returncode == 0, out.stderr
        state = json.loads((tmp_path / "layered.json").read_text())
        layers = state.get("layers", [])
        assert [l["kind"] for l in layers] == ["overlay", "labels"], layers
        plain = np.asarray(PILImage.open(tmp_path / "plain.png").convert("RGB")).astype(int)
        layered = np.asarray(PILImage.open(tmp_path / "layered.png").convert("RGB")).astype(int)
        changed = (np.abs(plain - layered).max(axis=2) > 30).mean()
        assert changed > 0.01, f"the layers change {changed:.2%} of the window"
    finally:
        xvfb.terminate()
        xvfb.wait()
