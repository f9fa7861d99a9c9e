//! The environment map (docs/model.md, Frames and conventions) on the CPU: loading the real maps and refusing bad
//! files, the texel policy and its report, the equirect mapping, bilinear lookup across the `u` seam, the mip chain,
//! SH9 irradiance, the brightest direction and the sampling distribution.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use brdf_shop::scene::env::{sh_irradiance, Environment};
use glam::DVec3;

fn hdri(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/hdri").join(name)
}

const MAPS: [&str; 10] = [
    "apartment.exr",
    "bridge.exr",
    "city.exr",
    "dawn.exr",
    "forest.exr",
    "hall.exr",
    "sky.exr",
    "studio.exr",
    "venice.exr",
    "warehouse.exr",
];

#[test]
fn every_real_map_loads_with_its_report() {
    let mut any_negative = false;
    for name in MAPS {
        let e = Environment::load(&hdri(name)).unwrap_or_else(|err| panic!("{name}: {err}"));
        assert_eq!((e.width, e.height), (512, 256), "{name}");
        let s = &e.stats;
        eprintln!(
            "{name}: {} non-finite, {} negative, {:.2} % negative energy",
            s.non_finite,
            s.negative,
            100.0 * s.negative_energy_fraction
        );
        // docs/model.md, Frames and conventions: the lossy maps carry up to 10 % negative energy; 15 % leaves room for
        // the solid-angle weighting of this count.
        assert!((0.0..0.15).contains(&s.negative_energy_fraction), "{name}: {}", s.negative_energy_fraction);
        any_negative |= s.negative > 0;
        assert!(e.texels.iter().flatten().all(|v| v.is_finite()));
    }
    assert!(any_negative, "the DWAB maps carry negative texels; none were kept");
    let sky = Environment::load(&hdri("sky.exr")).unwrap();
    let peak = sky.texels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    assert!(peak > 1e4, "the sky's sun: {peak}");
}

#[test]
fn bad_files_are_refused_with_their_name() {
    let dir = tempfile::TempDir::new().unwrap();
    let good = std::fs::read(hdri("city.exr")).unwrap();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("truncated.exr", good[..good.len() / 3].to_vec()),
        ("text.exr", b"this is not an image".to_vec()),
        ("text.hdr", b"#?RADIANCE\nnonsense".to_vec()),
        ("map.png", vec![0; 16]),
    ];
    for (name, bytes) in cases {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let err = Environment::load(&p).expect_err(name).to_string();
        assert!(err.contains(name), "{name}: {err}");
    }
    let missing = dir.path().join("missing.exr");
    assert!(Environment::load(&missing).unwrap_err().to_string().contains("missing.exr"));
    assert!(Environment::from_texels(0, 4, vec![], "empty").is_err());
    assert!(Environment::from_texels(2, 2, vec![[0.0; 3]; 3], "short").is_err());
}

/// Tiled and scanline EXR in several compressions, and Radiance HDR, read back to what was written
/// (half floats: 1e-3 relative; RGBE: 1 % of the texel's largest channel, whose exponent the three
/// 8-bit mantissas share — the formats' own precision).
#[test]
fn tiled_scanline_exr_and_hdr_read_back() {
    use exr::prelude::*;
    let dir = tempfile::TempDir::new().unwrap();
    let (w, h) = (37usize, 19usize);
    let value =
        |x: usize, y: usize| [0.1 + x as f32 * 0.3, 2.0 + y as f32, 1000.0 * (x == 5 && y == 7) as i32 as f32 + 0.5];
    for (name, compression, tiled) in [
        ("zip-lines.exr", Compression::ZIP16, false),
        ("piz-tiles.exr", Compression::PIZ, true),
        ("rle-tiles.exr", Compression::RLE, true),
        ("b44-lines.exr", Compression::Uncompressed, false),
    ] {
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let v = value(p.x(), p.y());
            (f16::from_f32(v[0]), f16::from_f32(v[1]), f16::from_f32(v[2]))
        });
        let blocks = if tiled { Blocks::Tiles(Vec2(16, 8)) } else { Blocks::ScanLines };
        let encoding = Encoding { compression, blocks, line_order: LineOrder::Increasing };
        let layer = Layer::new((w, h), LayerAttributes::named("rgb"), encoding, channels);
        let path = dir.path().join(name);
        exr::image::Image::from_layer(layer).write().to_file(&path).unwrap();
        let e = Environment::load(&path).unwrap_or_else(|err| panic!("{name}: {err}"));
        assert_eq!((e.width, e.height), (w, h));
        for y in 0..h {
            for x in 0..w {
                let (got, want) = (e.texels[y * w + x], value(x, y));
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() <= 1e-3 * want[c].abs() + 1e-3,
                        "{name} ({x},{y}): {got:?} {want:?}"
                    );
                }
            }
        }
    }
    let rgb: Vec<image::Rgb<f32>> = (0..w * h).map(|k| image::Rgb(value(k % w, k / w))).collect();
    let path = dir.path().join("map.hdr");
    let f = std::fs::File::create(&path).unwrap();
    image::codecs::hdr::HdrEncoder::new(f).encode(&rgb, w, h).unwrap();
    let e = Environment::load(&path).unwrap();
    for (k, t) in e.texels.iter().enumerate() {
        let want = value(k % w, k / w);
        let largest = want.iter().fold(0.0f32, |a, &b| a.max(b));
        for c in 0..3 {
            assert!((t[c] - want[c]).abs() <= 0.01 * largest, "hdr texel {k}: {t:?} {want:?}");
        }
    }
}

#[test]
fn non_finite_texels_become_zero_and_negatives_stay() {
    let e = Environment::from_texels(2, 1, vec![[f32::NAN, f32::INFINITY, 1.0], [-2.0, 1.0, 1.0]], "t").unwrap();
    assert_eq!(e.texels[0], [0.0, 0.0, 1.0]);
    assert_eq!(e.texels[1], [-2.0, 1.0, 1.0]);
    assert_eq!((e.stats.non_finite, e.stats.negative), (2, 1));
    // Energy of the negative texel: |mean| = 0 (−2+1+1)/3 … use a clearly negative one.
    let e = Environment::from_texels(2, 1, vec![[1.0; 3], [-1.0; 3]], "t").unwrap();
    assert!((e.stats.negative_energy_fraction - 0.5).abs() < 1e-12);
}

#[test]
fn equirect_mapping_follows_spec() {
    // docs/model.md, Frames and conventions: u = 0 looks down −z, u = 0.25 down +x, v = 0 is +y.
    let (u, v) = Environment::uv(DVec3::new(0.0, 0.0, -1.0));
    assert!(u.abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
    let (u, _) = Environment::uv(DVec3::X);
    assert!((u - 0.25).abs() < 1e-12);
    assert!(Environment::uv(DVec3::Y).1.abs() < 1e-12);
    for k in 0..200 {
        let (u, v) = ((k as f64 * 0.618).fract(), 0.01 + 0.98 * (k as f64 * 0.377).fract());
        let (u2, v2) = Environment::uv(Environment::direction(u, v));
        assert!(((u - u2 + 0.5).rem_euclid(1.0) - 0.5).abs() < 1e-12 && (v - v2).abs() < 1e-12);
    }
}

#[test]
fn lookup_is_bilinear_and_continuous_across_the_seam() {
    let (w, h) = (8, 4);
    let t: Vec<[f32; 3]> = (0..w * h).map(|k| [(k % w) as f32, (k / w) as f32, 1.0]).collect();
    let e = Environment::from_texels(w, h, t, "ramp").unwrap();
    // At a texel centre: the texel.
    let d = Environment::direction(2.5 / w as f64, 1.5 / h as f64);
    assert!((e.lookup(d) - DVec3::new(2.0, 1.0, 1.0)).length() < 1e-9);
    // Either side of u = 0: the average of the first and last columns.
    let a = e.lookup(Environment::direction(1e-9, 1.5 / h as f64));
    let b = e.lookup(Environment::direction(1.0 - 1e-9, 1.5 / h as f64));
    assert!((a - b).length() < 1e-6 && (a.x - 3.5).abs() < 1e-6, "{a} {b}");
}

#[test]
fn mip_chain_keeps_the_weighted_mean_and_the_seam_symmetry() {
    let e = Environment::load(&hdri("venice.exr")).unwrap();
    let levels = e.mip_chain();
    assert_eq!(levels.len(), 10);
    assert_eq!((levels[9].width, levels[9].height), (1, 1));
    let mean = |w: usize, h: usize, t: &[[f32; 4]]| -> f64 {
        let (mut s, mut ws) = (0.0, 0.0);
        for (k, p) in t.iter().enumerate() {
            let o = (PI * ((k / w) as f64 + 0.5) / h as f64).sin();
            s += p[0] as f64 * o;
            ws += o;
        }
        s / ws
    };
    let m0 = mean(levels[0].width, levels[0].height, &levels[0].texels);
    for l in &levels[1..] {
        let m = mean(l.width, l.height, &l.texels);
        // Each level averages sin θ-weighted texels, but weighs its own rows by their centre's
        // sin θ: the discretisation of that weight shifts the mean by up to a few % at the coarsest
        // (2- and 1-row) levels; 6 % bounds it.
        assert!((m / m0 - 1.0).abs() < 0.06, "level {}x{}: {m} vs {m0}", l.width, l.height);
    }
    // A map symmetric under u → 1 − u keeps that symmetry at every level (no seam bias).
    let (w, h) = (16, 8);
    let t: Vec<[f32; 3]> = (0..w * h)
        .map(|k| {
            let i = k % w;
            let d = i.min(w - 1 - i) as f32;
            [d, d * d, 1.0]
        })
        .collect();
    let s = Environment::from_texels(w, h, t, "sym").unwrap();
    for l in s.mip_chain() {
        for j in 0..l.height {
            for i in 0..l.width {
                let (a, b) = (l.texels[j * l.width + i], l.texels[j * l.width + l.width - 1 - i]);
                assert!((a[0] - b[0]).abs() < 1e-5 && (a[1] - b[1]).abs() < 1e-4, "{}x{} ({i},{j})", l.width, l.height);
            }
        }
    }
}

#[test]
fn sh9_irradiance_of_a_constant_map_is_pi_l() {
    let e = Environment::from_texels(64, 32, vec![[2.0, 1.0, 0.5]; 64 * 32], "constant").unwrap();
    let sh = e.sh9();
    for k in 0..50 {
        let n = Environment::direction((k as f64 * 0.618).fract(), (k as f64 * 0.377).fract());
        let irr = sh_irradiance(&sh, n);
        // Texel-centre quadrature on 32 rows overestimates ∫ sin θ dθ by (π/64)/sin(π/64) − 1 = 0.04 %.
        for (got, want) in [irr.x, irr.y, irr.z].iter().zip([2.0, 1.0, 0.5]) {
            assert!((got / (PI * want) - 1.0).abs() < 0.005, "{n}: {irr}");
        }
    }
}

/// SH9 against brute-force irradiance `Σ L max(n·ω, 0) Ω` on a real map: the truncation error of
/// nine coefficients, measured (printed) and bounded at 10 % of the mean irradiance.
#[test]
fn sh9_irradiance_is_close_to_brute_force() {
    let e = Environment::load(&hdri("city.exr")).unwrap();
    let sh = e.sh9();
    let mut worst = 0.0f64;
    let mut mean = 0.0;
    let normals: Vec<DVec3> = (0..40)
        .map(|k| Environment::direction((k as f64 * 0.618).fract(), 0.05 + 0.9 * (k as f64 * 0.377).fract()))
        .collect();
    for &n in &normals {
        let mut exact = 0.0;
        for j in 0..e.height {
            let o = e.texel_solid_angle(j);
            for i in 0..e.width {
                let d = Environment::direction((i as f64 + 0.5) / e.width as f64, (j as f64 + 0.5) / e.height as f64);
                let t = e.texels[j * e.width + i];
                exact += (t[0] + t[1] + t[2]) as f64 / 3.0 * n.dot(d).max(0.0) * o;
            }
        }
        let s = sh_irradiance(&sh, n);
        worst = worst.max((((s.x + s.y + s.z) / 3.0) - exact).abs());
        mean += exact / normals.len() as f64;
    }
    eprintln!("city.exr: SH9 irradiance worst error {:.3} % of the mean irradiance", 100.0 * worst / mean);
    assert!(worst / mean < 0.10);
}

#[test]
fn brightest_direction_prefers_a_small_sun_to_a_large_wall_and_noise() {
    let (w, h) = (256, 128);
    let mut t = vec![[1.0f32; 3]; w * h];
    // A wall of 60×40 texels at 50 (far more energy than the sun) …
    for j in 70..110 {
        for i in 10..70 {
            t[j * w + i] = [50.0; 3];
        }
    }
    // … a lone hot texel (noise) at 5e4 …
    t[100 * w + 200] = [5e4; 3];
    // … and a 3×3 sun at 2e4 with a ring of negative texels.
    let (si, sj) = (150usize, 30usize);
    for dj in -2i64..=2 {
        for di in -2i64..=2 {
            let k = (sj as i64 + dj) as usize * w + (si as i64 + di) as usize;
            t[k] = if di.abs() <= 1 && dj.abs() <= 1 { [2e4; 3] } else { [-2e3; 3] };
        }
    }
    let e = Environment::from_texels(w, h, t, "synthetic").unwrap();
    let d = e.brightest_direction();
    let sun = Environment::direction((si as f64 + 0.5) / w as f64, (sj as f64 + 0.5) / h as f64);
    let texel = PI / h as f64;
    assert!(d.angle_between(sun) < texel, "{d} vs sun {sun}: {} texels", d.angle_between(sun) / texel);
    let sky = Environment::load(&hdri("sky.exr")).unwrap().brightest_direction();
    assert!(sky.y > 0.0, "the sky's sun is above the horizon: {sky}");
}

#[test]
fn distribution_samples_follow_their_pdf() {
    let e = Environment::load(&hdri("sky.exr")).unwrap();
    let d = e.distribution();
    assert!((d.marginal_cdf[e.height] - 1.0).abs() < 1e-6);
    // The pdf a sample reports is the pdf of its direction, and histograms of 2·10⁵ samples over
    // 16×8 coarse cells match the pdf's integral over each cell within 5 σ (binomial) + 1e-4.
    let (cw, ch) = (16usize, 8usize);
    let mut hist = vec![0usize; cw * ch];
    let n = 200_000;
    let mut rng = brdf_shop::rng::Pcg32::new(1, 2);
    for _ in 0..n {
        let (dir, pdf) = d.sample(rng.next_f64(), rng.next_f64()).expect("a sample");
        let p2 = d.pdf(dir);
        assert!((pdf / p2 - 1.0).abs() < 1e-6 || pdf < 1e-12, "{pdf} vs {p2}");
        let (u, v) = Environment::uv(dir);
        hist[((v * ch as f64) as usize).min(ch - 1) * cw + ((u * cw as f64) as usize).min(cw - 1)] += 1;
    }
    let (fw, fh) = (e.width / cw, e.height / ch);
    let mut expected = vec![0.0f64; cw * ch];
    for j in 0..e.height {
        for i in 0..e.width {
            // Integrate the pdf over the texel with 4×4 points.
            let mut acc = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    let (u, v) = (
                        (i as f64 + (a as f64 + 0.5) / 4.0) / e.width as f64,
                        (j as f64 + (b as f64 + 0.5) / 4.0) / e.height as f64,
                    );
                    acc += d.pdf(Environment::direction(u, v)) * (2.0 * PI * PI * (PI * v).sin())
                        / (e.width * e.height * 16) as f64;
                }
            }
            expected[(j / fh) * cw + i / fw] += acc;
        }
    }
    let total: f64 = expected.iter().sum();
    assert!((total - 1.0).abs() < 1e-3, "∫ pdf = {total}");
    for k in 0..cw * ch {
        let p = expected[k];
        let sigma = (n as f64 * p * (1.0 - p)).sqrt();
        assert!(
            (hist[k] as f64 - n as f64 * p).abs() <= 5.0 * sigma + 1e-4 * n as f64,
            "cell {k}: {} vs {}",
            hist[k],
            n as f64 * p
        );
    }
    let black = Environment::from_texels(4, 2, vec![[0.0; 3]; 8], "black").unwrap().distribution();
    assert!(black.sample(0.3, 0.3).is_none());
    assert_eq!(black.pdf(DVec3::Y), 0.0);
}
