//! `bench`'s viewer group: the editor's frame without the window — the mesh view (`key`, 8 spp)
//! re-rendered every frame as the camera orbits, the canvas re-rendered (a stroke changed the
//! material), both composed into the window image — recorded on the frame ring with frames in
//! flight, as the editor does. Per size and material: the median wall time per frame (what the CPU
//! waits for, recording included), the median GPU time of the frame's passes, their ratio and the
//! frames per second. The swapchain copy and the tool panel are left out (they need a display).

use crate::brdf::Material;
use crate::error::Result;
use crate::layout::Layout;
use crate::render::compose::{Parts, Placement, WINDOW_FORMAT};
use crate::render::{Estimator, Progress, Renderer, Settings, View};
use crate::scene::{Camera, Mesh};
use crate::vk::Image;

/// One size and material.
#[derive(Clone, Debug)]
pub struct ViewerRow {
    pub size: (u32, u32),
    pub material: String,
    pub lobes: usize,
    /// Median wall ms and whole-frame GPU ms per frame.
    pub wall_ms: f64,
    pub gpu_ms: f64,
    pub frames: usize,
}

impl ViewerRow {
    pub fn fps(&self) -> f64 {
        1e3 / self.wall_ms.max(1e-9)
    }
}

/// Measures `frames` frames (after two not counted: pipelines compile on first use) of each size
/// and material on the torus; the environment is the renderer's.
pub fn run(
    r: &mut Renderer,
    sizes: &[(u32, u32)],
    materials: &[(String, Material)],
    frames: usize,
) -> Result<Vec<ViewerRow>> {
    r.set_mesh(&Mesh::resolve("torus")?)?;
    let mut out = Vec::new();
    for &(w, h) in sizes {
        let l = Layout::new(w, h);
        let window = Image::new(
            &r.ctx,
            (w, h),
            WINDOW_FORMAT,
            1,
            ash::vk::ImageUsageFlags::STORAGE | ash::vk::ImageUsageFlags::TRANSFER_SRC,
            "bench.window",
        )?;
        let measured = (|| -> Result<()> {
            for (name, m) in materials {
                let (walls, gpus) = frames_of(r, m, &l, &window, frames)?;
                out.push(ViewerRow {
                    size: (w, h),
                    material: name.clone(),
                    lobes: m.lobes.len(),
                    wall_ms: super::stats(&walls).0,
                    gpu_ms: super::stats(&gpus).0,
                    frames: walls.len(),
                });
                if crate::interrupt::requested() {
                    return Err(crate::Error::input("bench", "interrupted"));
                }
            }
            Ok(())
        })();
        let _ = r.finish_frames();
        window.destroy(&r.ctx);
        measured?;
    }
    Ok(out)
}

/// Wall ms and whole-frame GPU ms of each counted frame.
fn frames_of(
    r: &mut Renderer,
    m: &Material,
    l: &Layout,
    window: &Image,
    frames: usize,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut walls = Vec::new();
    let mut gpu = std::collections::HashMap::new();
    let warm = 2;
    for i in 0..frames + warm {
        let start = std::time::Instant::now();
        r.begin_frame(m)?;
        let number = r.frame_number();
        let yaw = 0.01 * i as f64;
        let camera = Camera {
            eye: glam::DVec3::new(yaw.sin(), 0.45f64.sin(), yaw.cos()) * 4.8,
            target: glam::DVec3::ZERO,
            up: glam::DVec3::Y,
            fov_deg: 30.0,
        };
        let mesh = Settings {
            width: l.mesh_w,
            height: l.height,
            spp: 8,
            estimator: Estimator::Key,
            view: View::Mesh,
            camera,
            light: glam::DVec3::new(0.3, 0.4, 0.866),
            intensity: 1.0,
            backdrop_blur: 0.0,
        };
        let canvas = Settings { width: l.canvas, height: l.canvas, view: View::Canvas, ..mesh.clone() };
        let recorded =
            r.record(m, &mesh, Progress::Fresh).and_then(|_| r.record(m, &canvas, Progress::Fresh)).and_then(|_| {
                let p = Placement {
                    mesh: (l.mesh_x, l.mesh_w, l.height),
                    canvas: (l.canvas_x, l.canvas),
                    mesh_scale: 1.0,
                    backdrop_scale: 1.0,
                    summed: 1,
                    canvas_scale: 1.0,
                    marker: None,
                };
                // The orbiting camera changes the mesh view and the canvas every frame; the grey
                // is written once.
                let parts = Parts { mesh: true, canvas: true, all: i == 0 };
                r.record_compose(window, &p, parts)
            });
        if let Err(e) = recorded {
            let _ = r.abandon_frame();
            return Err(e);
        }
        r.submit_frame(None, None)?;
        if i >= warm {
            walls.push(start.elapsed().as_secs_f64() * 1e3);
            gpu.entry(number).or_insert(f64::NAN);
        }
    }
    r.finish_frames()?;
    for f in r.take_finished() {
        gpu.insert(f.number, f.frame_ms);
    }
    r.ctx.check_validation()?;
    let first = r.frame_number() + 1 - frames as u64;
    let gpus: Vec<f64> =
        (first..=r.frame_number()).filter_map(|n| gpu.get(&n).copied()).filter(|v| v.is_finite()).collect();
    Ok((walls, gpus))
}

/// The viewer rows as a table.
pub fn table(rows: &[ViewerRow], device: &str) -> String {
    let mut s = format!(
        "\nviewer frames on {device} (mesh view key 8 spp + canvas + compose, {} in flight; median of each row's frames)\n\n",
        crate::vk::frame::FRAMES_IN_FLIGHT
    );
    s += "size         material           lobes   wall ms    GPU ms  wall/GPU      fps\n";
    for r in rows {
        s += &format!(
            "{:<12} {:<18} {:>5} {:>9.2} {:>9.2} {:>9.2} {:>8.1}\n",
            format!("{}x{}", r.size.0, r.size.1),
            r.material,
            r.lobes,
            r.wall_ms,
            r.gpu_ms,
            r.wall_ms / r.gpu_ms.max(1e-9),
            r.fps()
        );
    }
    s
}

/// The viewer rows as JSON.
pub fn json(rows: &[ViewerRow]) -> serde_json::Value {
    serde_json::Value::Array(
        rows.iter()
            .map(|r| {
                serde_json::json!({ "size": [r.size.0, r.size.1], "material": r.material, "lobes": r.lobes,
                    "median_wall_ms": r.wall_ms, "median_gpu_ms": r.gpu_ms, "wall_over_gpu": r.wall_ms / r.gpu_ms.max(1e-9),
                    "fps": r.fps(), "frames": r.frames })
            })
            .collect(),
    )
}
