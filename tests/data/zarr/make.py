"""Makes the OME-Zarr oracle stores in this folder and an expected.json per store, read back with ome-zarr-py.

Run with the pinned environment (`bash .ci/python-env`; zarr 3.1.6, ome-zarr 0.18.0, numpy 2.4.6):
    .venv-tests/bin/python tests/data/zarr/make.py
The stores are deterministic (fixed arrays); expected.json holds what the tools read: per level the shape and the
voxel-to-world affine (x = last space axis, millimetres) from the coordinateTransformations ome-zarr-py reports,
the dtype, some voxel values, and the omero channels.
"""
import json
import pathlib
import shutil

import numcodecs
import numpy as np
import zarr
from ome_zarr.format import FormatV04, FormatV05
from ome_zarr.io import parse_url
from ome_zarr.reader import Reader
from ome_zarr.writer import write_image

HERE = pathlib.Path(__file__).resolve().parent
TO_MM = {"micrometer": 1e-3, "nanometer": 1e-6, "millimeter": 1.0, "meter": 1e3, "angstrom": 1e-7, None: 1.0}


def fresh(name):
    path = HERE / name
    if path.exists():
        shutil.rmtree(path)
    return path


def ramp(shape, dtype):
    n = int(np.prod(shape))
    values = (np.arange(n) * 7 + 3) % 251
    if np.dtype(dtype).kind == "i":
        values = values - 100
    if np.dtype(dtype).kind == "f":
        values = values * 0.5 - 20.25
    return values.astype(dtype).reshape(shape)


def affine(axes, transforms):
    """The volcast-style affine of one level from the transforms ome-zarr-py reports."""
    n = len(axes)
    scale, shift = [1.0] * n, [0.0] * n
    for t in transforms:
        if t["type"] == "scale":
            scale = [a * b for a, b in zip(scale, t["scale"])]
            shift = [a * b for a, b in zip(shift, t["scale"])]
        elif t["type"] == "translation":
            shift = [a + b for a, b in zip(shift, t["translation"])]
    space = [i for i, a in enumerate(axes) if a.get("type") == "space"]
    mm = [TO_MM[axes[i].get("unit")] if i in space else 1.0 for i in range(n)]
    cols = list(reversed(space))  # x, y, z
    rows = [[0.0] * 4 for _ in range(4)]
    rows[3][3] = 1.0
    for k, i in enumerate(cols):
        rows[k][k] = scale[i] * mm[i]
        rows[k][3] = shift[i] * mm[i]
    if len(space) == 2:
        rows[2][2] = min(abs(rows[0][0]), abs(rows[1][1]))
    return rows


def expect(path, samples):
    """Reads the store back with ome-zarr-py and writes expected.json."""
    node = next(iter(Reader(parse_url(str(path)))()))
    meta = node.metadata
    axes = meta["axes"]
    names = [a["name"] for a in axes]
    levels = []
    for data, cts in zip(node.data, meta["coordinateTransformations"]):
        levels.append({"shape": list(data.shape), "affine": affine(axes, cts)})
    level0 = np.asarray(node.data[0])
    values = []
    for s in samples:
        index = tuple(s.get(n, 0) for n in names)
        values.append(dict(s, value=float(level0[index])))
    channels = []
    omero = node.zarr.root_attrs.get("omero") or node.zarr.root_attrs.get("ome", {}).get("omero")
    for i, c in enumerate((omero or {}).get("channels", [])):
        channels.append({"name": c.get("label", f"channel {i}"), "window": [c["window"]["start"], c["window"]["end"]],
                         "color": c["color"]})
    out = {"axes": names, "dtype": str(level0.dtype), "levels": levels, "values": values, "channels": channels}
    (path / "expected.json").write_text(json.dumps(out) + "\n")


def ome_zarr_v04_blosc():
    path = fresh("v04_blosc.zarr")
    image = ramp((8, 12, 16), "uint16")
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    # ome-zarr-py writes each level's scale and the half-voxel translation of its coarser voxel centres.
    write_image(image, group, fmt=FormatV04(), axes=["z", "y", "x"],
                scale_factors=[{"z": 2, "y": 2, "x": 2}, {"z": 4, "y": 4, "x": 4}], method="nearest",
                scale={"z": 2.0, "y": 0.5, "x": 0.25},
                axes_units={"z": "micrometer", "y": "micrometer", "x": "micrometer"},
                storage_options={"chunks": (4, 4, 8), "compressor": numcodecs.Blosc(cname="lz4", clevel=5)})
    expect(path, [{"z": 0, "y": 0, "x": 0}, {"z": 7, "y": 11, "x": 15}, {"z": 3, "y": 5, "x": 9}])


def ome_zarr_v05():
    path = fresh("v05.zarr")
    image = ramp((6, 10, 12), "float32")
    write_image(image, str(path), fmt=FormatV05(), axes=["z", "y", "x"],
                scale_factors=[{"z": 2, "y": 2, "x": 2}], method="nearest",
                scale={"z": 400.0, "y": 250.0, "x": 125.0},
                axes_units={"z": "nanometer", "y": "nanometer", "x": "nanometer"},
                storage_options={"chunks": (3, 5, 6)})
    expect(path, [{"z": 0, "y": 0, "x": 0}, {"z": 5, "y": 9, "x": 11}, {"z": 2, "y": 4, "x": 7}])


def sharded_tczyx():
    """zarr-python 3: sharded, zstd, fill value 7, some chunks never written; OME 0.5 metadata by hand."""
    path = fresh("sharded_tczyx.zarr")
    root = zarr.open_group(str(path), mode="w", zarr_format=3)
    shape = (2, 2, 4, 8, 8)
    arr = root.create_array("0", shape=shape, dtype="uint16", chunks=(1, 1, 2, 4, 4), shards=(1, 1, 4, 8, 8),
                            compressors=zarr.codecs.ZstdCodec(level=3), fill_value=7,
                            config={"write_empty_chunks": False})
    data = ramp(shape, "uint16")
    arr[0] = data[0]
    # t = 1: channel 0 whole, channel 1 only its upper half in z; chunks of the lower half are never written.
    arr[1, 0] = data[1, 0]
    arr[1, 1, 2:] = data[1, 1, 2:]
    axes = [{"name": "t", "type": "time", "unit": "second"}, {"name": "c", "type": "channel"},
            {"name": "z", "type": "space", "unit": "micrometer"}, {"name": "y", "type": "space", "unit": "micrometer"},
            {"name": "x", "type": "space", "unit": "micrometer"}]
    root.attrs["ome"] = {
        "version": "0.5",
        "multiscales": [{"name": "cells", "axes": axes, "datasets": [
            {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1.0, 1.0, 3.0, 1.5, 1.5]}]}]}],
        "omero": {"channels": [
            {"label": "DAPI", "color": "0000FF", "active": True,
             "window": {"min": 0, "max": 65535, "start": 10, "end": 200}},
            {"label": "GFP", "color": "00FF00", "active": True,
             "window": {"min": 0, "max": 65535, "start": 50, "end": 240}}]},
    }
    expect(path, [{"t": 0, "c": 0, "z": 0, "y": 0, "x": 0}, {"t": 1, "c": 1, "z": 0, "y": 3, "x": 5},
                  {"t": 1, "c": 1, "z": 3, "y": 7, "x": 7}, {"t": 1, "c": 0, "z": 1, "y": 2, "x": 3},
                  {"t": 0, "c": 1, "z": 2, "y": 6, "x": 1}])


def napari_czyx():
    """The shape napari's ome-zarr plugin saves: 0.4, Zarr v2, czyx, gzip, float32, omero channels."""
    path = fresh("napari_czyx.zarr")
    image = ramp((2, 4, 6, 8), "float32")
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    write_image(image, group, fmt=FormatV04(), axes=["c", "z", "y", "x"],
                scale_factors=[{"z": 2, "y": 2, "x": 2}], method="nearest",
                scale={"z": 1.0, "y": 0.5, "x": 0.5},
                axes_units={"z": "micrometer", "y": "micrometer", "x": "micrometer"},
                storage_options={"chunks": (1, 4, 6, 8), "compressor": numcodecs.GZip(level=5)})
    group.attrs["omero"] = {"channels": [
        {"label": "membrane", "color": "FF00FF", "window": {"min": -20.25, "max": 105.0, "start": 0.0, "end": 80.0}},
        {"label": "nuclei", "color": "00FFFF", "window": {"min": -20.25, "max": 105.0, "start": -5.0, "end": 60.0}}]}
    expect(path, [{"c": 0, "z": 0, "y": 0, "x": 0}, {"c": 1, "z": 3, "y": 5, "x": 7}, {"c": 1, "z": 1, "y": 2, "x": 3}])


def dtypes():
    """One tiny 0.5 store per dtype volcast reads, no compression; and a 2-D yx one."""
    for dtype in ["uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64"]:
        path = fresh(f"dtype_{dtype}.zarr")
        write_image(ramp((2, 3, 4), dtype), str(path), fmt=FormatV05(), axes=["z", "y", "x"], scale_factors=[],
                    storage_options={"chunks": (2, 3, 4), "compressors": None})
        expect(path, [{"z": 0, "y": 0, "x": 0}, {"z": 1, "y": 2, "x": 3}, {"z": 1, "y": 0, "x": 2}])
    path = fresh("yx.zarr")
    write_image(ramp((5, 7), "uint8"), str(path), fmt=FormatV05(), axes=["y", "x"], scale_factors=[],
                scale={"y": 2.0, "x": 3.0}, axes_units={"y": "millimeter", "x": "millimeter"})
    expect(path, [{"z": 0, "y": 4, "x": 6}, {"z": 0, "y": 1, "x": 2}])


if __name__ == "__main__":
    ome_zarr_v04_blosc()
    ome_zarr_v05()
    sharded_tczyx()
    napari_czyx()
    dtypes()
