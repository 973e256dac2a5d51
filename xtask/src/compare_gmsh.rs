//! `cargo xtask compare gmsh`: our quad mesh against Gmsh's on the same simplified boundary
//! graph G' of each fixture, at about the same number of quads, both measured with our metrics.
//!
//! Gmsh (the `gmsh` PyPI package, installed into `target/venv-gmsh`) gets G' as lines cutting the
//! domain rectangle (OpenCASCADE fragment) and meshes every piece with quads twice: Frontal-Delaunay
//! for quads with Blossom recombination and the all-quad subdivision (Gmsh's full-quad algorithm 3
//! refuses curves of one segment, which G' has), and its quasi-structured algorithm (slow: a run
//! is stopped after `IMESH_GMSH_TIMEOUT` seconds and reported as failed; `IMESH_SKIP_QQS`
//! skips it). Its time is the meshing call alone (no classification, no sampling), and again
//! with building and fragmenting the geometry of G' before it; ours is the whole run, image to
//! optimised quads. Both are the better of [`TIMED_RUNS`] runs where a run takes under
//! [`REPEAT_UNDER`] seconds: the first run of a process pays for its thread pool and the first
//! touch of its memory (our MRI run: 0.24 s first, 0.08 s after), which on a run of a tenth of a
//! second is most of the ratio.

use std::io::Write as _;
use std::process::{Command, Stdio};

use imesh::{MeshOptions, Pipeline};
use imesh_geom::predicates::orient2d;
use imesh_geom::Point;
use imesh_quality::QuadQuality;
use serde::{Deserialize, Serialize};

/// Runs timed of each side where one takes under [`REPEAT_UNDER`] seconds: the best counts.
const TIMED_RUNS: usize = 3;

/// Seconds under which a run is timed again ([`TIMED_RUNS`]).
const REPEAT_UNDER: f64 = 5.0;

/// The fixtures compared by default: the five label-like ones whose Gmsh runs take seconds
/// (`--fixtures all` adds the textured four and aloe, whose G' has thousands of curves).
pub const DEFAULT_FIXTURES: [&str; 5] = [
    "matplotlib-s1045_mri.png",
    "stardist-mask2d_labels.png",
    "skimage-coins.png",
    "pyvista-channels_z050_labels.png",
    "skimage-camera.png",
];

/// Which fixtures [`run`] compares.
#[derive(Clone, Debug, PartialEq)]
pub enum Fixtures {
    /// [`DEFAULT_FIXTURES`].
    Default,
    /// Every image under `fixtures/images`.
    All,
    /// These file names under `fixtures/images`.
    Named(Vec<String>),
}

impl std::str::FromStr for Fixtures {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "all" => Ok(Self::All),
            "default" => Ok(Self::Default),
            names => {
                let names: Vec<String> = names
                    .split(',')
                    .map(str::trim)
                    .filter(|n| !n.is_empty())
                    .map(String::from)
                    .collect();
                if names.is_empty() {
                    Err("--fixtures wants all, default or file names separated by commas".into())
                } else {
                    Ok(Self::Named(names))
                }
            }
        }
    }
}

impl Fixtures {
    /// The image files, each checked to exist.
    fn paths(&self) -> Result<Vec<std::path::PathBuf>, String> {
        let dir = crate::fixtures::fixtures_dir();
        let named = |names: &mut dyn Iterator<Item = &str>| {
            names
                .map(|name| {
                    let path = dir.join(name);
                    if path.is_file() {
                        Ok(path)
                    } else {
                        Err(format!(
                            "no fixture {name} under fixtures/images (its file names: `ls fixtures/images`)"
                        ))
                    }
                })
                .collect()
        };
        match self {
            Self::Default => named(&mut DEFAULT_FIXTURES.iter().copied()),
            Self::All => crate::fixtures::fixture_images(),
            Self::Named(names) => named(&mut names.iter().map(String::as_str)),
        }
    }
}

const GMSH: &str = "gmsh==4.15.2";

#[derive(Deserialize)]
struct GmshMesh {
    nodes: Vec<[f64; 2]>,
    quads: Vec<[u32; 4]>,
    triangles: Vec<[u32; 3]>,
    seconds: f64,
    geometry_seconds: f64,
}

#[derive(Serialize)]
struct Side {
    quads: usize,
    triangles: usize,
    invalid_quads: usize,
    /// Ours: the whole run from the image. Gmsh's: its meshing call alone.
    seconds: f64,
    /// Gmsh's: building and fragmenting the geometry of G' before meshing (0 for ours, whose
    /// `seconds` hold every stage).
    geometry_seconds: f64,
    shape_and_size_min: f64,
    shape_and_size_mean: f64,
    scaled_jacobian_min: f64,
    scaled_jacobian_mean: f64,
}

#[derive(Serialize)]
struct Row {
    fixture: String,
    ours: Side,
    blossom: Option<Side>,
    quasi_structured: Option<Side>,
}

/// Quads whose corners do not all turn the same way (exact orientation): inverted, non-convex or
/// degenerate. Gmsh may orient a whole surface clockwise, which is not counted.
fn invalid(vertices: &[[f64; 2]], quads: &[[u32; 4]]) -> usize {
    quads
        .iter()
        .filter(|q| {
            let p = q.map(|v| Point::new(vertices[v as usize][0], vertices[v as usize][1]));
            let turns = (0..4).map(|i| orient2d(p[(i + 3) % 4], p[i], p[(i + 1) % 4]));
            let (positive, negative) = turns.fold((0, 0), |(pos, neg), o| {
                (pos + usize::from(o > 0.0), neg + usize::from(o < 0.0))
            });
            positive != 4 && negative != 4
        })
        .count()
}

fn side(
    vertices: &[[f64; 2]],
    quads: &[[u32; 4]],
    triangles: usize,
    seconds: f64,
    geometry_seconds: f64,
) -> Side {
    let q = QuadQuality::of(vertices, quads);
    Side {
        quads: quads.len(),
        triangles,
        invalid_quads: invalid(vertices, quads),
        seconds,
        geometry_seconds,
        shape_and_size_min: q.shape_and_size.min,
        shape_and_size_mean: q.shape_and_size.mean,
        scaled_jacobian_min: q.scaled_jacobian.min,
        scaled_jacobian_mean: q.scaled_jacobian.mean,
    }
}

/// How long one Gmsh run may take before it is stopped and reported as failed (seconds;
/// `IMESH_GMSH_TIMEOUT` overrides): the quasi-structured algorithm took minutes on some of
/// these graphs.
const GMSH_TIMEOUT_S: u64 = 600;

fn gmsh(python: &std::path::Path, spec: &serde_json::Value) -> Result<GmshMesh, String> {
    let script = crate::fixtures::workspace_root()?.join("xtask/scripts/mesh_graph.py");
    let mut child = Command::new(python)
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start Gmsh's Python: {e}"))?;
    child
        .stdin
        .take()
        .ok_or("no stdin")?
        .write_all(spec.to_string().as_bytes())
        .map_err(|e| e.to_string())?;
    // The output is read while Gmsh runs, so that a mesh larger than the pipe's buffer cannot
    // block it, and the clock can stop it.
    let read = |pipe: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = read(child.stdout.take().map(|p| Box::new(p) as _));
    let stderr = read(child.stderr.take().map(|p| Box::new(p) as _));
    let limit = std::env::var("IMESH_GMSH_TIMEOUT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(GMSH_TIMEOUT_S);
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            break status;
        }
        if start.elapsed().as_secs() >= limit {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("Gmsh stopped after {limit} s (IMESH_GMSH_TIMEOUT)"));
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let (out, err) = (
        stdout.join().map_err(|_| "Gmsh's output reader failed")?,
        stderr.join().map_err(|_| "Gmsh's error reader failed")?,
    );
    if !status.success() {
        return Err(format!("Gmsh failed: {}", String::from_utf8_lossy(&err)));
    }
    serde_json::from_slice(&out).map_err(|e| format!("Gmsh's output: {e}"))
}

fn cell(s: &Option<Side>, ours: &Side) -> String {
    match s {
        None => "failed | | | | ".into(),
        Some(s) => format!(
            "{} + {} tri, {} inv | {:.3} / {:.3} | {:.3} / {:.3} | {:.2} s ({:.2}×) | {:.2} s ({:.2}×)",
            s.quads,
            s.triangles,
            s.invalid_quads,
            s.shape_and_size_min,
            s.shape_and_size_mean,
            s.scaled_jacobian_min,
            s.scaled_jacobian_mean,
            s.seconds,
            ours.seconds / s.seconds,
            s.geometry_seconds + s.seconds,
            ours.seconds / (s.geometry_seconds + s.seconds)
        ),
    }
}

/// Runs the comparison on the fixtures with our `options` (Gmsh gets the same G' and a uniform
/// size giving about our quad count) and writes `target/bench/compare-gmsh.json`.
pub fn run(options: MeshOptions, fixtures: &Fixtures) -> Result<(), String> {
    let root = crate::fixtures::workspace_root()?;
    let paths = fixtures.paths()?;
    let python = crate::fixtures::venv_python(&root, "venv-gmsh", "import gmsh", GMSH)?;
    let mut rows = Vec::new();
    println!("| fixture | ours: quads | S&S worst / mean | SJ worst / mean | s | Blossom: quads | S&S | SJ | meshing s (ours/Gmsh) | geometry + meshing s (ours/Gmsh) | quasi-structured: quads | S&S | SJ | meshing s (ours/Gmsh) | geometry + meshing s (ours/Gmsh) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for path in &paths {
        let file = path
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default();
        // Our whole run, timed alone, then once more for G' (the stage pictures).
        let ours = Pipeline::new(options.clone())
            .run_path(path)
            .map_err(|e| format!("{file}: {e}"))?;
        let staged = Pipeline::new(options.clone())
            .with_stages()
            .run_path(path)
            .map_err(|e| format!("{file}: {e}"))?;
        let g = staged
            .stages
            .iter()
            .find(|s| s.name.ends_with("simplified"))
            .ok_or("no G' picture")?;
        let (w, h) = (f64::from(ours.mesh.width), f64::from(ours.mesh.height));
        // G' as points and edges, y up so that Gmsh's elements are counter-clockwise.
        let mut index = std::collections::HashMap::new();
        let mut points: Vec<[f64; 2]> = Vec::new();
        let mut edges = Vec::new();
        for segment in &g.lines {
            let ends = segment.map(|p| {
                let key = (p[0].to_bits(), p[1].to_bits());
                *index.entry(key).or_insert_with(|| {
                    points.push([p[0], h - p[1]]);
                    points.len() - 1
                })
            });
            edges.push(ends);
        }
        let our_vertices = ours.mesh.vertices.clone();
        let our_quads: Vec<[u32; 4]> = ours
            .mesh
            .elements
            .iter()
            .filter_map(|e| match e {
                imesh_quality::Element::Quad(q) => Some(*q),
                imesh_quality::Element::Triangle(_) => None,
            })
            .collect();
        let mut our_seconds = ours.report.seconds.total;
        for _ in 1..TIMED_RUNS {
            if our_seconds >= REPEAT_UNDER {
                break;
            }
            let again = Pipeline::new(options.clone())
                .run_path(path)
                .map_err(|e| format!("{file}: {e}"))?;
            our_seconds = our_seconds.min(again.report.seconds.total);
        }
        let our_side = side(&our_vertices, &our_quads, 0, our_seconds, 0.0);
        let target = our_quads.len() as f64;
        let peer = |algorithm: &str| -> Option<Side> {
            // Quads of side lc: about area / lc² (the subdivision splits every element of the
            // mesh at 2 lc into three or four); run again, the size scaled by the count's
            // square root, while the count is off by over 10 % (at most three runs: Blossom's
            // first count is 1.05–1.25 times ours, and its time grows with the count).
            let full_quad = if algorithm == "blossom" { 2.0 } else { 1.0 };
            let mut lc = full_quad * (w * h / target).sqrt();
            let mut last: Option<GmshMesh> = None;
            let mut last_spec = serde_json::Value::Null;
            for _ in 0..3 {
                if let Some(m) = &last {
                    let count = (m.quads.len() + m.triangles.len()) as f64;
                    if (count / target - 1.0).abs() <= 0.1 {
                        break;
                    }
                }
                let spec = serde_json::json!({
                    "width": w, "height": h, "points": points, "edges": edges,
                    "size": lc, "algorithm": algorithm,
                });
                if std::env::var_os("IMESH_DUMP_SPEC").is_some() {
                    let dump = root
                        .join("target/bench")
                        .join(format!("{file}.{algorithm}.json"));
                    let _ = std::fs::write(dump, spec.to_string());
                }
                let m = match gmsh(&python, &spec) {
                    Ok(m) => m,
                    Err(e) => {
                        eprintln!("{file} {algorithm}: {e}");
                        return None;
                    }
                };
                let count = (m.quads.len() + m.triangles.len()).max(1) as f64;
                lc *= (count / target).sqrt();
                last = Some(m);
                last_spec = spec;
            }
            // The kept size again, as ours, where a run is short: the best time counts.
            if let Some(m) = &mut last {
                for _ in 1..TIMED_RUNS {
                    if m.seconds >= REPEAT_UNDER {
                        break;
                    }
                    let Ok(again) = gmsh(&python, &last_spec) else {
                        break;
                    };
                    m.seconds = m.seconds.min(again.seconds);
                    m.geometry_seconds = m.geometry_seconds.min(again.geometry_seconds);
                }
            }
            last.map(|m| {
                side(
                    &m.nodes,
                    &m.quads,
                    m.triangles.len(),
                    m.seconds,
                    m.geometry_seconds,
                )
            })
        };
        let blossom = peer("blossom");
        let skip_quasi = std::env::var_os("IMESH_SKIP_QQS").is_some();
        let quasi = if skip_quasi {
            None
        } else {
            peer("quasi-structured")
        };
        println!(
            "| {file} | {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.2} | {} | {} |",
            our_side.quads,
            our_side.shape_and_size_min,
            our_side.shape_and_size_mean,
            our_side.scaled_jacobian_min,
            our_side.scaled_jacobian_mean,
            our_side.seconds,
            cell(&blossom, &our_side),
            if skip_quasi {
                "skipped | | | | ".into()
            } else {
                cell(&quasi, &our_side)
            },
        );
        rows.push(Row {
            fixture: file,
            ours: our_side,
            blossom,
            quasi_structured: quasi,
        });
    }
    let out = crate::bench_dir()?.join("compare-gmsh.json");
    let text = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
    std::fs::write(&out, text).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    println!("\nwritten {}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--fixtures` takes all, default or names; the names must be fixtures, and all is every
    /// image under fixtures/images, the default five among them.
    #[test]
    fn the_fixtures_are_chosen_by_name_or_all() {
        assert_eq!("all".parse(), Ok(Fixtures::All));
        assert_eq!("default".parse(), Ok(Fixtures::Default));
        assert_eq!(
            "skimage-coins.png, skimage-grass.png".parse(),
            Ok(Fixtures::Named(vec![
                "skimage-coins.png".into(),
                "skimage-grass.png".into()
            ]))
        );
        assert!(" , ".parse::<Fixtures>().is_err());

        let all = Fixtures::All.paths().unwrap();
        let default = Fixtures::Default.paths().unwrap();
        assert_eq!(default.len(), DEFAULT_FIXTURES.len());
        assert!(default.iter().all(|p| all.contains(p)));
        assert!(all.len() > default.len());
        let named = Fixtures::Named(vec!["skimage-coins.png".into()]);
        assert_eq!(
            named.paths().unwrap(),
            [crate::fixtures::fixtures_dir().join("skimage-coins.png")]
        );
        let missing = Fixtures::Named(vec!["no-such.png".into()]);
        assert!(missing.paths().unwrap_err().contains("no-such.png"));
    }
}
