//! `cargo xtask`: project automation for imesh, in Rust (no shell scripts).
//!
//! ```text
//! cargo xtask bench delaunay [--runs N] [--quick]
//! cargo xtask bench refine [--runs N]
//! cargo xtask bench optim [--global-iterations N]
//! cargo xtask bench pipeline [--scaling-max SIDE] [--readme]
//! cargo xtask bench random [--count N] [--seed S] [--size S] [--optimizer M] [--corner-reach R] [--images DIR]
//! cargo xtask compare gmsh [--size auto|graded|PX] [--fixtures all|NAME,...]
//! cargo xtask fixtures [points | quality]
//! cargo xtask fuzz [TARGET ...] [--seconds N]
//! ```

mod alloc;
mod bench_delaunay;
mod bench_optim;
mod bench_pipeline;
mod bench_random;
mod bench_refine;
mod compare_gmsh;
mod fixtures;
mod fuzz;

use std::process::ExitCode;

const USAGE: &str = "usage: cargo xtask bench delaunay [--runs N] [--quick]
       cargo xtask bench refine [--runs N]
       cargo xtask bench optim [--global-iterations N]
       cargo xtask bench pipeline [--scaling-max SIDE] [--readme]
       cargo xtask bench random [--count N] [--seed S] [--size S] [--optimizer M] [--corner-reach R] [--images DIR]
       cargo xtask compare gmsh [--size auto|graded|PX] [--fixtures all|NAME,...]
       cargo xtask fixtures [points | quality]
       cargo xtask fuzz [TARGET ...] [--seconds N]

  bench delaunay   our Delaunay kernel against spade and delaunator on the same inputs;
                   writes target/bench/delaunay.json
    --runs N       timed runs per input and implementation (median reported; default 7)
    --quick        smaller inputs (10^4, 10^5 points, 316x316 grid) for a fast check

  bench refine     Ruppert refinement of fixture label boundaries and a random planar graph at
                   20.7°, 28° and 33°: ours against spade (and Triangle with --features triangle);
                   writes target/bench/refine.json

  bench optim      the quad optimisers (none, laplacian, vertex, local; global on the small
                   fixtures) through the whole pipeline: worst / mean quality and seconds;
                   writes target/bench/optim.json
    --global-iterations N   Powell iterations of the global mode (default 10)

  bench pipeline   the whole run on every fixture as the paper's Table I (counts, seconds per
                   stage, quality), again graded and at one quad size (--size 3), one image
                   at three densities (Figure 8 / Table II), and the
                   camera fixture resized 256² … 4096² (seconds and peak heap per stage);
                   writes target/bench/pipeline.md and pipeline.json
    --scaling-max SIDE   largest side of the scaling series (default 4096)
    --readme             also write the tables into README.md's results section

  bench random     the defaults on random label images (Voronoi cells, smoothed noise cut at
                   quantiles, discs and rectangles; 120-300 px): mean of the mean and of the
                   worst shape-and-size, quads under 0.25, under 0.5 in shape and in scaled
                   Jacobian, per image and summed (what a change is judged by: one image's
                   worst quads move by chance); writes target/bench/random.json
    --count N      images (default 150)
    --seed S       the images' seed (default 52)
    --size S       the quad size instead of the default (auto, graded or pixels)
    --optimizer M  the optimiser to run instead of the default (local, vertex, laplacian, none)
    --images DIR   also write each image there as NNN-KIND.png (to mesh one alone)

  compare gmsh     our quad mesh against Gmsh's (Blossom full-quad and quasi-structured) on the
                   same simplified boundaries of the fixtures (five label-like ones unless
                   --fixtures) at about the same quad count, both measured with our metrics,
                   Gmsh's time with and without building its geometry; Gmsh from PyPI into
                   target/venv-gmsh; writes target/bench/compare-gmsh.json
    --size S             our element size (auto, graded or pixels; default: auto)
    --fixtures F         all (every fixture), default (the five), or file names under
                         fixtures/images separated by commas

  fixtures         regenerate everything under fixtures/ that this project derives, and say
                   what changed: points/disc-boundary.txt (a synthetic label boundary) and
                   quality/ (the Verdict reference tables; VTK from PyPI into target/venv-vtk);
                   `fixtures points` or `fixtures quality` for one of them

  fuzz             coverage-guided fuzzing (cargo-fuzz, libFuzzer, nightly) of the harnesses
                   in fuzz/harness.rs: delaunay, refine, simplify, pipeline, decode, read (all when
                   none is named), one after the other; inputs that break an invariant land in
                   fuzz/artifacts/TARGET/ (replayed by `cargo test` once under fuzz/regressions/)
    --seconds N    fuzzing time per target (default 600)";

#[global_allocator]
static ALLOCATOR: alloc::CountingAllocator = alloc::CountingAllocator;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}\n\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &[String]) -> Result<(), String> {
    let words: Vec<&str> = args.iter().map(String::as_str).collect();
    match words.as_slice() {
        ["bench", "delaunay", rest @ ..] => {
            let mut options = bench_delaunay::Options::default();
            let mut it = rest.iter();
            while let Some(&flag) = it.next() {
                match flag {
                    "--quick" => options.quick = true,
                    "--runs" => options.runs = positive(flag, it.next())?,
                    other => return Err(format!("unknown option '{other}'")),
                }
            }
            bench_delaunay::run(&options)
        }
        ["bench", "refine", rest @ ..] => {
            let runs = match rest {
                [] => 3,
                [flag @ "--runs", n] => positive(flag, Some(n))?,
                _ => return Err(format!("unknown options '{}'", rest.join(" "))),
            };
            bench_refine::run(runs)
        }
        ["bench", "optim", rest @ ..] => {
            let iterations = match rest {
                [] => 10,
                [flag @ "--global-iterations", n] => positive(flag, Some(n))?,
                _ => return Err(format!("unknown options '{}'", rest.join(" "))),
            };
            bench_optim::run(iterations)
        }
        ["bench", "pipeline", rest @ ..] => {
            let (mut side, mut readme, mut rest) = (4096, false, rest);
            loop {
                match rest {
                    [] => break,
                    ["--readme", more @ ..] => (readme, rest) = (true, more),
                    [flag @ "--scaling-max", n, more @ ..] => {
                        (side, rest) = (positive(flag, Some(n))?, more);
                    }
                    _ => return Err(format!("unknown options '{}'", rest.join(" "))),
                }
            }
            bench_pipeline::run(side, readme)
        }
        ["bench", "random", rest @ ..] => {
            let (mut count, mut seed, mut rest) = (150, 52, rest);
            let mut images = None;
            let mut options = imesh::MeshOptions::default();
            loop {
                match rest {
                    [] => break,
                    [flag @ "--count", n, more @ ..] => {
                        (count, rest) = (positive(flag, Some(n))?, more);
                    }
                    ["--seed", n, more @ ..] => {
                        seed = n
                            .parse()
                            .map_err(|_| format!("--seed takes an integer, not '{n}'"))?;
                        rest = more;
                    }
                    ["--size", size, more @ ..] => (options.size, rest) = (size.parse()?, more),
                    ["--optimizer", method, more @ ..] => {
                        (options.optimizer, rest) = (method.parse()?, more);
                    }
                    ["--corner-reach", share, more @ ..] => {
                        options.corner_reach = share.parse().map_err(|_| {
                            format!("--corner-reach takes a share of the quad side, not '{share}'")
                        })?;
                        rest = more;
                    }
                    ["--images", dir, more @ ..] => {
                        (images, rest) = (Some(std::path::PathBuf::from(dir)), more);
                    }
                    _ => return Err(format!("unknown options '{}'", rest.join(" "))),
                }
            }
            bench_random::run(count, seed, &options, images.as_deref())
        }
        ["compare", "gmsh", rest @ ..] => {
            let mut options = imesh::MeshOptions::default();
            let mut fixtures = compare_gmsh::Fixtures::Default;
            let mut rest = rest;
            loop {
                match rest {
                    [] => break,
                    ["--size", size, more @ ..] => (options.size, rest) = (size.parse()?, more),
                    ["--fixtures", list, more @ ..] => (fixtures, rest) = (list.parse()?, more),
                    _ => return Err(format!("unknown options '{}'", rest.join(" "))),
                }
            }
            compare_gmsh::run(options, &fixtures)
        }
        ["fixtures", "quality"] => fixtures::quality(),
        ["fixtures", "points"] => fixtures::points(),
        ["fixtures"] => fixtures::all(),
        ["fuzz", rest @ ..] => {
            let mut options = fuzz::Options {
                targets: Vec::new(),
                seconds: 600,
            };
            let mut it = rest.iter();
            while let Some(&word) = it.next() {
                match word {
                    "--seconds" => options.seconds = positive(word, it.next())?,
                    target if !target.starts_with('-') => options.targets.push(target.into()),
                    other => return Err(format!("unknown option '{other}'")),
                }
            }
            fuzz::run(&options)
        }
        [] | ["help"] | ["--help"] | ["-h"] => {
            println!("{USAGE}");
            Ok(())
        }
        _ => Err(format!("unknown command '{}'", words.join(" "))),
    }
}

/// The positive integer after option `flag`.
fn positive<T: std::str::FromStr + Default + PartialOrd>(
    flag: &str,
    value: Option<&&str>,
) -> Result<T, String> {
    let n = value.ok_or_else(|| format!("{flag} needs a number"))?;
    n.parse()
        .ok()
        .filter(|r| *r > T::default())
        .ok_or_else(|| format!("{flag} takes a positive integer, not '{n}'"))
}

/// `target/bench/` of the workspace (created if needed).
pub fn bench_dir() -> Result<std::path::PathBuf, String> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("xtask is not inside the workspace")?
        .to_path_buf();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let dir = target.join("bench");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}
