//! Imesh for label grids: image-adaptive Delaunay sampling, the partition into labelled regions
//! and their boundaries (the c-edges), and the labelled quality triangle mesh (DESIGN.md §2,
//! steps 2–4; the paper's section IV).
//!
//! ```
//! use imesh_classify::{LabelGrid, Region};
//! use imesh_geom::RefineOptions;
//! use imesh_segment::{SampleOptions, SegmentedMesh, DEFAULT_MIN_ANGLE};
//! // A 32×32 image with a disk of label 1.
//! let labels = (0..32 * 32)
//!     .map(|i| u32::from(((i % 32) as f64 - 15.5).hypot((i / 32) as f64 - 15.5) < 10.0))
//!     .collect();
//! let regions = vec![Region { name: "back".into(), colour: [0; 3] }, Region { name: "disk".into(), colour: [255; 3] }];
//! let grid = LabelGrid::new(32, 32, labels, regions).unwrap();
//! let mut mesh = SegmentedMesh::from_grid(&grid, &SampleOptions::default()).unwrap();
//! assert!(mesh.label_agreement(&grid) > 0.95);
//! mesh.refine(&RefineOptions { min_angle_deg: DEFAULT_MIN_ANGLE, ..Default::default() }).unwrap();
//! mesh.triangulation.check().unwrap();
//! ```

#![warn(missing_docs)]

mod mesh;
mod partition;
mod regions;
mod sample;
pub mod traverse;

pub use mesh::{SegmentedMesh, DEFAULT_MIN_ANGLE};
pub use partition::{c_edges, partition, triangle_label, CEdge, OUTSIDE};
pub use regions::{
    merge_regions, merge_thin_regions, MergeReport, PartitionRegion, PartitionRegions, NO_REGION,
};
pub use sample::{median_error, sample, MedianError, SampleOptions, Sampling};

/// What can go wrong in the Imesh stages.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SegmentError {
    /// The error threshold is outside [0, 1).
    #[error("the error threshold t_e = {te} is outside [0, 1): use a value such as 0.1 (smaller gives a finer mesh)")]
    BadThreshold {
        /// The value given.
        te: f64,
    },
    /// The label grid has no pixels.
    #[error("the image has no pixels")]
    EmptyGrid,
    /// A geometry operation failed.
    #[error(transparent)]
    Geometry(#[from] imesh_geom::GeomError),
}
