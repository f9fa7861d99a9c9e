//! Image output (docs/model.md, Frames and conventions): EXR is the linear RGBA estimate, unclamped (alpha = coverage);
//! PNG is the linear image times `exposure`, then the sRGB curve, clamped — for looking at, never for measuring.
//! Both are written atomically: a failure leaves no half-written file.

use std::path::Path;

use exr::prelude::{Encoding, Layer, LayerAttributes, SpecificChannels, WritableImage};

use crate::error::{Error, Result};
use crate::fsio::write_atomic;

/// Linear radiance → 8-bit sRGB: exposure, the sRGB transfer curve, clamped; NaN → 0.
pub fn srgb8(v: f64, exposure: f64) -> u8 {
    let x = (v * exposure).clamp(0.0, 1.0);
    let x = if x.is_nan() { 0.0 } else { x };
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Radiance that overflowed `f32` (±Inf) becomes `±f32::MAX`, the largest finite value, and NaN
/// becomes 0; the number of channel values changed is returned for the command to report. An output
/// file never holds a non-finite value.
pub fn clamp_to_finite(pixels: &mut [[f32; 4]]) -> usize {
    let mut changed = 0;
    for p in pixels.iter_mut() {
        for v in p.iter_mut() {
            if !v.is_finite() {
                *v = if v.is_nan() { 0.0 } else { f32::MAX.copysign(*v) };
                changed += 1;
            }
        }
    }
    changed
}

/// Writes `.exr` (linear float RGBA) or `.png` (exposure + sRGB) by the path's extension.
pub fn write(path: &Path, width: u32, height: u32, pixels: &[[f32; 4]], exposure: f64) -> Result<()> {
    write_atomic(path, &encode(path, width, height, pixels, exposure)?)
}

/// The bytes [`write`] writes, to be written later with other outputs
/// ([`crate::fsio::write_all_atomic`]). Non-finite values are clamped as [`clamp_to_finite`] says.
pub fn encode(path: &Path, width: u32, height: u32, pixels: &[[f32; 4]], exposure: f64) -> Result<Vec<u8>> {
    encode_view(path, width, height, pixels, exposure, exposure)
}

/// Scales the backdrop of a mesh view (the pixels off the object, alpha < ½) by `brightness`: the
/// image then holds the map's radiance times it there, as `encode_view` expects.
pub fn scale_backdrop(pixels: &mut [[f32; 4]], brightness: f64) {
    for p in pixels.iter_mut().filter(|p| p[3] < 0.5) {
        for c in &mut p[..3] {
            *c = (*c as f64 * brightness) as f32;
        }
    }
}

/// [`encode`] of a mesh view whose backdrop has its own brightness: a PNG scales the object's
/// pixels (alpha ≥ ½) by `exposure` and the backdrop's (alpha < ½) by `backdrop_exposure`.
pub fn encode_view(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f32; 4]],
    exposure: f64,
    backdrop_exposure: f64,
) -> Result<Vec<u8>> {
    let origin = crate::fsio::show(path);
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = match ext.as_deref() {
        Some("exr") => {
            exr_bytes(width, height, pixels).map_err(|e| Error::input(&origin, format!("cannot encode EXR: {e}")))?
        }
        Some("png") => png_bytes(width, height, pixels, (exposure, backdrop_exposure))
            .map_err(|e| Error::input(&origin, format!("cannot encode PNG: {e}")))?,
        _ => return Err(Error::input(origin, "the output must end in .exr or .png")),
    };
    Ok(bytes)
}

/// Whether `path` names an output format this module writes.
pub fn check_output_path(path: &Path) -> Result<()> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("exr") | Some("png") => Ok(()),
        _ => Err(Error::input(path.display().to_string(), "the output must end in .exr or .png")),
    }
}

fn exr_bytes(width: u32, height: u32, pixels: &[[f32; 4]]) -> std::result::Result<Vec<u8>, exr::error::Error> {
    let w = width as usize;
    let channels = SpecificChannels::rgba(|pos: exr::math::Vec2<usize>| {
        let p = pixels[pos.y() * w + pos.x()];
        let f = |v: f32| if v.is_nan() { 0.0 } else { v.clamp(-f32::MAX, f32::MAX) };
        (f(p[0]), f(p[1]), f(p[2]), f(p[3]))
    });
    let layer =
        Layer::new((w, height as usize), LayerAttributes::named("brdf-shop"), Encoding::FAST_LOSSLESS, channels);
    let image = exr::image::Image::from_layer(layer);
    let mut cursor = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut cursor)?;
    Ok(cursor.into_inner())
}

fn png_bytes(
    width: u32,
    height: u32,
    pixels: &[[f32; 4]],
    (object, backdrop): (f64, f64),
) -> image::ImageResult<Vec<u8>> {
    use image::ImageEncoder;
    let rgb: Vec<u8> = pixels
        .iter()
        .flat_map(|p| {
            let exposure = if p[3] >= 0.5 { object } else { backdrop };
            [p[0], p[1], p[2]].map(|v| srgb8(v as f64, exposure))
        })
        .collect();
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png).write_image(&rgb, width, height, image::ExtendedColorType::Rgb8)?;
    Ok(png)
}

/// Writes 8-bit RGBA pixels (already display-encoded) as PNG, atomically (the editor's screenshot).
pub fn write_rgba8_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    use image::ImageEncoder;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgba, width, height, image::ExtendedColorType::Rgba8)
        .map_err(|e| Error::input(path.display().to_string(), format!("cannot encode PNG: {e}")))?;
    write_atomic(path, &png)
}

/// Refuses (naming `--size` or `--spp`) an image of an empty side or more than `max_pixels`
/// pixels (`shape`, e.g. "4096x4096", and `what` say which limit in the message), or a sample count
/// of 0 or over `max_spp` — before anything is allocated. `render` and `reference` each call it
/// with their own limits.
pub fn check_image_limits(
    (width, height, spp): (u32, u32, u32),
    (max_pixels, max_spp): (u64, u32),
    shape: &str,
    what: &str,
) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::input("--size", format!("{width}x{height} is empty; both sides must be at least 1")));
    }
    if width as u64 * height as u64 > max_pixels {
        return Err(Error::input(
            "--size",
            format!("{width}x{height} is more than the limit of {max_pixels} pixels ({shape}) for {what}"),
        ));
    }
    if spp == 0 {
        return Err(Error::input("--spp", "must be at least 1"));
    }
    if spp > max_spp {
        return Err(Error::input("--spp", format!("{spp} is more than the limit of {max_spp} samples per pixel")));
    }
    Ok(())
}
