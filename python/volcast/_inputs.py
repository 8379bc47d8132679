"""What ``volcast.render``, ``view`` and ``movie`` take as a volume: a ``Volume``, a path, a numpy array (shape
(z, y, x)), a nibabel or SimpleITK image (with its placement in patient space), or a zarr or dask array."""

from __future__ import annotations

import os
import tempfile
import weakref
from typing import Any, Optional, Tuple

import numpy as np

from ._volume import _DTYPES, Volume, open as open_file

#: The largest zarr or dask array read into memory whole (bytes). A larger one is written slab by slab to a raw
#: file in the cache folder, which volcast then reads as it reads any large file: within the memory budgets, at the
#: finest pyramid level they hold, finer bricks read from the file as the view needs them.
LAZY_LIMIT = 2 << 30

#: Bytes of one slab copied from a lazy array to the raw file.
SLAB_BYTES = 64 << 20


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


def cache_folder() -> str:
    """Where large lazy arrays are written: $XDG_CACHE_HOME/volcast/python, else ~/.cache/volcast/python."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = os.path.join(base, "volcast", "python")
    os.makedirs(folder, exist_ok=True)
    return folder


def _spill(arr: Any, kind: str, spacing: Any = None, **placement: Any) -> Volume:
    """A lazy array larger than LAZY_LIMIT, written slab by slab (z) to a raw file and opened in place."""
    if placement:
        raise ValueError(f"{', '.join(placement)}= cannot place a {kind} array this large; give spacing= only")
    if len(arr.shape) != 3:
        raise ValueError(f"a 3-D {kind} array of shape (z, y, x) is needed; got shape {tuple(arr.shape)}")
    dtype = np.dtype(arr.dtype)
    name = _DTYPES.get(dtype.newbyteorder("="))
    if name is None:
        raise ValueError(f"{kind} arrays of dtype {dtype} are not volumes volcast renders")
    z, y, x = (int(n) for n in arr.shape)
    fd, path = tempfile.mkstemp(prefix=f"{kind}-", suffix=".raw", dir=cache_folder())
    os.close(fd)
    try:
        out = np.memmap(path, dtype=dtype.newbyteorder("<"), mode="w+", shape=(z, y, x))
        step = max(1, SLAB_BYTES // max(1, y * x * dtype.itemsize))
        for z0 in range(0, z, step):
            out[z0 : z0 + step] = np.asarray(arr[z0 : z0 + step])
        out.flush()
        del out
        volume = open_file(path, dims=(x, y, z), type=name, spacing=spacing, no_cache=True)
    except BaseException:
        os.remove(path)
        raise
    # The file is the volume's finer levels: it goes when the volume does.
    weakref.finalize(volume, os.remove, path)
    return volume


def _lazy(arr: Any, kind: str, **placement: Any) -> Volume:
    nbytes = int(np.prod(arr.shape)) * np.dtype(arr.dtype).itemsize
    if nbytes > LAZY_LIMIT:
        return _spill(arr, kind, **placement)
    return Volume.from_array(np.asarray(arr), **placement)


def as_source(obj: Any, **placement: Any) -> Tuple[Optional[Volume], Optional[str]]:
    """(volume, None) for anything held in memory, (None, path) for a path, (None, None) for nothing."""
    if obj is None:
        return None, None
    if isinstance(obj, Volume):
        if placement:
            raise ValueError(f"{', '.join(placement)}= place arrays; a Volume is placed already")
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
