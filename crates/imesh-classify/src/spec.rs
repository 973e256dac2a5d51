//! Classifier selection: a short spec string or the typed enum.

use std::path::PathBuf;
use std::str::FromStr;

use crate::ClassifyError;

/// Which classifier turns pixels into labels.
///
/// ```
/// use imesh_classify::Classifier;
/// assert_eq!("otsu:3".parse::<Classifier>().unwrap(), Classifier::Otsu { classes: 3 });
/// assert_eq!("threshold:80,170".parse::<Classifier>().unwrap(), Classifier::Threshold { levels: vec![80, 170] });
/// assert!("kmeans:0".parse::<Classifier>().is_err());
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Classifier {
    /// `labels` for an image that looks like a label map (few distinct values in large flat
    /// regions; its dominant colours when it was stored with a lossy codec, see
    /// [`crate::ClassifyOptions::lossy`]), `otsu` otherwise.
    Auto,
    /// Each distinct grey value or colour is a label.
    Labels,
    /// Otsu thresholding of the luminance into `classes` classes (2: classic Otsu; more:
    /// multi-level Otsu).
    Otsu {
        /// Number of classes, 2 to 16.
        classes: usize,
    },
    /// Explicit luminance levels (0–255, increasing): `v ≤ levels[0]` is class 0, and so on.
    Threshold {
        /// The levels.
        levels: Vec<u8>,
    },
    /// k-means clustering of the colours in CIE Lab (k-means++ seeding, fixed seed).
    KMeans {
        /// Number of clusters, 2 to 64.
        k: usize,
    },
    /// The supervised texture classifier, trained on the sample rectangles of a TOML file.
    Texture {
        /// The sample file.
        samples: PathBuf,
    },
}

impl FromStr for Classifier {
    type Err = ClassifyError;

    fn from_str(spec: &str) -> Result<Self, ClassifyError> {
        let bad = |reason: &str| ClassifyError::BadSpec {
            spec: spec.to_string(),
            reason: reason.to_string(),
        };
        let count = |v: &str, lo: usize, hi: usize, what: &str| -> Result<usize, ClassifyError> {
            v.trim()
                .parse::<usize>()
                .ok()
                .filter(|k| (lo..=hi).contains(k))
                .ok_or_else(|| {
                    bad(&format!(
                        "{what} must be an integer from {lo} to {hi}, not '{v}'"
                    ))
                })
        };
        let (name, arg) = match spec.split_once(':') {
            Some((n, a)) => (n.trim(), Some(a)),
            None => (spec.trim(), None),
        };
        match (name, arg) {
            ("auto", None) => Ok(Classifier::Auto),
            ("labels", None) => Ok(Classifier::Labels),
            ("otsu", None) => Ok(Classifier::Otsu { classes: 2 }),
            ("otsu", Some(k)) => Ok(Classifier::Otsu {
                classes: count(k, 2, 16, "the number of classes")?,
            }),
            ("threshold", Some(levels)) => {
                let levels: Vec<u8> = levels
                    .split(',')
                    .map(|t| {
                        t.trim()
                            .parse::<u8>()
                            .map_err(|_| bad(&format!("'{t}' is not a level from 0 to 255")))
                    })
                    .collect::<Result<_, _>>()?;
                if levels.windows(2).any(|w| w[0] >= w[1]) {
                    return Err(bad("levels must increase"));
                }
                Ok(Classifier::Threshold { levels })
            }
            ("kmeans", Some(k)) => Ok(Classifier::KMeans {
                k: count(k, 2, 64, "k")?,
            }),
            ("texture", Some(path)) if !path.trim().is_empty() => Ok(Classifier::Texture {
                samples: PathBuf::from(path.trim()),
            }),
            ("threshold" | "kmeans" | "texture", None) => {
                Err(bad("this classifier needs an argument after ':'"))
            }
            _ => Err(bad("unknown classifier")),
        }
    }
}
