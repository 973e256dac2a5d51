//! An 8-bit colour image's distinct colours, each packed into one integer (`0xRRGGBB`), with
//! the number of pixels that have each.

use image::RgbImage;
use rayon::prelude::*;

/// Every pixel's colour packed as `0xRRGGBB`, in pixel order.
pub(crate) fn packed(rgb: &RgbImage) -> Vec<u32> {
    rgb.as_raw()
        .par_chunks_exact(3)
        .map(|p| (u32::from(p[0]) << 16) | (u32::from(p[1]) << 8) | u32::from(p[2]))
        .collect()
}

/// The distinct colours of `keys` ([`packed`]) in increasing order, each with its pixel count.
pub(crate) fn distinct(keys: &[u32]) -> Vec<(u32, usize)> {
    let mut sorted = keys.to_vec();
    sorted.par_sort_unstable();
    sorted
        .chunk_by(|a, b| a == b)
        .map(|run| (run[0], run.len()))
        .collect()
}

/// The red, green and blue channels of a packed colour.
pub(crate) fn channels(c: u32) -> [u8; 3] {
    [(c >> 16) as u8, (c >> 8) as u8, c as u8]
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    #[test]
    fn colours_are_packed_and_counted_in_increasing_order() {
        let img = RgbImage::from_fn(3, 2, |x, y| match (x + y) % 2 {
            0 => Rgb([1, 2, 3]),
            _ => Rgb([0, 9, 9]),
        });
        let keys = packed(&img);
        assert_eq!(keys[..2], [0x010203, 0x000909]);
        assert_eq!(distinct(&keys), [(0x000909, 3), (0x010203, 3)]);
        assert_eq!(channels(0x010203), [1, 2, 3]);
    }
}
