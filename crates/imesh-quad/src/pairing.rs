//! Pairing triangles of DT' into strictly convex quads: the mixed mesh M (DESIGN.md §2, step 7).

use imesh_geom::predicates::orient2d;
use imesh_geom::{HalfEdgeId, Point, TriangleId, Triangulation, VertexId};
use imesh_quality::quad::{self, Quad};

use crate::dt::NONE;
use crate::mesh::{scaled_jacobian, valid_above};
use rayon::prelude::*;

/// How triangles are paired.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Pairing {
    /// The paper's triquad: unconstrained edges longest first; an edge whose two triangles are
    /// both free and form a strictly convex quad pairs them.
    #[default]
    Greedy,
    /// Best quads first (by their worst corner), then augmenting paths that re-pair neighbours so
    /// that more triangles find a partner; no quad with a corner under 30° or over 150°
    /// ([`MIN_MATCHING_CORNER`]): better quads, and no corner the optimiser must mend. Nor a
    /// corner over 125° between two boundaries with sides too unequal for a shape of 0.5
    /// ([`MIN_PINNED_CORNER_SHAPE`]). The triangles left are then moved along paths of
    /// re-pairings to where their quads come nearer the mean quad's area. A second matching,
    /// run alongside, also leaves the pairs whose quads would be over [`LARGE_PAIR`] times the
    /// mean area, and is kept where its straight template quads score within [`SPLIT_MARGIN`]
    /// of the first's ([`ElementMesh::straight_shape_and_size`]).
    Matching,
    /// The matching with the bar at about 20.5° ([`MIN_FEWEST_CORNER`]): fewer triangles left
    /// than [`Pairing::Greedy`], some quads with flatter corners.
    Fewest,
}

/// One element of M: a triangle or a quad of DT' vertices, counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Element {
    /// A triangle left unpaired.
    Triangle([u32; 3]),
    /// Two triangles paired across their common edge.
    Quad([u32; 4]),
}

impl Element {
    /// The corner vertices, counter-clockwise.
    pub fn corners(&self) -> &[u32] {
        match self {
            Element::Triangle(c) => c,
            Element::Quad(c) => c,
        }
    }
}

/// M: the elements of a pairing, with their edges numbered so that neighbours share them.
#[derive(Clone, Debug)]
pub struct ElementMesh {
    /// The elements.
    pub elements: Vec<Element>,
    /// The region label of each element.
    pub labels: Vec<u32>,
    /// For each element, per side `i` (from corner `i` to corner `i + 1`): the DT' half-edge on
    /// that side. A side's M edge is [`ElementMesh::edge_of`] that half-edge.
    pub sides: Vec<[HalfEdgeId; 4]>,
    /// The M edge of each DT' half-edge slot ([`NONE`] for a pairing diagonal or a ghost).
    edge_of_half: Vec<u32>,
    /// The canonical half-edge of each M edge (its direction is the edge's direction).
    pub edges: Vec<HalfEdgeId>,
    /// Triangles left unpaired.
    pub unpaired: usize,
    /// The element each DT' triangle slot belongs to ([`NONE`] for a ghost or dead slot).
    pub element_of_triangle: Vec<u32>,
}

impl ElementMesh {
    /// Pairs the triangles of `t` by `method`.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// use imesh_quad::{ElementMesh, Pairing};
    /// let pts = [Point::new(0.0, 0.0), Point::new(3.0, 0.0), Point::new(3.0, 2.0), Point::new(0.0, 2.0)];
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// let m = ElementMesh::pair(&t, Pairing::Greedy);
    /// assert_eq!((m.elements.len(), m.unpaired), (1, 0)); // the two triangles make the rectangle
    /// ```
    pub fn pair(t: &Triangulation, method: Pairing) -> Self {
        let partner = match method {
            Pairing::Greedy => greedy(t),
            Pairing::Matching => {
                // Both candidates weigh the same quads: their corner sines are found once.
                let sines = corner_sines(t, MIN_MATCHING_CORNER, true);
                let (kept, split) = rayon::join(
                    || matching_on(t, &sines, true, false),
                    || matching_on(t, &sines, true, true),
                );
                if split == kept {
                    return Self::from_partners(t, &kept);
                }
                let (kept, split) = rayon::join(
                    || Self::from_partners(t, &kept),
                    || Self::from_partners(t, &split),
                );
                let (kept_score, split_score) = rayon::join(
                    || kept.straight_shape_and_size(t),
                    || split.straight_shape_and_size(t),
                );
                return if split_score > kept_score - SPLIT_MARGIN {
                    split
                } else {
                    kept
                };
            }
            Pairing::Fewest => matching(t, MIN_FEWEST_CORNER, false, false, false),
        };
        Self::from_partners(t, &partner)
    }

    /// The mean shape-and-size of the straight level-1 template quads of these elements (each
    /// quad's corner, side midpoints and centre), against their own mean area: how well a
    /// pairing does before adaptation and optimisation, a cheap stand-in for what they reach
    /// ([`SPLIT_MARGIN`] says how far it can be trusted).
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// use imesh_quad::{ElementMesh, Pairing};
    /// let pts = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 2.0), Point::new(0.0, 2.0)];
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// let m = ElementMesh::pair(&t, Pairing::Matching);
    /// assert!((m.straight_shape_and_size(&t) - 1.0).abs() < 1e-12); // four unit squares
    /// ```
    pub fn straight_shape_and_size(&self, t: &Triangulation) -> f64 {
        // Summed over chunks of elements of a fixed length, then the chunks' sums in order: the
        // same sums on any number of threads.
        let sum = |term: &(dyn Fn(&Quad) -> f64 + Sync)| {
            self.elements
                .par_chunks(SUM_CHUNK)
                .map(|chunk| {
                    chunk
                        .iter()
                        .map(|e| {
                            let (quads, n) = straight_quads(t, e);
                            quads[..n].iter().map(term).sum::<f64>()
                        })
                        .sum::<f64>()
                })
                .collect::<Vec<f64>>()
                .iter()
                .sum::<f64>()
        };
        let count = 3 * self.unpaired + 4 * (self.elements.len() - self.unpaired);
        if count == 0 {
            return 0.0;
        }
        let mean = sum(&quad::area) / count as f64;
        sum(&|q| quad::shape_and_size(q, mean)) / count as f64
    }

    /// The M edge on `side` of element `element`, and whether the element walks it in the
    /// edge's own direction.
    pub fn side_edge(&self, element: usize, side: usize) -> (u32, bool) {
        let h = self.sides[element][side];
        let e = self.edge_of_half[h.index()];
        (e, self.edges[e as usize] == h)
    }

    /// The M edge of DT' half-edge `h` (either direction), or [`NONE`] for a pairing diagonal.
    pub fn edge_of(&self, h: HalfEdgeId) -> u32 {
        self.edge_of_half[h.index()]
    }

    /// The quads templates of level `level` make of these elements: 3k² per triangle, 4k² per
    /// quad.
    ///
    /// ```
    /// use imesh_geom::{Point, Triangulation};
    /// use imesh_quad::{ElementMesh, Pairing};
    /// let pts = [Point::new(0.0, 0.0), Point::new(3.0, 0.0), Point::new(3.0, 2.0), Point::new(0.0, 2.0)];
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// assert_eq!(ElementMesh::pair(&t, Pairing::Greedy).quad_count(2), 16);
    /// ```
    pub fn quad_count(&self, level: u32) -> u64 {
        let k2 = u64::from(level) * u64::from(level);
        let triangles = self.unpaired as u64;
        let quads = self.elements.len() as u64 - triangles;
        3 * k2 * triangles + 4 * k2 * quads
    }

    /// The number of sides of element `element` (3 or 4).
    pub fn side_count(&self, element: usize) -> usize {
        self.elements[element].corners().len()
    }

    fn from_partners(t: &Triangulation, partner: &[u32]) -> Self {
        let slots = t.num_triangle_slots();
        let mut elements = Vec::with_capacity(slots);
        let mut labels = Vec::with_capacity(slots);
        let mut sides = Vec::with_capacity(slots);
        let mut unpaired = 0;
        let mut diagonal = vec![false; 3 * slots];
        let mut element_of_triangle = vec![NONE; slots];
        for f in t.triangles() {
            let p = partner[f.index()];
            if p != NONE && (p as usize) < f.index() {
                continue; // the pair is emitted from its first triangle
            }
            let e = t.triangle_edges(f);
            element_of_triangle[f.index()] = elements.len() as u32;
            if p != NONE {
                element_of_triangle[p as usize] = elements.len() as u32;
            }
            if p == NONE {
                unpaired += 1;
                elements.push(Element::Triangle(e.map(|h| t.origin(h).index() as u32)));
                sides.push([e[0], e[1], e[2], e[2]]);
            } else {
                // The shared half-edge a → b in f, its twin b → a in the partner (b, a, d):
                // the quad is a, d, b, c.
                let h = e
                    .into_iter()
                    .find(|&h| t.neighbour(h).map(|n| n.index() as u32) == Some(p))
                    .unwrap_or(e[0]);
                let twin = t.twin(h);
                let (h1, h2) = (t.next(h), t.prev(h)); // b → c, c → a
                let (g1, g2) = (t.next(twin), t.prev(twin)); // a → d, d → b
                diagonal[h.index()] = true;
                diagonal[twin.index()] = true;
                let v = |x: HalfEdgeId| t.origin(x).index() as u32;
                elements.push(Element::Quad([v(g1), v(g2), v(h1), v(h2)]));
                sides.push([g1, g2, h1, h2]);
            }
            labels.push(t.label(f));
        }
        let edges: Vec<HalfEdgeId> = par_edges(t).filter(|&h| !diagonal[h.index()]).collect();
        let mut edge_of_half = vec![NONE; 3 * slots];
        for (e, &h) in edges.iter().enumerate() {
            edge_of_half[h.index()] = e as u32;
            edge_of_half[t.twin(h).index()] = e as u32;
        }
        Self {
            elements,
            labels,
            sides,
            edge_of_half,
            edges,
            unpaired,
            element_of_triangle,
        }
    }
}

/// The length of the chunks of elements [`ElementMesh::straight_shape_and_size`] sums in
/// parallel.
const SUM_CHUNK: usize = 1024;

/// The straight level-1 template quads of element `e` (each corner, its sides' midpoints and
/// the centre), in the first 3 or 4 places.
fn straight_quads(t: &Triangulation, e: &Element) -> ([Quad; 4], usize) {
    let corners = e.corners();
    let n = corners.len();
    let mut c = [Point::new(0.0, 0.0); 4];
    for (p, &v) in c.iter_mut().zip(corners) {
        *p = t.point(VertexId::new(v));
    }
    let centre = c[..n].iter().fold(Point::new(0.0, 0.0), |a, &p| a + p) * (1.0 / n as f64);
    let mut quads = [[[0.0; 2]; 4]; 4];
    for (i, q) in quads.iter_mut().enumerate().take(n) {
        let (prev, next) = (c[(i + n - 1) % n], c[(i + 1) % n]);
        *q = [c[i], c[i].midpoint(next), centre, prev.midpoint(c[i])].map(|p| [p.x, p.y]);
    }
    (quads, n)
}

/// [`Triangulation::edges`] in parallel, in the same order when collected.
fn par_edges(t: &Triangulation) -> impl ParallelIterator<Item = HalfEdgeId> + '_ {
    (0..3 * t.num_triangle_slots() as u32)
        .into_par_iter()
        .map(HalfEdgeId::new)
        .filter(|&h| t.is_edge_representative(h))
}

/// The quad `a, d, b, c` made by the triangle of `h` (a → b → c) and its neighbour across `h`
/// (b → a → d), if both are real triangles of the same label across an unconstrained edge.
fn quad_across(t: &Triangulation, h: HalfEdgeId) -> Option<[Point; 4]> {
    if t.is_constrained(h) {
        return None;
    }
    let f = t.triangle_of(h);
    let n = t.neighbour(h)?;
    if t.label(f) != t.label(n) {
        return None;
    }
    let twin = t.twin(h);
    let p = |x: HalfEdgeId| t.point(t.origin(x));
    Some([p(t.next(twin)), p(t.prev(twin)), p(t.next(h)), p(t.prev(h))])
}

/// True when the quad turns strictly left at every corner (exact).
fn strictly_convex(q: &[Point; 4]) -> bool {
    (0..4).all(|i| orient2d(q[(i + 3) % 4], q[i], q[(i + 1) % 4]) > 0.0)
}

/// The worst corner sine (scaled Jacobian) of the quad across `h` ([`quad_across`]) if it is
/// strictly convex, that sine is at least `min_corner`, and, with `pinned`, its pinned corners
/// are fair ([`pinned_corners_fair`]).
fn corner_sine(t: &Triangulation, h: HalfEdgeId, min_corner: f64, pinned: bool) -> Option<f64> {
    let q = quad_across(t, h).filter(strictly_convex)?;
    let w = scaled_jacobian(&q);
    (w >= min_corner && (!pinned || pinned_corners_fair(t, h, &q))).then_some(w)
}

/// [`Pairing::Matching`] forms no quad with a pinned corner (both its sides on boundaries: at
/// a vertex of G', where nothing downstream moves either side's direction) wider than this, in
/// degrees, unless that corner's shape is at least [`MIN_PINNED_CORNER_SHAPE`].
pub const PINNED_OBTUSE_DEG: f64 = 125.0;

/// The least shape (`2 sin θ · a b / (a² + b²)`, Verdict's quad shape at one corner of sides `a`
/// and `b`) of a wide pinned corner ([`PINNED_OBTUSE_DEG`]) that [`Pairing::Matching`] pairs.
///
/// A template quad keeps its parent's corner and the ratio of its sides there (each is half its
/// parent's side). At a corner of 145°–150° between a short boundary piece and a long one (a
/// pixel step beside a long edge), the optimiser may slide the far ends along the boundaries
/// to even the sides, but along a curve that turns the corner past 150° first, under the
/// scaled Jacobian floor: the worst quads of grass (shape 0.417, 0.422) and aloe (0.359) were
/// such corners. Left unpaired, the two triangles meeting at the corner each keep about half
/// of it. Quads under 0.5 in shape over session 48's 150 images with the defaults, against
/// 114 without the bar: 99 at 125° (26 against 24 under 0.5 in scaled Jacobian), 109 at 100°
/// (25), 105 at 135° (27), and 117 at 125° with a bar of 0.55 (30); on 46 images of a seed
/// the bar was not chosen on, 39 → 31 (scaled Jacobian 6 → 5).
pub const MIN_PINNED_CORNER_SHAPE: f64 = 0.5;

/// Whether every corner of the quad `q` across `h` ([`quad_across`]) whose two sides are
/// constrained edges of `t`, and which is wider than [`PINNED_OBTUSE_DEG`], has a shape of at
/// least [`MIN_PINNED_CORNER_SHAPE`].
fn pinned_corners_fair(t: &Triangulation, h: HalfEdgeId, q: &[Point; 4]) -> bool {
    let twin = t.twin(h);
    // Side i of `q` (from corner i to corner i + 1), as `quad_across` orders the corners.
    let sides = [t.next(twin), t.prev(twin), t.next(h), t.prev(h)];
    let wide = PINNED_OBTUSE_DEG.to_radians().cos();
    (0..4).all(|i| {
        if !(t.is_constrained(sides[(i + 3) % 4]) && t.is_constrained(sides[i])) {
            return true;
        }
        let (u, v) = (q[(i + 3) % 4] - q[i], q[(i + 1) % 4] - q[i]);
        let (uu, vv) = (u.x * u.x + u.y * u.y, v.x * v.x + v.y * v.y);
        let dot = u.x * v.x + u.y * v.y;
        if dot >= wide * (uu * vv).sqrt() {
            return true;
        }
        2.0 * (u.x * v.y - u.y * v.x).abs() >= MIN_PINNED_CORNER_SHAPE * (uu + vv)
    })
}

/// The edges of `t` that have a `key`, by decreasing key, then increasing half-edge: the order
/// of the paper's max-heap, made deterministic. The keys are lengths and corner sines, never
/// negative, so their bits sort as they do, and the pairs are all distinct: one integer per
/// pair, the key's bits inverted above the half-edge's index, sorts into the one order
/// without a comparator's branches.
fn best_first(
    t: &Triangulation,
    key: impl Fn(HalfEdgeId) -> Option<f64> + Sync,
) -> Vec<HalfEdgeId> {
    let mut order: Vec<u128> = par_edges(t)
        .filter_map(|h| {
            let key = key(h)?;
            debug_assert!(key >= 0.0);
            Some((u128::from(!key.to_bits()) << 32) | h.index() as u128)
        })
        .collect();
    order.par_sort_unstable();
    order
        .into_iter()
        .map(|k| HalfEdgeId::new(k as u32))
        .collect()
}

fn pair_up(partner: &mut [u32], f: TriangleId, n: TriangleId) {
    partner[f.index()] = n.index() as u32;
    partner[n.index()] = f.index() as u32;
}

/// The greedy pairing's margin on "strictly convex": no corner within about 0.6° of flat
/// (sine 0.01). A corner at 179.99° is convex in exact arithmetic, but the level-k template's
/// corner quad there is so flat that the rounding of its points inverts it.
const MIN_GREEDY_CORNER: f64 = 0.01;

/// The paper's triquad. A sort stands in for the max-heap: the keys never change.
fn greedy(t: &Triangulation) -> Vec<u32> {
    // Only the edges whose quad is strictly convex enough: testing it here, in parallel,
    // rather than when the edge's turn comes, leaves the same pairs.
    let candidates = best_first(t, |h| {
        // Only whether the quad clears the margin matters here, not its worst sine: the
        // squared test spares the roots and divisions (a margin that far from 0 leaves no
        // doubt about the corners' signs either).
        let quad = quad_across(t, h)?;
        if !valid_above(&quad, MIN_GREEDY_CORNER) {
            return None;
        }
        let (a, b) = (t.point(t.origin(h)), t.point(t.destination(h)));
        Some(a.distance_squared(b))
    });
    let mut partner = vec![NONE; t.num_triangle_slots()];
    let mut marked = vec![false; 3 * t.num_triangle_slots()];
    for h in candidates {
        if marked[h.index()] {
            continue;
        }
        let (f, Some(n)) = (t.triangle_of(h), t.neighbour(h)) else {
            continue;
        };
        if partner[f.index()] != NONE || partner[n.index()] != NONE {
            continue;
        }
        pair_up(&mut partner, f, n);
        let twin = t.twin(h);
        for x in [t.next(h), t.prev(h), t.next(twin), t.prev(twin)] {
            marked[x.index()] = true;
            marked[t.twin(x).index()] = true;
        }
    }
    partner
}

/// [`Pairing::Fewest`] forms no quad worse than this (a corner angle under about 20.5° or over
/// 159.5°): a corner no worse than the smallest angle DT' refinement leaves in a triangle (20.7°
/// by default), so that pairing never makes a corner the two triangles would not have had, and
/// the templates keep it (a template quad has its parent's corner angle). Measured on nine
/// fixtures against the earlier 0.17 (about 10° of flat), this bar alone: worst scaled Jacobian
/// higher on seven, equal on coins and grass.
pub const MIN_FEWEST_CORNER: f64 = 0.35;

/// [`Pairing::Matching`] forms no quad worse than this: the sine of 30°, issue 8's target for
/// the scaled Jacobian. A template quad keeps its parent's corner, and a corner at a G' vertex,
/// or in a strip one quad wide, is pinned (the optimiser moves neither a G' vertex nor a
/// boundary, and slides the rest only along it), so 158° pairs were the worst quads on seven
/// fixtures. Measured with the defaults on nine fixtures against 0.35 (with adaptation's and
/// the repair's bars raised to match): worst scaled Jacobian 0.275–0.400 → 0.275–0.501 (mean of
/// the nine 0.349 → 0.424), worst shape mean 0.239 → 0.329, mean shape-and-size 0.8377 →
/// 0.8386; 0.45 and 0.55 did worse on the worst scaled Jacobian (mean 0.408, 0.407), and so
/// did 0.5 only at corners on a boundary (0.383). On graded meshes it leaves more triangles
/// than the greedy pairing (pyvista 36 % against 30 %), hence [`Pairing::Fewest`].
pub const MIN_MATCHING_CORNER: f64 = 0.5;

/// An augmenting path never undoes a pair whose quad has a worst corner sine of at least this
/// (the lattice's squares, and quads nearly as good): re-pairing them to free one triangle
/// turns two squares into rhombi and lowers the mesh's shape-and-size more than the triangle's
/// three quads would (measured on nine fixtures with the defaults: mean shape-and-size +0.002 to
/// +0.018 on eight, −0.0005 on camera; worst scaled Jacobian equal, or 0.004 lower on coins).
const KEEP_PAIR: f64 = 0.97;

/// How many re-pairings an augmenting path may make.
const MAX_AUGMENTING_DEPTH: usize = 8;

/// Best quads first, then augmenting paths for the triangles left; no quad with a corner sine
/// under `min_corner`, nor, with `pinned`, an unfair pinned corner ([`pinned_corners_fair`]);
/// with `even_sizes`, the triangles left then moved to where their quads come nearer the mean
/// quad's area ([`move_unpaired_to_mean_size`]); with `split_large`, no large blunt pair
/// ([`too_large`]).
fn matching(
    t: &Triangulation,
    min_corner: f64,
    pinned: bool,
    even_sizes: bool,
    split_large: bool,
) -> Vec<u32> {
    matching_on(
        t,
        &corner_sines(t, min_corner, pinned),
        even_sizes,
        split_large,
    )
}

/// Per half-edge of `t`: the worst corner sine of the quad across it ([`corner_sine`]), NaN
/// where it forms none. The searches ask for the same edges again and again (the best-first
/// order, an augmenting search from every free triangle, the pairs it would undo, the moves of
/// the triangles left), and [`Pairing::Matching`]'s two candidates for the same quads. Both
/// half-edges of an edge hold the same value, as [`corner_sine`] finds it from either: the
/// same quad, its corners in the same cyclic order.
fn corner_sines(t: &Triangulation, min_corner: f64, pinned: bool) -> Vec<f64> {
    let found: Vec<(HalfEdgeId, f64)> = par_edges(t)
        .filter_map(|h| Some((h, corner_sine(t, h, min_corner, pinned)?)))
        .collect();
    let mut sines = vec![f64::NAN; 3 * t.num_triangle_slots()];
    for (h, w) in found {
        sines[h.index()] = w;
        sines[t.twin(h).index()] = w;
    }
    sines
}

/// [`matching`] with the corner sines found ([`corner_sines`]).
fn matching_on(t: &Triangulation, sines: &[f64], even_sizes: bool, split_large: bool) -> Vec<u32> {
    let mean_quad = if split_large {
        let (area, count) = t
            .triangles()
            .fold((0.0, 0usize), |(a, n), f| (a + triangle_area(t, f), n + 1));
        area / (2 * count.max(1)) as f64
    } else {
        f64::INFINITY
    };
    let good = |h: HalfEdgeId| {
        let w = sines[h.index()];
        (!w.is_nan() && (w >= KEEP_PAIR || !(split_large && too_large(t, h, mean_quad))))
            .then_some(w)
    };
    // Whether the pair of `n` and its partner `p` is one an augmenting path keeps.
    let keeps = |n: TriangleId, p: u32| {
        t.triangle_edges(n).into_iter().any(|h| {
            t.neighbour(h).is_some_and(|m| m.index() == p as usize)
                && good(h).is_some_and(|w| w >= KEEP_PAIR)
        })
    };
    let candidates = best_first(t, good);
    let mut partner = vec![NONE; t.num_triangle_slots()];
    for &h in &candidates {
        let (f, Some(n)) = (t.triangle_of(h), t.neighbour(h)) else {
            continue;
        };
        if partner[f.index()] == NONE && partner[n.index()] == NONE {
            pair_up(&mut partner, f, n);
        }
    }
    // Augmenting paths: from a free triangle, step to a neighbour it could pair with; if that one
    // is paired, continue from its partner; a free triangle at the end flips the whole path.
    let mut mark = vec![0u32; t.num_triangle_slots()];
    let mut round = 0;
    let free: Vec<TriangleId> = t
        .triangles()
        .filter(|f| partner[f.index()] == NONE)
        .collect();
    // For a triangle reached as the neighbour of a free-side triangle: that triangle.
    let mut parent = vec![NONE; t.num_triangle_slots()];
    let mut queue = std::collections::VecDeque::new();
    for start in free {
        if partner[start.index()] != NONE {
            continue;
        }
        round += 1;
        queue.clear();
        queue.push_back((start, 0usize));
        mark[start.index()] = round;
        let mut end = None;
        'search: while let Some((f, depth)) = queue.pop_front() {
            if depth >= MAX_AUGMENTING_DEPTH {
                continue;
            }
            for h in t.triangle_edges(f) {
                let Some(n) = t.neighbour(h) else { continue };
                if mark[n.index()] == round || good(h).is_none() {
                    continue;
                }
                mark[n.index()] = round;
                parent[n.index()] = f.index() as u32;
                let p = partner[n.index()];
                if p == NONE {
                    end = Some(n);
                    break 'search;
                }
                if keeps(n, p) {
                    continue;
                }
                if mark[p as usize] != round {
                    mark[p as usize] = round;
                    queue.push_back((TriangleId::new(p), depth + 1));
                }
            }
        }
        // Flip the path back from its free end: each free-side triangle takes the neighbour the
        // search reached from it, and its old partner is re-paired the same way, up to `start`.
        let Some(n) = end else { continue };
        flip_path(&mut partner, &parent, start, n);
    }
    if even_sizes {
        move_unpaired_to_mean_size(t, &mut partner, good);
    }
    partner
}

/// How many times the mean quad's area (estimated as half the mean triangle's) a pair's
/// template quads may have, in [`Pairing::Matching`]'s second candidate, before the pair is
/// left as two triangles (where both have every corner of 30° or more, and the pair is not
/// one the matching keeps, such as a lattice square).
///
/// A pair gives four quads of half a triangle each, an unpaired triangle three of a third:
/// where refinement leaves triangles larger than the lattice's (across a strip too narrow for
/// it, in the band along a boundary), their pairs' quads are up to four times the mean area,
/// a shape-and-size under 0.25 that no optimiser can mend where all four corners are on
/// boundaries. Left unpaired, each triangle's quads are two thirds of those. Measured with
/// the defaults on 150 random label images (Voronoi cells, smoothed noise at two to four
/// levels, discs and rectangles) as the only pairing: mean of the means 0.86347 → 0.86902
/// (127 images higher, 14 lower), quads under 0.25 11 072 → 9 313; 1.2 gave 0.86445, 1.5
/// 0.86504. On the fixtures it lowered camera 0.9081 → 0.8964 and coffee 0.9109 → 0.9060 (big
/// band quads next to the lattice, which the optimiser shrinks, split into obtuse
/// triangles): hence a second candidate, kept only where its straight quads score nearly as
/// well or better ([`SPLIT_MARGIN`]).
pub const LARGE_PAIR: f64 = 1.3;

/// How much lower [`ElementMesh::straight_shape_and_size`] may be with the large pairs left
/// ([`LARGE_PAIR`]) than without, for [`Pairing::Matching`] to leave them. The optimiser
/// gains more on the split pairing than the straight templates show (its triangles' quads grow
/// towards the mean): grass's straight mean is 0.005 lower split, its optimised mean 0.010
/// higher; camera's and coffee's 0.017 and 0.019 lower, their optimised means 0.012 and 0.005
/// lower. Measured with the defaults, mean of the ten fixtures' means 0.83121 → 0.83152 at 0
/// (brick, coins and pyvista split), 0.83361 at 0.01 (grass and gravel too), 0.83429 at 0.015
/// (MRI too); on the 150 images 0.86347 → 0.86871, 0.86913 and 0.86907, quads under 0.5 in
/// shape 11, 18 and 23 (one mesh renumbered moves that count by about 7), in scaled Jacobian
/// 2, 2 and 3.
pub const SPLIT_MARGIN: f64 = 0.01;

/// The least corner sine (of 30°) both triangles of a large pair need for
/// [`too_large`] to leave them: an unpaired triangle's quads keep its corners, and a pair hides
/// them (without it, quads under 0.5 in scaled Jacobian over the 150 images 2 → 11).
const LARGE_PAIR_BLUNT: f64 = 0.5;

/// Whether the pair across `h` has quads over [`LARGE_PAIR`] times `mean_quad` and blunt
/// triangles ([`LARGE_PAIR_BLUNT`]).
fn too_large(t: &Triangulation, h: HalfEdgeId, mean_quad: f64) -> bool {
    let (f, Some(n)) = (t.triangle_of(h), t.neighbour(h)) else {
        return false;
    };
    (triangle_area(t, f) + triangle_area(t, n)) / 4.0 > LARGE_PAIR * mean_quad
        && smallest_corner_sine(t, f) >= LARGE_PAIR_BLUNT
        && smallest_corner_sine(t, n) >= LARGE_PAIR_BLUNT
}

/// Re-pairs an alternating path of a search from `start` back from its free end `n`: each
/// free-side triangle (`parent` of the triangle the search reached from it) takes that
/// triangle, and its old partner is re-paired the same way, up to `start`.
fn flip_path(partner: &mut [u32], parent: &[u32], start: TriangleId, mut n: TriangleId) {
    loop {
        let f = parent[n.index()];
        let old = partner[f as usize];
        partner[f as usize] = n.index() as u32;
        partner[n.index()] = f;
        if f == start.index() as u32 || old == NONE {
            break;
        }
        n = TriangleId::new(old);
    }
}

/// The signed area of triangle `f` (positive: counter-clockwise).
fn triangle_area(t: &Triangulation, f: TriangleId) -> f64 {
    let [a, b, c] = t.triangle_points(f);
    0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x))
}

/// The sine of the smallest corner of triangle `f`.
fn smallest_corner_sine(t: &Triangulation, f: TriangleId) -> f64 {
    let p = t.triangle_points(f);
    (0..3)
        .map(|i| {
            let (u, v) = (p[(i + 1) % 3] - p[i], p[(i + 2) % 3] - p[i]);
            (u.x * v.y - u.y * v.x).abs()
                / ((u.x * u.x + u.y * u.y) * (v.x * v.x + v.y * v.y)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

/// How many re-pairings a path that moves an unpaired triangle may make
/// ([`move_unpaired_to_mean_size`]; 2 and 8 measured within 0.00005 of 4).
const EVEN_SIZE_DEPTH: usize = 4;

/// The least gain in relative size, `3 (1 − min(r, 1/r)²)` over a triangle's three quads, for
/// which an unpaired triangle is moved (0.1 and 0.6 measured within 0.0001 of 0.3).
const EVEN_SIZE_GAIN: f64 = 0.3;

/// How much lower than the pair it undoes (in worst corner sine) a pair a move makes may be.
const EVEN_SIZE_PAIR_SLACK: f64 = 0.1;

/// Moves each unpaired triangle along an alternating path (it pairs with a neighbour, whose
/// partner pairs with its own neighbour, …, and the last partner is left) to the triangle whose
/// three quads come nearest the mean quad area, where that gains [`EVEN_SIZE_GAIN`] or more.
///
/// Shape-and-size scores a quad by the square of its relative size. A pair gives four quads of
/// half a triangle each, an unpaired triangle three of a third: where the matching leaves the
/// triangle that refinement made small against a short boundary piece, its quads are half the
/// mean area or less, under 0.25 (most of the quads under 0.25 on the label fixtures: coffee
/// 306 of 420 under half the mean area). A path's pairs are the matching's own kind (`good`:
/// no corner under its bar), none undoing a pair the matching keeps ([`KEEP_PAIR`]: the
/// lattice's squares) nor more than [`EVEN_SIZE_PAIR_SLACK`] worse than the pair it undoes, and
/// the triangle left has
/// a smallest corner no sharper than the one it replaces has, or than 30°: a sharp triangle's
/// quads keep its corner. Measured with the defaults: mean shape-and-size higher on all nine
/// fixtures (all but aloe; mean of them 0.83747 → 0.83851), the mean of 150 images' means
/// 0.84782 → 0.84927 and of 46 others' 0.82771 → 0.82922, quads under 0.5 in shape 75 → 71
/// and 30 → 25 (scaled Jacobian 10 and 2 either way). Counting the pairs' sizes too, the mean
/// of the nine rose less (0.83831), and less again with no pair worse than the one it undoes
/// (0.83782–0.83796); with any pair, it fell on three of four fixtures (coins 0.8681 → 0.8669).
fn move_unpaired_to_mean_size(
    t: &Triangulation,
    partner: &mut [u32],
    good: impl Fn(HalfEdgeId) -> Option<f64>,
) {
    let (mut area, mut unpaired, mut count) = (0.0, Vec::new(), 0usize);
    for f in t.triangles() {
        area += triangle_area(t, f);
        count += 1;
        if partner[f.index()] == NONE {
            unpaired.push(f);
        }
    }
    let quads = 2 * (count - unpaired.len()) + 3 * unpaired.len();
    let mean = area / quads.max(1) as f64;
    // What an unpaired triangle's three quads lose in relative size.
    let cost = |f: TriangleId| {
        let r = triangle_area(t, f) / (3.0 * mean);
        let s = r.min(1.0 / r);
        3.0 * (1.0 - s * s)
    };
    // The worst corner sine of the pair of `n` and its partner `p`.
    let pair_sine = |n: TriangleId, p: u32| {
        t.triangle_edges(n)
            .into_iter()
            .find(|&e| t.neighbour(e).is_some_and(|m| m.index() == p as usize))
            .and_then(&good)
            .unwrap_or(0.0)
    };
    let mut mark = vec![0u32; t.num_triangle_slots()];
    let mut parent = vec![NONE; t.num_triangle_slots()];
    let mut queue = std::collections::VecDeque::new();
    for (round, start) in (1u32..).zip(unpaired) {
        let (here, sharpest) = (cost(start), smallest_corner_sine(t, start).min(0.5));
        queue.clear();
        queue.push_back((start, 0usize));
        mark[start.index()] = round;
        // The best end: the paired triangle the path reaches last, whose partner is left.
        let mut best: Option<(f64, TriangleId)> = None;
        while let Some((f, depth)) = queue.pop_front() {
            if depth >= EVEN_SIZE_DEPTH {
                continue;
            }
            for h in t.triangle_edges(f) {
                let Some(n) = t.neighbour(h) else { continue };
                let Some(sine) = good(h) else { continue };
                let p = partner[n.index()];
                if mark[n.index()] == round || p == NONE || mark[p as usize] == round {
                    continue;
                }
                // The pair the path would undo: not one the matching keeps, nor much better.
                let undone = pair_sine(n, p);
                if undone >= KEEP_PAIR || sine < undone - EVEN_SIZE_PAIR_SLACK {
                    continue;
                }
                mark[n.index()] = round;
                mark[p as usize] = round;
                parent[n.index()] = f.index() as u32;
                let left = TriangleId::new(p);
                let gain = here - cost(left);
                if gain > EVEN_SIZE_GAIN
                    && best.is_none_or(|(b, _)| gain > b)
                    && smallest_corner_sine(t, left) >= sharpest
                {
                    best = Some((gain, n));
                }
                queue.push_back((left, depth + 1));
            }
        }
        // Flip the path back from its end, as an augmenting path, its last partner left.
        let Some((_, n)) = best else { continue };
        let p = partner[n.index()];
        partner[p as usize] = NONE;
        partner[n.index()] = NONE;
        flip_path(partner, &parent, start, n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The unpaired triangles of `partner`, each pair checked: its two triangles each other's
    /// partner, across an edge the matching of bar `bar` may pair (a quad with no corner sine
    /// under it).
    fn unpaired_checked(t: &Triangulation, partner: &[u32], bar: f64) -> Vec<TriangleId> {
        let mut unpaired = Vec::new();
        for f in t.triangles() {
            let p = partner[f.index()];
            if p == NONE {
                unpaired.push(f);
                continue;
            }
            assert_eq!(partner[p as usize], f.index() as u32);
            let across = t
                .triangle_edges(f)
                .into_iter()
                .find(|&h| t.neighbour(h).is_some_and(|n| n.index() == p as usize))
                .expect("a pair shares an edge");
            assert!(corner_sine(t, across, bar, true).is_some());
        }
        unpaired
    }

    /// What the unpaired triangles' quads lose in relative size, summed (as
    /// [`move_unpaired_to_mean_size`] scores it).
    fn size_cost(t: &Triangulation, unpaired: &[TriangleId]) -> f64 {
        let area: f64 = t.triangles().map(|f| triangle_area(t, f)).sum();
        let count = t.triangles().count();
        let mean = area / (2 * (count - unpaired.len()) + 3 * unpaired.len()) as f64;
        unpaired
            .iter()
            .map(|&f| {
                let r = triangle_area(t, f) / (3.0 * mean);
                3.0 * (1.0 - r.min(1.0 / r).powi(2))
            })
            .sum()
    }

    /// A strip of five triangles between two rows of points, the three on the left
    /// equilateral-ish (area 1.7), the two on the right larger: the matching pairs the two
    /// best quads and leaves the third small triangle, whose quads would be 0.6 of the mean
    /// area; the move re-pairs it with its right neighbour and leaves that one's partner, of
    /// area 2.125, whose quads come within 0.8 of it.
    #[test]
    fn an_unpaired_triangle_moves_to_a_larger_one() {
        let points = [
            (0.0, 0.0),
            (2.0, 0.0),
            (4.0, 0.0),
            (6.5, 0.0),
            (1.0, 1.7),
            (3.0, 1.7),
            (5.0, 1.7),
        ]
        .map(|(x, y)| Point::new(x, y));
        let (t, _) = Triangulation::from_points(&points).unwrap();
        assert_eq!(t.triangles().count(), 5);
        let before = matching(&t, MIN_MATCHING_CORNER, true, false, false);
        let after = matching(&t, MIN_MATCHING_CORNER, true, true, false);
        let (b, a) = (
            unpaired_checked(&t, &before, MIN_MATCHING_CORNER),
            unpaired_checked(&t, &after, MIN_MATCHING_CORNER),
        );
        assert_eq!((b.len(), a.len()), (1, 1));
        assert!((triangle_area(&t, b[0]) - 1.7).abs() < 1e-9);
        assert!((triangle_area(&t, a[0]) - 2.125).abs() < 1e-9);
        assert!(size_cost(&t, &a) < size_cost(&t, &b) - EVEN_SIZE_GAIN);
    }

    /// Two equilateral triangles of side 2 make a rhombus whose four quads are 0.87 each: too
    /// large against quads of 0.6 (by [`LARGE_PAIR`]), not against quads of 0.7; and never with
    /// a triangle sharper than 30°.
    #[test]
    fn large_blunt_pairs_are_left() {
        let h3 = 3f64.sqrt();
        let rhombus = [(0.0, 0.0), (2.0, 0.0), (1.0, h3), (3.0, h3)].map(|(x, y)| Point::new(x, y));
        let (t, _) = Triangulation::from_points(&rhombus).unwrap();
        let diagonal = t
            .edges()
            .find(|&h| t.neighbour(h).is_some() && t.neighbour(t.twin(h)).is_some())
            .unwrap();
        assert!(too_large(&t, diagonal, 0.6));
        assert!(!too_large(&t, diagonal, 0.7));
        // Two triangles with a corner of 22.6° at either end.
        let sliver =
            [(0.0, 0.0), (4.0, 0.0), (2.0, 0.4), (2.0, -0.4)].map(|(x, y)| Point::new(x, y));
        let (s, _) = Triangulation::from_points(&sliver).unwrap();
        let across = s
            .edges()
            .find(|&h| s.neighbour(h).is_some() && s.neighbour(s.twin(h)).is_some())
            .unwrap();
        assert!(!too_large(&s, across, 0.01));
    }

    /// The Delaunay triangulation of grid points `points`, the columns half a unit apart and
    /// the rows `stretch` apart (`None` where it cannot be built).
    fn triangulated(points: Vec<(u32, u32)>, stretch: f64) -> Option<Triangulation> {
        let points: Vec<Point> = points
            .into_iter()
            .map(|(x, y)| Point::new(f64::from(x) * 0.5, f64::from(y) * stretch))
            .collect();
        Triangulation::from_points(&points).ok().map(|(t, _)| t)
    }

    proptest! {
        /// On random points, the matching with large pairs left pairs only what the matching
        /// may pair, and [`ElementMesh::pair`] keeps it only within [`SPLIT_MARGIN`] of the
        /// other's straight shape-and-size.
        #[test]
        fn large_pairs_are_left_only_within_the_margin(
            points in proptest::collection::vec((0u32..40, 0u32..40), 8..60),
            stretch in 0.2f64..1.0,
        ) {
            let Some(t) = triangulated(points, stretch) else {
                return Ok(());
            };
            let kept = matching(&t, MIN_MATCHING_CORNER, true, true, false);
            let split = matching(&t, MIN_MATCHING_CORNER, true, true, true);
            unpaired_checked(&t, &kept, MIN_MATCHING_CORNER);
            let s = unpaired_checked(&t, &split, MIN_MATCHING_CORNER);
            let chosen = ElementMesh::pair(&t, Pairing::Matching);
            let kept = ElementMesh::from_partners(&t, &kept);
            let floor = kept.straight_shape_and_size(&t) - SPLIT_MARGIN;
            prop_assert!(chosen.straight_shape_and_size(&t) >= floor);
            prop_assert!(chosen.unpaired == kept.unpaired || chosen.unpaired == s.len());
        }

        /// On random points, the straight templates' shape-and-size summed in parallel chunks
        /// is the mean over the template quads built one by one, and the corner sines found
        /// once are those of either half-edge.
        #[test]
        fn straight_quality_and_corner_sines_are_the_direct_ones(
            points in proptest::collection::vec((0u32..40, 0u32..40), 8..60),
            stretch in 0.2f64..1.0,
        ) {
            let Some(t) = triangulated(points, stretch) else {
                return Ok(());
            };
            let m = ElementMesh::pair(&t, Pairing::Matching);
            let mut quads = Vec::new();
            for e in &m.elements {
                let c: Vec<Point> =
                    e.corners().iter().map(|&v| t.point(VertexId::new(v))).collect();
                let n = c.len() as f64;
                let centre = c.iter().fold(Point::new(0.0, 0.0), |a, &p| a + p) * (1.0 / n);
                for i in 0..c.len() {
                    let (prev, next) = (c[(i + c.len() - 1) % c.len()], c[(i + 1) % c.len()]);
                    let q = [c[i], c[i].midpoint(next), centre, prev.midpoint(c[i])];
                    quads.push(q.map(|p| [p.x, p.y]));
                }
            }
            let mean = quads.iter().map(quad::area).sum::<f64>() / quads.len() as f64;
            let direct = quads.iter().map(|q| quad::shape_and_size(q, mean)).sum::<f64>()
                / quads.len() as f64;
            prop_assert!((m.straight_shape_and_size(&t) - direct).abs() < 1e-12);
            let sines = corner_sines(&t, MIN_MATCHING_CORNER, true);
            for f in t.triangles() {
                for h in t.triangle_edges(f) {
                    let direct = corner_sine(&t, h, MIN_MATCHING_CORNER, true);
                    let cached = sines[h.index()];
                    let cached = (!cached.is_nan()).then(|| cached.to_bits());
                    prop_assert_eq!(direct.map(f64::to_bits), cached);
                }
            }
        }

        /// On random points, moving the unpaired triangles leaves as many, each pair one the
        /// matching could make, and their quads' loss in relative size never higher.
        #[test]
        fn moving_unpaired_triangles_keeps_the_matching_and_evens_sizes(
            points in proptest::collection::vec((0u32..40, 0u32..40), 8..60),
        ) {
            let Some(t) = triangulated(points, 0.37) else {
                return Ok(());
            };
            let before = matching(&t, MIN_MATCHING_CORNER, true, false, false);
            let after = matching(&t, MIN_MATCHING_CORNER, true, true, false);
            let (b, a) = (
                unpaired_checked(&t, &before, MIN_MATCHING_CORNER),
                unpaired_checked(&t, &after, MIN_MATCHING_CORNER),
            );
            prop_assert_eq!(a.len(), b.len());
            prop_assert!(size_cost(&t, &a) <= size_cost(&t, &b) + 1e-9);
        }
    }
}
