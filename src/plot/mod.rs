//! The pictures of a material that are plots rather than renders, as geometry and data: the 3-D
//! view of `f·cos θ_i` over the hemisphere for the canvas light ([`lobe3d`]) and the directional
//! albedo against the view angle ([`albedo`]). Plain Rust on `f64`: no window, GPU or drawing
//! library. The editor paints these with egui shapes (`editor::graph`), `brdf-shop plot` with
//! `plotters` into a PNG (`cli/plot.rs`); both draw the same lines.

pub mod albedo;
pub mod lobe3d;

use glam::DVec3;

/// One colour per lobe (lobe `k` takes `COLOURS[k % 6]`), in the editor's graphs and in the PNGs.
pub const COLOURS: [[u8; 3]; 6] =
    [[230, 120, 60], [90, 170, 230], [120, 200, 110], [200, 120, 210], [230, 200, 80], [110, 210, 200]];

/// The colour of the sum of the lobes and the diffuse term (the total).
pub const SUM_COLOUR: [u8; 3] = [240, 240, 240];

/// The plots' background (dark: the lobe colours and the white sum are made for it).
pub const BACKGROUND: [u8; 3] = [24, 24, 28];

/// The colour of lobe `k`.
pub fn lobe_colour(k: usize) -> [u8; 3] {
    COLOURS[k % COLOURS.len()]
}

/// A polyline in a plot's own 2-D coordinates, in one colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub points: Vec<[f64; 2]>,
    pub colour: [u8; 3],
}

/// The map from a plot's box `[left, right, bottom, top]` onto the pixel rectangle `(x, y, width,
/// height)` (`y` down) that keeps the aspect and centres the box, `margin` pixels inside:
/// `[px, py] = [ox + s·u, oy − s·v]` as `(ox, oy, s)`.
pub fn fit(frame: [f64; 4], rect: [f64; 4], margin: f64) -> (f64, f64, f64) {
    let [l, r, b, t] = frame;
    let [x, y, w, h] = rect;
    let s = ((w - 2.0 * margin) / (r - l)).min((h - 2.0 * margin) / (t - b)).max(0.0);
    let (cx, cy) = (x + w / 2.0, y + h / 2.0);
    (cx - s * (l + r) / 2.0, cy + s * (b + t) / 2.0, s)
}

/// How a value of `f·cos θ_i` becomes a distance from the origin: a share of the peak, or six
/// decades of it on a log scale (the graph's `G` key).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    Linear,
    Log,
}

impl Scale {
    /// `v` against `peak` in [0, 1]: `v / peak`, or `(log₁₀(v / peak) + 6) / 6` above 10⁻⁶ of the
    /// peak; 0 for what is not a finite number.
    pub fn radius(self, v: f64, peak: f64) -> f64 {
        let s = match self {
            Scale::Linear => v / peak,
            Scale::Log => ((v / peak).max(1e-6).log10() + 6.0) / 6.0,
        };
        if s.is_finite() {
            s.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// The incident direction the graphs use for a canvas light `light` (canvas space): in the local
/// frame of the canvas centre (`n = +z`), the light's elevation in the plane `φ = 0`, on the side of
/// negative `x`, at most 89° from the normal (a light at or below the horizon, or not a number, is
/// drawn at 89°).
pub fn incident(light: DVec3) -> DVec3 {
    let theta_i = elevation(light);
    DVec3::new(-theta_i.sin(), 0.0, theta_i.cos())
}

/// The polar angle of [`incident`] (radians).
pub fn elevation(light: DVec3) -> f64 {
    light.z.clamp(-1.0, 1.0).acos().min(89.0f64.to_radians())
}

/// The mean of the three channels: what the graphs plot of an RGB value.
pub fn mean(c: [f64; 3]) -> f64 {
    (c[0] + c[1] + c[2]) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_map_the_peak_to_one_and_nothing_to_zero() {
        for s in [Scale::Linear, Scale::Log] {
            assert_eq!(s.radius(2.0, 2.0), 1.0);
            assert_eq!(s.radius(0.0, 2.0), 0.0);
            assert_eq!(s.radius(f64::NAN, 2.0), 0.0);
            assert_eq!(s.radius(f64::INFINITY, f64::INFINITY), 0.0);
        }
        assert!((Scale::Log.radius(1e-3, 1.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn fit_centres_the_box_and_keeps_its_aspect() {
        let (ox, oy, s) = fit([-1.0, 1.0, -0.5, 1.0], [10.0, 20.0, 400.0, 100.0], 5.0);
        assert_eq!(s, 60.0);
        assert_eq!([ox - s, oy - s], [150.0, 25.0]);
        assert_eq!([ox + s, oy + 0.5 * s], [270.0, 115.0]);
    }

    #[test]
    fn the_incident_direction_keeps_the_elevation_and_stops_at_89_degrees() {
        let l = DVec3::new(0.3, 0.4, 0.866).normalize();
        let wi = incident(l);
        assert!((wi.z - l.z).abs() < 1e-12 && wi.x < 0.0 && wi.y == 0.0);
        for below in [DVec3::new(0.0, 1.0, -0.5), DVec3::splat(f64::NAN)] {
            assert!((incident(below).z - 89.0f64.to_radians().cos()).abs() < 1e-12);
        }
    }
}
