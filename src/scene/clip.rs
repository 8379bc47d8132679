//! Rule 10's arbitrary clipping plane (see `RenderSettings`'s rules): a half-space of the world the volume is
//! placed in, kept beside the axis-aligned slab box. Pure data and maths; the shaders clip each ray's segment by
//! the texture-space plane [`ClipPlane::texture_plane`] gives, and the CPU reference re-derives it from the rule.

use glam::{DMat3, DMat4, DVec3, Vec3};

/// What is wrong with a clipping plane a user gave.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClipPlaneError {
    #[error("clip plane normal {0} must be a finite, non-zero direction")]
    Normal(Vec3),
    #[error("clip plane offset {0} must be a finite number of millimetres")]
    Offset(f32),
    #[error("clip plane '{0}' must look like NX,NY,NZ or NX,NY,NZ,OFFSET (numbers; offset in mm)")]
    Syntax(String),
}

/// The half-space `(p − centre)·normal ≥ offset` of the world the camera uses (patient/world millimetres, the frame
/// the volume's box is placed in; with `voxel_axes` the voxel box), `centre` the centre of the volume's box there.
/// The normal points into what stays. Always valid: a unit, finite normal and a finite offset (the fields are
/// private, so every plane passes through [`ClipPlane::new`], JSON included).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "PlaneFields", into = "PlaneFields")]
pub struct ClipPlane {
    normal: Vec3,
    offset: f32,
}

/// The JSON form: `{"normal": [x, y, z], "offset": mm}` (offset 0 when left out).
#[derive(Clone, Copy, serde::Serialize, serde::Deserialize)]
struct PlaneFields {
    normal: Vec3,
    #[serde(default)]
    offset: f32,
}

impl TryFrom<PlaneFields> for ClipPlane {
    type Error = ClipPlaneError;

    fn try_from(f: PlaneFields) -> Result<ClipPlane, ClipPlaneError> {
        ClipPlane::new(f.normal, f.offset)
    }
}

impl From<ClipPlane> for PlaneFields {
    fn from(p: ClipPlane) -> PlaneFields {
        PlaneFields {
            normal: p.normal,
            offset: p.offset,
        }
    }
}

impl ClipPlane {
    /// The plane with `normal` (any length; normalised here) at `offset` mm from the box's centre along it.
    pub fn new(normal: Vec3, offset: f32) -> Result<ClipPlane, ClipPlaneError> {
        let unit = normal
            .try_normalize()
            .filter(|n| n.is_finite())
            .ok_or(ClipPlaneError::Normal(normal))?;
        if !offset.is_finite() {
            return Err(ClipPlaneError::Offset(offset));
        }
        Ok(ClipPlane { normal: unit, offset })
    }

    /// The plane with `normal` through `point` (mm, relative to the box's centre): for dragging a plane in 3D.
    pub fn through(normal: Vec3, point: Vec3) -> Result<ClipPlane, ClipPlaneError> {
        let unit = ClipPlane::new(normal, 0.0)?.normal;
        ClipPlane::new(unit, unit.dot(point))
    }

    /// `--clip-plane NX,NY,NZ[,OFFSET]`.
    pub fn parse(s: &str) -> Result<ClipPlane, ClipPlaneError> {
        let numbers: Result<Vec<f32>, _> = s.split(',').map(|x| x.trim().parse::<f32>()).collect();
        match numbers.as_deref() {
            Ok([x, y, z]) => ClipPlane::new(Vec3::new(*x, *y, *z), 0.0),
            Ok([x, y, z, offset]) => ClipPlane::new(Vec3::new(*x, *y, *z), *offset),
            _ => Err(ClipPlaneError::Syntax(s.to_string())),
        }
    }

    /// Unit normal, pointing into the half that is kept.
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// Millimetres from the box's centre along the normal.
    pub fn offset(&self) -> f32 {
        self.offset
    }

    /// The same plane at another offset (mm).
    pub fn with_offset(self, offset: f32) -> Result<ClipPlane, ClipPlaneError> {
        ClipPlane::new(self.normal, offset)
    }

    /// The same plane keeping the other half.
    pub fn flipped(self) -> ClipPlane {
        ClipPlane {
            normal: -self.normal,
            offset: -self.offset,
        }
    }

    /// The plane's point nearest the box's centre (mm, relative to it): where a viewer draws its handle.
    pub fn point(&self) -> Vec3 {
        self.normal * self.offset
    }

    /// Whether the point `p` (mm, relative to the box's centre) is kept.
    pub fn keeps(&self, p: Vec3) -> bool {
        p.dot(self.normal) >= self.offset
    }

    /// The plane in texture space for the frame uniforms: `(m, w)` such that a texture point p is kept when
    /// `m·p + w ≥ 0`. `tex_to_world` is the render world's placement (rule 0: the box centred on the origin), and
    /// `world_per_mm` its scale (`Geometry::world_per_mm`): the render world is the millimetre world moved to the
    /// box's centre and scaled uniformly, so the normal keeps its direction and the offset scales.
    pub fn texture_plane(&self, tex_to_world: DMat4, world_per_mm: f64) -> [f32; 4] {
        let (m, d) = self.equation_in(tex_to_world, world_per_mm);
        // Scaled to a unit texture-space normal: the shader's f32 sums then stay near the box's size.
        let scale = 1.0 / m.length().max(f64::MIN_POSITIVE);
        let m = m * scale;
        [m.x as f32, m.y as f32, m.z as f32, (-d * scale) as f32]
    }

    /// The plane in another frame whose points `to_world` maps into the render world (the millimetre world moved
    /// to the box's centre and scaled by `world_per_mm`, as in [`ClipPlane::texture_plane`]): `(m, d)` such that
    /// a point p of that frame is kept when `m·p ≥ d`.
    pub fn equation_in(&self, to_world: DMat4, world_per_mm: f64) -> (DVec3, f64) {
        let n = self.normal.as_dvec3();
        let m = DMat3::from_mat4(to_world).transpose() * n;
        (
            m,
            f64::from(self.offset) * world_per_mm - n.dot(to_world.w_axis.truncate()),
        )
    }

    /// A point of the plane and its normal (into the kept half, not unit) in the frame of [`ClipPlane::equation_in`]:
    /// how a slice view draws the plane's line.
    pub fn point_normal_in(&self, to_world: DMat4, world_per_mm: f64) -> (DVec3, DVec3) {
        let (m, d) = self.equation_in(to_world, world_per_mm);
        (m * (d / m.length_squared().max(f64::MIN_POSITIVE)), m)
    }
}

/// The uniform that keeps everything: `0·p + 1 ≥ 0`.
pub const KEEP_ALL: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

/// The texture-space plane of `plane` (None: [`KEEP_ALL`]).
pub fn texture_plane_or_all(plane: Option<&ClipPlane>, tex_to_world: DMat4, world_per_mm: f64) -> [f32; 4] {
    plane.map_or(KEEP_ALL, |p| p.texture_plane(tex_to_world, world_per_mm))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_normalises_and_names_bad_input() {
        let p = ClipPlane::parse("0, 0, 2").unwrap();
        assert_eq!(p.normal(), Vec3::Z);
        assert_eq!(p.offset(), 0.0);
        let p = ClipPlane::parse("3,4,0,-12.5").unwrap();
        assert!((p.normal() - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6);
        assert_eq!(p.offset(), -12.5);
        for bad in ["0,0,0", "0,0,0,5", "nan,1,0", "inf,0,0"] {
            let e = ClipPlane::parse(bad).unwrap_err();
            assert!(matches!(e, ClipPlaneError::Normal(_)), "{bad}: {e}");
            assert!(e.to_string().contains("non-zero"), "{e}");
        }
        assert!(matches!(ClipPlane::parse("1,0,0,nan"), Err(ClipPlaneError::Offset(_))));
        for bad in ["1,2", "1,2,3,4,5", "a,b,c", "", "1;2;3"] {
            let e = ClipPlane::parse(bad).unwrap_err();
            assert!(e.to_string().contains("NX,NY,NZ"), "{bad}: {e}");
        }
    }

    #[test]
    fn flipped_keeps_the_other_half() {
        let p = ClipPlane::new(Vec3::new(1.0, -2.0, 0.5), 3.0).unwrap();
        let q = p.flipped();
        assert_eq!(q.flipped(), p);
        for point in [
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(-4.0, 1.0, 2.0),
            Vec3::new(0.0, -3.0, 1.0),
        ] {
            assert_ne!(p.keeps(point), q.keeps(point), "{point}");
        }
        let through = ClipPlane::through(Vec3::X, Vec3::new(7.0, 1.0, 1.0)).unwrap();
        assert_eq!(through.offset(), 7.0);
        assert_eq!(through.point(), Vec3::new(7.0, 0.0, 0.0));
    }

    #[test]
    fn json_round_trips_and_refuses_invalid_planes() {
        let p = ClipPlane::new(Vec3::new(0.0, 3.0, 4.0), -2.0).unwrap();
        let json = serde_json::to_string(&p).unwrap();
        assert_eq!(serde_json::from_str::<ClipPlane>(&json).unwrap(), p);
        // A normal of any length is normalised; a missing offset is 0.
        let q: ClipPlane = serde_json::from_str(r#"{"normal": [0, 0, 5]}"#).unwrap();
        assert_eq!((q.normal(), q.offset()), (Vec3::Z, 0.0));
        let e = serde_json::from_str::<ClipPlane>(r#"{"normal": [0, 0, 0], "offset": 1}"#).unwrap_err();
        assert!(e.to_string().contains("non-zero"), "{e}");
        assert!(serde_json::from_str::<ClipPlane>(r#"{"offset": 1}"#).is_err());
        // Settings written before planes existed load without one.
        let old: crate::scene::settings::RenderSettings = serde_json::from_str(r#"{"width": 64}"#).unwrap();
        assert_eq!(old.cut.clip_plane, None);
    }

    #[test]
    fn texture_plane_agrees_with_the_millimetre_rule() {
        // A placement that scales, rotates and shifts: world = R·diag(s)·(tex − ½) scaled, centred.
        let linear = DMat3::from_rotation_z(0.4)
            * DMat3::from_rotation_x(-0.3)
            * DMat3::from_diagonal(DVec3::new(0.5, 0.8, 1.0));
        let tex_to_world = DMat4::from_mat3_translation(linear, -(linear * DVec3::splat(0.5)));
        let world_per_mm = 1.0 / 40.0;
        let plane = ClipPlane::new(Vec3::new(0.3, -0.7, 0.2), 4.5).unwrap();
        let t = plane.texture_plane(tex_to_world, world_per_mm);
        for i in 0..64 {
            let tex = DVec3::new((i % 4) as f64, ((i / 4) % 4) as f64, (i / 16) as f64) / 3.0;
            let mm = tex_to_world.transform_point3(tex) / world_per_mm;
            let f = DVec3::new(t[0].into(), t[1].into(), t[2].into()).dot(tex) + f64::from(t[3]);
            let exact = mm.dot(plane.normal().as_dvec3()) - f64::from(plane.offset());
            if exact.abs() > 1e-3 {
                assert_eq!(f >= 0.0, exact >= 0.0, "{tex}");
            }
        }
        assert_eq!(texture_plane_or_all(None, tex_to_world, world_per_mm), KEEP_ALL);
    }

    #[test]
    fn the_plane_in_another_frame_keeps_the_same_points() {
        // A frame (say a slice view's millimetres) mapped into the render world by a rotation, a scale and a shift.
        let to_world = DMat4::from_scale_rotation_translation(
            DVec3::splat(1.0 / 50.0),
            glam::DQuat::from_rotation_y(0.6),
            DVec3::new(-0.2, 0.1, 0.3),
        );
        let world_per_mm = 1.0 / 50.0;
        let plane = ClipPlane::new(Vec3::new(1.0, 2.0, -0.5), 6.0).unwrap();
        let (point, normal) = plane.point_normal_in(to_world, world_per_mm);
        // The point lies on the plane, and a step along the normal is kept.
        let mm_of = |p: DVec3| (to_world.transform_point3(p) / world_per_mm).as_vec3();
        let on = mm_of(point).dot(plane.normal()) - plane.offset();
        assert!(on.abs() < 1e-3, "{on}");
        assert!(plane.keeps(mm_of(point + normal.normalize())));
        assert!(!plane.keeps(mm_of(point - normal.normalize())));
    }
}
