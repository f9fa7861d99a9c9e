//! The mesh view's backdrop and the turned environment through the binary: the backdrop's pixels
//! are the map's radiance in each pixel's direction at the chosen blur (a level of the map's mip
//! chain) times the backdrop's brightness, independent of the object's exposure; `--background
//! black` draws none; and `--env-rotation θ` renders what the map turned by θ offline renders (the
//! test turns the EXR itself). Runs on this machine's Vulkan device (lavapipe in CI) with the
//! validation layer in debug builds.

use std::path::{Path, PathBuf};

use brdf_shop::reference::Image;
use brdf_shop::scene::{Camera, Environment};
use glam::{DQuat, DVec3};

mod common;

fn studio() -> PathBuf {
    common::asset("hdri/studio.exr")
}

fn render(args: &[&str]) {
    let (code, _, stderr) = common::run(&[&["render"][..], args].concat());
    assert_eq!(code, 0, "render {args:?}: {stderr}");
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// The backdrop's pixels against the CPU lookup of the same mip level along each pixel's ray,
/// times the brightness: the largest difference is at most 1e-4 of the level's brightest texel. The
/// GPU computes the ray and `atan2`/`acos` of the lookup in `f32` (relative error about 1e-6 of
/// the texel position), which moves a bilinear lookup by that fraction of a texel's step; 1e-4 of
/// the brightest texel is far above that and far below any error in the level, the brightness or
/// the direction (a blur one level off changes pixels by 1e-2 of it on this map).
#[test]
fn the_backdrop_is_the_map_at_its_blur_times_its_brightness() {
    let dir = tempfile::TempDir::new().unwrap();
    let env = Environment::load(&studio()).unwrap();
    let chain = env.mip_chain();
    let map = studio();
    for (size, blur, brightness) in [((64, 48), 2.0f64, 0.5f64), ((40, 64), 0.0, 3.0), ((48, 48), 4.5, 1.0)] {
        let out = dir.path().join("b.exr");
        let (b, l) = (brightness.to_string(), blur.to_string());
        let size_arg = format!("{}x{}", size.0, size.1);
        let args = ["--env", s(&map), "--size", &size_arg, "--spp", "1", "--exposure", "0.2"];
        render(&[&args[..], &["--backdrop-brightness", &b, "--backdrop-blur", &l, "--out", s(&out)]].concat());
        let img = common::read_exr(&out);
        let camera = Camera::framed(size.0, size.1);
        let level = blur.floor() as usize;
        let peak = chain[level].texels.iter().flat_map(|t| t[..3].iter().copied()).fold(0.0f32, f32::max) as f64;
        let (mut worst, mut seen) = (0.0f64, 0);
        for (k, p) in img.pixels.iter().enumerate().filter(|(_, p)| p[3] == 0.0) {
            let ray =
                camera.ray((k % size.0 as usize) as f64 + 0.5, (k / size.0 as usize) as f64 + 0.5, size.0, size.1);
            let want = Environment::lookup_chain(&chain, ray, blur) * brightness;
            let got = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            worst = worst.max((got - want).abs().max_element());
            seen += 1;
        }
        eprintln!("{size:?} blur {blur}: worst {worst:e} of peak {peak}");
        assert!(seen > img.pixels.len() / 4, "{size:?}: {seen} backdrop pixels");
        assert!(worst <= 1e-4 * peak * brightness, "{size:?} blur {blur}: worst {worst}, peak {peak}");
    }
    // Black: no backdrop at all, whatever the brightness.
    let out = dir.path().join("black.exr");
    render(&["--env", s(&studio()), "--size", "32x32", "--spp", "1", "--background", "black", "--out", s(&out)]);
    let img = common::read_exr(&out);
    assert!(img.pixels.iter().filter(|p| p[3] == 0.0).all(|p| p[..3] == [0.0; 3]));
    assert!(img.pixels.iter().any(|p| p[3] == 1.0 && p[0] > 0.0), "the object is drawn");
}

/// The backdrop keeps its brightness whatever the exposure: in a PNG its pixels do not change
/// with `--exposure`, the object's do.
#[test]
fn the_backdrop_brightness_is_independent_of_the_exposure() {
    let dir = tempfile::TempDir::new().unwrap();
    let map = studio();
    let png = |exposure: &str| {
        let out = dir.path().join(format!("e{exposure}.png"));
        let args = ["--env", s(&map), "--size", "32x32", "--spp", "1", "--exposure", exposure];
        render(&[&args[..], &["--backdrop-brightness", "2", "--out", s(&out)]].concat());
        image::open(&out).unwrap().to_rgb8()
    };
    let (a, b) = (png("0.1"), png("0.4"));
    let centre = |img: &image::RgbImage| img.get_pixel(16, 16).0;
    assert_ne!(centre(&a), centre(&b), "the object follows the exposure");
    assert_eq!(a.get_pixel(0, 0), b.get_pixel(0, 0), "the backdrop does not");
}

/// `map` turned by `deg` about +y, by this test's own arithmetic: the texel in direction `d` of
/// the turned map is the map's radiance along `R_y(−deg) d` (bilinear, `Environment::lookup`).
fn turned(map: &Environment, deg: f64) -> Vec<[f32; 4]> {
    let back = DQuat::from_rotation_y(-deg.to_radians());
    let (w, h) = (map.width, map.height);
    (0..w * h)
        .map(|k| {
            let (u, v) = (((k % w) as f64 + 0.5) / w as f64, ((k / w) as f64 + 0.5) / h as f64);
            let l = map.lookup(back * Environment::direction(u, v));
            [l.x as f32, l.y as f32, l.z as f32, 1.0]
        })
        .collect()
}

/// Relative L1 of two images over their common pixels.
fn rel_l1(a: &Image, b: &Image) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            num += (p[c] - q[c]).abs() as f64;
            den += q[c].abs() as f64;
        }
    }
    num / den
}

/// A render and a reference with `--env-rotation θ` equal those of the map turned by θ offline.
/// The program and this test interpolate between columns alike (linearly along `u`; this test's
/// texel-centre directions land within 1e-12 of the centres), so the two maps differ by the
/// rounding to `f32` of their texels (6e-8 relative) and the images by 1e-5 relative L1 at most
/// (the frames' samples do not depend on the map, so both carry the same noise).
#[test]
fn a_turned_environment_renders_as_the_map_turned_offline() {
    let dir = tempfile::TempDir::new().unwrap();
    let map = Environment::load(&studio()).unwrap();
    for deg in [90.0, 37.0, -135.0] {
        let file = dir.path().join("turned.exr");
        brdf_shop::imageio::write(&file, map.width as u32, map.height as u32, &turned(&map, deg), 1.0).unwrap();
        for cmd in ["render", "reference"] {
            let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
            let common_args = ["--size", "40x32", "--spp", "8", "--mesh", "torus"];
            let rot = deg.to_string();
            let run = |args: &[&str]| {
                let (code, _, stderr) = common::run(&[&[cmd][..], &common_args[..], args].concat());
                assert_eq!(code, 0, "{cmd} {args:?}: {stderr}");
            };
            run(&["--env", s(&studio()), "--env-rotation", &rot, "--out", s(&a)]);
            run(&["--env", s(&file), "--out", s(&b)]);
            let (a, b) = (common::read_exr(&a), common::read_exr(&b));
            let e = rel_l1(&a, &b);
            eprintln!("{cmd} at {deg}: relative L1 {e:e}");
            assert!(e <= 1e-5, "{cmd} at {deg}°: relative L1 {e}");
            if deg == 90.0 {
                // Turned, the image is not the unturned one.
                let plain = dir.path().join("plain.exr");
                run(&["--env", s(&studio()), "--out", s(&plain)]);
                assert!(rel_l1(&common::read_exr(&plain), &b) > 0.05, "{cmd}: the turn changes nothing");
            }
        }
    }
}

/// Bad backdrop and rotation values are refused naming the flag.
#[test]
fn bad_backdrop_and_rotation_values_are_refused() {
    let dir = tempfile::TempDir::new().unwrap();
    let out = dir.path().join("o.png");
    for (flag, value) in [
        ("--backdrop-brightness", "-1"),
        ("--backdrop-brightness", "nan"),
        ("--backdrop-blur", "-0.5"),
        ("--backdrop-blur", "inf"),
        ("--env-rotation", "nan"),
        ("--background", "grey"),
    ] {
        let (code, stdout, stderr) = common::run(&["render", "--env", s(&studio()), flag, value, "--out", s(&out)]);
        assert_eq!(code, 1, "{flag} {value}: {stderr}");
        assert!(stdout.is_empty() && stderr.lines().count() == 1 && stderr.contains(flag), "{flag} {value}: {stderr}");
    }
    assert!(!out.exists());
}
