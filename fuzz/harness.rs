//! Fuzz harnesses: each turns arbitrary bytes into an input for one part of imesh, runs it, and
//! panics only when an invariant breaks. A typed error is a correct answer to bad input; a panic,
//! a hang or an invalid mesh is a bug.
//!
//! Compiled twice: by the cargo-fuzz targets (`fuzz/fuzz_targets/`) and by the regression test
//! `crates/imesh/tests/fuzz_regressions.rs`, which replays every input under `fuzz/regressions/`.

#![allow(dead_code)]

use imesh::{
    ElementSize, Elements, MeshOptions, OptimizerMethod, PairingMethod, Pipeline, PipelineError,
};
use imesh_classify::{LabelGrid, Region};
use imesh_curves::{segment_distance, CurveGraph, SimplifyOptions};
use imesh_geom::{
    GeomError, Location, Point, RefineOptions, StopReason, TriangleId, Triangulation,
};
use imesh_segment::{SampleOptions, SegmentedMesh};

/// Reads the input a byte at a time; past its end every byte is 0, so any input is complete.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    fn new(data: &'a [u8]) -> Self {
        Self { data, at: 0 }
    }

    fn u8(&mut self) -> u8 {
        let b = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        b
    }

    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    fn f64(&mut self) -> f64 {
        let mut b = [0; 8];
        b.iter_mut().for_each(|x| *x = self.u8());
        f64::from_le_bytes(b)
    }

    fn left(&self) -> usize {
        self.data.len().saturating_sub(self.at)
    }

    /// One of `choices`, by the next byte.
    fn pick<T: Copy>(&mut self, choices: &[T]) -> T {
        choices[usize::from(self.u8()) % choices.len()]
    }
}

/// Points in one of three encodings, chosen by the first byte: a 16 × 16 half-pixel lattice
/// (massively collinear and cocircular, like pixel centres), 16-bit integers over 16 (fine but
/// exact), or raw `f64` bits (NaN, infinities, subnormals, huge values).
fn points(b: &mut Bytes, most: usize) -> Vec<Point> {
    let mode = b.u8() % 3;
    let mut out = Vec::new();
    while b.left() > 0 && out.len() < most {
        out.push(match mode {
            0 => {
                let (x, y) = (b.u8(), b.u8());
                Point::new(f64::from(x % 16) * 0.5, f64::from(y % 16) * 0.5)
            }
            1 => Point::new(
                f64::from(b.u16() as i16) / 16.0,
                f64::from(b.u16() as i16) / 16.0,
            ),
            _ => Point::new(b.f64(), b.f64()),
        });
    }
    out
}

/// Incremental insertion and bulk construction of the same points: both pass the exhaustive
/// `check()` (Delaunay with exact predicates, topology), refuse the same bad points, and agree on
/// the vertex and triangle counts.
pub fn delaunay(data: &[u8]) {
    let mut b = Bytes::new(data);
    let pts = points(&mut b, 2000);
    let mut incremental = Triangulation::new();
    let mut refused = false;
    for &p in &pts {
        match incremental.insert(p) {
            Ok(v) => assert_eq!(incremental.point(v), p, "a vertex moved"),
            Err(GeomError::NonFinitePoint { .. } | GeomError::OutOfRange { .. }) => refused = true,
            Err(e) => panic!("insert: {e}"),
        }
    }
    if let Err(e) = incremental.check() {
        panic!("incremental: {e:?}");
    }
    match Triangulation::from_points(&pts) {
        Ok((bulk, ids)) => {
            assert!(!refused, "bulk accepted a point insert refused");
            if let Err(e) = bulk.check() {
                panic!("bulk: {e:?}");
            }
            assert_eq!(bulk.num_vertices(), incremental.num_vertices());
            assert_eq!(bulk.num_triangles(), incremental.num_triangles());
            for (p, v) in pts.iter().zip(ids) {
                assert_eq!(bulk.point(v), *p);
            }
        }
        Err(GeomError::NonFinitePoint { .. } | GeomError::OutOfRange { .. }) => {
            assert!(refused, "bulk refused points insert accepted");
        }
        Err(e) => panic!("from_points: {e}"),
    }
}

/// The label of the triangle holding `p`, if `p` is strictly inside one.
fn label_at(t: &Triangulation, p: Point) -> Option<u32> {
    match t.locate(p) {
        Location::InTriangle(f) => Some(t.label(f)),
        _ => None,
    }
}

fn centroid(t: &Triangulation, f: TriangleId) -> Point {
    let [a, b, c] = t.triangle_points(f);
    Point::new((a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0)
}

/// The smallest altitude of triangle `f`.
fn smallest_altitude(t: &Triangulation, f: TriangleId) -> f64 {
    let [a, b, c] = t.triangle_points(f);
    let twice_area = ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)).abs();
    let longest = a
        .distance_squared(b)
        .max(b.distance_squared(c))
        .max(c.distance_squared(a));
    twice_area / longest.sqrt()
}

/// Segments (constrained or conforming) between lattice points, labels by flood fill from seeds,
/// then Ruppert refinement at an arbitrary angle and cap. Crossing segments must be refused with
/// an error; whatever is accepted must stay conforming, keep its labels and pass `check()`;
/// refinement must stop (libFuzzer's timeout catches a hang) within its cap.
pub fn refine(data: &[u8]) {
    let mut b = Bytes::new(data);
    let n = 3 + usize::from(b.u8() % 40);
    let pts: Vec<Point> = (0..n)
        .map(|_| Point::new(f64::from(b.u8() % 32), f64::from(b.u8() % 32)))
        .collect();
    let Ok((mut t, ids)) = Triangulation::from_points(&pts) else {
        panic!("lattice points refused");
    };
    if t.is_degenerate() {
        return;
    }
    let conforming = b.u8() % 2 == 1;
    for _ in 0..(b.u8() % 24) {
        let (i, j) = (usize::from(b.u8()) % n, usize::from(b.u8()) % n);
        let inserted = if conforming {
            t.insert_segment_conforming(ids[i], ids[j]).map(|_| ())
        } else {
            t.insert_segment(ids[i], ids[j]).map(|_| ())
        };
        match inserted {
            Ok(()) | Err(GeomError::CrossingSegments { .. } | GeomError::BadSegment { .. }) => {}
            Err(e) => panic!("segment: {e}"),
        }
        if let Err(e) = t.check() {
            panic!("after a segment: {e:?}");
        }
    }
    let seeds: Vec<(Point, u32)> = (0..1 + b.u8() % 4)
        .map(|k| {
            let p = Point::new(f64::from(b.u8() % 64) * 0.5, f64::from(b.u8() % 64) * 0.5);
            (p, 1 + u32::from(k))
        })
        .collect();
    assert_segments_conform(&t, conforming, "before refinement");
    t.label_regions(&seeds);
    // Probes: the centroid of every triangle but slivers, whose centroid lies within rounding
    // of an edge (a split point of a segment is rounded a hair off its line).
    let before: Vec<(Point, u32)> = t
        .triangles()
        .filter(|&f| smallest_altitude(&t, f) > 1e-9)
        .map(|f| (centroid(&t, f), t.label(f)))
        .collect();
    let options = RefineOptions {
        min_angle_deg: 5.0 + f64::from(b.u8() % 29),
        max_steiner: 3000,
        max_area: (b.u8() % 2 == 1).then(|| 1.0 + f64::from(b.u8() % 50)),
    };
    let report = match t.refine(&options) {
        Ok(r) => r,
        Err(e) => panic!("refine: {e}"),
    };
    assert!(report.inserted <= options.max_steiner);
    assert!(report.stopped == StopReason::Done || report.inserted == options.max_steiner);
    if let Err(e) = t.check() {
        panic!("after refinement: {e:?}");
    }
    // Every triangle lies inside one triangle of before: labels carried, never invented.
    for (p, label) in before {
        if let Some(now) = label_at(&t, p) {
            assert_eq!(now, label, "the label at {p:?} changed");
        }
    }
    assert_segments_conform(&t, conforming, "after refinement");
}

/// Every segment of `t` is a chain of constrained edges from end to end, each vertex within
/// rounding of the segment.
fn assert_segments_conform(t: &Triangulation, conforming: bool, when: &str) {
    for s in 0..t.num_segments() {
        let s = imesh_geom::SegmentId(s as u32);
        let chain = t.segment_vertices(s);
        let [a, z] = t.segment_ends(s);
        assert_eq!(chain.first(), Some(&a), "{when}");
        assert_eq!(chain.last(), Some(&z), "{when}");
        let (pa, pz) = (t.point(a), t.point(z));
        for w in chain.windows(2) {
            let Some(e) = t.find_edge(w[0], w[1]) else {
                panic!(
                    "{when}: segment {s:?} ({pa:?}–{pz:?}, conforming {conforming}): its piece {:?}–{:?} is no edge; chain {:?}",
                    t.point(w[0]),
                    t.point(w[1]),
                    chain.iter().map(|&v| t.point(v)).collect::<Vec<_>>()
                );
            };
            assert!(
                t.is_constrained(e),
                "{when}: segment {s:?} ({pa:?}–{pz:?}, conforming {conforming}): its piece {:?}–{:?} is not constrained",
                t.point(w[0]),
                t.point(w[1])
            );
            // Split points are rounded: within a few ulps of the segment, not exactly on it.
            let p = t.point(w[1]);
            let d =
                imesh_geom::predicates::orient2d(pa, pz, p).abs() / pa.distance_squared(pz).sqrt();
            let scale =
                pa.x.abs()
                    .max(pa.y.abs())
                    .max(pz.x.abs())
                    .max(pz.y.abs())
                    .max(1.0);
            assert!(
                d <= 1e-12 * scale,
                "{when}: a vertex of segment {s:?} is {d} off it"
            );
        }
    }
}

/// A label grid of up to 24 × 24 pixels and up to 6 labels, from the bytes.
fn label_grid(b: &mut Bytes) -> Option<LabelGrid> {
    let (w, h) = (1 + u32::from(b.u8() % 24), 1 + u32::from(b.u8() % 24));
    let k = 1 + u32::from(b.u8() % 6);
    let labels: Vec<u32> = (0..w * h).map(|_| u32::from(b.u8()) % k).collect();
    let used = labels.iter().max().map_or(1, |&m| m + 1);
    let regions = (0..used)
        .map(|i| Region {
            name: format!("r{i}"),
            colour: [i as u8; 3],
        })
        .collect();
    LabelGrid::new(w, h, labels, regions)
}

/// What identifies a face of a boundary graph through simplification: its label, the sign of its
/// area, and the polylines around it with the direction each is walked in.
type Signature = (u32, bool, Vec<(u32, bool)>);

fn signatures(g: &CurveGraph, direction_of: impl Fn(u32, bool) -> (u32, bool)) -> Vec<Signature> {
    let mut all: Vec<Signature> = g
        .faces()
        .into_iter()
        .map(|f| {
            let mut around: Vec<(u32, bool)> = f
                .walk
                .iter()
                .map(|&(e, fwd)| direction_of(e, fwd))
                .collect();
            around.sort_unstable();
            around.dedup();
            (f.label, f.area > 0.0, around)
        })
        .collect();
    all.sort();
    all
}

/// Imesh's c-edge graph of an arbitrary label image, simplified at an arbitrary tolerance: G'
/// stays planar, keeps every face with its label, has no face of zero area, and every removed
/// vertex is within the tolerance of its edge.
pub fn simplify(data: &[u8]) {
    let mut b = Bytes::new(data);
    let tolerance = f64::from(b.u8() % 64) * 0.25;
    let te = b.pick(&[0.05, 0.1, 0.3, 0.6]);
    let Some(grid) = label_grid(&mut b) else {
        panic!("an inconsistent label grid");
    };
    let segmented = match SegmentedMesh::from_grid(
        &grid,
        &SampleOptions {
            te,
            ..Default::default()
        },
    ) {
        Ok(s) => s,
        Err(e) => panic!("sampling: {e}"),
    };
    let g = match imesh::boundary_graph(&segmented) {
        Ok(g) => g,
        Err(e) => panic!("c-edge graph: {e}"),
    };
    assert_eq!(g.crossing(), None, "the c-edges cross");
    let s = match imesh_curves::simplify(&g, &SimplifyOptions::with_tolerance(tolerance)) {
        Ok(s) => s,
        Err(e) => panic!("simplify: {e}"),
    };
    assert_eq!(s.graph.crossing(), None, "G' has crossing edges");
    let mut owner = vec![(u32::MAX, false); g.edges().len()];
    for (l, line) in s.polylines.iter().enumerate() {
        for (i, &e) in line.edges.iter().enumerate() {
            let forward = g.edges()[e as usize].ends == [line.vertices[i], line.vertices[i + 1]];
            owner[e as usize] = (l as u32, forward);
        }
    }
    assert!(
        owner.iter().all(|o| o.0 != u32::MAX),
        "an edge in no polyline"
    );
    for (k, chain) in s.chains.iter().enumerate() {
        let [a, z] = s.graph.edges()[k].ends;
        for &v in chain {
            let d = segment_distance(g.point(a), g.point(z), g.point(v));
            assert!(
                d <= tolerance * (1.0 + 1e-12) + 1e-12,
                "vertex {v} is {d} px off"
            );
        }
    }
    let before = signatures(&g, |e, fwd| {
        let (l, forward) = owner[e as usize];
        (l, fwd == forward)
    });
    let after = signatures(&s.graph, |e, fwd| (s.polyline_of[e as usize], fwd));
    assert_eq!(before, after, "the faces changed");
    for f in s.graph.faces() {
        assert!(f.consistent, "a face of G' has two labels");
        assert!(f.area != 0.0, "a face of G' has no area");
    }
}

/// Panics unless `result` is a valid mesh or an error the user can act on.
fn assert_valid(result: Result<imesh::PipelineResult, PipelineError>, what: &str) {
    match result {
        Ok(r) => {
            let v = &r.report.validation;
            assert!(v.valid, "{what}: invalid");
            assert!(
                (v.area_ratio - 1.0).abs() < 1e-9,
                "{what}: area {}",
                v.area_ratio
            );
            assert!(r.report.counts.elements > 0, "{what}: no elements");
            assert!(
                r.report.quality.scaled_jacobian().min > 0.0,
                "{what}: inverted"
            );
        }
        Err(PipelineError::Limit(_)) => {}
        Err(e) => panic!("{what}: {e}"),
    }
}

/// The whole pipeline on an arbitrary label image with arbitrary options from the parameter
/// space (t_e, tolerance, smallest angle, largest size, template level, pairing, optimiser,
/// element kind): a valid mesh every time.
pub fn pipeline(data: &[u8]) {
    let mut b = Bytes::new(data);
    let options = MeshOptions {
        te: b.pick(&[0.05, 0.1, 0.3, 0.6]),
        tolerance: b.pick(&[Some(0.0), Some(0.5), Some(2.0), Some(5.0), Some(15.0)]),
        min_angle: b.pick(&[None, Some(10.0), Some(20.7), Some(28.0), Some(33.0)]),
        max_size: b.pick(&[None, None, Some(1.5), Some(4.0), Some(12.0)]),
        template_level: b.pick(&[1, 1, 2, 3]),
        pairing: b.pick(&[PairingMethod::Matching, PairingMethod::Greedy]),
        optimizer: b.pick(&[
            OptimizerMethod::Local,
            OptimizerMethod::Laplacian,
            OptimizerMethod::Vertex,
            OptimizerMethod::None,
            OptimizerMethod::Global,
        ]),
        global_iterations: 2,
        elements: b.pick(&[Elements::Quad, Elements::Quad, Elements::Tri]),
        ..MeshOptions::default()
    };
    let Some(grid) = label_grid(&mut b) else {
        panic!("an inconsistent label grid");
    };
    // The global optimiser is the paper's single Powell run, slow by design (seconds on a few
    // hundred quads under the sanitizer): only on the smallest images.
    let mut options = options;
    // Drawn after the grid, so that the saved inputs from before these options replay the same
    // grids (an exhausted input picks the first choice).
    options.size = b.pick(&[
        ElementSize::Graded,
        ElementSize::Auto,
        ElementSize::Pixels(1.0),
        ElementSize::Pixels(2.5),
    ]);
    options.min_region = b.pick(&[0, 3, 12]);
    options.majority = b.pick(&[Some(0), None, Some(1), Some(2)]);
    options.min_width = b.pick(&[None, Some(0.0), Some(3.0)]);
    if options.optimizer == OptimizerMethod::Global && grid.width() * grid.height() > 64 {
        options.optimizer = OptimizerMethod::Local;
    }
    assert_valid(
        Pipeline::new(options.clone()).run_grid(&grid, 0.0),
        &format!("{options:?}"),
    );
}

/// Any bytes through our image loader: an image or a clear error. Images it decodes are
/// classified and, when small, meshed (a valid mesh).
pub fn decode(data: &[u8]) {
    let image = match imesh_classify::decode_image(data, 1 << 16) {
        Ok(image) => image,
        Err(
            imesh_classify::ClassifyError::Decode { .. }
            | imesh_classify::ClassifyError::EmptyImage { .. }
            | imesh_classify::ClassifyError::TooLarge { .. },
        ) => return,
        Err(e) => panic!("decode: {e}"),
    };
    if u64::from(image.width()) * u64::from(image.height()) <= 48 * 48 {
        assert_valid(
            Pipeline::new(MeshOptions::default()).run_image(&image),
            "decoded image",
        );
    }
}

/// Any text through the mesh readers of `imesh quality` (the first byte picks the format): a
/// mesh whose every element's corners are among its points, or a clear error.
pub fn read(data: &[u8]) {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let format = imesh_io::MeshFormat::ALL[usize::from(first) % imesh_io::MeshFormat::ALL.len()];
    let text = String::from_utf8_lossy(rest);
    if let Ok(mesh) = imesh_io::parse_mesh(&text, format) {
        let n = mesh.vertices.len();
        for e in &mesh.elements {
            assert!(
                e.corners().iter().all(|&v| (v as usize) < n),
                "{format:?}: an element's corner beyond the {n} points"
            );
        }
    }
}
