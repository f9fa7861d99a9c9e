//! SPIR-V shader modules. The GLSL in `glsl/` is compiled by `build.rs` into `OUT_DIR`; [`spirv!`]
//! embeds one file and [`module`] loads it.

use ash::vk;

use super::{vk_err, Context};
use crate::error::{Error, Result};

/// The SPIR-V `build.rs` compiled from `glsl/<name>`.
#[macro_export]
macro_rules! spirv {
    ($name:literal) => {
        include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv"))
    };
}

pub fn module(ctx: &Context, spv: &[u8], name: &str) -> Result<vk::ShaderModule> {
    let m = module_on(ctx.raw(), spv, name)?;
    ctx.device.set_name(m, name);
    Ok(m)
}

/// [`module`] through a device handle alone (a pipeline built on another thread), unnamed.
pub fn module_on(raw: &ash::Device, spv: &[u8], name: &str) -> Result<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spv))
        .map_err(|e| Error::input(name, format!("embedded SPIR-V is malformed: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: `words` is SPIR-V produced by shaderc; the module is destroyed by its owner.
    unsafe { raw.create_shader_module(&info, None) }.map_err(vk_err("vkCreateShaderModule"))
}
