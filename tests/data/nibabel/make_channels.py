"""A 5-D NIfTI for tests/formats/headers.rs: three channels along dim[5], as nibabel writes a multi-channel image.

Run from this folder in a scratch venv:  pip install nibabel==5.4.2 numpy; python make_channels.py
Voxel (x, y, z) of channel c holds 100·c + x + 6·y + 30·z (float32, gzip), 6×5×4 voxels of 1.5 mm, one time point.
"""

import os

import nibabel as nib
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))

x, y, z, t, c = np.meshgrid(np.arange(6), np.arange(5), np.arange(4), np.arange(1), np.arange(3), indexing="ij")
data = (100 * c + x + 6 * y + 30 * z).astype(np.float32)
img = nib.Nifti1Image(data, np.diag([1.5, 1.5, 1.5, 1.0]))
nib.save(img, os.path.join(HERE, "channels_5d.nii.gz"))
back = nib.load(os.path.join(HERE, "channels_5d.nii.gz"))
assert back.shape == (6, 5, 4, 1, 3), back.shape
assert back.get_fdata()[1, 2, 3, 0, 2] == 200 + 1 + 12 + 90
print("wrote channels_5d.nii.gz", back.shape, back.header["dim"])
