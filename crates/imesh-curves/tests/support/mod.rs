//! Boundary graphs of label grids, shared by the tests and the benchmark.

#![allow(dead_code)]

use std::collections::HashMap;

use imesh_classify::{LabelGrid, Region};
use imesh_curves::{
    fit_edges, simplify, CubicBezier, CurveGraph, FitOptions, GraphEdge, Simplification,
    SimplifyOptions,
};
use imesh_geom::Point;
use imesh_segment::{SampleOptions, SegmentedMesh, OUTSIDE};

/// The label grid of fixture `name` (under `fixtures/images/`): a label map for the `*labels*`
/// images, three-level Otsu of the luminance otherwise.
pub fn fixture(name: &str) -> LabelGrid {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images")
        .join(name);
    let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS).unwrap();
    if name.contains("labels") {
        return imesh_classify::label_map(&image, 256).unwrap();
    }
    let grey = imesh_classify::luminance(&image);
    imesh_classify::threshold(&grey, &imesh_classify::multi_otsu_levels(&grey, 3))
}

/// A label grid from raw labels (regions named after their index).
pub fn grid(width: u32, height: u32, labels: Vec<u32>) -> LabelGrid {
    let count = labels.iter().max().map_or(1, |&m| m + 1);
    let regions = (0..count)
        .map(|i| Region {
            name: format!("r{i}"),
            colour: [i as u8; 3],
        })
        .collect();
    LabelGrid::new(width, height, labels, regions).expect("a consistent grid")
}

/// The pixel-boundary graph: pixel corners as vertices, every pixel side between two labels (or
/// on the domain border) as an edge. A staircase graph with long collinear runs.
pub fn pixel_boundaries(grid: &LabelGrid) -> CurveGraph {
    let (w, h) = (grid.width() as i64, grid.height() as i64);
    let label = |c: i64, r: i64| {
        if c < 0 || r < 0 || c >= w || r >= h {
            OUTSIDE
        } else {
            grid.label(c as u32, r as u32)
        }
    };
    let mut ids: HashMap<(i64, i64), u32> = HashMap::new();
    let mut points = Vec::new();
    let mut id = |c: i64, r: i64, points: &mut Vec<Point>| {
        *ids.entry((c, r)).or_insert_with(|| {
            points.push(Point::new(c as f64, r as f64));
            (points.len() - 1) as u32
        })
    };
    let mut edges = Vec::new();
    for r in 0..=h {
        for c in 0..w {
            // Side from corner (c, r) to (c + 1, r): pixel row r on its positive side.
            let (below, above) = (label(c, r), label(c, r - 1));
            if below != above {
                let ends = [id(c, r, &mut points), id(c + 1, r, &mut points)];
                edges.push(GraphEdge {
                    ends,
                    labels: [below, above],
                });
            }
        }
    }
    for c in 0..=w {
        for r in 0..h {
            // Side from corner (c, r) to (c, r + 1): pixel column c − 1 on its positive side.
            let (left, right) = (label(c - 1, r), label(c, r));
            if left != right {
                let ends = [id(c, r, &mut points), id(c, r + 1, &mut points)];
                edges.push(GraphEdge {
                    ends,
                    labels: [left, right],
                });
            }
        }
    }
    CurveGraph::image_boundaries(points, edges, w as f64, h as f64)
        .expect("a valid pixel-boundary graph")
}

/// The Imesh c-edge graph of `grid` (sampling and partition, DESIGN.md §2 steps 2–3).
pub fn imesh_boundaries(grid: &LabelGrid) -> CurveGraph {
    let m = SegmentedMesh::from_grid(grid, &SampleOptions::default()).expect("sampling works");
    let edges = m
        .c_edges
        .iter()
        .map(|e| GraphEdge {
            ends: [e.vertices[0].index() as u32, e.vertices[1].index() as u32],
            labels: e.labels,
        })
        .collect();
    let (w, h) = (f64::from(grid.width()), f64::from(grid.height()));
    CurveGraph::image_boundaries(m.triangulation.points().to_vec(), edges, w, h)
        .expect("valid c-edges")
}

/// The c-edge graph of `grid`, its simplification G' at the default tolerance, and the cubic
/// fitted to each edge of G' (the quad stage's input, as the benchmarks build it).
pub fn simplified_with_curves(grid: &LabelGrid) -> (CurveGraph, Simplification, Vec<CubicBezier>) {
    let g = imesh_boundaries(grid);
    let s = simplify(&g, &SimplifyOptions::default()).expect("simplification works");
    let curves = fit_edges(&s, &g, &FitOptions::default())
        .fits
        .iter()
        .map(|f| f.curve)
        .collect();
    (g, s, curves)
}
