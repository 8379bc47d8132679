"""Writes the VTK oracle files in this folder with VTK's own writers, and expected.json with what VTK's readers
read back from each (dims, spacing, origin, direction, per point array: type, components, sum, samples).

    /work/venv/bin/python tests/data/vtk/make.py      # VTK 9.7.2, numpy

Every volume is 7x6x5 (i fastest) with arrays from known formulas of (i, j, k), so a failing test can be read.
"""
import json
import lzma
import os

import numpy as np
import vtk
from vtk.util import numpy_support as ns

HERE = os.path.dirname(os.path.abspath(__file__))
DIMS = (7, 6, 5)


def grid():
    k, j, i = np.meshgrid(*(np.arange(n) for n in DIMS[::-1]), indexing="ij")
    return i.ravel(), j.ravel(), k.ravel()


def arrays():
    """Point arrays in file order: uint8 first (the default), then others."""
    i, j, k = grid()
    return [
        ("ramp", (i + 7 * j + 42 * k).astype(np.uint8) % 200),
        ("density", (0.5 * i - j + 2.25 * k).astype(np.float32)),
        ("label", (i * j - 100 * k).astype(np.int16)),
    ]


def vtk_array(name, values, components=1):
    a = ns.numpy_to_vtk(np.ascontiguousarray(values), deep=1)
    a.SetName(name)
    a.SetNumberOfComponents(components)
    return a


def image(names=None, origin=(0, 0, 0), spacing=(1, 1, 1), extent_start=(0, 0, 0), direction=None, cell=False):
    img = vtk.vtkImageData()
    s = extent_start
    img.SetExtent(s[0], s[0] + DIMS[0] - 1, s[1], s[1] + DIMS[1] - 1, s[2], s[2] + DIMS[2] - 1)
    img.SetOrigin(*origin)
    img.SetSpacing(*spacing)
    if direction is not None:
        img.SetDirectionMatrix(*direction)
    pd = img.GetPointData()
    for n, (name, values) in enumerate(arrays()):
        if names is not None and name not in names:
            continue
        a = vtk_array(name, values)
        if n == 0:
            pd.SetScalars(a)
        else:
            pd.AddArray(a)
    i, j, k = grid()
    pd.SetVectors(vtk_array("grad", np.stack([i, j, k], 1).astype(np.float32).ravel(), 3))
    if cell:
        ncells = (DIMS[0] - 1) * (DIMS[1] - 1) * (DIMS[2] - 1)
        img.GetCellData().SetScalars(vtk_array("cellid", np.arange(ncells, dtype=np.int32)))
        img.GetCellData().AddArray(vtk_array("cellf", np.arange(ncells, dtype=np.float64) * 0.5))
        fd = vtk_array("note", np.array([1.5, 2.5], dtype=np.float64))
        img.GetFieldData().AddArray(fd)
    return img


def legacy(name, img, binary, version=None, rectilinear=False):
    w = vtk.vtkDataSetWriter()
    w.SetInputData(img)
    w.SetFileName(os.path.join(HERE, name))
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    if version is not None:
        w.SetFileVersion(version)
    assert w.Write() == 1, name


def rect_grid(xs, ys, zs):
    g = vtk.vtkRectilinearGrid()
    g.SetDimensions(len(xs), len(ys), len(zs))
    g.SetXCoordinates(vtk_array("x", np.asarray(xs, np.float32)))
    g.SetYCoordinates(vtk_array("y", np.asarray(ys, np.float64)))
    g.SetZCoordinates(vtk_array("z", np.asarray(zs, np.float32)))
    for n, (name, values) in enumerate(arrays()):
        a = vtk_array(name, values)
        if n == 1:
            g.GetPointData().SetScalars(a)
        else:
            g.GetPointData().AddArray(a)
    return g


def xml(name, img, mode, compressor=None, header64=False, big_endian=False):
    w = vtk.vtkXMLImageDataWriter()
    w.SetInputData(img)
    w.SetFileName(os.path.join(HERE, name))
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary}.get(mode, w.SetDataModeToAppended)()
    w.SetEncodeAppendedData(mode == "appended-base64")
    if compressor is None:
        w.SetCompressorTypeToNone()
    else:
        {"zlib": w.SetCompressorTypeToZLib, "lz4": w.SetCompressorTypeToLZ4, "lzma": w.SetCompressorTypeToLZMA}[
            compressor
        ]()
        # Small blocks, so the 7x6x5 arrays span several (the last one partial).
        w.SetBlockSize(64)
    if header64:
        w.SetHeaderTypeToUInt64()
    if big_endian:
        w.SetByteOrderToBigEndian()
    assert w.Write() == 1, name


def read_back(name):
    path = os.path.join(HERE, name)
    if name.endswith(".vti"):
        r = vtk.vtkXMLImageDataReader()
    else:
        r = vtk.vtkDataSetReader()
        r.ReadAllScalarsOn()
        r.ReadAllFieldsOn()
        r.ReadAllColorScalarsOn()
        r.ReadAllVectorsOn()
    r.SetFileName(path)
    r.Update()
    out = r.GetOutput()
    entry = {}
    if isinstance(out, vtk.vtkRectilinearGrid):
        coords = [ns.vtk_to_numpy(c).astype(float) for c in
                  (out.GetXCoordinates(), out.GetYCoordinates(), out.GetZCoordinates())]
        entry["dims"] = [len(c) for c in coords]
        entry["spacing"] = [float((c[-1] - c[0]) / (len(c) - 1)) if len(c) > 1 else 1.0 for c in coords]
        entry["origin"] = [float(c[0]) for c in coords]
        entry["direction"] = [1.0, 0, 0, 0, 1, 0, 0, 0, 1]
    else:
        entry["dims"] = list(out.GetDimensions())
        entry["spacing"] = list(out.GetSpacing())
        # VTK puts index (0,0,0) of the extent at Origin + Direction * (extent start * spacing).
        first = [0.0, 0.0, 0.0]
        out.TransformIndexToPhysicalPoint(*[out.GetExtent()[2 * a] for a in range(3)], first)
        entry["origin"] = first
        entry["direction"] = [out.GetDirectionMatrix().GetElement(r_, c) for r_ in range(3) for c in range(3)]
    pd = out.GetPointData()
    scalars = pd.GetScalars()
    entry["active_scalars"] = scalars.GetName() if scalars is not None else None
    entry["arrays"] = []
    for n in range(pd.GetNumberOfArrays()):
        a = pd.GetAbstractArray(n)
        if not isinstance(a, vtk.vtkDataArray):
            continue
        v = ns.vtk_to_numpy(a)
        first = v if v.ndim == 1 else v[:, 0]
        idx = [0, 1, 7, 42, 100, len(first) - 1]
        entry["arrays"].append({
            "name": a.GetName(),
            "type": str(v.dtype),
            "components": a.GetNumberOfComponents(),
            "sum": float(first.astype(np.float64).sum()),
            "samples": [[i, float(first[i])] for i in idx],
        })
    return entry


def main():
    # Legacy: VTK 9.7 writes version 5.1 by default; unsigned char scalars come out as COLOR_SCALARS.
    legacy("legacy_u8_binary.vtk", image(["ramp"], origin=(1, 2, 3), spacing=(0.5, 1, 2)), True)
    legacy("legacy_u8_ascii.vtk", image(["ramp"], origin=(1, 2, 3), spacing=(0.5, 1, 2)), False)
    legacy("legacy_multi_binary.vtk", image(cell=True, spacing=(1, 2, 3)), True)
    legacy("legacy_multi_ascii.vtk", image(cell=True, spacing=(1, 2, 3)), False)
    legacy("legacy_v42_binary.vtk", image(cell=True), True, version=42)
    legacy("legacy_v42_ascii.vtk", image(cell=True), False, version=42)
    xs = 10 + 0.5 * np.arange(DIMS[0])
    ys = -3 + 1.25 * np.arange(DIMS[1])
    zs = 2 + 3.0 * np.arange(DIMS[2])
    legacy("legacy_rectilinear.vtk", rect_grid(xs, ys, zs), True)
    legacy("legacy_rectilinear_ascii.vtk", rect_grid(xs, ys, zs), False)
    ys_bad = ys.copy()
    ys_bad[3] += 0.4
    legacy("legacy_rectilinear_uneven.vtk", rect_grid(xs, ys_bad, zs), False)

    # XML ImageData.
    base = dict(origin=(1, 2, 3), spacing=(0.5, 1, 2))
    xml("vti_ascii.vti", image(**base), "ascii")
    xml("vti_binary.vti", image(**base), "binary")
    xml("vti_appended_raw.vti", image(**base), "appended")
    xml("vti_appended_base64.vti", image(**base), "appended-base64")
    for c in ("zlib", "lz4", "lzma"):
        xml(f"vti_{c}.vti", image(**base), "appended", compressor=c)
    xml("vti_zlib_inline.vti", image(**base), "binary", compressor="zlib")
    xml("vti_zlib_base64.vti", image(**base), "appended-base64", compressor="zlib")
    xml("vti_uint64_header.vti", image(**base), "appended", compressor="zlib", header64=True)
    xml("vti_uint64_raw.vti", image(**base), "appended", header64=True)
    xml("vti_big_endian.vti", image(**base), "appended", big_endian=True)
    xml("vti_extent.vti", image(origin=(1, 2, 3), spacing=(0.5, 1, 2), extent_start=(3, -2, 10)), "appended")
    rot = (0, -1, 0, 1, 0, 0, 0, 0, 1)
    xml("vti_direction.vti", image(origin=(1, 2, 3), spacing=(0.5, 1, 2), extent_start=(1, 2, 3), direction=rot),
        "appended")

    # Not ImageData: for the "unsupported" message.
    ug = vtk.vtkUnstructuredGrid()
    pts = vtk.vtkPoints()
    pts.InsertNextPoint(0, 0, 0)
    ug.SetPoints(pts)
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(ug)
    w.SetFileName(os.path.join(HERE, "unsupported.vtu"))
    w.Write()

    # An xz stream (as vtkLZMADataCompressor writes blocks) of 4 MiB of zeros in ~700 bytes: tests/formats/vtk.rs
    # wraps it in a .vti whose block header claims far less, and expects a refusal, not 4 MiB of output.
    with open(os.path.join(HERE, "bomb.xz"), "wb") as f:
        f.write(lzma.compress(bytes(4 << 20), format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC32))

    expected = {"vtk_version": vtk.vtkVersion.GetVTKVersion(), "files": {}}
    for name in sorted(os.listdir(HERE)):
        if (name.endswith(".vtk") or name.endswith(".vti")) and "uneven" not in name:
            expected["files"][name] = read_back(name)
    with open(os.path.join(HERE, "expected.json"), "w") as f:
        json.dump(expected, f, indent=1, sort_keys=True)
        f.write("\n")


if __name__ == "__main__":
    main()
