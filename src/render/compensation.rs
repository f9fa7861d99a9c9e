//! The energy compensation pass (docs/renderer.md, Energy compensation): after the lobe passes of an
//! energy-preserving material (`key`, `fis`, `plain`), each lobe's compensation term over the listed
//! pixels from its kernel's SH projection ([`kernel`]) and the map's SH9 (`glsl/compensation.comp`).
//! Also what the frame's buffers hold for it and for every shader that evaluates the material
//! (`Tables`): the lobes' tables, baked at once or, in the editor, on a thread of their own.

use std::f64::consts::PI;
use std::sync::Arc;

use super::diffuse;
use super::gpu::Push;
use super::Recording;
use crate::brdf::compensation::{self, Table};
use crate::brdf::Material;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::{Buffer, Context};
use crate::Result;

/// Cells a side of the cosine-weighted square the kernel is projected over: the same midpoint rule as
/// `Table::deficit`, so that the band-0 term is the table's measured deficit.
const KERNEL_GRID: usize = 256;

/// The SH coefficients (bands `l ≤ 2`, local frame) of a lobe's kernel `K = (1 − Ê) cos⁺θ`:
/// `k_i = π · mean((1 − Ê) Y_i)` over the midpoint rule's cosine-distributed directions.
pub fn kernel_sh(t: &Table) -> [f64; 9] {
    let mut k = [0.0; 9];
    for i in 0..KERNEL_GRID {
        for j in 0..KERNEL_GRID {
            let u = ((i as f64 + 0.5) / KERNEL_GRID as f64, (j as f64 + 0.5) / KERNEL_GRID as f64);
            let w = crate::brdf::sampling::sample_cosine(u.0, u.1);
            let g = 1.0 - f64::from(t.albedo(w.as_vec3().to_array()));
            for (c, y) in k.iter_mut().zip(crate::scene::env::sh_basis(w)) {
                *c += g * y;
            }
        }
    }
    k.map(|c| PI * c / (KERNEL_GRID * KERNEL_GRID) as f64)
}

/// The kernel as `compensation.comp` reads it, three `vec4`: `(a, b)`, `(C_xx, C_yy, C_zz, C_xy)`,
/// `(C_xz, C_yz, 0, 0)` of `K ≈ a + b·ω + ωᵀCω` (`C` traceless), with the integral's constants folded
/// in: `∫ K L dω = 4π aα + (4π/3) b·β + (8π/15) Σ_ij C_ij Γ_ij` for `L = α + β·ω + ωᵀΓω` (`Γ`
/// traceless; the bands are orthogonal), so the shader's sum is `a'α + b'·β + Σ C'Γ` over the six
/// distinct entries (the off-diagonal ones twice).
pub fn kernel(k: &[f64; 9]) -> [[f32; 4]; 3] {
    let (c2, c1, c0) = (8.0 * PI / 15.0, 4.0 * PI / 3.0, 4.0 * PI);
    let a = 0.282095 * k[0];
    let b = [0.488603 * k[3], 0.488603 * k[1], 0.488603 * k[2]];
    let (g, z) = (0.546274, 0.315392);
    let cxx = g * k[8] - z * k[6];
    let cyy = -g * k[8] - z * k[6];
    let czz = 2.0 * z * k[6];
    let (cxy, cyz, cxz) = (g * k[4], g * k[5], g * k[7]);
    let f = |v: f64| v as f32;
    [
        [f(c0 * a), f(c1 * b[0]), f(c1 * b[1]), f(c1 * b[2])],
        [f(c2 * cxx), f(c2 * cyy), f(c2 * czz), f(2.0 * c2 * cxy)],
        [f(2.0 * c2 * cxz), f(2.0 * c2 * cyz), 0.0, 0.0],
    ]
}

/// What the frame's buffers hold for the compensation: the tables' words (`compensation::words`)
/// and the kernels, one entry a lobe; a lobe whose table is not baked yet has none (its term is 0).
#[derive(Default)]
pub struct Tables {
    tables: Vec<Option<Arc<Table>>>,
    words: Vec<u8>,
    kernels: Vec<u8>,
}

impl Tables {
    /// The buffers' bytes for `m`, made again only where a lobe's table changed. `background`:
    /// tables not baked yet are baked on a thread of their own, which calls it when done (the
    /// editor); `None` bakes them now.
    pub fn update(&mut self, m: &Material, background: Option<&super::lobe::Notify>) -> (&[u8], &[u8]) {
        let tables: Vec<Option<Arc<Table>>> = if m.compensated() {
            m.lobes
                .iter()
                .map(|l| match background {
                    Some(notify) => {
                        let notify = notify.clone();
                        compensation::table_or_bake(l, move || notify())
                    }
                    None => Some(compensation::table(l)),
                })
                .collect()
        } else {
            Vec::new()
        };
        let same = |a: &Option<Arc<Table>>, b: &Option<Arc<Table>>| match (a, b) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            (None, None) => true,
            _ => false,
        };
        let unchanged = self.tables.len() == tables.len() && self.tables.iter().zip(&tables).all(|(a, b)| same(a, b));
        if !unchanged || self.words.is_empty() {
            let refs: Vec<Option<&Table>> = tables.iter().map(|t| t.as_deref()).collect();
            self.words = bytemuck::cast_slice(&compensation::words(&refs)).to_vec();
            let kernels: Vec<[[f32; 4]; 3]> = tables
                .iter()
                .map(|t| t.as_ref().map_or([[0.0; 4]; 3], |t| kernel(&kernel_sh(t))))
                .chain(std::iter::once([[0.0; 4]; 3]))
                .collect();
            self.kernels = bytemuck::cast_slice(&kernels).to_vec();
            self.tables = tables;
        }
        (&self.words, &self.kernels)
    }

    /// Whether every lobe of the material last updated has its table.
    pub fn complete(&self) -> bool {
        self.tables.iter().all(Option::is_some)
    }
}

pub struct CompensationPass {
    pipeline: Pipeline,
}

impl CompensationPass {
    pub fn new(ctx: &Context) -> Result<CompensationPass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("compensation.comp"), "compensation", 128, &[])?;
        Ok(CompensationPass { pipeline })
    }

    /// Adds each lobe's compensation term; `lights`: the map's lights as distant sources over the
    /// residual map's coefficients, on every estimator — the key and wide lights with the map
    /// without both where the cone table holds them all, else the key lights with the map without
    /// them. A bright small light's bands above 2 are much of the map's, and a tilted lobe's kernel
    /// has strong bands above 2 too: through the SH9 of the whole map the term misses a studio lamp
    /// by a third (the quick sweep's `painted-tilted` under `plain`).
    pub fn record(&self, rec: &Recording<'_>, buffers: [&Buffer; 3], lights: bool) -> Result<()> {
        let t = rec.targets;
        let [material, tables, kernels] = buffers;
        let mut push: Push = rec.push;
        let env = rec.env()?;
        let [mut sh, mut table] = diffuse::term(env, [0.0; 3], lights, &mut push);
        let wide = env.keys.as_ref().and_then(|k| k.wide.as_ref()).filter(|_| lights);
        if let Some((w, cones)) = wide.and_then(|w| w.cones.as_ref().map(|c| (w, c))) {
            (sh, table) = (&w.sh, cones);
        }
        let set = rec.set(
            &self.pipeline,
            &[
                Binding::StorageImageRead(&t.normal),
                Binding::StorageImage(&t.accum),
                Binding::StorageRead(sh),
                Binding::StorageRead(table),
                Binding::StorageRead(material),
                Binding::StorageRead(tables),
                Binding::StorageRead(kernels),
                Binding::StorageRead(&t.pixels),
            ],
        )?;
        rec.dispatch_over(&t.pixels, &self.pipeline, set, &push);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ K L dω` as the shader sums it, for `L` given by its SH coefficients `l` (local frame).
    fn shader_integral(kern: &[[f32; 4]; 3], l: &[f64; 9]) -> f64 {
        let k = kern.map(|v| v.map(f64::from));
        let alpha = 0.282095 * l[0];
        let beta = [0.488603 * l[3], 0.488603 * l[1], 0.488603 * l[2]];
        let (g, z) = (0.546274, 0.315392);
        let gxx = g * l[8] - z * l[6];
        let gyy = -g * l[8] - z * l[6];
        let gzz = 2.0 * z * l[6];
        k[0][0] * alpha
            + k[0][1] * beta[0]
            + k[0][2] * beta[1]
            + k[0][3] * beta[2]
            + k[1][0] * gxx
            + k[1][1] * gyy
            + k[1][2] * gzz
            + k[1][3] * g * l[4]
            + k[2][0] * g * l[7]
            + k[2][1] * g * l[5]
    }

    /// The folded constants give `Σ k_i l_i`, the integral of two band-limited functions, for each
    /// basis function and a random mix: to the six digits of the basis constants the shaders share
    /// (`0.488603² · 4π/3 = 1 + 2·10⁻⁶`) and the kernel's `f32` rounding, within 4·10⁻⁶.
    #[test]
    fn the_kernel_integrates_band_limited_light_exactly() {
        let k = [0.9, -0.3, 1.1, 0.25, 0.4, -0.7, 0.5, 0.2, -0.6];
        let kern = kernel(&k);
        for i in 0..9 {
            let mut l = [0.0; 9];
            l[i] = 1.0;
            let got = shader_integral(&kern, &l);
            assert!((got - k[i]).abs() < 4e-6 * (1.0 + k[i].abs()), "basis {i}: {got} against {}", k[i]);
        }
        let l = [0.3, 0.8, -0.2, 0.5, -0.9, 0.1, 0.7, -0.4, 0.6];
        let want: f64 = k.iter().zip(&l).map(|(a, b)| a * b).sum();
        assert!((shader_integral(&kern, &l) - want).abs() < 1e-5);
    }

    /// A table of `Ê = 0` everywhere makes `K = cos⁺θ`, whose projection is known in closed form
    /// (Ramamoorthi & Hanrahan: `√π/2`, `√(π/3)` along z, `√(5π)/8` for `Y_20`, the rest 0); the
    /// midpoint rule on 256² cells is within 2·10⁻³ of it (its error at the disc's rim).
    #[test]
    fn a_zero_table_projects_to_the_cosine_lobe() {
        let t = Table {
            rotation: [1.0, 0.0],
            xs: vec![0.0, 1e6],
            ys: vec![0.0],
            values: vec![-compensation::LOOKUP_MARGIN, -compensation::LOOKUP_MARGIN],
            mean: 0.0,
            scale: 0.0,
            deficit: 1.0,
        };
        let k = kernel_sh(&t);
        let want = [PI.sqrt() / 2.0, 0.0, (PI / 3.0).sqrt(), 0.0, 0.0, 0.0, (5.0 * PI).sqrt() / 8.0, 0.0, 0.0];
        for i in 0..9 {
            assert!((k[i] - want[i]).abs() < 2e-3, "coefficient {i}: {} against {}", k[i], want[i]);
        }
    }

    /// The shaders' and the Mitsuba plug-in's copies of the lookup margin are the model's.
    #[test]
    fn the_shaders_margin_is_the_models() {
        let src = include_str!("../../glsl/include/brdf.glsl");
        let line = src.lines().find(|l| l.contains("const float BRDF_SHOP_LOOKUP_MARGIN")).expect("declared");
        let value: f32 = line.split('=').nth(1).unwrap().trim().trim_end_matches(';').parse().unwrap();
        assert_eq!(value, compensation::LOOKUP_MARGIN);
        let plugin = include_str!("../export/mitsuba_plugin.py");
        let line = plugin.lines().find(|l| l.starts_with("LOOKUP_MARGIN = 2.0 ** -")).expect("declared");
        let exponent: i32 = line.rsplit('-').next().unwrap().trim().parse().unwrap();
        assert_eq!(2f32.powi(-exponent), compensation::LOOKUP_MARGIN);
    }
}
