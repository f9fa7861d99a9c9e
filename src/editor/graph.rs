//! The BRDF graph (paper Fig. 1, lower right): a polar plot of `f·cos θ_i` for the canvas light's
//! incident direction, over outgoing directions in its plane of incidence — one colour per lobe plus
//! the sum, linear or log scale — drawn on the CPU into the window's pixels.

use glam::DVec3;

use crate::brdf::Material;

const COLOURS: [[u8; 3]; 6] =
    [[230, 120, 60], [90, 170, 230], [120, 200, 110], [200, 120, 210], [230, 200, 80], [110, 210, 200]];

/// Draws into `rgba` (row stride `stride` pixels) the rectangle `(x0, y0, w, h)`.
#[allow(clippy::too_many_arguments)]
pub fn draw(
    rgba: &mut [u8],
    stride: usize,
    (x0, y0, w, h): (usize, usize, usize, usize),
    m: &Material,
    light: DVec3,
    log: bool,
) {
    if w < 8 || h < 8 {
        return;
    }
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            let k = 4 * (y * stride + x);
            rgba[k..k + 4].copy_from_slice(&[24, 24, 28, 255]);
        }
    }
    // The incident direction in the local frame of the canvas centre (n = +z): the light's elevation,
    // in the plane φ = 0.
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
        curves.push((dirs.iter().map(|&wo| mean(single.eval(wi, wo)) * wi.z).collect(), COLOURS[k % COLOURS.len()]));
    }
    curves.push((dirs.iter().map(|&wo| mean(m.eval(wi, wo)) * wi.z).collect(), [240, 240, 240]));
    let peak = curves.iter().flat_map(|c| c.0.iter()).fold(0.0f64, |a, &b| a.max(b)).max(1e-12);
    let scale = |v: f64| if log { ((v / peak).max(1e-6).log10() + 6.0) / 6.0 } else { v / peak };
    let (cx, cy) = (x0 as f64 + w as f64 / 2.0, (y0 + h) as f64 - 4.0);
    let radius = (w as f64 / 2.0 - 4.0).min(h as f64 - 8.0);
    let mut put = |x: f64, y: f64, c: [u8; 3]| {
        let (xi, yi) = (x.round() as i64, y.round() as i64);
        if xi >= x0 as i64 && xi < (x0 + w) as i64 && yi >= y0 as i64 && yi < (y0 + h) as i64 {
            let k = 4 * (yi as usize * stride + xi as usize);
            rgba[k..k + 3].copy_from_slice(&c);
        }
    };
    // The horizon and the light's direction.
    for k in 0..=200 {
        let t = k as f64 / 200.0;
        put(cx - radius + 2.0 * radius * t, cy, [70, 70, 80]);
        put(cx + wi.x * radius * t, cy - wi.z * radius * t, [120, 110, 60]);
    }
    for (values, colour) in &curves {
        let pts: Vec<(f64, f64)> = values
            .iter()
            .zip(&dirs)
            .map(|(&v, d)| (cx + d.x * radius * scale(v), cy - d.z * radius * scale(v)))
            .collect();
        for seg in pts.windows(2) {
            let ((ax, ay), (bx, by)) = (seg[0], seg[1]);
            let steps = ((bx - ax).abs().max((by - ay).abs()) as usize).max(1);
            for s in 0..=steps {
                let t = s as f64 / steps as f64;
                put(ax + (bx - ax) * t, ay + (by - ay) * t, *colour);
            }
        }
    }
}

fn mean(c: [f64; 3]) -> f64 {
    (c[0] + c[1] + c[2]) / 3.0
}
