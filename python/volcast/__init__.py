"""volcast for Python: the volume ray caster over numpy arrays, scans and microscopy.

``volcast.render(array_or_volume_or_path, **options)`` renders one frame; its keywords are ``volcast render``'s
options (``volcast.options()`` lists them), with the same defaults and the same images. ``volcast.open`` reads any
file the command line reads; ``Volume.from_array`` takes a numpy array of shape (z, y, x). ``volcast.movie``
writes turntables and keyframe movies, ``volcast.view`` opens the desktop viewer, ``volcast.widget`` a notebook
widget. The guide: docs/python.md in the repository.
"""

from __future__ import annotations

import atexit
import builtins
import os
import pathlib
import sys
from typing import Any, Dict, Optional

import numpy as np

from . import _volcast
from ._image import Image, png_bytes
from ._inputs import as_source
from ._options import Option, argv as _argv, options
from ._tf import TransferFunction
from ._volume import Volume, builtin, open

__all__ = [
    "Image", "Option", "Scene", "TransferFunction", "Volume", "builtin", "device", "movie", "open", "options",
    "png_bytes", "render", "shutdown", "view", "view_state", "volume", "widget",
]
__version__ = "0.1.0"
builtins_open = builtins.open  # `open` here is volcast.open


#: The options a ``camera=`` mapping may hold (the command line's camera options).
CAMERA = ("azimuth", "elevation", "distance", "eye", "look_at", "view_dir", "view", "fov", "ortho", "voxel_axes")


def _camera(options_: Dict[str, Any]) -> None:
    """Spreads ``camera={"azimuth": 30, ...}`` into the options it stands for."""
    camera = options_.pop("camera", None)
    if camera is None:
        return
    unknown = set(camera) - set(CAMERA)
    if unknown:
        raise TypeError(f"camera= takes {', '.join(CAMERA)}; not {', '.join(sorted(unknown))}")
    twice = set(camera) & set(options_)
    if twice:
        raise TypeError(f"{', '.join(sorted(twice))} given both in camera= and as keywords")
    options_.update(camera)


def _held_layers(options_: Dict[str, Any], placement: Dict[str, Any]) -> list:
    """The layers of ``overlay=`` and ``labels=`` held in memory, as (native volume, is labels); their paths stay
    in ``options_``. An array is placed like the volume (its ``spacing=``, ``origin=`` or ``affine=``); a Volume, a
    nibabel or SimpleITK image by its own placement."""
    held = []
    for key, labels in (("overlay", False), ("labels", True)):
        items = options_.get(key)
        if items is None:
            continue
        if not isinstance(items, (list, tuple)):
            items = [items]
        paths = []
        for item in items:
            if isinstance(item, (str, os.PathLike)):
                paths.append(os.fspath(item))
                continue
            array_like = isinstance(item, np.ndarray) or (
                not isinstance(item, Volume) and type(item).__module__.split(".")[0] not in ("nibabel", "SimpleITK")
            )
            volume, _ = as_source(item, **(placement if array_like else {}))
            held.append((volume._native, labels))
        if paths:
            options_[key] = paths
        else:
            del options_[key]
    return held


def _command(source: Any, placement: Dict[str, Any], command: str, options_: Dict[str, Any]):
    """The native volume (or None), the argument list and the transfer function's JSON of a call."""
    _camera(options_)
    placement = {k: v for k, v in placement.items() if v is not None}
    if isinstance(source, (str, os.PathLike)) or source is None:
        # A file is placed by its header; spacing= overrides it as --spacing does.
        if set(placement) - {"spacing"}:
            raise ValueError("origin= and affine= place arrays; a file is placed by its header (or spacing=)")
        if "spacing" in placement:
            options_["spacing"] = placement.pop("spacing")
    volume, path = as_source(source, **placement)
    tf = options_.pop("tf", None)
    tf_json = None
    if isinstance(tf, TransferFunction):
        tf_json = tf.to_json()
    elif tf is not None:
        options_["tf"] = tf
    argv = _argv(command, options_)
    if path is not None:
        argv += ["--", path]
    return (volume._native if volume is not None else None), argv, tf_json


def render(
    volume: Any = None,
    *,
    spacing: Any = None,
    affine: Any = None,
    origin: Any = None,
    **options: Any,
) -> Image:
    """Renders one frame of ``volume`` as ``volcast render`` does and returns it: an ``Image``, a numpy array of
    shape (H, W, 4) uint8 (RGBA) that Jupyter shows inline.

    ``volume`` is a numpy array of shape (z, y, x) (placed by ``spacing``/``origin`` or ``affine``, as
    ``Volume.from_array``), a ``Volume``, a path, a nibabel or SimpleITK image, or a zarr or dask array; or None with
    ``builtin="helix"``. Every other keyword is an option of ``volcast render``: ``size=(640, 480)``,
    ``azimuth=30`` (or ``camera={"azimuth": 30, "elevation": 10}``), ``view="left"``, ``preset="ct-bone"`` or ``tf=TransferFunction(...)``, ``mode="mip"``,
    ``window=("10%", "100%")`` (or data units, ``(-100, 300)``), ``shading=True``, ``quality="draft"``, ``clip_plane=(0, 0, 1, 0)``, ``output="f.png"``
    (also writes the PNG), ... ``timings=True`` adds ``frame.timings``, the medians (ms) of ``frames=`` more frames
    (wall, GPU, per pass); ``memory=True`` adds ``frame.memory``, the command line's memory line. ``overlay=[...]``
    and ``labels=[...]`` add layers composited in depth (docs/layers.md): paths, or arrays placed like ``volume``
    (or a ``Volume``, a nibabel or SimpleITK image, placed by their own affine). The device is made once per process and reused; a volume rendered again is not
    uploaded again. Raises ``ValueError`` for a bad option or array, ``OSError`` for a file it cannot read,
    ``RuntimeError`` where there is no Vulkan device (saying what to install).
    """
    placement = {k: v for k, v in dict(spacing=spacing, affine=affine, origin=origin).items() if v is not None}
    layers = _held_layers(options, placement)
    native, argv, tf_json = _command(volume, dict(spacing=spacing, affine=affine, origin=origin), "render", options)
    pixels, (timings, memory) = _volcast.render(native, argv, tf_json, layers)
    frame = pixels.view(Image)
    if timings:
        frame.timings = dict(timings)
    if memory is not None:
        frame.memory = memory
    return frame


def movie(
    volume: Any = None,
    output: "str | os.PathLike[str]" = "volcast.png",
    *,
    turntable: Optional[int] = None,
    keyframes: Optional[list] = None,
    spacing: Any = None,
    affine: Any = None,
    origin: Any = None,
    **options: Any,
) -> pathlib.Path:
    """Writes a turntable (``turntable=N`` frames once around) or a keyframed movie (``keyframes=[...]`` and
    ``frames=N``) as ``volcast render --turntable`` does: ``NAME-0000.png`` … beside ``output`` (NAME.png) and a
    looping ``NAME.gif`` (``fps=``), which is returned. A keyframe is a view-state file (the viewer's F12, or
    ``view_state``) or a dict of options (``{"azimuth": 90, "window": ("20%", "100%")}``) over the other keywords.
    Other keywords as ``render``. Ctrl+C stops it and removes what it wrote."""
    placement = dict(spacing=spacing, affine=affine, origin=origin)
    if keyframes and any(isinstance(k, dict) for k in keyframes):
        # Read once, not once per keyframe.
        held = None if volume is None else _to_volume(volume, placement)
        return _keyframed(held, output, keyframes, options)
    options.update(output=output, turntable=turntable, keyframes=keyframes)
    layers = _held_layers(options, {k: v for k, v in placement.items() if v is not None})
    native, argv, tf_json = _command(volume, placement, "render", options)
    _volcast.movie(native, argv, tf_json, layers)
    out = pathlib.Path(output)
    return out.with_name(out.stem + ".gif")


#: Options of a keyframed movie itself; the others make its keyframes' view states.
_MOVIE = ("frames", "fps", "validate", "device", "texture", "brick_size", "host_budget", "gpu_budget", "builtin",
          "builtin_size")


def _keyframed(volume: Any, output: Any, keyframes: list, options: Dict[str, Any]) -> pathlib.Path:
    """A keyframed movie of dicts of options: each becomes a view-state file in a temporary folder."""
    import tempfile

    movie_options = {k: options.pop(k) for k in _MOVIE if k in options}
    source = {k: movie_options[k] for k in ("builtin", "builtin_size") if k in movie_options}
    with tempfile.TemporaryDirectory(prefix="volcast-keyframes-") as folder:
        files = []
        for k, key in enumerate(keyframes):
            path = key
            if isinstance(key, dict):
                path = os.path.join(folder, f"key-{k:04}.json")
                with builtins_open(path, "w", encoding="utf-8") as f:
                    f.write(view_state(volume, **{**options, **source, **key}))
            files.append(os.fspath(path))
        return movie(volume, output, keyframes=files, **movie_options)


def view_state(volume: Any = None, **options: Any) -> str:
    """The view state of ``render``'s options on ``volume``, as JSON: what the viewer's F12 saves and
    ``render(state=...)`` and ``movie(keyframes=[...])`` read (camera, transfer function, mode, lighting, size, ...).
    """
    placement = {k: options.pop(k) for k in ("spacing", "affine", "origin") if k in options}
    native, argv, tf_json = _command(volume, placement, "render", options)
    return _volcast.view_state(native, argv, tf_json)


def view(volume: Any = None, **options: Any) -> None:
    """Opens the desktop viewer on ``volume`` (as ``render`` takes it; None: the built-in helix) with ``volcast
    view``'s options (``slices=True``, ``preset=``, ``quality=``, ``size=(1280, 800)``, ...); returns when the window
    closes. ``overlay=`` and ``labels=`` take paths, arrays (placed like the volume) and images, as ``render``'s.
    Needs a display."""
    placement = {k: options.pop(k) for k in ("spacing", "affine", "origin") if k in options}
    layers = _held_layers(options, {k: v for k, v in placement.items() if v is not None})
    native, argv, _ = _command(volume, placement, "view", options)
    _volcast.view(native, argv, layers)


def volume(obj: Any, **placement: Any) -> Volume:
    """Anything ``render`` takes as a ``Volume``: an array (placed by ``spacing``/``origin``/``affine``), a nibabel
    or SimpleITK image (in its patient space), a zarr or dask array, a path (read by ``volcast.open``)."""
    return _to_volume(obj, placement)


def _to_volume(obj: Any, placement: Dict[str, Any]) -> Volume:
    vol, path = as_source(obj, **{k: v for k, v in placement.items() if v is not None})
    if vol is None and path is not None:
        return open(path)
    if vol is None:
        raise TypeError("no volume given")
    return vol


class Scene:
    """A volume with render options, rendered on demand: Jupyter shows it inline; ``scene.render(**changes)``
    renders it with some options changed, ``scene.widget()`` adds sliders for the azimuth and the window."""

    def __init__(self, volume: Any, **options: Any) -> None:
        if isinstance(volume, (str, os.PathLike)) or volume is None:
            # A file is read at each render, its placement options with the others.
            self.volume, self.options = volume, options
            return
        placement = {k: options.pop(k) for k in ("spacing", "affine", "origin") if k in options}
        self.volume = _to_volume(volume, placement)
        self.options = options

    def render(self, **changes: Any) -> Image:
        return render(self.volume, **{**self.options, **changes})

    def _repr_png_(self) -> bytes:
        return png_bytes(np.asarray(self.render()))

    def widget(self, **changes: Any) -> Any:
        return widget(self.volume, **{**self.options, **changes})


def widget(volume: Any, **options: Any) -> Any:
    """A notebook widget: the rendered frame with a slider for the azimuth and one for the window (ipywidgets,
    ``pip install ./python[jupyter]``). Returns the widget box."""
    from ._widget import make_widget

    return make_widget(Scene(volume, **options))


def device() -> str:
    """The name of the Vulkan device volcast renders on (made now if not yet)."""
    return _volcast.device_name()


def shutdown() -> Optional[Dict[str, int]]:
    """Destroys the device (the next render makes it again). Returns None if there was none, else the validation
    layer's counts, ``{"validating": bool, "errors": n, "warnings": n}``, leaked objects included (validation is on
    with ``VOLCAST_VALIDATION=1`` or ``validate=True``)."""
    closed = _volcast.shutdown()
    if closed is None:
        return None
    validating, errors, warnings = closed
    return {"validating": validating, "errors": errors, "warnings": warnings}


@atexit.register
def _at_exit() -> None:
    counts = shutdown()
    if counts and counts["validating"]:
        print(f"volcast validation: {counts['errors']} errors, {counts['warnings']} warnings", file=sys.stderr)
