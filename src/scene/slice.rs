//! Slice views: a volume resampled on a plane of patient space (axial, coronal, sagittal, as 3D Slicer orients
//! them), or of the voxel grid's own axes for a volume without orientation. Pure code: the viewer draws the
//! images; the tests check them against the volume's voxels.
//!
//! Coordinates are world millimetres (`mm_from_index`: the volume's affine, RAS+ for an anatomical volume; or the
//! voxel sizes alone with `voxel_axes`), not the render world (which is centred and scaled to a unit box). A
//! slice image's pixel (x, y), continuous, has its top-left corner at (0, 0); pixel centres at half-integers.

use crate::volume::{Geometry, Volume};
use glam::{DMat4, DVec2, DVec3};

/// Which plane a slice view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SliceView {
    Axial,
    Coronal,
    Sagittal,
}

impl SliceView {
    pub const ALL: [SliceView; 3] = [SliceView::Axial, SliceView::Coronal, SliceView::Sagittal];

    /// The view's name: anatomical, or the voxel grid's plane.
    pub fn name(self, anatomical: bool) -> &'static str {
        match (self, anatomical) {
            (SliceView::Axial, true) => "axial",
            (SliceView::Coronal, true) => "coronal",
            (SliceView::Sagittal, true) => "sagittal",
            (SliceView::Axial, false) => "xy",
            (SliceView::Coronal, false) => "xz",
            (SliceView::Sagittal, false) => "yz",
        }
    }

    /// The world axis the view looks along (its normal): z, y or x.
    pub fn normal_axis(self) -> usize {
        match self {
            SliceView::Axial => 2,
            SliceView::Coronal => 1,
            SliceView::Sagittal => 0,
        }
    }

    /// (screen right, screen down) as world directions. Anatomical: 3D Slicer's orientation matrices (radiological:
    /// the patient's right on the screen's left; axial with anterior up, coronal and sagittal with superior up,
    /// sagittal with anterior on the left). Voxel axes: +x right and the other axis up.
    pub fn screen_axes(self, anatomical: bool) -> (DVec3, DVec3) {
        match (self, anatomical) {
            (SliceView::Axial, true) => (-DVec3::X, -DVec3::Y),
            (SliceView::Coronal, true) => (-DVec3::X, -DVec3::Z),
            (SliceView::Sagittal, true) => (-DVec3::Y, -DVec3::Z),
            (SliceView::Axial, false) => (DVec3::X, -DVec3::Y),
            (SliceView::Coronal, false) => (DVec3::X, -DVec3::Z),
            (SliceView::Sagittal, false) => (DVec3::Y, -DVec3::Z),
        }
    }

    /// The letters at the view's left, right, top and bottom edges (anatomical only).
    pub fn edge_labels(self) -> [char; 4] {
        match self {
            SliceView::Axial => ['R', 'L', 'A', 'P'],
            SliceView::Coronal => ['R', 'L', 'S', 'I'],
            SliceView::Sagittal => ['A', 'P', 'S', 'I'],
        }
    }
}

/// Voxel index to world millimetres for what the views show: the affine, or the voxel sizes alone.
pub fn mm_from_index(geometry: &Geometry, voxel_axes: bool) -> DMat4 {
    if voxel_axes {
        DMat4::from_scale(DVec3::from_array(geometry.spacing()))
    } else {
        geometry.affine
    }
}

/// The eight corners of the volume's box in world millimetres: the voxels' outer faces (half a voxel beyond the
/// centres), in the order (i & 1, i >> 1 & 1, i >> 2 & 1).
pub fn box_corners_mm(mm_from_index: DMat4, dims: [u32; 3]) -> [DVec3; 8] {
    std::array::from_fn(|c| {
        let t = DVec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64);
        let d = DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2]));
        mm_from_index.transform_point3(t * d - 0.5)
    })
}

/// Where the plane `{x : normal·x = d}` cuts the parallelepiped with `corners` (ordered as [`box_corners_mm`]):
/// the polygon's corners in order around it, or nothing when it misses (or only touches an edge or a corner).
/// Used for a slice's outline of the slab box and for the clipping plane's outline in the 3D view.
pub fn plane_section(corners: &[DVec3; 8], normal: DVec3, d: f64) -> Vec<DVec3> {
    let depth = |p: DVec3| p.dot(normal) - d;
    let mut points: Vec<DVec3> = Vec::new();
    for (a, b) in BOX_EDGES {
        let (da, db) = (depth(corners[a]), depth(corners[b]));
        if (da <= 0.0 && db >= 0.0) || (da >= 0.0 && db <= 0.0) {
            let t = if (db - da).abs() < 1e-12 { 0.0 } else { da / (da - db) };
            points.push(corners[a] + (corners[b] - corners[a]) * t);
        }
    }
    if points.len() < 3 {
        return Vec::new();
    }
    // Ordered by angle about their centre, in a basis of the plane.
    let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let unit = normal.normalize();
    let u = unit.any_orthonormal_vector();
    let v = unit.cross(u);
    let angle = |p: DVec3| (p - centre).dot(v).atan2((p - centre).dot(u));
    points.sort_by(|p, q| angle(*p).total_cmp(&angle(*q)));
    points.dedup_by(|p, q| p.distance(*q) < 1e-9);
    if points.len() > 2 && points[0].distance(points[points.len() - 1]) < 1e-9 {
        points.pop();
    }
    if points.len() < 3 {
        return Vec::new();
    }
    points
}

/// The 12 edges of a box whose corners are ordered as [`box_corners_mm`].
pub const BOX_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// The pixel grid of one slice image in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceFrame {
    pub view: SliceView,
    /// World step of one pixel to the right and one down (unit vectors times `pixel`).
    pub right: DVec3,
    pub down: DVec3,
    /// World point of the image's top-left corner (on the plane).
    pub corner: DVec3,
    /// Pixel size in millimetres.
    pub pixel: f64,
    pub width: u32,
    pub height: u32,
}

impl SliceFrame {
    /// The slice of `view` through the world point `through`, covering the volume's box projected onto the plane
    /// with pixels of the smallest voxel side (coarser when a side would exceed `max_side` pixels).
    pub fn new(
        view: SliceView,
        anatomical: bool,
        mm_from_index: DMat4,
        dims: [u32; 3],
        through: DVec3,
        max_side: u32,
    ) -> SliceFrame {
        let (r, d) = view.screen_axes(anatomical);
        let corners = box_corners_mm(mm_from_index, dims);
        let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for c in corners {
            (u0, u1) = (u0.min(c.dot(r)), u1.max(c.dot(r)));
            (v0, v1) = (v0.min(c.dot(d)), v1.max(c.dot(d)));
        }
        let spacing = [0, 1, 2].map(|a| mm_from_index.col(a).truncate().length());
        let smallest = spacing.iter().copied().fold(f64::MAX, f64::min).max(1e-9);
        let longest = (u1 - u0).max(v1 - v0).max(1e-9);
        let pixel = smallest.max(longest / f64::from(max_side.max(1)));
        let width = ((u1 - u0) / pixel).round().max(1.0) as u32;
        let height = ((v1 - v0) / pixel).round().max(1.0) as u32;
        let n = r.cross(d);
        // The corner: (u0, v0) in the plane's axes, at the depth of `through` along the normal.
        let corner = r * u0 + d * v0 + n * through.dot(n);
        SliceFrame {
            view,
            right: r * pixel,
            down: d * pixel,
            corner,
            pixel,
            width,
            height,
        }
    }

    /// The unit normal (right × down: into the screen).
    pub fn normal(&self) -> DVec3 {
        self.right.cross(self.down).normalize()
    }

    /// World point at image coordinates (x, y) (pixels, continuous).
    pub fn world(&self, p: DVec2) -> DVec3 {
        self.corner + self.right * p.x + self.down * p.y
    }

    /// Image coordinates of a world point's projection onto the plane.
    pub fn image(&self, w: DVec3) -> DVec2 {
        let rel = w - self.corner;
        DVec2::new(rel.dot(self.right), rel.dot(self.down)) / (self.pixel * self.pixel)
    }

    /// Where the plane through `point` with `normal` crosses this slice, as a segment across the image (None when
    /// parallel). The segment spans the image's diagonal beyond its edges; the painter clips it.
    pub fn line_of_plane(&self, point: DVec3, normal: DVec3) -> Option<(DVec2, DVec2)> {
        let (r, d) = (self.right / self.pixel, self.down / self.pixel);
        // Points on the slice: corner + a·r + b·d (mm). On the plane: (corner + a·r + b·d − point)·normal = 0.
        let (nr, nd) = (r.dot(normal), d.dot(normal));
        let c = (point - self.corner).dot(normal);
        let along = DVec2::new(-nd, nr);
        if along.length() < 1e-9 {
            return None;
        }
        // The foot of the line nearest the corner, then out along it.
        let foot = DVec2::new(nr, nd) * (c / (nr * nr + nd * nd));
        let reach = f64::from(self.width.max(self.height)) * self.pixel * 2.0;
        let dir = along.normalize() * reach;
        Some(((foot - dir) / self.pixel, (foot + dir) / self.pixel))
    }

    /// The outline, in image coordinates, of where this slice cuts the parallelepiped with `corners` (ordered as
    /// [`box_corners_mm`]); empty when it misses.
    pub fn section(&self, corners: &[DVec3; 8]) -> Vec<DVec2> {
        let n = self.normal();
        plane_section(corners, n, n.dot(self.corner))
            .into_iter()
            .map(|p| self.image(p))
            .collect()
    }
}

/// The volume's value (data units, trilinear between voxel centres) at a world point, or None outside the box of
/// voxel centres widened by half a voxel (the voxels' outer faces, clamped to the edge voxels there).
pub fn sample(volume: &Volume, index_from_mm: DMat4, w: DVec3) -> Option<f64> {
    let c = index_from_mm.transform_point3(w);
    let d = volume.dims;
    let mut i0 = [0u32; 3];
    let mut f = [0.0f64; 3];
    for a in 0..3 {
        let n = f64::from(d[a]);
        if !(c[a] >= -0.5 && c[a] <= n - 0.5) {
            return None;
        }
        let x = c[a].clamp(0.0, n - 1.0);
        let lo = x.floor().min((n - 2.0).max(0.0));
        i0[a] = lo as u32;
        f[a] = x - lo;
    }
    let at = |dx: u32, dy: u32, dz: u32| {
        let x = (i0[0] + dx).min(d[0] - 1);
        let y = (i0[1] + dy).min(d[1] - 1);
        let z = (i0[2] + dz).min(d[2] - 1);
        volume.value(x, y, z)
    };
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f[0]);
    let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f[0]);
    let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f[0]);
    let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f[0]);
    Some(lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2]))
}

/// The voxel nearest a world point (None outside the volume).
pub fn voxel_at(dims: [u32; 3], index_from_mm: DMat4, w: DVec3) -> Option<[u32; 3]> {
    let c = index_from_mm.transform_point3(w);
    let mut v = [0u32; 3];
    for a in 0..3 {
        let r = c[a].round();
        if !(r >= 0.0 && r < f64::from(dims[a])) {
            return None;
        }
        v[a] = r as u32;
    }
    Some(v)
}

/// Window and level in data units: grey = (value − (level − window/2)) / window, clamped.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WindowLevel {
    pub window: f64,
    pub level: f64,
}

impl WindowLevel {
    /// Grey in [0, 1] of a data value; NaN shows black.
    pub fn grey(&self, v: f64) -> f64 {
        let g = (v - (self.level - self.window / 2.0)) / self.window.max(1e-12);
        if g.is_nan() {
            0.0
        } else {
            g.clamp(0.0, 1.0)
        }
    }

    /// A drag by (dx, dy) pixels: right widens the window, down raises the level (3D Slicer's directions), by a
    /// fraction of the data range per pixel.
    pub fn dragged(&self, dx: f64, dy: f64, range: [f64; 2]) -> WindowLevel {
        let per_pixel = (range[1] - range[0]).abs().max(1e-12) / 500.0;
        WindowLevel {
            window: (self.window + dx * per_pixel).max(per_pixel),
            level: self.level + dy * per_pixel,
        }
    }
}

/// The slice image as RGBA8 (grey by `wl`; outside the volume transparent black).
pub fn render(volume: &Volume, mm_from_index: DMat4, frame: &SliceFrame, wl: WindowLevel) -> Vec<u8> {
    let index_from_mm = mm_from_index.inverse();
    let mut rgba = vec![0u8; frame.width as usize * frame.height as usize * 4];
    for y in 0..frame.height {
        for x in 0..frame.width {
            let w = frame.world(DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5));
            if let Some(v) = sample(volume, index_from_mm, w) {
                let g = (wl.grey(v) * 255.0).round() as u8;
                let i = (y as usize * frame.width as usize + x as usize) * 4;
                rgba[i..i + 4].copy_from_slice(&[g, g, g, 255]);
            }
        }
    }
    rgba
}

#[cfg(test)]
mod tests;
