//! Brush behaviour measured on the canvas image computed on the CPU (docs/model.md, Frames and conventions and The
//! paper model; paper §3.3).

use brdf_shop::brdf::{Material, ALPHA_MAX, ALPHA_MIN};
use brdf_shop::brush::brushes::{self, eq3_alpha, ModifyRule, Settings};
use brdf_shop::brush::{Canvas, Strokes};
use glam::{DQuat, DVec3};
use proptest::prelude::*;

const SIZE: usize = 512;

fn settings(light: [f64; 3], split: bool) -> Settings {
    let mut s = Settings::new(Canvas::new(DVec3::from_array(light), 1.0).unwrap());
    s.split_lobes = split;
    s
}

/// Lobe `k` alone (diffuse and the other lobes removed, unit albedo), so the image is its radiance.
fn lobe_only(m: &Material, k: usize) -> Material {
    let mut l = m.lobes[k].clone();
    l.albedo = [1.0; 3];
    Material { diffuse: [0.0; 3], lobes: vec![l], ..m.clone() }
}

/// The brightest pixel of the canvas image (column, row) and its value, over `window` if given.
fn argmax(img: &[[f64; 3]], window: Option<(f64, f64, f64)>) -> ((usize, usize), f64) {
    let mut best = ((0, 0), f64::NEG_INFINITY);
    for (p, v) in img.iter().enumerate() {
        let (i, j) = (p % SIZE, p / SIZE);
        if let Some((cu, cv, r)) = window {
            let (u, w) = ((i as f64 + 0.5) / SIZE as f64, (j as f64 + 0.5) / SIZE as f64);
            if (u - cu).hypot(w - cv) > r {
                continue;
            }
        }
        if v[0] > best.1 {
            best = ((i, j), v[0]);
        }
    }
    best
}

/// The pixel containing canvas point `p`.
fn pixel(p: (f64, f64)) -> (f64, f64) {
    (p.0 * SIZE as f64 - 0.5, p.1 * SIZE as f64 - 0.5)
}

const LIGHTS: [[f64; 3]; 3] = [[0.3, 0.4, 0.866], [0.0, 0.0, 1.0], [-0.6, -0.2, 0.77]];
const CLICKS: [(f64, f64); 4] = [(0.62, 0.35), (0.40, 0.62), (0.5, 0.5), (0.3, 0.3)];

#[test]
fn create_peaks_at_the_clicked_point() {
    for light in LIGHTS {
        for split in [false, true] {
            let s = settings(light, split);
            for (click, start) in
                CLICKS.into_iter().flat_map(|c| [(c, Material::scratch()), (c, Material::scratch_paper())])
            {
                let Ok((m, k)) = brushes::create(&start, &s, click) else {
                    continue; // refused where n·L ≤ 0; tested below
                };
                let img = s.canvas.image(&lobe_only(&m, k), SIZE);
                // A split lobe shows a second highlight elsewhere: look near the click for it.
                let window = split.then_some((click.0, click.1, 0.05));
                let ((i, j), _) = argmax(&img, window);
                let (pi, pj) = pixel(click);
                let d = (i as f64 - pi).hypot(j as f64 - pj);
                assert!(
                    d <= 1.0,
                    "light {light:?} click {click:?} split {split}: peak pixel ({i}, {j}) is {d:.2} px away"
                );
            }
        }
    }
}

#[test]
fn create_refuses_where_the_light_does_not_reach_and_off_the_sphere() {
    let s = settings([1.0, 0.0, 0.05], false);
    let e = brushes::create(&Material::scratch(), &s, (0.1, 0.5)).unwrap_err().to_string();
    assert!(e.contains("n·L"), "{e}");
    let e = brushes::create(&Material::scratch(), &s, (0.01, 0.01)).unwrap_err().to_string();
    assert!(e.contains("off the canvas sphere"), "{e}");
}

#[test]
fn create_snaps_to_the_mirror_point() {
    let s = settings([0.3, 0.4, 0.866], false);
    let mp = s.canvas.mirror_point().unwrap();
    let (m, k) = brushes::create(&Material::scratch(), &s, (mp.0 + 0.005, mp.1 - 0.004)).unwrap();
    assert_eq!(m.lobes[k].rotation, DQuat::IDENTITY);
    let (m, k) = brushes::create(&Material::scratch(), &s, (mp.0 + 0.05, mp.1)).unwrap();
    assert_ne!(m.lobes[k].rotation, DQuat::IDENTITY);
}

/// Brush positions a short drag from the highlight, toward and across the light.
const DRAGS: [((f64, f64), (f64, f64)); 4] = [
    ((0.62, 0.35), (0.65, 0.35)),
    ((0.40, 0.62), (0.45, 0.58)),
    ((0.5, 0.5), (0.5, 0.46)),
    ((0.62, 0.35), (0.60, 0.32)),
];

/// `radiance(brush) / max radiance` of lobe `k` on the 512² image: of the highlight the brush acts on,
/// so a split reciprocal lobe counts its first facet alone (its other face lights a second highlight
/// of a different brightness elsewhere).
fn image_ratio(s: &Settings, m: &Material, k: usize, brush: (f64, f64)) -> f64 {
    let mut m = m.clone();
    if m.normalization == brdf_shop::brdf::Normalization::Reciprocal {
        m.lobes[k].split = false;
    }
    let m = &m;
    let img = s.canvas.image(&lobe_only(m, k), SIZE);
    let (_, peak) = argmax(&img, None);
    let at = s.canvas.radiance(&lobe_only(m, k), brush.0, brush.1)[0];
    at / peak
}

#[test]
fn modify_puts_the_brush_at_gamma_of_the_peak() {
    // Both constructions: the reciprocal default and the paper's, split and not.
    for (split, start) in
        [false, true].into_iter().flat_map(|sp| [(sp, Material::scratch()), (sp, Material::scratch_paper())])
    {
        let s = settings([0.3, 0.4, 0.866], split);
        for (click, brush) in DRAGS {
            let (m, k) = brushes::create(&start, &s, click).unwrap();
            let m = brushes::modify(&m, &s, k, brush).unwrap();
            let l = &m.lobes[k];
            assert_eq!(l.alpha_x, l.alpha_y);
            let r = image_ratio(&s, &m, k, brush);
            assert!((r - s.gamma).abs() <= 0.02, "split {split} {click:?}→{brush:?}: ratio {r:.4}, α {}", l.alpha_x);
        }
    }
}

/// The principal axis (degrees, modulo 180) of the pixels above half the peak, weighted by radiance.
fn principal_axis(img: &[[f64; 3]], centre: (f64, f64), radius: f64) -> f64 {
    let (_, peak) = argmax(img, Some((centre.0, centre.1, radius)));
    let (mut sw, mut mx, mut my) = (0.0, 0.0, 0.0);
    let mut pts = Vec::new();
    for (p, v) in img.iter().enumerate() {
        let (x, y) = ((p % SIZE) as f64, (p / SIZE) as f64);
        let (u, w) = ((x + 0.5) / SIZE as f64, (y + 0.5) / SIZE as f64);
        if v[0] > 0.5 * peak && (u - centre.0).hypot(w - centre.1) < radius {
            pts.push((x, y, v[0]));
            sw += v[0];
            mx += v[0] * x;
            my += v[0] * y;
        }
    }
    let (mx, my) = (mx / sw, my / sw);
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (x, y, w) in pts {
        sxx += w * (x - mx) * (x - mx);
        syy += w * (y - my) * (y - my);
        sxy += w * (x - mx) * (y - my);
    }
    (0.5 * (2.0 * sxy).atan2(sxx - syy)).to_degrees()
}

fn axis_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

#[test]
fn streak_points_at_the_brush_and_sets_gamma() {
    let s = settings([0.3, 0.4, 0.866], false);
    for (click, brush) in DRAGS {
        let (m, k) = brushes::create(&Material::scratch(), &s, click).unwrap();
        let m = brushes::streak(&m, &s, k, brush).unwrap();
        let l = &m.lobes[k];
        assert!(l.alpha_x > l.alpha_y, "streak widens x only: {l:?}");
        let r = image_ratio(&s, &m, k, brush);
        assert!((r - s.gamma).abs() <= 0.02, "{click:?}→{brush:?}: ratio {r:.4}");
        let img = s.canvas.image(&lobe_only(&m, k), SIZE);
        let dist = (brush.0 - click.0).hypot(brush.1 - click.1);
        let axis = principal_axis(&img, click, 1.5 * dist);
        let want = (brush.1 - click.1).atan2(brush.0 - click.0).to_degrees();
        let d = axis_difference(axis, want);
        println!("{click:?}→{brush:?}: streak axis {axis:.2}°, brush direction {want:.2}°, off by {d:.2}°");
        assert!(d <= 2.0, "{click:?}→{brush:?}: axis {axis:.2}° vs brush {want:.2}°");
    }
}

#[test]
fn eq3_option_follows_its_formula() {
    let mut s = settings([0.3, 0.4, 0.866], false);
    for rule in [ModifyRule::Eq3, ModifyRule::Eq3Printed] {
        s.modify_rule = rule;
        for (click, brush) in DRAGS {
            // Eq. 3 is the paper's formula for its rotated views.
            let (m, k) = brushes::create(&Material::scratch_paper(), &s, click).unwrap();
            let out = brushes::modify(&m, &s, k, brush).unwrap();
            // Recompute eq. 3 from the canvas geometry here: n at the brush, its frame, ω_r, R ω_o.
            let (x, y) = (2.0 * brush.0 - 1.0, 1.0 - 2.0 * brush.1);
            let n = DVec3::new(x, y, (1.0 - x * x - y * y).sqrt());
            let t = DVec3::Y.cross(n).normalize();
            let b = n.cross(t);
            let local = |v: DVec3| DVec3::new(v.dot(t), v.dot(b), v.dot(n));
            let l = s.canvas.light;
            let wr = local(2.0 * n.dot(l) * n - l);
            let c = wr.dot(m.lobes[k].rotation * local(DVec3::Z));
            let want = match rule {
                ModifyRule::Eq3Printed => std::f64::consts::SQRT_2 * c.ln() / s.gamma.ln(),
                _ => (2.0 * c.ln() / s.gamma.ln()).sqrt(),
            }
            .clamp(ALPHA_MIN, ALPHA_MAX);
            assert!(
                (out.lobes[k].alpha_x - want).abs() <= 1e-12 * want,
                "{rule:?}: {} vs {want}",
                out.lobes[k].alpha_x
            );
            let lib = eq3_alpha(rule, c, s.gamma).clamp(ALPHA_MIN, ALPHA_MAX);
            assert!((lib - want).abs() <= 1e-12 * want);
        }
    }
}

#[test]
fn intensify_takes_from_diffuse_first_then_other_lobes() {
    let s = settings([0.3, 0.4, 0.866], false);
    let (m, _) = brushes::create(&Material::scratch(), &s, (0.62, 0.35)).unwrap();
    let (m, _) = brushes::create(&m, &s, (0.40, 0.62)).unwrap();
    // Scratch diffuse 0.5 + two lobes of 0.2 = 0.9: 0.1 of free budget first.
    let a = brushes::intensify(&m, &s, 0).unwrap();
    assert_eq!(a.diffuse, m.diffuse);
    assert!((a.lobes[0].albedo[0] - 0.25).abs() < 1e-15);
    // Next steps eat the free budget, then the diffuse term; the other lobe is untouched.
    let mut b = a.clone();
    for _ in 0..11 {
        b = brushes::intensify(&b, &s, 0).unwrap();
    }
    assert!(b.diffuse[0].abs() < 1e-12, "{b:?}");
    assert_eq!(b.lobes[1].albedo, m.lobes[1].albedo);
    // Then the other lobes give way, and the sum never passes 1.
    let c = brushes::intensify(&b, &s, 0).unwrap();
    assert!(c.lobes[1].albedo[0] < b.lobes[1].albedo[0]);
    assert!(c.energy_sums().iter().all(|&v| v <= 1.0 + 1e-12));
    // De-intensify hands albedo back to the diffuse term, total unchanged.
    let d = brushes::deintensify(&c, &s, 0).unwrap();
    assert!((d.diffuse[0] - c.diffuse[0] - 0.05).abs() < 1e-12);
    assert!((d.energy_sums()[0] - c.energy_sums()[0]).abs() < 1e-12);
}

#[test]
fn replay_is_bit_for_bit_reproducible() {
    let text = include_str!("../assets/default.strokes.json");
    let s = Strokes::from_json(text, "default").unwrap();
    let a = s.replay(&Material::scratch(), "default").unwrap();
    let b = Strokes::from_json(text, "default").unwrap().replay(&Material::scratch(), "default").unwrap();
    assert_eq!(a.to_json(), b.to_json());
    assert_eq!(a, b);
    // And it reads back bit for bit.
    assert_eq!(Material::from_json(&a.to_json(), "x").unwrap(), a);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    /// Any sequence of strokes keeps the energy bound and never produces a NaN.
    #[test]
    fn every_brush_keeps_the_energy_bound(ops in prop::collection::vec((0u8..5, 0.05f64..0.95, 0.05f64..0.95, -0.04f64..0.04, -0.04f64..0.04), 1..12)) {
        let s = settings([0.2, 0.3, 0.93], true);
        let mut m = Material::scratch();
        for (op, u, v, du, dv) in ops {
            let k = brushes::lobe_under(&m, &s.canvas, (u, v)).unwrap_or(0);
            let next = match op {
                0 => brushes::create(&m, &s, (u, v)).map(|r| r.0),
                1 => brushes::modify(&m, &s, k, ((u + du).clamp(0.0, 1.0), (v + dv).clamp(0.0, 1.0))),
                2 => brushes::streak(&m, &s, k, ((u + du).clamp(0.0, 1.0), (v + dv).clamp(0.0, 1.0))),
                3 => brushes::intensify(&m, &s, k),
                _ => brushes::deintensify(&m, &s, k),
            };
            if let Ok(n) = next {
                m = n;
            }
            prop_assert!(m.energy_sums().iter().all(|&v| v <= 1.0 + 1e-12), "{:?}", m);
            prop_assert!(m.validate("m").is_ok());
            let f = m.eval(DVec3::new(0.1, 0.2, 0.9), DVec3::new(-0.3, 0.1, 0.8));
            prop_assert!(f.iter().all(|v| v.is_finite()));
        }
    }
}
