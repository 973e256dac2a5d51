//! Errors of image loading and classification: each says what was wrong and what to do.

use std::path::PathBuf;

/// Everything that can go wrong while loading or classifying an image.
#[derive(Debug, thiserror::Error)]
pub enum ClassifyError {
    /// The file could not be read.
    #[error("cannot read '{path}': {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not an image the decoder understands, or it is damaged.
    #[error(
        "cannot decode '{path}' as an image: {reason} (give a PNG, JPEG, BMP or PNM file, or a TIFF of 8- or 16-bit channels or of one grey channel of any type)"
    )]
    Decode {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        reason: String,
    },
    /// The image has no pixels.
    #[error(
        "the image '{path}' is empty ({width}×{height}): give an image with at least one pixel"
    )]
    EmptyImage {
        /// The file.
        path: PathBuf,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
    },
    /// The image is larger than the configured pixel limit.
    #[error("the image is {width}×{height} = {pixels} pixels, over the limit of {limit}: downscale it or raise the limit")]
    TooLarge {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// width × height.
        pixels: u64,
        /// The limit.
        limit: u64,
    },
    /// A label map has more distinct values than allowed.
    #[error("the image has more than {limit} distinct values, too many for a label map: classify it instead (e.g. --classify otsu:3 or kmeans:4), or raise the label limit (--max-labels)")]
    TooManyLabels {
        /// The limit.
        limit: usize,
    },
    /// A classifier spec string is malformed.
    #[error("invalid classifier '{spec}': {reason}. Use one of: labels, otsu, otsu:K, threshold:T1,T2,…, kmeans:K, texture:SAMPLES.toml")]
    BadSpec {
        /// The spec as given.
        spec: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A texture sample file is invalid.
    #[error("invalid sample file '{path}': {reason}")]
    Samples {
        /// The sample file.
        path: PathBuf,
        /// What is wrong, with the line when known.
        reason: String,
    },
    /// A sample rectangle does not fit in the image.
    #[error("sample rectangle {rect:?} of label '{label}' is not inside the {width}×{height} image: give x, y, w, h with x + w ≤ {width} and y + h ≤ {height}")]
    RectangleOutside {
        /// The label it belongs to.
        label: String,
        /// `[x, y, w, h]`.
        rect: [u32; 4],
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
    /// An output file could not be written.
    #[error("cannot write '{path}': {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}
