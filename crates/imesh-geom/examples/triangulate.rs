//! Triangulates a point file (or a pixel grid), checks the result exactly, and can draw it.
//!
//! ```text
//! cargo run --release -p imesh-geom --example triangulate -- POINTS.txt [--svg OUT.svg]
//! cargo run --release -p imesh-geom --example triangulate -- --grid 1000x1000
//! ```
//! A point file has one point per line, `x y` separated by spaces, tabs or a comma; `#` starts a
//! comment.

use std::process::ExitCode;
use std::time::Instant;

use imesh_geom::{Point, Triangulation};

const USAGE: &str = "usage: triangulate (POINTS.txt | --grid WxH) [--svg OUT.svg]";

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut points = None;
    let mut svg = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--grid" => points = Some(grid(it.next().ok_or("--grid needs WxH, e.g. 1000x1000")?)?),
            "--svg" => svg = Some(it.next().ok_or("--svg needs a file name")?.clone()),
            path if !path.starts_with("--") => points = Some(read_points(path)?),
            other => return Err(format!("unknown option '{other}'")),
        }
    }
    let points = points.ok_or("give a point file or --grid WxH")?;
    let start = Instant::now();
    let (tri, _) = Triangulation::from_points(&points).map_err(|e| e.to_string())?;
    let build = start.elapsed();
    let start = Instant::now();
    tri.check()
        .map_err(|e| format!("internal error, please report: {e}"))?;
    println!(
        "{} points -> {} vertices, {} triangles, {} hull edges; built in {:.3} s, checked (exact empty-circle) in {:.3} s",
        points.len(),
        tri.num_vertices(),
        tri.num_triangles(),
        tri.num_hull_edges(),
        build.as_secs_f64(),
        start.elapsed().as_secs_f64()
    );
    if let Some(path) = svg {
        write_svg(&tri, &path)?;
        println!("drawn to {path}");
    }
    Ok(())
}

fn grid(spec: &str) -> Result<Vec<Point>, String> {
    let bad = || format!("--grid takes WxH with positive integers, not '{spec}'");
    let (w, h) = spec.split_once('x').ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if w == 0 || h == 0 || u64::from(w) * u64::from(h) > 50_000_000 {
        return Err(bad());
    }
    Ok((0..h)
        .flat_map(|r| (0..w).map(move |c| Point::pixel_centre(c, r)))
        .collect())
}

fn read_points(path: &str) -> Result<Vec<Point>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read '{path}': {e}"))?;
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|f| !f.is_empty())
            .collect();
        let parsed: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
        match parsed.as_deref() {
            Some(&[x, y]) if x.is_finite() && y.is_finite() => points.push(Point::new(x, y)),
            _ => {
                return Err(format!(
                    "{path}:{}: expected two finite numbers 'x y', found '{line}'",
                    n + 1
                ))
            }
        }
    }
    Ok(points)
}

fn write_svg(tri: &Triangulation, path: &str) -> Result<(), String> {
    let (mut lo, mut hi) = (
        Point::new(f64::MAX, f64::MAX),
        Point::new(f64::MIN, f64::MIN),
    );
    for p in tri.points() {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    let scale = 800.0 / (hi.x - lo.x).max(hi.y - lo.y).max(1e-9);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0}\" height=\"{:.0}\">\n<g fill=\"#cfe3f7\" stroke=\"#1f4e79\" stroke-width=\"0.6\">\n",
        (hi.x - lo.x) * scale + 20.0,
        (hi.y - lo.y) * scale + 20.0
    );
    for t in tri.triangles() {
        let pts: Vec<String> = tri
            .triangle_points(t)
            .iter()
            .map(|p| {
                format!(
                    "{:.2},{:.2}",
                    (p.x - lo.x) * scale + 10.0,
                    (p.y - lo.y) * scale + 10.0
                )
            })
            .collect();
        s.push_str(&format!("<polygon points=\"{}\"/>\n", pts.join(" ")));
    }
    s.push_str("</g>\n</svg>\n");
    // Write beside the target and rename, so that a failure never leaves half a file.
    let tmp = format!("{path}.tmp");
    std::fs::write(&tmp, s).map_err(|e| format!("cannot write '{tmp}': {e}"))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("cannot rename '{tmp}' to '{path}': {e}"))
}
