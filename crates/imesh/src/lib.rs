//! imesh: an image in, a segmented, simulation-ready mesh out.
//!
//! [`Pipeline`] composes the stages and times each one; the `imesh` program is a thin command
//! line over it. Quads (the default): classify → Imesh sampling and partition → curves
//! (topology-preserving simplification, Bézier fitting) → DT' → pairing → templates → boundary
//! adaptation → optimisation → checks. Triangles (`elements = "tri"`): classify → Imesh sampling and
//! partition → label-aware Ruppert refinement → checks.
//!
//! ```
//! use imesh::{MeshOptions, Pipeline};
//! let image = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(24, 16, |x, y| {
//!     image::Luma([if (x as i32 - 12).pow(2) + (y as i32 - 8).pow(2) < 30 { 255 } else { 0 }])
//! }));
//! let result = Pipeline::new(MeshOptions::default()).run_image(&image).unwrap();
//! assert!(result.report.validation.valid);
//! assert_eq!(result.report.counts.labels, 2);
//! assert!(result.report.counts.quads > 0 && result.report.counts.triangles == 0);
//! ```

#![warn(missing_docs)]

use std::path::Path;
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use imesh_classify::{classify, load_image, Classifier, ClassifyOptions, LabelGrid};
use imesh_curves::{
    blunt_sharp_tips, contract_short_links, fit_edges, neck_vertices, open_sharp_corners,
    sharp_vertices, simplify, CornerOptions, CurveGraph, FitOptions, GraphEdge, Simplification,
    SimplifyOptions, TipOptions,
};
use imesh_geom::{RefineOptions, StopReason, TriangleId, Triangulation, VertexId};
use imesh_io::{SecondOrder, SegmentedMeshData};
use imesh_optim::{optimise, Method, Metric, OptimOptions};
use imesh_quad::{remesh, DensityOptions, Pairing, QuadOptions};
use imesh_quality::{
    validate, BoundaryCorner, Domain, Element, Histogram, MeshView, QuadQuality, Statistics,
    TriangleQuality,
};
use imesh_segment::{
    c_edges, merge_regions, merge_thin_regions, partition, sample, CEdge, MergeReport,
    SampleOptions, SegmentedMesh, OUTSIDE,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which elements to produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Elements {
    /// The Imesh triangle mesh.
    Tri,
    /// The all-quad mesh.
    Quad,
}

/// How the quad stage pairs triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PairingMethod {
    /// The paper's greedy triquad (longest edges first).
    Greedy,
    /// Best quads first, then augmenting paths; every corner within 30°–150°.
    Matching,
    /// The matching with corners down to about 20.5°: fewer triangles left than greedy.
    Fewest,
}

impl FromStr for PairingMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "greedy" => Ok(Self::Greedy),
            "matching" => Ok(Self::Matching),
            "fewest" => Ok(Self::Fewest),
            _ => Err(format!(
                "unknown pairing {s:?}: use matching, fewest or greedy"
            )),
        }
    }
}

/// How large the quads are (`--size`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum ElementSize {
    /// Uniform, at a side chosen from the image's size and the width of its regions (default;
    /// see [`AUTO_QUADS`] and [`MIN_AUTO_SIZE`]).
    Auto,
    /// Uniform quads of about this side, in pixels (DT' spacing: 2 × level × this).
    Pixels(f64),
    /// DT' graded from the boundaries' own pieces inwards, by refinement alone (the paper's):
    /// fewer elements, lower shape-and-size.
    Graded,
}

/// Largest [`MeshOptions::majority`] radius: the filter costs 2(2R+1) per pixel on label maps
/// of up to 32 labels, (2R+1)² on others.
pub const MAX_MAJORITY: u32 = 8;

/// Automatic reduction ([`MeshOptions::reduction`]): an image whose uniform quads (of
/// automatic size, or of the size given) are `q` pixels wide is meshed on cells of
/// `F = ⌊q / AUTO_REDUCTION_SIZE⌋` pixels when `F ≥ 2`, so
/// that its quads are 4 to 8 cells wide: the size at which the defaults (curve tolerance,
/// majority filter, minimum width) were tuned and mesh best. Measured on the camera fixture
/// resized to 4096² (quads 41 pixels wide): mean shape-and-size 0.66 and worst scaled Jacobian
/// 0.10 on the pixels (the 2-pixel curve tolerance pins boundary vertices a fraction of a quad
/// apart, the majority filter's 8 pixels leave features thinner than a quad), against 0.91 and
/// 0.35 on cells of 10 pixels, in a quarter of the time (label agreement 97.6 % against 99.0 %).
pub const AUTO_REDUCTION_SIZE: f64 = 4.0;

/// Smallest quad side `--size auto` chooses, in pixels: the Imesh partition's vertices are
/// pixel centres, so finer quads would only repeat the pixel staircase.
pub const MIN_AUTO_SIZE: f64 = 2.0;

/// About how many quads `--size auto` aims at over a whole image with wide regions.
pub const AUTO_QUADS: f64 = 10_000.0;

/// `--size auto` makes quads no larger than this share of the width below which a quarter of
/// the boundaries lie ([`boundary_weighted_width`]).
pub const AUTO_WIDTH_SHARE: f64 = 0.35;

/// `--size auto` makes the quads small enough that those along the boundaries (a row on each
/// side of every boundary of G', the image border aside) are at most about this share of them
/// ([`band_limited_size`]). The quads along a boundary are where a uniform mesh loses its
/// shape-and-size (their vertices on the curve are fixed, the curve meets the lattice at any
/// angle, unpaired triangles gather there): on coins they scored 0.70 on average against 0.94
/// for the quads three rings in. Measured with no other option: mean shape-and-size coins 0.824
/// → 0.866 (9 817 → 17 440 quads), stardist 0.811 → 0.858 (16 098 → 35 577), the other eight
/// fixtures' sizes unchanged or within 2 %; at a share of 0.18 coins scored 0.850, at 0.20 0.834.
pub const AUTO_BAND_SHARE: f64 = 0.16;

/// [`band_limited_size`] makes the quads at most this many times smaller than the size the
/// clean-ups were chosen for (at most 2.25 times as many quads): the majority filter, the
/// minimum width and the boundary simplification keep that coarser size, so that a finer mesh
/// follows the same cleaned boundaries rather than more of the pixel noise.
pub const AUTO_BAND_REFINEMENT: f64 = 1.5;

/// Boundary pieces shorter than this many quad sides are joined with a neighbour where the
/// topology and a deviation of half their length allow ([`SimplifyOptions::min_length`]).
pub const MIN_PIECE: f64 = 1.0;

/// Two junctions of the boundaries closer than this many quad sides, joined by a boundary
/// within the curve tolerance of the segment between them, are merged into one
/// ([`contract_short_links`]): where four regions meet at a pixel corner, Imesh gives two
/// junctions a fraction of a pixel apart, and the quads around such a link are that small.
/// Where several grains meet within a few pixels (polycrystals), junctions half a quad to a
/// quad apart leave zig-zags of links a pixel or two long, slivers between them and tips of
/// 18–28°. Measured with no options over 180 images (the 42 of session 45, 138 synthetic
/// rectangle, smoothed-noise, ellipse and Voronoi label images) against 0.5: at 0.75, 70 meshes
/// changed, the mean up on 43 and down on 9 (+0.087 summed; Voronoi images up to +0.006), the
/// worst shape up on 13 and down on 5, the worst scaled Jacobian by more than 0.01 up on 4 (an
/// ellipse 1.5 px from the border 0.381 → 0.500) and down on 1 (smoothed noise 0.500 → 0.446,
/// a quad by a boundary the repairs left); of the fixtures only grass changed (worst shape
/// 0.350 → 0.395). At 1.0 the means rose more (+0.117) but the worst scaled Jacobian fell on
/// 17 (Voronoi grains 0.500 → 0.404).
pub const LINK_SHARE: f64 = 0.75;

/// The narrowest region the automatic quad size heeds, as a share of [`MIN_AUTO_SIZE`] (twice
/// this times that, in pixels, is the least width it weighs).
pub const AUTO_MIN_WIDTH: f64 = 0.5;

/// The automatic [`MeshOptions::min_width`], as a share of the finest quad side the mesh can
/// end with (the given `--size`; with `--size auto`, the chosen side refined as far as the band
/// limit may, [`AUTO_BAND_REFINEMENT`], and not below [`MIN_AUTO_SIZE`]): regions thinner are
/// merged into their neighbours. DT' fills a strip `d` wide with triangles whose corners stay
/// over 20.7°, about `2.6 d²` in area, and their template quads come to about `1.3 (d / q)²`
/// of the mean area: a region under three quarters of a quad holds quads of about 0.7 of it at
/// best, whose shape-and-size is about half their shape. Measured with the defaults (`cargo
/// xtask bench random`, 150 images a set; half a quad side of the chosen size before):
/// seed 52 26 meshes changed, 24 up (mean of the means 0.89354 → 0.89383, quads under 0.25
/// 3 608 → 3 413); seed 101 30, 25 up (0.90061 → 0.90087, 5 185 → 4 985); seed 202 33, 31 up
/// (0.89582 → 0.89607, 4 093 → 3 887); seed 303 at `--size 3` 45, 43 up (0.85824 → 0.85957,
/// 12 317 → 11 418); quads under 0.5 in shape 187 against 189 over the five sets (seed 52 at
/// `--size 3` too), in scaled Jacobian 20 against 25. Of the fixtures, the six whose chosen
/// side is under 3 px changed, every mean up (grass 0.705 → 0.719, pyvista 0.875 → 0.885,
/// coffee 0.912 → 0.918, aloe 0.769 → 0.775, gravel 0.719 → 0.724, brick +0.0002), label
/// agreement 0.01–0.4 points lower; worst shape pyvista 0.500 → 0.459, aloe 0.412 → 0.384,
/// grass 0.389 → 0.405. A share of 1.0 raised the means further (seed 52 0.89442, seed 303
/// at `--size 3` 0.86116) by dropping more of the image. Three quarters of the chosen side,
/// with the narrowest width the automatic size weighs raised to match ([`AUTO_MIN_WIDTH`]),
/// coarsened coffee's quads (2.0 → 2.9 px, mean 0.912 → 0.908).
pub const THIN_REGION_SHARE: f64 = 0.75;

/// The automatic [`MeshOptions::min_part_width`], as a share of the quad side: the parts of
/// regions thinner than a quad (strips, necks, arms between wider parts, of at least
/// [`THIN_PART_AREA`]) go to the regions beside them after the majority filter. The filter
/// thins such strips without removing them (camera's tripod: a strip 2–3 px wide between two
/// legs at quads of 5 px), and [`THIN_REGION_SHARE`] merges only whole regions; the templates
/// fill a strip `d` wide with two rows of quads of about `1.3 (d / q)²` of the mean area,
/// under 0.25 in shape-and-size (whose size term is squared) below about two thirds of a quad.
/// A part is what no disk of half this width, one label throughout, covers
/// ([`imesh_classify::remove_thin_parts`]); the disks are centred on pixel centres, so under
/// 2 px (quads under 2 px) nothing goes. Measured with the defaults (`cargo xtask bench
/// random`, seven sets of 150 images; docs/measurements.md, session 58): the mean of the means
/// up on all seven (+0.0002 to +0.0046), quads under 0.25 down by 21–44 %, under 0.5 in shape
/// 158 → 63 and in scaled Jacobian 23 → 12, label agreement 0.02–0.12 points lower. At 1.5
/// quad sides the means rose further (+0.0007 to +0.0076) but at `--size 3` the label
/// agreement fell by 0.6–0.7 points; at 2, by 0.5 points with the defaults.
pub const THIN_PART_SHARE: f64 = 1.0;

/// The least area, in quad areas, of a thin part [`THIN_PART_SHARE`] gives away: a smaller
/// one (a tip, a notch, a square corner's rounding) holds a few small quads at most, and the
/// tip cuts and the curve tolerance deal with it. A quarter of a quad changed twice as many
/// meshes for about the same means; three quads lowered them.
pub const THIN_PART_AREA: f64 = 1.0;

/// After the majority filter, the parts of regions thinner than twice this share of its radius
/// (the radius is about a quad side: half a quad) only because they lie
/// against the image's border, each of at least a quad's area, are given to their neighbours
/// ([`imesh_classify::remove_border_slivers`]). The filter's window is cut off at the border,
/// and where a region nearly touches the border the gap tapering between them kept its pixels
/// down to a cell's width, which the mesh filled with quads a few hundredths of the mean area.
/// Measured with no options: scikit-image's `retina` (not a fixture; a fundus photograph
/// whose disc comes within a few pixels of the frame, meshed on cells of 3 × 3 pixels) mean
/// shape-and-size 0.883 → 0.938, worst 1.5e-5 → 0.003, label agreement 99.31 → 99.28 %; a disc
/// 6 px from the side of a 1400² image 0.877 → 0.941 (worst scaled Jacobian 0.455 → 0.507); the
/// ten fixtures and the thirteen other unseen images of session 42 identical to the byte. With
/// parts down to `(2 · half-width)²` pixels instead of a quad's area, caps of nuclei a few
/// pixels across at stardist's border and a 4-pixel bump at `moon`'s went too, and those meshes
/// moved by the pipeline's usual path dependence (moon's mean 0.973 → 0.964 for 4 pixels).
///
/// The half-width is at least [`MIN_BORDER_SLIVER_PX`] wherever the filter's radius is 3 px or
/// more (quads of 2.5 px or more).
pub const BORDER_SLIVER: f64 = 0.25;

/// The least half-width, in pixels, of the border's thin parts given away after a majority
/// filter of radius 3 px or more: strips one or two pixels wide along the border, under 0.8 of
/// a quad. A quarter of the filter's radius is under a pixel for quads under 3.5 px, and there
/// the border's thin parts were all kept: a rectangle 2 px from the side of an image meshed
/// with quads of 2.6 px left a strip a pixel wide after the filter, which Imesh's pixel-centre
/// vertices made half a pixel wide and the mesh filled with quads of 0.2–5 % of the mean area
/// (worst shape 0.31, worst shape-and-size 0.0002). Measured with no options (`cargo xtask
/// bench random`, 150 images): two meshes changed, both up (that rectangle's mean 0.848 →
/// 0.938, a Voronoi image's 0.879 → 0.881), quads under 0.25 4 374 → 3 805, under 0.5 in
/// shape 58 → 9 and in scaled Jacobian 10 → 2; the ten fixtures identical. At `--size 3`
/// (`cargo xtask bench random --size 3`): mean of the means 0.85748 → 0.85881, quads under
/// 0.25 10 801 → 9 603, under 0.5 in shape 92 → 55 and in scaled Jacobian 10 → 9 (there the
/// fixtures' worst values moved by chance: grass's shape 0.500 → 0.426 at an inner junction
/// Imesh sampled anew, coffee's 0.476 → 0.486). Measured and left out: the same floor after a
/// filter of radius 2 (quads of 1.5–2.5 px, where a strip of 2 px is a quad wide): 48 meshes
/// changed, 30 up and 18 down (mean of the means +0.0009, under 0.5 in shape 16), but a street
/// grid's 2 px band along its border, given away, moved Imesh's samples and left a sliver at a
/// block's corner (worst scaled Jacobian 0.502 → 0.425), and aloe's worst scaled Jacobian fell
/// 0.463 → 0.429, coffee's mean 0.911 → 0.908.
pub const MIN_BORDER_SLIVER_PX: f64 = 1.0;

/// Where simplification brings a vertex of G' closer than this many quad sides to an edge of
/// G', the edge keeps the vertex of its chain nearest that vertex, if that one is
/// [`imesh_curves::NECK_RATIO`] times farther ([`imesh_curves::neck_vertices`]).
pub const NECK_SHARE: f64 = 0.5;

/// Where two simplified edges leave a vertex in a sharp sector, the boundaries' own directions
/// are taken this many quad sides from it ([`imesh_curves::sharp_vertices`]). Measured with no
/// options on nine fixtures (all but aloe), worst scaled Jacobian: brick 0.254 → 0.347, grass
/// 0.210 → 0.280, stardist 0.333 → 0.352, coffee 0.243 → 0.251, the rest equal; the mean
/// shape-and-size within ±0.0014 on each (averaged over the nine 0.8251 → 0.8253). At half a
/// quad brick gained less (0.327) and camera lost 0.005; at 1.5 and 2 quads coffee fell to 0.230;
/// with sectors up to 30° instead of 25°, coffee fell to 0.164.
pub const SHARP_LENGTH: f64 = 1.0;

/// Most rounds of restoring necks (and widening sharp sectors). A round's pins change the
/// chords next to them, which can bring another chord near a vertex: the rounds go on until
/// none is left. Measured with no options: grass needs three, aloe six (each other fixture at
/// most two, the earlier bound); with two, aloe kept a chord 0.02 px from another
/// boundary's vertex, which refinement filled with quads down to 0.01 px (worst shape-and-size
/// 4e-10 → 5e-5; grass's worst shape 0.406 → 0.422).
pub const NECK_ROUNDS: usize = 8;

/// Most rounds of merging the regions that simplification flattened below the minimum width,
/// each followed by the curve stage again.
pub const THIN_FACE_ROUNDS: usize = 3;

impl FromStr for ElementSize {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Self::Auto),
            "graded" => Ok(Self::Graded),
            _ => match s.parse::<f64>() {
                Ok(px) if px.is_finite() && px > 0.0 => Ok(Self::Pixels(px)),
                _ => Err(format!(
                    "unknown element size {s:?}: use auto, graded or a positive number of pixels"
                )),
            },
        }
    }
}

impl std::fmt::Display for ElementSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Auto => f.write_str("auto"),
            Self::Graded => f.write_str("graded"),
            Self::Pixels(px) => write!(f, "{px}"),
        }
    }
}

impl From<ElementSize> for String {
    fn from(s: ElementSize) -> Self {
        s.to_string()
    }
}

impl TryFrom<String> for ElementSize {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

/// How the quads are optimised (`--optimizer`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OptimizerMethod {
    /// Block coordinate descent over the free control points (default).
    Local,
    /// One Powell run over all free control points (the paper's; slow).
    Global,
    /// Laplacian smoothing of the quad vertices (baseline).
    Laplacian,
    /// Local optimisation of the quad vertices (baseline).
    Vertex,
    /// No optimisation.
    None,
}

impl FromStr for OptimizerMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "local" => Ok(Self::Local),
            "global" => Ok(Self::Global),
            "laplacian" => Ok(Self::Laplacian),
            "vertex" => Ok(Self::Vertex),
            "none" => Ok(Self::None),
            _ => Err(format!(
                "unknown optimizer {s:?}: use local, global, laplacian, vertex or none"
            )),
        }
    }
}

impl OptimizerMethod {
    fn method(self) -> Method {
        match self {
            Self::Local => Method::Local,
            Self::Global => Method::Global,
            Self::Laplacian => Method::Laplacian,
            Self::Vertex => Method::Vertex,
            Self::None => Method::None,
        }
    }
}

/// The quality the optimiser maximises (`--metric`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MetricName {
    /// Verdict's shape-and-size (shape and uniform size; default).
    ShapeAndSize,
    /// Verdict's shape.
    Shape,
}

impl FromStr for MetricName {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "shape-and-size" => Ok(Self::ShapeAndSize),
            "shape" => Ok(Self::Shape),
            _ => Err(format!("unknown metric {s:?}: use shape-and-size or shape")),
        }
    }
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
    /// Smallest angle of the triangles, in degrees (at most 34): of the Imesh triangle mesh
    /// (default 26.4°) or of DT' before pairing (default 20.7°).
    pub min_angle: Option<f64>,
    /// Most points refinement may insert.
    pub max_steiner: Option<usize>,
    /// Largest element size in pixels (the side of the largest equilateral triangle allowed
    /// before pairing or in the triangle mesh), if any.
    pub max_size: Option<f64>,
    /// Size of the quads: uniform (`auto`, or a side in pixels) or graded.
    pub size: ElementSize,
    /// Regions of the partition thinner than this many pixels (twice their area over their
    /// perimeter) are merged into the neighbour they share the longest boundary with, on the
    /// quad path: `None` (auto) is [`THIN_REGION_SHARE`] of the finest quad side a uniform mesh
    /// can end with and nothing for a graded one; 0 keeps every region.
    pub min_width: Option<f64>,
    /// Parts of regions thinner than this many pixels (strips, necks, the arms between wider
    /// parts of a region), each of at least [`THIN_PART_AREA`] quad areas, are given to the
    /// regions beside them before meshing ([`imesh_classify::remove_thin_parts`], after the
    /// majority filter): `None` (auto) is [`THIN_PART_SHARE`] of the quad side for a uniform
    /// quad mesh and nothing for a graded one or triangles; 0 keeps every part.
    pub min_part_width: Option<f64>,
    /// Regions (4-connected) smaller than this many pixels are merged into the neighbour they
    /// share the longest border with before meshing (0: every region is kept).
    pub min_region: usize,
    /// Radius of a majority filter applied to the labels before meshing (0: none): every pixel
    /// takes the label most common in its (2R+1)² window, which removes specks, notches and
    /// strips thinner than about R pixels; then the parts thinner than R / 2 against the image's
    /// border ([`BORDER_SLIVER`]) go to their neighbours. `None` (auto): about one quad side for
    /// a uniform quad mesh ([`auto_majority`]), none for a graded one or triangles.
    pub majority: Option<u32>,
    /// Mesh a reduced label grid whose every cell is the most frequent label of about
    /// `F × F` pixels ([`imesh_classify::reduce`]), then scale the mesh back onto the image:
    /// `None` (auto) reduces a uniform quad mesh whose quads (of automatic size, or of the size
    /// given) would be at least twice [`AUTO_REDUCTION_SIZE`] pixels wide, `Some(1)` never.
    /// The options given in pixels (size, tolerance, majority, min-width, min-part-width,
    /// min-region, max-size) are converted to cells; the defaults apply to the cells as to
    /// pixels (the curve tolerance is then 2 cells).
    pub reduction: Option<u32>,
    /// Curve simplification tolerance in pixels (quads); `None`:
    /// [`imesh_curves::DEFAULT_TOLERANCE`] pixels, or that many cells of a reduced grid.
    pub tolerance: Option<f64>,
    /// Template level k: each triangle gives 3k² quads, each paired quad 4k² (1–8).
    pub template_level: u32,
    /// How triangles are paired into quads.
    pub pairing: PairingMethod,
    /// Element kind.
    pub elements: Elements,
    /// Element order: 1 (linear), or 2 (a node in the middle of every side, on the boundary
    /// curve where the side follows one, and one at each quad's centre: 9-node quads and
    /// 6-node triangles, 8-node quads in Abaqus files).
    pub order: u32,
    /// How the quads are optimised.
    pub optimizer: OptimizerMethod,
    /// The quality the optimiser maximises.
    pub metric: MetricName,
    /// Most Powell iterations of the global optimiser.
    pub global_iterations: u64,
    /// Size of a pixel along x and y in the written mesh.
    pub pixel_size: [f64; 2],
    /// Where the image's bottom-left corner lies in the written mesh (in the pixel size's
    /// units; default 0, 0).
    pub origin: [f64; 2],
    /// Largest image accepted, in pixels.
    pub max_pixels: u64,
    /// Most labels a label map may have.
    pub max_labels: usize,
    /// Most elements the mesh may have: checked up front against a lower bound (with
    /// `max_size`), caps the refinement, and checked exactly before the templates are built.
    pub max_elements: u64,
    /// Keep the regions' tips sharper than 30° that the curves could not open, instead of
    /// cutting them off where they are one to two quad sides wide
    /// ([`imesh_curves::blunt_sharp_tips`], uniform quads only): the quad at such a tip has a
    /// corner that sharp, a scaled Jacobian under 0.5.
    pub keep_sharp_tips: bool,
    /// How far the optimiser's last repairs may move a corner or a junction of the boundaries
    /// (a vertex of G' off the image's border), as a share of the mean quad side, to open a
    /// corner that a quad there must otherwise keep under 30° or to give a small quad room; 0
    /// keeps every one where the boundaries put it ([`imesh_optim::OptimOptions::corner_reach`]).
    pub corner_reach: f64,
}

/// Default [`MeshOptions::max_elements`]: five million elements (about 1.5 GB at the peak of a
/// quad run).
pub const DEFAULT_MAX_ELEMENTS: u64 = 5_000_000;

impl Default for MeshOptions {
    fn default() -> Self {
        Self {
            classify: "auto".into(),
            te: 0.1,
            min_angle: None,
            max_steiner: None,
            max_size: None,
            size: ElementSize::Auto,
            min_width: None,
            min_part_width: None,
            min_region: 0,
            majority: None,
            reduction: None,
            tolerance: None,
            template_level: 1,
            pairing: PairingMethod::Matching,
            elements: Elements::Quad,
            order: 1,
            optimizer: OptimizerMethod::Local,
            metric: MetricName::ShapeAndSize,
            global_iterations: OptimOptions::default().global_iterations,
            pixel_size: [1.0, 1.0],
            origin: [0.0, 0.0],
            max_pixels: imesh_classify::DEFAULT_MAX_PIXELS,
            max_labels: imesh_classify::DEFAULT_MAX_LABELS,
            max_elements: DEFAULT_MAX_ELEMENTS,
            keep_sharp_tips: false,
            corner_reach: imesh_optim::CORNER_REACH,
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
    /// The curve stage refused its input.
    #[error(transparent)]
    Curves(#[from] imesh_curves::CurveError),
    /// The quad stage refused its input.
    #[error(transparent)]
    Quads(#[from] imesh_quad::QuadError),
    /// The optimiser refused its input.
    #[error(transparent)]
    Optimise(#[from] imesh_optim::OptimError),
    /// The mesh would exceed a resource limit (`max_elements`).
    #[error("{0}")]
    Limit(String),
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
    /// Quality refinement of the triangles (triangle output).
    pub refine: f64,
    /// Curve simplification and fitting (quads).
    pub curves: f64,
    /// DT', pairing, templates and adaptation (quads): the next four, and any retry at another
    /// lattice scale.
    pub quads: f64,
    /// DT': the conforming Delaunay triangulation of the simplified boundaries (quads).
    pub triangulate: f64,
    /// Pairing DT''s triangles into the mixed mesh M (quads).
    pub pairing: f64,
    /// The control net and the templates (quads).
    pub templates: f64,
    /// Boundary adaptation (quads).
    pub adapt: f64,
    /// Optimisation of the quads.
    pub optimise: f64,
    /// Invariant checks and quality measurement.
    pub check: f64,
    /// Writing the mesh file: set by whoever writes it (the `imesh` program), 0 from the
    /// pipeline alone.
    pub write: f64,
    /// All stages (the write's included once it is set).
    pub total: f64,
}

/// Element, vertex and label counts.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Counts {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The reduction ([`MeshOptions::reduction`]): each cell of the meshed grid is about
    /// `reduction × reduction` pixels (1: the pixels themselves).
    pub reduction: u32,
    /// Width of the meshed grid in cells (the image width without a reduction); the counts of
    /// pixels and sampled vertices below are of this grid.
    pub grid_width: u32,
    /// Height of the meshed grid in cells.
    pub grid_height: u32,
    /// Labels in the label grid meshed (after the clean-up).
    pub labels: usize,
    /// Labels with a pixel in the image's own label grid, before any reduction or clean-up.
    pub image_labels: usize,
    /// Labels the mesh's elements carry (one physical group each in the written files): fewer
    /// than `image_labels` when the reduction or the clean-up merged every region of a label
    /// away.
    pub meshed_labels: usize,
    /// Pixels whose label the clean-up (`majority`, `min_region`) changed; label agreement is
    /// measured against the image's own labels, so they count against it.
    pub cleaned_pixels: usize,
    /// Pixel centres Imesh sampled.
    pub sampled_vertices: usize,
    /// Regions of the partition merged into a neighbour for being thinner than `min_width`,
    /// in the partition or, once simplified, in G'.
    pub merged_regions: usize,
    /// Their area in square pixels.
    pub merged_area: f64,
    /// Pairs of boundary junctions merged for being closer than [`LINK_SHARE`] quad sides.
    pub contracted_links: usize,
    /// Boundary vertices kept where simplification would have narrowed a face below
    /// [`NECK_SHARE`] quad sides.
    pub kept_at_necks: usize,
    /// Sectors of G' narrower than [`imesh_curves::MIN_CORNER_DEG`] between two boundaries
    /// (about a quad side from their vertex), which [`imesh_curves::open_sharp_corners`] tried
    /// to widen.
    pub opened_corners: usize,
    /// Curves it refitted with turned ends, within the curve tolerance of their boundaries.
    pub turned_curves: usize,
    /// Sharp tips cut off where they were a quad side wide
    /// ([`imesh_curves::blunt_sharp_tips`]): sectors the curves could not open.
    pub blunted_tips: usize,
    /// The area those tips gave to their neighbours, in square pixels.
    pub blunted_area_px: f64,
    /// The farthest a cut moved a boundary (from a tip's vertex to its cut), in pixels: the
    /// boundary's Hausdorff distance includes it.
    pub blunted_depth_px: f64,
    /// Boundary vertices kept where two simplified edges would have left a vertex less than
    /// [`imesh_curves::SHARP_SECTOR_DEG`] apart though the boundaries leave it wider
    /// ([`imesh_curves::sharp_vertices`], at [`SHARP_LENGTH`] quad sides from it).
    pub kept_at_sharp_sectors: usize,
    /// The side of the quads of a uniform mesh, in pixels (0 when graded or for triangles).
    pub quad_size: f64,
    /// c-edges of the partition.
    pub c_edges: usize,
    /// Points the refinement inserted.
    pub refinement_points: usize,
    /// Triangles left below the smallest angle (at small angles between region boundaries).
    pub triangles_below_min_angle: usize,
    /// Edges of the simplified boundary graph G' (quads).
    pub simplified_edges: usize,
    /// Triangles of DT' (quads).
    pub dt_triangles: usize,
    /// Spacing of the uniform DT' in pixels (quads; 0 when graded).
    pub dt_spacing: f64,
    /// Its inside lattice's spacing as a multiple of it (1 unless one of [`LATTICE_MATCH`]'s
    /// tries was kept).
    pub lattice_scale: f64,
    /// DT' triangles left unpaired (quads).
    pub unpaired_triangles: usize,
    /// G' edges whose curve was flattened to keep every quad valid (quads).
    pub damped_curves: usize,
    /// Vertices of the output mesh.
    pub vertices: usize,
    /// Elements of the output mesh.
    pub elements: usize,
    /// Quads of the output mesh.
    pub quads: usize,
    /// Triangles of the output mesh.
    pub triangles: usize,
    /// Nodes of the output mesh: its vertices, and with `--order 2` the side middles and quad
    /// centres.
    pub nodes: usize,
    /// Element sides whose middle node lies off the straight side, on a boundary curve or part
    /// of the way there (`--order 2`, quads).
    pub curved_sides: usize,
    /// Of those, sides whose middle node keeps only a half or a quarter of the curve's offset:
    /// the whole would have bent a quad too far ([`imesh_io::CURVED_JACOBIAN_SHARE`]).
    pub damped_sides: usize,
    /// Sides along a curve left straight: even a quarter of its offset bent a quad too far.
    pub straightened_sides: usize,
}

/// Quality statistics of the output mesh: quads or triangles.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum MeshQuality {
    /// Verdict's quad metrics.
    Quads(QuadQuality),
    /// Verdict's triangle metrics.
    Triangles(TriangleQuality),
}

impl MeshQuality {
    /// Shape-and-size statistics (quads only).
    pub fn shape_and_size(&self) -> Option<&Statistics> {
        match self {
            Self::Quads(q) => Some(&q.shape_and_size),
            Self::Triangles(_) => None,
        }
    }

    /// Shape statistics.
    pub fn shape(&self) -> &Statistics {
        match self {
            Self::Quads(q) => &q.shape,
            Self::Triangles(t) => &t.shape,
        }
    }

    /// Smallest-angle statistics (degrees).
    pub fn min_angle_deg(&self) -> &Statistics {
        match self {
            Self::Quads(q) => &q.min_angle_deg,
            Self::Triangles(t) => &t.min_angle_deg,
        }
    }

    /// Scaled Jacobian statistics.
    pub fn scaled_jacobian(&self) -> &Statistics {
        match self {
            Self::Quads(q) => &q.scaled_jacobian,
            Self::Triangles(t) => &t.scaled_jacobian,
        }
    }
}

/// What the optimiser did (quads).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Optimisation {
    /// The method.
    pub method: OptimizerMethod,
    /// The metric of the energy.
    pub metric: MetricName,
    /// Points free to move.
    pub variables: usize,
    /// Independent sets solved in parallel (local modes).
    pub colours: usize,
    /// Energy `Σ (1 − s)²` before.
    pub energy_before: f64,
    /// Energy after.
    pub energy_after: f64,
    /// Sweeps (local modes) or Powell iterations (global).
    pub sweeps: usize,
    /// Quad vertices that slid along the boundary curves after the local or vertex mode.
    pub sliders: usize,
    /// Quad vertices moved last to raise the worst scaled Jacobians (local or vertex mode)...
    pub repaired: usize,
    /// ... of which boundary vertices moved along their curves.
    pub repaired_sliders: usize,
    /// Patches moved last for the quality of their poorest quads.
    pub quality_repaired: usize,
    /// Corners and junctions of the boundaries those last repairs moved
    /// ([`MeshOptions::corner_reach`])...
    pub moved_corners: usize,
    /// ... and the farthest one moved, in pixels.
    pub corner_shift_px: f64,
}

/// Quality histograms of the quads before and after optimisation (20 bins over [0, 1]), as the
/// paper's Figure 7 shows them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QualityHistograms {
    /// Shape-and-size before optimisation.
    pub shape_and_size_before: Histogram,
    /// Shape-and-size after.
    pub shape_and_size_after: Histogram,
    /// Scaled Jacobian before optimisation.
    pub scaled_jacobian_before: Histogram,
    /// Scaled Jacobian after.
    pub scaled_jacobian_after: Histogram,
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
    /// The program's version.
    pub imesh_version: &'static str,
    /// The image meshed.
    pub input: Input,
    /// The options used.
    pub options: MeshOptions,
    /// Counts.
    pub counts: Counts,
    /// Per-stage seconds (`"timings_s"` in the JSON, as DESIGN.md §6 names it).
    #[serde(rename = "timings_s")]
    pub seconds: StageSeconds,
    /// Share of pixels whose centre lies in an element of the pixel's label (also under
    /// `fidelity`).
    pub label_agreement: f64,
    /// How closely the mesh follows the image's regions.
    pub fidelity: Fidelity,
    /// Quality statistics.
    pub quality: MeshQuality,
    /// The quad corner with the smallest sine between two boundary edges (image pixels, y
    /// down): it fills a whole sector of its region at a boundary vertex, so its sine bounds the
    /// worst scaled Jacobian whatever the smoothing (quads only; none when no corner is held so).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sharpest_boundary_corner: Option<BoundaryCorner>,
    /// Quality statistics of the quads before optimisation (quads only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quality_before_optimisation: Option<MeshQuality>,
    /// What the optimiser did (quads only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimisation: Option<Optimisation>,
    /// Quality histograms before and after optimisation (quads only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub histograms: Option<QualityHistograms>,
    /// Invariant checks.
    pub validation: Validation,
}

/// The image a report is about.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Input {
    /// Its path, when it was read from a file.
    pub path: Option<String>,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

/// How closely the mesh follows the image's regions.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fidelity {
    /// Share of pixels whose centre lies in an element of the pixel's label.
    pub label_agreement: f64,
    /// Quads: the largest distance, either way, between a fitted boundary curve and the Imesh
    /// boundary chain it replaces (pixels); the triangle mesh's boundaries are the chains
    /// themselves (0).
    pub boundary_hausdorff_px: f64,
    /// Each label with a pixel in the image: how much of it the mesh holds (its area fraction against the
    /// image's, for a phase fraction), and how faithfully.
    pub regions: Vec<RegionFidelity>,
}

/// How one label of the image comes out in the mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegionFidelity {
    /// The label's name.
    pub name: String,
    /// Its pixels in the image.
    pub pixels: u64,
    /// The area of the mesh's elements of this label, in square pixels (compare with
    /// `pixels`).
    pub area_px: f64,
    /// How many elements carry it.
    pub elements: usize,
    /// The share of its pixels whose centre lies in an element of this label.
    pub agreement: f64,
}

/// What the quad path adds to the report.
struct QuadExtras {
    optimisation: Optimisation,
    before: QuadQuality,
    histograms: QualityHistograms,
    hausdorff: f64,
}

/// The outcome of a run: the mesh, ready for the writers, and its report.
#[derive(Clone, Debug)]
pub struct PipelineResult {
    /// The labelled mesh (image coordinates).
    pub mesh: SegmentedMeshData,
    /// What happened.
    pub report: Report,
    /// Pictures of every stage, in order (only with [`Pipeline::with_stages`]).
    pub stages: Vec<StagePicture>,
    /// The label image, one colour per label (only with [`Pipeline::with_stages`]).
    pub label_picture: Option<image::RgbImage>,
}

/// A picture of one stage (`--stages`), as the paper's Figures 1–2 show them: elements coloured
/// by label (none for a stage that is only boundaries) and segments drawn over them.
#[derive(Clone, Debug, PartialEq)]
pub struct StagePicture {
    /// A file-name stem that sorts in pipeline order, e.g. `"05-dt"`.
    pub name: String,
    /// Vertices in image coordinates.
    pub vertices: Vec<[f64; 2]>,
    /// Elements.
    pub elements: Vec<Element>,
    /// A label per element.
    pub labels: Vec<u32>,
    /// Segments drawn over the elements.
    pub lines: Vec<[[f64; 2]; 2]>,
}

/// Collects stage pictures when asked to; building one costs nothing otherwise.
struct Pictures {
    on: bool,
    list: Vec<StagePicture>,
}

type Drawing = (Vec<[f64; 2]>, Vec<Element>, Vec<u32>, Vec<[[f64; 2]; 2]>);

impl Pictures {
    fn add(&mut self, name: &str, draw: impl FnOnce() -> Drawing) {
        if self.on {
            let (vertices, elements, labels, lines) = draw();
            self.list.push(StagePicture {
                name: format!("{:02}-{name}", self.list.len() + 1),
                vertices,
                elements,
                labels,
                lines,
            });
        }
    }
}

/// The segments of a graph's edges.
fn segments(points: &[[f64; 2]], edges: impl Iterator<Item = [u32; 2]>) -> Vec<[[f64; 2]; 2]> {
    edges
        .map(|[a, b]| [points[a as usize], points[b as usize]])
        .collect()
}

/// A stage of the pipeline, as the progress callback hears of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Loading and classifying the image.
    Classify,
    /// Imesh sampling, partition and c-edges.
    Sample,
    /// Quality refinement of the triangle mesh.
    Refine,
    /// Curve simplification and fitting.
    Curves,
    /// DT', pairing, templates and boundary adaptation.
    Quads,
    /// Optimisation of the quads.
    Optimise,
    /// Invariant checks and quality measurement.
    Check,
}

impl Stage {
    /// What the stage does, for a progress line.
    pub fn description(self) -> &'static str {
        match self {
            Stage::Classify => "classifying the image",
            Stage::Sample => "sampling (Imesh)",
            Stage::Refine => "refining the triangles",
            Stage::Curves => "simplifying and fitting the boundaries",
            Stage::Quads => "building the quads",
            Stage::Optimise => "optimising the quads",
            Stage::Check => "checking the mesh",
        }
    }
}

/// The progress callback: told each stage as it starts.
type Progress = Arc<dyn Fn(Stage) + Send + Sync>;

/// Image → mesh, with typed options and timed stages.
#[derive(Clone)]
pub struct Pipeline {
    options: MeshOptions,
    progress: Option<Progress>,
    stages: bool,
}

impl std::fmt::Debug for Pipeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pipeline")
            .field("options", &self.options)
            .field("progress", &self.progress.is_some())
            .field("stages", &self.stages)
            .finish()
    }
}

impl Pipeline {
    /// A pipeline with these options.
    pub fn new(options: MeshOptions) -> Self {
        Self {
            options,
            progress: None,
            stages: false,
        }
    }

    /// Also returns a picture of every stage ([`PipelineResult::stages`]).
    #[must_use]
    pub fn with_stages(mut self) -> Self {
        self.stages = true;
        self
    }

    /// Calls `progress` as each stage starts (e.g. to drive a progress bar).
    ///
    /// ```
    /// use std::sync::{Arc, Mutex};
    /// use imesh::{MeshOptions, Pipeline, Stage};
    /// let image = image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(16, 16, |x, _| {
    ///     image::Luma([if x < 8 { 0 } else { 255 }])
    /// }));
    /// let heard = Arc::new(Mutex::new(Vec::new()));
    /// let log = Arc::clone(&heard);
    /// Pipeline::new(MeshOptions::default())
    ///     .with_progress(move |stage| log.lock().unwrap().push(stage))
    ///     .run_image(&image)?;
    /// assert_eq!(heard.lock().unwrap().first(), Some(&Stage::Classify));
    /// assert_eq!(heard.lock().unwrap().last(), Some(&Stage::Check));
    /// # Ok::<(), imesh::PipelineError>(())
    /// ```
    #[must_use]
    pub fn with_progress(mut self, progress: impl Fn(Stage) + Send + Sync + 'static) -> Self {
        self.progress = Some(Arc::new(progress));
        self
    }

    fn stage(&self, stage: Stage) {
        if let Some(progress) = &self.progress {
            progress(stage);
        }
    }

    /// Loads `path` (refusing images above `max_pixels`) and meshes it.
    ///
    /// # Errors
    /// [`PipelineError`], each saying what to change.
    pub fn run_path(&self, path: &Path) -> Result<PipelineResult, PipelineError> {
        let start = Instant::now();
        self.stage(Stage::Classify);
        let image = load_image(path, self.options.max_pixels)?;
        let mut result = self.classify_and_run(&image, imesh_classify::is_lossy_file(path))?;
        let load = start.elapsed().as_secs_f64() - result.report.seconds.total;
        result.report.seconds.classify += load;
        result.report.seconds.total += load;
        result.report.input.path = Some(path.display().to_string());
        Ok(result)
    }

    /// Meshes a decoded image (as losslessly stored: see [`ClassifyOptions::lossy`]).
    ///
    /// # Errors
    /// [`PipelineError`], each saying what to change.
    pub fn run_image(&self, image: &image::DynamicImage) -> Result<PipelineResult, PipelineError> {
        self.stage(Stage::Classify);
        self.classify_and_run(image, false)
    }

    /// Classifies `image` (stored with a lossy codec when `lossy`) and meshes its labels.
    fn classify_and_run(
        &self,
        image: &image::DynamicImage,
        lossy: bool,
    ) -> Result<PipelineResult, PipelineError> {
        let o = &self.options;
        self.check_options()?;
        let start = Instant::now();
        let classifier = Classifier::from_str(&o.classify)?;
        let grid = classify(
            image,
            &classifier,
            &ClassifyOptions {
                max_labels: o.max_labels,
                lossy,
            },
        )?;
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
        self.check_options()?;
        let start = Instant::now();
        let Some((factor, reduced)) = self.reduced(grid) else {
            let mut result = self.mesh_grid(grid, classified)?;
            result.report.counts.image_labels = labels_present(grid);
            return Ok(result);
        };
        let reducing = start.elapsed().as_secs_f64();
        let (sx, sy) = (
            f64::from(grid.width()) / f64::from(reduced.width()),
            f64::from(grid.height()) / f64::from(reduced.height()),
        );
        let on_cells = Pipeline {
            options: self.options.in_cells(sx, sy),
            ..self.clone()
        };
        let mut result = on_cells.mesh_grid(&reduced, classified + reducing)?;
        self.enlarge(&mut result, grid, factor)?;
        result.report.counts.image_labels = labels_present(grid);
        result.report.seconds.total = classified + start.elapsed().as_secs_f64();
        Ok(result)
    }

    /// The reduction of `grid` the options ask for ([`MeshOptions::reduction`]), and the
    /// reduced grid; `None` for none. The automatic factor needs the automatic quad size, whose
    /// widths of regions would take a pass over every pixel: they are measured on the grid
    /// reduced by the bound the pixel count alone gives (the size can only be smaller), which
    /// is kept when the widths agree, and the image reduced again by the smaller factor when
    /// they do not.
    fn reduced(&self, grid: &LabelGrid) -> Option<(u32, LabelGrid)> {
        let o = &self.options;
        let (w, h) = (grid.width(), grid.height());
        let reduce = |f: u32| {
            let cells = |n: u32| (n.saturating_add(f / 2) / f).clamp(1, n.max(1));
            // A grid already as small as the cells would be (a line of pixels) stays as it is.
            (f >= 2 && (cells(w), cells(h)) != (w, h))
                .then(|| imesh_classify::reduce(grid, cells(w), cells(h)))
                .flatten()
                .map(|g| (f, g))
        };
        let factor = |q: f64| (q / AUTO_REDUCTION_SIZE).floor().clamp(0.0, 1e9) as u32;
        match (o.reduction, o.size, o.elements) {
            (Some(f), _, _) => reduce(f),
            (None, ElementSize::Pixels(px), Elements::Quad) => reduce(factor(px)),
            (None, ElementSize::Auto, Elements::Quad) => {
                let by_count = (f64::from(w) * f64::from(h) / AUTO_QUADS).sqrt();
                let (bound, first) = reduce(factor(by_count))?;
                let q = self.quad_size(&first)? * f64::from(w) / f64::from(first.width());
                match factor(q) {
                    f if f >= bound => Some((bound, first)),
                    f => reduce(f),
                }
            }
            _ => None,
        }
    }

    /// Scales the mesh of a reduced grid back onto the pixels of `original` (`factor`: the
    /// reduction), and measures it again there: validity on the image's own domain, quality
    /// (the scales along x and y differ by the rounding of the cell counts), label agreement
    /// against the image's own labels.
    fn enlarge(
        &self,
        result: &mut PipelineResult,
        original: &LabelGrid,
        factor: u32,
    ) -> Result<(), PipelineError> {
        let check = Instant::now();
        let mesh = &mut result.mesh;
        let (w, h) = (f64::from(original.width()), f64::from(original.height()));
        let (cw, ch) = (f64::from(mesh.width), f64::from(mesh.height));
        // (x · W) / w' is exact at x = 0 and x = w': the border stays the border.
        let scale = |v: &mut [f64; 2]| *v = [v[0] * w / cw, v[1] * h / ch];
        mesh.vertices.iter_mut().for_each(scale);
        if let Some(so) = &mut mesh.second_order {
            so.points.iter_mut().for_each(scale);
        }
        // The stage pictures too: drawn over the image's frame, on the reduced labels stretched
        // to it (the cells are what was meshed).
        for stage in &mut result.stages {
            stage.vertices.iter_mut().for_each(scale);
            stage.lines.iter_mut().flatten().for_each(scale);
        }
        let counts = &mut result.report.counts;
        (counts.grid_width, counts.grid_height) = (mesh.width, mesh.height);
        (mesh.width, mesh.height) = (original.width(), original.height());
        (counts.width, counts.height) = (mesh.width, mesh.height);
        counts.reduction = factor;
        let (sx, sy) = (w / cw, h / ch);
        counts.quad_size *= sx;
        counts.dt_spacing *= sx;
        counts.merged_area *= sx * sy;
        counts.blunted_area_px *= sx * sy;
        counts.blunted_depth_px *= sx.max(sy);
        let report = &mut result.report;
        // The options as given, the tolerance as used (in pixels).
        let tolerance = report.options.tolerance.map(|t| t * (sx * sy).sqrt());
        report.options = MeshOptions {
            tolerance,
            ..self.options.clone()
        };
        report.input.width = original.width();
        report.input.height = original.height();
        report.fidelity.boundary_hausdorff_px *= sx.max(sy);
        if let Some(o) = &mut report.optimisation {
            o.corner_shift_px *= sx.max(sy);
        }
        let mesh = &*mesh;
        let (area_ratio, (quality, label_agreement)) = rayon::join(
            || area_ratio(mesh, w, h),
            || {
                rayon::join(
                    || mesh_quality(mesh, self.options.elements),
                    || agreement_with_original(mesh, original),
                )
            },
        );
        report.validation.area_ratio = area_ratio?;
        report.quality = quality;
        (report.label_agreement, report.fidelity.regions) = label_agreement;
        report.fidelity.label_agreement = report.label_agreement;
        report.seconds.check += check.elapsed().as_secs_f64();
        Ok(())
    }

    /// Meshes `grid` as it is (no reduction).
    fn mesh_grid(
        &self,
        grid: &LabelGrid,
        classified: f64,
    ) -> Result<PipelineResult, PipelineError> {
        let o = &self.options;
        self.check_size(grid.width(), grid.height())?;
        let start = Instant::now();
        let quad_size = match o.elements {
            Elements::Quad => self.quad_size(grid),
            Elements::Tri => None,
        };
        let majority = o
            .majority
            .unwrap_or_else(|| quad_size.map_or(0, auto_majority));
        let original = grid;
        let cleaned = self.clean_up(grid, majority, quad_size);
        let (grid, cleaned_pixels) = match &cleaned {
            Some((g, changed)) => (g, *changed),
            None => (grid, 0),
        };
        self.stage(Stage::Sample);
        let sampling = sample(
            grid,
            &SampleOptions {
                te: o.te,
                ..Default::default()
            },
        )?;
        let mut label = partition(grid, &sampling.triangulation);
        let min_width = o
            .min_width
            .unwrap_or_else(|| quad_size.map_or(0.0, |q| self.auto_min_width(q)));
        let (w, h) = (grid.width(), grid.height());
        let mut merged = match o.elements {
            Elements::Quad => merge_thin_regions(&sampling.triangulation, &mut label, min_width),
            Elements::Tri => MergeReport::default(),
        };
        let sampled = start.elapsed().as_secs_f64();
        let curves = match o.elements {
            Elements::Quad => {
                self.stage(Stage::Curves);
                let t = &sampling.triangulation;
                let (c, m) = self.curves_wide_enough(t, &mut label, w, h, quad_size, min_width)?;
                merged.regions += m.regions;
                merged.area += m.area;
                Some(c)
            }
            Elements::Tri => None,
        };
        let mut segmented = SegmentedMesh::from_partition(sampling, label, w, h)?;
        let mut seconds = StageSeconds {
            classify: classified,
            sample: sampled,
            curves: start.elapsed().as_secs_f64() - sampled,
            ..Default::default()
        };
        let mut counts = Counts {
            width: w,
            height: h,
            reduction: 1,
            grid_width: w,
            grid_height: h,
            labels: grid.num_labels(),
            sampled_vertices: segmented.inserted,
            merged_regions: merged.regions,
            merged_area: merged.area,
            quad_size: quad_size.unwrap_or(0.0),
            c_edges: segmented.c_edges.len(),
            cleaned_pixels,
            ..Default::default()
        };
        let mut pictures = Pictures {
            on: self.stages,
            list: Vec::new(),
        };
        let label_picture = self.stages.then(|| {
            image::RgbImage::from_fn(w, h, |x, y| {
                let l = grid.label(x, y) as usize;
                image::Rgb(grid.regions().get(l).map_or([128; 3], |r| r.colour))
            })
        });
        let c_edge_lines = |segmented: &SegmentedMesh| {
            let points: Vec<[f64; 2]> = segmented
                .triangulation
                .points()
                .iter()
                .map(|p| [p.x, p.y])
                .collect();
            segments(
                &points,
                segmented
                    .c_edges
                    .iter()
                    .map(|e| e.vertices.map(|v| v.index() as u32)),
            )
        };
        pictures.add("imesh", || {
            let (vertices, triangles, labels) = segmented.arrays();
            let elements = triangles.into_iter().map(Element::Triangle).collect();
            (vertices, elements, labels, c_edge_lines(&segmented))
        });
        pictures.add("c-edges", || {
            (Vec::new(), Vec::new(), Vec::new(), c_edge_lines(&segmented))
        });
        let mut optimised = None;
        let (vertices, elements, labels, curved) = match curves {
            None => self.triangles(&mut segmented, &mut counts, &mut seconds)?,
            Some(curves) => self.quads(
                curves,
                quad_size,
                &mut counts,
                &mut seconds,
                &mut optimised,
                &mut pictures,
            )?,
        };
        pictures.add("result", || {
            (
                vertices.clone(),
                elements.clone(),
                labels.clone(),
                Vec::new(),
            )
        });
        let check = Instant::now();
        self.stage(Stage::Check);
        let mut mesh = SegmentedMeshData {
            vertices,
            elements,
            labels,
            label_names: grid.regions().iter().map(|r| r.name.clone()).collect(),
            label_colours: grid.regions().iter().map(|r| r.colour).collect(),
            width: w,
            height: h,
            second_order: None,
        };
        if o.order == 2 {
            let so = SecondOrder::new(&mesh, &curved);
            counts.curved_sides = so.curved;
            counts.damped_sides = so.damped;
            counts.straightened_sides = so.straightened;
            mesh.second_order = Some(so);
        }
        counts.nodes = mesh.node_count();
        counts.vertices = mesh.vertices.len();
        counts.elements = mesh.elements.len();
        counts.quads = mesh
            .elements
            .iter()
            .filter(|e| matches!(e, Element::Quad(_)))
            .count();
        counts.triangles = mesh.elements.len() - counts.quads;
        counts.meshed_labels = mesh.used_labels().len();
        // The checks and measures of the written mesh read it only: side by side.
        let ((area_ratio, quality), (sharpest_boundary_corner, label_agreement)) = rayon::join(
            || {
                rayon::join(
                    || area_ratio(&mesh, f64::from(w), f64::from(h)),
                    || mesh_quality(&mesh, o.elements),
                )
            },
            || {
                rayon::join(
                    || sharpest_boundary_corner(&mesh),
                    // Against the image's own labels, so that the clean-up's changes count as
                    // disagreement.
                    || match &cleaned {
                        Some(_) => agreement_with_original(&mesh, original),
                        None => region_fidelity(&mesh, grid),
                    },
                )
            },
        );
        let area_ratio = area_ratio?;
        seconds.check = check.elapsed().as_secs_f64();
        seconds.total = classified + start.elapsed().as_secs_f64();
        let report = Report {
            options: MeshOptions {
                tolerance: Some(self.tolerance()),
                ..o.clone()
            },
            counts,
            seconds,
            imesh_version: env!("CARGO_PKG_VERSION"),
            input: Input {
                path: None,
                width: w,
                height: h,
            },
            label_agreement: label_agreement.0,
            fidelity: Fidelity {
                label_agreement: label_agreement.0,
                boundary_hausdorff_px: optimised.as_ref().map_or(0.0, |x| x.hausdorff),
                regions: label_agreement.1,
            },
            quality,
            sharpest_boundary_corner,
            quality_before_optimisation: optimised
                .as_ref()
                .map(|x| MeshQuality::Quads(x.before.clone())),
            histograms: optimised.as_ref().map(|x| x.histograms.clone()),
            optimisation: optimised.map(|x| x.optimisation),
            validation: Validation {
                valid: true,
                area_ratio,
            },
        };
        Ok(PipelineResult {
            mesh,
            report,
            stages: pictures.list,
            label_picture,
        })
    }

    /// The Imesh triangle output: label-aware Ruppert refinement.
    fn triangles(
        &self,
        segmented: &mut SegmentedMesh,
        counts: &mut Counts,
        seconds: &mut StageSeconds,
    ) -> Result<MeshArrays, PipelineError> {
        let o = &self.options;
        let start = Instant::now();
        self.stage(Stage::Refine);
        let refined = segmented.refine(&RefineOptions {
            min_angle_deg: o.min_angle.unwrap_or(imesh_segment::DEFAULT_MIN_ANGLE),
            max_steiner: self.refinement_cap(),
            max_area: o.max_size.map(equilateral_area),
        })?;
        let triangles = segmented.triangulation.num_triangles() as u64;
        if triangles > o.max_elements
            || (refined.stopped == StopReason::CapReached
                && o.max_steiner.is_none_or(|n| n > self.refinement_cap()))
        {
            return Err(self.too_many_elements(triangles.max(o.max_elements + 1), "triangles"));
        }
        seconds.refine = start.elapsed().as_secs_f64();
        counts.refinement_points = refined.inserted;
        counts.triangles_below_min_angle = if refined.stopped == StopReason::Done {
            refined.bad_left
        } else {
            0
        };
        let (vertices, triangles, labels) = segmented.arrays();
        let elements = triangles.iter().map(|&t| Element::Triangle(t)).collect();
        Ok((vertices, elements, labels, Vec::new()))
    }

    /// The curve stage of the quad output: the boundary graph G of the partition `label` of
    /// `t`, its short links contracted (uniform quads), simplified into G'.
    fn curves(
        &self,
        t: &Triangulation,
        label: &[u32],
        width: u32,
        height: u32,
        quad_size: Option<f64>,
    ) -> Result<Curves, PipelineError> {
        let g = graph_of_c_edges(t, &c_edges(t, label), width, height)?;
        let (g, contracted) = match quad_size {
            // Junctions closer than a fraction of a quad (four regions meeting at a pixel
            // corner) would pin a boundary piece that short, and quads that small around it.
            Some(q) => {
                let c = contract_short_links(
                    &g,
                    LINK_SHARE * q,
                    self.tolerance(),
                    f64::from(width),
                    f64::from(height),
                )?;
                (c.graph, c.contracted)
            }
            None => (g, 0),
        };
        let simplified = simplify(&g, &self.simplify_options(quad_size))?;
        Ok(Curves {
            g,
            simplified,
            contracted,
            necks: 0,
            sharp: 0,
        })
    }

    /// The curve tolerance in pixels of the grid meshed.
    fn tolerance(&self) -> f64 {
        self.options
            .tolerance
            .unwrap_or(imesh_curves::DEFAULT_TOLERANCE)
    }

    /// The simplification options: the tolerance, and pieces of at least a quad side (uniform
    /// quads).
    fn simplify_options(&self, quad_size: Option<f64>) -> SimplifyOptions {
        SimplifyOptions {
            tolerance: self.tolerance(),
            min_length: quad_size.map_or(0.0, |q| MIN_PIECE * q),
        }
    }

    /// [`Pipeline::curves`], then, while G' has faces narrower than `min_width` (simplification
    /// may flatten a region the partition found wide enough into a sliver: its tolerance is
    /// about a quad side), their regions merged into their neighbours and the curves drawn
    /// again, at most [`THIN_FACE_ROUNDS`] times (merged regions are gone for good, so a few
    /// rounds suffice). Then, with uniform quads, where a simplified edge cuts within
    /// [`NECK_SHARE`] quad sides of another boundary's vertex, the edge keeps the vertex of its
    /// chain nearest to it ([`neck_vertices`], pinned), and where two simplified edges leave a
    /// vertex in a sharp sector the boundaries leave wider, each keeps its chain's first vertex
    /// [`SHARP_LENGTH`] quad sides away ([`sharp_vertices`], pinned); the curves are then
    /// simplified again, at most [`NECK_ROUNDS`] times. Returns the curves and what the merges
    /// did.
    fn curves_wide_enough(
        &self,
        t: &Triangulation,
        label: &mut [u32],
        width: u32,
        height: u32,
        quad_size: Option<f64>,
        min_width: f64,
    ) -> Result<(Curves, MergeReport), PipelineError> {
        let mut merged = MergeReport::default();
        let mut c = self.curves(t, label, width, height, quad_size)?;
        for _ in 0..THIN_FACE_ROUNDS {
            let thin = thin_faces(&c.simplified, t, label, min_width);
            let m = merge_regions(t, label, min_width, &thin);
            if m.regions == 0 {
                break;
            }
            merged.regions += m.regions;
            merged.area += m.area;
            c = self.curves(t, label, width, height, quad_size)?;
        }
        if let Some(q) = quad_size {
            for _ in 0..NECK_ROUNDS {
                let necks = neck_vertices(&c.g, &c.simplified, NECK_SHARE * q);
                let sharp = sharp_vertices(&c.g, &c.simplified, SHARP_LENGTH * q);
                if necks.is_empty() && sharp.is_empty() {
                    break;
                }
                c.necks += necks.len();
                c.sharp += sharp.len();
                for v in necks.into_iter().chain(sharp) {
                    c.g.pin(v)?;
                }
                c.simplified = simplify(&c.g, &self.simplify_options(quad_size))?;
            }
        }
        Ok((c, merged))
    }

    /// The quad output: curve fitting, DT', pairing, templates, boundary adaptation and
    /// optimisation, from the curve stage's G'.
    fn quads(
        &self,
        curves: Curves,
        quad_size: Option<f64>,
        counts: &mut Counts,
        seconds: &mut StageSeconds,
        optimised: &mut Option<QuadExtras>,
        pictures: &mut Pictures,
    ) -> Result<MeshArrays, PipelineError> {
        let o = &self.options;
        let start = Instant::now();
        let Curves {
            g,
            simplified,
            contracted,
            necks,
            sharp,
        } = curves;
        counts.contracted_links = contracted;
        counts.kept_at_necks = necks;
        counts.kept_at_sharp_sectors = sharp;
        let mut fits = fit_edges(&simplified, &g, &FitOptions::default());
        // Sharp corners opened within the tolerance, measured about one quad side out (where
        // the first element edge along a boundary ends); the image's border stays straight.
        let corners = open_sharp_corners(
            &simplified,
            &g,
            &mut fits,
            &CornerOptions {
                tolerance: self.tolerance(),
                reach: quad_size.unwrap_or(self.tolerance()),
                ..CornerOptions::default()
            },
            |k| {
                simplified.graph.edges()[k as usize]
                    .labels
                    .contains(&OUTSIDE)
            },
        );
        counts.opened_corners = corners.sharp;
        counts.turned_curves = corners.refitted;
        let curves: Vec<_> = fits.fits.iter().map(|f| f.curve).collect();
        // Sharp tips the curves could not open are cut off where they are one to two quad sides
        // wide (uniform quads only).
        let tips = quad_size.filter(|_| !o.keep_sharp_tips).and_then(|q| {
            blunt_sharp_tips(
                &simplified.graph,
                &curves,
                &TipOptions {
                    width: q,
                    reach: q,
                    ..TipOptions::default()
                },
            )
        });
        let (graph, curves, tip_moved) = match tips {
            Some(b) => {
                counts.blunted_tips = b.tips;
                counts.blunted_area_px = b.area;
                counts.blunted_depth_px = b.moved;
                (b.graph, b.curves, b.moved)
            }
            None => (simplified.graph, curves, 0.0),
        };
        let fitting = start.elapsed().as_secs_f64();
        seconds.curves += fitting;
        pictures.add("simplified", || {
            let points: Vec<[f64; 2]> = graph.points().iter().map(|p| [p.x, p.y]).collect();
            let lines = segments(&points, graph.edges().iter().map(|e| e.ends));
            (Vec::new(), Vec::new(), Vec::new(), lines)
        });
        self.stage(Stage::Quads);
        let quad_size = match (quad_size, o.size) {
            (Some(q), ElementSize::Auto) => {
                let (w, h) = (f64::from(counts.width), f64::from(counts.height));
                let q = band_limited_size(&graph, w, h, q);
                counts.quad_size = q;
                Some(q)
            }
            (q, _) => q,
        };
        let spacing = quad_size.map(|q| 2.0 * f64::from(o.template_level) * q);
        let remesh_with = |lattice_scale: f64| {
            remesh(
                &graph,
                &curves,
                &QuadOptions {
                    density: DensityOptions {
                        min_angle_deg: o
                            .min_angle
                            .unwrap_or(DensityOptions::default().min_angle_deg),
                        max_steiner: self.refinement_cap(),
                        max_size: o.max_size,
                        spacing,
                        lattice_scale,
                    },
                    pairing: match o.pairing {
                        PairingMethod::Greedy => Pairing::Greedy,
                        PairingMethod::Matching => Pairing::Matching,
                        PairingMethod::Fewest => Pairing::Fewest,
                    },
                    level: o.template_level,
                    max_quads: o.max_elements,
                },
            )
            .map_err(|e| match e {
                imesh_quad::QuadError::TooManyQuads { quads, .. } => {
                    self.too_many_elements(quads, "quads")
                }
                imesh_quad::QuadError::LatticeTooFine { points, .. } => {
                    self.too_many_elements(points, "vertices")
                }
                e => PipelineError::Quads(e),
            })
        };
        let mut r = remesh_with(1.0)?;
        counts.lattice_scale = 1.0;
        if spacing.is_some() {
            // The lattice's quads should have the mesh's mean area: where the band along the
            // boundaries makes the mean differ from them (the median quad is a lattice quad),
            // lattices scaled towards it are tried, and the mesh with the highest mean
            // shape-and-size (before optimisation) kept. The mean follows the lattice (most
            // quads are its squares), so each try steps LATTICE_STEP times the ratio's log.
            // A try is only a try: a finer lattice over a limit (`--max-steiner`,
            // `--max-elements`) leaves the best so far.
            let (mut median, mut mean) = median_and_mean_area(&r.mesh);
            let mut best = mean_shape_and_size(&r.mesh, mean);
            let mut scale = 1.0;
            for _ in 0..LATTICE_TRIES {
                if !(median > 0.0 && (mean / median - 1.0).abs() > LATTICE_MATCH) {
                    break;
                }
                scale = (scale * (mean / median).powi(LATTICE_STEP))
                    .clamp(1.0 / MAX_LATTICE_SCALE, MAX_LATTICE_SCALE);
                let Ok(other) = remesh_with(scale) else { break };
                (median, mean) = median_and_mean_area(&other.mesh);
                let score = mean_shape_and_size(&other.mesh, mean);
                if score > best {
                    best = score;
                    r = other;
                    counts.lattice_scale = scale;
                }
            }
        }
        seconds.quads = start.elapsed().as_secs_f64() - fitting;
        seconds.triangulate = r.seconds.triangulation;
        seconds.pairing = r.seconds.pairing;
        seconds.templates = r.seconds.templates;
        seconds.adapt = r.seconds.adaptation;
        counts.simplified_edges = graph.edges().len();
        counts.dt_triangles = r.dt.triangulation.num_triangles();
        counts.dt_spacing = spacing.unwrap_or(0.0);
        counts.refinement_points = r.dt.refinement.inserted;
        counts.unpaired_triangles = r.elements.unpaired;
        counts.damped_curves = r.adaptation.damped_curves;
        if r.adaptation.invalid_left > 0 {
            return Err(PipelineError::Invalid(format!(
                "{} quads stayed inverted after boundary adaptation",
                r.adaptation.invalid_left
            )));
        }
        let straight: Vec<[f64; 2]> = if pictures.on {
            r.straight_vertices.iter().map(|p| [p.x, p.y]).collect()
        } else {
            Vec::new()
        };
        let graph_lines = || {
            let points: Vec<[f64; 2]> = graph.points().iter().map(|p| [p.x, p.y]).collect();
            segments(&points, graph.edges().iter().map(|e| e.ends))
        };
        pictures.add("dt", || {
            let t = &r.dt.triangulation;
            let points: Vec<[f64; 2]> = t.points().iter().map(|p| [p.x, p.y]).collect();
            let (mut elements, mut labels) = (Vec::new(), Vec::new());
            for f in t.triangles() {
                elements.push(Element::Triangle(
                    t.triangle_vertices(f).map(|v| v.index() as u32),
                ));
                labels.push(t.label(f));
            }
            (points, elements, labels, graph_lines())
        });
        pictures.add("pairing", || {
            let elements = r
                .elements
                .elements
                .iter()
                .map(|e| match *e {
                    imesh_quad::Element::Triangle(c) => Element::Triangle(c),
                    imesh_quad::Element::Quad(c) => Element::Quad(c),
                })
                .collect();
            (
                straight.clone(),
                elements,
                r.elements.labels.clone(),
                graph_lines(),
            )
        });
        let quad_elements = || r.mesh.quads.iter().map(|&q| Element::Quad(q)).collect();
        pictures.add("templates", || {
            (
                straight.clone(),
                quad_elements(),
                r.mesh.labels.clone(),
                Vec::new(),
            )
        });
        pictures.add("adapted", || {
            let points = r.mesh.vertices.iter().map(|p| [p.x, p.y]).collect();
            (points, quad_elements(), r.mesh.labels.clone(), Vec::new())
        });
        self.stage(Stage::Optimise);
        let optimisation = optimise(
            &mut r,
            &OptimOptions {
                method: o.optimizer.method(),
                metric: match o.metric {
                    MetricName::ShapeAndSize => Metric::ShapeAndSize,
                    MetricName::Shape => Metric::Shape,
                },
                global_iterations: o.global_iterations,
                corner_reach: o.corner_reach,
                ..OptimOptions::default()
            },
        )?;
        seconds.optimise = optimisation.seconds;
        *optimised = Some(QuadExtras {
            // A corner the repair moved takes the boundary beside it that far at most.
            hausdorff: fits.max_error.max(fits.max_curve_deviation).max(tip_moved)
                + optimisation.corner_shift,
            optimisation: Optimisation {
                method: o.optimizer,
                metric: o.metric,
                variables: optimisation.variables,
                colours: optimisation.colours,
                energy_before: optimisation.energy_before,
                energy_after: optimisation.energy_after,
                sweeps: optimisation.sweeps,
                sliders: optimisation.sliders,
                repaired: optimisation.repaired,
                repaired_sliders: optimisation.repaired_sliders,
                quality_repaired: optimisation.quality_repaired,
                moved_corners: optimisation.moved_corners,
                corner_shift_px: optimisation.corner_shift,
            },
            before: optimisation.before,
            histograms: QualityHistograms {
                shape_and_size_before: optimisation.histograms_before.shape_and_size,
                shape_and_size_after: optimisation.histograms_after.shape_and_size,
                scaled_jacobian_before: optimisation.histograms_before.scaled_jacobian,
                scaled_jacobian_after: optimisation.histograms_after.scaled_jacobian,
            },
        });
        let vertices = r.mesh.vertices.iter().map(|p| [p.x, p.y]).collect();
        let elements = r.mesh.quads.iter().map(|&q| Element::Quad(q)).collect();
        // The middle of each quad side along a boundary curve, where the optimiser's sliding left
        // its two ends on the curve (second order).
        let curved = if o.order == 2 {
            let chains = optimisation.boundary.unwrap_or_else(|| r.boundary_chains());
            chains
                .iter()
                .flat_map(|c| c.middles().map(|(e, p)| (e, [p.x, p.y])))
                .collect()
        } else {
            Vec::new()
        };
        Ok((vertices, elements, r.mesh.labels, curved))
    }

    /// The label grid after the clean-up the options ask for (a majority filter, the border's
    /// thin parts, for quads of side `quad_size` the thin parts of
    /// [`MeshOptions::min_part_width`], then merging small regions), with the number of pixels
    /// whose label changed; `None` without clean-up.
    fn clean_up(
        &self,
        grid: &LabelGrid,
        majority: u32,
        quad_size: Option<f64>,
    ) -> Option<(LabelGrid, usize)> {
        let o = &self.options;
        let thin_parts = quad_size.map(|q| {
            let width = o.min_part_width.unwrap_or(THIN_PART_SHARE * q);
            (width, (THIN_PART_AREA * q * q).round() as usize)
        });
        // A disk of radius under a pixel is its pixel alone: every part is covered.
        let thin_parts = thin_parts.filter(|&(width, _)| width >= 2.0);
        if majority == 0 && o.min_region <= 1 && thin_parts.is_none() {
            return None;
        }
        let mut cleaned = grid.clone();
        if majority > 0 {
            cleaned = imesh_classify::majority_filter(&cleaned, majority, 1);
            // Parts of at least a quad's area (the filter's radius is about a quad side): a
            // smaller one holds a few small quads at most, and keeps its pixels.
            let mut half_width = BORDER_SLIVER * f64::from(majority);
            if majority >= 3 {
                half_width = half_width.max(MIN_BORDER_SLIVER_PX);
            }
            cleaned = imesh_classify::remove_border_slivers(
                &cleaned,
                half_width,
                (majority * majority) as usize,
            );
        }
        if let Some((width, least)) = thin_parts {
            cleaned = imesh_classify::remove_thin_parts(&cleaned, width / 2.0, least);
        }
        if o.min_region > 1 {
            cleaned = imesh_classify::remove_small_regions(&cleaned, o.min_region);
        }
        let changed = relabelled_pixels(grid, &cleaned);
        Some((cleaned, changed))
    }

    /// The side of the quads of a uniform mesh, in pixels (`None` when graded). `auto` takes
    /// the smaller of two sizes, and at least [`MIN_AUTO_SIZE`]: the one that gives about
    /// [`AUTO_QUADS`] quads over the image, and [`AUTO_WIDTH_SHARE`] of the width under which a
    /// quarter of the boundaries lie ([`boundary_weighted_width`] of the label grid's regions,
    /// before any clean-up), so that most regions are crossed by several quads.
    fn quad_size(&self, grid: &LabelGrid) -> Option<f64> {
        match self.options.size {
            ElementSize::Graded => None,
            ElementSize::Pixels(px) => Some(px),
            ElementSize::Auto => {
                let area = f64::from(grid.width()) * f64::from(grid.height());
                let by_count = (area / AUTO_QUADS).sqrt();
                let regions = imesh_classify::pixel_regions(grid);
                let widths = regions.iter().map(|r| (r.width(), r.perimeter as f64));
                let narrowest = 2.0 * AUTO_MIN_WIDTH * MIN_AUTO_SIZE;
                let by_width = AUTO_WIDTH_SHARE * boundary_weighted_width(widths, 0.25, narrowest);
                Some(by_count.min(by_width).max(MIN_AUTO_SIZE))
            }
        }
    }

    /// The automatic `min_width` for quads of side `q` chosen from the image (or given):
    /// [`THIN_REGION_SHARE`] of the finest side the mesh can end with (with `--size auto`, the
    /// band limit may refine `q` down to `q /` [`AUTO_BAND_REFINEMENT`], never below
    /// [`MIN_AUTO_SIZE`]).
    fn auto_min_width(&self, q: f64) -> f64 {
        let finest = match self.options.size {
            ElementSize::Auto => (q / AUTO_BAND_REFINEMENT).max(MIN_AUTO_SIZE.min(q)),
            _ => q,
        };
        THIN_REGION_SHARE * finest
    }

    /// The refinement's point cap: the user's, and never more than the element limit (every
    /// inserted point adds about two triangles).
    fn refinement_cap(&self) -> usize {
        let o = &self.options;
        let limit = usize::try_from(o.max_elements).unwrap_or(usize::MAX);
        o.max_steiner.unwrap_or(usize::MAX).min(limit)
    }

    fn too_many_elements(&self, at_least: u64, kind: &str) -> PipelineError {
        PipelineError::Limit(format!(
            "the mesh would have at least {at_least} {kind}, over the limit of {} elements: \
             raise --max-elements, or give a larger --size, --max-size, --tolerance or --te, or \
             a lower --template-level",
            self.options.max_elements
        ))
    }

    /// Refuses, before any work, a run whose element count is sure to exceed the limit: with a
    /// largest size, DT' (or the triangle mesh) needs at least the domain's area over the
    /// largest triangle's, and pairing at best halves that before the templates multiply it.
    fn check_size(&self, width: u32, height: u32) -> Result<(), PipelineError> {
        let o = &self.options;
        let Some(size) = o.max_size else {
            return Ok(());
        };
        let triangles = (f64::from(width) * f64::from(height) / equilateral_area(size)).floor();
        let k2 = f64::from(o.template_level).powi(2);
        let (at_least, kind) = match o.elements {
            Elements::Tri => (triangles, "triangles"),
            Elements::Quad => (2.0 * k2 * triangles, "quads"),
        };
        if at_least > o.max_elements as f64 {
            return Err(self.too_many_elements(at_least.min(u64::MAX as f64) as u64, kind));
        }
        Ok(())
    }

    fn check_options(&self) -> Result<(), PipelineError> {
        let o = &self.options;
        if !(1..=8).contains(&o.template_level) {
            return Err(PipelineError::Options(format!(
                "template level {} is out of range: give 1 to 8",
                o.template_level
            )));
        }
        if !(1..=2).contains(&o.order) {
            return Err(PipelineError::Options(format!(
                "element order {} is not made: give 1 (linear) or 2 (quadratic)",
                o.order
            )));
        }
        if let Some(r) = o.majority.filter(|&r| r > MAX_MAJORITY) {
            return Err(PipelineError::Options(format!(
                "the majority filter radius {r} is too large: give 0 to {MAX_MAJORITY} pixels \
                 (use --min-region for larger specks)"
            )));
        }
        if o.reduction == Some(0) {
            return Err(PipelineError::Options(
                "a reduction of 0 means nothing: give auto, 1 (mesh every pixel) or a factor of \
                 2 or more"
                    .into(),
            ));
        }
        if let Some(w) = o.min_width.filter(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(PipelineError::Options(format!(
                "the smallest region width must be a distance in pixels ≥ 0 (0 keeps every \
                 region), not {w}"
            )));
        }
        if let Some(w) = o.min_part_width.filter(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(PipelineError::Options(format!(
                "the smallest part width must be a distance in pixels ≥ 0 (0 keeps every part), \
                 not {w}"
            )));
        }
        if !(o.corner_reach.is_finite() && (0.0..=1.0).contains(&o.corner_reach)) {
            return Err(PipelineError::Options(format!(
                "the corner reach must be a share of the quad side from 0 (corners stay where \
                 the boundaries put them) to 1, not {}",
                o.corner_reach
            )));
        }
        if let Some(t) = o.tolerance.filter(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(PipelineError::Options(format!(
                "the curve tolerance must be a distance in pixels ≥ 0, not {t}"
            )));
        }
        if let Some(s) = o.max_size {
            if !(s.is_finite() && s > 0.0) {
                return Err(PipelineError::Options(format!(
                    "the largest element size must be a positive number of pixels, not {s}"
                )));
            }
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
        if !o.origin.iter().all(|x| x.is_finite()) {
            return Err(PipelineError::Options(format!(
                "the origin must be two finite numbers, not {:?}",
                o.origin
            )));
        }
        Ok(())
    }
}

impl MeshOptions {
    /// These options for a grid of cells `sx × sy` pixels each ([`MeshOptions::reduction`]):
    /// the lengths and areas given in pixels become cells; the defaults stay, so that they
    /// scale with the cells (the 2-pixel curve tolerance becomes 2 cells).
    fn in_cells(&self, sx: f64, sy: f64) -> MeshOptions {
        let s = (sx * sy).sqrt();
        MeshOptions {
            size: match self.size {
                ElementSize::Pixels(px) => ElementSize::Pixels(px / s),
                other => other,
            },
            tolerance: self.tolerance.map(|t| t / s),
            majority: self.majority.map(|r| (f64::from(r) / s).round() as u32),
            min_width: self.min_width.map(|w| w / s),
            min_part_width: self.min_part_width.map(|w| w / s),
            min_region: (self.min_region as f64 / (sx * sy)).ceil() as usize,
            max_size: self.max_size.map(|m| m / s),
            ..self.clone()
        }
    }
}

/// The output mesh's vertices, elements and labels, and the points on the boundary curves where
/// second-order sides put their middle nodes.
type MeshArrays = (
    Vec<[f64; 2]>,
    Vec<Element>,
    Vec<u32>,
    Vec<([u32; 2], [f64; 2])>,
);

/// How many labels of `grid` have a pixel.
fn labels_present(grid: &LabelGrid) -> usize {
    grid.counts().iter().filter(|&&n| n > 0).count()
}

/// How many pixels of `cleaned` have a region other than in `grid`. Labels are renumbered
/// when regions vanish, so regions are compared by name (each name given one number first,
/// rather than comparing strings per pixel).
fn relabelled_pixels(grid: &LabelGrid, cleaned: &LabelGrid) -> usize {
    let mut numbers = std::collections::HashMap::new();
    let mut number = |g: &LabelGrid| -> Vec<usize> {
        g.regions()
            .iter()
            .map(|r| {
                let next = numbers.len();
                *numbers.entry(r.name.clone()).or_insert(next)
            })
            .collect()
    };
    let (before, after) = (number(grid), number(cleaned));
    // A label without a region (none in a valid grid) has no name, as `usize::MAX`.
    let name = |names: &[usize], l: u32| names.get(l as usize).copied().unwrap_or(usize::MAX);
    grid.labels()
        .par_iter()
        .zip(cleaned.labels())
        .filter(|&(&a, &b)| name(&before, a) != name(&after, b))
        .count()
}

/// The radius of the majority filter that `--majority auto` applies before a uniform mesh of
/// quad side `quad_size`: about one quad, so that notches, specks and strips the quads could
/// only follow with small elements are smoothed away (1 to [`MAX_MAJORITY`] pixels).
///
/// ```
/// assert_eq!(imesh::auto_majority(2.56), 3);
/// assert_eq!(imesh::auto_majority(0.3), 1);
/// assert_eq!(imesh::auto_majority(40.0), imesh::MAX_MAJORITY);
/// ```
pub fn auto_majority(quad_size: f64) -> u32 {
    (quad_size.round().max(1.0) as u32).min(MAX_MAJORITY)
}

/// A uniform mesh whose median quad area (a lattice quad's) is off the mean by more than this
/// share is meshed again with its lattice scaled towards the mean, at most [`LATTICE_TRIES`]
/// times, and the try with the highest mean shape-and-size before optimisation kept (on nine
/// fixtures with the lattice scaled by 0.985, 1, 1.015, 1.03 and 1.05, that mean picked the
/// best scale after optimisation on seven). 1 % with one try until session 57, which lowered it
/// with the tries of [`LATTICE_STEP`] (docs/measurements.md).
pub const LATTICE_MATCH: f64 = 0.002;

/// The most lattices [`LATTICE_MATCH`] tries after the first mesh. Each costs one more DT',
/// pairing, templates and adaptation (about 7 % of a run); on seven sets of 150 random images
/// the mean of the means rose by 0.0007–0.0015 with two tries of the plain ratio, by
/// 0.0010–0.0021 with three, and by 0.0013–0.0028 with two of [`LATTICE_STEP`] 3.
pub const LATTICE_TRIES: usize = 2;

/// Each lattice try scales the spacing by (mean / median)^LATTICE_STEP. The mean follows the
/// lattice, since most quads are its squares: scaled by the plain area ratio, the camera's
/// median went from 1.013 to 1.010 of the mean, and three tries reached 1.002. Steps of 2 and 3
/// measured; 3 kept (docs/measurements.md, session 57).
pub const LATTICE_STEP: i32 = 3;

/// The most the lattice is scaled either way by [`LATTICE_MATCH`]'s tries.
pub const MAX_LATTICE_SCALE: f64 = 1.1;

/// The median and the mean quad area of `mesh` (0 for no quad).
fn median_and_mean_area(mesh: &imesh_quad::QuadMesh) -> (f64, f64) {
    let mut areas: Vec<f64> = mesh
        .quads
        .iter()
        .map(|quad| imesh_quality::quad::area(&corners(mesh, quad)))
        .collect();
    if areas.is_empty() {
        return (0.0, 0.0);
    }
    let mean = areas.iter().sum::<f64>() / areas.len() as f64;
    let middle = areas.len() / 2;
    let (_, median, _) = areas.select_nth_unstable_by(middle, f64::total_cmp);
    (*median, mean)
}

/// The corners of `quad` of `mesh`, as the quality metrics take them.
fn corners(mesh: &imesh_quad::QuadMesh, quad: &[u32; 4]) -> [[f64; 2]; 4] {
    quad.map(|v| [mesh.vertices[v as usize].x, mesh.vertices[v as usize].y])
}

/// The mean shape-and-size of `mesh`'s quads against their mean area, `mean`.
fn mean_shape_and_size(mesh: &imesh_quad::QuadMesh, mean: f64) -> f64 {
    let sum: f64 = mesh
        .quads
        .iter()
        .map(|quad| imesh_quality::quad::shape_and_size(&corners(mesh, quad), mean))
        .sum();
    sum / mesh.quads.len().max(1) as f64
}

/// The quad side for a uniform mesh of the `width` × `height` domain whose boundaries are `g`
/// (G'), given the side `quad_size` chosen from the image: `quad_size` itself, unless the quads
/// along the boundaries would be more than [`AUTO_BAND_SHARE`] of them; then smaller, down to
/// `quad_size /` [`AUTO_BAND_REFINEMENT`] and not below [`MIN_AUTO_SIZE`] (nor `quad_size`).
///
/// A uniform mesh of side `s` has about `A / s²` quads and a row of `L / s` along each side of
/// boundaries of length `L`: the row's share is `2 L s / A`. Edges along the image border do
/// not count (the lattice meets the border square on).
///
/// ```
/// use imesh::{band_limited_size, AUTO_BAND_SHARE};
/// use imesh_curves::{CurveGraph, GraphEdge};
/// use imesh_geom::Point;
/// // A 100 × 100 image cut in two by a vertical boundary, with its border.
/// let points = [(0.0, 0.0), (50.0, 0.0), (100.0, 0.0), (100.0, 100.0), (50.0, 100.0), (0.0, 100.0)]
///     .map(|(x, y)| Point::new(x, y))
///     .to_vec();
/// let ring = [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 0]];
/// let mut edges: Vec<GraphEdge> = ring.iter().map(|&ends| GraphEdge { ends, labels: [0, 9] }).collect();
/// edges.push(GraphEdge { ends: [1, 4], labels: [0, 1] });
/// let g = CurveGraph::new(points, edges)?;
/// // One boundary of length 100: quads of 10 px would put 2 · 100 · 10 / 10⁴ = 20 % along it.
/// let s = band_limited_size(&g, 100.0, 100.0, 10.0);
/// assert!((s - AUTO_BAND_SHARE * 1e4 / 200.0).abs() < 1e-12);
/// // Quads of 5 px put 10 % along it: kept.
/// assert_eq!(band_limited_size(&g, 100.0, 100.0, 5.0), 5.0);
/// # Ok::<(), imesh_curves::CurveError>(())
/// ```
pub fn band_limited_size(g: &CurveGraph, width: f64, height: f64, quad_size: f64) -> f64 {
    let points = g.points();
    let domain = Domain::image(width, height);
    let length: f64 = g
        .edges()
        .iter()
        .map(|e| {
            let [a, b] = e.ends.map(|v| points[v as usize]);
            if domain.on_border([a.x, a.y], [b.x, b.y]) {
                0.0
            } else {
                a.distance_squared(b).sqrt()
            }
        })
        .sum();
    if !(length > 0.0 && quad_size > 0.0) {
        return quad_size;
    }
    let by_band = AUTO_BAND_SHARE * width * height / (2.0 * length);
    let floor = (quad_size / AUTO_BAND_REFINEMENT).max(MIN_AUTO_SIZE.min(quad_size));
    quad_size.min(by_band.max(floor))
}

/// The width below which a share `share` of the boundaries lie: `(width, perimeter)` of each
/// region, sorted by width and weighted by perimeter (a boundary counts once for each region
/// along it), those narrower than `narrowest` left out; 0 when none is left.
///
/// The boundaries are where a mesh of one element size must fit its elements between curves,
/// so they, not the area (which a background dominates), say which widths matter.
///
/// ```
/// use imesh::boundary_weighted_width;
/// // A speck (width 0.5), a region of width 10 and perimeter 20, one of width 2 and perimeter 60.
/// let regions = [(0.5, 4.0), (10.0, 20.0), (2.0, 60.0)];
/// assert_eq!(boundary_weighted_width(regions, 0.5, 1.0), 2.0);
/// assert_eq!(boundary_weighted_width(regions, 0.9, 1.0), 10.0);
/// assert_eq!(boundary_weighted_width(regions, 0.02, 0.0), 0.5);
/// ```
pub fn boundary_weighted_width(
    regions: impl IntoIterator<Item = (f64, f64)>,
    share: f64,
    narrowest: f64,
) -> f64 {
    let mut by_width: Vec<(f64, f64)> = regions
        .into_iter()
        .filter(|&(w, _)| w >= narrowest)
        .collect();
    by_width.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = by_width.iter().map(|&(_, p)| p).sum();
    let mut below = 0.0;
    for &(w, p) in &by_width {
        below += p;
        if below >= share * total {
            return w;
        }
    }
    by_width.last().map_or(0.0, |&(w, _)| w)
}

/// The boundary graph G of an Imesh partition: its c-edges, with the domain corners pinned (the
/// curve stage's input).
///
/// # Errors
/// [`imesh_curves::CurveError`] if the c-edges do not make a valid graph (a bug in the sampler).
pub fn boundary_graph(segmented: &SegmentedMesh) -> Result<CurveGraph, imesh_curves::CurveError> {
    graph_of_c_edges(
        &segmented.triangulation,
        &segmented.c_edges,
        segmented.width,
        segmented.height,
    )
}

/// The boundary graph of the c-edges `edges` of `t` over a `width` × `height` domain: the
/// triangulation's points (G's vertex ids are `t`'s), the domain corners pinned.
fn graph_of_c_edges(
    t: &Triangulation,
    edges: &[CEdge],
    width: u32,
    height: u32,
) -> Result<CurveGraph, imesh_curves::CurveError> {
    let edges = edges
        .iter()
        .map(|e| GraphEdge {
            ends: e.vertices.map(|v| v.index() as u32),
            labels: e.labels,
        })
        .collect();
    CurveGraph::image_boundaries(
        t.points().to_vec(),
        edges,
        f64::from(width),
        f64::from(height),
    )
}

/// The curve stage's result (quads): G (contracted) and its simplification G'.
struct Curves {
    g: CurveGraph,
    simplified: Simplification,
    contracted: usize,
    /// Chain vertices kept at necks.
    necks: usize,
    /// Chain vertices kept to widen sharp sectors.
    sharp: usize,
}

/// One triangle of `t` inside each face of G' (`s.graph`, whose edge `k` replaces the chain
/// `s.chains[k]` of G's vertices, which are `t`'s) narrower than `min_width` (see
/// [`imesh_curves::Face::width`]): a region that simplification flattened. The triangle is the one
/// on the face's side of the first G edge of the face's walk that is an edge of `t`, under
/// `label`; a face whose walk finds none is left out.
fn thin_faces(
    s: &Simplification,
    t: &Triangulation,
    label: &[u32],
    min_width: f64,
) -> Vec<TriangleId> {
    if min_width.is_nan() || min_width <= 0.0 {
        return Vec::new();
    }
    let (graph, chains) = (&s.graph, &s.chains);
    graph
        .faces()
        .iter()
        .filter(|f| f.consistent && f.label != OUTSIDE && f.area > 0.0)
        .filter(|f| f.width(graph) < min_width)
        .filter_map(|f| {
            f.walk.iter().find_map(|&(e, forward)| {
                chains.get(e as usize)?.windows(2).find_map(|w| {
                    let (a, b) = if forward { (w[0], w[1]) } else { (w[1], w[0]) };
                    let h = t.find_edge(VertexId::new(a), VertexId::new(b))?;
                    let inside = t.triangle_of(h);
                    (t.is_triangle(inside) && label.get(inside.index()) == Some(&f.label))
                        .then_some(inside)
                })
            })
        })
        .collect()
}

/// The area of the equilateral triangle of side `s`.
fn equilateral_area(s: f64) -> f64 {
    3f64.sqrt() / 4.0 * s * s
}

/// The share of pixels whose centre lies in an element of the pixel's own label (on an edge
/// between two elements, either counts). Elements are convex (positive Jacobian at every corner),
/// so a centre is inside when it is on the inner side of every edge.
pub fn label_agreement(mesh: &SegmentedMeshData, grid: &LabelGrid) -> f64 {
    region_fidelity(mesh, grid).0
}

/// [`label_agreement`], and how each label of `grid` comes out in `mesh` (whose labels are
/// `grid`'s): its pixels, the area of its elements (curved, in a second-order mesh), their count
/// and its own agreement (of the elements' corners).
///
/// ```
/// use imesh::region_fidelity;
/// use imesh_classify::{LabelGrid, Region};
/// use imesh_io::SegmentedMeshData;
/// use imesh_quality::Element;
/// // A 2 × 1 image of two labels, meshed as one quad per pixel.
/// let region = |name: &str| Region { name: name.into(), colour: [0; 3] };
/// let grid = LabelGrid::new(2, 1, vec![0, 1], vec![region("pore"), region("grain")]).unwrap();
/// let mesh = SegmentedMeshData {
///     vertices: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0]],
///     elements: vec![Element::Quad([0, 1, 4, 3]), Element::Quad([1, 2, 5, 4])],
///     labels: vec![0, 0], // the second pixel meshed with the first's label
///     label_names: grid.regions().iter().map(|r| r.name.clone()).collect(),
///     label_colours: vec![[0; 3]; 2], width: 2, height: 1, second_order: None,
/// };
/// let (agreement, regions) = region_fidelity(&mesh, &grid);
/// assert_eq!(agreement, 0.5);
/// assert_eq!((regions[0].pixels, regions[0].area_px, regions[0].agreement), (1, 2.0, 1.0));
/// assert_eq!((regions[1].pixels, regions[1].elements, regions[1].agreement), (1, 0, 0.0));
/// ```
pub fn region_fidelity(mesh: &SegmentedMeshData, grid: &LabelGrid) -> (f64, Vec<RegionFidelity>) {
    let (agreement, mut regions) = agreement(&mesh.vertices, &mesh.elements, &mesh.labels, grid);
    curved_areas(mesh, &mesh.labels, &mut regions);
    (agreement, regions)
}

/// A second-order mesh's curved sides move area between the labels on either side: each
/// label's area becomes its elements' curved area (`labels`: the elements' labels as numbered
/// in `regions`); the agreement stays that of the corners.
fn curved_areas(mesh: &SegmentedMeshData, labels: &[u32], regions: &mut [RegionFidelity]) {
    if mesh.second_order.is_none() {
        return;
    }
    regions.iter_mut().for_each(|r| r.area_px = 0.0);
    for (i, &l) in labels.iter().enumerate() {
        if let Some(r) = regions.get_mut(l as usize) {
            r.area_px += mesh.element_area(i);
        }
    }
}

/// Validates a mesh on the image domain `w × h` (conforming, exact area, no inverted element,
/// one known label per element): its area over the domain's, or the violations as an error.
fn area_ratio(mesh: &SegmentedMeshData, w: f64, h: f64) -> Result<f64, PipelineError> {
    let view = MeshView {
        vertices: &mesh.vertices,
        elements: &mesh.elements,
        labels: &mesh.labels,
    };
    let checked = validate(&view, &Domain::image(w, h));
    if !checked.is_valid() {
        return Err(PipelineError::Invalid(format!("{:?}", checked.violations)));
    }
    Ok(checked.area / (w * h))
}

/// The quality statistics of `mesh`'s quads, or of its triangles.
fn mesh_quality(mesh: &SegmentedMeshData, elements: Elements) -> MeshQuality {
    let (mut triangles, mut quads) = (Vec::new(), Vec::new());
    for element in &mesh.elements {
        match *element {
            Element::Triangle(t) => triangles.push(t),
            Element::Quad(q) => quads.push(q),
        }
    }
    match elements {
        Elements::Tri => MeshQuality::Triangles(TriangleQuality::of(&mesh.vertices, &triangles)),
        Elements::Quad => MeshQuality::Quads(QuadQuality::of(&mesh.vertices, &quads)),
    }
}

/// [`imesh_quality::sharpest_boundary_corner`] of `mesh`'s quads (`None` for a mesh with a
/// triangle).
fn sharpest_boundary_corner(mesh: &SegmentedMeshData) -> Option<BoundaryCorner> {
    let quads: Vec<[u32; 4]> = mesh
        .elements
        .iter()
        .map(|e| match *e {
            Element::Quad(q) => Some(q),
            Element::Triangle(_) => None,
        })
        .collect::<Option<_>>()?;
    imesh_quality::sharpest_boundary_corner(&mesh.vertices, &quads, &mesh.labels)
}

/// [`label_agreement`] of a mesh whose labels name the regions of another grid (a cleaned or
/// reduced one, whose regions are a subset of `original`'s) against `original`, region by name.
fn agreement_with_original(
    mesh: &SegmentedMeshData,
    original: &LabelGrid,
) -> (f64, Vec<RegionFidelity>) {
    let id: std::collections::HashMap<&str, u32> = original
        .regions()
        .iter()
        .enumerate()
        .map(|(i, r)| (r.name.as_str(), i as u32))
        .collect();
    // Looked up once per label, not per element.
    let original_label: Vec<u32> = mesh
        .label_names
        .iter()
        .map(|name| id.get(name.as_str()).copied().unwrap_or(u32::MAX))
        .collect();
    let labels: Vec<u32> = mesh
        .labels
        .iter()
        .map(|&l| original_label.get(l as usize).copied().unwrap_or(u32::MAX))
        .collect();
    let (agreement, mut regions) = agreement(&mesh.vertices, &mesh.elements, &labels, original);
    curved_areas(mesh, &labels, &mut regions);
    (agreement, regions)
}

/// Pixels counted per parallel task by [`agreement`].
const COUNT_CHUNK: usize = 1 << 16;

/// [`label_agreement`] of elements with their own labels (numbered as `grid`'s, [`u32::MAX`]
/// for none of them), and each of `grid`'s labels' [`RegionFidelity`].
fn agreement(
    vertices: &[[f64; 2]],
    elements: &[Element],
    labels: &[u32],
    grid: &LabelGrid,
) -> (f64, Vec<RegionFidelity>) {
    let (w, h) = (grid.width() as usize, grid.height() as usize);
    let mut regions: Vec<RegionFidelity> = grid
        .regions()
        .iter()
        .map(|r| RegionFidelity {
            name: r.name.clone(),
            pixels: 0,
            area_px: 0.0,
            elements: 0,
            agreement: 1.0,
        })
        .collect();
    for (element, &label) in elements.iter().zip(labels) {
        if let Some(region) = regions.get_mut(label as usize) {
            region.elements += 1;
            let ids = element.corners();
            let mut corners = [[0.0; 2]; 4];
            for (c, &v) in corners.iter_mut().zip(ids) {
                *c = vertices[v as usize];
            }
            region.area_px += imesh_quality::signed_area(&corners[..ids.len()]);
        }
    }
    if w == 0 || h == 0 {
        return (1.0, regions);
    }
    // Each element marks its pixel centres of its own label, element by element in parallel
    // (a centre on an edge shared by two elements may be marked twice).
    let agrees: Vec<AtomicBool> = (0..w * h).map(|_| AtomicBool::new(false)).collect();
    elements
        .par_iter()
        .zip(labels)
        .for_each(|(element, &label)| {
            let ids = element.corners();
            let n = ids.len();
            let mut corners = [[0.0; 2]; 4];
            for (c, &v) in corners.iter_mut().zip(ids) {
                *c = vertices[v as usize];
            }
            let corners = &corners[..n];
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for c in corners {
                for k in 0..2 {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            // Pixel centres (col + 0.5, row + 0.5) inside the bounding box.
            let first = |x: f64| (x - 0.5).ceil().max(0.0) as usize;
            let last = |x: f64, n: usize| ((x - 0.5).floor().min(n as f64 - 1.0)).max(-1.0);
            let (c0, r0) = (first(lo[0]), first(lo[1]));
            let (c1, r1) = (last(hi[0], w), last(hi[1], h));
            if c1 < 0.0 || r1 < 0.0 {
                return;
            }
            for row in r0..=r1 as usize {
                for col in c0..=c1 as usize {
                    let p = [col as f64 + 0.5, row as f64 + 0.5];
                    let inside = (0..n).all(|i| {
                        let (a, b) = (corners[i], corners[(i + 1) % n]);
                        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= 0.0
                    });
                    if inside && grid.label(col as u32, row as u32) == label {
                        agrees[row * w + col].store(true, Ordering::Relaxed);
                    }
                }
            }
        });
    // Per label, its pixels and those agreeing, counted over parts of the image in parallel.
    let labels = regions.len();
    let tally = |mut counts: Vec<[u64; 2]>, (grid_labels, agrees): (&[u32], &[AtomicBool])| {
        for (&label, agrees) in grid_labels.iter().zip(agrees) {
            if let Some(c) = counts.get_mut(label as usize) {
                c[0] += 1;
                c[1] += u64::from(agrees.load(Ordering::Relaxed));
            }
        }
        counts
    };
    let counts = grid
        .labels()
        .par_chunks(COUNT_CHUNK)
        .zip(agrees.par_chunks(COUNT_CHUNK))
        .fold(|| vec![[0u64; 2]; labels], tally)
        .reduce(
            || vec![[0u64; 2]; labels],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    x[0] += y[0];
                    x[1] += y[1];
                }
                a
            },
        );
    for (region, &[pixels, agreeing]) in regions.iter_mut().zip(&counts) {
        region.pixels = pixels;
        if pixels > 0 {
            region.agreement = agreeing as f64 / pixels as f64;
        }
    }
    let agreeing: u64 = counts.iter().map(|c| c[1]).sum();
    // A label of the grid's with no pixel (an empty class) says nothing.
    regions.retain(|g| g.pixels > 0 || g.elements > 0);
    (agreeing as f64 / (w * h) as f64, regions)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The automatic thin-region width is three quarters of the finest quad side: the given
    /// size, or the chosen one refined as far as the band limit may (a 1.5th), not below the
    /// 2 px floor nor above the chosen side; an explicit width is kept.
    #[test]
    fn thin_regions_are_measured_against_the_finest_quad() {
        let width = |size: ElementSize, q: f64| {
            Pipeline::new(MeshOptions {
                size,
                ..MeshOptions::default()
            })
            .auto_min_width(q)
        };
        for (q, finest) in [(2.0, 2.0), (2.4, 2.0), (4.5, 3.0), (9.0, 6.0), (1.5, 1.5)] {
            let w = width(ElementSize::Auto, q);
            assert!((w - THIN_REGION_SHARE * finest).abs() < 1e-12, "{q}: {w}");
        }
        assert!((width(ElementSize::Pixels(3.0), 3.0) - 2.25).abs() < 1e-12);
        assert!((width(ElementSize::Pixels(1.0), 1.0) - 0.75).abs() < 1e-12);
    }

    /// A `side` × `side` square image cut by `cuts` vertical boundaries, as G'.
    fn striped(side: f64, cuts: u32) -> CurveGraph {
        let mut points = vec![imesh_geom::Point::new(0.0, 0.0)];
        let n = f64::from(cuts + 1);
        for k in 1..=cuts + 1 {
            points.push(imesh_geom::Point::new(side * f64::from(k) / n, 0.0));
        }
        for k in (0..=cuts + 1).rev() {
            points.push(imesh_geom::Point::new(side * f64::from(k) / n, side));
        }
        let m = points.len() as u32;
        let mut edges: Vec<GraphEdge> = (0..m)
            .map(|i| GraphEdge {
                ends: [i, (i + 1) % m],
                labels: [0, u32::MAX],
            })
            .collect();
        for k in 1..=cuts {
            edges.push(GraphEdge {
                ends: [k, m - 1 - k],
                labels: [k - 1, k],
            });
        }
        CurveGraph::new(points, edges).unwrap()
    }

    #[test]
    fn the_band_limited_size_keeps_within_its_floors() {
        // No boundary inside: the size chosen stays, whatever it is.
        assert_eq!(
            band_limited_size(&striped(100.0, 0), 100.0, 100.0, 7.0),
            7.0
        );
        // One cut of 100 px: 2 · 100 · s / 10⁴ ≤ the share.
        let one = band_limited_size(&striped(100.0, 1), 100.0, 100.0, 10.0);
        assert!((one - AUTO_BAND_SHARE * 50.0).abs() < 1e-12, "{one}");
        assert_eq!(
            band_limited_size(&striped(100.0, 1), 100.0, 100.0, 4.0),
            4.0
        );
        // Forty cuts would ask for quads of a fifth of a pixel: at most 1.5 times finer...
        let many = band_limited_size(&striped(100.0, 40), 100.0, 100.0, 6.0);
        assert!((many - 6.0 / AUTO_BAND_REFINEMENT).abs() < 1e-12, "{many}");
        // ... and never under the smallest automatic size, unless the size given is.
        assert_eq!(
            band_limited_size(&striped(100.0, 40), 100.0, 100.0, 2.5),
            MIN_AUTO_SIZE
        );
        assert_eq!(
            band_limited_size(&striped(100.0, 40), 100.0, 100.0, 1.0),
            1.0
        );
    }

    /// What the curve stage starts from on fixture `name` with the default options: the
    /// pipeline, the cleaned grid, its sampling, the partition after the thin-region merge, the
    /// quad size and the minimum width.
    fn partitioned(
        name: &str,
    ) -> (
        Pipeline,
        LabelGrid,
        imesh_segment::Sampling,
        Vec<u32>,
        f64,
        f64,
    ) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/images")
            .join(name);
        let image = load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS).unwrap();
        let grid = classify(&image, &Classifier::Auto, &ClassifyOptions::default()).unwrap();
        let pipeline = Pipeline::new(MeshOptions::default());
        let q = pipeline.quad_size(&grid).unwrap();
        // The majority filter as the pipeline has it, but the thin parts it gives away after
        // the filter kept: the flattened regions and necks these tests need are such parts.
        let (grid, _) = pipeline.clean_up(&grid, auto_majority(q), None).unwrap();
        let sampling = sample(&grid, &SampleOptions::default()).unwrap();
        let min_width = pipeline.auto_min_width(q);
        let mut label = partition(&grid, &sampling.triangulation);
        merge_thin_regions(&sampling.triangulation, &mut label, min_width);
        (pipeline, grid, sampling, label, q, min_width)
    }

    /// On coins (Otsu, the default options), simplification flattens a small coin fragment the
    /// partition found wide enough into a sliver of G'; the curve stage merges it, and leaves
    /// G' with no face narrower than the minimum width, having changed only the labels of the
    /// regions it merged.
    #[test]
    fn the_curve_stage_leaves_no_face_narrower_than_the_minimum_width() {
        let (pipeline, grid, sampling, mut label, q, min_width) = partitioned("skimage-coins.png");
        let t = &sampling.triangulation;
        let (w, h) = (grid.width(), grid.height());
        let first = pipeline.curves(t, &label, w, h, Some(q)).unwrap();
        let thin = thin_faces(&first.simplified, t, &label, min_width);
        assert!(!thin.is_empty(), "coins has a flattened region");
        let before = label.clone();
        let (c, merged) = pipeline
            .curves_wide_enough(t, &mut label, w, h, Some(q), min_width)
            .unwrap();
        assert!(merged.regions >= thin.len());
        assert!(thin_faces(&c.simplified, t, &label, min_width).is_empty());
        for face in c.simplified.graph.faces() {
            if face.consistent && face.label != OUTSIDE && face.area > 0.0 {
                assert!(face.width(&c.simplified.graph) >= min_width);
            }
        }
        // The triangles named have changed label, and no more area than the merges report.
        assert!(thin.iter().all(|f| label[f.index()] != before[f.index()]));
        let changed: f64 = t
            .triangles()
            .filter(|f| label[f.index()] != before[f.index()])
            .map(|f| t.signed_area(f).abs())
            .sum();
        assert!(changed > 0.0 && changed <= merged.area * (1.0 + 1e-9));
    }

    /// On the pyvista label map, simplification narrows faces below half a quad side in places
    /// where the image is wider; the curve stage keeps the boundary there, and leaves no such
    /// neck in G'.
    #[test]
    fn the_curve_stage_keeps_the_boundary_at_necks() {
        let (pipeline, grid, sampling, mut label, q, min_width) =
            partitioned("pyvista-channels_z050_labels.png");
        let t = &sampling.triangulation;
        let (w, h) = (grid.width(), grid.height());
        let (c, _) = pipeline
            .curves_wide_enough(t, &mut label, w, h, Some(q), min_width)
            .unwrap();
        assert!(c.necks > 0, "pyvista has necks");
        assert!(neck_vertices(&c.g, &c.simplified, NECK_SHARE * q).is_empty());
        // Still within the tolerance of the image's boundaries.
        assert!(c.simplified.max_deviation <= pipeline.tolerance());
    }

    /// A round's pins can bring another chord near a vertex: on grass (Otsu), two rounds left
    /// three necks in G'. The rounds go on until none is left.
    #[test]
    fn the_neck_rounds_go_on_until_no_neck_is_left() {
        let (pipeline, grid, sampling, mut label, q, min_width) = partitioned("skimage-grass.png");
        let t = &sampling.triangulation;
        let (w, h) = (grid.width(), grid.height());
        let (c, _) = pipeline
            .curves_wide_enough(t, &mut label, w, h, Some(q), min_width)
            .unwrap();
        // Two rounds pin 21 neck vertices (and 75 at sharp sectors); the third pins more.
        assert!(c.necks > 21, "grass needs a third round: {} necks", c.necks);
        assert!(neck_vertices(&c.g, &c.simplified, NECK_SHARE * q).is_empty());
        assert!(c.simplified.max_deviation <= pipeline.tolerance());
    }
}
