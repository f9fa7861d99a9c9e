//! The mesh camera of SPEC §1: perspective, `eye`, `target`, `up`, vertical field of view; pixel
//! `(i, j)` (column, row from the top) samples the ray through its centre. The same camera gives the
//! CPU reference its rays and the GPU rasteriser its view-projection matrix, and the two agree.

use glam::{DMat4, DVec3, DVec4, Mat4};

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    pub fov_deg: f64,
}

impl Default for Camera {
    /// `eye=(0,0,4) target=(0,0,0) up=(0,1,0) fov=30`.
    fn default() -> Self {
        Camera { eye: DVec3::new(0.0, 0.0, 4.0), target: DVec3::ZERO, up: DVec3::Y, fov_deg: 30.0 }
    }
}

/// Near and far planes of the projection (the scene fits the unit sphere; the eye may come close).
pub const NEAR: f64 = 1e-3;
pub const FAR: f64 = 1e3;

fn parse_vec(key: &str, v: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = v.split(',').collect();
    let nums: Option<Vec<f64>> = parts.iter().map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect();
    match nums {
        Some(n) if n.len() == 3 => Ok(DVec3::new(n[0], n[1], n[2])),
        _ => Err(format!("{key}: expected three finite numbers x,y,z, got \"{v}\"")),
    }
}

impl Camera {
    /// Parses `"eye=x,y,z target=x,y,z up=x,y,z fov=deg"`: any subset, any order, the rest default.
    pub fn parse(s: &str) -> Result<Camera, String> {
        let mut c = Camera::default();
        for item in s.split_whitespace() {
            let (key, value) = item.split_once('=').ok_or_else(|| format!("\"{item}\" is not key=value"))?;
            match key {
                "eye" => c.eye = parse_vec(key, value)?,
                "target" => c.target = parse_vec(key, value)?,
                "up" => c.up = parse_vec(key, value)?,
                "fov" => {
                    c.fov_deg = value
                        .parse::<f64>()
                        .ok()
                        .filter(|f| f.is_finite())
                        .ok_or_else(|| format!("fov: \"{value}\" is not a number"))?
                }
                _ => return Err(format!("unknown key \"{key}\" (eye, target, up, fov)")),
            }
        }
        c.check()?;
        Ok(c)
    }

    /// Refuses a camera without a view direction, with `up` along it, or with a field of view
    /// outside (0°, 180°).
    pub fn check(&self) -> Result<(), String> {
        let f = self.target - self.eye;
        if !(f.length() > 1e-12) {
            return Err("eye and target are the same point".into());
        }
        if !(f.normalize().cross(self.up).length() > 1e-9) {
            return Err("up is zero or parallel to the view direction".into());
        }
        if !(self.fov_deg > 0.0 && self.fov_deg < 180.0) {
            return Err(format!("fov: {} is not between 0 and 180 degrees", self.fov_deg));
        }
        Ok(())
    }

    /// The orthonormal basis (right, up, forward).
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        (right, right.cross(forward), forward)
    }

    /// The unit direction through image point `(px, py)` in pixels (pixel `(i, j)`'s centre is
    /// `(i + 0.5, j + 0.5)`, rows from the top).
    pub fn ray(&self, px: f64, py: f64, width: u32, height: u32) -> DVec3 {
        let (right, up, forward) = self.basis();
        let t = (self.fov_deg.to_radians() / 2.0).tan();
        let aspect = width as f64 / height as f64;
        let x = (2.0 * px / width as f64 - 1.0) * t * aspect;
        let y = (2.0 * py / height as f64 - 1.0) * t;
        (forward + x * right - y * up).normalize()
    }

    /// The view-projection for Vulkan: clip `y` points down the image (NDC `y = −1` is the top row),
    /// depth in `[0, 1]` between [`NEAR`] and [`FAR`]. A point `eye + s·ray(px, py)` lands at NDC
    /// `(2px/W − 1, 2py/H − 1)`.
    pub fn view_proj(&self, width: u32, height: u32) -> Mat4 {
        let (right, up, forward) = self.basis();
        // View space: x right, y down, z forward.
        let view = DMat4::from_cols(
            DVec4::new(right.x, -up.x, forward.x, 0.0),
            DVec4::new(right.y, -up.y, forward.y, 0.0),
            DVec4::new(right.z, -up.z, forward.z, 0.0),
            DVec4::new(-right.dot(self.eye), up.dot(self.eye), -forward.dot(self.eye), 1.0),
        );
        let t = (self.fov_deg.to_radians() / 2.0).tan();
        let aspect = width as f64 / height as f64;
        let (sx, sy) = (1.0 / (t * aspect), 1.0 / t);
        let a = FAR / (FAR - NEAR);
        let proj = DMat4::from_cols(
            DVec4::new(sx, 0.0, 0.0, 0.0),
            DVec4::new(0.0, sy, 0.0, 0.0),
            DVec4::new(0.0, 0.0, a, 1.0),
            DVec4::new(0.0, 0.0, -NEAR * a, 0.0),
        );
        (proj * view).as_mat4()
    }
}
