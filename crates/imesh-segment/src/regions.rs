//! The regions of the partition (connected triangles of one label), their size and width, and
//! the merging of regions too thin for the element size.
//!
//! A quad mesh of uniform element size `h` cannot fill a strip narrower than about `h/2` with
//! elements of that size: every quad across it is at most as wide as the strip, so its area is a
//! fraction of the mean and its shape-and-size collapses (relative size squared: (w/h)²). Such
//! regions (isolated specks of a pixel classifier, one-pixel lines, slivers the partition leaves
//! along a boundary) are merged into the neighbour they share the longest boundary with, before
//! the c-edges are drawn. The width of a region is `2 · area / perimeter`: the width of a long
//! strip, the radius of a disc, half the side of a square.

use std::collections::BTreeMap;

use imesh_geom::{TriangleId, Triangulation};

/// "No region" in [`PartitionRegions::of_triangle`] (ghost slots).
pub const NO_REGION: u32 = u32::MAX;

/// One region of the partition: triangles of one label joined across shared edges.
#[derive(Clone, Debug, PartialEq)]
pub struct PartitionRegion {
    /// Its label.
    pub label: u32,
    /// Its area, in square pixels.
    pub area: f64,
    /// The length of its boundary (against other regions and the domain border), in pixels.
    pub perimeter: f64,
    /// The number of triangles in it.
    pub triangles: usize,
}

impl PartitionRegion {
    /// `2 · area / perimeter`, in pixels: a strip's width, a disc's radius (0 without perimeter).
    ///
    /// ```
    /// use imesh_segment::PartitionRegion;
    /// // A 10 × 2 strip.
    /// let r = PartitionRegion { label: 0, area: 20.0, perimeter: 24.0, triangles: 2 };
    /// assert!((r.width() - 20.0 / 12.0).abs() < 1e-12);
    /// ```
    pub fn width(&self) -> f64 {
        if self.perimeter > 0.0 {
            2.0 * self.area / self.perimeter
        } else {
            0.0
        }
    }
}

/// The regions of a labelled triangulation, with the boundary each pair shares.
#[derive(Clone, Debug)]
pub struct PartitionRegions {
    /// The region of every triangle slot (by [`TriangleId::index`]; [`NO_REGION`] for ghosts).
    pub of_triangle: Vec<u32>,
    /// The regions.
    pub regions: Vec<PartitionRegion>,
    /// For each region, the length of boundary it shares with each neighbouring region (ordered,
    /// so that sums over it are the same on every run).
    pub shared: Vec<BTreeMap<u32, f64>>,
}

impl PartitionRegions {
    /// Finds the regions of `t` under `label` (one label per triangle slot, as [`partition`]
    /// gives): a flood fill across the edges whose two triangles have the same label.
    ///
    /// [`partition`]: crate::partition
    ///
    /// ```
    /// use imesh_geom::{Point, TriangleId, Triangulation};
    /// use imesh_segment::{PartitionRegions, OUTSIDE};
    /// // A 2 × 1 rectangle cut along a diagonal into two triangles, labelled by their side of
    /// // the other diagonal's midpoint (ghost slots: OUTSIDE).
    /// let pts = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 1.0), Point::new(0.0, 1.0)];
    /// let (t, _) = Triangulation::from_points(&pts).unwrap();
    /// let label: Vec<u32> = (0..t.num_triangle_slots() as u32)
    ///     .map(|i| {
    ///         let f = TriangleId::new(i);
    ///         if !t.is_triangle(f) {
    ///             return OUTSIDE;
    ///         }
    ///         let [a, b, c] = t.triangle_points(f);
    ///         u32::from(a.x + b.x + c.x > 3.0)
    ///     })
    ///     .collect();
    /// let r = PartitionRegions::new(&t, &label);
    /// assert_eq!(r.regions.len(), 2);
    /// assert!(r.regions.iter().all(|g| (g.area - 1.0).abs() < 1e-12 && g.triangles == 1));
    /// ```
    pub fn new(t: &Triangulation, label: &[u32]) -> Self {
        let slots = t.num_triangle_slots();
        let mut of_triangle = vec![NO_REGION; slots];
        let mut regions = Vec::new();
        let mut stack = Vec::new();
        for start in t.triangles() {
            if of_triangle[start.index()] != NO_REGION {
                continue;
            }
            let id = regions.len() as u32;
            let own = label[start.index()];
            let mut region = PartitionRegion {
                label: own,
                area: 0.0,
                perimeter: 0.0,
                triangles: 0,
            };
            of_triangle[start.index()] = id;
            stack.push(start);
            while let Some(f) = stack.pop() {
                region.area += t.signed_area(f).abs();
                region.triangles += 1;
                for e in t.triangle_edges(f) {
                    match t.neighbour(e) {
                        Some(g) if label[g.index()] == own => {
                            if of_triangle[g.index()] == NO_REGION {
                                of_triangle[g.index()] = id;
                                stack.push(g);
                            }
                        }
                        _ => region.perimeter += edge_length(t, e),
                    }
                }
            }
            regions.push(region);
        }
        let mut shared = vec![BTreeMap::new(); regions.len()];
        for f in t.triangles() {
            let a = of_triangle[f.index()];
            for e in t.triangle_edges(f) {
                if let Some(g) = t.neighbour(e) {
                    let b = of_triangle[g.index()];
                    if b != a {
                        *shared[a as usize].entry(b).or_insert(0.0) += edge_length(t, e);
                    }
                }
            }
        }
        Self {
            of_triangle,
            regions,
            shared,
        }
    }
}

fn edge_length(t: &Triangulation, e: imesh_geom::HalfEdgeId) -> f64 {
    t.point(t.origin(e))
        .distance_squared(t.point(t.destination(e)))
        .sqrt()
}

/// What [`merge_thin_regions`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MergeReport {
    /// Regions merged into a neighbour.
    pub regions: usize,
    /// Their total area, in square pixels.
    pub area: f64,
}

/// Relabels every region of `t` thinner than `min_width` pixels (see [`PartitionRegion::width`])
/// with the label of the neighbouring region it shares the longest boundary with, thinnest
/// first, until none is left (a region alone in the domain is kept). `label` is one label per
/// triangle slot, as [`partition`](crate::partition) gives; nothing changes for `min_width ≤ 0`.
///
/// A merged region's width is recomputed before it is judged again (a speck merged into a thin
/// strip may leave the strip wide enough), so the result does not depend on the triangle order.
///
/// ```
/// use imesh_geom::{Point, Triangulation};
/// use imesh_segment::{merge_thin_regions, PartitionRegions};
/// // A 10 × 10 square with a 10 × 0.5 strip along its bottom.
/// let pts = [
///     Point::new(0.0, 0.0), Point::new(10.0, 0.0), Point::new(10.0, 0.5), Point::new(0.0, 0.5),
///     Point::new(10.0, 10.0), Point::new(0.0, 10.0),
/// ];
/// let (t, _) = Triangulation::from_points(&pts).unwrap();
/// let mut label: Vec<u32> = (0..t.num_triangle_slots() as u32)
///     .map(|i| {
///         let f = imesh_geom::TriangleId::new(i);
///         if !t.is_triangle(f) {
///             return imesh_segment::OUTSIDE;
///         }
///         let c = t.triangle_points(f).iter().map(|p| p.y).sum::<f64>() / 3.0;
///         u32::from(c > 0.5)
///     })
///     .collect();
/// let merged = merge_thin_regions(&t, &mut label, 1.0);
/// assert_eq!(merged.regions, 1);
/// assert_eq!(PartitionRegions::new(&t, &label).regions.len(), 1);
/// ```
pub fn merge_thin_regions(t: &Triangulation, label: &mut [u32], min_width: f64) -> MergeReport {
    merge_regions(t, label, min_width, &[])
}

/// [`merge_thin_regions`], and also the regions holding the triangles `also` whatever their
/// width: regions that the partition finds wide enough but a later stage measures as too thin
/// (a region that the curve simplification, within its tolerance, flattens into a sliver). Those
/// go first, in their order of width, then the thin ones as [`merge_thin_regions`] does.
/// `min_width ≤ 0` with `also` empty changes nothing.
///
/// ```
/// use imesh_geom::{Point, Triangulation};
/// use imesh_segment::{merge_regions, PartitionRegions};
/// // A 10 × 10 square cut into two halves by x = 5: the left half's triangles are label 0.
/// let pts = [
///     Point::new(0.0, 0.0), Point::new(5.0, 0.0), Point::new(10.0, 0.0),
///     Point::new(0.0, 10.0), Point::new(5.0, 10.0), Point::new(10.0, 10.0),
/// ];
/// let (t, _) = Triangulation::from_points(&pts).unwrap();
/// let side = |f| u32::from(t.triangle_points(f).iter().map(|p| p.x).sum::<f64>() > 15.0);
/// let mut label: Vec<u32> = (0..t.num_triangle_slots() as u32)
///     .map(|i| imesh_geom::TriangleId::new(i))
///     .map(|f| if t.is_triangle(f) { side(f) } else { imesh_segment::OUTSIDE })
///     .collect();
/// // Both halves are 5 wide: only the one named goes.
/// let left = t.triangles().find(|&f| side(f) == 0).unwrap();
/// let merged = merge_regions(&t, &mut label, 1.0, &[left]);
/// assert_eq!(merged.regions, 1);
/// assert!(t.triangles().all(|f| label[f.index()] == 1));
/// ```
pub fn merge_regions(
    t: &Triangulation,
    label: &mut [u32],
    min_width: f64,
    also: &[TriangleId],
) -> MergeReport {
    let mut report = MergeReport::default();
    let min_width = if min_width.is_nan() { 0.0 } else { min_width };
    if min_width <= 0.0 && also.is_empty() {
        return report;
    }
    let PartitionRegions {
        of_triangle,
        mut regions,
        mut shared,
    } = PartitionRegions::new(t, label);
    let n = regions.len();
    let mut forced = vec![false; n];
    for f in also {
        if let Some(&r) = of_triangle.get(f.index()) {
            if r != NO_REGION {
                forced[r as usize] = true;
            }
        }
    }
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut r: u32) -> u32 {
        while parent[r as usize] != r {
            parent[r as usize] = parent[parent[r as usize] as usize];
            r = parent[r as usize];
        }
        r
    }
    // A forced region goes in the first round, before the thin ones.
    let goes = |r: u32, regions: &[PartitionRegion], parent: &[u32]| {
        parent[r as usize] == r && (forced[r as usize] || regions[r as usize].width() < min_width)
    };
    // Rounds over the thin regions, thinnest first. A merge changes the target's width either
    // way (a speck merged into a strip widens it; a strip merged into a compact region may
    // make it thin), so each region is judged again when its turn comes, and every root again
    // in the next round.
    loop {
        let mut queue: Vec<u32> = (0..n as u32)
            .filter(|&r| goes(r, &regions, &parent))
            .collect();
        if queue.is_empty() {
            break;
        }
        queue.sort_by(|&a, &b| {
            let (ra, rb) = (&regions[a as usize], &regions[b as usize]);
            (!forced[a as usize])
                .cmp(&!forced[b as usize])
                .then(ra.width().total_cmp(&rb.width()))
                .then(a.cmp(&b))
        });
        let mut merged_any = false;
        for &r in &queue {
            if !goes(r, &regions, &parent) {
                continue;
            }
            // The neighbour with the longest shared boundary (ties to the lower id).
            let mut by_root: BTreeMap<u32, f64> = BTreeMap::new();
            for (&d, &len) in &shared[r as usize] {
                let q = root(&mut parent, d);
                if q != r {
                    *by_root.entry(q).or_insert(0.0) += len;
                }
            }
            let Some((target, along)) = by_root
                .into_iter()
                .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            else {
                continue;
            };
            parent[r as usize] = target;
            let (area, perimeter, triangles) = {
                let from = &regions[r as usize];
                (from.area, from.perimeter, from.triangles)
            };
            report.regions += 1;
            report.area += area;
            let into = &mut regions[target as usize];
            into.area += area;
            into.perimeter = (into.perimeter + perimeter - 2.0 * along).max(0.0);
            into.triangles += triangles;
            let moved = std::mem::take(&mut shared[r as usize]);
            for (d, len) in moved {
                *shared[target as usize].entry(d).or_insert(0.0) += len;
            }
            merged_any = true;
        }
        if !merged_any {
            break;
        }
    }
    if report.regions == 0 {
        return report;
    }
    let final_label: Vec<u32> = (0..n as u32)
        .map(|r| regions[root(&mut parent, r) as usize].label)
        .collect();
    for (slot, l) in label.iter_mut().enumerate() {
        let r = of_triangle[slot];
        if r != NO_REGION {
            *l = final_label[r as usize];
        }
    }
    report
}
