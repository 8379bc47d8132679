"""What ``volcast.render``, ``view`` and ``movie`` take as a volume: a ``Volume``, a path, a numpy array (shape
(z, y, x)), a nibabel or SimpleITK image (with its placement in patient space), or a zarr or dask array."""

from __future__ import annotations

import os
from typing import Any, Optional, Tuple

import numpy as np

from ._volume import Volume

#: The largest array materialised from a zarr or dask array (bytes); larger ones are refused with what to do.
LAZY_LIMIT = 4 << 30


def _nibabel(img: Any) -> Volume:
    data = np.asanyarray(img.dataobj)
    while data.ndim > 3 and data.shape[-1] == 1:
        data = data[..., 0]  # NIfTI's trailing axes of one (x, y, z, 1)
    if data.ndim != 3:
        raise ValueError(f"a 3-D image is needed; this nibabel image has shape {data.shape}")
    # nibabel's axes are (x, y, z); volcast's arrays are (z, y, x), so the transpose (a view) is the same voxels.
    return Volume.from_array(data.T, affine=np.asarray(img.affine), name=_name(img, "nibabel image"))


def _simpleitk(img: Any) -> Volume:
    import SimpleITK as sitk  # noqa: F401  (only reached with a SimpleITK image in hand)

    if img.GetDimension() != 3 or img.GetNumberOfComponentsPerPixel() != 1:
        raise ValueError("a 3-D single-component SimpleITK image is needed")
    data = sitk.GetArrayViewFromImage(img)
    direction = np.array(img.GetDirection(), dtype=float).reshape(3, 3)
    lps = np.eye(4)
    lps[:3, :3] = direction * np.array(img.GetSpacing(), dtype=float)
    lps[:3, 3] = img.GetOrigin()
    # ITK's physical space is LPS; volcast's patient space is RAS (negate x and y).
    ras = np.diag([-1.0, -1.0, 1.0, 1.0]) @ lps
    return Volume.from_array(np.array(data), affine=ras, name="SimpleITK image")


def _name(obj: Any, default: str) -> str:
    name = getattr(obj, "get_filename", lambda: None)()
    return os.path.basename(name) if name else default


def _lazy(arr: Any, kind: str, **placement: Any) -> Volume:
    nbytes = int(np.prod(arr.shape)) * np.dtype(arr.dtype).itemsize
    if nbytes > LAZY_LIMIT:
        raise ValueError(
            f"this {kind} array of shape {tuple(arr.shape)} holds {nbytes / 2**30:.1f} GiB, over the "
            f"{LAZY_LIMIT / 2**30:.0f} GiB volcast reads into memory from a {kind} array; write it as OME-Zarr "
            "(ome_zarr.writer or `volcast convert`) and pass the store's path, which volcast reads level by level"
        )
    return Volume.from_array(np.asarray(arr), **placement)


def as_source(obj: Any, **placement: Any) -> Tuple[Optional[Volume], Optional[str]]:
    """(volume, None) for anything held in memory, (None, path) for a path, (None, None) for nothing."""
    if obj is None:
        return None, None
    if isinstance(obj, Volume):
        return obj, None
    if isinstance(obj, (str, os.PathLike)):
        return None, os.fspath(obj)
    module = type(obj).__module__.split(".")[0]
    if module == "nibabel":
        return _nibabel(obj), None
    if module == "SimpleITK":
        return _simpleitk(obj), None
    if module in ("zarr", "dask"):
        return _lazy(obj, module, **placement), None
    if isinstance(obj, np.ndarray) or hasattr(obj, "__array__"):
        return Volume.from_array(np.asarray(obj), **placement), None
    raise TypeError(
        f"volcast cannot show a {type(obj).__name__}: pass a numpy array (z, y, x), a volcast.Volume, a path, "
        "a nibabel or SimpleITK image, or a zarr or dask array"
    )
