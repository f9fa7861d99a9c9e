//! What the editor derives from the environment once per map: where the canvas light starts (the
//! brightest direction, seen from the orbiting camera) and the mesh view's automatic exposure.

use glam::DVec3;

use crate::scene::Environment;

/// What the editor needs of the environment beyond its texels, computed once per map (not per frame).
pub struct EnvSummary {
    /// `Environment::brightest_direction`, where the canvas light starts.
    pub brightest: DVec3,
    /// [`auto_exposure`]'s scale of the mesh view.
    pub exposure: f64,
}

impl EnvSummary {
    pub fn of(env: &Environment) -> EnvSummary {
        EnvSummary { brightest: env.brightest_direction(), exposure: auto_exposure(env) }
    }
}

/// The canvas light the editor starts with: the environment's brightest direction seen from the
/// camera (canvas x = right, y = up, z = towards the viewer).
pub fn light_from(env: &EnvSummary, state_camera: &crate::scene::Camera) -> DVec3 {
    let d = env.brightest;
    let (right, up, forward) = state_camera.basis();
    DVec3::new(d.dot(right), d.dot(up), -d.dot(forward)).normalize()
}

/// Scales the mesh view so the environment's mean radiance shows as mid grey.
pub fn auto_exposure(env: &Environment) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for j in 0..env.height {
        let o = env.texel_solid_angle(j);
        for t in &env.texels[j * env.width..(j + 1) * env.width] {
            s += (t[0] + t[1] + t[2]).max(0.0) as f64 / 3.0 * o;
            w += o;
        }
    }
    if s > 0.0 {
        (0.18 * w / s).clamp(1e-4, 1e4)
    } else {
        1.0
    }
}
