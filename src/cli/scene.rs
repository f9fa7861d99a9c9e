//! The flags `render` and `reference` share (README, Commands) and what they load: material,
//! environment, mesh, camera, canvas light, image size and sample count. Every refusal names the flag or file.

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
    /// Key lights split off the map (light + BRDF sampling) and the residual prefiltered: the default.
    Key,
    /// The paper's filtered importance sampling.
    Fis,
    Plain,
    Mis,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BackgroundArg {
    /// The environment map, at `--backdrop-brightness` and `--backdrop-blur`.
    Env,
    Black,
}

#[derive(clap::Args, Clone, Debug)]
pub struct SceneArgs {
    /// The material (*.brdf.json); default: the embedded default strokes painted on the scratch material.
    #[arg(long)]
    pub material: Option<PathBuf>,
    /// Environment map (.exr or .hdr, equirectangular); required for mesh views.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Turn the environment by DEG degrees about the up axis (+y, counter-clockwise seen from
    /// above): the lighting, the key lights and the backdrop together.
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_hyphen_values = true)]
    pub env_rotation: f64,
    /// `sphere`, `torus` or a mesh file: OBJ, glTF 2.0 (.gltf, .glb) or PLY.
    #[arg(long, default_value = "sphere")]
    pub mesh: String,
    #[arg(long, value_enum, default_value_t = ViewArg::Mesh)]
    pub view: ViewArg,
    /// Image size `WxH`.
    #[arg(long, default_value = "512x512", allow_hyphen_values = true)]
    pub size: String,
    /// Samples per pixel per lobe component (key, fis, plain; key adds as many light samples, at most
    /// 408) or per pixel (mis, reference).
    #[arg(long, allow_hyphen_values = true)]
    pub spp: Option<u32>,
    /// The estimator of the mesh view (default key).
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
    #[arg(long, allow_hyphen_values = true)]
    pub light: Option<String>,
    /// Linear scale before the sRGB curve (PNG output): a finite number > 0.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub exposure: f64,
    /// What the mesh view shows behind the object: the environment (`env`) or black.
    #[arg(long, value_enum, default_value_t = BackgroundArg::Env)]
    pub background: BackgroundArg,
    /// The backdrop's own linear scale, independent of the object's exposure (the image's backdrop
    /// pixels are the map's radiance times this); default: the exposure.
    #[arg(long, value_name = "B", allow_hyphen_values = true)]
    pub backdrop_brightness: Option<f64>,
    /// The backdrop's blur: the level of the environment's mip chain it shows (0 the map itself,
    /// each level halves the resolution; fractional levels blend two).
    #[arg(long, value_name = "LEVEL", default_value_t = 0.0, allow_hyphen_values = true)]
    pub backdrop_blur: f64,
    /// Output image: .exr (linear) or .png.
    #[arg(long, required_unless_present = "plan")]
    pub out: Option<PathBuf>,
    /// Write the GPU time of every pass that ran, and the frame's plan (JSON).
    #[arg(long)]
    pub timings: Option<PathBuf>,
    /// Print the frame's plan (its passes in order, each one's variant and why it runs; what it leaves
    /// out and why) without rendering; with `--out`, render as well and print each pass's GPU time
    /// beside it (`render` only).
    #[arg(long)]
    pub plan: bool,
}

impl SceneArgs {
    /// The output image (clap makes `--out` required unless `--plan` is given, and the commands
    /// that draw nothing never ask for it).
    pub fn out(&self) -> &Path {
        self.out.as_deref().unwrap_or(Path::new(""))
    }
}

/// Everything a render needs, loaded and checked.
pub struct Scene {
    pub material: Material,
    pub env: Option<Environment>,
    pub mesh: Option<Mesh>,
    pub settings: Settings,
    /// The backdrop's linear scale ([`backdrop_brightness`]); `None`: the exposure's.
    pub backdrop: Option<f64>,
}

pub fn parse_size(s: &str) -> Result<(u32, u32), Error> {
    let bad = || {
        Error::input("--size", format!("expected WxH with positive integers, got \"{}\"", brdf_shop::fsio::quote(s)))
    };
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
            brdf_shop::brdf::material::unit(d).ok_or_else(|| {
                Error::input(flag, format!("\"{}\" is not a usable direction (zero length)", brdf_shop::fsio::quote(s)))
            })
        }
        _ => Err(Error::input(
            flag,
            format!("expected x,y,z with three finite numbers, got \"{}\"", brdf_shop::fsio::quote(s)),
        )),
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

/// Checks the output paths before any work: `--out` (an image format, a writable folder) and
/// `--timings` (a writable folder, not the same file as `--out` however spelled).
pub fn check_outputs(args: &SceneArgs) -> anyhow::Result<()> {
    if args.out.is_none() {
        if args.timings.is_some() {
            return Err(Error::input("--timings", "needs --out: a plan without --out renders no frame to time").into());
        }
        return Ok(());
    }
    brdf_shop::imageio::check_output_path(args.out())?;
    let mut outputs = vec![("--out", args.out())];
    outputs.extend(args.timings.as_deref().map(|t| ("--timings", t)));
    brdf_shop::fsio::check_outputs(&outputs)?;
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        return Err(Error::input("--exposure", format!("must be a finite number > 0, got {}", args.exposure)).into());
    }
    Ok(())
}

/// Loads and checks everything; `default_spp` per estimator when `--spp` is absent; `limits`
/// refuses a size or sample count beyond the command's limits (before anything is loaded).
pub fn load(
    args: &SceneArgs,
    default_spp: impl Fn(Estimator) -> u32,
    limits: impl Fn(u32, u32, u32) -> Result<(), Error>,
) -> anyhow::Result<Scene> {
    check_outputs(args)?;
    let (width, height) = parse_size(&args.size)?;
    let estimator = match (args.estimator, args.no_prefilter) {
        (None, false) | (Some(EstimatorArg::Key), false) => Estimator::Key,
        (Some(EstimatorArg::Fis), false) => Estimator::Fis,
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
    limits(width, height, spp)?;
    let camera = match &args.camera {
        Some(c) => Camera::parse(c).map_err(|e| Error::input("--camera", e))?,
        None => Camera::framed(width, height),
    };
    let material = match &args.material {
        Some(p) => Material::load(p)?,
        None => brdf_shop::brush::strokes::default_material()?,
    };
    let view = match args.view {
        ViewArg::Mesh => View::Mesh,
        ViewArg::Canvas => View::Canvas,
    };
    let backdrop = backdrop_brightness(args)?;
    if !(args.backdrop_blur.is_finite() && args.backdrop_blur >= 0.0) {
        return Err(Error::input(
            "--backdrop-blur",
            format!("{} is not a mip level (a finite number ≥ 0)", args.backdrop_blur),
        )
        .into());
    }
    if !args.env_rotation.is_finite() {
        return Err(
            Error::input("--env-rotation", format!("{} is not a finite number of degrees", args.env_rotation)).into()
        );
    }
    let env = match &args.env {
        Some(p) if args.env_rotation != 0.0 => Some(load_env(p)?.rotated(args.env_rotation)),
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
    let settings = Settings {
        width,
        height,
        spp,
        estimator,
        view,
        camera,
        light,
        intensity: 1.0,
        backdrop_blur: args.backdrop_blur,
    };
    Ok(Scene { material, env, mesh, settings, backdrop })
}

/// The backdrop's linear scale: 0 for `--background black`, else `--backdrop-brightness` (a finite
/// number ≥ 0); `None` (the default) draws it as the object is drawn, at the exposure.
fn backdrop_brightness(args: &SceneArgs) -> Result<Option<f64>, Error> {
    match (args.background, args.backdrop_brightness) {
        (BackgroundArg::Black, _) => Ok(Some(0.0)),
        (BackgroundArg::Env, None) => Ok(None),
        (BackgroundArg::Env, Some(b)) if b.is_finite() && b >= 0.0 => Ok(Some(b)),
        (BackgroundArg::Env, Some(b)) => {
            Err(Error::input("--backdrop-brightness", format!("{b} is not a finite number ≥ 0")))
        }
    }
}

/// Loads an environment map.
pub fn load_env(path: &Path) -> anyhow::Result<Environment> {
    Ok(Environment::load(path)?)
}

/// What the loader changed or kept (docs/model.md, Frames and conventions), printed once the command succeeded (a
/// refusal stays one line).
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

/// Writes the image and, with `--timings`, the timings JSON as one atomic step (both temporary files
/// are written before either is renamed), after warning about radiance clamped to `f32`'s range.
pub fn write_outputs(
    args: &SceneArgs,
    image: &mut brdf_shop::reference::Image,
    device: &str,
    scene: &Scene,
    passes: &[(String, f64)],
    frame_ms: f64,
    extra: Vec<(&str, serde_json::Value)>,
) -> anyhow::Result<()> {
    // The backdrop (alpha 0) at its own brightness: the image holds the map's radiance times it, and
    // a PNG shows it as it is, the object at the exposure.
    let backdrop = scene.backdrop.filter(|_| scene.settings.view == View::Mesh);
    if let Some(b) = backdrop {
        brdf_shop::imageio::scale_backdrop(&mut image.pixels, b);
    }
    let clamped = brdf_shop::imageio::clamp_to_finite(&mut image.pixels);
    let backdrop_exposure = if backdrop.is_some() { 1.0 } else { args.exposure };
    let (w, h) = (image.width, image.height);
    let bytes = brdf_shop::imageio::encode_view(args.out(), w, h, &image.pixels, args.exposure, backdrop_exposure)?;
    let timings = args
        .timings
        .as_ref()
        .map(|t| timings_json(device, scene, passes, frame_ms, &extra).map(|j| (t, j)))
        .transpose()?;
    let mut outputs: Vec<(&Path, &[u8])> = vec![(args.out(), &bytes)];
    if let Some((t, j)) = &timings {
        outputs.push((t.as_path(), j.as_bytes()));
    }
    brdf_shop::fsio::write_all_atomic(&outputs)?;
    if clamped > 0 {
        eprintln!(
            "warning: {clamped} channel value(s) overflowed f32 (or were NaN) and were written as ±{:e} (NaN as 0)",
            f32::MAX
        );
    }
    Ok(())
}

/// The `--timings` JSON: device, estimator, size, samples, per pass its name and GPU ms, their sum
/// (`total_ms`), the whole frame (`frame_ms`, first command to last) and the part of it no pass
/// timed (`untimed_ms`), then the `extra` fields (the frame's plan, the key lights).
fn timings_json(
    device: &str,
    scene: &Scene,
    passes: &[(String, f64)],
    frame_ms: f64,
    extra: &[(&str, serde_json::Value)],
) -> anyhow::Result<String> {
    let s = &scene.settings;
    let total = passes.iter().map(|p| p.1).sum::<f64>() + 0.0;
    let mut json = serde_json::json!({
        "device": device,
        "estimator": s.estimator.name(),
        "view": if s.view == View::Mesh { "mesh" } else { "canvas" },
        "size": [s.width, s.height],
        "spp": s.spp,
        "passes": passes.iter().map(|(n, ms)| serde_json::json!({"name": n, "ms": ms})).collect::<Vec<_>>(),
        "total_ms": total,
        "frame_ms": frame_ms,
        "untimed_ms": brdf_shop::vk::query::untimed_ms(frame_ms, total),
    });
    for (name, value) in extra {
        json[*name] = value.clone();
    }
    Ok(serde_json::to_string_pretty(&json).context("encoding timings")? + "\n")
}
