// Generated from tests/data/world/expected.json (written by tests/data/world/make.py); the comment above each
// entry is the library call that gave its affine.
const EXPECTED: &[Expected] = &[
    // nibabel.load(path).affine
    Expected {
        path: "tests/data/world/nifti_ras.nii.gz",
        affine: [
            [3.0, 0.0, 0.0, -52.5],
            [0.0, 3.0, 0.0, -58.5],
            [0.0, 0.0, 3.0, -50.0],
        ],
        axes: Some("RAS"),
        handedness: "right",
    },
    // nibabel.load(path).affine
    Expected {
        path: "tests/data/world/nifti_las_qform.nii.gz",
        affine: [
            [-2.5, 0.0, 0.0, 46.0],
            [0.0, 3.0, 0.0, -53.0],
            [0.0, 0.0, 3.5, -52.0],
        ],
        axes: Some("LAS"),
        handedness: "left",
    },
    // nibabel.load(path).affine
    Expected {
        path: "tests/data/world/nifti_coronal.nii.gz",
        affine: [
            [-2.0, 0.0, 0.0, 45.0],
            [0.0, 0.0, -4.0, 56.0],
            [0.0, -2.0, 0.0, 50.0],
        ],
        axes: Some("LIP"),
        handedness: "right",
    },
    // nibabel.load(path).affine
    Expected {
        path: "tests/data/world/nifti_oblique.nii.gz",
        affine: [
            [1.879385232925415, -0.8420602083206177, 0.20786911249160767, -32.07932662963867],
            [0.6840403079986572, 2.3135414123535156, -0.5711156725883484, -64.32946014404297],
            [0.0, 0.43412044644355774, 3.4468271732330322, -59.19353103637695],
        ],
        axes: Some("RAS"),
        handedness: "right",
    },
    // nibabel.load(path).affine
    Expected {
        path: "tests/data/world/nifti_pixdim_only.nii.gz",
        affine: [
            [-3.0, 0.0, 0.0, 52.5],
            [0.0, 2.5, 0.0, -53.75],
            [0.0, 0.0, 3.5, -50.75],
        ],
        axes: Some("LAS"),
        handedness: "left",
    },
    // FLIP @ [GetDirection() @ diag(GetSpacing()) | GetOrigin()] from sitk.ReadImage(path); FLIP = diag(-1, -1, 1, 1) (ITK physical space is LPS)
    Expected {
        path: "tests/data/world/mha_rip.mha",
        affine: [
            [-2.0, 0.0, 0.0, 45.5],
            [0.0, 0.0, 3.0, -54.0],
            [0.0, 2.5, 0.0, -48.25],
        ],
        axes: Some("LSA"),
        handedness: "right",
    },
    // pynrrd nrrd.read(path): A[:3,:3] = S @ header['space directions'].T, A[:3,3] = S @ header['space origin'], S = the file space -> RAS sign matrix
    Expected {
        path: "tests/data/world/nrrd_lps.nrrd",
        affine: [
            [0.0, 0.0, 4.0, -44.5],
            [-2.4453690018345142, -0.4574057197990706, 0.0, 63.76983695655473],
            [0.5197792270443984, -2.151924721614373, 0.0, 41.8751983494388],
        ],
        axes: Some("PIR"),
        handedness: "right",
    },
    // pynrrd nrrd.read(path): A[:3,:3] = S @ header['space directions'].T, A[:3,3] = S @ header['space origin'], S = the file space -> RAS sign matrix
    Expected {
        path: "tests/data/world/nrrd_ras.nhdr",
        affine: [
            [2.5, 0.0, 0.0, -49.0],
            [0.0, -3.0, 0.0, 56.0],
            [0.0, 0.0, 4.0, -50.0],
        ],
        axes: Some("RPS"),
        handedness: "left",
    },
    // vtkStructuredPointsReader: diag(GetSpacing()) with GetOrigin() (no orientation in the format)
    Expected {
        path: "tests/data/world/vtk_legacy.vtk",
        affine: [
            [3.0, 0.0, 0.0, -46.5],
            [0.0, 2.5, 0.0, -53.5],
            [0.0, 0.0, 3.5, -51.0],
        ],
        axes: None,
        handedness: "right",
    },
    // SimpleITK ImageSeriesReader (files from GetGDCMSeriesFileNames): FLIP @ [GetDirection() @ diag(GetSpacing()) | GetOrigin()]
    Expected {
        path: "tests/data/world/dicom_series",
        affine: [
            [-2.0, 0.0, 0.0, 46.0],
            [0.0, -2.5, 0.0, 55.75],
            [0.0, 0.0, 6.5, -48.75],
        ],
        axes: Some("LPS"),
        handedness: "right",
    },
    // SimpleITK ImageSeriesReader (files from GetGDCMSeriesFileNames): FLIP @ [GetDirection() @ diag(GetSpacing()) | GetOrigin()]
    Expected {
        path: "tests/data/world/dicom_oblique",
        affine: [
            [-2.0, 0.0, 0.0, 46.0],
            [0.0, -2.4148145657226716, 1.8117333157176412, 41.236379953014],
            [0.0, 0.6470476127562992, 6.761480784023493, -58.241889162425],
        ],
        axes: Some("LPS"),
        handedness: "right",
    },
    // SimpleITK ImageSeriesReader (files from GetGDCMSeriesFileNames): FLIP @ [GetDirection() @ diag(GetSpacing()) | GetOrigin()]
    Expected {
        path: "tests/data/world/dicom_uneven",
        affine: [
            [-2.0, 0.0, 0.0, 46.0],
            [0.0, -2.5, 0.0, 55.75],
            [0.0, 0.0, 6.266666666666667, -47.0],
        ],
        axes: Some("LPS"),
        handedness: "right",
    },
    // nibabel.load(path).affine
    Expected {
        path: "../shared/data/native/motor_zmap/image_10426.nii.gz",
        affine: [
            [-3.0, 0.0, 0.0, 78.0],
            [0.0, 3.0, 0.0, -112.0],
            [0.0, 0.0, 3.0, -50.0],
        ],
        axes: Some("LAS"),
        handedness: "left",
    },
    // nibabel.load(path).affine
    Expected {
        path: "../shared/data/native/colin27_t1/ch2.nii.gz",
        affine: [
            [1.0, 0.0, 0.0, -90.0],
            [0.0, 1.0, 0.0, -125.0],
            [0.0, 0.0, 1.0, -71.0],
        ],
        axes: Some("RAS"),
        handedness: "right",
    },
    // nibabel.load(path).affine
    Expected {
        path: "../shared/data/native/dwi_b0_ascm/ascm_out_test.nii.gz",
        affine: [
            [-3.999786615371704, -5.817553756060079e-06, -0.05163605883717537, 118.76344299316406],
            [0.023993905633687973, -3.2563929557800293, -2.9034810066223145, 132.19818115234375],
            [-0.03362608328461647, -2.322908639907837, 4.070274353027344, 22.819555282592773],
        ],
        axes: Some("LPS"),
        handedness: "right",
    },
    // nibabel.load(path).affine
    Expected {
        path: "../shared/data/native/dwi_s0_10slices/S0_10slices.nii.gz",
        affine: [
            [2.0, 0.0, 30.0, -123.3592529296875],
            [0.0, 2.0, 30.0, -102.854736328125],
            [-0.0, -0.0, 32.0, -38.755863189697266],
        ],
        axes: Some("RAS"),
        handedness: "right",
    },
    // SimpleITK ImageSeriesReader, LPS->RAS
    Expected {
        path: "../shared/data/native/brain_pd_mr",
        affine: [
            [-0.859375, 0.0, 0.0, 110.5],
            [0.0, -0.8516062114375684, 0.9391762988623816, 78.3063],
            [0.0, 0.1152920260293466, 6.937239263559875, -72.7575],
        ],
        axes: Some("LPS"),
        handedness: "right",
    },
];
