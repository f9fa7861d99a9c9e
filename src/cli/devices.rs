//! `brdf-shop devices`: the Vulkan devices the renderer can use, best first, and which one it picks
//! (`BRDF_SHOP_DEVICE` overrides by name). Exit 2 with a how-to when there is none.

use brdf_shop::vk::{device, Context, DEVICE_ENV};

pub fn run() -> anyhow::Result<()> {
    let filter = std::env::var(DEVICE_ENV).ok();
    let ctx = Context::new(false, filter.as_deref())?;
    for c in device::candidates(&ctx.instance)? {
        let mark = if c.name == ctx.device.name { "*" } else { " " };
        println!("{mark} {} ({:?})", c.name, c.kind);
    }
    println!("using: {} (override with {DEVICE_ENV}=NAME)", ctx.device.name);
    Ok(())
}
