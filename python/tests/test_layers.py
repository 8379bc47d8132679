"""Layers from Python (docs/layers.md): overlay= and labels= take paths and arrays alike, and an array layer gives
the bytes that `volcast render --overlay`/`--labels` gives for the same voxels in a file."""

import json
import subprocess

import numpy as np
from PIL import Image as PILImage

import volcast


def ball(shape, centre, radius):
    z, y, x = np.meshgrid(*[np.arange(n, dtype=np.float32) for n in shape], indexing="ij")
    r = np.sqrt((x - centre[2]) ** 2 + (y - centre[1]) ** 2 + (z - centre[0]) ** 2)
    return np.clip(radius + 1 - r, 0, 1).astype(np.float32)


def raw(tmp_path, name, array):
    z, y, x = array.shape
    path = tmp_path / f"{name}_{x}x{y}x{z}_{array.dtype.name}.raw"
    array.tofile(path)
    return path


def test_array_layers_match_the_command_line(tmp_path, cli):
    base = ball((24, 24, 24), (12, 12, 12), 9) * 0.3
    overlay = ball((24, 24, 24), (12, 8, 14), 4) * 5.0
    labels = (ball((24, 24, 24), (10, 16, 10), 3) > 0.5).astype(np.uint8) * 7
    options = dict(size=(64, 48), threshold=1.0)
    frame = volcast.render(base, overlay=[overlay], labels=[labels], **options)
    base_path, ov, lab = raw(tmp_path, "base", base), raw(tmp_path, "ov", overlay), raw(tmp_path, "lab", labels)
    out = tmp_path / "cli.png"
    argv = [cli, "render", str(base_path), "--overlay", str(ov), "--labels", str(lab), "--size", "64x48",
            "--threshold", "1", "-o", str(out)]
    subprocess.run(argv, check=True, capture_output=True)
    expected = np.asarray(PILImage.open(out).convert("RGBA"))
    assert np.array_equal(np.asarray(frame), expected)
    # The layers show: the base alone differs.
    assert not np.array_equal(np.asarray(volcast.render(base, **options)), expected)
    # A path and an array are the same layer.
    by_path = volcast.render(base, overlay=[str(ov)], labels=[labels], **options)
    assert np.array_equal(np.asarray(by_path), expected)


def test_a_movie_shows_array_layers(tmp_path):
    base = ball((24, 24, 24), (12, 12, 12), 9) * 0.3
    overlay = ball((24, 24, 24), (12, 8, 14), 4) * 5.0
    labels = (ball((24, 24, 24), (10, 16, 10), 3) > 0.5).astype(np.uint8) * 7
    options = dict(size=(64, 48), threshold=1.0)
    layers = dict(overlay=[overlay], labels=[labels])
    gif = volcast.movie(base, tmp_path / "spin.png", turntable=2, **layers, **options)
    assert gif.name == "spin.gif"
    first = np.asarray(PILImage.open(tmp_path / "spin-0000.png").convert("RGBA"))
    # The movie's first frame is the still with the same layers, not the base alone.
    assert np.array_equal(first, np.asarray(volcast.render(base, **layers, **options)))
    assert not np.array_equal(first, np.asarray(volcast.render(base, **options)))


def test_a_saved_view_keeps_its_layers(tmp_path, cli):
    """A view state records its layers' files and looks: `render --state` shows them again, in Python and on the
    command line, and a layer given beside the state replaces them."""
    base = ball((24, 24, 24), (12, 12, 12), 9) * 0.3
    overlay = ball((24, 24, 24), (12, 8, 14), 4) * 5.0
    base_path, ov = raw(tmp_path, "base", base), raw(tmp_path, "ov", overlay)
    options = dict(size=(64, 48), threshold=1.0, overlay_opacity=0.9, overlay_colormap="viridis")
    state = tmp_path / "view.json"
    state.write_text(volcast.view_state(base, overlay=[str(ov)], **options))
    saved = json.loads(state.read_text())
    assert saved["layer_files"]["overlays"] == [str(ov.resolve())]
    assert saved["layers"][0]["colormap"] == "viridis" and saved["layers"][0]["threshold"] == 1.0
    expected = np.asarray(volcast.render(base, overlay=[str(ov)], **options))
    assert np.array_equal(np.asarray(volcast.render(base, state=state)), expected)
    out = tmp_path / "cli.png"
    subprocess.run([cli, "render", str(base_path), "--state", str(state), "-o", str(out)], check=True,
                   capture_output=True)
    assert np.array_equal(np.asarray(PILImage.open(out).convert("RGBA")), expected)
    # Another overlay beside the state replaces the saved one, with its own look.
    other = raw(tmp_path, "other", ball((24, 24, 24), (8, 14, 10), 4) * 5.0)
    replaced = np.asarray(volcast.render(base, state=state, overlay=[str(other)]))
    assert np.array_equal(replaced, np.asarray(volcast.render(base, overlay=[str(other)], size=(64, 48))))
