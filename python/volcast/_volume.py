"""``volcast.Volume``: a volume in memory, from a file (``volcast.open``) or a numpy array (``Volume.from_array``)."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _volcast

_DTYPES = {
    np.dtype(np.uint8): "uint8",
    np.dtype(np.int8): "int8",
    np.dtype(np.uint16): "uint16",
    np.dtype(np.int16): "int16",
    np.dtype(np.uint32): "uint32",
    np.dtype(np.int32): "int32",
    np.dtype(np.float32): "float32",
    np.dtype(np.float64): "float64",
}


class Volume:
    """A 3-D volume volcast renders: voxels, their type and their placement in space.

    Axis order: ``array`` has numpy's shape (z, y, x), x varying fastest, as ``SimpleITK.GetArrayFromImage`` gives;
    ``dims``, ``spacing`` and ``affine`` follow (x, y, z), as SimpleITK's ``GetSize``/``GetSpacing`` and NIfTI's
    affine do: ``affine @ (x, y, z, 1)`` is the world position of ``array[z, y, x]`` (RAS+ millimetres where
    ``anatomical``).
    """

    __slots__ = ("_native", "__weakref__")

    def __init__(self, native: Any) -> None:
        self._native = native

    @classmethod
    def from_array(
        cls,
        array: Any,
        spacing: Optional[Sequence[float]] = None,
        affine: Optional[Any] = None,
        origin: Optional[Sequence[float]] = None,
        name: str = "array",
    ) -> "Volume":
        """A volume of a 3-D array of shape (z, y, x), uint8, int8, uint16, int16, uint32, int32, float32 or float64.

        ``spacing`` (x, y, z) and ``origin`` (the world position of voxel (0, 0, 0)) place it; or ``affine``, a 4×4
        voxel-(x, y, z)-to-RAS+ matrix as nibabel's, which makes the volume anatomical (viewed from anterior, with
        L/R/A/P/S/I labels). The voxels are copied once, into volcast's own storage (``Volume.array`` then views
        them without a copy). Raises ``ValueError`` for another dtype or ndim, for NaN or infinite values, and for
        a spacing or affine that places no volume.
        """
        a = np.asarray(array)
        if a.ndim != 3:
            raise ValueError(f"a 3-D array of shape (z, y, x) is needed; got {a.ndim}-D, shape {a.shape}")
        dtype = _DTYPES.get(a.dtype.newbyteorder("="))
        if dtype is None:
            raise ValueError(
                f"arrays of dtype {a.dtype} are not volumes volcast renders; use one of "
                + ", ".join(sorted(set(_DTYPES.values())))
            )
        a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("="))
        if affine is not None:
            if spacing is not None or origin is not None:
                raise ValueError("give affine= or spacing=/origin=, not both")
            m = np.asarray(affine, dtype=float)
            if m.shape != (4, 4):
                raise ValueError(f"affine= must be 4x4; got shape {m.shape}")
            return cls(_volcast.from_bytes(a, dtype, name, (1.0, 1.0, 1.0), m.tolist(), True))
        s = tuple(float(v) for v in (spacing if spacing is not None else (1.0, 1.0, 1.0)))
        if len(s) != 3:
            raise ValueError(f"spacing= takes three values (x, y, z); got {len(s)}")
        if origin is None:
            return cls(_volcast.from_bytes(a, dtype, name, s))
        o = [float(v) for v in origin]
        if len(o) != 3:
            raise ValueError(f"origin= takes three values (x, y, z); got {len(o)}")
        m = [[s[0], 0, 0, o[0]], [0, s[1], 0, o[1]], [0, 0, s[2], o[2]], [0, 0, 0, 1]]
        return cls(_volcast.from_bytes(a, dtype, name, s, m, False))

    @property
    def array(self) -> np.ndarray:
        """The voxels, shape (z, y, x), read-only: a view without a copy for uint8, uint16 and float32 (and for
        float64, int32 and uint32, which volcast holds as float32); a copy for int8 and int16."""
        return self._native.array

    @property
    def dims(self) -> Tuple[int, int, int]:
        """Voxels along (x, y, z)."""
        return self._native.dims

    @property
    def shape(self) -> Tuple[int, int, int]:
        """The array's shape, (z, y, x)."""
        x, y, z = self._native.dims
        return (z, y, x)

    @property
    def dtype(self) -> str:
        """The voxel type of the file or array (uint8, int16, float64, ...)."""
        return self._native.dtype

    @property
    def spacing(self) -> Tuple[float, float, float]:
        """The voxel size along (x, y, z)."""
        return self._native.spacing

    @property
    def affine(self) -> np.ndarray:
        """The 4×4 voxel-(x, y, z)-to-world matrix (RAS+ millimetres where ``anatomical``)."""
        return self._native.affine

    @property
    def anatomical(self) -> bool:
        """Whether the placement is in patient space (RAS+)."""
        return self._native.anatomical

    @property
    def value_range(self) -> Tuple[float, float]:
        """The smallest and largest finite value (after the file's rescale, if any)."""
        return self._native.value_range

    @property
    def name(self) -> str:
        return self._native.name

    @property
    def notes(self) -> List[str]:
        """What the reader noted: orientation ignored, a coarser level shown, series skipped, ..."""
        return self._native.notes

    def info(self) -> Dict[str, Any]:
        """``volcast info --json`` of this volume, as a dict."""
        return json.loads(self._native.info_json())

    def __repr__(self) -> str:
        x, y, z = self.dims
        return f"<volcast.Volume {self.name!r} {x}x{y}x{z} {self.dtype}, spacing {self.spacing}>"


def open(path: "str | os.PathLike[str]", **options: Any) -> Volume:  # noqa: A001  (volcast.open, as the issue names it)
    """Reads a volume file, DICOM folder or OME-Zarr store as ``volcast render`` does (every format the command
    line reads). Keywords are the command line's volume options: ``dims=(w, h, d)``, ``type="int16"``,
    ``spacing=(sx, sy, sz)``, ``endian=``, ``header_bytes=``, ``series=``, ``channel=``, ``time=``, ``max_dim=``,
    ``host_budget="4G"``, ``cache_dir=``, ``no_cache=True``, ``array=`` (a VTK file's array). Raises ``OSError``
    naming the file and the problem where it cannot be read."""
    from ._options import argv as to_argv

    argv = to_argv("open", options) + ["--", os.fspath(path)]
    native = _volcast.open(argv)
    return Volume(native)


def builtin(name: str = "helix", size: Optional[int] = None) -> Volume:
    """A built-in test volume: helix, box, colormap or marschner-lobb (edge ``size``, default 256; 41 for
    marschner-lobb)."""
    return Volume(_volcast.builtin(name, size))
