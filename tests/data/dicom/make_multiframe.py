#!/usr/bin/env python3
"""A multi-frame CT whose frames lie in order in the file (tests/formats/dicom_slices.rs, decoded_finer.rs).

Run from the repository root (writes tests/data/dicom/multiframe_ct_native.dcm only):

    python tests/data/dicom/make_multiframe.py      # a Python with pydicom 3.0.2 and numpy

A classic multi-frame CT (one ImagePositionPatient, SpacingBetweenSlices), 16 columns x 12 rows x 6 frames of
int16 with every allocated bit stored, rescale intercept -1024, explicit VR little endian, frames stored in slice
order: its frames lie in the file as a raw volume's voxels do, so volcast reads it by box. Deterministic: fixed UIDs.
"""

from pathlib import Path

import numpy as np
from pydicom.dataset import FileDataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian

HERE = Path(__file__).resolve().parent
COLS, ROWS, N = 16, 12, 6
ROOT_UID = "1.2.826.0.1.3680043.8.498.12"

meta = FileMetaDataset()
meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
meta.MediaStorageSOPInstanceUID = ROOT_UID + ".9.1"
meta.TransferSyntaxUID = ExplicitVRLittleEndian
path = HERE / "multiframe_ct_native.dcm"
ds = FileDataset(str(path), {}, file_meta=meta, preamble=b"\0" * 128)
ds.SOPClassUID = meta.MediaStorageSOPClassUID
ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
ds.StudyInstanceUID = ROOT_UID + ".9.2"
ds.SeriesInstanceUID = ROOT_UID + ".9.3"
ds.Modality = "CT"
ds.Rows, ds.Columns, ds.NumberOfFrames = ROWS, COLS, N
ds.SamplesPerPixel = 1
ds.PhotometricInterpretation = "MONOCHROME2"
ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
ds.PixelSpacing = [0.5, 0.75]
ds.SliceThickness = 2.0
ds.SpacingBetweenSlices = 2.0
ds.ImagePositionPatient = [-4.0, -4.5, 10.0]
ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
ds.RescaleSlope, ds.RescaleIntercept = 1, -1024
k, j, i = np.mgrid[0:N, 0:ROWS, 0:COLS]
values = (900 + 37 * i - 23 * j + 151 * k + (i * j * k) % 7).astype(np.int16)
ds.PixelData = values.tobytes()
ds.save_as(path, enforce_file_format=True)
print(path, values.min(), values.max())
