//! `cargo xtask bench delaunay`: our kernel against spade (bulk load) and delaunator.
//!
//! All three build the triangulation of the same points in one process, interleaved run by run so
//! that machine noise hits them alike; the table reports median wall times and the ratio ours/peer.

use std::hint::black_box;
use std::time::Instant;

use imesh_geom::{Point, Triangulation};
use serde::Serialize;
use spade::Triangulation as _;

use crate::alloc::peak_during;

/// Options of the Delaunay benchmark.
pub struct Options {
    /// Timed runs per input and implementation.
    pub runs: usize,
    /// Small inputs only.
    pub quick: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            runs: 7,
            quick: false,
        }
    }
}

#[derive(Serialize)]
struct Row {
    input: String,
    points: usize,
    triangles: usize,
    runs: usize,
    median_s: Timings,
    ratio_ours_over_spade: f64,
    ratio_ours_over_delaunator: f64,
    peak_bytes_per_vertex: Timings,
}

#[derive(Serialize, Clone, Copy)]
struct Timings {
    ours: f64,
    spade: f64,
    delaunator: f64,
}

fn uniform(n: usize, seed: u64) -> Vec<Point> {
    imesh_geom::sample::uniform_points(n, seed, 1000.0)
}

fn pixel_grid(side: u32) -> Vec<Point> {
    imesh_geom::sample::pixel_centres(side, side)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ours(points: &[Point]) -> usize {
    match Triangulation::from_points(points) {
        Ok((t, _)) => t.num_triangles(),
        Err(_) => 0,
    }
}

fn spade(points: Vec<spade::Point2<f64>>) -> usize {
    spade::DelaunayTriangulation::<spade::Point2<f64>>::bulk_load(points)
        .map(|t| t.num_inner_faces())
        .unwrap_or(0)
}

fn delaunator(points: &[delaunator::Point]) -> usize {
    delaunator::triangulate(points).len()
}

fn bench_input(name: &str, points: &[Point], runs: usize) -> Row {
    let spade_pts: Vec<spade::Point2<f64>> = points
        .iter()
        .map(|p| spade::Point2::new(p.x, p.y))
        .collect();
    let del_pts: Vec<delaunator::Point> = points
        .iter()
        .map(|p| delaunator::Point { x: p.x, y: p.y })
        .collect();
    let (mut t_ours, mut t_spade, mut t_del) = (Vec::new(), Vec::new(), Vec::new());
    let mut counts = (0, 0, 0);
    for _ in 0..runs {
        let start = Instant::now();
        counts.0 = black_box(ours(black_box(points)));
        t_ours.push(start.elapsed().as_secs_f64());

        let input = spade_pts.clone();
        let start = Instant::now();
        counts.1 = black_box(spade(black_box(input)));
        t_spade.push(start.elapsed().as_secs_f64());

        let start = Instant::now();
        counts.2 = black_box(delaunator(black_box(&del_pts)));
        t_del.push(start.elapsed().as_secs_f64());
    }
    if counts.0 != counts.1 || counts.0 != counts.2 {
        eprintln!(
            "warning: {name}: triangle counts differ (ours {}, spade {}, delaunator {})",
            counts.0, counts.1, counts.2
        );
    }
    let n = points.len() as f64;
    let (_, b_ours) = peak_during(|| ours(points));
    let (_, b_spade) = peak_during(|| spade(spade_pts.clone()));
    // The clone handed to spade is its input, not its working memory.
    let b_spade =
        b_spade.saturating_sub(spade_pts.len() * std::mem::size_of::<spade::Point2<f64>>());
    let (_, b_del) = peak_during(|| delaunator(&del_pts));
    let median_s = Timings {
        ours: median(t_ours),
        spade: median(t_spade),
        delaunator: median(t_del),
    };
    Row {
        input: name.to_string(),
        points: points.len(),
        triangles: counts.0,
        runs,
        ratio_ours_over_spade: median_s.ours / median_s.spade,
        ratio_ours_over_delaunator: median_s.ours / median_s.delaunator,
        median_s,
        peak_bytes_per_vertex: Timings {
            ours: b_ours as f64 / n,
            spade: b_spade as f64 / n,
            delaunator: b_del as f64 / n,
        },
    }
}

/// Runs the benchmark, prints the table and writes `target/bench/delaunay.json`.
pub fn run(options: &Options) -> Result<(), String> {
    let (small, large, side) = if options.quick {
        (10_000, 100_000, 316)
    } else {
        (100_000, 1_000_000, 1000)
    };
    let inputs = [
        (format!("uniform {small}"), uniform(small, 0x1234_5678)),
        (format!("uniform {large}"), uniform(large, 0x8765_4321)),
        (format!("pixel grid {side}x{side}"), pixel_grid(side)),
    ];
    let mut rows = Vec::new();
    println!(
        "{:<22} {:>9} {:>10} {:>10} {:>10} {:>11} {:>11} {:>16}",
        "input",
        "points",
        "ours s",
        "spade s",
        "delaun. s",
        "ours/spade",
        "ours/delau",
        "bytes/vertex o/s/d"
    );
    for (name, points) in &inputs {
        let r = bench_input(name, points, options.runs);
        println!(
            "{:<22} {:>9} {:>10.4} {:>10.4} {:>10.4} {:>11.3} {:>11.3} {:>6.0}/{:.0}/{:.0}",
            r.input,
            r.points,
            r.median_s.ours,
            r.median_s.spade,
            r.median_s.delaunator,
            r.ratio_ours_over_spade,
            r.ratio_ours_over_delaunator,
            r.peak_bytes_per_vertex.ours,
            r.peak_bytes_per_vertex.spade,
            r.peak_bytes_per_vertex.delaunator
        );
        rows.push(r);
    }
    let path = crate::bench_dir()?.join("delaunay.json");
    let json = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
    std::fs::write(&path, json).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    println!("written {}", path.display());
    Ok(())
}
