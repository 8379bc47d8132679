#!/usr/bin/env python3
"""Oracle files for volcast's voxel-to-world placement, written by the real third-party libraries.

Run from the repository root (it rewrites every file in tests/data/world/, deterministically):

    /work/venv/bin/python tests/data/world/make.py

Needs numpy, nibabel, SimpleITK, pynrrd (module ``nrrd``), pydicom and vtk; nothing else, no network.

World convention (nibabel's): RAS+ millimetres, +x towards the patient's Right, +y Anterior, +z Superior. An
affine maps the voxel index (i, j, k, 1), i fastest on disk, to RAS; voxel centres sit at integer indices.
ITK and DICOM work in LPS (+x Left, +y Posterior); LPS -> RAS negates x and y (``FLIP`` below).

Every volume shows the same phantom in patient space (``phantom``): 0 outside, a body ellipsoid of 100 with
semi-axes 40 (L-R), 50 (A-P), 45 (S-I) mm centred at RAS (0, 0, 0), and three 8 mm marker cubes (|d| <= 4 mm
along each RAS axis): 1000 on the patient's LEFT at RAS (-30, 0, 0), 700 ANTERIOR at (0, +35, 0), 400 SUPERIOR
at (0, 0, +32). Each file is filled by mapping every voxel index through that file's own affine (for DICOM:
each slice's own IOP/IPP) and evaluating the phantom there, so whatever the storage order, every file depicts
the same anatomy. A reader that places voxels correctly finds each marker's voxels around its RAS centre.

After writing, every file is read back with the library that wrote it (nibabel, SimpleITK, pynrrd, VTK) to get
the expected affine, and with a second reader where one exists (SimpleITK for NIfTI and NRRD, a plain-text parse
of the MetaImage header, pydicom IOP/IPP for DICOM). The shared real files under /work/shared/data/native are
measured the same way. Results go to expected.json (machine-readable) and README.md (generated from the same
numbers; the prose in it is in this script).

Determinism: no random numbers; DICOM UIDs come from pydicom's generate_uid with fixed entropy sources; pynrrd's
"# on <date>" header comment is pinned to 2000-01-01 00:00:00 by patching nrrd.writer.datetime; nibabel and zlib
gzip streams carry no timestamp. Re-running gives byte-identical files with the same library versions.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import re
import shutil
import sys
import warnings
from pathlib import Path

import numpy as np
import nibabel as nib
import nrrd
import nrrd.writer
import pydicom
import SimpleITK as sitk
import vtk
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, generate_uid, CTImageStorage, MRImageStorage
from pydicom.valuerep import format_number_as_ds
from vtk.util import numpy_support

HERE = Path(__file__).resolve().parent
SHARED = Path("/work/shared/data/native")

# ---------------------------------------------------------------------------------------------------------------
# The phantom
# ---------------------------------------------------------------------------------------------------------------

BODY_SEMI_AXES = np.array([40.0, 50.0, 45.0])  # RAS mm: L-R, A-P, S-I
BODY_VALUE = 100
MARKER_HALF = 4.0  # mm: cubes are 8 mm on a side
MARKERS = [  # name, value, RAS centre (mm)
    ("left", 1000, (-30.0, 0.0, 0.0)),
    ("anterior", 700, (0.0, 35.0, 0.0)),
    ("superior", 400, (0.0, 0.0, 32.0)),
]
EPS = 1e-6  # points on a boundary (to within float noise) count as inside

FLIP = np.diag([-1.0, -1.0, 1.0, 1.0])  # LPS <-> RAS


def phantom(ras: np.ndarray) -> np.ndarray:
    """Phantom value (int16) at RAS points ``ras`` of shape (..., 3)."""
    ras = np.asarray(ras, dtype=np.float64)
    out = np.zeros(ras.shape[:-1], dtype=np.int16)
    q = np.sum((ras / BODY_SEMI_AXES) ** 2, axis=-1)
    out[q <= 1.0 + EPS] = BODY_VALUE
    for _, value, centre in MARKERS:
        inside = np.all(np.abs(ras - np.array(centre)) <= MARKER_HALF + EPS, axis=-1)
        out[inside] = value
    return out


def fill(shape, affine) -> np.ndarray:
    """Array indexed [i, j, k] holding the phantom at affine @ (i, j, k, 1) (affine: voxel -> RAS)."""
    idx = np.indices(shape, dtype=np.float64).reshape(3, -1)
    ras = (affine[:3, :3] @ idx + affine[:3, 3:4]).T
    return phantom(ras).reshape(shape)


# ---------------------------------------------------------------------------------------------------------------
# Small helpers
# ---------------------------------------------------------------------------------------------------------------


def rot(axis: str, degrees: float) -> np.ndarray:
    """Right-handed rotation about world axis x, y or z."""
    t = math.radians(degrees)
    c, s = math.cos(t), math.sin(t)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def centred(linear: np.ndarray, dims, centre) -> np.ndarray:
    """4x4 affine with 3x3 part ``linear`` whose grid centre ((dims-1)/2) lands on world point ``centre``."""
    a = np.eye(4)
    a[:3, :3] = linear
    a[:3, 3] = np.asarray(centre, float) - linear @ ((np.asarray(dims, float) - 1) / 2)
    return a


def affine_from_itk(img) -> np.ndarray:
    """Voxel -> LPS affine of an ITK image (direction columns scaled by spacing, origin)."""
    d = np.array(img.GetDirection(), dtype=np.float64).reshape(3, 3)
    a = np.eye(4)
    a[:3, :3] = d @ np.diag(img.GetSpacing())
    a[:3, 3] = img.GetOrigin()
    return a


def itk_array(img) -> np.ndarray:
    """ITK image -> numpy array indexed [i, j, k]."""
    return np.ascontiguousarray(sitk.GetArrayFromImage(img).transpose(2, 1, 0))


def lst(a) -> list:
    return np.asarray(a, dtype=np.float64).tolist()


def axcodes(affine) -> str:
    return "".join(nib.aff2axcodes(affine))


def handedness(affine) -> tuple[float, str]:
    det = float(np.linalg.det(np.asarray(affine)[:3, :3]))
    return det, ("right-handed" if det > 0 else "left-handed (mirrors)")


def spacing_of(affine) -> list:
    return lst(np.linalg.norm(np.asarray(affine)[:3, :3], axis=0))


def value_range(a) -> list:
    a = np.asarray(a)
    return [a.min().item(), a.max().item()]


def markers_info(data: np.ndarray, affine: np.ndarray) -> dict:
    """Where each marker is in the voxel grid of ``data`` (indexed [i, j, k]) under ``affine`` (voxel -> RAS)."""
    inv = np.linalg.inv(affine)
    out = {}
    for name, value, centre in MARKERS:
        cont = inv @ np.array([*centre, 1.0])
        nearest = np.rint(cont[:3]).astype(int)
        inb = bool(np.all(nearest >= 0) and np.all(nearest < np.array(data.shape)))
        vox = np.argwhere(data == value)
        info = {
            "value": value,
            "ras_centre": list(centre),
            "index_continuous": lst(cont[:3]),
            "index_nearest": nearest.tolist(),
            "value_at_nearest": int(data[tuple(nearest)]) if inb else None,
            "count": int(len(vox)),
        }
        if len(vox):
            c = vox.mean(axis=0)
            info["index_min"] = vox.min(axis=0).tolist()
            info["index_max"] = vox.max(axis=0).tolist()
            info["centroid_index"] = lst(c)
            info["centroid_ras"] = lst((affine @ np.array([*c, 1.0]))[:3])
        out[name] = info
    return out


def phantom_agreement(data: np.ndarray, affine: np.ndarray) -> dict:
    """Fraction of voxels whose value (as the library read it) equals the phantom at affine @ index (as the library
    reports the affine): 1.0 unless the affine misplaces voxels (or float32 storage moves a boundary voxel)."""
    a = np.asarray(affine, float)
    expect = fill(data.shape, a)
    ok = np.asarray(data) == expect
    out = {"fraction": float(ok.mean()), "mismatched_voxels": int((~ok).sum())}
    # The same under affines a buggy reader might use, to show the file tells them apart.
    no_origin = a.copy()
    no_origin[:3, 3] = 0
    k_flipped = a.copy()  # k column negated about the grid (e.g. qfac ignored, slices stacked the wrong way)
    k_flipped[:3, 2] *= -1
    k_flipped[:3, 3] = a[:3, 3] + a[:3, 2] * (data.shape[2] - 1)
    wrong = {"lps_ras_flip_missing_or_doubled": FLIP @ a, "origin_dropped": no_origin,
             "x_mirrored": np.diag([-1.0, 1, 1, 1]) @ a, "k_axis_reversed": k_flipped}
    out["mismatched_voxels_under_wrong_affines"] = {k: int((np.asarray(data) != fill(data.shape, w)).sum())
                                                    for k, w in wrong.items()}
    return out


def body_clipped(data: np.ndarray) -> bool:
    """Whether any non-zero voxel touches the grid's boundary faces (the body should lie fully inside)."""
    faces = [data[0], data[-1], data[:, 0], data[:, -1], data[:, :, 0], data[:, :, -1]]
    return bool(any(np.any(f != 0) for f in faces))


def max_diff(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a, float) - np.asarray(b, float))))


def column_angles(affine) -> dict:
    """Angles (degrees) between the affine's index-axis columns: 90, 90, 90 unless the affine shears."""
    m = np.asarray(affine, float)[:3, :3]
    u = m / np.linalg.norm(m, axis=0)
    ang = lambda a, b: math.degrees(math.acos(max(-1.0, min(1.0, float(u[:, a] @ u[:, b])))))
    return {"ij": ang(0, 1), "ik": ang(0, 2), "jk": ang(1, 2)}


def describe(affine, data, **extra) -> dict:
    det, hand = handedness(affine)
    d = {
        "dims": list(data.shape),
        "voxel_type": str(data.dtype),
        "spacing": spacing_of(affine),
        "affine": lst(affine),
        "axcodes": axcodes(affine),
        "determinant": det,
        "handedness": hand,
        "column_angles_deg": column_angles(affine),
        "value_range": value_range(data),
    }
    d.update(extra)
    return d


def gz_header_clean(path: Path) -> None:
    """Asserts a .gz file's header carries no timestamp (MTIME bytes 4..8 are zero)."""
    with open(path, "rb") as f:
        head = f.read(10)
    assert head[:2] == b"\x1f\x8b", path
    assert head[4:8] == b"\0\0\0\0", f"{path}: gzip header has a timestamp"


VERSIONS = {
    "python": platform.python_version(),
    "numpy": np.__version__,
    "nibabel": nib.__version__,
    "SimpleITK": sitk.Version.VersionString(),
    "ITK": f"{sitk.Version.ITKMajorVersion()}.{sitk.Version.ITKMinorVersion()}",
    "pynrrd": nrrd.__version__ if hasattr(nrrd, "__version__") else "?",
    "pydicom": pydicom.__version__,
    "vtk": vtk.vtkVersion.GetVTKVersion(),
}

RESULTS: dict = {}
NOTES: dict = {}  # file name -> list of README lines (prose)
DISAGREEMENTS: list = []


def note(name, *lines):
    NOTES.setdefault(name, []).extend(lines)


def check(name, what, a, b, tol):
    """Records a cross-check between two affines (or arrays); a miss beyond ``tol`` is a disagreement."""
    d = max_diff(a, b)
    ok = d <= tol
    RESULTS[name].setdefault("cross_checks", []).append({"check": what, "max_abs_diff": d, "tolerance": tol, "agree": ok})
    if not ok:
        DISAGREEMENTS.append(f"{name}: {what}: max |diff| = {d:.6g} > {tol}")
    return ok


# ---------------------------------------------------------------------------------------------------------------
# NIfTI (nibabel)
# ---------------------------------------------------------------------------------------------------------------


def nifti_readback(name: str, path: Path, call: str, intended: np.ndarray | None, sitk_expected_same=True):
    img = nib.load(path)
    h = img.header
    data = np.asanyarray(img.dataobj)
    aff = img.affine
    extra = {
        "format": "NIfTI-1 (.nii.gz)",
        "writer": f"nibabel {nib.__version__}",
        "call": call,
        "affine_source": "nibabel.load(path).affine",
        "header": {
            "sform_code": int(h["sform_code"]),
            "qform_code": int(h["qform_code"]),
            "pixdim": lst(h["pixdim"][:4]),
            "qfac": float(h["pixdim"][0]),
            "quatern_bcd": lst([h["quatern_b"], h["quatern_c"], h["quatern_d"]]),
            "qoffset": lst([h["qoffset_x"], h["qoffset_y"], h["qoffset_z"]]),
            "srow": lst([h["srow_x"], h["srow_y"], h["srow_z"]]),
            "datatype": str(h.get_data_dtype()),
            "xyzt_units": list(h.get_xyzt_units()),
        },
    }
    if int(h["sform_code"]) > 0:
        extra["sform_affine"] = lst(h.get_sform())
    if int(h["qform_code"]) > 0:
        extra["qform_affine"] = lst(h.get_qform())
    RESULTS[name] = describe(aff, data, **extra)
    RESULTS[name]["markers"] = markers_info(data, aff)
    RESULTS[name]["phantom_agreement"] = phantom_agreement(data, aff)
    RESULTS[name]["body_clipped"] = body_clipped(data)
    if intended is not None:
        check(name, "nibabel affine vs the float64 affine used to fill (float32 storage)", aff, intended, 1e-4)
    # Second reader: ITK (LPS), flipped to RAS.
    with warnings.catch_warnings():
        simg = sitk.ReadImage(str(path))
    itk_ras = FLIP @ affine_from_itk(simg)
    RESULTS[name]["simpleitk_ras_affine"] = lst(itk_ras)
    if sitk_expected_same:
        check(name, "SimpleITK ReadImage (LPS->RAS) vs nibabel affine", itk_ras, aff, 1e-4)
        arr_ok = bool(np.array_equal(itk_array(simg), data))
        RESULTS[name]["cross_checks"].append({"check": "SimpleITK voxel array == nibabel voxel array", "agree": arr_ok})
        if not arr_ok:
            DISAGREEMENTS.append(f"{name}: SimpleITK and nibabel voxel arrays differ")
    return img


def make_nifti():
    # --- nifti_ras: diagonal 3 mm, RAS storage, origin offset, sform_code 1 and qform_code 1 ------------------
    name = "nifti_ras.nii.gz"
    dims = (34, 40, 36)
    aff = np.array([[3.0, 0, 0, -52.5], [0, 3.0, 0, -58.5], [0, 0, 3.0, -50.0], [0, 0, 0, 1]])
    data = fill(dims, aff)
    img = nib.Nifti1Image(data, aff)
    img.header.set_data_dtype(np.int16)
    img.header.set_xyzt_units("mm")
    img.set_sform(aff, code=1)
    img.set_qform(aff, code=1)
    nib.save(img, HERE / name)
    call = ("img = nib.Nifti1Image(data_int16, A); img.header.set_xyzt_units('mm'); "
            "img.set_sform(A, code=1); img.set_qform(A, code=1); nib.save(img, 'nifti_ras.nii.gz')")
    nifti_readback(name, HERE / name, call, aff)
    note(name, "Diagonal 3 mm affine, RAS storage, voxel (0,0,0) at RAS (-52.5, -58.5, -50): the body is not at "
         "the grid centre, so a reader that ignores the origin misplaces it. sform and qform are identical "
         "(codes 1 and 1).")

    # --- nifti_las_qform: LAS storage, qform only (qfac = -1) ---------------------------------------------
    name = "nifti_las_qform.nii.gz"
    dims = (38, 37, 30)
    aff = np.array([[-2.5, 0, 0, 46.0], [0, 3.0, 0, -53.0], [0, 0, 3.5, -52.0], [0, 0, 0, 1]])
    data = fill(dims, aff)
    img = nib.Nifti1Image(data, None)
    img.header.set_data_dtype(np.int16)
    img.header.set_xyzt_units("mm")
    img.set_qform(aff, code=1)
    img.set_sform(None, code=0)
    nib.save(img, HERE / name)
    call = ("img = nib.Nifti1Image(data_int16, None); img.header.set_xyzt_units('mm'); "
            "img.set_qform(A, code=1); img.set_sform(None, code=0); nib.save(img, 'nifti_las_qform.nii.gz')")
    nifti_readback(name, HERE / name, call, aff)
    h = nib.load(HERE / name).header
    note(name, f"LAS storage: i runs towards the patient's Left (affine[0,0] = -2.5), determinant < 0. sform_code 0, "
         f"qform_code 1, so only the qform places it. nibabel stored the negative determinant as qfac = "
         f"pixdim[0] = {float(h['pixdim'][0]):g} with quaternion (b, c, d) = "
         f"({float(h['quatern_b']):g}, {float(h['quatern_c']):g}, {float(h['quatern_d']):g}) -- a 180 degree "
         f"rotation about y, and qfac negates the k column. A reader that ignores qfac gets k running Inferior.")

    # --- nifti_coronal: permuted (coronal) 'LIP', 2 x 2 x 4 mm, sform_code 2, qform_code 0 -----------------
    name = "nifti_coronal.nii.gz"
    dims = (46, 50, 28)
    lin = np.array([[-2.0, 0, 0], [0, 0, -4.0], [0, -2.0, 0]])  # i -> L 2 mm, j -> I 2 mm, k -> P 4 mm
    aff = np.eye(4)
    aff[:3, :3] = lin
    aff[:3, 3] = [45.0, 56.0, 50.0]
    data = fill(dims, aff)
    img = nib.Nifti1Image(data, None)
    img.header.set_data_dtype(np.int16)
    img.header.set_xyzt_units("mm")
    img.header.set_zooms((2.0, 2.0, 4.0))  # pixdim must match the sform's column lengths (ITK takes spacing from pixdim)
    img.set_sform(aff, code=2)
    img.set_qform(None, code=0)
    nib.save(img, HERE / name)
    call = ("img = nib.Nifti1Image(data_int16, None); img.header.set_xyzt_units('mm'); img.header.set_zooms((2.0, 2.0, 4.0)); "
            "img.set_sform(A, code=2); img.set_qform(None, code=0); nib.save(img, 'nifti_coronal.nii.gz')")
    nifti_readback(name, HERE / name, call, aff)
    note(name, "Coronal storage as a coronal acquisition keeps it: i -> Left (2 mm), j -> Inferior (2 mm), "
         "k (slices) -> Posterior (4 mm); axcodes LIP, right-handed. Only the sform places it, with code 2 "
         "(ALIGNED_ANAT), qform_code 0: a reader that accepts only sform_code 1 falls back wrongly. "
         "pixdim is set to (2, 2, 4) explicitly: nibabel's set_sform does not touch pixdim, and when pixdim "
         "disagrees with the sform's column lengths ITK warns 'unexpected scales in sform' and takes its "
         "spacing from pixdim (nibabel uses the sform).")

    # --- nifti_oblique: 20 deg about S (z) then 10 deg about R (x); 2.0 x 2.5 x 3.5 mm; sform 1 & qform 1 ----
    name = "nifti_oblique.nii.gz"
    dims = (54, 46, 32)
    rmat = rot("z", 20.0) @ rot("x", 10.0)
    aff = centred(rmat @ np.diag([2.0, 2.5, 3.5]), dims, (2.0, -3.0, 4.0))
    data = fill(dims, aff)
    img = nib.Nifti1Image(data, None)
    img.header.set_data_dtype(np.int16)
    img.header.set_xyzt_units("mm")
    img.set_sform(aff, code=1)
    img.set_qform(aff, code=1)
    nib.save(img, HERE / name)
    call = ("A = centred(rot('z', 20) @ rot('x', 10) @ diag(2.0, 2.5, 3.5), dims, centre=(2, -3, 4)); "
            "img = nib.Nifti1Image(data_int16, None); img.set_sform(A, code=1); img.set_qform(A, code=1); "
            "nib.save(img, 'nifti_oblique.nii.gz')")
    nifti_readback(name, HERE / name, call, aff)
    r = RESULTS[name]
    qs = max_diff(r["sform_affine"], r["qform_affine"])
    r["sform_vs_qform_max_abs_diff"] = qs
    note(name, "Oblique: linear part = Rz(20 deg) @ Rx(10 deg) @ diag(2.0, 2.5, 3.5) (rotation about the S axis "
         "by 20 degrees after a 10 degree rotation about the R axis), grid centre at RAS (2, -3, 4). sform and "
         f"qform both code 1; they agree to {qs:.3g} mm (the sform rows are float32, the qform is rebuilt from a "
         "float32 quaternion). nibabel's affine is the sform (NIfTI prefers the sform when sform_code > 0).")

    # --- nifti_pixdim_only: sform_code 0, qform_code 0 ------------------------------------------------------
    name = "nifti_pixdim_only.nii.gz"
    dims = (36, 44, 30)
    hdr = nib.Nifti1Header()
    hdr.set_data_shape(dims)
    hdr.set_zooms((3.0, 2.5, 3.5))
    hdr.set_data_dtype(np.int16)
    hdr.set_xyzt_units("mm")
    fallback = hdr.get_base_affine()  # what nibabel will report; the phantom is drawn for it
    data = fill(dims, fallback)
    img = nib.Nifti1Image(data, None, hdr)
    assert int(img.header["sform_code"]) == 0 and int(img.header["qform_code"]) == 0
    nib.save(img, HERE / name)
    call = ("hdr = nib.Nifti1Header(); hdr.set_data_shape(dims); hdr.set_zooms((3.0, 2.5, 3.5)); "
            "hdr.set_data_dtype(np.int16); hdr.set_xyzt_units('mm'); img = nib.Nifti1Image(data_int16, None, hdr); "
            "nib.save(img, 'nifti_pixdim_only.nii.gz')")
    nifti_readback(name, HERE / name, call, fallback, sitk_expected_same=False)
    r = RESULTS[name]
    nx, ny, nz = dims
    spec = np.diag([3.0, 2.5, 3.5, 1.0])
    r["nifti1_method1_affine"] = lst(spec)
    r["nifti1_method1_axcodes"] = axcodes(spec)
    r["simpleitk_axcodes"] = axcodes(np.array(r["simpleitk_ras_affine"]))
    r["readers_disagree"] = True
    note(name,
         "No sform, no qform (codes 0, 0, quaternion and offsets 0): only pixdim = (3, 2.5, 3.5). The readers "
         "DISAGREE here, by design of the standard:",
         f"* nibabel `img.affine` = `header.get_base_affine()` = Analyze-style `shape_zoom_affine(shape, zooms, "
         f"x_flip=True)`: x NEGATED (LAS) and the grid CENTRED on (0,0,0): "
         f"diag(-3, 2.5, 3.5) with offset (+(nx-1)/2*3, -(ny-1)/2*2.5, -(nz-1)/2*3.5) = "
         f"({(nx - 1) / 2 * 3:g}, {-(ny - 1) / 2 * 2.5:g}, {-(nz - 1) / 2 * 3.5:g}); axcodes {r['axcodes']}. "
         "The phantom in this file is drawn for THIS affine, so the markers are at their RAS places only under "
         "nibabel's reading.",
         f"* NIfTI-1 'Method 1' (nifti1.h, for qform_code 0, 'the ANALYZE 7.5 way'): x = pixdim[1]*i, "
         f"y = pixdim[2]*j, z = pixdim[3]*k, no flip, no centring: diag(3, 2.5, 3.5) (axcodes "
         f"{r['nifti1_method1_axcodes']} if read as RAS), and nifti1.h adds that 'no particular spatial "
         "orientation is attached to these (x,y,z) coordinates'.",
         f"* SimpleITK/ITK {VERSIONS['ITK']} (observed): origin (0, 0, 0), identity direction, spacing pixdim, in "
         f"ITK's LPS -> RAS diag(-3, -2.5, 3.5), axcodes {r['simpleitk_axcodes']}.",
         "A test should therefore pin whichever convention volcast documents; nibabel's is what this brief asked "
         "to record. Under method 1 the 1000 marker would appear on the patient's RIGHT (x flipped) and shifted.")


# ---------------------------------------------------------------------------------------------------------------
# MetaImage (SimpleITK)
# ---------------------------------------------------------------------------------------------------------------


def parse_mha_header(path: Path) -> dict:
    text = open(path, "rb").read(4096).split(b"ElementDataFile")[0].decode("ascii")
    fields = {}
    for line in text.splitlines():
        if "=" in line:
            k, v = line.split("=", 1)
            fields[k.strip()] = v.strip()
    return fields


def make_mha():
    name = "mha_rip.mha"
    dims = (46, 40, 37)
    spacing = (2.0, 2.5, 3.0)
    # LPS direction columns: i -> +x (Left), j -> +z (Superior), k -> -y (Anterior)
    direction = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    origin = (-45.5, 54.0, -48.25)  # LPS
    lps = np.eye(4)
    lps[:3, :3] = direction @ np.diag(spacing)
    lps[:3, 3] = origin
    ras = FLIP @ lps
    data = fill(dims, ras)
    img = sitk.GetImageFromArray(data.transpose(2, 1, 0))
    img.SetSpacing(spacing)
    img.SetOrigin(origin)
    img.SetDirection(direction.ravel().tolist())
    sitk.WriteImage(img, str(HERE / name), useCompression=True)
    call = ("img = sitk.GetImageFromArray(data_ijk.transpose(2, 1, 0)); img.SetSpacing((2.0, 2.5, 3.0)); "
            "img.SetOrigin((-45.5, 54.0, -48.25)); img.SetDirection((1,0,0, 0,0,-1, 0,1,0)); "
            "sitk.WriteImage(img, 'mha_rip.mha', useCompression=True)")
    back = sitk.ReadImage(str(HERE / name))
    got_lps = affine_from_itk(back)
    got = FLIP @ got_lps
    arr = itk_array(back)
    fields = parse_mha_header(HERE / name)
    RESULTS[name] = describe(
        got, arr,
        format="MetaImage (.mha, one file, zlib CompressedData)",
        writer=f"SimpleITK {sitk.Version.VersionString()} (ITK {VERSIONS['ITK']})",
        call=call,
        affine_source="FLIP @ [GetDirection() @ diag(GetSpacing()) | GetOrigin()] from sitk.ReadImage(path); "
                      "FLIP = diag(-1, -1, 1, 1) (ITK physical space is LPS)",
        lps_affine=lst(got_lps),
        header_fields={k: fields[k] for k in fields if k in (
            "NDims", "TransformMatrix", "Offset", "CenterOfRotation", "AnatomicalOrientation", "ElementSpacing",
            "DimSize", "ElementType", "CompressedData", "BinaryDataByteOrderMSB")},
    )
    RESULTS[name]["markers"] = markers_info(arr, got)
    RESULTS[name]["phantom_agreement"] = phantom_agreement(arr, got)
    RESULTS[name]["body_clipped"] = body_clipped(arr)
    check(name, "SimpleITK read-back vs the affine used to fill", got, ras, 1e-9)
    # Second reading: the header text itself. TransformMatrix lists the direction column by column (axis i's
    # direction first), Offset is the LPS position of voxel 0, ElementSpacing the voxel size.
    tm = np.array([float(x) for x in fields["TransformMatrix"].split()]).reshape(3, 3).T  # columns
    off = np.array([float(x) for x in fields["Offset"].split()])
    sp = np.array([float(x) for x in fields["ElementSpacing"].split()])
    manual = np.eye(4)
    manual[:3, :3] = tm @ np.diag(sp)
    manual[:3, 3] = off
    check(name, "header text (TransformMatrix as columns, Offset, ElementSpacing; LPS->RAS) vs SimpleITK", FLIP @ manual,
          got, 1e-9)
    ao = fields.get("AnatomicalOrientation")
    assert ao == "RIP", ao
    note(name,
         f"ITK wrote `AnatomicalOrientation = {ao}` and `TransformMatrix = {fields['TransformMatrix']}`. "
         "TransformMatrix holds the direction cosines COLUMN BY COLUMN: the first triple is where index i points "
         "(LPS +x = Left), the second j (+z = Superior), the third k (-y = Anterior). The MetaImage/ITK "
         "orientation letters name where each axis comes FROM (ITK's legacy RAI = identity LPS), so 'RIP' here "
         f"is nibabel axcodes '{RESULTS[name]['axcodes']}' (each letter the opposite). AnatomicalOrientation "
         "is informative only; ITK reads the geometry from TransformMatrix/Offset/ElementSpacing.")


# ---------------------------------------------------------------------------------------------------------------
# NRRD (pynrrd)
# ---------------------------------------------------------------------------------------------------------------


class _FixedDatetime(_dt.datetime):
    @classmethod
    def utcnow(cls):
        return cls(2000, 1, 1, 0, 0, 0)

    @classmethod
    def now(cls, tz=None):
        return cls(2000, 1, 1, 0, 0, 0)


nrrd.writer.datetime = _FixedDatetime  # pin pynrrd's "# on <date>(GMT)." comment (determinism)

SPACE_TO_RAS = {  # NRRD space name -> matrix taking that space's coordinates to RAS
    "right-anterior-superior": np.diag([1.0, 1.0, 1.0]),
    "RAS": np.diag([1.0, 1.0, 1.0]),
    "left-posterior-superior": np.diag([-1.0, -1.0, 1.0]),
    "LPS": np.diag([-1.0, -1.0, 1.0]),
    "left-anterior-superior": np.diag([-1.0, 1.0, 1.0]),
    "LAS": np.diag([-1.0, 1.0, 1.0]),
}


def nrrd_affine(header) -> np.ndarray:
    """RAS affine from a pynrrd header: 'space directions' rows are the per-axis vectors (= affine columns)."""
    m = SPACE_TO_RAS[header["space"]]
    a = np.eye(4)
    a[:3, :3] = m @ np.asarray(header["space directions"], float).T
    a[:3, 3] = m @ np.asarray(header["space origin"], float)
    return a


def nrrd_readback(name, path, call, intended, fmt):
    data, header = nrrd.read(str(path))  # index_order='F': data[i, j, k]
    aff = nrrd_affine(header)
    hdr_json = {k: (lst(v) if isinstance(v, np.ndarray) else v) for k, v in header.items()}
    hdr_json = {k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in hdr_json.items()}
    RESULTS[name] = describe(
        aff, data, format=fmt, writer=f"pynrrd {VERSIONS['pynrrd']}", call=call,
        affine_source="pynrrd nrrd.read(path): A[:3,:3] = S @ header['space directions'].T, A[:3,3] = S @ "
                      "header['space origin'], S = the file space -> RAS sign matrix",
        header=hdr_json,
    )
    RESULTS[name]["markers"] = markers_info(data, aff)
    RESULTS[name]["phantom_agreement"] = phantom_agreement(data, aff)
    RESULTS[name]["body_clipped"] = body_clipped(data)
    check(name, "pynrrd read-back vs the affine used to fill", aff, intended, 1e-12)
    simg = sitk.ReadImage(str(path))
    itk_ras = FLIP @ affine_from_itk(simg)
    RESULTS[name]["simpleitk_ras_affine"] = lst(itk_ras)
    check(name, "SimpleITK ReadImage (LPS->RAS) vs pynrrd affine", itk_ras, aff, 1e-9)
    ok = bool(np.array_equal(itk_array(simg), data))
    RESULTS[name]["cross_checks"].append({"check": "SimpleITK voxel array == pynrrd voxel array", "agree": ok})
    if not ok:
        DISAGREEMENTS.append(f"{name}: SimpleITK and pynrrd voxel arrays differ")


def make_nrrd():
    # --- nrrd_lps: LPS space, sagittal (PIR) storage tilted 12 deg about the L-R axis, attached, gzip --------
    name = "nrrd_lps.nrrd"
    dims = (46, 48, 24)
    base = np.array([[0.0, 0, -1.0], [1.0, 0, 0], [0, -1.0, 0]])  # LPS columns: i -> +y (P), j -> -z (I), k -> -x (R)
    lin_lps = rot("x", 12.0) @ base @ np.diag([2.5, 2.2, 4.0])
    a_lps = centred(lin_lps, dims, (-1.5, 2.0, 3.0))  # grid centre LPS (-1.5, 2, 3) = RAS (1.5, -2, 3)
    a_ras = FLIP @ a_lps
    data = fill(dims, a_ras)
    header = {
        "space": "left-posterior-superior",
        "space directions": a_lps[:3, :3].T,  # one row per index axis
        "space origin": a_lps[:3, 3],
        "kinds": ["domain", "domain", "domain"],
        "encoding": "gzip",
    }
    nrrd.write(str(HERE / name), data, header)
    call = ("nrrd.write('nrrd_lps.nrrd', data_int16_ijk, {'space': 'left-posterior-superior', 'space directions': "
            "A_lps[:3,:3].T, 'space origin': A_lps[:3,3], 'kinds': ['domain']*3, 'encoding': 'gzip'}) with "
            "A_lps = centred(Rx(12 deg) @ [[0,0,-1],[1,0,0],[0,-1,0]] @ diag(2.5, 2.2, 4.0), dims, (-1.5, 2, 3))")
    nrrd_readback(name, HERE / name, call, a_ras, "NRRD (attached header, gzip)")
    note(name, "LPS space. Sagittal storage (i -> Posterior, j -> Inferior, k -> Right, as a sagittal DICOM "
         "stack has it) tilted by 12 degrees about the L-R axis; voxels 2.5 x 2.2 x 4.0 mm. Each 'space "
         "directions' vector is one index axis (a column of the affine) in LPS; RAS negates their x and y, and "
         "the origin's. pynrrd writes them with 17 significant digits, so they round-trip exactly.")

    # --- nrrd_ras: RAS space, detached header + gzip data, uint16, 'RPS' storage -----------------------------
    name = "nrrd_ras.nhdr"
    dims = (40, 38, 26)
    a_ras = np.array([[2.5, 0, 0, -49.0], [0, -3.0, 0, 56.0], [0, 0, 4.0, -50.0], [0, 0, 0, 1]])
    data = fill(dims, a_ras).astype(np.uint16)
    header = {
        "space": "right-anterior-superior",
        "space directions": a_ras[:3, :3].T,
        "space origin": a_ras[:3, 3],
        "kinds": ["domain", "domain", "domain"],
        "encoding": "gzip",
    }
    nrrd.write(str(HERE / name), data, header, detached_header=True)
    call = ("nrrd.write('nrrd_ras.nhdr', data_uint16_ijk, {'space': 'right-anterior-superior', 'space directions': "
            "[(2.5,0,0), (0,-3,0), (0,0,4)], 'space origin': (-49, 56, -50), 'kinds': ['domain']*3, "
            "'encoding': 'gzip'}, detached_header=True)  # data go to nrrd_ras.raw.gz")
    nrrd_readback(name, HERE / name, call, a_ras, "NRRD (detached header .nhdr + gzip data file nrrd_ras.raw.gz)")
    RESULTS[name]["data_file"] = "nrrd_ras.raw.gz"
    gz_header_clean(HERE / "nrrd_ras.raw.gz")
    note(name, "RAS space (no flips needed), detached header with `data file: nrrd_ras.raw.gz`, uint16. Storage "
         "'RPS': j runs Posterior (space direction (0,-3,0)), so the determinant is negative (left-handed).")


# ---------------------------------------------------------------------------------------------------------------
# VTK legacy
# ---------------------------------------------------------------------------------------------------------------


def make_vtk():
    name = "vtk_legacy.vtk"
    dims = (32, 44, 30)
    spacing = (3.0, 2.5, 3.5)
    origin = (-46.5, -53.5, -51.0)
    aff = np.eye(4)
    aff[:3, :3] = np.diag(spacing)
    aff[:3, 3] = origin
    data = fill(dims, aff)  # the file's x, y, z taken as RAS for drawing the phantom
    im = vtk.vtkImageData()
    im.SetDimensions(*dims)
    im.SetSpacing(*spacing)
    im.SetOrigin(*origin)
    arr = numpy_support.numpy_to_vtk(data.ravel(order="F"), deep=1, array_type=vtk.VTK_SHORT)
    arr.SetName("phantom")
    im.GetPointData().SetScalars(arr)
    w = vtk.vtkStructuredPointsWriter()
    w.SetInputData(im)
    w.SetFileName(str(HERE / name))
    w.SetFileTypeToBinary()
    assert w.Write() == 1
    call = ("im = vtk.vtkImageData(); im.SetDimensions(32, 44, 30); im.SetSpacing(3.0, 2.5, 3.5); "
            "im.SetOrigin(-46.5, -53.5, -51.0); scalars = numpy_to_vtk(data_int16_ijk.ravel(order='F'), "
            "array_type=VTK_SHORT) named 'phantom'; w = vtk.vtkStructuredPointsWriter(); w.SetInputData(im); "
            "w.SetFileTypeToBinary(); w.Write()")
    r = vtk.vtkStructuredPointsReader()
    r.SetFileName(str(HERE / name))
    r.Update()
    out = r.GetOutput()
    got = np.eye(4)
    got[:3, :3] = np.diag(out.GetSpacing())
    got[:3, 3] = out.GetOrigin()
    dm = out.GetDirectionMatrix()
    direction = [[dm.GetElement(a, b) for b in range(3)] for a in range(3)]
    back = numpy_support.vtk_to_numpy(out.GetPointData().GetScalars()).reshape(out.GetDimensions()[::-1]).transpose(2, 1, 0)
    first = open(HERE / name, "rb").readline().decode().strip()
    RESULTS[name] = describe(
        got, back, format=f"VTK legacy STRUCTURED_POINTS, BINARY (big-endian); first line '{first}'",
        writer=f"VTK {VERSIONS['vtk']} vtkStructuredPointsWriter", call=call,
        affine_source="vtkStructuredPointsReader: diag(GetSpacing()) with GetOrigin() (no orientation in the format)",
        anatomical=False,
        vtk_direction_matrix_after_read=direction,
    )
    RESULTS[name]["markers"] = markers_info(back, got)
    RESULTS[name]["phantom_agreement"] = phantom_agreement(back, got)
    RESULTS[name]["body_clipped"] = body_clipped(back)
    check(name, "vtkStructuredPointsReader read-back vs the affine used to fill", got, aff, 1e-12)
    ok = bool(np.array_equal(back, data))
    RESULTS[name]["cross_checks"].append({"check": "VTK read-back voxels == written voxels", "agree": ok})
    simg = sitk.ReadImage(str(HERE / name))
    itk_world = affine_from_itk(simg)
    RESULTS[name]["simpleitk_affine_in_its_lps"] = lst(itk_world)
    check(name, "SimpleITK (VTKImageIO) origin/spacing/direction vs VTK (as raw x, y, z, no flip)", itk_world, got, 1e-12)
    ok = bool(np.array_equal(itk_array(simg), back))
    RESULTS[name]["cross_checks"].append({"check": "SimpleITK voxel array == VTK voxel array", "agree": ok})
    # Does the legacy writer keep a direction matrix? (It does not: written with one, read back as identity.)
    probe = vtk.vtkImageData()
    probe.SetDimensions(2, 2, 2)
    probe.SetDirectionMatrix(0, 1, 0, 1, 0, 0, 0, 0, -1)
    probe.GetPointData().SetScalars(numpy_support.numpy_to_vtk(np.zeros(8, np.int16), deep=1))
    pw = vtk.vtkStructuredPointsWriter()
    pw.SetInputData(probe)
    pw.SetWriteToOutputString(1)
    pw.Write()
    kept = "DIRECTION" in pw.GetOutputString().upper()
    RESULTS[name]["legacy_writer_keeps_direction_matrix"] = bool(kept)
    note(name,
         f"VTK legacy has SPACING and ORIGIN but no orientation and no anatomical convention: its world is just "
         f"the file's x, y, z (`{first}`; VTK {VERSIONS['vtk']} writes version 5.1 by default). "
         f"vtkStructuredPointsWriter silently drops a vtkImageData direction matrix (probe: direction kept = "
         f"{kept}). The phantom was drawn taking the file's x, y, z AS RAS (identity), so a reader that shows "
         "x, y, z as they are sees the markers at x = -30 (1000), y = +35 (700), z = +32 (400). The axcodes "
         "'RAS' listed are only that reading. ITK's VTKImageIO reads the same numbers as ITK (LPS) physical "
         "coordinates, i.e. RAS diag(-3, -2.5, 3.5): for a VTK file there is no right answer, only a convention.")


# ---------------------------------------------------------------------------------------------------------------
# DICOM (pydicom writes; SimpleITK and our own IOP/IPP computation read)
# ---------------------------------------------------------------------------------------------------------------


def ds(x) -> str:
    s = format_number_as_ds(float(x))
    assert len(s) <= 16
    return s


def dicom_slice_affine(iop, ipp, ps):
    """Voxel (column i, row j) -> LPS for one slice: IPP + i*ps[1]*row + j*ps[0]*col. Returns (row, col, normal)."""
    row = np.array(iop[:3], float)
    col = np.array(iop[3:], float)
    return row, col, np.cross(row, col)


def write_dicom_series(folder: str, spec: dict):
    """Writes one series; spec gives geometry, modality, pixel representation and slice positions."""
    out = HERE / folder
    if out.exists():
        shutil.rmtree(out)
    out.mkdir()
    rows, cols = spec["rows"], spec["cols"]
    ps = [float(ds(spec["pixel_spacing"][0])), float(ds(spec["pixel_spacing"][1]))]
    iop_s = [ds(v) for v in spec["iop"]]
    iop = [float(v) for v in iop_s]
    row, col, normal = dicom_slice_affine(iop, None, ps)
    seed = f"volcast tests/data/world/{folder}"
    study_uid = generate_uid(entropy_srcs=[seed, "study"])
    series_uid = generate_uid(entropy_srcs=[seed, "series"])
    frame_uid = generate_uid(entropy_srcs=[seed, "frame"])
    modality = spec["modality"]
    slope, intercept = spec.get("rescale", (None, None))
    signed = spec["signed"]
    slices = []
    for n, ipp_f in enumerate(spec["ipps"]):
        ipp_s = [ds(v) for v in ipp_f]
        ipp = np.array([float(v) for v in ipp_s])
        # pixel (row j, column i) -> LPS, exactly as a reader computes it from the stored strings
        jj, ii = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        lps = ipp + ii[..., None] * ps[1] * row + jj[..., None] * ps[0] * col
        values = phantom(lps * np.array([-1.0, -1.0, 1.0]))  # [row, column]
        if slope is not None:
            stored = np.rint((values - intercept) / slope)
        else:
            stored = values
        stored = stored.astype(np.int16 if signed else np.uint16)
        inst = spec["instance"][n]
        sop_uid = generate_uid(entropy_srcs=[seed, "instance", str(inst)])
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = CTImageStorage if modality == "CT" else MRImageStorage
        meta.MediaStorageSOPInstanceUID = sop_uid
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        d = Dataset()
        d.file_meta = meta
        d.SpecificCharacterSet = "ISO_IR 100"
        d.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL"]
        d.SOPClassUID = meta.MediaStorageSOPClassUID
        d.SOPInstanceUID = sop_uid
        d.StudyDate = d.SeriesDate = d.ContentDate = "20240101"
        d.StudyTime = d.SeriesTime = d.ContentTime = "120000"
        d.AccessionNumber = ""
        d.Modality = modality
        d.Manufacturer = "volcast test phantom (pydicom)"
        d.ReferringPhysicianName = ""
        d.SeriesDescription = spec["description"]
        d.PatientName = "Phantom^World"
        d.PatientID = "VOLCAST-WORLD"
        d.PatientBirthDate = ""
        d.PatientSex = "O"
        if modality == "CT":
            d.KVP = "120"
        else:
            d.ScanningSequence = "SE"
            d.SequenceVariant = "NONE"
            d.ScanOptions = ""
            d.MRAcquisitionType = "2D"
            d.RepetitionTime = "2000"
            d.EchoTime = "20"
            d.MagneticFieldStrength = "1.5"
        d.SliceThickness = ds(spec["thickness"])
        if "spacing_between_slices" in spec:
            d.SpacingBetweenSlices = ds(spec["spacing_between_slices"])
        d.PatientPosition = "HFS"
        d.StudyInstanceUID = study_uid
        d.SeriesInstanceUID = series_uid
        d.StudyID = "1"
        d.SeriesNumber = spec["series_number"]
        d.InstanceNumber = inst
        d.ImagePositionPatient = ipp_s
        d.ImageOrientationPatient = iop_s
        d.FrameOfReferenceUID = frame_uid
        d.PositionReferenceIndicator = ""
        d.SliceLocation = ds(float(ipp @ normal))
        d.SamplesPerPixel = 1
        d.PhotometricInterpretation = "MONOCHROME2"
        d.Rows = rows
        d.Columns = cols
        d.PixelSpacing = [ds(spec["pixel_spacing"][0]), ds(spec["pixel_spacing"][1])]
        d.BitsAllocated = 16
        d.BitsStored = spec["bits_stored"]
        d.HighBit = spec["bits_stored"] - 1
        d.PixelRepresentation = 1 if signed else 0
        d.WindowCenter = "300"
        d.WindowWidth = "1200"
        if slope is not None:
            d.RescaleIntercept = ds(intercept)
            d.RescaleSlope = ds(slope)
            d.RescaleType = "HU" if modality == "CT" else "US"
        d.PixelData = stored.astype("<i2" if signed else "<u2").tobytes()
        fname = f"{spec['prefix']}_{inst:03d}.dcm"
        d.save_as(out / fname, enforce_file_format=True)
        slices.append({"file": fname, "instance": inst, "ipp": ipp.tolist(), "slice_location": float(d.SliceLocation)})
    return slices


def read_dicom_series(folder: Path, use_itk=True):
    """Reads a series with SimpleITK's ImageSeriesReader and independently from pydicom IOP/IPP."""
    res = {}
    reader = sitk.ImageSeriesReader()
    ids = reader.GetGDCMSeriesIDs(str(folder))
    assert len(ids) == 1, ids
    files = reader.GetGDCMSeriesFileNames(str(folder), ids[0])
    reader.SetFileNames(files)
    sitk.ProcessObject.SetGlobalWarningDisplay(False)
    img = reader.Execute()
    sitk.ProcessObject.SetGlobalWarningDisplay(True)
    itk_lps = affine_from_itk(img)
    itk_ras = FLIP @ itk_lps
    res["itk_file_order"] = [Path(f).name for f in files]
    res["itk_lps_affine"] = lst(itk_lps)
    res["itk_ras_affine"] = lst(itk_ras)
    res["itk_pixel_type"] = img.GetPixelIDTypeAsString()
    itk_vol = itk_array(img)

    # Own computation from the tags
    dsets = [pydicom.dcmread(f) for f in sorted(folder.glob("*.dcm"))]
    iops = {tuple(float(v) for v in x.ImageOrientationPatient) for x in dsets}
    assert len(iops) == 1, "IOP differs between slices"
    iop = list(iops.pop())
    row, col = np.array(iop[:3]), np.array(iop[3:])
    iop_norms = [float(np.linalg.norm(row)), float(np.linalg.norm(col))]
    iop_dot = float(row @ col)
    row, col = row / np.linalg.norm(row), col / np.linalg.norm(col)  # the DS strings are rounded
    normal = np.cross(row, col)
    normal /= np.linalg.norm(normal)
    ps = [float(v) for v in dsets[0].PixelSpacing]
    pos = [float(np.array(x.ImagePositionPatient, float) @ normal) for x in dsets]
    order = np.argsort(pos, kind="stable")
    dsets = [dsets[o] for o in order]
    ipps = np.array([[float(v) for v in x.ImagePositionPatient] for x in dsets])
    dist = ipps @ normal
    steps = np.diff(dist)
    n = len(dsets)
    first_last = (ipps[-1] - ipps[0]) / (n - 1)
    own_lps = np.eye(4)
    own_lps[:3, 0] = row * ps[1]
    own_lps[:3, 1] = col * ps[0]
    own_lps[:3, 2] = normal * float(np.mean(steps)) if n > 1 else normal
    own_lps[:3, 3] = ipps[0]
    ipp_lps = own_lps.copy()
    ipp_lps[:3, 2] = first_last  # the actual mean step vector (keeps any shear)
    # Residual of each IPP from the straight line along the normal with the mean spacing (ITK's model).
    model = ipps[0] + np.outer(np.arange(n), normal * np.mean(steps))
    resid = np.linalg.norm(ipps - model, axis=1)
    # Shear: angle between the step vector and the slice normal.
    step_vec = ipps[-1] - ipps[0]
    shear_deg = math.degrees(math.acos(min(1.0, abs(step_vec @ normal) / np.linalg.norm(step_vec))))
    in_plane = step_vec - (step_vec @ normal) * normal
    vols = []
    for x in dsets:
        a = x.pixel_array.astype(np.float64)
        slope = float(getattr(x, "RescaleSlope", 1) or 1)
        inter = float(getattr(x, "RescaleIntercept", 0) or 0)
        vols.append(a * slope + inter)
    own_vol = np.stack([v.T for v in vols], axis=2)  # [i = column, j = row, k]
    stored = np.stack([x.pixel_array.T for x in dsets], axis=2)
    # Markers with each slice at its own IPP (the truth when the spacing is uneven).
    true_markers = {}
    for mname, value, centre in MARKERS:
        vox = np.argwhere(own_vol == value)
        if len(vox):
            lps = ipps[vox[:, 2]] + np.outer(vox[:, 0] * ps[1], row) + np.outer(vox[:, 1] * ps[0], col)
            true_markers[mname] = {"value": value, "ras_centre": list(centre), "count": int(len(vox)),
                                   "centroid_ras_per_slice_ipp": lst((lps * [-1, -1, 1]).mean(axis=0))}
    # Third reader for the in-plane geometry: nibabel's DICOM wrapper (maps (row, column, slice) to LPS; its
    # third column uses SpacingBetweenSlices and points along -normal, so only columns 0, 1 and the origin count).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from nibabel.nicom import dicomwrappers
        wrap = dicomwrappers.wrapper_from_file(dsets[0].filename)
        nib_aff = np.asarray(wrap.affine, float)
    nib_lps = np.eye(4)
    nib_lps[:3, 0] = nib_aff[:3, 1]  # its column index
    nib_lps[:3, 1] = nib_aff[:3, 0]  # its row index
    nib_lps[:3, 3] = nib_aff[:3, 3]
    res.update({
        "rows_columns": [int(dsets[0].Rows), int(dsets[0].Columns)],
        "pixel_spacing_row_col": ps,
        "slice_thickness": float(dsets[0].SliceThickness) if "SliceThickness" in dsets[0] else None,
        "spacing_between_slices_tag": float(dsets[0].SpacingBetweenSlices) if "SpacingBetweenSlices" in dsets[0] else None,
        "iop": iop,
        "iop_row_col_norms": iop_norms,
        "iop_row_dot_col": iop_dot,
        "normal_lps": lst(normal),
        "sorted_by_position": [{"file": Path(x.filename).name, "instance": int(x.InstanceNumber),
                                "ipp": lst(ipps[m]), "distance_along_normal": float(dist[m])}
                               for m, x in enumerate(dsets)],
        "slice_steps_along_normal": lst(steps),
        "slice_step_min_max_mean": [float(steps.min()), float(steps.max()), float(steps.mean())] if n > 1 else None,
        "first_to_last_euclidean_over_n_minus_1": float(np.linalg.norm(step_vec) / (n - 1)) if n > 1 else None,
        "first_to_last_along_normal_over_n_minus_1": float((step_vec @ normal) / (n - 1)) if n > 1 else None,
        "max_ipp_residual_from_uniform_model_mm": float(resid.max()),
        "step_vs_normal_angle_deg": shear_deg,
        "step_in_plane_component_lps": lst(in_plane),
        "own_ras_affine_normal_x_mean_step": lst(FLIP @ own_lps),
        "own_ras_affine_mean_step_vector": lst(FLIP @ ipp_lps),
        "stored_value_range": value_range(stored),
        "stored_dtype": str(stored.dtype),
        "markers_true_geometry": true_markers,
        "nibabel_nicom_wrapper_affine_first_slice_lps": lst(nib_aff),
        "nibabel_nicom_voxel_sizes": lst(wrap.voxel_sizes),
    })
    res["_nib_lps"] = nib_lps
    res["_itk_lps"] = itk_lps
    return res, itk_vol, own_vol, itk_ras, FLIP @ own_lps, FLIP @ ipp_lps


def nicom_check(name, res):
    """nibabel.nicom (first slice): columns 0, 1 and origin must match ITK's LPS affine."""
    nib_lps, itk_lps = res.pop("_nib_lps"), res.pop("_itk_lps")
    sel = np.ix_(range(3), [0, 1, 3])
    check(name, "nibabel.nicom DICOM wrapper (first slice; in-plane columns swapped to (column, row), origin) vs "
                "SimpleITK", nib_lps[sel], itk_lps[sel], 1e-6)


def make_dicom():
    c15, s15 = math.cos(math.radians(15)), math.sin(math.radians(15))
    series = {
        "dicom_series": dict(
            modality="CT", description="AXIAL PHANTOM", prefix="ct", series_number=1,
            rows=44, cols=48, pixel_spacing=(2.5, 2.0), thickness=6.5,
            iop=(1, 0, 0, 0, 1, 0), signed=False, bits_stored=12, rescale=(1.0, -1024.0),
            centre=(1.0, -2.0), positions=[-48.75 + 6.5 * k for k in range(16)],
            descending_instances=True,
        ),
        "dicom_oblique": dict(
            modality="MR", description="AXIAL OBL PHANTOM 15DEG", prefix="mr", series_number=2,
            rows=44, cols=48, pixel_spacing=(2.5, 2.0), thickness=5.0, spacing_between_slices=7.0,
            iop=(1, 0, 0, 0, c15, s15), signed=True, bits_stored=16,
            centre3=(1.0, -2.0, 3.0), positions=[7.0 * (k - 7) for k in range(15)],
            descending_instances=False,
        ),
        "dicom_uneven": dict(
            modality="CT", description="AXIAL PHANTOM UNEVEN", prefix="ct", series_number=3,
            rows=44, cols=48, pixel_spacing=(2.5, 2.0), thickness=6.0,
            iop=(1, 0, 0, 0, 1, 0), signed=True, bits_stored=16, rescale=(1.0, -1024.0),
            centre=(1.0, -2.0), positions=[-47.0 + 6.0 * k + (4.0 if k >= 10 else 0.0) for k in range(16)],
            descending_instances=False,
        ),
    }
    for folder, sp in series.items():
        row = np.array(sp["iop"][:3], float)
        col = np.array(sp["iop"][3:], float)
        normal = np.cross(row, col)
        w = (sp["cols"] - 1) * sp["pixel_spacing"][1]
        h = (sp["rows"] - 1) * sp["pixel_spacing"][0]
        if "centre3" in sp:
            c = np.array(sp["centre3"])
            ipps = [c - w / 2 * row - h / 2 * col + s * normal for s in sp["positions"]]
        else:
            cx, cy = sp["centre"]
            ipps = [np.array([cx - w / 2, cy - h / 2, s]) for s in sp["positions"]]
        n = len(ipps)
        sp["ipps"] = ipps
        sp["instance"] = [n - m for m in range(n)] if sp["descending_instances"] else [m + 1 for m in range(n)]
        written = write_dicom_series(folder, sp)
        res, itk_vol, own_vol, itk_ras, own_ras, ipp_ras = read_dicom_series(HERE / folder)
        name = folder + "/"
        aff = itk_ras
        RESULTS[name] = describe(
            aff, itk_vol,
            format=f"DICOM series, {len(written)} files, {sp['modality']} Image Storage, explicit VR little endian",
            writer=f"pydicom {pydicom.__version__}",
            call=("Dataset() with file_meta (TransferSyntaxUID = ExplicitVRLittleEndian), IOP/IPP/PixelSpacing as "
                  "DS strings from pydicom.valuerep.format_number_as_ds, PixelData = stored.astype('<u2'|'<i2')"
                  ".tobytes(); ds.save_as(path, enforce_file_format=True)"),
            affine_source=("SimpleITK ImageSeriesReader (files from GetGDCMSeriesFileNames): "
                           "FLIP @ [GetDirection() @ diag(GetSpacing()) | GetOrigin()]"),
            slices_written=written,
        )
        RESULTS[name].update(res)
        RESULTS[name]["value_range_rescaled"] = RESULTS[name].pop("value_range")
        RESULTS[name]["markers"] = markers_info(itk_vol, aff)
        RESULTS[name]["phantom_agreement"] = phantom_agreement(itk_vol, aff)
        RESULTS[name]["body_clipped"] = body_clipped(itk_vol)
        nicom_check(name, RESULTS[name])
        check(name, "own IOP/IPP affine (normal x mean step) vs SimpleITK", own_ras, itk_ras, 1e-6)
        check(name, "own IOP/IPP affine (mean step vector, keeps shear) vs SimpleITK", ipp_ras, itk_ras, 1e-6)
        ok = bool(np.array_equal(own_vol, itk_vol))
        RESULTS[name]["cross_checks"].append({"check": "own pydicom stack (sorted along the normal, rescaled) == "
                                                       "SimpleITK voxels", "agree": ok})
        if not ok:
            DISAGREEMENTS.append(f"{name}: own pydicom stack differs from SimpleITK voxels")
        itk_first = res["itk_file_order"][0]
        own_first = res["sorted_by_position"][0]["file"]
        order_note = (f"ITK's k = 0 is {itk_first} (instance {res['sorted_by_position'][0]['instance']}), the "
                      f"slice furthest along -normal; k increases along the normal row x col = "
                      f"LPS {np.round(res['normal_lps'], 6).tolist()}.")
        if itk_first != own_first:
            DISAGREEMENTS.append(f"{name}: ITK's first file {itk_first} != own first {own_first}")
        base = (f"{sp['modality']}, {sp['rows']} rows x {sp['cols']} columns, PixelSpacing {list(sp['pixel_spacing'])} "
                "(row spacing first: the distance between ROWS, i.e. along the column direction = j; then between "
                "columns = i), so i = column -> IOP row vector, j = row -> IOP column vector.")
        if folder == "dicom_series":
            note(name, base,
                 "Axial, IOP (1,0,0, 0,1,0): i -> LPS +x (Left), j -> +y (Posterior), slices 6.5 mm apart along +z. "
                 "Instance numbers run HEAD TO FOOT (instance 1 = most superior, file ct_001.dcm), so file/instance "
                 "order is the reverse of ITK's spatial order. " + order_note,
                 "CT: 12 bits stored, unsigned, RescaleSlope 1, RescaleIntercept -1024: stored = phantom + 1024, "
                 "rescaled (HU) = phantom value.")
        elif folder == "dicom_oblique":
            note(name, base,
                 "Oblique: IOP row = (1, 0, 0), column = (0, cos 15, sin 15): the image plane is rotated by 15 "
                 "degrees about the patient's L-R axis; the slice normal is (0, -sin 15, cos 15). IPPs step along "
                 "that normal (a true rotation, no shear), 7 mm apart (SpacingBetweenSlices 7, SliceThickness 5). "
                 "DS strings hold 16 characters, so cos 15 is stored as "
                 f"{format_number_as_ds(c15)} and sin 15 as {format_number_as_ds(s15)}. " + order_note,
                 "MR: signed 16-bit, no rescale: stored = phantom value.")
        else:
            note(name, base,
                 "Axial like dicom_series, but the slice positions are UNEVEN: 6 mm steps except one 10 mm gap "
                 "between instances 10 (z = +7) and 11 (z = +17). No single affine describes the series: the expected "
                 "affine is what ITK produces (it warns 'Non uniform sampling' and uses |IPP_last - IPP_first| / (n-1) = "
                 f"{res['slice_step_min_max_mean'][2]:.10g} mm); the truth per slice is in slices_written / "
                 "sorted_by_position. The phantom in each slice was drawn at that slice's own IPP, so under ITK's "
                 "uniform affine slices beyond the gap are misplaced by up to "
                 f"{res['max_ipp_residual_from_uniform_model_mm']:.4g} mm (compare the marker table, under ITK's affine, with "
                 "the per-slice-IPP centroids below it). " + order_note,
                 "CT: signed 16-bit, RescaleSlope 1, RescaleIntercept -1024: stored = phantom + 1024. ITK returns "
                 "int32 voxels here (signed int16 stored minus 1024 may not fit int16), int16 for dicom_series "
                 "(unsigned 12-bit stored minus 1024 fits).")


# ---------------------------------------------------------------------------------------------------------------
# Shared real files
# ---------------------------------------------------------------------------------------------------------------


def shared_nifti(rel: str):
    path = SHARED / rel
    img = nib.load(path)
    h = img.header
    data = np.asanyarray(img.dataobj)
    aff = img.affine
    d = describe(
        aff, data if data.ndim == 3 else data[..., 0],
        path=str(path), format="NIfTI-1", affine_source="nibabel.load(path).affine",
        shape=list(img.shape),
        header={
            "sform_code": int(h["sform_code"]), "qform_code": int(h["qform_code"]),
            "pixdim": lst(h["pixdim"][:5]), "qfac": float(h["pixdim"][0]),
            "datatype": str(h.get_data_dtype()), "scl_slope": float(h["scl_slope"]) if np.isfinite(h["scl_slope"]) else None,
            "scl_inter": float(h["scl_inter"]) if np.isfinite(h["scl_inter"]) else None,
            "xyzt_units": list(h.get_xyzt_units()), "descrip": h["descrip"].item().decode(errors="replace").strip(),
        },
    )
    d["dims"] = list(img.shape)
    d["qform_if_code_ignored"] = lst(h.get_qform(coded=False))
    d["zooms"] = lst(h.get_zooms())
    d["value_range"] = [float(np.nanmin(data)), float(np.nanmax(data))]
    if int(h["sform_code"]) > 0:
        d["sform_affine"] = lst(h.get_sform())
    if int(h["qform_code"]) > 0:
        d["qform_affine"] = lst(h.get_qform())
    if "sform_affine" in d and "qform_affine" in d:
        d["sform_vs_qform_max_abs_diff"] = max_diff(d["sform_affine"], d["qform_affine"])
    name = "shared:" + rel
    RESULTS[name] = d
    try:
        simg = sitk.ReadImage(str(path))
        if simg.GetDimension() == 4:
            simg = simg[:, :, :, 0]
        itk_ras = FLIP @ affine_from_itk(simg)
        d["simpleitk_ras_affine"] = lst(itk_ras)
        check(name, "SimpleITK ReadImage (LPS->RAS) vs nibabel affine", itk_ras, aff, 1e-3)
    except Exception as e:  # noqa: BLE001
        d["simpleitk_error"] = str(e)


def shared_dicom():
    folder = SHARED / "brain_pd_mr"
    res, itk_vol, own_vol, itk_ras, own_ras, ipp_ras = read_dicom_series(folder)
    name = "shared:brain_pd_mr/"
    RESULTS[name] = describe(itk_ras, itk_vol, path=str(folder), format="DICOM series (MR, GE Signa, 20 files)",
                             affine_source="SimpleITK ImageSeriesReader, LPS->RAS")
    RESULTS[name].update(res)
    RESULTS[name]["value_range_rescaled"] = RESULTS[name].pop("value_range")
    check(name, "own IOP/IPP affine (normal x mean step) vs SimpleITK", own_ras, itk_ras, 1e-6)
    nicom_check(name, RESULTS[name])
    RESULTS[name]["mean_step_vector_affine_vs_itk_max_abs_diff"] = max_diff(ipp_ras, itk_ras)
    RESULTS[name]["mean_step_vector_affine_vs_itk_note"] = (
        "not a disagreement between readers: ITK's third column is normal x (first-to-last distance along the "
        "normal / (n-1)); the mean IPP step vector also carries the IPPs' small in-plane drift")
    ok = bool(np.array_equal(own_vol, itk_vol))
    RESULTS[name]["cross_checks"].append({"check": "own pydicom stack == SimpleITK voxels", "agree": ok})
    col = np.array(res["iop"][3:])
    RESULTS[name]["tilt_about_LR_deg"] = math.degrees(math.atan2(col[2], col[1]))
    sizes = {f.name: f.stat().st_size for f in sorted(folder.glob("*.dcm"))}
    RESULTS[name]["file_sizes"] = sizes
    d0 = pydicom.dcmread(folder / "brain_001.dcm")
    RESULTS[name]["brain_001_trailing_bytes_after_pixel_data"] = int(
        sizes["brain_001.dcm"] - (d0["PixelData"].file_tell + len(d0.PixelData)))
    RESULTS[name]["series_description"] = str(d0.SeriesDescription)
    RESULTS[name]["slice_location_tags"] = [float(pydicom.dcmread(folder / x["file"]).SliceLocation)
                                            for x in res["sorted_by_position"]]


# ---------------------------------------------------------------------------------------------------------------
# README
# ---------------------------------------------------------------------------------------------------------------


def fmt_aff(a) -> str:
    rows = []
    for r in a:
        rows.append("[" + ", ".join(repr(float(x)) for x in r) + "]")
    return "```\n[" + ",\n ".join(rows) + "]\n```"


def fmt_markers(m: dict) -> list:
    out = ["| marker | value | RAS centre | nearest voxel (i, j, k) | value there | voxels | centroid (i, j, k) | centroid RAS |",
           "|---|---|---|---|---|---|---|---|"]
    for k, v in m.items():
        cen = ", ".join(f"{x:.4g}" for x in v.get("centroid_index", []))
        cras = ", ".join(f"{x:.3f}" for x in v.get("centroid_ras", []))
        out.append(f"| {k} | {v['value']} | ({', '.join(f'{x:g}' for x in v['ras_centre'])}) | "
                   f"({', '.join(str(x) for x in v['index_nearest'])}) | {v['value_at_nearest']} | {v['count']} | "
                   f"({cen}) | ({cras}) |")
    return out


def write_readme(sizes: dict):
    L = []
    L += [
        "# World-placement oracles (`tests/data/world/`)",
        "",
        "Files for testing that volcast places voxels in patient space correctly. Every file here was written by "
        "the real third-party library named below and regenerated by `make.py` (run "
        "`/work/venv/bin/python tests/data/world/make.py` from the repository root; deterministic, rewrites "
        "everything including this README and `expected.json`).",
        "",
        "**Convention** (nibabel's): the affine maps voxel index (i, j, k, 1), i fastest on disk, voxel centres "
        "at integer indices, to RAS+ millimetres: +x patient Right, +y Anterior, +z Superior. ITK and DICOM are LPS; "
        "LPS -> RAS negates x and y (`FLIP = diag(-1, -1, 1, 1)`, applied as `FLIP @ A_lps`). axcodes are "
        "`nibabel.aff2axcodes` (the direction each index axis points TO). Handedness = sign of det of the 3x3.",
        "",
        "**Phantom** (same anatomy in every file): background 0; body ellipsoid 100, semi-axes 40 (L-R), 50 (A-P), "
        "45 (S-I) mm, centred at RAS (0, 0, 0); marker cubes 8 mm on a side (|d| <= 4 mm along each RAS axis): "
        "**1000 = patient's LEFT at RAS (-30, 0, 0)**, **700 = ANTERIOR at (0, +35, 0)**, **400 = SUPERIOR at "
        "(0, 0, +32)**. Each voxel was filled by mapping its index through the file's own affine (DICOM: its "
        "slice's IOP/IPP) and evaluating the phantom there. A test can load a file, take the centroid of the "
        "voxels of each marker value, map it through volcast's affine and expect the RAS centre within a voxel "
        "or so (the sampled cubes are small; `centroid_ras` below is what the correct affine gives).",
        "",
        "`phantom_agreement` (per file, in `expected.json` and below) re-evaluates the phantom at every voxel "
        "through the expected affine and counts voxels that differ from the stored value: 0 for every file except "
        "`dicom_uneven/` (whose slices no single affine describes); under typical reader bugs (LPS/RAS flip missing "
        "or doubled, origin dropped, x mirrored, k reversed) the counts are non-zero, so a test comparing volcast's "
        "affine this way (or via marker centroids) catches them. The body ellipsoid is symmetric about the "
        "origin, so only the markers reveal mirror errors.",
        "",
        "`expected.json` holds every number below in machine-readable form (affines as row-major 4x4 lists, full "
        "float64 precision); the README rounds nothing in the affines either.",
        "",
        "Library versions: " + ", ".join(f"{k} {v}" for k, v in VERSIONS.items()) + ".",
        "",
        "## Summary",
        "",
        "| file | size (bytes) | writer | dims | type | spacing (mm) | axcodes | det |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, r in RESULTS.items():
        if name.startswith("shared:"):
            continue
        L.append(f"| `{name}` | {sizes.get(name, '')} | {r['writer']} | {' x '.join(map(str, r['dims']))} | "
                 f"{r['voxel_type']} | {', '.join(f'{x:.6g}' for x in r['spacing'])} | {r['axcodes']} | "
                 f"{r['determinant']:.6g} |")
    L += ["", "Cross-checks: " + ("all agree except where noted." if not DISAGREEMENTS else
                                  "disagreements: " + "; ".join(DISAGREEMENTS)), ""]
    for name, r in RESULTS.items():
        if name.startswith("shared:"):
            continue
        L += [f"## `{name}`", ""]
        L += [f"* Format: {r['format']}", f"* Written by: {r['writer']}", f"* Call: `{r['call']}`",
              f"* Expected affine from: `{r['affine_source']}`",
              f"* dims {r['dims']}, voxel type {r['voxel_type']}, spacing {r['spacing']}, axcodes **{r['axcodes']}**, "
              f"det {r['determinant']!r} ({r['handedness']})"]
        if "header" in r and "sform_code" in r["header"]:
            hh = r["header"]
            L.append(f"* NIfTI header: sform_code {hh['sform_code']}, qform_code {hh['qform_code']}, "
                     f"qfac {hh['qfac']:g}, pixdim {hh['pixdim'][1:4]}, quatern (b,c,d) {hh['quatern_bcd']}, "
                     f"qoffset {hh['qoffset']}")
        if "header_fields" in r:
            L.append("* MetaImage header: " + "; ".join(f"`{k} = {v}`" for k, v in r["header_fields"].items()))
        if "value_range" in r:
            L.append(f"* stored value range {r['value_range']}")
        if "value_range_rescaled" in r:
            L.append(f"* value range after rescale {r['value_range_rescaled']}; stored ({r['stored_dtype']}) "
                     f"{r['stored_value_range']}")
        L.append(f"* body clipped by the grid: {r['body_clipped']}; voxels equal to the phantom at the expected affine: "
                 f"{r['phantom_agreement']['fraction']:.6f} ({r['phantom_agreement']['mismatched_voxels']} differ); "
                 "voxels that differ under plausible wrong affines: " +
                 ", ".join(f"{k} {v}" for k, v in r["phantom_agreement"]["mismatched_voxels_under_wrong_affines"].items()))
        L += ["", "Expected affine:", "", fmt_aff(r["affine"]), ""]
        for line in NOTES.get(name, []):
            L.append(line)
        L.append("")
        if name.endswith("/"):
            L += [f"ITK file order (k = 0 first): {', '.join(r['itk_file_order'])}.", "",
                  f"Slice steps along the normal: {r['slice_steps_along_normal']}", ""]
        L += fmt_markers(r["markers"])
        L += [""]
        if name.endswith("/"):
            L += ["Marker centroids with every slice at its own IPP (pydicom; the truth when spacing is uneven): " +
                  "; ".join(f"{k} ({v['value']}): ({', '.join(f'{x:.3f}' for x in v['centroid_ras_per_slice_ipp'])})"
                            for k, v in r["markers_true_geometry"].items()), ""]
        L.append("Cross-checks:")
        for c in r.get("cross_checks", []):
            extra = f" (max abs diff {c['max_abs_diff']:.3g}, tol {c['tolerance']})" if "max_abs_diff" in c else ""
            L.append(f"* {c['check']}: {'agree' if c['agree'] else 'DISAGREE'}{extra}")
        L.append("")
    # Shared files
    L += ["## Shared real files (`/work/shared/data/native/`, not copied here)", ""]
    L += ["| file | dims | type | spacing (mm) | axcodes | det | sform/qform codes | value range |",
          "|---|---|---|---|---|---|---|---|"]
    for name, r in RESULTS.items():
        if not name.startswith("shared:"):
            continue
        codes = (f"{r['header']['sform_code']}/{r['header']['qform_code']}" if "header" in r else "DICOM")
        vr = r.get("value_range", r.get("value_range_rescaled"))
        L.append(f"| `{name[7:]}` | {' x '.join(map(str, r['dims']))} | {r['voxel_type']} | "
                 f"{', '.join(f'{x:.6g}' for x in r['spacing'])} | {r['axcodes']} | {r['determinant']:.6g} | "
                 f"{codes} | {vr} |")
    L.append("")
    for name, r in RESULTS.items():
        if not name.startswith("shared:"):
            continue
        L += [f"### `{name[7:]}`", "", f"Expected affine from `{r['affine_source']}`:", "", fmt_aff(r["affine"]), ""]
        if "header" in r:
            L.append(f"* header: {json.dumps(r['header'])}")
            if "sform_vs_qform_max_abs_diff" in r:
                L.append(f"* sform vs qform max abs diff: {r['sform_vs_qform_max_abs_diff']:.6g}")
            L.append(f"* axcodes {r['axcodes']}, det {r['determinant']!r}, spacing {r['spacing']}, angles between "
                     f"columns (deg) {json.dumps({k: round(v, 4) for k, v in r['column_angles_deg'].items()})}")
            if "simpleitk_error" in r:
                L.append(f"* SimpleITK cannot read it: `{r['simpleitk_error'].strip().splitlines()[-1]}`")
        for line in NOTES.get(name, []):
            L.append(line)
        for c in r.get("cross_checks", []):
            extra = f" (max abs diff {c['max_abs_diff']:.3g}, tol {c['tolerance']})" if "max_abs_diff" in c else ""
            L.append(f"* {c['check']}: {'agree' if c['agree'] else 'DISAGREE'}{extra}")
        L.append("")
    (HERE / "README.md").write_text("\n".join(L))


def shared_notes():
    note("shared:motor_zmap/image_10426.nii.gz",
         "* LAS storage (x negated), 3 mm, sform_code 2, qform_code 0; pixdim[0] (qfac) = -1 although the qform is "
         "unused. float32 z-map with negative values.")
    note("shared:colin27_t1/ch2.nii.gz",
         "* RAS storage, 1 mm, sform_code 4 (MNI_152), qform_code 0: a reader that only accepts sform codes 1/2 "
         "must still take code 4.")
    r = RESULTS.get("shared:dwi_b0_ascm/ascm_out_test.nii.gz")
    if r:
        a = np.array(r["affine"])[:3, :3] / np.array(r["spacing"])
        tilt = math.degrees(math.acos(abs(a[2, 2])))
        note("shared:dwi_b0_ascm/ascm_out_test.nii.gz",
             f"* OBLIQUE and stored LPS-like: i -> Left, j -> Posterior-Inferior, k -> Superior-Posterior; the slice "
             f"axis is tilted {tilt:.2f} degrees from S (mostly about the L-R axis). 4 x 4 x 5 mm, sform_code 2, "
             "qform_code 0, float64 voxels (NIfTI datatype 64), negative values present. ITK agrees with nibabel.")
    r = RESULTS.get("shared:dwi_s0_10slices/S0_10slices.nii.gz")
    if r:
        note("shared:dwi_s0_10slices/S0_10slices.nii.gz",
             f"* 4-D header: dim = {r['shape']} (last axis 1). The sform (code 2) SHEARS: its k column is "
             f"(30, 30, 32), length {r['spacing'][2]:.6f} = pixdim[3], at {r['column_angles_deg']['ik']:.4f} degrees "
             "to i and j (not 90): the slices are axial planes (i, j along R and A) stacked along an oblique "
             "direction. nibabel returns the sform as is; ITK refuses the file ('only supports orthonormal "
             "direction cosines'). qform_code is 0 but the quaternion fields are filled "
             f"(quatern b, c = -0.162, 0.162); used anyway they would give {json.dumps(np.round(r['qform_if_code_ignored'], 4).tolist())}, "
             "a different (unsheared, rotated) placement -- a reader must not use them.")
    r = RESULTS.get("shared:brain_pd_mr/")
    if not r:
        return
    st = r["slice_steps_along_normal"]
    note("shared:brain_pd_mr/",
         f"* {r['series_description']!r}: IOP row (1, 0, 0), column (0, {r['iop'][4]}, {r['iop'][5]}): the plane "
         f"is tilted by {r['tilt_about_LR_deg']:.4f} degrees about the patient's L-R axis (a rotation: row and "
         f"column are orthonormal). Normal (LPS) {np.round(r['normal_lps'], 6).tolist()}.",
         f"* Slice order: ITK sorts along the normal; k = 0 is {r['itk_file_order'][0]}, file names and "
         "InstanceNumber run in the same (inferior -> superior) order.",
         f"* Slice spacing: IPP steps along the normal are {min(st):.6f} .. {max(st):.6f} mm "
         f"(mean {np.mean(st):.10g}); UNEVEN at the 0.1 mm level because the IPPs are rounded to 0.1 mm "
         f"(they alternate steps of (0, -1.0, 7.0) and (0, -0.9, 6.9) mm). ITK warns 'Non uniform sampling' and "
         f"uses spacing {r['spacing'][2]!r} = |IPP_last - IPP_first| / (n-1) (Euclidean: "
         f"{r['first_to_last_euclidean_over_n_minus_1']!r}; along the normal it would be "
         f"{r['first_to_last_along_normal_over_n_minus_1']!r}). ITK also normalises the IOP vectors (the stored "
         f"column vector has norm {r['iop_row_col_norms'][1]!r}). The tags say SliceThickness "
         f"{r['slice_thickness']} and SpacingBetweenSlices {r['spacing_between_slices_tag']} (GE's GAP, not the "
         "centre distance): neither is the true ~7.0 mm step; nibabel.nicom's DICOM wrapper takes SpacingBetweenSlices "
         f"at face value (voxel sizes {r['nibabel_nicom_voxel_sizes']}). SliceLocation tags: "
         f"{r['slice_location_tags']} (steps 6.9-7.0).",
         f"* Tilt vs step: the IPP step vector deviates from the normal by {r['step_vs_normal_angle_deg']:.4f} degrees "
         f"(in-plane drift {np.round(r['step_in_plane_component_lps'], 4).tolist()} mm over the whole series), "
         f"i.e. essentially a rotation (no real shear; the residue is IPP rounding). Largest IPP distance from "
         f"ITK's uniform model: {r['max_ipp_residual_from_uniform_model_mm']:.4f} mm.",
         f"* brain_001.dcm is {r['file_sizes']['brain_001.dcm']} bytes, the others 132914: brain_001 has "
         f"{r['brain_001_trailing_bytes_after_pixel_data']} zero bytes after its Pixel Data element (trailing "
         "padding; pydicom and ITK ignore it).",
         f"* Pixel type: stored {r['stored_dtype']} {r['stored_value_range']}, no rescale (slope 1, intercept 0).")


def main():
    os.chdir(HERE.parent.parent.parent)  # repo root; paths below are absolute anyway
    keep = {"make.py"}
    for p in HERE.iterdir():
        if p.name in keep:
            continue
        if p.is_dir():
            shutil.rmtree(p)
        else:
            p.unlink()
    make_nifti()
    make_mha()
    make_nrrd()
    make_vtk()
    make_dicom()
    for rel in ["motor_zmap/image_10426.nii.gz", "colin27_t1/ch2.nii.gz", "dwi_b0_ascm/ascm_out_test.nii.gz",
                "dwi_s0_10slices/S0_10slices.nii.gz"]:
        shared_nifti(rel)
    shared_dicom()
    shared_notes()
    for p in HERE.glob("*.gz"):
        gz_header_clean(p)
    sizes = {}
    for name in RESULTS:
        if name.startswith("shared:"):
            continue
        p = HERE / name.rstrip("/")
        if p.is_dir():
            sizes[name] = sum(f.stat().st_size for f in p.iterdir())
        else:
            sizes[name] = p.stat().st_size
            if name == "nrrd_ras.nhdr":
                sizes[name] += (HERE / "nrrd_ras.raw.gz").stat().st_size
    for name, s in sizes.items():
        RESULTS[name]["size_bytes"] = s
        assert s < 2 * 1024 * 1024, (name, s)
    # Every phantom file must show every marker at its nearest voxel (except the uneven series beyond its gap
    # and the pixdim-only file, which is drawn for nibabel's fallback, i.e. also checked).
    for name, r in RESULTS.items():
        if name.startswith("shared:"):
            continue
        for mk, m in r["markers"].items():
            if m["count"] == 0 or (name != "dicom_uneven/" and m["value_at_nearest"] != m["value"]):
                print("WARNING: marker", name, mk, m)
        if r["body_clipped"]:
            print("WARNING: body clipped in", name)
    out = {
        "convention": "affine: voxel index (i, j, k, 1), i fastest on disk, voxel centres at integers -> RAS+ mm "
                      "(+x Right, +y Anterior, +z Superior); row-major 4x4. LPS->RAS: negate x and y.",
        "phantom": {
            "background": 0, "body": {"value": BODY_VALUE, "semi_axes_mm_RAS": lst(BODY_SEMI_AXES), "centre_ras": [0, 0, 0]},
            "marker_half_side_mm": MARKER_HALF,
            "markers": [{"name": n, "value": v, "ras_centre": list(c)} for n, v, c in MARKERS],
        },
        "versions": VERSIONS,
        "disagreements": DISAGREEMENTS,
        "files": {k: v for k, v in RESULTS.items() if not k.startswith("shared:")},
        "shared": {k[7:]: v for k, v in RESULTS.items() if k.startswith("shared:")},
    }
    (HERE / "expected.json").write_text(json.dumps(out, indent=1) + "\n")
    write_readme(sizes)
    print(f"wrote {len(sizes)} phantom files to {HERE}")
    for name, s in sizes.items():
        r = RESULTS[name]
        print(f"  {name:28s} {s:8d} B  {r['axcodes']}  det {r['determinant']:+.4g}")
    if DISAGREEMENTS:
        print("DISAGREEMENTS:")
        for d in DISAGREEMENTS:
            print("  " + d)


if __name__ == "__main__":
    main()
