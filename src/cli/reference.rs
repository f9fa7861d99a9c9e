//! `brdf-shop reference`: the same image as `render`, on the CPU from the `f64` model — converged
//! by multiple importance sampling between the environment and the material (mesh views), or the
//! exact point-lit canvas (canvas views). The ground truth for tests and reports.

use std::time::Instant;

use brdf_shop::brush::canvas::Canvas;
use brdf_shop::reference;
use brdf_shop::render::View;

use super::scene::{self, SceneArgs};

pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    if args.plan {
        return Err(brdf_shop::Error::input(
            "--plan",
            "is the GPU renderer's (brdf-shop render --plan); the reference has no passes",
        )
        .into());
    }
    let scene = scene::load(args, |_| 1024, reference::check_limits)?;
    brdf_shop::interrupt::install();
    let s = &scene.settings;
    let start = Instant::now();
    let image = match s.view {
        View::Mesh => {
            let (env, mesh) =
                (scene.env.as_ref().expect("loaded for mesh views"), scene.mesh.as_ref().expect("loaded"));
            let stop = brdf_shop::interrupt::requested;
            let mut image = reference::render_mesh_watched(
                &scene.material,
                env,
                mesh,
                &s.camera,
                s.width,
                s.height,
                s.spp,
                true,
                &stop,
            )
            .ok_or(brdf_shop::interrupt::Interrupted)?;
            if s.backdrop_blur > 0.0 {
                blur_backdrop(&mut image, env, &s.camera, s.backdrop_blur);
            }
            image
        }
        View::Canvas => {
            let canvas = Canvas { light: s.light, intensity: s.intensity };
            reference::render_canvas(&scene.material, &canvas, s.width, s.height)
        }
    };
    let mut image = image;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    scene::write_outputs(
        args,
        &mut image,
        "cpu (reference)",
        &scene,
        &[("reference".to_string(), ms)],
        ms,
        Vec::new(),
    )?;
    scene::report_env(&scene);
    eprintln!(
        "reference {}x{} at {} spp in {:.1} s; wrote {}",
        image.width,
        image.height,
        s.spp,
        ms / 1e3,
        brdf_shop::fsio::show(args.out())
    );
    Ok(())
}

/// The backdrop (the pixels off the object, alpha 0) at mip level `lod` of the map, as the GPU's
/// backdrop reads it ([`brdf_shop::scene::Environment::lookup_chain`]).
fn blur_backdrop(
    image: &mut reference::Image,
    env: &brdf_shop::scene::Environment,
    camera: &brdf_shop::scene::Camera,
    lod: f64,
) {
    let chain = env.mip_chain();
    let rays = brdf_shop::scene::camera::Rays::new(camera, image.width, image.height);
    let w = image.width as usize;
    for (k, p) in image.pixels.iter_mut().enumerate().filter(|(_, p)| p[3] < 0.5) {
        let dir = rays.at((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        let l = brdf_shop::scene::Environment::lookup_chain(&chain, dir, lod);
        *p = [l.x as f32, l.y as f32, l.z as f32, p[3]];
    }
}
