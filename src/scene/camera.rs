//! The mesh camera (docs/model.md, Frames and conventions): perspective, `eye`, `target`, `up`, vertical field of view;
//! pixel
//! `(i, j)` (column, row from the top) samples the ray through its centre. The same camera gives the
//! CPU reference its rays ([`Camera::ray`]) and the GPU rasteriser its view-projection matrix
//! ([`Camera::view_proj`]), and the two agree (tested in `tests/mesh_camera.rs`).
//!
//! Owns the camera's text form (`--camera`) and its geometry; knows nothing of meshes or Vulkan
//! objects (the matrix is plain `glam`).

use std::fmt;

use glam::{DMat4, DVec3, DVec4, Mat4};

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_deg: f64,
}

impl Default for Camera {
    /// `eye=(0,0,4) target=(0,0,0) up=(0,1,0) fov=30`.
    fn default() -> Self {
        Camera { eye: DVec3::new(0.0, 0.0, 4.0), target: DVec3::ZERO, up: DVec3::Y, fov_deg: 30.0 }
    }
}

/// The distance from a sphere's centre at which a camera of vertical field of view `fov_deg`
/// looking at it, with an image `aspect` = width / height, sees the sphere of `radius` grown by the
/// factor `margin` just touch the nearer pair of the image's edges: the sphere's silhouette (angular
/// radius `asin(r / d)`) fits within both half-angles, the vertical `fov / 2` and the horizontal
/// `atan(tan(fov / 2) · aspect)`. A degenerate aspect (zero, negative or not finite) counts as 1.
pub fn fit_distance(fov_deg: f64, aspect: f64, radius: f64, margin: f64) -> f64 {
    let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
    let half_v = 0.5 * fov_deg.to_radians();
    let half_h = (half_v.tan() * aspect).atan();
    radius * margin / half_v.min(half_h).sin()
}

impl Camera {
    /// The default camera for an image of `width × height`: [`Camera::default`] where the image is
    /// at least as wide as it is tall; for a taller image the eye moves back along the same line
    /// until the unit sphere (every mesh is scaled into it) keeps the same margin to the left and
    /// right edges as the default camera keeps to the top and bottom of a square image.
    pub fn framed(width: u32, height: u32) -> Camera {
        let c = Camera::default();
        if width >= height {
            return c;
        }
        let d = c.eye.length();
        let margin = d * (0.5 * c.fov_deg.to_radians()).sin();
        let eye = c.eye * (fit_distance(c.fov_deg, width as f64 / height as f64, 1.0, margin) / d);
        Camera { eye, ..c }
    }
}

/// The near plane of [`Camera::view_proj`], also the smallest ray distance the CPU reference accepts.
/// The far plane is at infinity: depth `1 − NEAR/z` never reaches the cleared 1.0, so no part of the
/// scene is clipped however far the eye is. With `D32_SFLOAT` and the default camera (`z ≈ 4`) the
/// depth resolution is about `z² · 6e-8 / NEAR ≈ 1e-4` — far below any feature of a mesh scaled to
/// the unit sphere.
pub const NEAR: f64 = 0.01;

/// The largest `|coordinate|` of `eye` and `target`. Meshes are scaled to the unit sphere and the
/// GPU works in `f32`, whose spacing at 1e6 is 0.06: a camera further out sees the object as a
/// sub-pixel dot and its rays lose the precision to hit it, so such a camera is refused rather than
/// overflowing (`target − eye` of 1e300 and −1e300 is infinite).
pub const MAX_COORD: f64 = 1.0e6;

/// The smallest field of view (degrees): narrower, a pixel spans less than `f32` can tell apart
/// at the default distance (and `1/tan(fov/2)` heads for `f32`'s overflow).
pub const MIN_FOV_DEG: f64 = 1.0e-3;

/// Sine of the smallest angle allowed between `up` and the view direction.
const MIN_UP_SINE: f64 = 1e-6;

fn parse_vec(key: &str, v: &str) -> Result<DVec3, String> {
    let nums: Option<Vec<f64>> = v.split(',').map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect();
    match nums {
        Some(n) if n.len() == 3 => Ok(DVec3::new(n[0], n[1], n[2])),
        _ => Err(format!("{key}: expected three finite numbers x,y,z, got \"{}\"", crate::fsio::quote(v))),
    }
}

impl Camera {
    /// Parses `"eye=x,y,z target=x,y,z up=x,y,z fov=deg"`: any subset, any order, separated by
    /// whitespace; the keys not given keep their defaults. Every refusal names the key (or the item)
    /// and what is wrong: an item without `=`, an unknown or repeated key, a value that is not three
    /// finite numbers (one for `fov`), and the geometric refusals of [`Camera::check`].
    pub fn parse(s: &str) -> Result<Camera, String> {
        let mut c = Camera::default();
        let mut seen: Vec<&str> = Vec::new();
        for item in s.split_whitespace() {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| format!("\"{}\" is not key=value (eye, target, up, fov)", crate::fsio::quote(item)))?;
            if seen.contains(&key) {
                return Err(format!("{}: given twice", crate::fsio::quote(key)));
            }
            match key {
                "eye" => c.eye = parse_vec(key, value)?,
                "target" => c.target = parse_vec(key, value)?,
                "up" => c.up = parse_vec(key, value)?,
                "fov" => {
                    c.fov_deg =
                        value.trim().parse::<f64>().ok().filter(|f| f.is_finite()).ok_or_else(|| {
                            format!("fov: \"{}\" is not a number of degrees", crate::fsio::quote(value))
                        })?
                }
                _ => return Err(format!("unknown key \"{}\" (eye, target, up, fov)", crate::fsio::quote(key))),
            }
            seen.push(key);
        }
        c.check()?;
        Ok(c)
    }

    /// Refuses a camera without a view direction (`eye` = `target`), with `up` zero or parallel to
    /// the view direction (within 1e-6 rad), a non-finite coordinate, or a field of view outside
    /// (0°, 180°).
    pub fn check(&self) -> Result<(), String> {
        for (key, v) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if !v.is_finite() {
                return Err(format!("{key}: {v} is not finite"));
            }
        }
        for (key, v) in [("eye", self.eye), ("target", self.target)] {
            if v.abs().max_element() > MAX_COORD {
                return Err(format!("{key}: {v} lies beyond ±{MAX_COORD:e}, the largest coordinate allowed"));
            }
        }
        let Some(f) = (self.target - self.eye).try_normalize() else {
            return Err(format!("eye and target are the same point {}", self.eye));
        };
        match crate::brdf::material::unit(self.up) {
            None => return Err("up: must not be zero".into()),
            Some(u) if !(f.cross(u).length() > MIN_UP_SINE) => {
                return Err(format!("up: {} is parallel to the view direction {f}", self.up))
            }
            Some(_) => {}
        }
        if !(self.fov_deg > 0.0 && self.fov_deg < 180.0) {
            return Err(format!("fov: {} is not between 0 and 180 degrees", self.fov_deg));
        }
        if self.fov_deg < MIN_FOV_DEG {
            return Err(format!("fov: {} is below {MIN_FOV_DEG} degrees, the smallest allowed", self.fov_deg));
        }
        Ok(())
    }

    /// The orthonormal basis (right, up, forward) of a camera that passes [`Camera::check`]; `up` is
    /// made orthogonal to the view direction.
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = (self.target - self.eye).normalize();
        let up = crate::brdf::material::unit(self.up).unwrap_or(self.up);
        let right = forward.cross(up).normalize();
        (right, right.cross(forward), forward)
    }

    /// `tan(fov/2)` times the aspect ratio and `tan(fov/2)`: the half extents of the image plane at
    /// distance 1.
    pub fn half_extents(&self, width: u32, height: u32) -> (f64, f64) {
        let t = (self.fov_deg.to_radians() / 2.0).tan();
        (t * width as f64 / height as f64, t)
    }

    /// The unit direction through image point `(px, py)` in pixels (pixel `(i, j)`'s centre is
    /// `(i + 0.5, j + 0.5)`, rows from the top): vertical field of view, aspect `width/height`.
    pub fn ray(&self, px: f64, py: f64, width: u32, height: u32) -> DVec3 {
        Rays::new(self, width, height).at(px, py)
    }

    /// The view-projection for Vulkan: clip `y` points down the image (NDC `y = −1` is the top row),
    /// depth `1 − NEAR/z` in `[0, 1)` for view depth `z ≥` [`NEAR`] (infinite far plane, compare
    /// `LESS`, clear to 1). A point `eye + s·ray(px, py)` lands at NDC `(2px/W − 1, 2py/H − 1)`.
    pub fn view_proj(&self, width: u32, height: u32) -> Mat4 {
        let (right, up, forward) = self.basis();
        // View space: x right, y down the image, z forward (depth).
        let view = DMat4::from_cols(
            DVec4::new(right.x, -up.x, forward.x, 0.0),
            DVec4::new(right.y, -up.y, forward.y, 0.0),
            DVec4::new(right.z, -up.z, forward.z, 0.0),
            DVec4::new(-right.dot(self.eye), up.dot(self.eye), -forward.dot(self.eye), 1.0),
        );
        let (tx, ty) = self.half_extents(width, height);
        let proj = DMat4::from_cols(
            DVec4::new(1.0 / tx, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / ty, 0.0, 0.0),
            DVec4::new(0.0, 0.0, 1.0, 1.0),
            DVec4::new(0.0, 0.0, -NEAR, 0.0),
        );
        (proj * view).as_mat4()
    }
}

/// The camera's rays for one image size with the basis computed once: what [`Camera::ray`] computes,
/// for renderers that need a ray per pixel.
#[derive(Clone, Copy, Debug)]
pub struct Rays {
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    sx: f64,
    sy: f64,
}

impl Rays {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Rays {
        let (right, up, forward) = camera.basis();
        let (tx, ty) = camera.half_extents(width, height);
        Rays { right: right * tx, up: up * ty, forward, sx: 2.0 / width as f64, sy: 2.0 / height as f64 }
    }

    /// The unit direction through image point `(px, py)` in pixels.
    pub fn at(&self, px: f64, py: f64) -> DVec3 {
        let (x, y) = (px * self.sx - 1.0, py * self.sy - 1.0);
        (self.forward + x * self.right - y * self.up).normalize()
    }
}

impl fmt::Display for Camera {
    /// The form [`Camera::parse`] reads, every key given; `{}` of an `f64` is its shortest exact
    /// decimal, so `parse(&c.to_string()) == Ok(c)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = |d: DVec3| format!("{},{},{}", d.x, d.y, d.z);
        write!(f, "eye={} target={} up={} fov={}", v(self.eye), v(self.target), v(self.up), self.fov_deg)
    }
}
