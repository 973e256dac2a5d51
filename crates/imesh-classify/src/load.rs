//! Image loading with limits.

use std::path::Path;

use image::{DynamicImage, ImageReader, Limits};

use crate::ClassifyError;

/// Default pixel limit: 2^28 (a 16384 × 16384 image).
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 28;

/// Loads any image the `image` crate decodes (PNG, JPEG, TIFF, BMP, PNM; 8 or 16 bits; grey,
/// grey + alpha, RGB, RGBA), refusing images over `max_pixels` before decoding them.
///
/// # Errors
/// [`ClassifyError::Io`] (missing file), [`ClassifyError::Decode`] (not an image, truncated),
/// [`ClassifyError::EmptyImage`], [`ClassifyError::TooLarge`].
///
/// ```no_run
/// let img = imesh_classify::load_image("fixtures/images/skimage-camera.png".as_ref(), imesh_classify::DEFAULT_MAX_PIXELS)?;
/// # Ok::<(), imesh_classify::ClassifyError>(())
/// ```
pub fn load_image(path: &Path, max_pixels: u64) -> Result<DynamicImage, ClassifyError> {
    let io = |source| ClassifyError::Io {
        path: path.to_path_buf(),
        source,
    };
    let decode = |e: image::ImageError| ClassifyError::Decode {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let (width, height) = ImageReader::open(path)
        .map_err(io)?
        .with_guessed_format()
        .map_err(io)?
        .into_dimensions()
        .map_err(decode)?;
    check_size(path, width, height, max_pixels)?;
    let mut reader = ImageReader::open(path)
        .map_err(io)?
        .with_guessed_format()
        .map_err(io)?;
    let mut limits = Limits::default();
    // 16 bytes per pixel covers RGBA at 32-bit float, the widest layout decoded here.
    limits.max_alloc = Some(max_pixels.saturating_mul(16).max(1 << 20));
    reader.limits(limits);
    let image = reader.decode().map_err(decode)?;
    check_size(path, image.width(), image.height(), max_pixels)?;
    Ok(image)
}

fn check_size(path: &Path, width: u32, height: u32, max_pixels: u64) -> Result<(), ClassifyError> {
    let pixels = u64::from(width) * u64::from(height);
    if pixels == 0 {
        return Err(ClassifyError::EmptyImage {
            path: path.to_path_buf(),
            width,
            height,
        });
    }
    if pixels > max_pixels {
        return Err(ClassifyError::TooLarge {
            width,
            height,
            pixels,
            limit: max_pixels,
        });
    }
    Ok(())
}
