//! The BRDF graph (paper Fig. 1, lower right): a polar plot of `f·cos θ_i` for the canvas light's
//! incident direction, over outgoing directions in its plane of incidence — one colour per lobe plus
//! the sum, linear or log scale — drawn as egui shapes over the composed window (GPU triangles, no
//! CPU pixels). The curves are computed once per material and light ([`Curves`]).

use glam::DVec3;

use crate::brdf::Material;

const COLOURS: [[u8; 3]; 6] =
    [[230, 120, 60], [90, 170, 230], [120, 200, 110], [200, 120, 210], [230, 200, 80], [110, 210, 200]];

/// The plot's data: the light's incident direction, the outgoing directions and one curve per lobe
/// plus the sum (values of `f·cos θ_i`, channel mean).
pub struct Curves {
    wi: DVec3,
    dirs: Vec<DVec3>,
    curves: Vec<(Vec<f64>, [u8; 3])>,
    peak: f64,
}

impl Curves {
    pub fn new(m: &Material, light: DVec3) -> Curves {
        // The incident direction in the local frame of the canvas centre (n = +z): the light's
        // elevation, in the plane φ = 0.
        let theta_i = light.z.clamp(-1.0, 1.0).acos().min(89.0f64.to_radians());
        let wi = DVec3::new(-theta_i.sin(), 0.0, theta_i.cos());
        let n = 181;
        let dirs: Vec<DVec3> = (0..n)
            .map(|k| {
                let t = (-90.0 + 180.0 * k as f64 / (n - 1) as f64).to_radians();
                DVec3::new(t.sin(), 0.0, t.cos().max(1e-4)).normalize()
            })
            .collect();
        let mut curves: Vec<(Vec<f64>, [u8; 3])> = Vec::new();
        for (k, lobe) in m.lobes.iter().enumerate() {
            let single = crate::brdf::Material { diffuse: [0.0; 3], lobes: vec![lobe.clone()], ..m.clone() };
            curves
                .push((dirs.iter().map(|&wo| mean(single.eval(wi, wo)) * wi.z).collect(), COLOURS[k % COLOURS.len()]));
        }
        curves.push((dirs.iter().map(|&wo| mean(m.eval(wi, wo)) * wi.z).collect(), [240, 240, 240]));
        let peak = curves.iter().flat_map(|c| c.0.iter()).fold(0.0f64, |a, &b| a.max(b)).max(1e-12);
        let peak = if peak.is_finite() { peak } else { 1.0 };
        Curves { wi, dirs, curves, peak }
    }

    /// Paints the plot into `rect` (window points) with `painter`: background, horizon, the light's
    /// direction and the curves.
    pub fn paint(&self, painter: &egui::Painter, rect: egui::Rect, log: bool) {
        if rect.width() < 8.0 || rect.height() < 8.0 {
            return;
        }
        let rgb = |c: [u8; 3]| egui::Color32::from_rgb(c[0], c[1], c[2]);
        painter.rect_filled(rect, 0.0, rgb([24, 24, 28]));
        let scale = |v: f64| {
            let s = if log { ((v / self.peak).max(1e-6).log10() + 6.0) / 6.0 } else { v / self.peak };
            if s.is_finite() {
                s.clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let (cx, cy) = (rect.center().x as f64, rect.bottom() as f64 - 4.0);
        let radius = (rect.width() as f64 / 2.0 - 4.0).min(rect.height() as f64 - 8.0);
        let at = |x: f64, y: f64| egui::pos2(x as f32, y as f32);
        let thin = |c: [u8; 3]| egui::Stroke::new(1.0, rgb(c));
        painter.line_segment([at(cx - radius, cy), at(cx + radius, cy)], thin([70, 70, 80]));
        painter.line_segment([at(cx, cy), at(cx + self.wi.x * radius, cy - self.wi.z * radius)], thin([120, 110, 60]));
        for (values, colour) in &self.curves {
            let pts: Vec<egui::Pos2> = values
                .iter()
                .zip(&self.dirs)
                .map(|(&v, d)| at(cx + d.x * radius * scale(v), cy - d.z * radius * scale(v)))
                .collect();
            painter.add(egui::Shape::line(pts, thin(*colour)));
        }
    }
}
fn mean(c: [f64; 3]) -> f64 {
    (c[0] + c[1] + c[2]) / 3.0
}
