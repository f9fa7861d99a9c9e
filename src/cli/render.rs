//! `brdf-shop render`: one headless GPU frame (README, Commands) written as EXR or PNG, with
//! `--timings`; `--plan` prints the frame's plan (without `--out`, instead of rendering).

use brdf_shop::render::plan::Plan;
use brdf_shop::render::{Estimator, Progress, Renderer, View};
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
    // The plan of the frame `render` records: a frame of its own, which rasterises.
    let plan = renderer.plan(&scene.material, &scene.settings, Progress::Fresh, false);
    if args.out.is_none() {
        print!("{}", plan.describe());
        return Ok(());
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
    let mut extra = vec![
        ("plan", plan.to_json()),
        ("barriers", serde_json::json!(frame.commands.barriers)),
        ("dispatches", serde_json::json!(frame.commands.dispatches)),
    ];
    extra.extend(key_lights.map(|k| ("key_lights", k.to_json())));
    scene::write_outputs(args, &mut frame.image, renderer.device_name(), &scene, &passes, frame.frame_ms, extra)?;
    if args.plan {
        print!("{}", timed_plan(&plan, &passes));
        println!("{} dispatches, {} pipeline barriers", frame.commands.dispatches, frame.commands.barriers);
    }
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
        brdf_shop::fsio::show(args.out())
    );
    Ok(())
}

/// The plan in words with each pass's GPU time at the start of its line (`untimed` for a transfer
/// clear, which no timestamp pair brackets).
fn timed_plan(plan: &Plan, passes: &[(String, f64)]) -> String {
    let words = plan.describe();
    let mut out = String::new();
    let mut steps = plan.steps.iter();
    for line in words.lines() {
        let numbered = line.trim_start().split_once(". ").filter(|(n, _)| n.parse::<usize>().is_ok());
        match (numbered, steps.clone().next()) {
            (Some(_), Some(step)) => {
                steps.next();
                let ms = passes.iter().find(|(n, _)| *n == step.name()).map(|p| p.1);
                let time = ms.map_or("   untimed".to_string(), |ms| format!("{ms:>7.3} ms"));
                out.push_str(&format!("{time} {line}\n"));
            }
            _ => out.push_str(&format!("           {line}\n")),
        }
    }
    out
}
