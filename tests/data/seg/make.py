"""Writes two.seg.nrrd and overlap.seg.nrrd with slicerio (3D Slicer's segmentation I/O), as tests/data/README.md says.

Run in a virtual environment with `pip install slicerio==1.4.0 numpy` from this repository's root."""

import numpy as np
import slicerio

shape = (12, 10, 8)
# slicerio's voxels are (i, j, k); the affine maps them to LPS millimetres.
ijk_to_lps = np.array([[-2.0, 0, 0, 10], [0, -2.0, 0, 20], [0, 0, 2.0, -5], [0, 0, 0, 1]])
i, j, k = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
liver = (i < 6) & (j >= 2) & (j < 8) & (k >= 1) & (k < 7)  # 216 voxels
tumour = (i >= 7) & (i < 11) & (j >= 3) & (j < 6) & (k >= 2) & (k < 5)  # 36 voxels
core = (i >= 2) & (i < 4) & (j >= 4) & (j < 6) & (k >= 3) & (k < 5)  # 8 voxels, inside the liver
for name, segments in [
    ("two", [("liver", liver, [0.87, 0.51, 0.4]), ("tumour", tumour, [0.9, 0.9, 0.2])]),
    ("overlap", [("liver", liver, [0.87, 0.51, 0.4]), ("tumour", tumour, [0.9, 0.9, 0.2]), ("core", core, [0.2, 0.4, 1.0])]),
]:
    seg = slicerio.create_segmentation(shape, ijk_to_lps)
    for segment, mask, colour in segments:
        # A segment overlapping another goes into a new layer (the voxels become 4-D, the layer axis first).
        slicerio.add_segment(seg, mask, {"id": segment, "name": segment, "color": colour})
    slicerio.write_segmentation(f"tests/data/seg/{name}.seg.nrrd", seg)
