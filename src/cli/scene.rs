//! The flags `render` and `reference` share (SPEC §4) and what they load: material, environment,
//! mesh, camera, canvas light, image size and sample count. Every refusal names the flag or file.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use brdf_shop::brdf::Material;
use brdf_shop::render::{Estimator, Settings, View};
use brdf_shop::scene::{Camera, Environment, Mesh};
use brdf_shop::Error;
use glam::DVec3;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewArg {
    Mesh,
    Canvas,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EstimatorArg {
    Fis,
    Plain,
    Mis,
}

#[derive(clap::Args, Clone, Debug)]
pub struct SceneArgs {
    /// The material (*.brdf.json); default: the embedded default strokes painted on the scratch material.
    #[arg(long)]
    pub material: Option<PathBuf>,
    /// Environment map (.exr or .hdr, equirectangular); required for mesh views.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// `sphere`, `torus` or a mesh file: OBJ, glTF 2.0 (.gltf, .glb) or PLY.
    #[arg(long, default_value = "sphere")]
    pub mesh: String,
    #[arg(long, value_enum, default_value_t = ViewArg::Mesh)]
    pub view: ViewArg,
    /// Image size `WxH`.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// Samples per pixel per lobe (fis, plain) or per pixel (mis, reference).
    #[arg(long)]
    pub spp: Option<u32>,
    #[arg(long, value_enum)]
    pub estimator: Option<EstimatorArg>,
    /// Read the environment at level 0 only (the `plain` estimator).
    #[arg(long)]
    pub no_prefilter: bool,
    /// "eye=x,y,z target=x,y,z up=x,y,z fov=deg" (any subset).
    #[arg(long)]
    pub camera: Option<String>,
    /// Canvas light direction `x,y,z` (canvas space); default: the environment's brightest direction
    /// seen from the camera, or the default strokes' light without an environment.
    #[arg(long)]
    pub light: Option<String>,
    /// Linear scale before the sRGB curve (PNG output).
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f64,
    /// Output image: .exr (linear) or .png.
    #[arg(long)]
    pub out: PathBuf,
    /// Write the GPU time of every pass that ran (JSON).
    #[arg(long)]
    pub timings: Option<PathBuf>,
}

/// Everything a render needs, loaded and checked.
pub struct Scene {
    pub material: Material,
    pub env: Option<Environment>,
    pub mesh: Option<Mesh>,
    pub settings: Settings,
}

pub fn parse_size(s: &str) -> Result<(u32, u32), Error> {
    let bad = || Error::input("--size", format!("expected WxH with positive integers, got \"{s}\""));
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if w == 0 || h == 0 {
        return Err(Error::input("--size", format!("{w}x{h} is empty; both sides must be at least 1")));
    }
    Ok((w, h))
}

fn parse_vec3(flag: &str, s: &str) -> Result<DVec3, Error> {
    let parts: Vec<&str> = s.split(',').collect();
    let v: Option<Vec<f64>> = parts.iter().map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect();
    match v {
        Some(v) if v.len() == 3 => {
            let d = DVec3::new(v[0], v[1], v[2]);
            brdf_shop::brdf::material::unit(d)
                .ok_or_else(|| Error::input(flag, format!("\"{s}\" is not a usable direction (zero length)")))
        }
        _ => Err(Error::input(flag, format!("expected x,y,z with three finite numbers, got \"{s}\""))),
    }
}

/// The canvas light: `--light`, else the environment's brightest direction in the camera's frame
/// (canvas x = camera right, y = camera up, z = towards the viewer), else the default strokes' light.
fn canvas_light(args: &SceneArgs, env: Option<&Environment>, camera: &Camera) -> anyhow::Result<DVec3> {
    if let Some(l) = &args.light {
        return Ok(parse_vec3("--light", l)?);
    }
    if let Some(env) = env {
        let d = env.brightest_direction();
        let forward = (camera.target - camera.eye).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        return Ok(DVec3::new(d.dot(right), d.dot(up), -d.dot(forward)));
    }
    let strokes = brdf_shop::brush::strokes::default_strokes()?;
    Ok(strokes.settings("embedded default strokes")?.canvas.light)
}

/// Loads and checks everything; `default_spp` per estimator when `--spp` is absent.
pub fn load(args: &SceneArgs, default_spp: impl Fn(Estimator) -> u32) -> anyhow::Result<Scene> {
    brdf_shop::imageio::check_output_path(&args.out)?;
    let (width, height) = parse_size(&args.size)?;
    let estimator = match (args.estimator, args.no_prefilter) {
        (None, false) | (Some(EstimatorArg::Fis), false) => Estimator::Fis,
        (None, true) | (Some(EstimatorArg::Plain), _) => Estimator::Plain,
        (Some(EstimatorArg::Mis), false) => Estimator::Mis,
        (Some(e), true) => {
            return Err(Error::input(
                "--no-prefilter",
                format!("conflicts with --estimator {} (--no-prefilter means plain)", format!("{e:?}").to_lowercase()),
            )
            .into())
        }
    };
    let spp = args.spp.unwrap_or_else(|| default_spp(estimator));
    if spp == 0 {
        return Err(Error::input("--spp", "must be at least 1").into());
    }
    let camera = match &args.camera {
        Some(c) => Camera::parse(c).map_err(|e| Error::input("--camera", e))?,
        None => Camera::default(),
    };
    let material = match &args.material {
        Some(p) => Material::load(p)?,
        None => brdf_shop::brush::strokes::default_material()?,
    };
    let view = match args.view {
        ViewArg::Mesh => View::Mesh,
        ViewArg::Canvas => View::Canvas,
    };
    let env = match &args.env {
        Some(p) => Some(load_env(p)?),
        None if view == View::Mesh => {
            return Err(Error::input("--env", "a mesh view needs an environment map (.exr or .hdr)").into())
        }
        None => None,
    };
    let mesh = match view {
        View::Mesh => Some(Mesh::resolve(&args.mesh)?),
        View::Canvas => None,
    };
    let light = canvas_light(args, env.as_ref(), &camera)?;
    let settings = Settings { width, height, spp, estimator, view, camera, light, intensity: 1.0 };
    Ok(Scene { material, env, mesh, settings })
}

/// Loads an environment map.
pub fn load_env(path: &Path) -> anyhow::Result<Environment> {
    Ok(Environment::load(path)?)
}

/// What the loader changed or kept (SPEC §1), printed once the command succeeded (a refusal stays
/// one line).
pub fn report_env(scene: &Scene) {
    if let Some(env) = &scene.env {
        let s = &env.stats;
        eprintln!(
            "{}: {}x{}, {} non-finite texel(s) set to 0, {} negative texel(s) kept ({:.2} % of the energy)",
            env.origin,
            env.width,
            env.height,
            s.non_finite,
            s.negative,
            100.0 * s.negative_energy_fraction
        );
    }
}

/// Writes the `--timings` JSON: device, estimator, size, samples, and per pass its name and GPU ms.
pub fn write_timings(path: &Path, device: &str, scene: &Scene, passes: &[(String, f64)]) -> anyhow::Result<()> {
    let s = &scene.settings;
    let json = serde_json::json!({
        "device": device,
        "estimator": s.estimator.name(),
        "view": if s.view == View::Mesh { "mesh" } else { "canvas" },
        "size": [s.width, s.height],
        "spp": s.spp,
        "passes": passes.iter().map(|(n, ms)| serde_json::json!({"name": n, "ms": ms})).collect::<Vec<_>>(),
        "total_ms": passes.iter().map(|p| p.1).sum::<f64>(),
    });
    let text = serde_json::to_string_pretty(&json).context("encoding timings")? + "\n";
    brdf_shop::fsio::write_atomic(path, text.as_bytes())?;
    Ok(())
}
