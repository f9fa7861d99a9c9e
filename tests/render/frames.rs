//! Frames: whole-frame timing, refinement frames, frames that keep the G-buffer, the two frame
//! plans, background-built pipelines, culling: each draws the image a plain frame draws.

use super::*;

/// A frame that does not time its passes (`Renderer::time_passes` false, as the error-vs-time sweep
/// renders) records the whole frame's pair alone: no pass times, a whole-frame time above 0, and the
/// image of the frame that times them bit for bit (timestamps change no work), for `key` with a
/// filtered lobe and `fis`.
#[test]
fn a_frame_that_does_not_time_its_passes_times_the_whole_frame_and_draws_the_same_image() {
    let mut r = renderer();
    r.set_environment(&env("studio.exr")).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let m = Material {
        preserve_energy: false,
        diffuse: [0.2; 3],
        normalization: Normalization::Reciprocal,
        symmetrize: false,
        lobes: vec![common::lobe(0.4, 0.02, 0.02), common::lobe(0.4, 0.3, 0.3)],
    };
    for est in [Estimator::Key, Estimator::Fis] {
        let s = settings(32, 8, est);
        let timed = r.render(&m, &s).unwrap();
        assert!(timed.timings.len() >= 2 && timed.frame_ms > 0.0, "{:?}", timed.timings);
        r.time_passes = false;
        let whole = r.render(&m, &s).unwrap();
        r.time_passes = true;
        assert!(whole.timings.is_empty(), "{:?}: {:?}", est, whole.timings);
        assert!(whole.frame_ms > 0.0 && whole.frame_ms.is_finite(), "{est:?}: {}", whole.frame_ms);
        assert!(whole.image.pixels == timed.image.pixels, "{est:?}: the images differ");
    }
}

/// Progressive refinement on the GPU: four refinement frames of 16 `mis` samples, summed in the
/// mesh view's persistent image and shown as sum / frames, are the one 64-sample estimate (each frame
/// continues the sequence where the last stopped). Equal to f32 rounding: 1e-5 relative over the
/// object. One 16-sample frame alone is a different estimate (> 1e-4 away), so the test sees the
/// frames' offsets; a fresh frame restarts the sum.
#[test]
fn refinement_frames_accumulate_on_the_gpu_into_one_estimate() {
    let mut r = renderer();
    let e = env("studio.exr");
    r.set_environment(&e).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let m = &common::feature_materials()[1].1;
    let whole = r.render(m, &settings(24, 64, Estimator::Mis)).unwrap().image;
    let mut first = None;
    for k in 0..4 {
        r.begin_frame(m).unwrap();
        assert_eq!(r.record(m, &settings(24, 16, Estimator::Mis), Progress::Refine).unwrap(), Recorded::Done);
        r.submit_frame(None, None).unwrap();
        assert_eq!(r.refined_samples(), 16 * (k + 1));
        if k == 0 {
            first = Some(r.read_mesh_view().unwrap());
        }
    }
    let avg = r.read_mesh_view().unwrap();
    let err = reference::relative_l1(&avg, &whole).unwrap();
    assert!(err < 1e-5, "{err}");
    assert!(reference::relative_l1(&first.unwrap(), &whole).unwrap() > 1e-4);
    // Frames of different sample counts (the editor's budget sets each): 8 + 16 + 40 samples are the
    // same 64 (each frame weighs its mean by its samples; a mean over frames would give the 8-sample
    // frame as much weight as the 40-sample one).
    // A fresh frame restarts the sum; the refinement then starts again from sample 0.
    r.begin_frame(m).unwrap();
    assert_eq!(r.record(m, &settings(24, 8, Estimator::Key), Progress::Fresh).unwrap(), Recorded::Done);
    r.submit_frame(None, None).unwrap();
    for spp in [8, 16, 40] {
        r.begin_frame(m).unwrap();
        assert_eq!(r.record(m, &settings(24, spp, Estimator::Mis), Progress::Refine).unwrap(), Recorded::Done);
        r.submit_frame(None, None).unwrap();
    }
    assert_eq!(r.refined_samples(), 64);
    let err = reference::relative_l1(&r.read_mesh_view().unwrap(), &whole).unwrap();
    assert!(err < 1e-5, "unequal frames: {err}");
    r.begin_frame(m).unwrap();
    assert_eq!(r.record(m, &settings(24, 16, Estimator::Mis), Progress::Fresh).unwrap(), Recorded::Done);
    r.submit_frame(None, None).unwrap();
    assert_eq!(r.refined_samples(), 0);
}

/// A frame abandoned after a swapchain acquire (the editor's recording failed) consumes the
/// acquire's semaphore: six frames over the two slots, each slot's semaphore signalled as an acquire
/// would and the frame then abandoned, leave no validation error — a binary semaphore signalled again
/// before a wait is one (VUID-vkQueueSubmit-pSignalSemaphores-00067), which is what ending the command
/// buffer alone (`abandon_frame`) left behind — and the ring renders normally after.
#[test]
fn a_frame_abandoned_after_an_acquire_consumes_its_semaphore() {
    use ash::vk;
    let mut r = renderer();
    r.set_environment(&env("venice.exr")).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let m = &common::feature_materials()[0].1;
    for _ in 0..6 {
        r.begin_frame(m).unwrap();
        let (_, acquired) = r.frame_commands();
        let signal = [acquired];
        let info = vk::SubmitInfo::default().signal_semaphores(&signal);
        // SAFETY: the semaphore is the current slot's, unsignalled unless an earlier abandon left it
        // signalled (what the validation layer is to catch), and lives as long as the renderer.
        unsafe { r.ctx.raw().queue_submit(r.ctx.device.queue, &[info], vk::Fence::null()) }.unwrap();
        r.abandon_acquired_frame(acquired).unwrap();
    }
    r.finish_frames().unwrap();
    r.ctx.check_validation().unwrap();
    let im = r.render(m, &settings(16, 4, Estimator::Key)).unwrap().image;
    assert_finite("after the abandoned frames", &im);
    assert!(im.pixels.iter().any(|p| p[3] > 0.5 && p[0] > 0.0), "an empty image after the abandoned frames");
    r.ctx.check_validation().unwrap();
}

/// Skipping the faces a closed mesh hides from an eye outside it (the G-buffer's speed-up) leaves the
/// image unchanged: per mesh, the mesh view rendered with culling equals the one without. Culling only
/// removes fragments that should lose the depth test to a nearer face, so on the analytic meshes the
/// images are equal bit for bit. Which faces are hidden is decided per mesh: the outward-wound sphere
/// and torus hide the faces clockwise from the eye, the same sphere wound inward the counter-clockwise
/// ones, and an open hemisphere none (looking into it shows its inside). The scanned bunny (closed by
/// the check) has folds where a hidden face ties a visible one within depth precision: without
/// culling the hidden face can win such a tie. Measured: 1 pixel of 2304 differs, by 0.14 %; bound:
/// at most 0.1 % of the pixels, each under 1 % (a wrong winding would change most of the object).
#[test]
fn culling_hidden_faces_leaves_the_image_unchanged() {
    use brdf_shop::scene::mesh::Hidden;
    let sphere = Mesh::sphere();
    let inward =
        Mesh { indices: sphere.indices.chunks_exact(3).flat_map(|t| [t[0], t[2], t[1]]).collect(), ..sphere.clone() };
    let hemisphere = Mesh {
        indices: sphere
            .indices
            .chunks_exact(3)
            .filter(|t| t.iter().all(|&i| sphere.positions[i as usize].z >= -1e-6))
            .flatten()
            .copied()
            .collect(),
        ..sphere.clone()
    };
    let bunny = Mesh::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/meshes/bunny.obj")).unwrap();
    let cases = [
        ("sphere", sphere.clone(), Some(Hidden::Clockwise)),
        ("torus", Mesh::torus(), Some(Hidden::Clockwise)),
        ("inward sphere", inward, Some(Hidden::CounterClockwise)),
        ("hemisphere", hemisphere, Some(Hidden::None)),
        ("bunny", bunny, None),
    ];
    let mut r = renderer();
    r.set_environment(&env("venice.exr")).unwrap();
    let m = &common::feature_materials()[1].1;
    for (name, mesh, expected) in cases {
        let hidden = mesh.hidden_faces();
        if let Some(e) = expected {
            assert_eq!(hidden, e, "{name}");
        }
        r.set_mesh(&mesh).unwrap();
        // From the side (the hemisphere shows its inside) and from above.
        for eye in [DVec3::new(3.0, 0.5, 0.2), DVec3::new(0.3, 3.5, 1.0)] {
            let s = Settings { camera: Camera { eye, ..Camera::default() }, ..settings(48, 4, Estimator::Fis) };
            r.options.cull_hidden_faces = true;
            let culled = r.render(m, &s).unwrap().image;
            r.options.cull_hidden_faces = false;
            let all = r.render(m, &s).unwrap().image;
            // Pixels that differ, and the largest relative difference among them.
            let differ: Vec<f32> = culled
                .pixels
                .iter()
                .zip(&all.pixels)
                .filter(|(a, b)| a != b)
                .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs() / b[c].abs().max(1e-3)).fold(0.0f32, f32::max))
                .collect();
            if !differ.is_empty() {
                dump(&format!("cull-{name}"), &[("culled", &culled), ("all", &all)]);
            }
            if expected.is_some() {
                assert!(differ.is_empty(), "{name} ({hidden:?}) from {eye}: culling changed {} pixels", differ.len());
            } else {
                let worst = differ.iter().fold(0.0f32, |a, &b| a.max(b));
                assert!(
                    differ.len() * 1000 <= all.pixels.len() && worst < 0.01,
                    "{name} ({hidden:?}) from {eye}: {} pixels differ, by up to {worst}",
                    differ.len()
                );
            }
            assert!(all.pixels.iter().any(|p| p[3] > 0.5), "{name}: the mesh is not in view");
        }
    }
}

/// The editor's frames keep the G-buffer while mesh, camera and size are unchanged (a stroke or a
/// refinement frame does not rasterise again), and rasterise when the camera moves; the kept
/// G-buffer gives the same image as a fresh one (bit for bit: the same shading passes read it).
/// The second frame on a kept G-buffer saves what the background and diffuse passes
/// drew (`base.save`), and the next ones start from it instead (`base`, neither pass), again bit
/// for bit; a new diffuse albedo draws them again, and its image is a fresh frame's. A
/// frame that rasterises draws the background and diffuse term in the G-buffer's pass
/// (`CompactPass::record`), bit for bit as those two passes draw them in the next frame.
#[test]
fn frames_reuse_the_gbuffer_until_the_camera_moves() {
    let mut r = renderer();
    r.set_environment(&env("venice.exr")).unwrap();
    r.set_mesh(&Mesh::torus()).unwrap();
    let m = common::feature_materials()[1].1.clone();
    let other = Material { diffuse: [0.1, 0.2, 0.3], ..m.clone() };
    for estimator in [Estimator::Fis, Estimator::Key] {
        let s = settings(32, 4, estimator);
        let moved = Settings { camera: Camera { eye: DVec3::new(1.0, 2.0, 4.0), ..Camera::default() }, ..s.clone() };
        let has = |names: &[String], n: &str| names.iter().any(|x| x == n);
        // Another camera first, so that the first frame rasterises (the loop's last render kept
        // its G-buffer).
        frame(&mut r, &m, &moved);
        let (first, a) = frame(&mut r, &m, &s);
        let (second, b) = frame(&mut r, &m, &s);
        let (kept, c) = frame(&mut r, &m, &s);
        let (recoloured, d) = frame(&mut r, &other, &s);
        // A `mis` frame between kept frames leaves the kept image; another estimator's diffuse
        // term (`key`'s or not) and another map draw it again.
        let (again, e) = frame(&mut r, &other, &s);
        frame(&mut r, &other, &Settings { estimator: Estimator::Mis, ..s.clone() });
        let (after_mis, f) = frame(&mut r, &other, &s);
        let switched = if estimator == Estimator::Key { Estimator::Fis } else { Estimator::Key };
        let (other_estimator, _) = frame(&mut r, &other, &Settings { estimator: switched, ..s.clone() });
        r.set_environment(&env("studio.exr")).unwrap();
        let (other_map, _) = frame(&mut r, &other, &s);
        r.set_environment(&env("venice.exr")).unwrap();
        let (third, _) = frame(&mut r, &m, &moved);
        // With a diffuse term: a frame that rasterises draws it in the G-buffer's pass, the next
        // (kept) frame in the diffuse pass, bit for bit alike.
        let (drawn, g) = frame(&mut r, &other, &s);
        let (redrawn, h) = frame(&mut r, &other, &s);
        // The same on a map with a key light, whose power `key`'s diffuse term adds (and `fis`'s not).
        r.set_environment(&env("studio.exr")).unwrap();
        let (lit_drawn, lit_g) = frame(&mut r, &other, &moved);
        let (lit_redrawn, lit_h) = frame(&mut r, &other, &moved);
        r.set_environment(&env("venice.exr")).unwrap();
        assert!(has(&lit_drawn, "gbuffer") && !has(&lit_drawn, "diffuse"), "{lit_drawn:?}");
        assert!(has(&lit_redrawn, "diffuse"), "{lit_redrawn:?}");
        assert_eq!(lit_g.pixels, lit_h.pixels, "{estimator:?}: studio's diffuse term drawn in either pass");
        assert!(has(&first, "gbuffer") && !has(&first, "base.save"), "{first:?}");
        assert!(!has(&second, "gbuffer") && has(&second, "background") && has(&second, "base.save"), "{second:?}");
        assert!(has(&kept, "base") && !has(&kept, "background") && !has(&kept, "diffuse"), "{kept:?}");
        assert!(has(&recoloured, "diffuse") && has(&recoloured, "base.save"), "{recoloured:?}");
        assert!(has(&third, "gbuffer"), "{third:?}");
        assert!(has(&drawn, "gbuffer") && !has(&drawn, "diffuse"), "{drawn:?}");
        assert!(has(&redrawn, "diffuse") && has(&redrawn, "background"), "{redrawn:?}");
        assert_eq!(g.pixels, h.pixels, "{estimator:?}: the diffuse term drawn in either pass");
        assert_eq!(g.pixels, d.pixels, "{estimator:?}: the same frame as the recoloured one");
        for first_pass in [&first, &third, &drawn] {
            assert!(!has(first_pass, "background") && !has(first_pass, "diffuse"), "{first_pass:?}");
        }
        assert!(has(&again, "base") && has(&after_mis, "base"), "{again:?} {after_mis:?}");
        assert!(has(&other_estimator, "base.save"), "{other_estimator:?}");
        assert!(has(&other_map, "base.save"), "{other_map:?}");
        assert_eq!(d.pixels, e.pixels);
        assert_eq!(d.pixels, f.pixels);
        assert_eq!(a.pixels, b.pixels, "{estimator:?}: a kept G-buffer");
        assert_eq!(a.pixels, c.pixels, "{estimator:?}: a kept base");
        let fresh = r.render(&other, &s).unwrap().image;
        assert_eq!(d.pixels, fresh.pixels, "{estimator:?}: a new diffuse albedo on a kept G-buffer");
        assert_ne!(c.pixels, d.pixels);
    }
    r.ctx.check_validation().unwrap();
}

/// A frame that rasterises and filters sparsely leaves the diffuse term to the filter
/// (`compact::Start::Later`: the compact pass stores the background alone, the accumulation image
/// cleared to (0, 0, 0, 1) under the object), and, its passes all running over the blocks, the list
/// of pixels empty; the next frame keeps the G-buffer, lists the pixels and draws the background and
/// diffuse term in the compact pass (`compact`, in place of `background` and `diffuse`), the one
/// after it starts from their image (`base`). With one lobe whose light term goes to each pixel (`pixel_lights`:
/// α 0.1 at 128²) the two images are equal bit for bit (x + d = d + x); with two such lobes the sum
/// at a pixel is taken in another order, so within rounding: the terms are radiances (no sign
/// cancels), and three additions reassociated differ by at most 3 ulp of the largest partial sum,
/// so 4 ε of the pixel's value.
#[test]
fn the_sparse_filter_adds_the_diffuse_term_of_a_frame_that_rasterises() {
    let mut r = renderer();
    r.set_environment(&env("studio.exr")).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let s = settings(128, 4, Estimator::Key);
    let moved = Settings { camera: Camera { eye: DVec3::new(1.0, 2.0, 4.0), ..Camera::default() }, ..s.clone() };
    let has = |names: &[String], n: &str| names.iter().any(|x| x == n);
    let material = |alphas: &[f64]| Material {
        preserve_energy: false,
        diffuse: [0.2, 0.3, 0.4],
        normalization: Normalization::Ward,
        symmetrize: false,
        lobes: alphas.iter().map(|&a| Lobe::isotropic([0.2; 3], a)).collect(),
    };
    for (alphas, exact) in [(&[0.1, 0.3][..], true), (&[0.1, 0.15, 0.3][..], false)] {
        let m = material(alphas);
        frame(&mut r, &m, &moved);
        let (drawn, a) = frame(&mut r, &m, &s);
        let (kept, b) = frame(&mut r, &m, &s);
        let (restored, c) = frame(&mut r, &m, &s);
        assert!(has(&drawn, "gbuffer") && has(&drawn, "denoise[sparse,diffuse]"), "{drawn:?}");
        assert!(!has(&drawn, "diffuse") && !has(&drawn, "denoise[sparse]"), "{drawn:?}");
        assert!(has(&kept, "compact") && has(&kept, "base.save") && has(&kept, "denoise[sparse]"), "{kept:?}");
        assert!(!has(&kept, "gbuffer") && !has(&kept, "background") && !has(&kept, "diffuse"), "{kept:?}");
        assert!(has(&restored, "base") && !has(&restored, "compact"), "{restored:?}");
        assert_eq!(b.pixels, c.pixels, "{alphas:?}: the kept base");
        assert_finite("deferred diffuse", &a);
        if exact {
            assert_eq!(a.pixels, b.pixels, "{alphas:?}: the diffuse term drawn by the filter or the diffuse pass");
            continue;
        }
        for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
            for c in 0..4 {
                let bound = 4.0 * f32::EPSILON * p[c].abs().max(q[c].abs());
                assert!((p[c] - q[c]).abs() <= bound, "{alphas:?}: pixel {i} channel {c}: {} against {}", p[c], q[c]);
            }
        }
    }
    r.ctx.check_validation().unwrap();
}

/// The editor builds new lobe pipelines off its thread (`Renderer::build_in_background`): a mesh view
/// whose pipelines are not built yet records nothing (`Recorded::Waiting`) and keeps its image —
/// black for new targets, which are cleared so that compose may read them (the validation layer
/// checks the layouts) — and each build calls back once its pipeline can be collected; then the view
/// draws exactly what a headless render of the same frame draws (same seed, same passes).
#[test]
fn lobe_pipelines_built_in_the_background_draw_the_same_image() {
    let mut r = renderer();
    r.set_environment(&env("studio.exr")).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let m = &common::feature_materials()[1].1;
    let s = settings(24, 8, Estimator::Key);
    let (built, notified) = std::sync::mpsc::channel();
    r.build_in_background = Some(std::sync::Arc::new(move || {
        let _ = built.send(());
    }));
    r.begin_frame(m).unwrap();
    assert_eq!(r.record(m, &s, Progress::Fresh).unwrap(), Recorded::Waiting);
    r.submit_frame(None, None).unwrap();
    let black = r.read_mesh_view().unwrap();
    assert!(black.pixels.iter().all(|p| *p == [0.0; 4]), "a new view waiting for its pipelines is not black");
    let mut frames = 1;
    loop {
        notified.recv_timeout(std::time::Duration::from_secs(120)).expect("a background build never called back");
        r.begin_frame(m).unwrap();
        let recorded = r.record(m, &s, Progress::Fresh).unwrap();
        r.submit_frame(None, None).unwrap();
        frames += 1;
        if recorded == Recorded::Done {
            break;
        }
        assert!(frames < 16, "still waiting after {frames} frames");
    }
    let drawn = r.read_mesh_view().unwrap();
    r.build_in_background = None;
    let headless = r.render(m, &s).unwrap().image;
    assert!(drawn.pixels.iter().any(|p| p[3] > 0.5 && p[0] > 0.0), "the view is empty");
    assert!(drawn.pixels == headless.pixels, "the view differs from the headless render");
    // A headless render builds what it needs at once even with background builds on: a material
    // with lobes of other variants (rotated, split, Ward) renders the same either way.
    let other = &common::feature_materials()[2].1;
    r.build_in_background = Some(std::sync::Arc::new(|| {}));
    let with = r.render(other, &s).unwrap().image;
    r.build_in_background = None;
    let without = r.render(other, &s).unwrap().image;
    assert!(with.pixels.iter().any(|p| p[3] > 0.5 && p[0] > 0.0), "the headless render is empty");
    assert!(with.pixels == without.pixels, "the headless render depends on background builds");
    r.ctx.check_validation().unwrap();
}

/// The editor's stand-in lobe pipeline (`lobe::Output::Any`: the code of every output, the one to
/// take read from the push constants) draws what the
/// view's own pipelines draw (`lobe::Output`, one output each), bit for bit, so a settle frame that
/// takes the stand-in while its own pipelines are built shows the same image. Studio, `key` 8 spp:
/// `assets/bench-4lobes.brdf.json` at 512² (sparse cells, its α 0.02 lobe with its light term at
/// each pixel, the unfiltered accumulation) and at 48² (the dense filter's `rough`), and a rotated
/// split lobe of α 0.18 at 128² (its light points at each pixel, two views).
#[test]
fn the_any_output_stand_in_draws_what_the_views_own_pipelines_draw() {
    let mut r = renderer();
    r.set_environment(&env("studio.exr")).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let bench = Material::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench-4lobes.brdf.json")).unwrap();
    let mut split = bench.clone();
    split.lobes = vec![Lobe { split: true, rotation: DQuat::from_rotation_y(0.35), ..Lobe::isotropic([0.3; 3], 0.18) }];
    // The outputs the cases take (`render::denoise`'s thresholds; asserted so that the test notices
    // when a threshold moves them): the α 0.02 lobe at 512² and the split lobe at 128² take their
    // light term at each pixel, and at 48² (dense) all but the α 0.2 lobe stay unfiltered.
    use brdf_shop::render::denoise;
    assert!(denoise::pixel_lights(&bench.lobes[0], 512, 512) && denoise::pixel_lights(&split.lobes[0], 128, 128));
    assert!(!denoise::sparse(8, 48, 48) && denoise::min_alpha(false, 48, 48) > 0.1);
    let mut failures = Vec::new();
    for (name, m, size, filter) in [
        ("bench", &bench, 512, "denoise[sparse,diffuse]"),
        ("split", &split, 128, "denoise[sparse,diffuse]"),
        ("bench", &bench, 48, "denoise"),
    ] {
        let s = settings(size, 8, Estimator::Key);
        r.options.any_output_lobes = false;
        let own = r.render(m, &s).unwrap();
        r.options.any_output_lobes = true;
        let any = r.render(m, &s).unwrap();
        r.options.any_output_lobes = false;
        let names: Vec<&str> = own.timings.iter().map(|t| t.name.as_str()).collect();
        assert!(names.contains(&filter), "{name} at {size}²: {names:?}");
        // The lobes with their light term at each pixel see the lights as points (`block_points`).
        if size != 48 {
            assert!(names.iter().any(|n| n.starts_with("lobe0[") && n.contains("points")), "{name}: {names:?}");
        }
        assert_finite(name, &own.image);
        if own.image.pixels != any.image.pixels {
            let d = reference::relative_l1(&any.image, &own.image).unwrap_or(f64::NAN);
            failures.push(format!("{name} at {size}²: the stand-in differs by {d:.3e} relative L1"));
        }
    }
    r.ctx.check_validation().unwrap();
    assert!(failures.is_empty(), "{failures:?}");
}

/// The GPU device plan (`render::plan::DevicePlan::GPU`: the compact pass starts every pixel, the
/// filter's images zeroed by a compute pass, a kept G-buffer's background and diffuse image drawn
/// again instead of copied), forced on lavapipe, draws the CPU plan's images. Frames that keep the
/// G-buffer match bit for bit (both plans draw the kept image in the compact pass, or copy what it
/// drew; zeros are zeros). A frame that rasterises and filters sparsely adds the diffuse term in the
/// filter under the CPU plan and in the compact pass under the GPU plan: the same terms summed in
/// another order. They are radiances (no sign cancels), and the bench material's 4 lobes, diffuse
/// term and background make at most 6 reassociated additions, each off by at most 1 ulp of the
/// largest partial sum: 8 ε of the pixel's value bounds the difference.
#[test]
fn the_gpu_device_plan_draws_the_cpu_plans_images() {
    use brdf_shop::render::plan::DevicePlan;
    let mut r = renderer();
    r.set_environment(&env("studio.exr")).unwrap();
    r.set_mesh(&Mesh::sphere()).unwrap();
    let bench = Material::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench-4lobes.brdf.json")).unwrap();
    let has = |names: &[String], n: &str| names.iter().any(|x| x == n);
    for size in [128, 48] {
        let s = settings(size, 8, Estimator::Key);
        let sparse = brdf_shop::render::denoise::sparse(8, size, size);
        assert_eq!(sparse, size == 128, "the cases are a sparse and a dense frame");
        let moved = Settings { camera: Camera { eye: DVec3::new(1.0, 2.0, 4.0), ..Camera::default() }, ..s.clone() };
        let mut runs = Vec::new();
        for plan in [DevicePlan::CPU, DevicePlan::GPU] {
            r.device_plan = plan;
            frame(&mut r, &bench, &moved);
            let frames = [frame(&mut r, &bench, &s), frame(&mut r, &bench, &s), frame(&mut r, &bench, &s)];
            runs.push(frames);
        }
        r.device_plan = DevicePlan::for_device(r.ctx.device.kind);
        let [cpu, gpu] = [&runs[0], &runs[1]];
        let (drawn, kept, restored) = (&gpu[0].0, &gpu[1].0, &gpu[2].0);
        assert!(has(drawn, "gbuffer") && has(drawn, "zero") && !has(drawn, "background"), "{drawn:?}");
        assert!(!has(drawn, "denoise[sparse,diffuse]"), "{drawn:?}");
        for k in [kept, restored] {
            assert!(has(k, "compact") && !has(k, "base") && !has(k, "base.save") && has(k, "zero"), "{k:?}");
        }
        assert!(!cpu.iter().any(|f| has(&f.0, "zero")), "{:?}", cpu[0].0);
        assert_finite("gpu plan", &gpu[0].1);
        assert_eq!(gpu[0].1.pixels, gpu[1].1.pixels, "{size}²: the GPU plan's raster and kept frames");
        assert_eq!(gpu[1].1.pixels, cpu[1].1.pixels, "{size}²: kept frames of both plans");
        assert_eq!(gpu[2].1.pixels, cpu[2].1.pixels, "{size}²: a recomputed base against a copied one");
        for (i, (p, q)) in gpu[0].1.pixels.iter().zip(&cpu[0].1.pixels).enumerate() {
            for c in 0..4 {
                let bound = 8.0 * f32::EPSILON * p[c].abs().max(q[c].abs());
                assert!((p[c] - q[c]).abs() <= bound, "{size}²: pixel {i} channel {c}: {} against {}", p[c], q[c]);
            }
        }
    }
    r.ctx.check_validation().unwrap();
}
