//! The CPU references the error-vs-time report measures against, cached in the report's folder
//! (`cache/ref-KEY.bin`, KEY a hash of the material, map, mesh, camera, size and samples) so that a
//! second run reads them instead of computing them again. A cache file is read through
//! [`crate::fsio::read_regular_limited`] with its exact expected size as the limit: a FIFO is never
//! opened, a huge or sparse file never read, and an entry that is not what this scene's reference
//! takes (the wrong size, values that are not finite) is computed again with a note.

use std::path::Path;

use crate::brdf::Material;
use crate::error::{Error, Result};
use crate::fsio::write_atomic;
use crate::reference::{self, Image};
use crate::render::environment;
use crate::scene::{Camera, Environment, Mesh};

fn fnv(h: &mut u64, bytes: &[u8]) {
    for b in bytes {
        *h = (*h ^ *b as u64).wrapping_mul(0x100000001b3);
    }
}

/// The cache key of a reference image.
pub fn reference_key(m: &Material, env: &Environment, mesh: &Mesh, camera: &Camera, size: u32, spp: u32) -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    fnv(&mut h, b"brdf-shop reference v1");
    fnv(&mut h, m.to_json().as_bytes());
    fnv(&mut h, format!("{:?}", environment::key(env)).as_bytes());
    fnv(
        &mut h,
        format!("{} {} {} {:?} {size} {spp}", mesh.name, mesh.positions.len(), mesh.indices.len(), camera).as_bytes(),
    );
    format!("{h:016x}")
}

const MAGIC: &[u8; 8] = b"BRDFREF1";

fn save_image(path: &Path, im: &Image) -> Result<()> {
    let mut bytes = MAGIC.to_vec();
    bytes.extend_from_slice(&im.width.to_le_bytes());
    bytes.extend_from_slice(&im.height.to_le_bytes());
    for p in &im.pixels {
        for v in p {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    write_atomic(path, &bytes)
}

/// The bytes of a cached reference of `size`² pixels: the magic, width, height, then RGBA `f32`s.
fn cache_bytes(size: u32) -> u64 {
    MAGIC.len() as u64 + 8 + size as u64 * size as u64 * 16
}

/// Why a cache entry is not used.
enum Stale {
    /// No file at its name: computed without a note.
    Missing,
    /// Something else: computed again, with a note saying why.
    Unusable(String),
}

/// The cached reference at `path` when it is a regular file of exactly the size a `size`² image
/// takes (checked before anything is read: a huge or sparse file is never read), with the magic,
/// this size in its header and finite values throughout.
fn load_image(path: &Path, size: u32) -> std::result::Result<Image, Stale> {
    let bytes = match crate::fsio::read_regular_limited(path, cache_bytes(size)) {
        Ok(b) => b,
        Err(crate::fsio::Unreadable::Missing) => return Err(Stale::Missing),
        Err(e) => return Err(Stale::Unusable(e.to_string())),
    };
    let bad = |why: &str| Stale::Unusable(why.to_string());
    if bytes.len() as u64 != cache_bytes(size) || &bytes[..8] != MAGIC {
        return Err(bad("not a cached reference of this size"));
    }
    let word = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    if (word(8), word(12)) != (size, size) {
        return Err(bad("not a cached reference of this size"));
    }
    let f: Vec<f32> = bytes[16..].chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    if f.iter().any(|v| !v.is_finite()) {
        return Err(bad("it holds values that are not finite"));
    }
    Ok(Image { width: size, height: size, pixels: f.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect() })
}

/// The reference for a scene, from the cache in `cache` or computed (and cached). A cache entry
/// that is a folder, FIFO, device or socket is refused before anything is computed (it could not be
/// replaced: [`write_atomic`] replaces regular files only); one that is there but not usable (a
/// link, the wrong size, not finite) is computed again and replaced, with a note on stderr naming it.
pub fn cached_reference(
    cache: &Path,
    m: &Material,
    env: &Environment,
    mesh: &Mesh,
    camera: &Camera,
    size: u32,
    spp: u32,
) -> Result<Image> {
    let path = cache.join(format!("ref-{}.bin", reference_key(m, env, mesh, camera, size, spp)));
    if let Ok(meta) = std::fs::symlink_metadata(&path) {
        if !meta.file_type().is_file() && !meta.file_type().is_symlink() {
            return Err(Error::input(
                crate::fsio::show(&path),
                "is not a regular file (a folder, FIFO, device or socket); the reference cache holds regular files only",
            ));
        }
    }
    match load_image(&path, size) {
        Ok(im) => return Ok(im),
        Err(Stale::Missing) => {}
        Err(Stale::Unusable(why)) => {
            eprintln!("brdf-shop: note: the cached reference {} is computed again: {why}", crate::fsio::show(&path))
        }
    }
    let im = reference::render_mesh(m, env, mesh, camera, size, size, spp, false);
    std::fs::create_dir_all(cache).map_err(|e| Error::io(cache, e))?;
    save_image(&path, &im)?;
    Ok(im)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One entry of a scene small enough to compute in a unit test: (folder, material, map, mesh,
    /// camera, size, samples).
    fn scene() -> (tempfile::TempDir, Material, Environment, Mesh, Camera) {
        let m = crate::measure::report_materials().remove(0).1;
        (tempfile::tempdir().unwrap(), m, Environment::constant([1.0, 0.5, 0.25]), Mesh::sphere(), Camera::default())
    }

    /// A second call reads the entry back (a marker image written at its name is what it returns);
    /// an entry that is not finite, of another size, a link or larger than the size takes is
    /// computed again and replaced; a FIFO is refused by its name without being opened.
    #[test]
    fn entries_are_read_back_and_unusable_ones_computed_again() {
        let (dir, m, env, mesh, cam) = scene();
        let (size, spp) = (8, 4);
        let get = || cached_reference(dir.path(), &m, &env, &mesh, &cam, size, spp);
        let first = get().expect("computed");
        let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().path()).collect();
        assert_eq!(entries.len(), 1, "{entries:?}");
        let path = &entries[0];
        let image =
            |v: f32, side: u32| Image { width: side, height: side, pixels: vec![[v; 4]; (side * side) as usize] };
        let marker = image(0.125, size);
        save_image(path, &marker).unwrap();
        assert_eq!(get().unwrap(), marker, "the cached entry is read back");
        // The reference is deterministic: an entry computed again equals the first.
        let recomputed = |what: &str| {
            assert_eq!(get().unwrap(), first, "{what}: computed again");
            assert_eq!(load_image(path, size).ok(), Some(first.clone()), "{what}: the entry is replaced");
        };
        save_image(path, &image(f32::NAN, size)).unwrap();
        recomputed("NaN");
        save_image(path, &image(f32::INFINITY, size)).unwrap();
        recomputed("infinite");
        save_image(path, &image(0.125, size + 1)).unwrap();
        recomputed("another size");
        let f = std::fs::File::create(path).unwrap();
        f.set_len(1 << 40).unwrap();
        drop(f);
        recomputed("a sparse file of 1 TiB");
        let elsewhere = dir.path().join("elsewhere.bin");
        save_image(&elsewhere, &marker).unwrap();
        std::fs::remove_file(path).unwrap();
        std::os::unix::fs::symlink(&elsewhere, path).unwrap();
        recomputed("a link");
        assert_eq!(load_image(&elsewhere, size).ok(), Some(marker), "the link's target is left as it was");
        std::fs::remove_file(path).unwrap();
        let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
        // SAFETY: `c` is a NUL-terminated path that outlives the call.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = get().expect_err("a FIFO is refused").to_string();
        assert!(e.contains(&crate::fsio::show(path)) && e.contains("not a regular file"), "{e}");
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::symlink_metadata(path).unwrap().file_type().is_fifo(), "the FIFO is left as it was");
    }
}
