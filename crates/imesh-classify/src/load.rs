//! Image loading with limits.

use std::io::Cursor;
use std::path::Path;

use image::metadata::Orientation;
use image::{DynamicImage, ImageDecoder, ImageFormat, ImageReader, Limits};

use crate::grey_tiff::{decode_grey_tiff, is_tiff};
use crate::ClassifyError;

/// Default pixel limit: 2^28 (a 16384 × 16384 image).
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 28;

/// Loads any image the `image` crate decodes (PNG, JPEG, TIFF, BMP, PNM; 8 or 16 bits; grey,
/// grey + alpha, RGB, RGBA), and grey TIFFs of any sample type (signed, 32- or 64-bit integers,
/// floating point: brought to 16-bit grey, whole values from 0 to 65 535 kept as they are,
/// others stretched over the 16 bits in their order), turned as its EXIF or TIFF orientation
/// says (a photograph as it is shown), refusing images over `max_pixels` before decoding them.
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
    let bytes = std::fs::read(path).map_err(|source| ClassifyError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode(&bytes, path, max_pixels)
}

/// Decodes an image held in memory, as [`load_image`] does a file (the format is guessed from
/// the bytes); errors name the image `<memory>`.
///
/// # Errors
/// [`ClassifyError::Decode`], [`ClassifyError::EmptyImage`], [`ClassifyError::TooLarge`].
///
/// ```
/// let mut png = Vec::new();
/// image::GrayImage::new(3, 2)
///     .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
///     .unwrap();
/// let image = imesh_classify::decode_image(&png, 100)?;
/// assert_eq!((image.width(), image.height()), (3, 2));
/// assert!(imesh_classify::decode_image(&png, 5).is_err()); // 6 pixels > 5
/// assert!(imesh_classify::decode_image(b"not an image", 100).is_err());
/// # Ok::<(), imesh_classify::ClassifyError>(())
/// ```
pub fn decode_image(bytes: &[u8], max_pixels: u64) -> Result<DynamicImage, ClassifyError> {
    decode(bytes, Path::new("<memory>"), max_pixels)
}

/// Whether the file at `path` was stored with a lossy codec: JPEG, WebP with a lossy (VP8)
/// bitstream, or AVIF. False for anything else, and when the file cannot be read.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// let (jpeg, webp) = (dir.path().join("a.jpg"), dir.path().join("b.webp"));
/// std::fs::write(&jpeg, [0xff, 0xd8, 0xff, 0xe0])?;
/// std::fs::write(&webp, b"RIFF\x1a\0\0\0WEBPVP8L")?;
/// assert!(imesh_classify::is_lossy_file(&jpeg));
/// assert!(!imesh_classify::is_lossy_file(&webp)); // VP8L: lossless
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn is_lossy_file(path: &Path) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = Vec::with_capacity(16);
    if (&mut file).take(16).read_to_end(&mut head).is_err() {
        return false;
    }
    if head.starts_with(&[0xff, 0xd8, 0xff]) {
        return true;
    }
    // Shorter than any WebP or AVIF header.
    if head.len() < 16 {
        return false;
    }
    if &head[4..8] == b"ftyp" {
        return matches!(&head[8..12], b"avif" | b"avis");
    }
    if &head[..4] != b"RIFF" || &head[8..12] != b"WEBP" {
        return false;
    }
    // The chunks after "WEBP": a lossy image has a "VP8 " one (after "VP8X" and others in the
    // extended format), a lossless one "VP8L".
    let mut at = 12u64;
    for _ in 0..16 {
        let mut chunk = [0u8; 8];
        if file.seek(SeekFrom::Start(at)).is_err() || file.read_exact(&mut chunk).is_err() {
            return false;
        }
        match &chunk[..4] {
            b"VP8 " => return true,
            b"VP8L" => return false,
            _ => {}
        }
        let size = u64::from(u32::from_le_bytes([chunk[4], chunk[5], chunk[6], chunk[7]]));
        // Chunks are padded to an even size.
        at += 8 + size + (size & 1);
    }
    false
}

/// Reads the header first, so that an image over the limit is refused before any pixel is
/// decoded, then decodes with an allocation limit in case the header lied.
fn decode(bytes: &[u8], path: &Path, max_pixels: u64) -> Result<DynamicImage, ClassifyError> {
    let io = |source| ClassifyError::Io {
        path: path.to_path_buf(),
        source,
    };
    let decode = |e: image::ImageError| ClassifyError::Decode {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    // The bytes name the format; the file's extension only when they do not (e.g. TGA).
    let reader = || {
        ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map(|mut r| {
                if r.format().is_none() {
                    if let Ok(format) = ImageFormat::from_path(path) {
                        r.set_format(format);
                    }
                }
                r
            })
    };
    let with_image = || {
        let (width, height) = reader().map_err(io)?.into_dimensions().map_err(decode)?;
        check_size(path, width, height, max_pixels)?;
        let mut reader = reader().map_err(io)?;
        let mut limits = Limits::default();
        // 16 bytes per pixel covers RGBA at 32-bit float, the widest layout decoded here.
        limits.max_alloc = Some(max_pixels.saturating_mul(16).max(1 << 20));
        reader.limits(limits.clone());
        let mut decoder = reader.into_decoder().map_err(decode)?;
        limits.reserve(decoder.total_bytes()).map_err(decode)?;
        // A camera records how it was held (EXIF orientation) rather than turning the pixels:
        // the regions are meshed as the image is shown. A broken tag leaves it as stored.
        let orientation = decoder.orientation().unwrap_or(Orientation::NoTransforms);
        let mut image = DynamicImage::from_decoder(decoder).map_err(decode)?;
        image.apply_orientation(orientation);
        Ok(image)
    };
    let image = match with_image() {
        // The grey TIFFs the `image` crate leaves out (signed, 32- or 64-bit, floating point).
        Err(e @ ClassifyError::Decode { .. }) if is_tiff(bytes) => {
            decode_grey_tiff(bytes, path, max_pixels).unwrap_or(Err(e))?
        }
        other => other?,
    };
    check_size(path, image.width(), image.height(), max_pixels)?;
    Ok(image)
}

pub(crate) fn check_size(
    path: &Path,
    width: u32,
    height: u32,
    max_pixels: u64,
) -> Result<(), ClassifyError> {
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
