"""``volcast.TransferFunction``: colour and opacity by value, as ``volcast render --tf`` reads it (its JSON
format, docs/rendering.md), from a preset, a file or control points."""

from __future__ import annotations

import json
import os
from typing import Any, Optional, Sequence

from . import _volcast


class TransferFunction:
    """A 1-D transfer function: piecewise-linear opacity points ``(x, alpha)`` (alpha: the opacity of one
    voxel-length step) and colour points ``(x, r, g, b)`` (sRGB, 0–1) or a colormap spanning the window. ``x`` is
    a fraction of the value range (``units="normalized"``) or a data value (``units="data"``, e.g. Hounsfield)."""

    __slots__ = ("_json",)

    def __init__(
        self,
        opacity: Sequence[Sequence[float]],
        colors: Optional[Sequence[Sequence[float]]] = None,
        colormap: Optional[str] = None,
        units: str = "normalized",
        name: str = "python",
    ) -> None:
        d: dict = {"name": name, "units": units, "opacity": [[float(v) for v in p] for p in opacity]}
        if colors is not None:
            d["colors"] = [[float(v) for v in p] for p in colors]
        if colormap is not None:
            d["colormap"] = colormap
        self._json = _volcast.check_tf(json.dumps(d))

    @classmethod
    def from_json(cls, text: str) -> "TransferFunction":
        tf = cls.__new__(cls)
        tf._json = _volcast.check_tf(text)
        return tf

    @classmethod
    def preset(cls, name: str) -> "TransferFunction":
        """ct-bone, ct-soft-tissue, ct-lung, mr-default or qt-example."""
        tf = cls.__new__(cls)
        tf._json = _volcast.preset_tf(name)
        return tf

    @classmethod
    def load(cls, path: "str | os.PathLike[str]") -> "TransferFunction":
        """A JSON file as ``--tf`` reads it (``render(save_tf=...)`` writes one)."""
        with open(path, encoding="utf-8") as f:
            text = f.read()
        d = json.loads(text)
        if not d.get("name"):
            d["name"] = os.path.splitext(os.path.basename(os.fspath(path)))[0]
        return cls.from_json(json.dumps(d))

    def to_json(self) -> str:
        return self._json

    def save(self, path: "str | os.PathLike[str]") -> None:
        with open(path, "w", encoding="utf-8") as f:
            f.write(self._json)

    def _get(self, key: str) -> Any:
        return json.loads(self._json).get(key)

    @property
    def name(self) -> str:
        return self._get("name")

    @property
    def units(self) -> str:
        return self._get("units")

    @property
    def opacity(self) -> list:
        return self._get("opacity")

    @property
    def colors(self) -> list:
        return self._get("colors")

    @property
    def colormap(self) -> str:
        return self._get("colormap")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, TransferFunction) and json.loads(self._json) == json.loads(other._json)

    def __repr__(self) -> str:
        return f"<volcast.TransferFunction {self.name!r}: {len(self.opacity)} opacity points>"
