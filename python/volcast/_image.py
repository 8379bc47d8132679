"""``volcast.Image``: a rendered frame, a numpy array of shape (H, W, 4) uint8 RGBA that shows itself in Jupyter."""

from __future__ import annotations

import struct
import zlib

import numpy as np


def png_bytes(rgba: np.ndarray) -> bytes:
    """``rgba`` (H, W, 4) uint8 as PNG file bytes (8-bit RGBA, no filter)."""
    a = np.ascontiguousarray(rgba, dtype=np.uint8)
    h, w = a.shape[:2]
    rows = np.concatenate([np.zeros((h, 1), np.uint8), a.reshape(h, w * 4)], axis=1)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6)) + chunk(b"IEND", b"")


class Image(np.ndarray):
    """A rendered frame: shape (H, W, 4), uint8, RGBA (sRGB colour, straight alpha). Jupyter shows it inline.
    ``Image(array)`` makes one of any (H, W, 4) uint8 array, such as frames put side by side."""

    def __new__(cls, array: np.ndarray) -> "Image":
        a = np.asarray(array)
        if a.ndim != 3 or a.shape[2] != 4 or a.dtype != np.uint8:
            raise ValueError(f"an Image is (H, W, 4) uint8; got {a.shape} {a.dtype}")
        return a.view(cls)

    #: With ``render(timings=True)``: medians in ms of ``frames=`` frames (wall_ms, gpu_ms, march_ms, ...).
    timings: dict
    #: With ``render(memory=True)``: the command line's memory line.
    memory: str

    def _repr_png_(self) -> bytes:
        return png_bytes(np.asarray(self))

    def save(self, path: str) -> None:
        """Writes the frame as a PNG file."""
        with open(path, "wb") as f:
            f.write(png_bytes(np.asarray(self)))
