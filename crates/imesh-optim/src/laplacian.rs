//! The Laplacian baseline: each free quad vertex moves to the mean of its edge neighbours,
//! Gauss–Seidel style, a move being kept only when the vertex's quads stay feasible (valid, and
//! above the same floors as every mode), so that it never lowers the worst quality either.

use imesh_geom::Point;

use crate::variables::Variables;
use crate::Setup;

/// Smooths the free vertices `variables` of `vertices`; returns the sweeps run (until no vertex
/// moves by more than 10⁻⁴ of the mean edge length, or `setup.max_sweeps`).
pub(crate) fn smooth(variables: &Variables, vertices: &mut [Point], setup: &Setup<'_>) -> usize {
    let neighbours: Vec<Vec<u32>> = (0..variables.len())
        .map(|i| {
            let v = variables.ids[i];
            let mut n: Vec<u32> = variables
                .quads
                .row(i)
                .iter()
                .flat_map(|&q| {
                    let quad = setup.quads[q as usize];
                    let k = quad.iter().position(|&u| u == v).unwrap_or(0);
                    [quad[(k + 1) % 4], quad[(k + 3) % 4]]
                })
                .collect();
            n.sort_unstable();
            n.dedup();
            n
        })
        .collect();
    let still = 1e-4 * setup.average_area.sqrt();
    let mut sweeps = 0;
    while sweeps < setup.max_sweeps {
        sweeps += 1;
        let mut largest: f64 = 0.0;
        for (i, around) in neighbours.iter().enumerate() {
            if around.is_empty() {
                continue;
            }
            let v = variables.ids[i] as usize;
            let sum = around
                .iter()
                .fold(Point::new(0.0, 0.0), |s, &u| s + vertices[u as usize]);
            let target = sum * (1.0 / around.len() as f64);
            let old = vertices[v];
            vertices[v] = target;
            let valid = variables.quads.row(i).iter().all(|&q| {
                let p = setup.quads[q as usize].map(|u| vertices[u as usize]);
                setup.term(q as usize, &p).is_some()
            });
            if valid {
                largest = largest.max(old.distance_squared(target).sqrt());
            } else {
                vertices[v] = old;
            }
        }
        if largest <= still {
            break;
        }
    }
    sweeps
}
