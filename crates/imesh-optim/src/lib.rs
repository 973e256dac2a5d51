//! # imesh-optim
//!
//! Quality optimisation of the quad mesh Q (DESIGN.md §2, step 10; the paper's section V-C):
//! minimise `q_s = Σ (1 − s(ν))²` over the quads ν, `s` being Verdict's shape-and-size against
//! the mesh's fixed average quad area ([`Metric::ShapeAndSize`]) or shape ([`Metric::Shape`]),
//! by moving the free Bézier control points: those not on a c-edge or on the domain border, so
//! that every region keeps its fitted boundary. Quad vertices follow their patches, until the
//! local mode hands over to the free quad vertices themselves.
//!
//! A move is feasible only if every quad keeps positive Jacobians at its four corners (exact
//! orientation), every moved control point stays strictly inside the polygon of its
//! neighbours in the control net, no quad falls below the mesh's starting worst quality, and
//! no quad's shape falls below its own start shape or [`OptimOptions::keep_shape`], whichever
//! is lower (the last repair may take a quad to [`REPAIR_FLOOR`] for a worse neighbour): the
//! result is never worse than the start, and sizes are evened out (shape-and-size) only where
//! shapes allow.
//!
//! [`Method`]s: [`Method::Local`] (default) is block coordinate descent, one control point at a
//! time by [`Powell`]'s method, points coloured so that one colour shares no quad and is solved
//! in parallel, the free quad vertices after two sweeps ([`OptimOptions::control_sweeps`]);
//! [`Method::Global`] is the paper's single Powell run over all variables;
//! [`Method::Laplacian`] and [`Method::Vertex`] are baselines that move the quad vertices
//! directly. The repairs after the descent ([`OptimOptions::repair`]) are runs of small
//! searches, each seeing the moves before it; they run side by side wherever neither of two
//! reads what the other moves, kept in order, so they end where one after the other would.
//!
//! ```
//! use imesh_curves::{fit_edges, simplify, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
//! use imesh_geom::Point;
//! use imesh_optim::{optimise, Method, OptimOptions};
//! use imesh_quad::{remesh, QuadOptions};
//! // A 20 × 20 domain holding a disc of radius 6, as a 32-gon.
//! let mut points = vec![Point::new(0.0, 0.0), Point::new(20.0, 0.0), Point::new(20.0, 20.0), Point::new(0.0, 20.0)];
//! let mut edges: Vec<GraphEdge> = (0..4u32).map(|i| GraphEdge { ends: [i, (i + 1) % 4], labels: [0, u32::MAX] }).collect();
//! for i in 0..32u32 {
//!     let a = f64::from(i) * std::f64::consts::TAU / 32.0;
//!     points.push(Point::new(10.0 + 6.0 * a.cos(), 10.0 + 6.0 * a.sin()));
//!     edges.push(GraphEdge { ends: [4 + i, 4 + (i + 1) % 32], labels: [1, 0] });
//! }
//! let mut g = CurveGraph::new(points, edges)?;
//! g.pin_domain_corners(20.0, 20.0);
//! let s = simplify(&g, &SimplifyOptions::with_tolerance(0.5))?;
//! let fits = fit_edges(&s, &g, &FitOptions::default());
//! let curves: Vec<_> = fits.fits.iter().map(|f| f.curve).collect();
//! let mut r = remesh(&s.graph, &curves, &QuadOptions::default())?;
//! let report = optimise(&mut r, &OptimOptions::default())?;
//! assert!(report.energy_after < report.energy_before);
//! assert!(report.after.shape_and_size.min >= report.before.shape_and_size.min);
//! assert!((0..r.mesh.quads.len()).all(|q| r.mesh.is_valid(q)));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod batches;
mod energy;
mod global;
mod joint;
mod laplacian;
mod local;
mod powell;
mod repair;
mod slide;
mod variables;

pub use energy::{is_valid, Metric};

use energy::worst_corner;
pub use powell::Powell;
pub use repair::{REPAIR_FLOOR, REPAIR_JACOBIAN};

use std::time::Instant;

use imesh_geom::Point;
use imesh_quad::{BoundaryChain, Remesh};
use imesh_quality::{QuadHistograms, QuadQuality};
use rayon::prelude::*;

use crate::variables::{fixed_vertices, vertex_quads, Variables};

/// After the boundary vertices slide ([`OptimOptions::slide`]), the free quad vertices within
/// this many quad rings of them are moved once more (measured on stardist: mean shape-and-size
/// 0.7955 / 0.7984 / 0.7995 / 0.8012 at 1 / 2 / 3 rings / all, that pass taking 0.07 / 0.13 /
/// 0.18 / 0.36 s).
pub const POLISH_RINGS: usize = 2;

/// Most sweeps of that pass (measured, mean shape-and-size on stardist / gravel and optimiser
/// seconds on gravel: 1 sweep 0.794 / 0.666, 2.7 s; 2: 0.797 / 0.672, 3.1 s; up to 40 (it
/// stops at 4–5): 0.798 / 0.676, 3.7 s; without sliding 0.785 / 0.642, 2.3 s).
pub const POLISH_SWEEPS: usize = 2;

/// The default [`OptimOptions::keep_quality`]: the paper's worst shape-and-size (Table I). The
/// energy `Σ (1 − s)²` saturates: a quad already poor costs little more when it gets worse, so
/// the descent grew quads beside a boundary to two or three times the mean area (s under 0.1)
/// to even out their neighbours. Measured with the defaults on nine fixtures (all but aloe):
/// quads under 0.25 brick 1 464 → 773, grass 4 578 → 3 721, stardist 430 → 272, pyvista 278 →
/// 202, coffee 788 → 660; quads over twice the mean area 2 739 → 1 340 in all; worst scaled
/// Jacobian coffee 0.280 → 0.366, grass 0.299 → 0.310, camera 0.383 → 0.375; mean
/// shape-and-size 0.0003–0.0028 lower. Held at 0.15 it changed little (brick 1 488 quads under
/// 0.25); held to every quad's own start quality where lower, camera's worst shape fell 0.248 →
/// 0.147 (a poor quad could no longer shrink to square up).
pub const KEEP_QUALITY: f64 = 0.25;

/// The default [`OptimOptions::corner_reach`]: about a third of the mean quad side (0.7 px at
/// the automatic size's 2 px floor, within the 2 px curve tolerance up to quads of 5.7 px).
/// Measured with `cargo xtask bench random` on seven sets of 150 images (seeds 52, 101, 202,
/// 404 and 505, and 303 and 52 at `--size 3`) against 0 (the corners held), the vertices on the
/// border held: quads under 0.5 in shape 63 → 28, 20 and 14 at 0.2, 0.35 and 0.5, in scaled
/// Jacobian 12 → 3 at each; quads under 0.25 25 360 → 23 055, 22 297 and 21 901; the mean of
/// the means up on every set, by 0.0002–0.0004 at 0.35; label agreement 0.011–0.024 points
/// lower, the same at every reach within 0.005. At 0.35 with the border's vertices moving
/// along it: 12, 1 and 22 105 (aloe's worst shape 0.443 → 0.500: a junction on the border);
/// on four held-out sets (seeds 606 and 707, 808 at `--size 4`, 909 at 2.5) quads under 0.5
/// in shape 74 → 35, in scaled Jacobian 6 → 1, under 0.25 16 099 → 14 069.
pub const CORNER_REACH: f64 = 0.35;

/// The quads whose shape-and-size is under this are lifted by the quality repair
/// ([`OptimOptions::quality_repair`]): Verdict's acceptable range for shape-and-size starts at
/// 0.2, the paper's worst quads are 0.21–0.29, issue 8's target for the worst is 0.25.
pub const POOR_QUALITY: f64 = 0.25;

/// ... towards this, their patches' smallest shape-and-size counted up to it: issue 8's goal
/// for the worst quad. Measured at two Powell iterations a patch against lifting every quad
/// under 0.35 (quads under 0.25 after): stardist 97 against 82, brick 272 against 260, coins 13
/// against 11, for 30–45 % less time in the quality repair; a bar of 0.25 or 0.5 lifted fewer
/// (coins 26 and 22 against 12).
pub const QUALITY_BAR: f64 = 0.35;

/// The share of the quads the quality repair takes at most, the poorest. The label images
/// have 0.3–1.5 % of their quads under [`POOR_QUALITY`], the textured ones 4–6 %; measured
/// against 2 %: grass 3 369 quads under 0.25 after against 3 127 (3 480 before), camera 128
/// against 116, for 9–12 % less optimiser time on both.
pub const QUALITY_SHARE: f64 = 0.01;

/// The quality repair leaves a mesh with more than this share of its quads under
/// [`POOR_QUALITY`]: it is graded by design (`--size graded`: 25–80 % of them), its poorest quads
/// a hundredth of the mean area. Lifting them all took 4–7 times the optimiser's time for a
/// mean shape-and-size 0.004–0.009 higher; the poorest 2 % changed nothing (MRI, coins,
/// stardist, camera) for up to 20 % more time.
pub const GRADED_SHARE: f64 = 0.1;

/// How the mesh is optimised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Leave the mesh as it is.
    None,
    /// Baseline: Laplacian smoothing of the free quad vertices (each to the mean of its edge
    /// neighbours, kept only when its quads stay valid).
    Laplacian,
    /// Baseline: the local optimisation moving free quad vertices instead of control points.
    Vertex,
    /// Block coordinate descent over the free control points (default).
    #[default]
    Local,
    /// One Powell run over all free control points at once, as the paper does (slow: for
    /// comparison and small meshes).
    Global,
}

/// How each local solve (two variables) is minimised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LocalSolver {
    /// [`Powell`]'s method (derivative-free; default).
    #[default]
    Powell,
    /// argmin's L-BFGS with the analytic gradient of the local energy and a backtracking
    /// (Armijo) line search.
    Lbfgs,
}

/// Options of [`optimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimOptions {
    /// The method.
    pub method: Method,
    /// The quality the energy is built on.
    pub metric: Metric,
    /// Sweeps stop when one lowers the energy by less than this fraction (default 3 %: measured
    /// against 1 %, the local mode takes 9 sweeps instead of 12, 10–45 % less time, for a mean
    /// shape-and-size 0.0004–0.003 lower; at 10 %, 5 sweeps and 0.002–0.014 lower).
    pub tolerance: f64,
    /// Most sweeps (local, vertex and Laplacian modes).
    pub max_sweeps: usize,
    /// The local mode's sweeps over the control points, after which the quad vertices
    /// themselves move (as in the vertex mode) until a sweep lowers the energy by less than
    /// [`OptimOptions::vertex_tolerance`]; `None`: the control points alone, until
    /// [`OptimOptions::tolerance`]. A control point moves the quads of its patches together,
    /// which the first sweeps need (sizes evened out over whole elements); what is left after
    /// them is each vertex among its own quads, which a vertex moves at half the cost of a
    /// control point (it moves one mesh point, not the template points of two patches).
    /// Measured with the defaults (`cargo xtask bench random`, 150 images; optimiser seconds
    /// on one thread summed over coins, stardist, gravel, grass and brick, each the least of
    /// three runs): the control points alone, 0.8921 and 4.5–4.8 s; two sweeps then the
    /// vertices to 1.5 %, 0.8935 and 4.6 s (every fixture's mean up, by 0.0003 on camera to
    /// 0.0035 on grass); one sweep then 3 %, 0.8922 and 3.8 s; the control points alone then
    /// the vertices to 3 %, 0.8937 and 5.3 s; the control points alone to 1 %, 0.8932; the
    /// vertex mode alone to 3 %, 1 % and 0.5 %: 0.8920 and 3.2 s, 0.8936 and 4.6 s, 0.8942.
    pub control_sweeps: Option<usize>,
    /// The energy drop under which the local mode's vertex sweeps stop
    /// ([`OptimOptions::control_sweeps`]).
    pub vertex_tolerance: f64,
    /// The minimiser of each local solve.
    pub local_solver: LocalSolver,
    /// Most Powell iterations of each local solve (twice as many L-BFGS ones).
    pub local_iterations: u64,
    /// Most Powell iterations of the global run.
    pub global_iterations: u64,
    /// No quad whose shape is at least this may fall below it, and no other quad below its
    /// start shape: with shape-and-size, sizes are evened out only where shapes allow. 0 leaves
    /// only the global guard (no quad below the start's worst shape). The repair
    /// ([`OptimOptions::repair`]) may still lower a quad to [`REPAIR_FLOOR`] for a worse
    /// neighbour.
    pub keep_shape: f64,
    /// No quad whose quality (the metric's) is at least this at the start may fall below it
    /// in the descent and the sliding: good quads are not spent on their neighbours
    /// ([`KEEP_QUALITY`] by default; 0 leaves only the global guard, no quad below the start's
    /// worst, which the repair keeps too).
    pub keep_quality: f64,
    /// A point of the local modes is not solved while the quads it moves score at least this
    /// on average (by the mean of their energy terms, `(1 − s)²`): on a uniform mesh most of
    /// the inside is settled from the start, and solving it gains next to nothing (measured:
    /// mean shape-and-size within 0.004, 20–45 % less optimiser time). 1 solves every point.
    pub settled: f64,
    /// After the local or the vertex mode: the quad vertices on every boundary curve slide
    /// along it (between their neighbours there, staying on the curve), then the free quad
    /// vertices within [`POLISH_RINGS`] quad rings of them are moved once more as in the vertex
    /// mode, so that the inside follows. The control points keep the spacing DT' gave each
    /// boundary; this frees it. Measured on the fixtures: mean shape-and-size +0.004 to +0.03.
    pub slide: bool,
    /// After the local or the vertex mode (and the sliding): every free quad vertex within two
    /// rings of a quad whose scaled Jacobian or shape is under [`REPAIR_JACOBIAN`] moves, by
    /// compass search, to raise the smallest scaled Jacobian of its quads, then their smallest
    /// shape (up to that bar), every quad held to [`REPAIR_FLOOR`] or its own values if lower;
    /// then the free corners of each quad still under the bar move two or more at a time;
    /// then, for each quad still under it, every free vertex and boundary vertex of the quads
    /// around its corners in one [`Powell`] run (`joint.rs`), pass after pass
    /// ([`OptimOptions::joint_passes`]); undone if it would leave the energy above the start's.
    /// The energy leaves such quads where their shape-and-size is fair. Measured with the
    /// defaults (a bar of 0.4 and the descent's floors then): worst scaled Jacobian stardist
    /// 0.272 → 0.355, coffee 0.251 → 0.280, grass 0.280 → 0.299, MRI 0.352 → 0.371, camera
    /// 0.358 → 0.383; worst shape stardist 0.232 → 0.312, coffee 0.192 → 0.224, grass 0.068 →
    /// 0.119, gravel 0.075 → 0.155; the other values equal; mean shape-and-size within 0.001;
    /// 0.5–4 % of the optimiser's time.
    pub repair: bool,
    /// Most passes of the repair's last step (`joint.rs`: each quad still under the bar with
    /// its neighbourhood moved at once). A patch is solved with its neighbours where the
    /// patches before it left them; once they have moved on, the poorest quads may rise further.
    /// Measured with the defaults on fourteen images (ten fixtures, four unseen), worst shape
    /// after one pass, two and three: camera 0.480, 0.497, 0.500; grass 0.388, 0.406, 0.406;
    /// pyvista 0.473, 0.474, 0.474; the other eleven equal, and equal again at seven passes;
    /// mean shape-and-size within 0.0002; optimiser time within the noise (interleaved runs:
    /// −5 % to +10 %, graded +8 % at most).
    pub joint_passes: usize,
    /// With shape-and-size, after the repair ([`OptimOptions::repair`]): each quad under
    /// [`POOR_QUALITY`] (the poorest [`QUALITY_SHARE`] of the quads at most, none when more
    /// than [`GRADED_SHARE`] of them are under it) with the free
    /// vertices and sliders around it moved at once, as the repair's last step moves them, to
    /// raise the patch's smallest shape-and-size up to [`QUALITY_BAR`], the patch's energy
    /// weighing in a little; every quad held to its shape-and-size up to that bar, and its
    /// shape and scaled Jacobian up to [`REPAIR_JACOBIAN`], so the worst of none of them
    /// falls. The energy of all the quads leaves a quad a third of the mean area, at a tip or
    /// in a strip, where it is: it is one term among thousands. Measured with the defaults,
    /// quads under 0.25 before → after: see docs/measurements.md's session-35 paragraph.
    pub quality_repair: bool,
    /// How far the repair's last steps (`joint.rs`) may move a vertex of G' (a corner of the
    /// boundaries or a junction of three regions or more; one on the domain's border along it,
    /// the domain's corners not at all) from where it started, as a share of the mean quad side ([`CORNER_REACH`] by default); 0 holds them
    /// where they are, as the rest of the optimiser does. Nothing else moves them: a corner
    /// shared by two quads (a 56° tip split by an edge), or a junction's sectors, keep their
    /// angles whatever the vertices around them do, and were most of the quads left under 0.5
    /// in shape or scaled Jacobian (gravel's worst, 0.468 and 0.472: a 56° tip; aloe's 0.461:
    /// a junction). Moving the tip a fraction of a quad side into the region opens both corners.
    /// The boundaries beside a moved corner move with it, by its shift at most
    /// ([`OptimReport::corner_shift`]; the pipeline adds it to the boundary's reported
    /// Hausdorff distance), and a second-order side there stays straight.
    pub corner_reach: f64,
}

impl Default for OptimOptions {
    fn default() -> Self {
        Self {
            method: Method::Local,
            metric: Metric::ShapeAndSize,
            tolerance: 3e-2,
            max_sweeps: 40,
            control_sweeps: Some(2),
            vertex_tolerance: 1.5e-2,
            local_solver: LocalSolver::Powell,
            local_iterations: 1,
            global_iterations: 20,
            keep_shape: 0.5,
            keep_quality: KEEP_QUALITY,
            settled: 0.95,
            slide: true,
            repair: true,
            joint_passes: 3,
            quality_repair: true,
            corner_reach: CORNER_REACH,
        }
    }
}

/// Errors of [`optimise`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptimError {
    /// The mesh given has an invalid quad: nothing can be moved feasibly around it.
    #[error("quad {quad} of the mesh to optimise is inverted or degenerate: the quad stage should never give one; please report it")]
    InvalidStart {
        /// The first invalid quad.
        quad: usize,
    },
    /// The global solver failed.
    #[error("the global optimiser failed: {0}")]
    Solver(String),
}

/// What [`optimise`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimReport {
    /// The method run.
    pub method: Method,
    /// The metric of the energy.
    pub metric: Metric,
    /// Points free to move (control points, or quad vertices for the baselines).
    pub variables: usize,
    /// Colours of the local modes (independent sets solved in parallel).
    pub colours: usize,
    /// The fixed average quad area of shape-and-size.
    pub average_area: f64,
    /// Energy `Σ (1 − s)²` before.
    pub energy_before: f64,
    /// Energy after.
    pub energy_after: f64,
    /// Sweeps (local modes: the control points' and the vertices' after them, the sliding and
    /// its vertex pass included) or Powell iterations (global).
    pub sweeps: usize,
    /// Quad vertices that slid along the boundary curves ([`OptimOptions::slide`]).
    pub sliders: usize,
    /// Quad vertices moved to raise the worst scaled Jacobians ([`OptimOptions::repair`]), and
    /// patches moved as a whole...
    pub repaired: usize,
    /// ... of which boundary vertices moved along their curves.
    pub repaired_sliders: usize,
    /// Patches moved for the quality of their poorest quads ([`OptimOptions::quality_repair`]).
    pub quality_repaired: usize,
    /// Vertices of G' (corners and junctions of the boundaries) the repair moved
    /// ([`OptimOptions::corner_reach`])...
    pub moved_corners: usize,
    /// ... and the farthest one moved, in the mesh's units.
    pub corner_shift: f64,
    /// The boundary chains with their vertices where sliding left them along the curves, for
    /// second-order sides that follow the curves between them; `None` when the method does not
    /// slide (the vertices are where [`Remesh::boundary_chains`] finds them).
    pub boundary: Option<Vec<BoundaryChain>>,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Quality before.
    pub before: QuadQuality,
    /// Quality after.
    pub after: QuadQuality,
    /// The report's histograms before...
    pub histograms_before: QuadHistograms,
    /// ... and after.
    pub histograms_after: QuadHistograms,
}

/// What every solver needs to know about the energy.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup<'a> {
    pub quads: &'a [[u32; 4]],
    pub metric: Metric,
    pub average_area: f64,
    /// Quad `q` may not fall below quality `quality_floors[q]`: [`OptimOptions::keep_quality`]
    /// if it started there (or the start's worst if that is higher), else the start's worst...
    pub quality_floors: &'a [f64],
    /// ... and quad `q` not below shape `shape_floors[q]` (its own start shape, or
    /// [`OptimOptions::keep_shape`] if that is lower, but never below the start's worst),
    /// whatever the metric: sizes are never evened out by spoiling shapes.
    pub shape_floors: &'a [f64],
    /// ... and quad `q` not below scaled Jacobian `jacobian_floors[q]`: its start value where
    /// its shape floor is its own start shape (a poor quad), the start's worst elsewhere (a
    /// shape of at least [`OptimOptions::keep_shape`] keeps the scaled Jacobian above that: at
    /// every corner `2α / (|a|² + |b|²) ≤ α / (|a| |b|)`, so the floor costs a Jacobian only
    /// when the start's worst is above `keep_shape`). So the worst scaled Jacobian never falls.
    pub jacobian_floors: &'a [f64],
    pub max_sweeps: usize,
    pub tolerance: f64,
    pub local_iterations: u64,
    pub local_solver: LocalSolver,
    /// A local solve whose quads' mean energy term is at most this is skipped
    /// ([`OptimOptions::settled`]).
    pub settled_term: f64,
}

/// Quads scored side by side ([`Setup::qualities_and_areas`]) by the local solves and the
/// repairs: four lanes fill two vector registers of the baseline x86-64 (SSE2), and a local
/// solve's point most often moves four quads (a quad patch's centre).
pub(crate) const LANES: usize = 4;

/// A quad whose shape (as computed) is at least this, with a positive area, is valid without
/// the exact test. Every corner's cross product `α = a × b` is then at least `shape · |a| |b|
/// ≥ shape · (|aₓ b_y| + |a_y bₓ|)`, some 10⁵ times the bound on its rounding error (about
/// `4ε` times that sum), so the exact orientation is positive too, and the area's sign says the
/// corners turn left.
const SURE_SHAPE: f64 = 1e-10;

/// How far above a scaled-Jacobian floor a quad's shape must be for the floor to hold without
/// computing the Jacobian: far above the rounding of either.
const JACOBIAN_MARGIN: f64 = 1e-9;

impl Setup<'_> {
    /// The metric of quad `q` over `vertices`.
    pub fn value(&self, vertices: &[Point], q: usize) -> f64 {
        let p = self.quads[q].map(|v| vertices[v as usize]);
        self.quality(&p).0
    }

    /// Verdict's shape of quad `q` over `vertices` (the repairs' measure of a poor quad).
    pub fn shape(&self, vertices: &[Point], q: usize) -> f64 {
        let p = self.quads[q].map(|v| [vertices[v as usize].x, vertices[v as usize].y]);
        imesh_quality::quad::shape(&p)
    }

    /// The metric `s` and the shape of quad `p`, in one pass: Verdict's shape, and the relative
    /// size from the shoelace area (Verdict's `¼ Σ α_k`, the same area up to rounding), so that
    /// every energy term, floor and gradient here agrees to the bit.
    #[inline]
    pub fn quality(&self, p: &[Point; 4]) -> (f64, f64) {
        let (s, shape, _) = self.quality_and_area(p);
        (s, shape)
    }

    /// [`Setup::quality`] and the quad's signed area ([`Setup::qualities_and_areas`] of the one
    /// quad).
    #[inline]
    fn quality_and_area(&self, p: &[Point; 4]) -> (f64, f64, f64) {
        let (s, shape, area) = self.qualities_and_areas(&[*p]);
        (s[0], shape[0], area[0])
    }

    /// The energy term `(1 − s)²` of quad `p`, or `None` when the quad is invalid or falls
    /// below a floor.
    #[inline]
    pub fn term(&self, quad: usize, p: &[Point; 4]) -> Option<f64> {
        self.term_given(quad, p, self.quality_and_area(p))
    }

    /// [`Setup::quality_and_area`] of `N` quads at once (the same bits as one by one), lane by
    /// lane so that the compiler can put the lanes side by side in vector registers.
    #[inline]
    pub fn qualities_and_areas<const N: usize>(
        &self,
        p: &[[Point; 4]; N],
    ) -> ([f64; N], [f64; N], [f64; N]) {
        let (shape, area) = energy::shapes_and_areas(p);
        let s = match self.metric {
            Metric::Shape => shape,
            Metric::ShapeAndSize => {
                // Shape times the relative size `min(R, 1/R)²`, `R = area / Ā`, without a
                // branch: the relative size of a quad of no positive area is computed, then
                // dropped for 0.
                let mut s = [0.0; N];
                for l in 0..N {
                    let r = area[l] / self.average_area;
                    let m = r.min(1.0 / r);
                    let m = if r > 0.0 { m } else { 0.0 };
                    s[l] = shape[l] * m * m;
                }
                s
            }
        };
        (s, shape, area)
    }

    /// [`Setup::term`] of quad `p` whose metric, shape and area ([`energy::shapes_and_areas`]) are
    /// known (`scores`, as [`Setup::quality_and_area`] gives them).
    #[inline]
    pub fn term_given(&self, quad: usize, p: &[Point; 4], scores: (f64, f64, f64)) -> Option<f64> {
        self.feasible_given(quad, p, scores)
            .map(|(s, _)| (1.0 - s) * (1.0 - s))
    }

    /// Visits `quads` (over `vertices`) in order, each with its corners and, when it is valid
    /// and above its floors, its metric and shape ([`Setup::feasible_quality`]); the quads
    /// scored [`LANES`] at a time, side by side ([`Setup::qualities_and_areas`]). Stops when
    /// `visit` returns false.
    #[inline]
    pub(crate) fn visit_feasible(
        &self,
        quads: &[u32],
        vertices: &[Point],
        mut visit: impl FnMut(&[Point; 4], Option<(f64, f64)>) -> bool,
    ) {
        for group in quads.chunks(LANES) {
            // The last group padded with its last quad, whose results are not read.
            let corners: [[Point; 4]; LANES] = std::array::from_fn(|l| {
                self.quads[group[l.min(group.len() - 1)] as usize].map(|u| vertices[u as usize])
            });
            let (metric, shape, area) = self.qualities_and_areas(&corners);
            for (l, &q) in group.iter().enumerate() {
                let scores = (metric[l], shape[l], area[l]);
                if !visit(
                    &corners[l],
                    self.feasible_given(q as usize, &corners[l], scores),
                ) {
                    return;
                }
            }
        }
    }

    /// The metric and the shape of quad `p` when it is valid and above both floors.
    #[inline]
    fn feasible_quality(&self, quad: usize, p: &[Point; 4]) -> Option<(f64, f64)> {
        self.feasible_given(quad, p, self.quality_and_area(p))
    }

    /// [`Setup::feasible_quality`] given the quad's metric, shape and area (`scores`).
    #[inline]
    fn feasible_given(
        &self,
        quad: usize,
        p: &[Point; 4],
        (s, shape, area): (f64, f64, f64),
    ) -> Option<(f64, f64)> {
        if !((shape >= SURE_SHAPE && area > 0.0) || is_valid(p)) {
            return None;
        }
        let jacobian = self.jacobian_floors[quad];
        // At every corner the scaled Jacobian α / (|a| |b|) is at least the shape's
        // 2α / (|a|² + |b|²): a shape clear of the floor spares computing the Jacobian.
        (s >= self.quality_floors[quad]
            && shape >= self.shape_floors[quad]
            && (jacobian == f64::NEG_INFINITY
                || shape >= jacobian + JACOBIAN_MARGIN
                || energy::jacobian_at_least(p, jacobian)))
        .then_some((s, shape))
    }

    /// The energy term of quad `p` and its gradient with respect to each corner (`None` where
    /// [`Setup::term`] is). Shape is the minimum over the corners: its gradient is that of the
    /// worst corner (a subgradient where two tie).
    pub fn term_gradient(&self, quad: usize, p: &[Point; 4]) -> Option<(f64, [Point; 4])> {
        let (s, shape) = self.feasible_quality(quad, p)?;
        let e = (1.0 - s) * (1.0 - s);
        // ∂shape/∂p at the worst corner k (the first of equals): shape = 2α / D, α = a × b,
        // D = |a|² + |b|², with a = p_k − p_{k−1} and b = p_{k+1} − p_k.
        let k = worst_corner(p);
        let (u, c, v) = (p[(k + 3) % 4], p[k], p[(k + 1) % 4]);
        let (a, b) = (c - u, v - c);
        let alpha = a.x * b.y - a.y * b.x;
        let d = a.x * a.x + a.y * a.y + b.x * b.x + b.y * b.y;
        let scale = 2.0 / (d * d);
        let da = Point::new(b.y * d - 2.0 * alpha * a.x, -b.x * d - 2.0 * alpha * a.y) * scale;
        let db = Point::new(-a.y * d - 2.0 * alpha * b.x, a.x * d - 2.0 * alpha * b.y) * scale;
        let mut ds = [Point::new(0.0, 0.0); 4];
        ds[(k + 3) % 4] = da * -1.0;
        ds[k] = da - db;
        ds[(k + 1) % 4] = db;
        if self.metric == Metric::ShapeAndSize {
            // relative size min(R, 1/R)², R = area / Ā, ∂area/∂p_i = ½ (y_{i+1} − y_{i−1},
            // x_{i−1} − x_{i+1}).
            let r = energy::area(p) / self.average_area;
            let (rel, drel) = if r < 1.0 {
                (r * r, 2.0 * r)
            } else {
                (1.0 / (r * r), -2.0 / (r * r * r))
            };
            for i in 0..4 {
                let (next, prev) = (p[(i + 1) % 4], p[(i + 3) % 4]);
                let darea = Point::new(next.y - prev.y, prev.x - next.x) * 0.5;
                ds[i] = ds[i] * rel + darea * (shape * drel / self.average_area);
            }
        }
        Some((e, ds.map(|g| g * (-2.0 * (1.0 - s)))))
    }

    /// The whole energy over `vertices`. The terms are computed in parallel but summed in
    /// order, so that the sum (and the sweeps' stopping test) is the same on any number of
    /// threads.
    pub fn energy(&self, vertices: &[Point]) -> f64 {
        let terms: Vec<f64> = (0..self.quads.len())
            .into_par_iter()
            .map(|q| (1.0 - self.value(vertices, q)).powi(2))
            .collect();
        terms.iter().sum()
    }
}

/// The quality of the quads and its histograms, every metric computed once for both.
fn measure(vertices: &[Point], quads: &[[u32; 4]]) -> (QuadQuality, QuadHistograms) {
    let v: Vec<[f64; 2]> = vertices.iter().map(|p| [p.x, p.y]).collect();
    QuadQuality::with_histograms(&v, quads)
}

/// What [`optimise`] builds from the start mesh before it moves anything.
struct Prepared {
    /// The method's variables (none for [`Method::None`]).
    variables: Option<Variables>,
    /// The free quad vertices the local mode moves after its control points
    /// ([`OptimOptions::control_sweeps`]).
    vertex_variables: Option<Variables>,
    /// The sliders, and the free vertices near them that follow them (when sliding).
    sliders: slide::Sliders,
    polish_variables: Option<Variables>,
    /// The start's quality and histograms.
    before: QuadQuality,
    histograms_before: QuadHistograms,
}

/// [`Prepared`] for `method`: the variables on one side, the sliders, the sliding's vertex
/// variables and the start's quality on the other (all read the mesh only; most of the
/// variables' indexing is sequential).
fn prepare(remesh: &Remesh, options: &OptimOptions, sliding: bool) -> Prepared {
    let t = &remesh.dt.triangulation;
    let (elements, mesh) = (&remesh.elements, &remesh.mesh);
    let then_vertices = options.method == Method::Local && options.control_sweeps.is_some();
    let ((variables, vertex_variables), (sliders, polish_variables, (before, histograms_before))) =
        rayon::join(
            || match options.method {
                Method::None => (None, None),
                Method::Laplacian | Method::Vertex => {
                    (Some(Variables::vertices(t, elements, mesh)), None)
                }
                Method::Local | Method::Global => {
                    let (control, vertices) = rayon::join(
                        || Variables::control_points(t, elements, &remesh.net, mesh),
                        || then_vertices.then(|| Variables::vertices(t, elements, mesh)),
                    );
                    (Some(control), vertices)
                }
            },
            || {
                let (sliders, polish) = if sliding {
                    let sliders = slide::Sliders::new(remesh);
                    let near = sliders.near(&mesh.quads, mesh.vertices.len(), POLISH_RINGS);
                    let polish = Variables::vertices_where(t, elements, mesh, |v| near[v as usize]);
                    (sliders, Some(polish))
                } else {
                    (slide::Sliders::default(), None)
                };
                (sliders, polish, measure(&mesh.vertices, &mesh.quads))
            },
        );
    Prepared {
        variables,
        vertex_variables,
        sliders,
        polish_variables,
        before,
        histograms_before,
    }
}

/// Optimises the quad mesh of `remesh` in place (its control net too, in the control-point
/// modes), keeping every quad valid and every constrained point where it was.
///
/// # Errors
/// [`OptimError::InvalidStart`] when the mesh given has an invalid quad;
/// [`OptimError::Solver`] if argmin fails in the global mode.
pub fn optimise(remesh: &mut Remesh, options: &OptimOptions) -> Result<OptimReport, OptimError> {
    let clock = Instant::now();
    let sliding = options.slide && matches!(options.method, Method::Local | Method::Vertex);
    if let Some(quad) = (0..remesh.mesh.quads.len())
        .into_par_iter()
        .find_first(|&q| !remesh.mesh.is_valid(q))
    {
        return Err(OptimError::InvalidStart { quad });
    }
    let Prepared {
        variables: prepared,
        vertex_variables,
        mut sliders,
        polish_variables,
        before,
        histograms_before,
    } = prepare(remesh, options, sliding);
    let Remesh {
        dt,
        elements,
        net,
        mesh,
        ..
    } = remesh;
    let quads = mesh.quads.clone();
    // Where the vertices of G' start: only the repair moves them.
    let corners_at_start: Vec<(usize, Point)> = (dt.graph_vertex.iter().enumerate())
        .filter(|&(v, &g)| g != imesh_quad::NONE && v < mesh.vertices.len())
        .map(|(v, _)| (v, mesh.vertices[v]))
        .collect();
    let (shape_floors, jacobian_floors): (Vec<f64>, Vec<f64>) = quads
        .par_iter()
        .map(|q| {
            let p = q.map(|v| [mesh.vertices[v as usize].x, mesh.vertices[v as usize].y]);
            let shape = imesh_quality::quad::shape(&p);
            // A shape of at least `keep_shape` holds the scaled Jacobian above `keep_shape`
            // only: the start's worst can be higher (a mesh of good quads).
            let jacobian = if shape < options.keep_shape {
                imesh_quality::quad::scaled_jacobian(&p)
            } else {
                before.scaled_jacobian.min
            };
            (
                shape.min(options.keep_shape).max(before.shape.min),
                jacobian,
            )
        })
        .unzip();
    let average_area = if quads.is_empty() {
        0.0
    } else {
        mesh.area() / quads.len() as f64
    };
    let mut setup = Setup {
        quads: &quads,
        metric: options.metric,
        average_area,
        quality_floors: &[],
        shape_floors: &shape_floors,
        jacobian_floors: &jacobian_floors,
        max_sweeps: options.max_sweeps,
        tolerance: options.tolerance,
        local_iterations: options.local_iterations.max(1),
        local_solver: options.local_solver,
        settled_term: (1.0 - options.settled.clamp(0.0, 1.0)).powi(2),
    };
    let start: Vec<f64> = (0..quads.len())
        .into_par_iter()
        .map(|q| setup.value(&mesh.vertices, q))
        .collect();
    let worst = start.iter().copied().fold(f64::INFINITY, f64::min);
    let quality_floors: Vec<f64> = start
        .iter()
        .map(|&s| {
            // Never below the start's worst, however low the bar.
            if s >= options.keep_quality {
                options.keep_quality.max(worst)
            } else {
                worst
            }
        })
        .collect();
    setup.quality_floors = &quality_floors;
    let energy_before = setup.energy(&mesh.vertices);
    let t = &dt.triangulation;
    let (variables, colours, sweeps) = match (options.method, &prepared) {
        (Method::None, _) | (_, None) => (0, 0, 0),
        (Method::Laplacian, Some(vars)) => {
            let sweeps = laplacian::smooth(vars, &mut mesh.vertices, &setup);
            (vars.len(), 0, sweeps)
        }
        (Method::Vertex, Some(vars)) => {
            let sweeps = local::descend(vars, &mut mesh.vertices, None, setup, |v| setup.energy(v));
            (vars.len(), vars.colours.len(), sweeps)
        }
        (Method::Local, Some(vars)) => {
            let control = Setup {
                max_sweeps: options.control_sweeps.unwrap_or(setup.max_sweeps),
                ..setup
            };
            let mut sweeps = local::descend(
                vars,
                &mut mesh.vertices,
                Some(&mut net.points),
                control,
                |v| setup.energy(v),
            );
            // Then the quad vertices, from where the control points left them (the net is no
            // longer read: the mesh is the result).
            if let Some(vertex_vars) = &vertex_variables {
                let vertices = Setup {
                    tolerance: options.vertex_tolerance,
                    ..setup
                };
                sweeps += local::descend(vertex_vars, &mut mesh.vertices, None, vertices, |v| {
                    setup.energy(v)
                });
            }
            (vars.len(), vars.colours.len(), sweeps)
        }
        (Method::Global, Some(vars)) => {
            let iterations = global::minimise(
                vars,
                &mut mesh.vertices,
                &mut net.points,
                setup,
                options.global_iterations,
            )
            .map_err(|e| OptimError::Solver(e.to_string()))?;
            (vars.len(), 0, iterations)
        }
    };
    let sweeps = if let Some(vertex_vars) = &polish_variables {
        // The boundary vertices slide along their curves, and the inside follows, every quad
        // held to the same floors (the start's worst scaled Jacobian at least).
        let polish = Setup {
            max_sweeps: POLISH_SWEEPS,
            ..setup
        };
        sweeps
            + sliders.sweep(&mut mesh.vertices, &polish, options.max_sweeps)
            + local::descend(vertex_vars, &mut mesh.vertices, None, polish, |v| {
                polish.energy(v)
            })
    } else {
        sweeps
    };
    let (repaired, repaired_sliders, quality_repaired) =
        if options.repair && matches!(options.method, Method::Local | Method::Vertex) {
            let (descended, descended_along) = (mesh.vertices.clone(), sliders.positions());
            // The repair trades a quad's size for the corners of its neighbours: of the metric it
            // keeps only the start's worst (held to each quad's own, it left grass's worst shape
            // 0.136 → 0.106 and stardist's 0.312 → 0.302); a quad's shape and scaled Jacobian may
            // fall to REPAIR_FLOOR (a quad already under it stays where it is or above), never
            // below the start's worst, so the worst of neither falls.
            let loose = vec![worst; quads.len()];
            let (shape_now, jacobian_now): (Vec<f64>, Vec<f64>) = quads
                .par_iter()
                .map(|q| {
                    let [shape, jacobian] = repair::held_at(&mesh.vertices, q);
                    (
                        shape.max(before.shape.min),
                        jacobian.max(before.scaled_jacobian.min),
                    )
                })
                .unzip();
            let repair_setup = Setup {
                quality_floors: &loose,
                shape_floors: &shape_now,
                jacobian_floors: &jacobian_now,
                ..setup
            };
            // The free vertices first; then the boundary vertices along their curves, for the
            // corners pinned between them, and the free vertices again around the moved ones.
            // Measured with the defaults against the free vertices alone: worst scaled Jacobian
            // brick 0.364 → 0.500, coffee 0.429 → 0.453 (mean of nine 0.460 → 0.477), worst shape
            // mean of nine 0.333 → 0.378; at 3 px 0.398 → 0.407 and 0.305 → 0.354; mean
            // shape-and-size within 0.0003.
            let mut moved = repair::repair(t, elements, mesh, &repair_setup, REPAIR_JACOBIAN);
            let slid = sliders.repair(&mut mesh.vertices, &repair_setup, REPAIR_JACOBIAN);
            if slid > 0 {
                moved += slid + repair::repair(t, elements, mesh, &repair_setup, REPAIR_JACOBIAN);
            }
            // Then every quad still under the bar with the free vertices and sliders around it
            // moved at once, within the energy the repairs left (measured with the defaults,
            // worst shape before and after one pass: camera 0.251 → 0.480, coffee 0.306 →
            // 0.431, brick 0.383 → 0.462, gravel 0.321 → 0.414 and its worst scaled Jacobian
            // 0.484 → 0.500; see the module), pass after pass ([`OptimOptions::joint_passes`]).
            let (around, fixed) = (vertex_quads(mesh), fixed_vertices(t, elements, mesh));
            let reach = corner_reach(dt, mesh, options.corner_reach * average_area.sqrt());
            let slack = energy_before - setup.energy(&mesh.vertices);
            moved += joint::repair_jointly::<{ joint::BATCH }>(
                &mut mesh.vertices,
                &around,
                &fixed,
                &reach,
                &mut sliders,
                &repair_setup,
                joint::Aim::Corners(REPAIR_JACOBIAN),
                joint::Budget {
                    first: usize::MAX,
                    slack,
                    passes: options.joint_passes,
                    later: joint::LATER_PASS_QUADS,
                    graded: usize::MAX,
                },
            );
            // Last, with shape-and-size, the quads under POOR_QUALITY, each with its
            // neighbourhood, lifted towards QUALITY_BAR: mostly quads a third to half the mean
            // area at a tip or in a strip, which the energy of all the quads leaves there. Not
            // on a graded mesh, most of whose quads are that small by design.
            let mut raised = 0;
            if options.quality_repair && options.metric == Metric::ShapeAndSize {
                let slack = energy_before - setup.energy(&mesh.vertices);
                raised = joint::repair_jointly::<{ joint::BATCH }>(
                    &mut mesh.vertices,
                    &around,
                    &fixed,
                    &reach,
                    &mut sliders,
                    &repair_setup,
                    joint::Aim::Quality {
                        poor: POOR_QUALITY,
                        bar: QUALITY_BAR,
                    },
                    joint::Budget {
                        first: (QUALITY_SHARE * quads.len() as f64).ceil() as usize,
                        slack,
                        passes: 1,
                        later: 0,
                        graded: (GRADED_SHARE * quads.len() as f64).floor() as usize,
                    },
                );
            }
            // Repair trades energy for corners; it never takes back more than the descent gained
            // (on the fixtures it costs 0.001 of mean shape-and-size at most).
            if moved + raised > 0 && setup.energy(&mesh.vertices) > energy_before {
                mesh.vertices = descended;
                sliders.restore(descended_along);
                (0, 0, 0)
            } else {
                (moved, slid, raised)
            }
        } else {
            (0, 0, 0)
        };
    // Sliding re-evaluates boundary vertices on their curves, the border's too.
    mesh.snap_to_border(t, elements);
    let energy_after = setup.energy(&mesh.vertices);
    let (after, histograms_after) = measure(&mesh.vertices, &mesh.quads);
    let slider_count = sliders.len();
    let moved: Vec<(usize, f64)> = corners_at_start
        .iter()
        .map(|&(v, p)| (v, mesh.vertices[v].distance_squared(p).sqrt()))
        .filter(|&(_, d)| d > 0.0)
        .collect();
    let corner_shift = moved.iter().map(|&(_, d)| d).fold(0.0, f64::max);
    // A moved corner is off its chains' ends: the sides beside it leave the chains (a
    // second-order side there stays straight).
    let boundary = sliding.then(|| {
        let mut chains = sliders.into_chains();
        if !moved.is_empty() {
            let mut off = vec![false; mesh.vertices.len()];
            for &(v, _) in &moved {
                off[v] = true;
            }
            for c in &mut chains {
                let kept: Vec<(u32, f64)> = (c.vertices.iter().zip(&c.along))
                    .filter(|&(&v, _)| !off[v as usize])
                    .map(|(&v, &a)| (v, a))
                    .collect();
                (c.vertices, c.along) = kept.into_iter().unzip();
            }
        }
        chains
    });
    Ok(OptimReport {
        method: options.method,
        metric: options.metric,
        variables,
        colours,
        average_area,
        energy_before,
        energy_after,
        sweeps,
        sliders: slider_count,
        boundary,
        repaired,
        repaired_sliders,
        quality_repaired,
        moved_corners: moved.len(),
        corner_shift,
        seconds: clock.elapsed().as_secs_f64(),
        before,
        after,
        histograms_before,
        histograms_after,
    })
}

/// Per quad vertex, how far the repair may move it ([`OptimOptions::corner_reach`]): `reach`
/// from where it is for a vertex of G', along the domain's border for one on it, nothing for
/// the rest and the domain's corners (empty when `reach` is 0). The border is where the mesh's
/// extreme coordinates are: its vertices there were put exactly on it, and a vertex moving
/// along it keeps that coordinate to the bit.
fn corner_reach(
    dt: &imesh_quad::RegionTriangulation,
    mesh: &imesh_quad::QuadMesh,
    reach: f64,
) -> Vec<joint::Reach> {
    if reach <= 0.0 {
        return Vec::new();
    }
    let (mut lo, mut hi) = (
        Point::new(f64::INFINITY, f64::INFINITY),
        Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in &mesh.vertices {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    (0..mesh.vertices.len())
        .map(|v| {
            let origin = mesh.vertices[v];
            let graph = dt
                .graph_vertex
                .get(v)
                .is_some_and(|&g| g != imesh_quad::NONE);
            // An axis is held where the vertex is on a side across it.
            let free = |c: f64, lo: f64, hi: f64| if c == lo || c == hi { 0.0 } else { 1.0 };
            let axes = Point::new(free(origin.x, lo.x, hi.x), free(origin.y, lo.y, hi.y));
            let moves = graph && (axes.x > 0.0 || axes.y > 0.0);
            joint::Reach {
                origin,
                reach: if moves { reach } else { 0.0 },
                axes,
            }
        })
        .collect()
}

#[cfg(test)]
impl<'a> Setup<'a> {
    /// The tests' setup of `quads`: `metric` against a mean quad area of 1, quad `q` held to
    /// quality `quality[q]`, shape `shape[q]` and scaled Jacobian `jacobian[q]`, one sweep of
    /// one Powell iteration per solve.
    pub(crate) fn held(
        quads: &'a [[u32; 4]],
        metric: Metric,
        [quality, shape, jacobian]: [&'a [f64]; 3],
    ) -> Self {
        Setup {
            quads,
            metric,
            average_area: 1.0,
            quality_floors: quality,
            shape_floors: shape,
            jacobian_floors: jacobian,
            max_sweeps: 1,
            tolerance: 0.0,
            local_iterations: 1,
            local_solver: LocalSolver::Powell,
            settled_term: 0.0,
        }
    }
}

/// The boundary graphs of label grids that imesh-curves' tests build.
#[cfg(test)]
#[path = "../../imesh-curves/tests/support/mod.rs"]
mod support;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The analytic gradient of a term against central differences.
    fn check_gradient(metric: Metric, p: [Point; 4]) -> Result<(), TestCaseError> {
        let setup = Setup {
            metric,
            average_area: 1.3,
            ..unit_setup()
        };
        let Some((_, gradient)) = setup.term_gradient(0, &p) else {
            return Ok(());
        };
        let h = 1e-6;
        for i in 0..4 {
            for axis in 0..2 {
                let step = if axis == 0 {
                    Point::new(h, 0.0)
                } else {
                    Point::new(0.0, h)
                };
                let (mut plus, mut minus) = (p, p);
                plus[i] = plus[i] + step;
                minus[i] = minus[i] - step;
                let (Some(a), Some(b)) = (setup.term(0, &plus), setup.term(0, &minus)) else {
                    continue;
                };
                let numeric = (a - b) / (2.0 * h);
                let analytic = if axis == 0 {
                    gradient[i].x
                } else {
                    gradient[i].y
                };
                // The shape is a minimum over corners: skip points where the worst corner changes
                // within the step (the one-sided slopes differ there).
                let kink = { worst_corner(&plus) != worst_corner(&minus) };
                if !kink {
                    prop_assert!(
                        (numeric - analytic).abs() <= 1e-5 * (1.0 + numeric.abs()),
                        "corner {i} axis {axis}: {numeric} vs {analytic}"
                    );
                }
            }
        }
        Ok(())
    }

    /// The optimiser's shape of the one quad `p`.
    fn shape_of(p: &[Point; 4]) -> f64 {
        energy::shapes_and_areas(&[*p]).0[0]
    }

    /// A setup of one quad with no floors.
    fn unit_setup() -> Setup<'static> {
        Setup::held(
            &[[0, 1, 2, 3]],
            Metric::ShapeAndSize,
            [&[0.0], &[0.0], &[f64::NEG_INFINITY]],
        )
    }

    /// Two or four coincident corners make a corner's shape 0/0: the quad's shape is still 0,
    /// wherever the NaN corner falls in the order of the corners.
    #[test]
    fn a_quad_with_coincident_corners_has_shape_zero() {
        let (a, b, c) = (
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.0, 1.0),
        );
        for quad in [
            [a, a, a, b],
            [a, b, a, a],
            [a, a, b, c],
            [b, a, a, a],
            [a, a, a, a],
        ] {
            for turn in 0..4 {
                let p: [Point; 4] = std::array::from_fn(|i| quad[(i + turn) % 4]);
                assert_eq!(shape_of(&p), 0.0, "{p:?}");
                assert_eq!(energy::shapes_and_areas(&[p, p]).0, [0.0; 2], "{p:?}");
                assert_eq!(
                    imesh_quality::quad::shape(&p.map(|p| [p.x, p.y])),
                    0.0,
                    "{p:?}"
                );
            }
        }
    }

    proptest! {
        /// The shortcut of [`SURE_SHAPE`] never calls a quad valid that the exact test calls
        /// invalid: random quads, flat ones (a corner nudged by a hair off its neighbours'
        /// line), far from the origin.
        #[test]
        fn a_sure_shape_is_a_valid_quad(
            corners in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 4),
            offset in -1e6f64..1e6, scale in 1e-6f64..1e3, flat in 0usize..4, hair in -1e-9f64..1e-9,
        ) {
            // A jittered unit square (mostly convex), or its mirror image half the time.
            let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
            let mirror = if corners[0].0 < 0.0 { -1.0 } else { 1.0 };
            let mut p: [Point; 4] = std::array::from_fn(|i| {
                Point::new(
                    offset + mirror * scale * (square[i].0 + 0.3 * corners[i].0),
                    offset / 2.0 + scale * (square[i].1 + 0.3 * corners[i].1),
                )
            });
            // Corner `flat` on the line of its neighbours, nudged across by `hair` of the scale.
            let (a, b) = (p[(flat + 3) % 4], p[(flat + 1) % 4]);
            p[flat] = Point::new(0.5 * (a.x + b.x) - hair * scale * (b.y - a.y), 0.5 * (a.y + b.y) + hair * scale * (b.x - a.x));
            let shape = shape_of(&p);
            if shape >= SURE_SHAPE && energy::area(&p) > 0.0 {
                prop_assert!(is_valid(&p), "{p:?}: shape {shape}");
            }
        }

        /// The optimiser's shape is Verdict's to the bit on every counter-clockwise quad, and
        /// 0 where a corner turns right, the quad being convex, reflex or crossed, at any
        /// scale and offset.
        #[test]
        fn the_optimisers_shape_is_verdicts(
            corners in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 4),
            scale in 1e-3f64..1e3, offset in -1e4f64..1e4,
        ) {
            let p: [Point; 4] = std::array::from_fn(|i| {
                Point::new(offset + scale * corners[i].0, offset / 3.0 + scale * corners[i].1)
            });
            let verdict = imesh_quality::quad::shape(&p.map(|p| [p.x, p.y]));
            let ours = shape_of(&p);
            if is_valid(&p) {
                prop_assert_eq!(ours.to_bits(), verdict.to_bits(), "{:?}", p);
            } else {
                prop_assert!(ours < SURE_SHAPE, "{:?}: {}", p, ours);
            }
        }

        /// Four quads scored side by side give each quad's metric, shape and area to the bit
        /// as one by one, for both metrics: valid, clockwise, crossed and flat quads (a corner
        /// on its neighbours' line), at any scale and offset.
        #[test]
        fn quads_side_by_side_score_as_one_by_one(
            corners in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 16),
            scale in 1e-3f64..1e3, offset in -1e4f64..1e4, flat in 0usize..5,
            average_area in 1e-3f64..1e3,
        ) {
            let mut quads: [[Point; 4]; 4] = std::array::from_fn(|l| {
                std::array::from_fn(|i| {
                    let (x, y) = corners[4 * l + i];
                    Point::new(offset + scale * x, offset / 3.0 + scale * y)
                })
            });
            if flat < 4 {
                let q = &mut quads[flat];
                q[1] = Point::new(0.5 * (q[0].x + q[2].x), 0.5 * (q[0].y + q[2].y));
            }
            for metric in [Metric::ShapeAndSize, Metric::Shape] {
                let setup = Setup { metric, average_area, ..unit_setup() };
                let (s, shape, area) = setup.qualities_and_areas(&quads);
                for (l, quad) in quads.iter().enumerate() {
                    let (s1, shape1, area1) = setup.quality_and_area(quad);
                    prop_assert_eq!(
                        [s[l].to_bits(), shape[l].to_bits(), area[l].to_bits()],
                        [s1.to_bits(), shape1.to_bits(), area1.to_bits()],
                        "{:?} {:?}", quad, metric
                    );
                }
            }
        }

        /// The quick scaled-Jacobian tests give Verdict's answers on every valid quad, at any
        /// scale and offset, for bounds on and a few ulps either side of Verdict's value (where
        /// the quick value cannot tell) and far from it (where it does).
        #[test]
        fn quick_jacobian_tests_answer_as_verdict(
            corners in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 4),
            thin in 0.0f64..1.0,
            scale in 1e-3f64..1e3, offset in -1e4f64..1e4,
            ulps in -3i64..=3, far in -1.0f64..1.0,
        ) {
            // A jittered unit square squeezed towards a sliver, mostly valid.
            let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
            let p: [Point; 4] = std::array::from_fn(|i| {
                Point::new(
                    offset + scale * (square[i].0 + 0.4 * corners[i].0),
                    offset / 3.0 + scale * (1.0 - thin) * (square[i].1 + 0.4 * corners[i].1),
                )
            });
            prop_assume!(is_valid(&p));
            let verdict = energy::verdict_jacobian(&p);
            let near = f64::from_bits((verdict.to_bits() as i64 + ulps) as u64);
            for bound in [verdict, near, far, verdict + 1e-7, verdict - 1e-7] {
                prop_assert_eq!(energy::jacobian_at_least(&p, bound), verdict >= bound, "{:?} {}", p, bound);
                let under = energy::jacobian_under(&p, bound);
                prop_assert_eq!(under.min(bound).to_bits(), verdict.min(bound).to_bits(), "{:?} {}", p, bound);
            }
        }

        #[test]
        fn term_gradients_match_central_differences(
            jitter in proptest::collection::vec(-0.3f64..0.3, 8), scale in 0.5f64..2.0,
        ) {
            let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
            let p: [Point; 4] = std::array::from_fn(|i| {
                Point::new(
                    (square[i].0 + jitter[2 * i]) * scale,
                    (square[i].1 + jitter[2 * i + 1]) * scale,
                )
            });
            check_gradient(Metric::ShapeAndSize, p)?;
            check_gradient(Metric::Shape, p)?;
        }
    }
}
