//! `brdf-shop render`: one headless GPU frame (README, Commands) written as EXR or PNG, with `--timings`.

use brdf_shop::render::{Estimator, Renderer, View};
use brdf_shop::vk::Context;

use super::scene::{self, SceneArgs};

pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    let scene = scene::load(args, |e| if e == Estimator::Mis { 1024 } else { 8 }, brdf_shop::render::check_limits)?;
    let mut renderer = Renderer::new(Context::from_env()?)?;
    if let Some(env) = &scene.env {
        renderer.set_environment(env)?;
    }
    if let Some(mesh) = &scene.mesh {
        renderer.set_mesh(mesh)?;
    }
    if !renderer.linear_filtering() {
        eprintln!(
            "warning: this device cannot filter RGBA32F linearly; the environment is read with nearest filtering"
        );
    }
    let mut frame = renderer.render(&scene.material, &scene.settings)?;
    let passes: Vec<(String, f64)> = frame.timings.iter().map(|t| (t.name.clone(), t.ms)).collect();
    // The key estimator's decision about the map (which lights it split off, and the threshold).
    let key_lights = (scene.settings.estimator == Estimator::Key && scene.settings.view == View::Mesh)
        .then(|| renderer.key_lights())
        .flatten();
    let json = key_lights.map(|k| k.to_json());
    scene::write_outputs(args, &mut frame.image, renderer.device_name(), &scene, &passes, frame.frame_ms, json)?;
    scene::report_env(&scene);
    if let Some(k) = key_lights {
        eprintln!("key estimator: {}", k.describe());
    }
    eprintln!(
        "rendered {}x{} on {} in {:.3} ms of GPU time (whole frame; {} passes {:.3} ms, untimed {:.3} ms); wrote {}",
        frame.image.width,
        frame.image.height,
        renderer.device_name(),
        frame.frame_ms,
        frame.timings.len(),
        frame.passes_ms(),
        frame.untimed_ms(),
        brdf_shop::fsio::show(&args.out)
    );
    Ok(())
}
