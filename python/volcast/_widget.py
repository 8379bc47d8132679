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
    window = options.get("window") or (0.0, 1.0)
    azimuth = w.FloatSlider(value=float(options.get("azimuth", 35.0)), min=-180, max=180, step=5, description="azimuth")
    win = w.FloatRangeSlider(value=tuple(window), min=0.0, max=1.0, step=0.01, description="window")
    picture = w.Image(format="png")

    def update(*_: Any) -> None:
        frame = scene.render(azimuth=azimuth.value, window=tuple(win.value))
        picture.value = png_bytes(frame)

    azimuth.observe(update, names="value")
    win.observe(update, names="value")
    update()
    box = w.VBox([picture, azimuth, win])
    box.update = update
    return box
