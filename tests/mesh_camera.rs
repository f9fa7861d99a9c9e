//! The built-in meshes against their closed forms, every asset OBJ, every refusal of the OBJ loader,
//! and the mesh camera: `--camera` parsing and its refusals, rays, and the view-projection's
//! agreement with the rays (what makes the GPU rasteriser and the CPU reference see the same image).

use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};

use brdf_shop::scene::camera::NEAR;
use brdf_shop::scene::{Camera, Mesh};
use brdf_shop::Error;
use glam::{DVec3, DVec4, Vec3};
use proptest::prelude::*;

mod common;

/// Six times the enclosed volume (positive for outward winding), in f64.
fn volume(m: &Mesh) -> f64 {
    m.indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize].as_dvec3());
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

/// Index ranges, unit normals, no degenerate triangle, and every triangle wound counter-clockwise
/// seen from the side its vertex normals point to.
fn check_structure(m: &Mesh) {
    assert_eq!(m.positions.len(), m.normals.len(), "{}", m.name);
    assert_eq!(m.indices.len() % 3, 0);
    assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()), "{}: index out of range", m.name);
    for (k, n) in m.normals.iter().enumerate() {
        // f32 normalisation is exact to a few ulp.
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-5, "{}: normal {k} = {n}", m.name);
    }
}

fn check_winding(m: &Mesh) {
    for (k, t) in m.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
        let g = (b - a).cross(c - a);
        assert!(g.length() > 0.0, "{}: triangle {k} is degenerate", m.name);
        let n: Vec3 = t.iter().map(|&i| m.normals[i as usize]).sum();
        assert!(g.dot(n) > 0.0, "{}: triangle {k} winds against its normals", m.name);
    }
}

#[test]
fn sphere_is_the_unit_sphere() {
    let m = Mesh::sphere();
    assert_eq!(m.name, "sphere");
    // Ring r of 127 holds ⌈256 sin(π r / 128)⌉ segments (and one vertex more, φ = 2π), a pole one
    // vertex; each step along a pair of rings is a triangle.
    let segments: Vec<usize> = (1..128).map(|r| (256.0 * (PI * f64::from(r) / 128.0).sin()).ceil() as usize).collect();
    assert_eq!(segments[63], 256);
    assert_eq!(m.positions.len(), segments.iter().map(|n| n + 1).sum::<usize>() + 2);
    assert_eq!(m.triangle_count(), 2 * segments.iter().sum::<usize>());
    assert_eq!(m.triangle_count(), 41_848);
    // The deepest point of each flat triangle (its vertices on the sphere): the foot of the
    // perpendicular from the centre where it falls inside the triangle, else the middle of its
    // longest edge. None sags below the sphere by more than the equator's quads, (Δφ² + Δθ²)/8 with
    // Δ = π/128 (to f32 rounding of the vertices, 1e-7).
    let bound = 2.0 * (PI / 128.0).powi(2) / 8.0 + 1e-7;
    let mut deepest = 0.0f64;
    for t in m.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize].as_dvec3());
        let n = (b - a).cross(c - a).normalize();
        let foot = n * n.dot(a);
        let inside = [(a, b), (b, c), (c, a)].iter().all(|(p, q)| (*q - *p).cross(foot - *p).dot(n) >= 0.0);
        let sag = if inside {
            1.0 - foot.length()
        } else {
            [(a, b), (b, c), (c, a)].iter().map(|(p, q)| 1.0 - ((*p + *q) / 2.0).length()).fold(0.0, f64::max)
        };
        deepest = deepest.max(sag);
    }
    assert!(deepest <= bound && deepest > 0.9 * bound, "deepest sag {deepest:e} against {bound:e}");
    check_structure(&m);
    check_winding(&m);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        // Vertices on the sphere and normals = positions, to f32 rounding of sin/cos.
        assert!((p.length() - 1.0).abs() < 1e-6, "vertex {p} off the unit sphere");
        assert!((*p - *n).length() < 1e-6, "normal {n} at {p}");
    }
    // The inscribed polyhedron's volume is short of 4π/3 by about 1.5 × (mean sag 1e-4 of 1): 5e-4.
    let v = volume(&m);
    let exact = 4.0 * PI / 3.0;
    assert!(v < exact && (exact - v) / exact < 5e-4, "volume {v} vs {exact}");
    // The benchmark's coarser spheres follow the same rule.
    for (seg, rings) in [(3, 2), (16, 8), (100, 50)] {
        let m = Mesh::uv_sphere(seg, rings);
        assert_eq!(m.triangle_count(), (2 * seg * (rings - 1)) as usize);
        check_structure(&m);
        check_winding(&m);
    }
}

#[test]
fn torus_is_the_papers_torus() {
    let m = Mesh::torus();
    assert_eq!(m.name, "torus");
    assert_eq!(m.positions.len(), 257 * 97);
    assert_eq!(m.triangle_count(), 2 * 256 * 96);
    check_structure(&m);
    check_winding(&m);
    let (major, minor) = (0.7f64, 0.3f64);
    let mut max_radius = 0.0f64;
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let p = p.as_dvec3();
        // Distance from the ring circle (radius 0.7 in the xz plane) is the minor radius.
        let ring = DVec3::new(p.x, 0.0, p.z).normalize() * major;
        assert!(((p - ring).length() - minor).abs() < 1e-6, "vertex {p} off the torus");
        // The exact normal points from the ring circle to the vertex.
        assert!(((p - ring) / minor - n.as_dvec3()).length() < 1e-5, "normal {n} at {p}");
        max_radius = max_radius.max(p.length());
    }
    // It fits the unit sphere (touching it on the outer equator).
    assert!((max_radius - 1.0).abs() < 1e-6, "bounding radius {max_radius}");
    // Volume 2π² R r², short by the tessellation sag (relative 1e-3 is generous: Δ²/8 terms are 2e-4).
    let (v, exact) = (volume(&m), 2.0 * PI * PI * major * minor * minor);
    assert!((v - exact).abs() / exact < 1e-3, "volume {v} vs {exact}");
}

fn bounds(m: &Mesh) -> (DVec3, DVec3) {
    m.positions.iter().fold((DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)), |(lo, hi), p| {
        (lo.min(p.as_dvec3()), hi.max(p.as_dvec3()))
    })
}

/// The repository's bunny and two procedural blobs (tens of thousands of triangles, written off
/// centre and scaled, one of them wound inward) load centred, with bounding radius 1 and outward
/// normals.
#[test]
fn every_asset_mesh_loads_centred_with_radius_one() {
    let dir = tempfile::tempdir().unwrap();
    let (coarse, fine) = (common::blob(4), common::blob(5));
    common::write_obj(&dir.path().join("blob.obj"), &coarse, 40.0, [3.0, -2.0, 5.0], false);
    common::write_obj(&dir.path().join("blob-inward.obj"), &fine, 0.01, [-0.5, 0.0, 0.25], true);
    let cases = [
        (common::asset("meshes/bunny.obj"), 3674),
        (dir.path().join("blob.obj"), coarse.triangles.len()),
        (dir.path().join("blob-inward.obj"), fine.triangles.len()),
    ];
    for (path, triangles) in cases {
        let file = path.file_name().unwrap().to_str().unwrap();
        let m = Mesh::load_obj(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(m.name, file);
        assert_eq!(m.triangle_count(), triangles, "{file}");
        check_structure(&m);
        let (lo, hi) = bounds(&m);
        // Scaling and centring are done in f64 and rounded to f32: 1e-5 is a few f32 ulp of 1.
        let radius = (hi - lo).length() / 2.0;
        assert!((radius - 1.0).abs() < 1e-5, "{file}: bounding radius {radius}");
        assert!(((lo + hi) / 2.0).length() < 1e-5, "{file}: centre {}", (lo + hi) / 2.0);
        // Outward: these closed meshes have no normals in the file, so the loader's winding rule
        // decides, and the enclosed volume must come out positive.
        assert!(volume(&m) > 0.0, "{file}: normals point inward");
        // `resolve` takes a path too.
        assert_eq!(Mesh::resolve(path.to_str().unwrap()).unwrap().triangle_count(), triangles);
    }
    assert_eq!(fine.triangles.len(), 20 * 4usize.pow(5));
}

#[test]
fn resolve_names_the_built_in_meshes() {
    assert_eq!(Mesh::resolve("sphere").unwrap().name, "sphere");
    assert_eq!(Mesh::resolve("torus").unwrap().name, "torus");
    let e = Mesh::resolve("nonexistent.obj").unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    assert!(e.to_string().contains("nonexistent.obj"), "{e}");
}

fn obj(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::File::create(&path).unwrap().write_all(text.as_bytes()).unwrap();
    path
}

const TETRA_VERTICES: &str = "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\n";

#[test]
fn bad_obj_files_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("garbage.obj", "this is not\n\u{1}\u{2} an OBJ file at all {}\n", "no triangles"),
        ("out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", ""),
        ("no_faces.obj", TETRA_VERTICES, "no triangles"),
        ("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"),
        ("inf.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"),
        ("point.obj", "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n", "one point"),
        ("empty.obj", "", "no triangles"),
    ];
    for (name, text, why) in cases {
        let path = obj(dir.path(), name, text);
        let e = Mesh::load_obj(&path).map(|m| m.triangle_count()).unwrap_err();
        assert!(matches!(e, Error::Input { .. }), "{name}: {e:?}");
        let msg = e.to_string();
        assert!(msg.contains(name), "{name}: message does not name the file: {msg}");
        assert!(msg.contains(why), "{name}: message does not say {why:?}: {msg}");
        eprintln!("{msg}");
    }
    let missing = dir.path().join("missing.obj");
    let e = Mesh::load_obj(&missing).unwrap_err();
    assert!(matches!(e, Error::Io { .. }) && e.to_string().contains("missing.obj"), "{e:?}");
    // A folder is not a file either.
    let e = Mesh::load_obj(dir.path()).unwrap_err();
    assert!(e.is_user_error(), "{e:?}");
}

#[test]
fn inward_winding_is_turned_outward_and_file_normals_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    // A tetrahedron wound clockwise seen from outside.
    let inward = obj(dir.path(), "inward.obj", &format!("{TETRA_VERTICES}f 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n"));
    let m = Mesh::load_obj(&inward).unwrap();
    assert!(volume(&m) > 0.0);
    check_winding(&m);
    let centroid: Vec3 = m.positions.iter().sum::<Vec3>() / 4.0;
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!((*p - centroid).dot(*n) > 0.0, "normal {n} at {p} points inward");
    }
    // Normals given in the file are used (normalised), even where they disagree with the winding.
    let with_normals = obj(dir.path(), "normals.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 -2\nf 1//1 2//1 3//1\n");
    let m = Mesh::load_obj(&with_normals).unwrap();
    assert!(m.normals.iter().all(|n| (*n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6), "{:?}", m.normals);
    // Quads are triangulated; several objects are concatenated.
    let two = obj(
        dir.path(),
        "two.obj",
        "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5 6 7\n",
    );
    let m = Mesh::load_obj(&two).unwrap();
    assert_eq!(m.triangle_count(), 3);
    check_structure(&m);
}

// --- camera ---

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos()
}

#[test]
fn parse_defaults_subsets_and_round_trips() {
    assert_eq!(Camera::parse("").unwrap(), Camera::default());
    assert_eq!(Camera::default().to_string(), "eye=0,0,4 target=0,0,0 up=0,1,0 fov=30");
    let c = Camera::parse("  fov=45   eye=1,2.5,-3e1 ").unwrap();
    assert_eq!(c, Camera { eye: DVec3::new(1.0, 2.5, -30.0), fov_deg: 45.0, ..Camera::default() });
    let c = Camera::parse("up=0,0,1 target=0.1,0.2,0.3 eye=3,0,0").unwrap();
    assert_eq!((c.up, c.target, c.eye, c.fov_deg), (DVec3::Z, DVec3::new(0.1, 0.2, 0.3), DVec3::X * 3.0, 30.0));
    assert_eq!(Camera::parse(&c.to_string()).unwrap(), c);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// Every valid camera prints to text that parses back to the same camera, bit for bit.
    #[test]
    fn display_parse_round_trip(e in prop::array::uniform3(-1e3f64..1e3), t in prop::array::uniform3(-1.0f64..1.0),
                                u in prop::array::uniform3(-1.0f64..1.0), fov in 0.001f64..179.999) {
        let c = Camera { eye: DVec3::from_array(e), target: DVec3::from_array(t), up: DVec3::from_array(u), fov_deg: fov };
        prop_assume!(c.check().is_ok());
        prop_assert_eq!(Camera::parse(&c.to_string()).unwrap(), c);
    }
}

#[test]
fn parse_refusals_name_the_key_and_value() {
    let cases = [
        ("eye=1,2", "eye"),
        ("eye=1,2,3,4", "eye"),
        ("eye=a,b,c", "eye"),
        ("target=0,nan,0", "target"),
        ("up=0,inf,0", "up"),
        ("fov=wide", "fov"),
        ("fov=0", "fov"),
        ("fov=180", "fov"),
        ("fov=-10", "fov"),
        ("fov=1e400", "fov"),
        ("zoom=2", "zoom"),
        ("eye", "eye"),
        ("eye=0,0,0", "same point"),
        ("eye=1,1,1 target=1,1,1", "same point"),
        ("up=0,0,0", "up"),
        ("up=0,0,-3", "up"),
        ("eye=0,5,0", "up"),
        ("fov=20 fov=30", "fov"),
    ];
    for (text, key) in cases {
        let e = Camera::parse(text).expect_err(text);
        assert!(e.contains(key), "{text}: {e}");
        eprintln!("{text}: {e}");
    }
}

#[test]
fn rays_through_centre_and_edges() {
    let cameras = [
        Camera::default(),
        Camera::parse("eye=3,2,1 target=0.2,-0.1,0.3 up=0,1,0 fov=50").unwrap(),
        Camera::parse("eye=0,5,0.01 target=0,0,0 up=0,0,-1 fov=10").unwrap(),
    ];
    for c in &cameras {
        let forward = (c.target - c.eye).normalize();
        let half = (c.fov_deg / 2.0).to_radians();
        for (w, h) in [(64u32, 64u32), (160, 90), (31, 47)] {
            let aspect = w as f64 / h as f64;
            let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
            // Unit vectors, 1e-12: f64 normalisation.
            let centre = c.ray(cx, cy, w, h);
            assert!((centre.length() - 1.0).abs() < 1e-12);
            assert!((centre - forward).length() < 1e-12, "{c}: centre ray {centre} vs {forward}");
            // Top and bottom edge midpoints are the vertical half angle off the axis; left and right
            // atan(tan(half)·aspect); the corners atan(tan(half)·√(1 + aspect²)).
            let (top, bottom) = (c.ray(cx, 0.0, w, h), c.ray(cx, h as f64, w, h));
            let (left, right) = (c.ray(0.0, cy, w, h), c.ray(w as f64, cy, w, h));
            let horiz = (half.tan() * aspect).atan();
            for (r, a) in [(top, half), (bottom, half), (left, horiz), (right, horiz)] {
                assert!((angle(r, forward) - a).abs() < 1e-12, "{c} {w}x{h}");
            }
            let corner = (half.tan() * (1.0 + aspect * aspect).sqrt()).atan();
            for (px, py) in [(0.0, 0.0), (w as f64, 0.0), (0.0, h as f64), (w as f64, h as f64)] {
                assert!((angle(c.ray(px, py, w, h), forward) - corner).abs() < 1e-12);
            }
            // Orientation: the top row looks toward `up`, the right column to forward × up.
            let (r, u, _) = c.basis();
            assert!(top.dot(u) > 0.0 && bottom.dot(u) < 0.0 && right.dot(r) > 0.0 && left.dot(r) < 0.0);
            assert!(r.dot(forward.cross(c.up)) > 0.0);
        }
    }
    // The default camera: the top row looks up (+y), the right column toward +x.
    let c = Camera::default();
    assert!(c.ray(32.0, 0.0, 64, 64).y > 0.0 && c.ray(64.0, 32.0, 64, 64).x > 0.0);
}

#[test]
fn view_proj_puts_ray_points_at_their_pixels() {
    let cameras = [
        Camera::default(),
        Camera::parse("eye=3,2,1 target=0.2,-0.1,0.3 up=0,1,0 fov=50").unwrap(),
        Camera::parse("eye=-0.5,0.3,2 target=0,0,0 up=1,1,0 fov=120").unwrap(),
    ];
    let mut worst = 0.0f64;
    for c in &cameras {
        for (w, h) in [(64u32, 64u32), (160, 90), (7, 300)] {
            let vp = c.view_proj(w, h).as_dmat4();
            let forward = (c.target - c.eye).normalize();
            let mut last_depth = -1.0;
            for (fx, fy) in [(0.5, 0.5), (0.0, 0.0), (1.0, 1.0), (0.1, 0.9), (0.77, 0.23)] {
                let (px, py) = (fx * w as f64, fy * h as f64);
                let d = c.ray(px, py, w, h);
                last_depth = -1.0;
                for s in [0.1, 0.5, 4.0, 50.0, 1e4] {
                    let p = c.eye + s * d;
                    let clip = vp * DVec4::new(p.x, p.y, p.z, 1.0);
                    let ndc = clip.truncate() / clip.w;
                    let want = (2.0 * px / w as f64 - 1.0, 2.0 * py / h as f64 - 1.0);
                    // The matrix is f32 (relative rounding 6e-8 of entries up to |eye|/tan(fov/2)), and
                    // clip coordinates are divided by the view depth: the NDC error grows as the
                    // point nears the eye. Where the scene is (depth ≥ 0.5) 1e-5 in NDC (0.0015 px at
                    // 300 px); nearer, 1e-3 px.
                    let depth = (s * d).dot(forward);
                    let err = (ndc.x - want.0).abs().max((ndc.y - want.1).abs());
                    let err_px = ((ndc.x - want.0).abs() * w as f64).max((ndc.y - want.1).abs() * h as f64) / 2.0;
                    if depth >= 0.5 {
                        worst = worst.max(err);
                        assert!(err < 1e-5, "{c} {w}x{h} ({px},{py}) s={s}: NDC {ndc} vs {want:?}");
                    }
                    assert!(err_px < 1e-3, "{c} {w}x{h} ({px},{py}) s={s}: NDC {ndc} vs {want:?}");
                    // Depth inside [0, 1), growing with distance.
                    assert!(ndc.z >= 0.0 && ndc.z < 1.0 && ndc.z > last_depth, "{c}: depth {} at s={s}", ndc.z);
                    last_depth = ndc.z;
                }
            }
            // The near plane maps to depth 0, a point behind it is clipped (depth < 0).
            let at_near = c.eye + forward * NEAR;
            let behind = c.eye + forward * (NEAR / 2.0);
            for (p, sign) in [(at_near, 0.0), (behind, -1.0)] {
                let clip = vp * DVec4::new(p.x, p.y, p.z, 1.0);
                let z = clip.z / clip.w;
                if sign == 0.0 {
                    assert!(z.abs() < 1e-4, "{c}: near plane at depth {z}");
                } else {
                    assert!(z < 0.0, "{c}: a point before the near plane is not clipped ({z})");
                }
            }
            assert!(last_depth < 1.0);
        }
    }
    eprintln!("worst NDC error of view_proj against ray at view depth >= 0.5: {worst:.2e}");
}

/// The largest |x| and |y| in normalised device coordinates of the unit sphere's silhouette seen by
/// `c` in a `w × h` image (points on the sphere, 64 × 128 of them, projected by `view_proj`).
fn sphere_extent(c: &Camera, w: u32, h: u32) -> (f64, f64) {
    let vp = c.view_proj(w, h);
    let mut ext: (f64, f64) = (0.0, 0.0);
    for i in 0..=64 {
        let t = PI * i as f64 / 64.0;
        for j in 0..128 {
            let p = 2.0 * PI * j as f64 / 128.0;
            let q = vp * glam::Vec4::new((t.sin() * p.cos()) as f32, t.cos() as f32, (t.sin() * p.sin()) as f32, 1.0);
            ext = (ext.0.max((q.x / q.w).abs() as f64), ext.1.max((q.y / q.w).abs() as f64));
        }
    }
    ext
}

/// `render`'s default camera frames the unit sphere (which every mesh is scaled into) at every
/// aspect: a square or wider image keeps the default camera, and a taller one moves the eye back
/// until the sphere keeps the square image's margin to the left and right edges. `fit_distance`
/// puts a sphere's silhouette tangent to the nearer edges. Sampled silhouettes lie inside the
/// exact one, so the extents are compared to 1e-3 (the 64 × 128 points miss the tangent point by
/// at most 1 − cos(π/64) ≈ 1.2e-3 of the radius).
#[test]
fn the_default_camera_frames_the_unit_sphere_at_every_aspect() {
    use brdf_shop::scene::camera::fit_distance;
    assert_eq!(Camera::framed(256, 256), Camera::default());
    assert_eq!(Camera::framed(512, 256), Camera::default());
    // The exact extent, in NDC, of a unit sphere grown by `m` touching the edges of half-angle `a`.
    let exact = |a: f64, m: f64| (a.sin() / m).asin().tan() / a.tan();
    let (half_v, m) = (15f64.to_radians(), 4.0 * 15f64.to_radians().sin());
    let (_, y) = sphere_extent(&Camera::default(), 256, 256);
    assert!((y - exact(half_v, m)).abs() < 1e-3, "square: {y}");
    for (w, h) in [(256, 512), (100, 720), (720, 1280), (1, 1000)] {
        let (x, y) = sphere_extent(&Camera::framed(w, h), w, h);
        let half_h = (half_v.tan() * w as f64 / h as f64).atan();
        assert!((x - exact(half_h, m)).abs() < 1e-3 && x < 1.0 && y < x, "{w}x{h}: extent {x}, {y}");
    }
    for (w, h) in [(1280, 720), (720, 1280), (1920, 800), (400, 720)] {
        let d = fit_distance(30.0, w as f64 / h as f64, 1.0, 1.25);
        let c = Camera { eye: DVec3::new(0.0, 0.0, d), ..Camera::default() };
        let (x, y) = sphere_extent(&c, w, h);
        let half_h = (half_v.tan() * w as f64 / h as f64).atan();
        let want = if half_h < half_v { (x, exact(half_h, 1.25)) } else { (y, exact(half_v, 1.25)) };
        assert!((want.0 - want.1).abs() < 1e-3 && x.max(y) < 0.8, "{w}x{h}: {x}, {y}");
    }
    // A degenerate aspect counts as square.
    assert_eq!(fit_distance(30.0, f64::NAN, 1.0, 1.0), fit_distance(30.0, 1.0, 1.0, 1.0));
}
