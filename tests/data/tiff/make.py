"""Writes the TIFF oracle files for tests/formats/tiff.rs with tifffile, then reads every one back with tifffile
and records what volcast must find in expected.json: dims (x, y, z), dtype, spacing in millimetres, the sum of
the voxels and a few voxels by (x, y, z).

Also writes tests/data/unsupported/brain.h5 with h5py (an HDF5 file volcast must name, not read as raw).

Run from the repository root:  /work/venv/bin/python tests/data/tiff/make.py
"""

import json
import os
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import tifffile

HERE = os.path.dirname(os.path.abspath(__file__))
Z, Y, X = 5, 7, 9  # numpy order: z slowest, x fastest, as volcast stores voxels


def ramp(dtype, scale=1, offset=0):
    return (np.arange(Z * Y * X).reshape(Z, Y, X) * scale + offset).astype(dtype)


def path(name):
    return os.path.join(HERE, name)


def write_all():
    w = tifffile.imwrite
    # ImageJ stacks: x/y spacing from XResolution/YResolution (pixels per micron), z from spacing=, unit=micron.
    w(path("u8_imagej.tif"), ramp(np.uint8), imagej=True, resolution=(1 / 0.25, 1 / 0.5),
      metadata={"spacing": 2.0, "unit": "micron", "axes": "ZYX"})
    w(path("u16_imagej_lzw.tif"), ramp(np.uint16, 97, 1000), imagej=True, compression="lzw",
      resolution=(1 / 0.5, 1 / 0.5), metadata={"spacing": 1.5, "unit": "micron", "axes": "ZYX"})
    w(path("f32_imagej.tif"), ramp(np.float32, 0.25, -7.5), imagej=True, resolution=(2.0, 2.0),
      metadata={"spacing": 0.75, "unit": "micron", "axes": "ZYX"})
    # Plain TIFFs: ResolutionUnit centimetre (20 and 10 pixels per cm: 0.5 and 1 mm), no z spacing.
    w(path("i16_deflate_cm.tif"), ramp(np.int16, -13, 200), compression="zlib", resolution=(20, 10),
      resolutionunit="CENTIMETER")
    w(path("u16_tiled.tif"), ramp(np.uint16, 3), tile=(16, 16), compression="zlib")
    w(path("f32_bigtiff.tif"), ramp(np.float32, -0.5, 3.25), bigtiff=True)
    w(path("u8_packbits.tif"), ramp(np.uint8, 3, 5), compression="packbits")
    w(path("i32.tif"), ramp(np.int32, -100000, 7))
    w(path("u32.tif"), ramp(np.uint32, 70001))
    w(path("f64.tif"), ramp(np.float64, 0.125, -1.0))
    # An ImageJ hyperstack: 3 slices x 2 channels; volcast loads channel 0, or another by --channel.
    hyper = (np.arange(3 * 2 * Y * X).reshape(1, 3, 2, Y, X) % 251).astype(np.uint8)
    w(path("hyperstack.tif"), hyper, imagej=True, metadata={"axes": "TZCYX"})
    # OME-TIFF with physical sizes in micrometres.
    w(path("ome.ome.tif"), ramp(np.uint16, 11), ome=True,
      metadata={"axes": "ZYX", "PhysicalSizeX": 0.4, "PhysicalSizeY": 0.6, "PhysicalSizeZ": 1.2})
    # RGB: refused.
    w(path("rgb.tif"), np.zeros((2, Y, X, 3), np.uint8), photometric="rgb")
    # A folder of single-slice TIFFs named so that natural order (z2 < z10) differs from byte order.
    folder = path("stack")
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    for z in range(1, 13):
        w(os.path.join(folder, f"z{z}.tif"), (np.arange(Y * X).reshape(Y, X) + 10 * z).astype(np.uint8))
    with open(os.path.join(folder, "notes.txt"), "w") as f:
        f.write("not a slice\n")
    with open(os.path.join(folder, ".hidden"), "w") as f:
        f.write("not a slice either\n")


UNIT_MM = {"micron": 1e-3, "um": 1e-3, "\u00b5m": 1e-3, "mm": 1.0, "cm": 10.0}


def spacing(tif):
    """Millimetres per voxel from what tifffile reads back."""
    page = tif.pages[0]
    if tif.is_ome:
        pixels = next(e for e in ET.fromstring(tif.ome_metadata).iter() if e.tag.endswith("Pixels"))
        f = UNIT_MM[pixels.get("PhysicalSizeXUnit", "\u00b5m")]
        return [float(pixels.get(k)) * f for k in ("PhysicalSizeX", "PhysicalSizeY", "PhysicalSizeZ")]
    xres = page.tags.get("XResolution")
    yres = page.tags.get("YResolution")
    sx = yx = None
    if xres is not None:
        sx = xres.value[1] / xres.value[0]
        yx = yres.value[1] / yres.value[0]
    ij = tif.imagej_metadata
    if ij is not None:
        f = UNIT_MM.get(ij.get("unit"))
        if f is None:
            return [sx or 1.0, yx or sx or 1.0, ij.get("spacing", sx or 1.0)]
        sz = ij.get("spacing", sx)
        return [sx * f, yx * f, sz * f]
    unit = page.tags.get("ResolutionUnit")
    f = {2: 25.4, 3: 10.0}.get(int(unit.value) if unit is not None else 1)
    if f is None or sx is None:
        return [1.0, 1.0, 1.0]
    return [sx * f, yx * f, sx * f]


def volume(name):
    """The voxels as z, y, x (channel 0 of a hyperstack) and the spacing."""
    p = path(name)
    if os.path.isdir(p):
        files = sorted(os.listdir(p), key=lambda n: int(n[1:-4]) if n.endswith(".tif") else -1)
        files = [f for f in files if f.endswith(".tif")]
        data = np.stack([tifffile.imread(os.path.join(p, f)) for f in files])
        with tifffile.TiffFile(os.path.join(p, files[0])) as tif:
            return data, spacing(tif)
    with tifffile.TiffFile(p) as tif:
        data = tif.asarray()
        if tif.series[0].axes == "ZCYX":
            data = data[:, 0]
        return data, spacing(tif)


def expected():
    out = {}
    names = ["u8_imagej.tif", "u16_imagej_lzw.tif", "f32_imagej.tif", "i16_deflate_cm.tif", "u16_tiled.tif",
             "f32_bigtiff.tif", "u8_packbits.tif", "i32.tif", "u32.tif", "f64.tif", "hyperstack.tif",
             "ome.ome.tif", "stack"]
    for name in names:
        data, sp = volume(name)
        z, y, x = data.shape
        picks = [(0, 0, 0), (x - 1, 0, 0), (0, y - 1, 0), (0, 0, z - 1), (x - 1, y - 1, z - 1), (x // 2, y // 2, z // 2)]
        out[name] = {
            "dims": [x, y, z],
            "dtype": str(data.dtype),
            "spacing_mm": [float(s) for s in sp],
            "sum": float(data.astype(np.float64).sum()),
            "voxels": [[i, j, k, float(data[k, j, i])] for (i, j, k) in picks],
        }
    out["_writer"] = f"tifffile {tifffile.__version__}, numpy {np.__version__}"
    with open(path("expected.json"), "w") as f:
        json.dump(out, f, indent=1, sort_keys=True)
        f.write("\n")


def write_hdf5():
    """A small real HDF5 file for the "unsupported format is named" test (tests/data/unsupported/brain.h5)."""
    import h5py

    folder = os.path.join(HERE, "..", "unsupported")
    os.makedirs(folder, exist_ok=True)
    with h5py.File(os.path.join(folder, "brain.h5"), "w", libver="latest") as f:
        f.create_dataset("volume", data=ramp(np.uint8)[:2, :3, :4])


if __name__ == "__main__":
    write_all()
    expected()
    write_hdf5()
