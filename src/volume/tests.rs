//! Unit tests of the volume model: types, ranges, scaling, sizes and the errors a user sees.

use super::*;

fn volume(source_type: VoxelType, data: VoxelData) -> Volume {
    let n = data.len() as u32;
    Volume::new("t", [n, 1, 1], [1.0; 3], source_type, data).expect("valid test volume")
}

#[test]
fn voxel_type_names_and_aliases() {
    for t in VoxelType::ALL {
        assert_eq!(VoxelType::parse(t.name()), Some(t));
        assert_eq!(VoxelType::parse(&t.name().to_uppercase()), Some(t));
        assert_eq!(t.to_string(), t.name());
    }
    let aliases = [
        ("u8", VoxelType::U8),
        ("UCHAR", VoxelType::U8),
        ("unsigned_char", VoxelType::U8),
        ("u16", VoxelType::U16),
        ("ushort", VoxelType::U16),
        ("i16", VoxelType::I16),
        ("Short", VoxelType::I16),
        ("f32", VoxelType::F32),
        ("float", VoxelType::F32),
        ("f64", VoxelType::F64),
        ("DOUBLE", VoxelType::F64),
    ];
    for (s, t) in aliases {
        assert_eq!(VoxelType::parse(s), Some(t), "{s}");
    }
    assert_eq!(VoxelType::parse("int32"), Some(VoxelType::I32));
    assert_eq!(VoxelType::parse("unsigned_int"), Some(VoxelType::U32));
    assert_eq!(VoxelType::parse("char"), Some(VoxelType::I8));
    assert_eq!(VoxelType::parse("int64"), None);
    assert_eq!(VoxelType::parse(""), None);
    let sizes: Vec<usize> = VoxelType::ALL.iter().map(|t| t.size()).collect();
    assert_eq!(sizes, [1, 2, 2, 4, 8, 1, 4, 4]);
    let err = "int64".parse::<VoxelType>().unwrap_err();
    assert_eq!(
        err.to_string(),
        "unknown voxel type 'int64': use one of uint8, int8, uint16, int16, uint32, int32, float32, float64"
    );
}

#[test]
fn new_validates() {
    let err = Volume::new("t", [2, 2, 2], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![0; 7])).unwrap_err();
    assert_eq!(err.to_string(), "voxel data for 2x2x2 has 7 values but needs 8");

    let err = Volume::new("t", [2, 0, 2], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![])).unwrap_err();
    assert_eq!(
        err.to_string(),
        "dimensions 2x0x2 contain a zero; every dimension must be at least 1"
    );

    let err = Volume::new("t", [16385, 1, 1], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![])).unwrap_err();
    assert_eq!(
        err.to_string(),
        "dimensions 16385x1x1 exceed the limit of 16384 per axis"
    );

    let err = Volume::new("t", [16384, 16384, 257], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![])).unwrap_err();
    assert_eq!(
        err.to_string(),
        "dimensions 16384x16384x257 make 68987912192 voxels, more than the limit of 68719476736 (2^36)"
    );

    for spacing in [
        [0.0, 1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, f32::NAN],
        [f32::INFINITY, 1.0, 1.0],
    ] {
        let err = Volume::new("t", [1, 1, 1], spacing, VoxelType::U8, VoxelData::U8(vec![0])).unwrap_err();
        assert!(matches!(err, VolumeError::BadSpacing { .. }), "{spacing:?}");
        assert!(err.to_string().starts_with("voxel spacing "), "{err}");
    }
    let err = Volume::new("t", [1, 1, 1], [0.0, 1.0, 1.0], VoxelType::U8, VoxelData::U8(vec![0])).unwrap_err();
    assert_eq!(
        err.to_string(),
        "voxel spacing 0 1 1 is invalid: each must be positive and finite (and dims × spacing finite)"
    );
    // Finite spacing whose box side overflows f32.
    let err = Volume::new(
        "t",
        [4, 1, 1],
        [1e38, 1.0, 1.0],
        VoxelType::U8,
        VoxelData::U8(vec![0; 4]),
    )
    .unwrap_err();
    assert!(matches!(err, VolumeError::BadSpacing { .. }));

    let err = Volume::new("t", [1, 1, 1], [1.0; 3], VoxelType::I16, VoxelData::F32(vec![0.0])).unwrap_err();
    assert_eq!(err.to_string(), "voxel data of kind F32 cannot hold source type int16");
}

#[test]
fn value_and_index_order() {
    let data: Vec<u8> = (0..24).collect();
    let v = Volume::new("t", [4, 3, 2], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    assert_eq!(v.voxel_count(), 24);
    assert_eq!(v.value(0, 0, 0), 0.0);
    assert_eq!(v.value(3, 0, 0), 3.0);
    assert_eq!(v.value(0, 1, 0), 4.0);
    assert_eq!(v.value(0, 0, 1), 12.0);
    assert_eq!(v.value(3, 2, 1), 23.0);
    assert_eq!(v.range, [0.0, 23.0]);
    assert_eq!(v.normalized(3, 2, 1), 1.0);
    assert_eq!(v.normalized(0, 0, 0), 0.0);
    assert!((v.normalized(0, 0, 1) - 12.0 / 23.0).abs() < 1e-15);
    assert_eq!(v.gpu_texel_size(), 1);
    assert_eq!(v.gpu_bytes().len(), 24);
}

#[test]
fn int16_bias_and_range() {
    let raw: [i16; 4] = [-1024, 0, 2986, i16::MIN];
    let stored: Vec<u16> = raw.iter().map(|&v| (i32::from(v) + 32768) as u16).collect();
    assert_eq!(stored, [31744, 32768, 35754, 0]);
    let v = volume(VoxelType::I16, VoxelData::U16(stored));
    assert_eq!(v.value(0, 0, 0), -1024.0);
    assert_eq!(v.value(2, 0, 0), 2986.0);
    assert_eq!(v.value(3, 0, 0), -32768.0);
    assert_eq!(v.range, [-32768.0, 2986.0]);
    assert_eq!(v.gpu_texel_size(), 2);
}

#[test]
fn range_ignores_nan_and_inf() {
    let v = volume(
        VoxelType::F32,
        VoxelData::F32(vec![f32::NAN, -2.5, f32::INFINITY, 4.0, f32::NEG_INFINITY]),
    );
    assert_eq!(v.range, [-2.5, 4.0]);
    assert!(v.normalized(0, 0, 0).is_nan());
    assert_eq!(v.normalized(1, 0, 0), 0.0);
    assert_eq!(v.normalized(3, 0, 0), 1.0);

    let all_nan = volume(VoxelType::F32, VoxelData::F32(vec![f32::NAN; 3]));
    assert_eq!(all_nan.range, [0.0, 0.0]);
    assert!(all_nan.normalized(0, 0, 0).is_nan());
    assert_eq!(all_nan.gpu_scale_bias(), (0.0, 0.0));
}

#[test]
fn scaling_and_int8() {
    let v = volume(VoxelType::I8, VoxelData::U8(vec![0, 255, 128]));
    assert_eq!(
        [v.value(0, 0, 0), v.value(1, 0, 0), v.value(2, 0, 0)],
        [-128.0, 127.0, 0.0]
    );
    assert_eq!(v.range, [-128.0, 127.0]);
    let v = v
        .with_scaling(Scaling {
            slope: -2.0,
            intercept: 1.0,
        })
        .unwrap();
    assert_eq!(v.value(0, 0, 0), 257.0);
    assert_eq!(v.stored(0, 0, 0), -128.0);
    assert_eq!(v.stored_range, [-128.0, 127.0]);
    assert_eq!(v.range, [-253.0, 257.0]);
    for (slope, intercept) in [(0.0, 1.0), (f64::NAN, 0.0), (1.0, f64::INFINITY)] {
        let err = v.clone().with_scaling(Scaling { slope, intercept }).unwrap_err();
        assert!(err.to_string().contains("must be finite and non-zero"), "{err}");
    }
    assert_eq!(v.gpu_memory_bytes(), 3);
}

#[test]
fn constant_volume_normalizes_to_zero() {
    let v = volume(VoxelType::U16, VoxelData::U16(vec![7; 5]));
    assert_eq!(v.range, [7.0, 7.0]);
    assert_eq!(v.normalized(2, 0, 0), 0.0);
    assert_eq!(v.gpu_scale_bias(), (0.0, 0.0));
}

/// What a shader reads from the texture for voxel i.
fn sampled(v: &Volume, i: usize) -> f64 {
    match &v.data {
        VoxelData::U8(d) => f64::from(d[i]) / 255.0,
        VoxelData::U16(d) => f64::from(d[i]) / 65535.0,
        VoxelData::F32(d) => f64::from(d[i]),
    }
}

#[test]
fn gpu_scale_bias_agrees_with_normalized() {
    let volumes = [
        volume(VoxelType::U8, VoxelData::U8(vec![3, 0, 255, 17, 200])),
        volume(VoxelType::U8, VoxelData::U8(vec![40, 41, 90])),
        volume(VoxelType::U16, VoxelData::U16(vec![100, 4095, 0, 65535, 1234])),
        volume(VoxelType::U16, VoxelData::U16(vec![1000, 1001, 1500])),
        volume(
            VoxelType::I16,
            VoxelData::U16([-1024i16, 2986, 0, 40].map(|x| (i32::from(x) + 32768) as u16).to_vec()),
        ),
        volume(
            VoxelType::I16,
            VoxelData::U16([i16::MIN, i16::MAX, -1].map(|x| (i32::from(x) + 32768) as u16).to_vec()),
        ),
        volume(VoxelType::F32, VoxelData::F32(vec![-7.94, 7.94, 0.0, 1.5])),
        volume(VoxelType::F64, VoxelData::F32(vec![-117.843, 2121.07, 3.0, f32::NAN])),
        volume(VoxelType::I8, VoxelData::U8(vec![0, 255, 128, 100])),
        volume(VoxelType::I32, VoxelData::F32(vec![-70000.0, 1.0e6, 3.0])),
        volume(VoxelType::U16, VoxelData::U16(vec![0, 4095, 1024, 7]))
            .with_scaling(Scaling {
                slope: 1.0,
                intercept: -1024.0,
            })
            .unwrap(),
        volume(
            VoxelType::I16,
            VoxelData::U16([-5i16, 300, 0].map(|x| (i32::from(x) + 32768) as u16).to_vec()),
        )
        .with_scaling(Scaling {
            slope: -0.5,
            intercept: 10.0,
        })
        .unwrap(),
    ];
    for v in &volumes {
        let (scale, bias) = v.gpu_scale_bias();
        for i in 0..v.voxel_count() {
            let expected = v.normalized(i as u32, 0, 0);
            // The shader evaluates in f32.
            let got = f64::from(sampled(v, i) as f32 * scale + bias);
            if expected.is_nan() {
                assert!(got.is_nan());
            } else {
                // f32 arithmetic on a value in [0, 1] after cancelling a bias: a few ulps of the bias.
                let tolerance = 1e-6 * (1.0 + f64::from(bias.abs()));
                assert!(
                    (got - expected).abs() < tolerance,
                    "{:?} voxel {i}: {got} vs {expected}",
                    v.source_type
                );
            }
        }
    }
}

#[test]
fn extent_follows_physical_size() {
    let v = Volume::new(
        "ct",
        [256, 256, 108],
        [0.957, 0.957, 1.5],
        VoxelType::U8,
        VoxelData::U8(vec![0; 256 * 256 * 108]),
    )
    .unwrap();
    let e = v.extent();
    assert!((e.x - 1.0).abs() < 1e-6 && (e.y - 1.0).abs() < 1e-6, "{e}");
    assert!((e.z - 0.661).abs() < 1e-3, "{e}");

    let v = Volume::new(
        "t",
        [10, 20, 5],
        [2.0, 1.0, 1.0],
        VoxelType::U8,
        VoxelData::U8(vec![0; 1000]),
    )
    .unwrap();
    assert_eq!(v.extent(), glam::Vec3::new(1.0, 1.0, 0.25));
}

#[test]
fn debug_does_not_dump_voxels() {
    let v = volume(VoxelType::U8, VoxelData::U8(vec![1; 1000]));
    let text = format!("{v:?}");
    assert!(text.contains("VoxelData::U8(len 1000)"), "{text}");
    assert!(text.len() < 600, "{text}");
}
