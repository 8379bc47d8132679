"""``volcast.widget``: a rendered frame with sliders for the azimuth and the window (ipywidgets)."""

from __future__ import annotations

from typing import Any


def make_widget(scene: Any) -> Any:
    try:
        import ipywidgets as w
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("volcast.widget needs ipywidgets: pip install './python[jupyter]'") from e
    from ._image import png_bytes

    options = scene.options
    azimuth = w.FloatSlider(value=float(options.get("azimuth", 35.0)), min=-180, max=180, step=5, description="azimuth")
    # The window as percentages of the data's range (a bare number would be in the data's units).
    win = w.FloatRangeSlider(value=_percentages(options.get("window")), min=0.0, max=100.0, step=1.0,
                             description="window %")
    picture = w.Image(format="png")

    def update(*_: Any) -> None:
        lo, hi = win.value
        frame = scene.render(azimuth=azimuth.value, window=(f"{lo:g}%", f"{hi:g}%"))
        picture.value = png_bytes(frame)

    azimuth.observe(update, names="value")
    win.observe(update, names="value")
    update()
    box = w.VBox([picture, azimuth, win])
    box.update = update
    return box


def _percentages(window: Any) -> tuple:
    """The slider's start: a window given as percentages ("10%", "90%"), else the whole range."""
    try:
        lo, hi = (float(str(v).rstrip("%")) for v in window if str(v).endswith("%"))
        return (lo, hi)
    except (TypeError, ValueError):
        return (0.0, 100.0)
