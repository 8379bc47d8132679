"""Every option of `volcast render` is a keyword of volcast.render: the walk below fails for an option that has no
sample here, and renders each sample (a rejected value would raise)."""

import json

import numpy as np
import pytest

import volcast

# A value for every option of `volcast render`, as a Python user passes it. None: not a rendering option here,
# with the reason (the test still checks that the keyword exists).
SAMPLES = {
    "builtin": "box", "builtin_size": 20, "dims": None, "type": None, "spacing": (1, 1, 2), "endian": None,
    "header_bytes": None, "max_dim": 16, "host_budget": "512M", "gpu_budget": "256M", "cache_dir": "CACHE",
    "no_cache": True, "no_downsample": True, "array": None, "series": None, "channel": None, "time": 0,
    "validate": None, "device": "0", "texture": "float", "brick_size": 8,
    "size": (24, 16), "azimuth": -30, "elevation": 10, "distance": 2.5, "eye": (1, -2, 1), "look_at": (0, 0, 0.1),
    "view_dir": (0, 1, 0), "view": "left", "voxel_axes": True, "fov": 40, "colormap": "viridis", "window": ("10%", "80%"),
    "preset": "qt-example", "tf": "TF", "save_tf": "SAVE", "mode": "average", "iso": 0.3, "iso_color": (1, 0.5, 0),
    "iso_opacity": 0.7, "surface": [(0.2, 0.9, 0.6, 0.5, 0.3)], "light": (1, 1, 0), "light_color": (1, 0.9, 0.8),
    "light_intensity": 1.2, "shadows": True, "ambient_occlusion": True, "density": 2, "shading": True,
    "lighting": (0.3, 0.6, 0.2, 10), "gradient_opacity": 0.05, "shading_fade": 0.05, "no_jitter": True,
    "jitter_seed": 3, "ortho": True, "no_skip": True, "max_stride": 2, "ray_spacing": 2, "gradients": "samples",
    "gradient_texture": True, "step_alpha": 0.05, "quality": "fast", "step_length": 0.7, "multiplied_alpha": True,
    "early_termination": 0.9, "background": (0.1, 0.1, 0.2), "slice": ("x", 0.5, 0.4), "clip_plane": (0, 0, 1, 0),
    "positions": "rgba16f", "output": "OUT", "method": "compute", "timings": True, "memory": True, "colorbar": True,
    "scale_bar": True, "overlay": ["OVERLAY"], "threshold": 0.5, "overlay_opacity": 0.4,
    "overlay_colormap": "viridis", "overlay_blend": "add", "labels": ["LABELS"], "label_table": "TABLE", "label_ids": [1],
    "label_opacity": 0.3, "channels": "all",
    "frames": 2, "state": None, "level": 0, "turntable": None, "keyframes": None, "fps": None,
}
# Read-a-file options (the walk's volume is built in) and the state file: test_the_file_options_apply_to_a_path;
# the movie's options: test_the_movie_options_are_keywords.
NOT_HERE = {"dims", "type", "endian", "header_bytes", "array", "series", "channel", "channels", "validate", "state",
            "turntable", "keyframes", "fps"}
# Options that conflict with another sample, rendered in a call of their own.
ALONE = {"eye", "view_dir", "view", "preset", "tf", "save_tf", "gradient_texture", "max_dim", "no_downsample",
         "elevation", "azimuth", "distance", "time", "level"}


def test_every_render_option_has_a_sample():
    listed = set(volcast.options("render"))
    assert listed - set(SAMPLES) == set(), "options without a sample: add them to SAMPLES"
    assert set(SAMPLES) - listed == set(), "samples of options volcast render no longer has"


def value(name, tmp_path):
    v = SAMPLES[name]
    if v == "CACHE":
        return str(tmp_path / "cache")
    if v == "TF":
        path = tmp_path / "tf.json"
        path.write_text(volcast.TransferFunction.preset("qt-example").to_json())
        return str(path)
    if v == ["OVERLAY"]:
        path = tmp_path / "ov_8x8x8_float32.raw"
        np.linspace(-1, 1, 512, dtype=np.float32).tofile(path)
        return [str(path)]
    if v == ["LABELS"]:
        path = tmp_path / "lab_8x8x8_uint8.raw"
        (np.arange(512) % 3).astype(np.uint8).tofile(path)
        return [str(path)]
    if v == "TABLE":
        path = tmp_path / "lab.ctbl"
        path.write_text("1 one 255 0 0 255\n2 two 0 255 0 255\n")
        return str(path)
    if v in ("SAVE", "OUT"):
        return str(tmp_path / ("saved.json" if v == "SAVE" else "out.png"))
    return v


@pytest.mark.parametrize("name", sorted(n for n in SAMPLES if n not in NOT_HERE))
def test_each_option_renders(name, tmp_path):
    base = {"builtin": "helix", "builtin_size": 20, "size": 16}
    options = {**base, name: value(name, tmp_path)}
    if name == "save_tf":
        options["preset"] = "qt-example"  # a built-in is shown with the colormap model, which has no function
    if name not in ALONE and name not in base:
        # With a second option too, so that combining keywords is walked as well.
        options["mode"] = options.get("mode", "emission")
    frame = volcast.render(**options)
    assert frame.ndim == 3 and frame.shape[2] == 4
    if name == "save_tf":
        assert json.loads((tmp_path / "saved.json").read_text())["opacity"]
    if name == "output":
        assert (tmp_path / "out.png").stat().st_size > 0
    if name == "timings":
        assert frame.timings["wall_ms"] > 0 and frame.timings["march_ms"] > 0
    if name == "memory":
        assert "MiB" in frame.memory or "MB" in frame.memory, frame.memory


def test_the_movie_options_are_keywords(tmp_path):
    for name in ("turntable", "keyframes", "fps"):
        assert name in volcast.options("render")
    gif = volcast.movie(builtin="helix", builtin_size=20, output=tmp_path / "spin.png", turntable=3, fps=5, size=16)
    assert gif.exists() and len(list(tmp_path.glob("spin-*.png"))) == 3


def test_values_follow_the_command_lines_forms():
    from volcast._options import argv

    assert argv("render", {"size": 300}) == ["--size=300x300"]
    assert argv("render", {"size": (640, 480), "shadows": True, "ortho": False}) == ["--size=640x480", "--shadows"]
    assert argv("render", {"slice": [("x", 0.5, 0.2), "y:0.5:0.1"]}) == ["--slice=x:0.5:0.2", "--slice=y:0.5:0.1"]
    assert argv("render", {"clip_plane": np.array([0.0, 0.0, 1.0])}) == ["--clip-plane=0.0,0.0,1.0"]
    with pytest.raises(TypeError):
        argv("render", {"shadows": "yes"})


def test_a_keyframed_movie_of_dicts_passes_through_its_keys(tmp_path):
    a = np.random.default_rng(8).integers(0, 255, (20, 24, 28), dtype=np.uint8)
    keys = [{"azimuth": 0}, {"azimuth": 90, "window": ("30%", "100%")}, {"azimuth": 180}]
    gif = volcast.movie(a, tmp_path / "path.png", keyframes=keys, frames=5, size=32, preset="qt-example")
    assert gif == tmp_path / "path.gif" and gif.exists()
    from PIL import Image as PILImage

    frames = [np.asarray(PILImage.open(tmp_path / f"path-{k:04}.png").convert("RGBA")) for k in range(5)]
    # Frames 0, 2 and 4 are the keys exactly; the states hold the options given beside them.
    for k, key in zip((0, 2, 4), keys):
        assert np.array_equal(frames[k], volcast.render(a, size=32, preset="qt-example", **key)), k
    state = json.loads(volcast.view_state(a, azimuth=90, size=32))
    assert state["width"] == 32 and state["volume"]["path"] is None


def test_camera_spreads_into_its_options():
    a = np.random.default_rng(9).integers(0, 255, (16, 16, 16), dtype=np.uint8)
    assert np.array_equal(
        volcast.render(a, size=24, camera={"azimuth": 40, "elevation": -10}),
        volcast.render(a, size=24, azimuth=40, elevation=-10),
    )
    with pytest.raises(TypeError):
        volcast.render(a, camera={"azimuth": 1}, azimuth=2)


def test_the_file_options_apply_to_a_path(tmp_path, data):
    """The walk's NOT_HERE options, on sources they apply to (series and channel share the parser and the reading
    with the command line, whose tests/cli/series.rs and zarr.rs exercise them)."""
    voxels = np.random.default_rng(11).integers(-900, 900, (10, 12, 14)).astype(">i2")
    raw = tmp_path / "scan.bin"
    raw.write_bytes(b"H" * 16 + voxels.tobytes())
    ours = volcast.render(raw, dims=(14, 12, 10), type="int16", endian="big", header_bytes=16, size=24)
    little = volcast.Volume.from_array(voxels.astype("<i2"))
    assert np.array_equal(ours, volcast.render(little, size=24))
    multi = data / "vtk" / "legacy_multi_binary.vtk"
    assert not np.array_equal(volcast.render(multi, size=24), volcast.render(multi, array="density", size=24))
    store = data / "zarr" / "napari_czyx.zarr"
    assert not np.array_equal(volcast.render(store, size=24), volcast.render(store, channels="all", size=24))
    state = tmp_path / "state.json"
    state.write_text(volcast.view_state(little, azimuth=70, size=24, mode="mip"))
    assert np.array_equal(volcast.render(little, state=state), volcast.render(little, azimuth=70, size=24, mode="mip"))
    assert volcast.render(little, size=24, validate=True).shape == (24, 24, 4)
