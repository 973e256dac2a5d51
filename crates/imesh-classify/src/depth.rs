//! Images deeper than 8 bits, as the 8-bit classifiers see them.

use std::borrow::Cow;

use image::{DynamicImage, GrayImage, RgbImage};
use rayon::prelude::*;

/// `image` with 8 bits a channel, as the luminance thresholds, Otsu, k-means and the texture
/// classifier read it. An 8-bit image is itself. A deeper one has its colour channels
/// stretched together from their lowest to their highest value over 0–255, its alpha left out
/// (none of them reads it): a micrograph whose 12 bits fill a 16-bit file from 900 to 1 200
/// would otherwise fall on 2 of the 256 levels, and Otsu would split its noise; a linear
/// stretch changes no Otsu or k-means partition that 8 bits resolve.
///
/// ```
/// use image::{DynamicImage, ImageBuffer, Luma};
/// let deep: ImageBuffer<Luma<u16>, Vec<u16>> =
///     ImageBuffer::from_fn(3, 1, |x, _| Luma([[900, 1000, 1200][x as usize]]));
/// let deep = DynamicImage::ImageLuma16(deep);
/// assert_eq!(imesh_classify::eight_bit(&deep).to_luma8().as_raw(), &[0, 85, 255]);
/// ```
pub fn eight_bit(image: &DynamicImage) -> Cow<'_, DynamicImage> {
    let (w, h) = (image.width(), image.height());
    let grey = |data| DynamicImage::ImageLuma8(GrayImage::from_raw(w, h, data).expect(ONE_EACH));
    let colour = |data| DynamicImage::ImageRgb8(RgbImage::from_raw(w, h, data).expect(ONE_EACH));
    Cow::Owned(match image {
        DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_) => return Cow::Borrowed(image),
        DynamicImage::ImageLuma16(p) => grey(stretched(p.as_raw(), 1, 1, f32::from)),
        DynamicImage::ImageLumaA16(p) => grey(stretched(p.as_raw(), 2, 1, f32::from)),
        DynamicImage::ImageRgb16(p) => colour(stretched(p.as_raw(), 3, 3, f32::from)),
        DynamicImage::ImageRgba16(p) => colour(stretched(p.as_raw(), 4, 3, f32::from)),
        // Floating point, and any layout `image` adds.
        _ => colour(stretched(image.to_rgb32f().as_raw(), 3, 3, |v| v)),
    })
}

/// What building an 8-bit image from [`stretched`] samples cannot fail on.
const ONE_EACH: &str = "one 8-bit sample for every colour sample";

/// The first `colour` samples of every pixel of `raw` (pixels of `channels` samples) at 8 bits,
/// stretched together over 0–255 from their lowest finite value to their highest
/// (not-a-number samples 0).
fn stretched<T: Copy + Sync>(
    raw: &[T],
    channels: usize,
    colour: usize,
    value: impl Fn(T) -> f32 + Sync,
) -> Vec<u8> {
    let value = &value;
    let samples = || {
        raw.par_chunks_exact(channels)
            .flat_map_iter(move |p| p[..colour].iter().map(move |&v| value(v)))
    };
    let (lo, hi) = finite_range(samples().map(f64::from));
    let (lo, hi) = (lo as f32, hi as f32);
    let scale = if hi > lo { 255.0 / (hi - lo) } else { 0.0 };
    // NaN casts to 0, and out-of-range values saturate.
    samples()
        .map(|v| ((v - lo) * scale).round() as u8)
        .collect()
}

/// The lowest and highest finite values (∞ and −∞ when there are none).
pub(crate) fn finite_range(values: impl ParallelIterator<Item = f64>) -> (f64, f64) {
    values
        .filter(|v| v.is_finite())
        .fold(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |(lo, hi), v| (lo.min(v), hi.max(v)),
        )
        .reduce(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        )
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{ImageBuffer, Luma, LumaA, Rgb};

    #[test]
    fn an_eight_bit_image_is_itself() {
        let img = DynamicImage::ImageLuma8(GrayImage::from_fn(4, 4, |x, _| Luma([x as u8 * 3])));
        assert!(matches!(eight_bit(&img), Cow::Borrowed(_)));
    }

    #[test]
    fn deep_grey_is_stretched_and_its_alpha_left_out() {
        let img: ImageBuffer<LumaA<u16>, Vec<u16>> =
            ImageBuffer::from_fn(2, 1, |x, _| LumaA([[4000, 4100][x as usize], 65535]));
        let img = DynamicImage::ImageLumaA16(img);
        let e = eight_bit(&img);
        assert!(matches!(*e, DynamicImage::ImageLuma8(_)));
        assert_eq!(e.to_luma8().as_raw(), &[0, 255]);
        // One value: level 0.
        let flat: ImageBuffer<Luma<u16>, Vec<u16>> = ImageBuffer::from_pixel(2, 2, Luma([300]));
        let e = eight_bit(&DynamicImage::ImageLuma16(flat)).to_luma8();
        assert!(e.as_raw().iter().all(|&v| v == 0));
    }

    #[test]
    fn deep_colour_is_stretched_over_all_its_channels_together() {
        let img: ImageBuffer<Rgb<f32>, Vec<f32>> = ImageBuffer::from_fn(2, 1, |x, _| {
            Rgb([[2.0, 0.0, 4.0], [f32::NAN, 1.0, 3.0]][x as usize])
        });
        let e = eight_bit(&DynamicImage::ImageRgb32F(img)).to_rgb8();
        assert_eq!(e.as_raw(), &[128, 0, 255, 0, 64, 191]);
    }
}
