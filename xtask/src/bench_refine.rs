//! `cargo xtask bench refine`: our Ruppert refinement against spade's (and Triangle's, with the
//! `triangle` feature) on the same PSLGs, in one run.

use std::time::Instant;

use imesh_classify::{label_map, load_image, DEFAULT_MAX_PIXELS};
use imesh_geom::{Point, RefineOptions, Triangulation};
use serde::Serialize;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation as _,
};

/// A planar straight-line graph: points and segments between them.
struct Pslg {
    name: String,
    points: Vec<Point>,
    segments: Vec<[usize; 2]>,
}

#[derive(Serialize)]
struct Row {
    pslg: String,
    points: usize,
    segments: usize,
    min_angle_deg: f64,
    inserted: Peers<usize>,
    seconds: Peers<f64>,
    ratio_points_vs_triangle: Option<f64>,
    ratio_time_vs_triangle: Option<f64>,
    ratio_points_vs_spade: f64,
    ratio_time_vs_spade: f64,
}

#[derive(Serialize)]
struct Peers<T> {
    ours: T,
    spade: T,
    triangle: Option<T>,
}

/// The boundaries between labels of a label image, plus the image border, as maximal straight runs
/// of pixel edges between pixel corners.
fn label_boundaries(file: &str) -> Result<Pslg, String> {
    let path = crate::fixtures::fixtures_dir().join(file);
    let img = load_image(&path, DEFAULT_MAX_PIXELS).map_err(|e| e.to_string())?;
    let grid = label_map(&img, 4096).map_err(|e| e.to_string())?;
    let (w, h) = (grid.width(), grid.height());
    let differs_h = |c: u32, r: u32| r == 0 || r == h || grid.label(c, r - 1) != grid.label(c, r);
    let differs_v = |c: u32, r: u32| c == 0 || c == w || grid.label(c - 1, r) != grid.label(c, r);
    let mut corners: Vec<(u32, u32)> = Vec::new();
    let mut runs: Vec<((u32, u32), (u32, u32))> = Vec::new();
    // A run ends where the boundary turns or meets another boundary: at every corner where more
    // than the two collinear pixel edges of the run meet.
    let is_vertex = |c: u32, r: u32| {
        let left = c > 0 && differs_h(c - 1, r);
        let right = c < w && differs_h(c, r);
        let up = r > 0 && differs_v(c, r - 1);
        let down = r < h && differs_v(c, r);
        !((left && right && !up && !down) || (up && down && !left && !right))
    };
    for r in 0..=h {
        let mut start = None;
        for c in 0..=w {
            let on = c < w && differs_h(c, r);
            match (start, on) {
                (None, true) => start = Some(c),
                (Some(s), _) if !on || (c > s && is_vertex(c, r)) => {
                    runs.push(((s, r), (c, r)));
                    start = if on { Some(c) } else { None };
                }
                _ => {}
            }
        }
    }
    for c in 0..=w {
        let mut start = None;
        for r in 0..=h {
            let on = r < h && differs_v(c, r);
            match (start, on) {
                (None, true) => start = Some(r),
                (Some(s), _) if !on || (r > s && is_vertex(c, r)) => {
                    runs.push(((c, s), (c, r)));
                    start = if on { Some(r) } else { None };
                }
                _ => {}
            }
        }
    }
    for &(a, b) in &runs {
        corners.push(a);
        corners.push(b);
    }
    corners.sort_unstable();
    corners.dedup();
    let index = |p: (u32, u32)| corners.binary_search(&p).unwrap_or(0);
    Ok(Pslg {
        name: format!("{file} boundaries"),
        points: corners
            .iter()
            .map(|&(c, r)| Point::new(f64::from(c), f64::from(r)))
            .collect(),
        segments: runs.iter().map(|&(a, b)| [index(a), index(b)]).collect(),
    })
}

/// 1000 segments: edges of the Delaunay triangulation of random integer points (planar by
/// construction), taken every few edges.
fn random_planar_graph() -> Result<Pslg, String> {
    let mut s = 0x5eed_u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let points: Vec<Point> = (0..1500)
        .map(|_| Point::new((next() % 2000) as f64, (next() % 2000) as f64))
        .collect();
    let (t, ids) = Triangulation::from_points(&points).map_err(|e| e.to_string())?;
    let first: Vec<usize> = {
        let mut f = vec![usize::MAX; t.num_vertices()];
        for (i, v) in ids.iter().enumerate() {
            if f[v.index()] == usize::MAX {
                f[v.index()] = i;
            }
        }
        f
    };
    let segments: Vec<[usize; 2]> = t
        .edges()
        .step_by(4)
        .take(1000)
        .map(|e| [first[t.origin(e).index()], first[t.destination(e).index()]])
        .collect();
    Ok(Pslg {
        name: "random planar graph".into(),
        points,
        segments,
    })
}

fn ours(p: &Pslg, theta: f64) -> Result<(usize, f64), String> {
    let start = Instant::now();
    let (mut t, ids) = Triangulation::from_points(&p.points).map_err(|e| e.to_string())?;
    for &[a, b] in &p.segments {
        t.insert_segment(ids[a], ids[b])
            .map_err(|e| e.to_string())?;
    }
    let r = t
        .refine(&RefineOptions {
            min_angle_deg: theta,
            max_steiner: 2_000_000,
            ..Default::default()
        })
        .map_err(|e| e.to_string())?;
    Ok((r.inserted, start.elapsed().as_secs_f64()))
}

fn spade_refine(p: &Pslg, theta: f64) -> Result<(usize, f64), String> {
    let start = Instant::now();
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let mut handles = Vec::with_capacity(p.points.len());
    for q in &p.points {
        handles.push(
            cdt.insert(Point2::new(q.x, q.y))
                .map_err(|e| format!("{e:?}"))?,
        );
    }
    for &[a, b] in &p.segments {
        cdt.add_constraint(handles[a], handles[b]);
    }
    let before = cdt.num_vertices();
    let params = RefinementParameters::<f64>::new()
        .with_angle_limit(AngleLimit::from_deg(theta))
        .with_max_additional_vertices(2_000_000)
        .exclude_outer_faces(false);
    cdt.refine(params);
    Ok((cdt.num_vertices() - before, start.elapsed().as_secs_f64()))
}

#[cfg(feature = "triangle")]
fn triangle(p: &Pslg, theta: f64) -> Option<(usize, f64)> {
    let start = Instant::now();
    let nodes: Vec<f64> = p.points.iter().flat_map(|q| [q.x, q.y]).collect();
    let mut b = triangle_rs::Builder::new();
    b.add_nodes(&nodes);
    let starts = p.segments.iter().map(|s| s[0] as i32).collect();
    let ends = p.segments.iter().map(|s| s[1] as i32).collect();
    let mut b = b.set_segments(starts, ends);
    // p: PSLG, c: keep the convex hull (as our refinement does), q: quality, Q: quiet.
    b.set_switches(&format!("pcq{theta}Q"));
    let d = b.build();
    Some((
        d.n_vertices().saturating_sub(p.points.len()),
        start.elapsed().as_secs_f64(),
    ))
}

#[cfg(not(feature = "triangle"))]
fn triangle(_: &Pslg, _: f64) -> Option<(usize, f64)> {
    None
}

/// Runs the benchmark, prints the table and writes `target/bench/refine.json`.
pub fn run(runs: usize) -> Result<(), String> {
    if cfg!(not(feature = "triangle")) {
        println!("Triangle: OFF (its licence keeps it out of default builds; run `cargo xtask bench refine` with `--features triangle` in the xtask: cargo run -p xtask --release --features triangle -- bench refine)");
    }
    let pslgs = [
        label_boundaries("pyvista-channels_z050_labels.png")?,
        label_boundaries("stardist-mask2d_labels.png")?,
        random_planar_graph()?,
    ];
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{:<42} {:>6} {:>6} {:>5} | {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} | {:>6} {:>6}",
        "PSLG",
        "points",
        "segs",
        "θ",
        "ours pts",
        "spade",
        "Triangle",
        "ours s",
        "spade s",
        "Tri s",
        "pts/T",
        "t/T"
    );
    let mut rows = Vec::new();
    for p in &pslgs {
        for theta in [20.7, 28.0, 33.0] {
            let (mut to, mut ts, mut tt) = (Vec::new(), Vec::new(), Vec::new());
            let (mut no, mut ns, mut nt) = (0, 0, None);
            for _ in 0..runs {
                let (n, t) = ours(p, theta)?;
                no = n;
                to.push(t);
                let (n, t) = spade_refine(p, theta)?;
                ns = n;
                ts.push(t);
                if let Some((n, t)) = triangle(p, theta) {
                    nt = Some(n);
                    tt.push(t);
                }
            }
            let (so, ss) = (median(to), median(ts));
            let st = (!tt.is_empty()).then(|| median(tt));
            let row = Row {
                pslg: p.name.clone(),
                points: p.points.len(),
                segments: p.segments.len(),
                min_angle_deg: theta,
                ratio_points_vs_triangle: nt.map(|n| no as f64 / n.max(1) as f64),
                ratio_time_vs_triangle: st.map(|s| so / s),
                ratio_points_vs_spade: no as f64 / ns.max(1) as f64,
                ratio_time_vs_spade: so / ss,
                inserted: Peers {
                    ours: no,
                    spade: ns,
                    triangle: nt,
                },
                seconds: Peers {
                    ours: so,
                    spade: ss,
                    triangle: st,
                },
            };
            let opt = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
            println!(
                "{:<42} {:>6} {:>6} {:>5} | {:>8} {:>8} {:>8} | {:>8.4} {:>8.4} {:>8} | {:>6} {:>6}",
                row.pslg, row.points, row.segments, theta, no, ns, nt.map_or("-".into(), |n| n.to_string()), so, ss, opt(st, 4), opt(row.ratio_points_vs_triangle, 3), opt(row.ratio_time_vs_triangle, 3)
            );
            rows.push(row);
        }
    }
    let path = crate::bench_dir()?.join("refine.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?,
    )
    .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    println!("written {}", path.display());
    Ok(())
}
