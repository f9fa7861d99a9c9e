//! The Vulkan foundation on whatever device this machine has (lavapipe in CI), with the validation
//! layer on. No device is a failure, never a skip.

use brdf_shop::vk::{device, Context, Instance};
use brdf_shop::Error;

#[test]
fn context_comes_up_clean_with_validation() {
    let ctx = Context::new(true, None)
        .expect("a Vulkan 1.3 device with the validation layer (tools/setup installs lavapipe)");
    assert!(!ctx.device.name.is_empty());
    assert!(ctx.device.timestamp_period > 0.0);
    let errors = ctx.validation_errors();
    assert!(errors.is_empty(), "validation errors: {errors:?}");
}

#[test]
fn best_device_first_and_filter_by_name() {
    let instance = Instance::new(true).expect("instance");
    let all = device::candidates(&instance).expect("devices");
    assert!(!all.is_empty(), "no Vulkan 1.3 device: run tools/setup");
    drop(instance);
    // Choosing by a part of its name, in any case, picks that device.
    let name = all.last().unwrap().name.clone();
    let ctx = Context::new(true, Some(&name.to_uppercase())).expect("device by name");
    assert_eq!(ctx.device.name, name);
    assert!(ctx.validation_errors().is_empty());
    // A name that matches nothing is a clear device error that lists what exists.
    match Context::new(true, Some("no such gpu 12345")) {
        Err(Error::NoDevice(msg)) => assert!(msg.contains("no such gpu 12345") && msg.contains(&name), "{msg}"),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("a device that does not exist was found"),
    }
}

#[test]
fn devices_command_lists_the_chosen_device() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_brdf-shop")).arg("devices").output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.lines().any(|l| l.starts_with('*')) && text.contains("using:"), "{text}");
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_brdf-shop"))
        .arg("devices")
        .env("BRDF_SHOP_DEVICE", "no such gpu 12345")
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&bad.stderr).lines().count(), 1);
}

/// The canary: a deliberately invalid call (a buffer of size 0) must reach the error list, or the
/// clean results above would prove nothing.
#[test]
fn validation_errors_are_caught() {
    use ash::vk;
    let ctx = Context::new(true, None).expect("device");
    let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    // SAFETY: deliberately invalid for the validation layer to report; the driver accepts a zero-size
    // buffer, which is destroyed right away.
    if let Ok(buffer) = unsafe { ctx.device.raw.create_buffer(&info, None) } {
        unsafe { ctx.device.raw.destroy_buffer(buffer, None) };
    }
    let errors = ctx.validation_errors();
    assert!(errors.iter().any(|e| e.contains("VUID-VkBufferCreateInfo-size")), "{errors:?}");
    // Reported with the layer's label and the validation exit status.
    let e = ctx.check_validation().expect_err("the layer's error fails the check");
    assert!(matches!(e, Error::Validation(_)) && e.to_string().starts_with("Vulkan validation: "), "{e}");
    assert_eq!(e.exit_status(), brdf_shop::error::EXIT_VALIDATION);
}

/// The pipeline cache: a pipeline built through it is saved to its file with this device's header;
/// a second context reads the file and the driver accepts it; a damaged or foreign file is ignored
/// (the cache starts empty, pipelines still build, and the file is written afresh). The command line
/// writes the cache under `XDG_CACHE_HOME`, and `BRDF_SHOP_PIPELINE_CACHE=0` writes none.
#[test]
fn the_pipeline_cache_is_saved_and_read_back() {
    use brdf_shop::vk::pipeline_cache::{header_matches, PipelineCache};
    let dir = tempfile::TempDir::new().unwrap();
    let path = dir.path().join("sub").join("pipelines.bin");
    // A context whose cache is the file at `path`, a pipeline built through it, the cache saved.
    let run = |want_accepted: bool| {
        let mut ctx = Context::new(true, None).expect("a Vulkan device");
        let cache = PipelineCache::open(&ctx.device, &path);
        assert_eq!(cache.accepted(), want_accepted, "{}", path.display());
        let old = std::mem::replace(&mut *ctx.pipeline_cache, cache);
        // SAFETY: nothing was built with the replaced cache.
        unsafe { old.destroy(&ctx.device) };
        let pass = brdf_shop::render::peak::PeakPass::new(&ctx).expect("a pipeline through the cache");
        pass.destroy(&ctx);
        ctx.pipeline_cache.save(&ctx.device).expect("saved");
        let bytes = std::fs::read(&path).expect("the cache file is written");
        assert!(header_matches(&bytes, &ctx.device), "{} bytes", bytes.len());
        assert!(ctx.validation_errors().is_empty(), "{:?}", ctx.validation_errors());
    };
    run(false);
    run(true);
    // Damaged: not this device's header. Foreign: another pipelineCacheUUID.
    std::fs::write(&path, b"not a pipeline cache at all, but long enough for a header").unwrap();
    run(false);
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[20] ^= 0xff;
    std::fs::write(&path, &bytes).unwrap();
    run(false);
    // Through the binary: the user's cache folder, and none when turned off.
    for (off, want) in [(true, false), (false, true)] {
        let home = tempfile::TempDir::new().unwrap();
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_brdf-shop"));
        cmd.args(["render", "--view", "canvas", "--size", "16x16", "--out"])
            .arg(home.path().join("c.png"))
            .env("XDG_CACHE_HOME", home.path());
        if off {
            cmd.env("BRDF_SHOP_PIPELINE_CACHE", "0");
        } else {
            cmd.env_remove("BRDF_SHOP_PIPELINE_CACHE");
        }
        let out = cmd.output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(home.path().join("brdf-shop/pipelines.bin").is_file(), want, "turned off: {off}");
    }
}
