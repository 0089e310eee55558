//! Pinhole camera: automatic framing of a bounding box, or a caller's view.
//!
//! Convention: world `+y` is up (the usual OBJ convention). View space has `x`
//! to the right, `y` up and `z` the distance in front of the eye; screen space
//! has `x` to the right and `y` down, in pixels.

use nalgebra::Vector3;

use super::error::RenderError;

type V3 = Vector3<f64>;

/// Default azimuth of the automatic view, degrees, about `+y` from `+z` towards `+x`.
pub const DEFAULT_AZIMUTH_DEG: f64 = 35.0;
/// Default elevation of the automatic view above the `xz` plane, degrees.
pub const DEFAULT_ELEVATION_DEG: f64 = 25.0;
/// Default vertical field of view, degrees.
pub const DEFAULT_FOV_Y_DEG: f64 = 30.0;

/// Fraction of the picture the framed box may fill (the rest is margin).
const FILL: f64 = 0.88;

/// A perspective view given by the caller, or made by [`CameraSpec::frame_box`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    /// Eye position (world units).
    pub eye: [f64; 3],
    /// Point looked at; must differ from `eye`.
    pub target: [f64; 3],
    /// Up direction; must not be parallel to `target - eye`. Usually `[0, 1, 0]`.
    pub up: [f64; 3],
    /// Vertical field of view in degrees, in `(0, 170]`. Default: 30.
    pub fov_y_deg: f64,
}

impl CameraSpec {
    /// The automatic view of the box `min..max` for a picture of `aspect = width / height`:
    /// from azimuth [`DEFAULT_AZIMUTH_DEG`] and elevation [`DEFAULT_ELEVATION_DEG`],
    /// at the distance where the whole box fits with a small margin.
    pub fn frame_box(min: [f64; 3], max: [f64; 3], aspect: f64) -> Self {
        Self::frame_box_from(min, max, aspect, DEFAULT_AZIMUTH_DEG, DEFAULT_ELEVATION_DEG)
    }

    /// Like [`CameraSpec::frame_box`] from a chosen direction (degrees; elevation
    /// is clamped to `[-85, 85]`).
    pub fn frame_box_from(
        min: [f64; 3],
        max: [f64; 3],
        aspect: f64,
        azimuth_deg: f64,
        elevation_deg: f64,
    ) -> Self {
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|c: usize| {
                let pick = |k: usize| if c & (1 << k) == 0 { min[k] } else { max[k] };
                [pick(0), pick(1), pick(2)]
            })
            .collect();
        Self::frame_points_from(&corners, aspect, azimuth_deg, elevation_deg)
    }

    /// The automatic view of a point set: like [`CameraSpec::frame_box`], but
    /// fitted to the points themselves (tighter for round or sparse shapes) and
    /// centred on their picture.
    pub fn frame_points(points: &[[f64; 3]], aspect: f64) -> Self {
        Self::frame_points_from(points, aspect, DEFAULT_AZIMUTH_DEG, DEFAULT_ELEVATION_DEG)
    }

    /// Like [`CameraSpec::frame_points`] from a chosen direction (degrees,
    /// about world `+y`; elevation is clamped to `[-85, 85]`). Non-finite
    /// points are ignored; no point, or all at one place, is framed as a
    /// unit cube around it.
    pub fn frame_points_from(
        points: &[[f64; 3]],
        aspect: f64,
        azimuth_deg: f64,
        elevation_deg: f64,
    ) -> Self {
        let (az, el) = (
            azimuth_deg.to_radians(),
            elevation_deg.clamp(-85.0, 85.0).to_radians(),
        );
        let to_eye = V3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        Self::frame_points_along(points, aspect, (-to_eye).into(), [0.0, 1.0, 0.0])
    }

    /// The view of a point set looking along `view` (from the eye towards
    /// the points) with `up` pointing up in the picture, at the distance
    /// where all points fit with a small margin, centred on their picture.
    /// A zero or non-finite `view` looks along `-z`; an `up` that is zero,
    /// not finite or parallel to `view` is replaced by the world axis least
    /// aligned with `view`. Non-finite points are ignored; no point, or all
    /// at one place, is framed as a unit cube around it.
    pub fn frame_points_along(
        points: &[[f64; 3]],
        aspect: f64,
        view: [f64; 3],
        up: [f64; 3],
    ) -> Self {
        let finite = || {
            points
                .iter()
                .filter(|p| p.iter().all(|c| c.is_finite()))
                .map(|&p| V3::from(p))
        };
        let (mut lo, mut hi) = (V3::repeat(f64::INFINITY), V3::repeat(f64::NEG_INFINITY));
        for p in finite() {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let mut center = if lo.x <= hi.x {
            (lo + hi) * 0.5
        } else {
            V3::zeros()
        };
        let extent = if lo.x <= hi.x {
            (hi - lo).norm() * 0.5
        } else {
            0.0
        };
        let forward = unit(V3::from(view)).unwrap_or(-V3::z());
        let right = unit(forward.cross(&V3::from(up)))
            .filter(|r| r.cross(&forward).norm() > 1e-6)
            .unwrap_or_else(|| {
                let least = (0..3)
                    .min_by(|&a, &b| forward[a].abs().total_cmp(&forward[b].abs()))
                    .unwrap_or(0);
                forward.cross(&V3::ith(least, 1.0)).normalize()
            });
        let cam_up = right.cross(&forward);
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let ty = (DEFAULT_FOV_Y_DEG.to_radians() * 0.5).tan() * FILL;
        let tx = ty * aspect;
        let distance = if extent > 0.0 && extent.is_finite() {
            // Centre the picture of the points, then back off until all fit.
            let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for p in finite() {
                let d = p - center;
                let (x, y) = (d.dot(&right), d.dot(&cam_up));
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
            center += right * (0.5 * (x0 + x1)) + cam_up * (0.5 * (y0 + y1));
            let (mut fit, mut behind) = (0.0_f64, 0.0_f64);
            for p in finite() {
                let d = p - center;
                let z = d.dot(&forward);
                fit = fit
                    .max(d.dot(&right).abs() / tx - z)
                    .max(d.dot(&cam_up).abs() / ty - z);
                behind = behind.max(-z);
            }
            // Keep every point well in front of the eye.
            fit.max(behind + 0.2 * extent)
        } else {
            // One point (or none): a unit cube around it.
            0.5 * 3f64.sqrt() / ty.min(tx) + 0.5
        };
        let eye = center - forward * distance;
        CameraSpec {
            eye: eye.into(),
            target: center.into(),
            up: cam_up.into(),
            fov_y_deg: DEFAULT_FOV_Y_DEG,
        }
    }

    /// Checks that the view is usable.
    ///
    /// # Errors
    /// [`RenderError::BadOption`] if a value is not finite, `eye == target`,
    /// `up` is parallel to the view direction or the field of view is outside `(0, 170]`.
    pub fn validate(&self) -> Result<(), RenderError> {
        let all = self.eye.iter().chain(&self.target).chain(&self.up);
        if !all.clone().all(|c| c.is_finite()) || !self.fov_y_deg.is_finite() {
            return Err(RenderError::option(
                "camera",
                format!("all values must be finite, got {self:?}"),
            ));
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg <= 170.0) {
            return Err(RenderError::option(
                "camera.fov_y_deg",
                format!("{} is outside (0, 170] degrees", self.fov_y_deg),
            ));
        }
        let view = V3::from(self.target) - V3::from(self.eye);
        if view.norm() <= 0.0 {
            return Err(RenderError::option("camera", "eye and target must differ"));
        }
        let up = V3::from(self.up);
        if view.normalize().cross(&up).norm() <= 1e-9 * up.norm().max(1e-300) {
            return Err(RenderError::option(
                "camera.up",
                "up must be non-zero and not parallel to target - eye",
            ));
        }
        Ok(())
    }
}

/// `v` normalized, `None` when it is zero or not finite.
fn unit(v: V3) -> Option<V3> {
    let n = v.norm();
    (n.is_finite() && n > 0.0).then(|| v / n)
}

/// A validated camera bound to a picture size (in raster pixels).
#[derive(Clone, Debug)]
pub(crate) struct Camera {
    eye: V3,
    right: V3,
    up: V3,
    forward: V3,
    focal_px: f64,
    cx: f64,
    cy: f64,
    /// Nearest view depth drawn; geometry in front of it is clipped.
    near: f64,
}

impl Camera {
    /// Binds `spec` to a raster of `width x height` pixels.
    pub(crate) fn new(spec: &CameraSpec, width: usize, height: usize) -> Result<Self, RenderError> {
        spec.validate()?;
        let eye = V3::from(spec.eye);
        let view = V3::from(spec.target) - eye;
        let forward = view.normalize();
        let right = forward.cross(&V3::from(spec.up)).normalize();
        let up = right.cross(&forward);
        let focal_px = height as f64 * 0.5 / (spec.fov_y_deg.to_radians() * 0.5).tan();
        Ok(Camera {
            eye,
            right,
            up,
            forward,
            focal_px,
            cx: width as f64 * 0.5,
            cy: height as f64 * 0.5,
            near: view.norm() * 1e-3,
        })
    }

    /// World point to view space (`x` right, `y` up, `z` depth in front of the eye).
    pub(crate) fn to_view(&self, p: V3) -> V3 {
        let d = p - self.eye;
        V3::new(d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward))
    }

    /// World direction to view space.
    pub(crate) fn dir_to_view(&self, d: V3) -> V3 {
        V3::new(d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward))
    }

    /// The eye position (world).
    pub(crate) fn eye(&self) -> V3 {
        self.eye
    }

    /// Nearest drawn depth.
    pub(crate) fn near(&self) -> f64 {
        self.near
    }

    /// View point (with `z >= near`) to screen `(x, y, 1/z)`.
    pub(crate) fn project(&self, v: V3) -> [f64; 3] {
        let inv = 1.0 / v.z.max(self.near);
        [
            self.cx + v.x * self.focal_px * inv,
            self.cy - v.y * self.focal_px * inv,
            inv,
        ]
    }

    /// Clips a view-space segment to `z >= near`; `None` if wholly in front of the eye plane.
    pub(crate) fn clip_segment(&self, a: V3, b: V3) -> Option<(V3, V3)> {
        let n = self.near;
        match (a.z >= n, b.z >= n) {
            (true, true) => Some((a, b)),
            (false, false) => None,
            (a_in, _) => {
                let t = (n - a.z) / (b.z - a.z);
                let m = a + (b - a) * t;
                Some(if a_in { (a, m) } else { (m, b) })
            }
        }
    }

    /// Clips a view-space polygon to `z >= near` (Sutherland-Hodgman, one plane).
    pub(crate) fn clip_polygon(&self, poly: &[V3], out: &mut Vec<V3>) {
        out.clear();
        let n = self.near;
        for (i, &a) in poly.iter().enumerate() {
            let b = poly[(i + 1) % poly.len()];
            let (a_in, b_in) = (a.z >= n, b.z >= n);
            if a_in {
                out.push(a);
            }
            if a_in != b_in {
                let t = (n - a.z) / (b.z - a.z);
                out.push(a + (b - a) * t);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framed_box_is_inside_the_picture() {
        let (w, h) = (800, 600);
        let spec = CameraSpec::frame_box([-1.0, -0.2, -3.0], [2.0, 0.5, 1.0], w as f64 / h as f64);
        spec.validate().unwrap();
        let cam = Camera::new(&spec, w, h).unwrap();
        let mut max_x: f64 = 0.0;
        for corner in 0..8 {
            let pick = |bit: usize, lo: f64, hi: f64| if corner & bit == 0 { lo } else { hi };
            let p = V3::new(pick(1, -1.0, 2.0), pick(2, -0.2, 0.5), pick(4, -3.0, 1.0));
            let v = cam.to_view(p);
            assert!(v.z > cam.near());
            let s = cam.project(v);
            assert!(s[0] > 0.0 && s[0] < w as f64, "{s:?}");
            assert!(s[1] > 0.0 && s[1] < h as f64, "{s:?}");
            max_x = max_x
                .max((s[0] - 400.0).abs())
                .max((s[1] - 300.0).abs() * 4.0 / 3.0);
        }
        assert!(
            max_x > 300.0,
            "the box should fill most of the frame, {max_x}"
        );
    }

    #[test]
    fn framed_points_fill_and_centre_the_picture() {
        // Points on a unit sphere off the origin.
        let pts: Vec<[f64; 3]> = (0..200)
            .map(|i| {
                let (t, p) = (i as f64 * 0.7, i as f64 * 0.013 * std::f64::consts::PI);
                [
                    5.0 + p.sin() * t.cos(),
                    -2.0 + p.cos(),
                    1.0 + p.sin() * t.sin(),
                ]
            })
            .collect();
        let cam = Camera::new(&CameraSpec::frame_points(&pts, 1.0), 100, 100).unwrap();
        let s: Vec<[f64; 3]> = pts
            .iter()
            .map(|&p| cam.project(cam.to_view(V3::from(p))))
            .collect();
        let (lo, hi) = s
            .iter()
            .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            });
        assert!(
            lo[0] > 0.0 && lo[1] > 0.0 && hi[0] < 100.0 && hi[1] < 100.0,
            "{lo:?} {hi:?}"
        );
        assert!(
            hi[0] - lo[0] > 75.0 && hi[1] - lo[1] > 75.0,
            "{lo:?} {hi:?}"
        );
        assert!(((lo[0] + hi[0]) * 0.5 - 50.0).abs() < 3.0);
        assert!(((lo[1] + hi[1]) * 0.5 - 50.0).abs() < 3.0);
        // One point, no point: still a valid camera looking at it.
        let one = CameraSpec::frame_points(&[[1.0, 2.0, 3.0]], 1.5);
        one.validate().unwrap();
        assert_eq!(one.target, [1.0, 2.0, 3.0]);
        CameraSpec::frame_points(&[], 1.0).validate().unwrap();
        CameraSpec::frame_points(&[[f64::NAN, 0.0, 0.0]], 1.0)
            .validate()
            .unwrap();
    }

    #[test]
    fn degenerate_boxes_and_bad_specs() {
        let spec = CameraSpec::frame_box([1.0; 3], [1.0; 3], 1.0);
        spec.validate().unwrap();
        let mut bad = spec;
        bad.target = bad.eye;
        assert!(bad.validate().is_err());
        let mut bad = spec;
        bad.up = [0.0; 3];
        assert!(bad.validate().is_err());
        let mut bad = spec;
        bad.fov_y_deg = 0.0;
        assert!(bad.validate().is_err());
        let mut bad = spec;
        bad.eye[0] = f64::INFINITY;
        assert!(bad.validate().is_err());
    }

    #[test]
    fn near_clipping() {
        let spec = CameraSpec {
            eye: [0.0, 0.0, 10.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 40.0,
        };
        let cam = Camera::new(&spec, 100, 100).unwrap();
        let a = V3::new(0.0, 0.0, -1.0);
        let b = V3::new(0.0, 0.0, 5.0);
        let (p, q) = cam.clip_segment(a, b).unwrap();
        assert!((p.z - cam.near()).abs() < 1e-12 && q == b);
        let mut out = Vec::new();
        cam.clip_polygon(&[a, b, V3::new(1.0, 0.0, 5.0)], &mut out);
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|v| v.z >= cam.near() - 1e-12));
    }
}
