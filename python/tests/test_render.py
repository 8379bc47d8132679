"""volcast.render against `volcast render`: the same voxels and options give the same bytes."""

import subprocess

import numpy as np
import pytest
from PIL import Image as PILImage

import volcast


def field(shape, dtype, seed=1):
    """A smooth blob with noise, in `dtype`'s range."""
    z, y, x = np.meshgrid(*[np.linspace(-1, 1, n) for n in shape], indexing="ij")
    f = np.exp(-3 * (x * x + 1.5 * y * y + 2 * z * z)) + 0.05 * np.random.default_rng(seed).random(shape)
    if np.dtype(dtype).kind == "f":
        return (f * 100 - 20).astype(dtype)
    info = np.iinfo(dtype)
    return (info.min + f / f.max() * (int(info.max) - int(info.min))).astype(dtype)


def cli_render(cli, tmp_path, array, argv):
    z, y, x = array.shape
    raw = tmp_path / f"vol_{x}x{y}x{z}_{array.dtype.name}.raw"
    array.astype(array.dtype.newbyteorder("<")).tofile(raw)
    out = tmp_path / "cli.png"
    subprocess.run([cli, "render", str(raw), "-o", str(out), *argv], check=True, capture_output=True)
    return np.asarray(PILImage.open(out).convert("RGBA"))


CASES = [
    ("uint8", {}, []),
    ("int16", {"mode": "mip", "size": (96, 64)}, ["--mode", "mip", "--size", "96x64"]),
    ("float32", {"shading": True, "azimuth": -40.0, "window": ("20%", "90%")},
     ["--shading", "--azimuth=-40", "--window", "20%,90%"]),
    ("uint16", {"preset": "mr-default", "clip_plane": (0, 0.6, 0.8, 0.1), "quality": "draft"},
     ["--preset", "mr-default", "--clip-plane", "0,0.6,0.8,0.1", "--quality", "draft"]),
    ("float64", {"mode": "iso", "iso": "40%", "method": "analytic"}, ["--mode", "iso", "--iso", "40%", "--method", "analytic"]),
]


@pytest.mark.parametrize("dtype,options,argv", CASES, ids=[c[0] for c in CASES])
def test_an_array_renders_as_its_raw_file_does(cli, tmp_path, dtype, options, argv):
    array = field((20, 28, 36), dtype)
    ours = volcast.render(array, size=options.pop("size", (64, 64)), **options)
    theirs = cli_render(cli, tmp_path, array, argv if "--size" in argv else argv + ["--size", "64x64"])
    assert ours.shape == theirs.shape and ours.dtype == np.uint8
    assert np.array_equal(np.asarray(ours), theirs), f"{np.count_nonzero(ours != theirs)} bytes differ"


def test_a_volume_rendered_again_gives_the_same_frame():
    v = volcast.Volume.from_array(field((24, 24, 24), "uint8"))
    first = volcast.render(v, size=48)
    assert np.array_equal(volcast.render(v, size=48), first)
    assert volcast.render(v, size=48, azimuth=120).tobytes() != first.tobytes()


def test_output_writes_the_png_too(tmp_path):
    out = tmp_path / "frame.png"
    frame = volcast.render(builtin="helix", builtin_size=32, size=40, output=out)
    assert np.array_equal(np.asarray(PILImage.open(out).convert("RGBA")), frame)


def test_a_transfer_function_object_equals_its_file(tmp_path):
    tf = volcast.TransferFunction(opacity=[(0.2, 0), (0.6, 0.3), (1, 0.8)], colors=[(0, 0, 0, 1), (1, 1, 0.5, 0)])
    path = tmp_path / "tf.json"
    tf.save(path)
    a = field((16, 16, 16), "uint8")
    assert np.array_equal(volcast.render(a, size=32, tf=tf), volcast.render(a, size=32, tf=str(path)))
    assert volcast.TransferFunction.load(path) == tf
    assert volcast.TransferFunction.preset("ct-bone").units == "data"


def test_a_frame_shows_itself_in_jupyter():
    frame = volcast.render(builtin="box", builtin_size=16, size=24)
    png = frame._repr_png_()
    assert png.startswith(b"\x89PNG")
    import io

    assert np.array_equal(np.asarray(PILImage.open(io.BytesIO(png)).convert("RGBA")), frame)
    scene = volcast.Scene(field((16, 16, 16), "uint8"), size=24)
    assert scene._repr_png_().startswith(b"\x89PNG")


def test_a_builtin_volume_renders_as_the_builtin_option():
    v = volcast.builtin("helix", 32)
    assert np.array_equal(volcast.render(v, size=40), volcast.render(builtin="helix", builtin_size=32, size=40))


def test_the_widget_renders_as_its_sliders_move():
    pytest.importorskip("ipywidgets")
    box = volcast.widget(field((20, 20, 20), "uint8"), size=32)
    picture, azimuth, window = box.children
    first = picture.value
    assert bytes(first).startswith(b"\x89PNG")
    azimuth.value = 90.0
    assert picture.value != first
    second = picture.value
    window.value = (60.0, 100.0)
    assert picture.value != second
