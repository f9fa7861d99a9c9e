//! The `VkPipelineCache` every pipeline is built through, kept between runs in a file of the user's
//! cache folder (`$XDG_CACHE_HOME/brdf-shop/pipelines.bin`, else `~/.cache/brdf-shop/pipelines.bin`;
//! a relative `XDG_CACHE_HOME` is ignored, [`crate::fsio::user_dir`]), so that a second run (the editor's cold start, a bench) skips the driver's compiles.
//! `BRDF_SHOP_PIPELINE_CACHE=0` turns it off.
//!
//! The file is what `vkGetPipelineCacheData` returns. A file whose header does not name this device
//! (vendor, device id and `pipelineCacheUUID`, which changes with the driver), a damaged or
//! oversized one, one that is not a regular file (a FIFO, device, socket or link: read through
//! [`crate::fsio::read_regular_limited`], which never blocks) or one that cannot be read is ignored without a message: the cache starts empty and
//! the run builds its pipelines as without one. It is written atomically (`fsio::write_atomic`) when
//! the context drops, only when its contents changed. Owns the cache handle; destroyed by
//! `Context`'s drop before the device.

use std::path::{Path, PathBuf};

use ash::vk;

use super::device::Device;
use super::vk_err;
use crate::error::Result;

/// The environment variable that turns the cache off (`0`).
pub const ENV: &str = "BRDF_SHOP_PIPELINE_CACHE";

/// A file larger than this is not loaded (the cache then holds this run's pipelines alone, and the
/// file written at the end replaces it): pipelines of old shader versions are never evicted by the
/// driver, so the file would otherwise grow with every build of the program.
pub const MAX_BYTES: u64 = 64 << 20;

/// `VkPipelineCacheHeaderVersionOne`'s size.
const HEADER_BYTES: usize = 32;

pub struct PipelineCache {
    /// The cache; null when turned off or when its creation failed (pipelines are then built
    /// without one).
    pub raw: vk::PipelineCache,
    path: Option<PathBuf>,
    /// The file's bytes as loaded, when the driver accepted them.
    loaded: Option<Vec<u8>>,
}

/// Where the cache lives: `None` with `BRDF_SHOP_PIPELINE_CACHE=0` or without a cache or home folder.
pub fn default_path() -> Option<PathBuf> {
    if std::env::var_os(ENV).is_some_and(|v| v == "0") {
        return None;
    }
    Some(crate::fsio::user_dir("XDG_CACHE_HOME", ".cache")?.join("brdf-shop").join("pipelines.bin"))
}

/// Whether `bytes` start with a version-one header naming `device`'s vendor, device and cache UUID.
pub fn header_matches(bytes: &[u8], device: &Device) -> bool {
    if bytes.len() < HEADER_BYTES {
        return false;
    }
    let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().expect("4 bytes"));
    let info = &device.info;
    word(0) as usize >= HEADER_BYTES
        && word(1) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
        && word(2) == info.vendor_id
        && word(3) == info.device_id
        && bytes[16..32] == info.pipeline_cache_uuid
}

impl PipelineCache {
    /// The cache of [`default_path`] (none when that is `None`).
    pub fn open_default(device: &Device) -> PipelineCache {
        match default_path() {
            Some(p) => PipelineCache::open(device, &p),
            None => PipelineCache { raw: vk::PipelineCache::null(), path: None, loaded: None },
        }
    }

    /// A cache started from the file at `path` where the file is this device's, else empty; saved
    /// there by [`PipelineCache::save`]. Never fails: a cache that cannot be created is null.
    pub fn open(device: &Device, path: &Path) -> PipelineCache {
        // A cache that is missing, not a regular file (a FIFO is never opened for reading), too
        // large or another device's is ignored: the cache only saves time.
        let bytes = crate::fsio::read_regular_limited(path, MAX_BYTES).ok().filter(|b| header_matches(b, device));
        let mut cache = PipelineCache { raw: vk::PipelineCache::null(), path: Some(path.to_path_buf()), loaded: None };
        if let Some(b) = bytes {
            if let Ok(raw) = create(device, &b) {
                cache.raw = raw;
                cache.loaded = Some(b);
                return cache;
            }
        }
        cache.raw = create(device, &[]).unwrap_or(vk::PipelineCache::null());
        if cache.raw != vk::PipelineCache::null() {
            device.set_name(cache.raw, "pipelines");
        }
        cache
    }

    /// Whether the file was read and accepted by the driver.
    pub fn accepted(&self) -> bool {
        self.loaded.is_some()
    }

    /// The file the cache is saved to.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Writes the cache's data to its file (creating its folder) when it differs from what was
    /// loaded. Pipelines built on other threads must have finished.
    pub fn save(&self, device: &Device) -> Result<()> {
        let Some(path) = &self.path else { return Ok(()) };
        if self.raw == vk::PipelineCache::null() {
            return Ok(());
        }
        // SAFETY: the cache is live; no pipeline is being built with it (the caller's promise).
        let data = unsafe { device.raw.get_pipeline_cache_data(self.raw) }.map_err(vk_err("vkGetPipelineCacheData"))?;
        if data.is_empty() || self.loaded.as_deref() == Some(&data[..]) || data.len() as u64 > MAX_BYTES {
            return Ok(());
        }
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| crate::Error::io(dir, e))?;
        }
        crate::fsio::write_atomic(path, &data)
    }

    /// Saves (a failure is ignored: the cache only saves time) and destroys the cache.
    ///
    /// # Safety
    /// No pipeline is being built with the cache, and none will be.
    pub unsafe fn destroy(self, device: &Device) {
        let _ = self.save(device);
        if self.raw != vk::PipelineCache::null() {
            // SAFETY: the caller's promise: nothing uses the cache any more.
            unsafe { device.raw.destroy_pipeline_cache(self.raw, None) };
        }
    }
}

fn create(device: &Device, data: &[u8]) -> Result<vk::PipelineCache> {
    let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
    // SAFETY: the device is live; `info` and `data` outlive the call; the cache is destroyed in
    // `PipelineCache::destroy`.
    unsafe { device.raw.create_pipeline_cache(&info, None) }.map_err(vk_err("vkCreatePipelineCache"))
}
