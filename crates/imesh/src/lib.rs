//! imesh: an image in, a segmented, simulation-ready mesh out.
//!
//! [`Pipeline`] composes the stages (classify → Imesh sampling and partition → quality triangle
//! mesh → checks) and times each one; the `imesh` program is a thin command line over it. Quad
//! output (templates, Bézier boundary fitting, optimisation) joins the pipeline as those crates
//! land; today the pipeline gives the Imesh triangle mesh.
//!
//! ```
//! use imesh::{MeshOptions, Pipeline};
//! let image = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(24, 16, |x, y| {
//!     image::Luma([if (x as i32 - 12).pow(2) + (y as i32 - 8).pow(2) < 30 { 255 } else { 0 }])
//! }));
//! let result = Pipeline::new(MeshOptions::default()).run_image(&image).unwrap();
//! assert!(result.report.validation.valid);
//! assert_eq!(result.report.counts.labels, 2);
//! ```

use std::path::Path;
use std::str::FromStr;
use std::time::Instant;

use imesh_classify::{classify, load_image, Classifier, ClassifyOptions, LabelGrid};
use imesh_geom::{RefineOptions, StopReason};
use imesh_io::SegmentedMeshData;
use imesh_quality::{validate, Domain, Element, MeshView, TriangleQuality};
use imesh_segment::{SampleOptions, SegmentedMesh};
use serde::{Deserialize, Serialize};

/// Which elements to produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Elements {
    /// The Imesh triangle mesh.
    Tri,
    /// The all-quad mesh (not in this build yet).
    Quad,
}

impl FromStr for Elements {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "tri" => Ok(Self::Tri),
            "quad" => Ok(Self::Quad),
            _ => Err(format!("unknown element kind {s:?}: use tri or quad")),
        }
    }
}

/// Every option of a mesh run (a TOML or JSON file can hold them; missing fields take defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeshOptions {
    /// Classifier: `auto`, `labels`, `otsu[:K]`, `threshold:T1,T2`, `kmeans:K`,
    /// `texture:SAMPLES.toml`.
    pub classify: String,
    /// Imesh error threshold t_e (smaller: more vertices, closer boundaries).
    pub te: f64,
    /// Smallest angle of the triangle mesh, in degrees (at most 34).
    pub min_angle: f64,
    /// Most points refinement may insert.
    pub max_steiner: Option<usize>,
    /// Largest element area in square pixels, if any.
    pub max_area: Option<f64>,
    /// Element kind.
    pub elements: Elements,
    /// Size of a pixel along x and y in the written mesh.
    pub pixel_size: [f64; 2],
    /// Largest image accepted, in pixels.
    pub max_pixels: u64,
}

impl Default for MeshOptions {
    fn default() -> Self {
        Self {
            classify: "auto".into(),
            te: 0.1,
            min_angle: imesh_segment::DEFAULT_MIN_ANGLE,
            max_steiner: None,
            max_area: None,
            elements: Elements::Tri,
            pixel_size: [1.0, 1.0],
            max_pixels: imesh_classify::DEFAULT_MAX_PIXELS,
        }
    }
}

/// Why a run failed. Every variant is the user's to fix (exit code 2 in the program).
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// The options are inconsistent.
    #[error("{0}")]
    Options(String),
    /// Loading or classifying the image failed.
    #[error(transparent)]
    Classify(#[from] imesh_classify::ClassifyError),
    /// Sampling or refinement failed.
    #[error(transparent)]
    Segment(#[from] imesh_segment::SegmentError),
    /// The mesh broke an invariant (a bug: please report it with the image).
    #[error("the mesh is invalid ({0}); please report this with the image")]
    Invalid(String),
}

/// Seconds spent in each stage.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageSeconds {
    /// Loading and classification.
    pub classify: f64,
    /// Imesh sampling, partition and c-edges.
    pub sample: f64,
    /// Quality refinement of the triangles.
    pub refine: f64,
    /// Invariant checks and quality measurement.
    pub check: f64,
    /// All stages.
    pub total: f64,
}

/// Element, vertex and label counts.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Counts {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Labels in the label grid.
    pub labels: usize,
    /// Pixel centres Imesh sampled.
    pub sampled_vertices: usize,
    /// c-edges of the partition.
    pub c_edges: usize,
    /// Points the refinement inserted.
    pub refinement_points: usize,
    /// Triangles left below the smallest angle (at small angles between region boundaries).
    pub triangles_below_min_angle: usize,
    /// Vertices of the output mesh.
    pub vertices: usize,
    /// Elements of the output mesh.
    pub elements: usize,
}

/// The invariant checks' outcome.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Validation {
    /// True when the mesh is conforming, covers the domain exactly, and no element is inverted.
    pub valid: bool,
    /// Sum of the element areas over the domain's area (1 for an exact cover).
    pub area_ratio: f64,
}

/// The JSON report of a run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The options used.
    pub options: MeshOptions,
    /// Counts.
    pub counts: Counts,
    /// Per-stage seconds.
    pub seconds: StageSeconds,
    /// Share of pixels whose centre lies in an element of the pixel's label.
    pub label_agreement: f64,
    /// Triangle quality statistics.
    pub quality: TriangleQuality,
    /// Invariant checks.
    pub validation: Validation,
}

/// The outcome of a run: the mesh, ready for the writers, and its report.
#[derive(Clone, Debug)]
pub struct PipelineResult {
    /// The labelled mesh (image coordinates).
    pub mesh: SegmentedMeshData,
    /// What happened.
    pub report: Report,
}

/// Image → mesh, with typed options and timed stages.
#[derive(Clone, Debug)]
pub struct Pipeline {
    options: MeshOptions,
}

impl Pipeline {
    /// A pipeline with these options.
    pub fn new(options: MeshOptions) -> Self {
        Self { options }
    }

    /// Loads `path` (refusing images above `max_pixels`) and meshes it.
    ///
    /// # Errors
    /// [`PipelineError`], each saying what to change.
    pub fn run_path(&self, path: &Path) -> Result<PipelineResult, PipelineError> {
        let start = Instant::now();
        let image = load_image(path, self.options.max_pixels)?;
        let mut result = self.run_image(&image)?;
        let load = start.elapsed().as_secs_f64() - result.report.seconds.total;
        result.report.seconds.classify += load;
        result.report.seconds.total += load;
        Ok(result)
    }

    /// Meshes a decoded image.
    ///
    /// # Errors
    /// [`PipelineError`], each saying what to change.
    pub fn run_image(&self, image: &image::DynamicImage) -> Result<PipelineResult, PipelineError> {
        let o = &self.options;
        self.check_options()?;
        let start = Instant::now();
        let classifier = Classifier::from_str(&o.classify)?;
        let grid = classify(image, &classifier, &ClassifyOptions::default())?;
        let t_classify = start.elapsed().as_secs_f64();
        self.run_grid(&grid, t_classify)
    }

    /// Meshes a label grid (`classified` seconds already spent getting it).
    ///
    /// # Errors
    /// [`PipelineError`], each saying what to change.
    pub fn run_grid(
        &self,
        grid: &LabelGrid,
        classified: f64,
    ) -> Result<PipelineResult, PipelineError> {
        let o = &self.options;
        self.check_options()?;
        let start = Instant::now();
        let mut segmented = SegmentedMesh::from_grid(
            grid,
            &SampleOptions {
                te: o.te,
                ..Default::default()
            },
        )?;
        let t_sample = start.elapsed().as_secs_f64();
        let refined = segmented.refine(&RefineOptions {
            min_angle_deg: o.min_angle,
            max_steiner: o.max_steiner.unwrap_or(usize::MAX),
            max_area: o.max_area,
        })?;
        let t_refine = start.elapsed().as_secs_f64() - t_sample;
        let (vertices, triangles, labels) = segmented.arrays();
        let elements: Vec<Element> = triangles.iter().map(|&t| Element::Triangle(t)).collect();
        let (w, h) = (grid.width(), grid.height());
        let checked = validate(
            &MeshView {
                vertices: &vertices,
                elements: &elements,
                labels: &labels,
            },
            &Domain::image(f64::from(w), f64::from(h)),
        );
        if !checked.is_valid() {
            return Err(PipelineError::Invalid(format!("{:?}", checked.violations)));
        }
        let quality = TriangleQuality::of(&vertices, &triangles);
        let label_agreement = segmented.label_agreement(grid);
        let t_check = start.elapsed().as_secs_f64() - t_sample - t_refine;
        let counts = Counts {
            width: w,
            height: h,
            labels: grid.num_labels(),
            sampled_vertices: segmented.inserted,
            c_edges: segmented.c_edges.len(),
            refinement_points: refined.inserted,
            triangles_below_min_angle: if refined.stopped == StopReason::Done {
                refined.bad_left
            } else {
                0
            },
            vertices: vertices.len(),
            elements: elements.len(),
        };
        let mesh = SegmentedMeshData {
            vertices,
            elements,
            labels,
            label_names: grid.regions().iter().map(|r| r.name.clone()).collect(),
            label_colours: grid.regions().iter().map(|r| r.colour).collect(),
            width: w,
            height: h,
        };
        let report = Report {
            options: o.clone(),
            counts,
            seconds: StageSeconds {
                classify: classified,
                sample: t_sample,
                refine: t_refine,
                check: t_check,
                total: classified + t_sample + t_refine + t_check,
            },
            label_agreement,
            quality,
            validation: Validation {
                valid: true,
                area_ratio: checked.area / (f64::from(w) * f64::from(h)),
            },
        };
        Ok(PipelineResult { mesh, report })
    }

    fn check_options(&self) -> Result<(), PipelineError> {
        let o = &self.options;
        if o.elements == Elements::Quad {
            return Err(PipelineError::Options(
                "quad meshes are not in this build yet: use --elements tri (the default)".into(),
            ));
        }
        if !(o.pixel_size[0] > 0.0
            && o.pixel_size[1] > 0.0
            && o.pixel_size.iter().all(|s| s.is_finite()))
        {
            return Err(PipelineError::Options(format!(
                "the pixel size must be positive, not {:?}",
                o.pixel_size
            )));
        }
        Ok(())
    }
}
