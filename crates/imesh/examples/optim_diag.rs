use imesh_classify::{classify, load_image, Classifier, ClassifyOptions};
use imesh_curves::{fit_edges, simplify, CurveGraph, FitOptions, GraphEdge, SimplifyOptions};
use imesh_optim::{optimise, Method, Metric, OptimOptions};
use imesh_quad::{remesh, DensityOptions, Pairing, QuadOptions};
use imesh_segment::{SampleOptions, SegmentedMesh};
use std::str::FromStr;
fn env<T: FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let image = load_image(std::path::Path::new(&path), 1 << 28).unwrap();
    let grid = classify(
        &image,
        &Classifier::from_str("auto").unwrap(),
        &ClassifyOptions::default(),
    )
    .unwrap();
    let seg = SegmentedMesh::from_grid(&grid, &SampleOptions::default()).unwrap();
    let edges = seg
        .c_edges
        .iter()
        .map(|e| GraphEdge {
            ends: e.vertices.map(|v| v.index() as u32),
            labels: e.labels,
        })
        .collect();
    let g = CurveGraph::image_boundaries(
        seg.triangulation.points().to_vec(),
        edges,
        seg.width as f64,
        seg.height as f64,
    )
    .unwrap();
    let s = simplify(
        &g,
        &SimplifyOptions {
            tolerance: env("TOL", 2.0),
        },
    )
    .unwrap();
    let fits = fit_edges(&s, &g, &FitOptions::default());
    let curves: Vec<_> = fits.fits.iter().map(|f| f.curve).collect();
    let ms: f64 = env("MAXSIZE", 0.0);
    let mut r = remesh(
        &s.graph,
        &curves,
        &QuadOptions {
            density: DensityOptions {
                min_angle_deg: env("ANGLE", 20.7),
                max_steiner: usize::MAX,
                max_size: (ms > 0.0).then_some(ms),
            },
            pairing: Pairing::Matching,
            level: env("LEVEL", 1),
        },
    )
    .unwrap();
    let method = match std::env::var("METHOD").as_deref() {
        Ok("global") => Method::Global,
        Ok("vertex") => Method::Vertex,
        Ok("laplacian") => Method::Laplacian,
        Ok("none") => Method::None,
        _ => Method::Local,
    };
    let metric = if std::env::var("SHAPE").is_ok() {
        Metric::Shape
    } else {
        Metric::ShapeAndSize
    };
    let o = OptimOptions {
        method,
        metric,
        tolerance: env("STOP", 1e-3),
        max_sweeps: env("SWEEPS", 40),
        local_iterations: env("ITERS", 2),
        global_iterations: env("GITERS", 20),
    };
    let rep = optimise(&mut r, &o).unwrap();
    println!(
        "quads {} vars {} colours {} sweeps {} E {:.1}->{:.1} t {:.3}s",
        r.mesh.quads.len(),
        rep.variables,
        rep.colours,
        rep.sweeps,
        rep.energy_before,
        rep.energy_after,
        rep.seconds
    );
    for (n, b, a) in [
        ("S&S", &rep.before.shape_and_size, &rep.after.shape_and_size),
        ("shape", &rep.before.shape, &rep.after.shape),
        (
            "SJ",
            &rep.before.scaled_jacobian,
            &rep.after.scaled_jacobian,
        ),
    ] {
        println!(
            "  {n}: {:.3}/{:.3} -> {:.3}/{:.3}",
            b.min, b.mean, a.min, a.mean
        );
    }
    if std::env::var("WORST").is_ok() {
        let v: Vec<[f64; 2]> = r.mesh.vertices.iter().map(|p| [p.x, p.y]).collect();
        let mut qs: Vec<(f64, usize)> = r
            .mesh
            .quads
            .iter()
            .enumerate()
            .map(|(i, q)| {
                (
                    imesh_quality::quad::scaled_jacobian(&q.map(|u| v[u as usize])),
                    i,
                )
            })
            .collect();
        qs.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
        for &(sj, i) in qs.iter().take(8) {
            let q = r.mesh.quads[i];
            let el = r.mesh.parents[i] as usize;
            println!(
                "  q{i} sj {sj:.4} parent {:?} pts {:?}",
                r.elements.elements[el],
                q.map(|u| (v[u as usize][0] as f32, v[u as usize][1] as f32))
            );
        }
    }
}
