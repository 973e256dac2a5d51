//! The worst corners last. The energy `Σ (1 − s)²` weighs a quad by its shape-and-size, so a
//! quad of fair size with one sharp corner costs it little, and the descent leaves it: a
//! triangle template's corner at a flat triangle's centroid, or a quad squeezed against a curve.
//! Here every free quad vertex within two rings of a quad whose scaled Jacobian or shape is
//! under the bar moves, by compass search, to raise the smallest scaled Jacobian of its own
//! quads, then at an equal one their smallest shape (both counted up to the bar only, so that
//! nothing moves for quads already good enough), every quad held to the descent's floors: the
//! worst quality, worst shape and worst scaled Jacobian never fall.

use imesh_geom::{Point, Triangulation};
use imesh_quad::{ElementMesh, QuadMesh};

use crate::variables::{vertex_quads, Variables};
use crate::Setup;

/// Quads with a scaled Jacobian or a shape under this are repaired
/// ([`crate::OptimOptions::repair`]), and a vertex's objective counts up to it. Measured on
/// nine fixtures with the defaults (scaled Jacobians alone): at 0.5 (the sine of 30°, issue 8's
/// target) the same worst scaled Jacobians as at 0.4, but mean shape-and-size up to 0.0025 lower
/// (grass), more vertices moving for quads already fair; at 0.4 within 0.0005.
pub const REPAIR_JACOBIAN: f64 = 0.4;

/// Most passes over the vertices near poor quads (each pass finds them again).
const PASSES: usize = 4;

/// Compass directions: the axes, then the diagonals.
const DIRECTIONS: [(f64, f64); 8] = [
    (1.0, 0.0),
    (-1.0, 0.0),
    (0.0, 1.0),
    (0.0, -1.0),
    (1.0, 1.0),
    (-1.0, -1.0),
    (1.0, -1.0),
    (-1.0, 1.0),
];

/// The first step, as a share of the mean distance from the vertex to the other corners of its
/// quads, and how many times it is halved before the search stops. The search takes the first
/// direction that improves and stops once its quads reach the bar, so a long first step
/// overshoots: against 0.25, a twentieth gave a higher mean shape-and-size on 33 of 36 runs
/// (nine fixtures at the default size, 3 px, 4 px and graded; +0.0001 to +0.002, the other
/// three equal to four decimals) and fewer quads under 0.25 on 26 (more on 6), while the worst
/// single quads moved both ways
/// (coffee's worst scaled Jacobian 0.280 → 0.366 at the default size, MRI's 0.417 → 0.401 at
/// 3 px, coffee's worst shape 0.307 → 0.234 at 4 px). 0.1 and 0.02 did no better.
const FIRST_STEP: f64 = 0.05;
const HALVINGS: usize = 12;

/// Raises the worst scaled Jacobians and shapes of `mesh`'s quads towards `bar`, moving its
/// free vertices (those of the vertex mode: not on a constrained M edge of `elements`); returns
/// how many moved. Sequential and in a fixed order: the same on any number of threads.
pub(crate) fn repair(
    t: &Triangulation,
    elements: &ElementMesh,
    mesh: &mut QuadMesh,
    setup: &Setup,
    bar: f64,
) -> usize {
    // The quads under the bar: by shape, which is at most the scaled Jacobian at every corner.
    let poor = |vertices: &[Point]| -> Vec<u32> {
        (0..setup.quads.len() as u32)
            .filter(|&q| {
                let p = setup.quads[q as usize]
                    .map(|v| [vertices[v as usize].x, vertices[v as usize].y]);
                imesh_quality::quad::shape(&p) < bar
            })
            .collect()
    };
    let first = poor(&mesh.vertices);
    if first.is_empty() {
        return 0;
    }
    // Only the vertices within two rings of a poor quad can take part.
    let around = vertex_quads(mesh);
    let mut near = vec![false; mesh.vertices.len()];
    for &q in &first {
        for v in setup.quads[q as usize] {
            for &r in around.row(v as usize) {
                for u in setup.quads[r as usize] {
                    near[u as usize] = true;
                }
            }
        }
    }
    let vars = Variables::vertices_where(t, elements, mesh, |v| near[v as usize]);
    let vertices = &mut mesh.vertices;
    let mut moved = vec![false; vars.len()];
    let mut poor_quads = first;
    for pass in 0..PASSES {
        if pass > 0 {
            poor_quads = poor(vertices);
        }
        // The variables within two rings of a poor quad: those of the quads sharing a free
        // vertex with it (its own vertices' other quads).
        let mut wanted = vec![false; vars.len()];
        for &q in &poor_quads {
            for &i in vars.by_quad.row(q as usize) {
                for &r in vars.quads.row(i as usize) {
                    for &j in vars.by_quad.row(r as usize) {
                        wanted[j as usize] = true;
                    }
                }
            }
        }
        let mut any = false;
        for i in (0..vars.len()).filter(|&i| wanted[i]) {
            if improve(&vars, i, vertices, setup, bar) {
                moved[i] = true;
                any = true;
            }
        }
        if !any {
            break;
        }
    }
    moved.iter().filter(|&&m| m).count()
}

/// Compass search for vertex variable `i`: the smallest of its quads' scaled Jacobians as high
/// as the floors allow, then, at an equal smallest scaled Jacobian, the smallest of their shapes
/// (both capped at `bar`). True when it moved.
fn improve(vars: &Variables, i: usize, vertices: &mut [Point], setup: &Setup, bar: f64) -> bool {
    let v = vars.ids[i] as usize;
    let quads = vars.quads.row(i);
    // The objective at the current position, or None where a quad is invalid or under a floor.
    let value = |vertices: &[Point]| -> Option<(f64, f64)> {
        let (mut jacobian, mut shape) = (bar, bar);
        for &q in quads {
            let p = setup.quads[q as usize].map(|u| vertices[u as usize]);
            let (_, s) = setup.feasible_quality(q as usize, &p)?;
            shape = shape.min(s);
            // The scaled Jacobian is at least the shape: only a shape under the bar can leave
            // it there.
            if s < bar {
                let j = imesh_quality::quad::scaled_jacobian(&p.map(|p| [p.x, p.y]));
                jacobian = jacobian.min(j);
            }
        }
        Some((jacobian, shape))
    };
    let Some(mut best) = value(vertices) else {
        return false;
    };
    let start = vertices[v];
    let (mut sum, mut count) = (0.0, 0usize);
    for &q in quads {
        for u in setup.quads[q as usize] {
            if u as usize != v {
                sum += vertices[u as usize].distance_squared(start).sqrt();
                count += 1;
            }
        }
    }
    let mut step = FIRST_STEP * sum / count.max(1) as f64;
    let mut halvings = 0;
    while halvings <= HALVINGS && best.1 < bar {
        let here = vertices[v];
        let mut stepped = false;
        for (dx, dy) in DIRECTIONS {
            vertices[v] = Point::new(here.x + dx * step, here.y + dy * step);
            match value(vertices) {
                Some(f) if f.0 > best.0 || (f.0 == best.0 && f.1 > best.1) => {
                    best = f;
                    stepped = true;
                    break;
                }
                _ => vertices[v] = here,
            }
        }
        if !stepped {
            step *= 0.5;
            halvings += 1;
        }
    }
    vertices[v] != start
}
