//! # imesh-classify
//!
//! The first stage of imesh: load an image (with limits) and turn it into a [`LabelGrid`] — one
//! label per pixel, with a name and a display colour per label.
//!
//! Classifiers ([`Classifier`], also parsed from short specs such as `otsu:3`):
//! - label-map passthrough (each distinct grey value or colour is a region);
//! - thresholds on luminance: explicit levels, Otsu, multi-level Otsu;
//! - k-means colour clustering in CIE Lab (k-means++, fixed seed);
//! - the supervised texture classifier of Imesh ([`TextureClassifier`]).
//!
//! Clean-up: [`remove_small_regions`], [`majority_filter`], [`remove_border_slivers`] (the
//! thin parts the majority filter leaves against the image's border) and [`remove_thin_parts`]
//! (the parts of regions thinner than a width anywhere else: strips, necks, arms).
//!
//! ```
//! use imesh_classify::{classify, Classifier, ClassifyOptions};
//! let img = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(16, 16, |x, y| {
//!     image::Luma([if (x as i32 - 8).pow(2) + (y as i32 - 8).pow(2) < 25 { 200 } else { 30 }])
//! }));
//! let grid = classify(&img, &"otsu".parse::<Classifier>()?, &ClassifyOptions::default())?;
//! assert_eq!(grid.num_labels(), 2);
//! assert_eq!(grid.label(8, 8), 1); // the bright disc is the upper class
//! # Ok::<(), imesh_classify::ClassifyError>(())
//! ```

#![warn(missing_docs)]

mod cleanup;
mod colours;
mod depth;
mod dominant;
mod error;
mod grey_tiff;
mod grid;
mod kmeans;
mod labels;
mod load;
mod reduce;
mod slivers;
mod spec;
mod texture;
mod threshold;

use image::DynamicImage;

pub use cleanup::{majority_filter, pixel_regions, remove_small_regions, PixelRegion};
pub use depth::eight_bit;
pub use dominant::{dominant_colours, COLOUR_SPREAD, DOMINANT_SHARE};
pub use error::ClassifyError;
pub use grid::{LabelGrid, Region};
pub use kmeans::kmeans;
pub use labels::{label_map, looks_like_label_map};
pub use load::{decode_image, is_lossy_file, load_image, DEFAULT_MAX_PIXELS};
pub use reduce::reduce;
pub use slivers::{remove_border_slivers, remove_thin_parts, MAX_SLIVER_HALF_WIDTH};
pub use spec::Classifier;
pub use texture::{SampleLabel, TextureClassifier, TextureSamples};
pub use threshold::{luminance, multi_otsu_levels, threshold};

/// Options shared by the classifiers.
#[derive(Clone, Debug, PartialEq)]
pub struct ClassifyOptions {
    /// Most distinct values a label map may have (default [`DEFAULT_MAX_LABELS`]).
    pub max_labels: usize,
    /// The image was stored with a lossy codec ([`is_lossy_file`]): `auto` then reads a
    /// label-like image by its dominant colours ([`dominant_colours`]) rather than every colour.
    pub lossy: bool,
}

/// Default [`ClassifyOptions::max_labels`]: 65 536, every value of a 16-bit label map (instance
/// segmentations often hold thousands of labels).
pub const DEFAULT_MAX_LABELS: usize = 1 << 16;

impl Default for ClassifyOptions {
    fn default() -> Self {
        Self {
            max_labels: DEFAULT_MAX_LABELS,
            lossy: false,
        }
    }
}

/// Classifies `image` with `classifier`.
///
/// # Errors
/// [`ClassifyError::TooManyLabels`] for a label map with too many values; sample-file and
/// rectangle errors for the texture classifier.
pub fn classify(
    image: &DynamicImage,
    classifier: &Classifier,
    options: &ClassifyOptions,
) -> Result<LabelGrid, ClassifyError> {
    match classifier {
        Classifier::Auto => {
            if looks_like_label_map(image, options.max_labels) {
                if options.lossy {
                    Ok(dominant_colours(image))
                } else {
                    label_map(image, options.max_labels)
                }
            } else {
                classify(image, &Classifier::Otsu { classes: 2 }, options)
            }
        }
        Classifier::Labels => label_map(image, options.max_labels),
        Classifier::Otsu { classes } => {
            let grey = luminance(image);
            let levels = if *classes == 2 {
                vec![imageproc::contrast::otsu_level(&grey)]
            } else {
                multi_otsu_levels(&grey, *classes)
            };
            Ok(threshold(&grey, &levels))
        }
        Classifier::Threshold { levels } => Ok(threshold(&luminance(image), levels)),
        Classifier::KMeans { k } => Ok(kmeans(image, *k)),
        Classifier::Texture { samples } => {
            let samples = TextureSamples::load(samples)?;
            Ok(TextureClassifier::train(image, &samples)?.classify(image))
        }
    }
}
