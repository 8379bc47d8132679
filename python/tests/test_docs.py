"""The worked example of docs/python.md, run as written (its data path made absolute)."""

import os
import re

import numpy as np
from PIL import Image as PILImage

from conftest import ROOT


def test_the_worked_example_runs(shared, tmp_path, monkeypatch):
    text = (ROOT / "docs" / "python.md").read_text()
    section = text.split("## Worked example", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    code = code.replace("../shared/data", str(shared))
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "docs/python.md", "exec"), {})
    views = np.asarray(PILImage.open(tmp_path / "three_views.png"))
    assert views.shape == (256, 768, 4)
    thirds = [views[:, k * 256:(k + 1) * 256, :3] for k in range(3)]
    assert all(t.max() > 60 for t in thirds), "each view shows the head"
    assert not np.array_equal(thirds[0], thirds[1])
    assert (tmp_path / "turntable.gif").stat().st_size > 0
    assert len(list(tmp_path.glob("turntable-*.png"))) == 12
    assert os.path.exists(tmp_path / "turntable-0011.png")
