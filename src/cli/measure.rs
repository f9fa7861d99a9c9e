//! `brdf-shop bench` and `brdf-shop report {error-vs-time, stability}`: thin
//! front ends over `brdf_shop::measure`, each with a `--quick` setting the tests run.

use std::path::Path;

use anyhow::Context as _;
use brdf_shop::measure::{bench, error_vs_time, stability, viewer};
use brdf_shop::render::Renderer;
use brdf_shop::vk::Context;

fn renderer() -> anyhow::Result<Renderer> {
    Ok(Renderer::new(Context::from_env()?)?)
}

/// A report's result, or [`brdf_shop::interrupt::Interrupted`] (exit status 130) when it stopped on
/// Ctrl-C.
fn unless_interrupted<T>(r: brdf_shop::Result<T>) -> anyhow::Result<T> {
    match r {
        Err(_) if brdf_shop::interrupt::requested() => Err(brdf_shop::interrupt::Interrupted.into()),
        r => Ok(r?),
    }
}

pub fn bench(quick: bool, goal: bool, json: Option<&Path>, hdri: Option<&Path>) -> anyhow::Result<()> {
    if let Some(p) = json {
        brdf_shop::fsio::check_output("--json", p)?;
    }
    let mut plan = if quick { bench::Plan::quick() } else { bench::Plan::full() };
    plan.hdri = brdf_shop::measure::hdri_dir(hdri);
    plan.goal_only = goal;
    // Refused before the device starts: a missing map leaves nothing written.
    brdf_shop::measure::require_maps(&plan.hdri, &[bench::ENV])?;
    let mut r = renderer()?;
    brdf_shop::interrupt::install();
    let vendor = r.ctx.device.info.vendor_id;
    let clocks_start = brdf_shop::measure::control::clocks(vendor);
    let peak = bench::peak(&r, plan.repeats)?;
    let rows = unless_interrupted(bench::run(&mut r, &plan, true))?;
    let clocks_end = brdf_shop::measure::control::clocks(vendor);
    print!("{}", bench::table(&rows, r.device_name(), peak));
    let stability = bench::stability(&rows);
    if !stability.stable {
        eprintln!(
            "warning: unstable run: the whole-frame medians of the control rows and the goal row at their size are {:.1} % apart (more than {:.0} %)",
            100.0 * stability.spread,
            100.0 * brdf_shop::measure::control::CONTROL_TOLERANCE
        );
    }
    // `--goal`: the goal scene alone, no viewer rows.
    let viewer = if goal {
        Vec::new()
    } else {
        let materials = vec![
            ("default".to_string(), brdf_shop::brush::strokes::default_material()?),
            ("8 lobes".to_string(), bench::material(8)),
        ];
        let frames = if quick { 4 } else { 20 };
        let viewer = unless_interrupted(viewer::run(&mut r, &plan.viewer_sizes, &materials, frames))?;
        print!("{}", viewer::table(&viewer, r.device_name()));
        viewer
    };
    if let Some(path) = json {
        let mut doc = bench::json(&rows, r.device_name(), &plan, peak);
        doc["driver"] = bench::driver_json(&r.ctx.device.info);
        doc["device_plan"] = serde_json::json!(r.device_plan.name());
        doc["goal_plan"] = bench::goal_plan_json(&mut r, &plan)?;
        doc["clocks"] = match (clocks_start, clocks_end) {
            (Some(a), Some(b)) => serde_json::json!({ "start": a, "end": b }),
            _ => serde_json::Value::Null,
        };
        doc["viewer"] = viewer::json(&viewer);
        let text = serde_json::to_string_pretty(&doc).context("encoding JSON")? + "\n";
        brdf_shop::fsio::write_atomic(path, text.as_bytes())?;
        println!("wrote {}", brdf_shop::fsio::show(path));
    }
    Ok(())
}

pub fn error_vs_time(
    quick: bool,
    out: &Path,
    hdri: Option<&Path>,
    maps: &[String],
    materials: &[String],
    size: Option<u32>,
) -> anyhow::Result<()> {
    let mut plan = if quick { error_vs_time::Plan::quick() } else { error_vs_time::Plan::full() };
    plan.restrict(maps, materials)?;
    if let Some(side) = size {
        plan.resize(side)?;
    }
    brdf_shop::fsio::check_output_dir("--out", out)?;
    plan.hdri = brdf_shop::measure::hdri_dir(hdri);
    brdf_shop::measure::require_maps(&plan.hdri, &plan.envs)?;
    let mut r = renderer()?;
    brdf_shop::interrupt::install();
    let (_, files) = unless_interrupted(error_vs_time::report(&mut r, &plan, out, true))?;
    // The summary as written (files: CSV, plot, summary).
    print!("{}", std::fs::read_to_string(&files[2]).map_err(|e| brdf_shop::Error::io(&files[2], e))?);
    for f in files {
        println!("wrote {}", brdf_shop::fsio::show(&f));
    }
    Ok(())
}

pub fn stability(quick: bool, out: Option<&Path>) -> anyhow::Result<()> {
    if let Some(p) = out {
        brdf_shop::fsio::check_output("--out", p)?;
    }
    let mut r = renderer()?;
    let cases = stability::run(&mut r, quick)?;
    let text = stability::table(&cases, r.device_name());
    print!("{text}");
    if let Some(path) = out {
        brdf_shop::fsio::write_atomic(path, text.as_bytes())?;
        println!("wrote {}", brdf_shop::fsio::show(path));
    }
    let bad: Vec<&str> = cases.iter().filter(|c| c.non_finite > 0).map(|c| c.name.as_str()).collect();
    if !bad.is_empty() {
        anyhow::bail!("non-finite values in: {}", bad.join(", "));
    }
    Ok(())
}
