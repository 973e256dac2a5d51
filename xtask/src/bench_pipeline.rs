//! `cargo xtask bench pipeline`: the whole image → quad mesh run on every fixture, in the shape of
//! the paper's Table I (counts, seconds per stage, quality), the paper's Figure 8 experiment (one
//! image at three densities, its Table II), and the scaling of one image from 256² to 4096²
//! (seconds and peak heap per stage). Writes Markdown and JSON under `target/bench/`.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use imesh::{MeshOptions, Pipeline, PipelineResult, Stage};
use imesh_quality::QuadHistograms;
use serde::Serialize;

use crate::alloc;
use crate::fixtures::{fixture_images, fixtures_dir};

/// One run: counts, seconds per stage, peak heap per stage, quality.
#[derive(Serialize)]
struct Row {
    name: String,
    width: u32,
    height: u32,
    /// Pixels per side of the meshed grid's cells (1: no reduction).
    reduction: u32,
    vertices: usize,
    quads: usize,
    seconds: Seconds,
    /// Peak live heap bytes during each stage, by stage name.
    peak_bytes: Vec<(String, usize)>,
    shape_and_size: [f64; 3],
    shape: [f64; 2],
    scaled_jacobian: [f64; 2],
    label_agreement: f64,
    unpaired_share: f64,
    /// Quads whose shape-and-size is under the paper's worst value (0.25, issue 8's target).
    poor_quads: usize,
}

#[derive(Serialize)]
struct Seconds {
    classify: f64,
    sample: f64,
    curves: f64,
    dt: f64,
    pairing_templates: f64,
    adaptation: f64,
    optimise: f64,
    write: f64,
    total: f64,
}

/// A fixture image, as the pipeline would load it.
fn load(path: &Path) -> Result<image::DynamicImage, String> {
    imesh_classify::load_image(path, imesh_classify::DEFAULT_MAX_PIXELS)
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Runs the pipeline on `image`, recording the heap peak of each stage, then writes the mesh
/// as MSH 4.1 (timed: the paper's "write" column).
fn measure(name: &str, image: &image::DynamicImage, options: &MeshOptions) -> Result<Row, String> {
    let peaks: Arc<Mutex<Vec<(Stage, usize)>>> = Arc::new(Mutex::new(Vec::new()));
    let log = Arc::clone(&peaks);
    let base = alloc::live();
    alloc::take_peak();
    let clock = Instant::now();
    let result: PipelineResult = Pipeline::new(options.clone())
        .with_progress(move |stage| {
            // The peak since the previous stage began belongs to that stage.
            let peak = alloc::take_peak().saturating_sub(base);
            if let Ok(mut log) = log.lock() {
                log.push((stage, peak));
            }
        })
        .run_image(image)
        .map_err(|e| format!("{name}: {e}"))?;
    let last_peak = alloc::take_peak().saturating_sub(base);
    let dir = tempdir()?;
    let path = dir.join(format!(
        "{}.msh",
        name.replace(|c: char| !c.is_alphanumeric(), "_")
    ));
    let write = Instant::now();
    imesh_io::write_msh(&path, &result.mesh, &imesh_io::Frame::default())
        .map_err(|e| format!("{name}: {e}"))?;
    let write = write.elapsed().as_secs_f64();
    let total = clock.elapsed().as_secs_f64();
    let _ = std::fs::remove_file(&path);
    let stages = peaks.lock().map_err(|_| "poisoned")?;
    // Stage k's peak was read when stage k + 1 began; the last one's at the end.
    let peak_bytes: Vec<(String, usize)> = stages
        .iter()
        .enumerate()
        .map(|(k, (stage, _))| {
            let peak = stages.get(k + 1).map_or(last_peak, |s| s.1);
            (format!("{stage:?}").to_lowercase(), peak)
        })
        .collect();
    let r = &result.report;
    let s = &r.seconds;
    let q = &r.quality;
    let sas = q.shape_and_size().ok_or("no quad quality")?;
    Ok(Row {
        name: name.to_string(),
        width: r.counts.width,
        height: r.counts.height,
        reduction: r.counts.reduction,
        vertices: r.counts.vertices,
        quads: r.counts.quads,
        seconds: Seconds {
            classify: s.classify,
            sample: s.sample,
            curves: s.curves,
            dt: s.triangulate,
            pairing_templates: s.pairing + s.templates,
            adaptation: s.adapt,
            optimise: s.optimise,
            write,
            total,
        },
        peak_bytes,
        shape_and_size: [sas.min, sas.mean, sas.variance],
        shape: [q.shape().min, q.shape().mean],
        scaled_jacobian: [q.scaled_jacobian().min, q.scaled_jacobian().mean],
        label_agreement: r.label_agreement,
        unpaired_share: r.counts.unpaired_triangles as f64 / r.counts.dt_triangles.max(1) as f64,
        poor_quads: under_a_quarter(
            &r.histograms
                .as_ref()
                .ok_or("no quality histograms")?
                .shape_and_size_after,
        )?,
    })
}

/// The values under 0.25 in `histogram`, which must be the report's bins over [0, 1]
/// ([`QuadHistograms::BINS`]): its first quarter.
fn under_a_quarter(histogram: &imesh_quality::Histogram) -> Result<usize, String> {
    const BINS: usize = QuadHistograms::BINS;
    // 0.25 is a bin edge.
    const _: () = assert!(BINS.is_multiple_of(4));
    if histogram.counts.len() != BINS || histogram.lo != 0.0 || histogram.hi != 1.0 {
        return Err(format!(
            "the shape-and-size histogram is not {BINS} bins over [0, 1]"
        ));
    }
    Ok(histogram.counts[..BINS / 4].iter().sum())
}

fn tempdir() -> Result<PathBuf, String> {
    let dir = crate::bench_dir()?.join("pipeline-meshes");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}

const HEADER: &str = "| image | size | vertices | quads | classify | sample | curves | DT' | pairing + templates | adaptation | optimisation | write | total s | S&S worst / mean / var | S&S < 0.25 | shape worst / mean | SJ worst / mean | label agreement | unpaired |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";

fn line(r: &Row) -> String {
    let s = &r.seconds;
    format!(
        "| {} | {} × {}{} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {:.3} / {:.3} / {:.3} | {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.1} % | {:.1} % |",
        r.name,
        r.width,
        r.height,
        if r.reduction > 1 {
            format!(" (cells of {} px)", r.reduction)
        } else {
            String::new()
        },
        r.vertices,
        r.quads,
        s.classify,
        s.sample,
        s.curves,
        s.dt,
        s.pairing_templates,
        s.adaptation,
        s.optimise,
        s.write,
        s.total,
        r.shape_and_size[0],
        r.shape_and_size[1],
        r.shape_and_size[2],
        r.poor_quads,
        r.shape[0],
        r.shape[1],
        r.scaled_jacobian[0],
        r.scaled_jacobian[1],
        100.0 * r.label_agreement,
        100.0 * r.unpaired_share,
    )
}

/// The paper's Figure 8 densities (about 1.2 K, 5 K and 10 K quads) on the MRI fixture: the
/// default (uniform, its size chosen from the image) and two larger quad sizes.
fn densities() -> [(&'static str, MeshOptions); 3] {
    let size = |px: f64| MeshOptions {
        size: imesh::ElementSize::Pixels(px),
        ..MeshOptions::default()
    };
    [
        ("MRI, --size 7.5", size(7.5)),
        ("MRI, --size 3.6", size(3.6)),
        ("MRI, default", MeshOptions::default()),
    ]
}

/// The options of the last fixture table: the default clean-up without the automatic size, at
/// quads 3 px wide on every image.
fn uniform() -> MeshOptions {
    MeshOptions {
        size: imesh::ElementSize::Pixels(3.0),
        ..MeshOptions::default()
    }
}

/// Where `--readme` puts the tables in README.md.
const README_BEGIN: &str = "<!-- cargo xtask bench pipeline --readme: begin -->";
const README_END: &str = "<!-- cargo xtask bench pipeline --readme: end -->";

/// `text` (the README) with the text between its markers replaced by `tables`.
fn fill_block(text: &str, tables: &str) -> Result<String, String> {
    let (Some(begin), Some(end)) = (text.find(README_BEGIN), text.find(README_END)) else {
        return Err(format!(
            "README.md has no '{README_BEGIN}' … '{README_END}' block to fill"
        ));
    };
    if end < begin {
        return Err("README.md's bench markers are in the wrong order".into());
    }
    Ok(format!(
        "{}{README_BEGIN}\n{}\n{}",
        &text[..begin],
        tables.trim(),
        &text[end..]
    ))
}

/// Replaces the README's results block by `tables`, whole or not at all (a temporary file
/// renamed over it).
fn write_readme(tables: &str) -> Result<(), String> {
    let path = fixtures_dir().join("../../README.md");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read README.md: {e}"))?;
    let updated = fill_block(&text, tables)?;
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, updated).map_err(|e| format!("cannot write README.md: {e}"))?;
    std::fs::rename(&tmp, &path).map_err(|e| format!("cannot replace README.md: {e}"))?;
    println!("README.md: results section regenerated");
    Ok(())
}

/// Runs the experiments; `scaling_max` is the largest side of the scaling series; `readme`
/// also writes the tables into README.md's results section.
pub fn run(scaling_max: u32, readme: bool) -> Result<(), String> {
    let mut markdown = String::new();
    let mut table = |title: &str, rows: &[Row]| {
        let text = format!(
            "\n### {title}\n\n{HEADER}\n{}\n",
            rows.iter().map(line).collect::<Vec<_>>().join("\n")
        );
        println!("{text}");
        markdown.push_str(&text);
    };

    let paths = fixture_images()?;
    let (mut fixtures, mut graded_fixtures, mut uniform_fixtures) =
        (Vec::new(), Vec::new(), Vec::new());
    let graded = MeshOptions {
        size: imesh::ElementSize::Graded,
        ..MeshOptions::default()
    };
    for path in &paths {
        let image = load(path)?;
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        fixtures.push(measure(&name, &image, &MeshOptions::default())?);
        graded_fixtures.push(measure(&name, &image, &graded)?);
        uniform_fixtures.push(measure(&name, &image, &uniform())?);
    }
    table(
        "Every fixture, default options (`--size auto`; the paper's Table I)",
        &fixtures,
    );
    table(
        "Every fixture, the paper's graded size: --size graded",
        &graded_fixtures,
    );
    table(
        "Every fixture, one quad size for all: --size 3",
        &uniform_fixtures,
    );

    let mri = load(&fixtures_dir().join("matplotlib-s1045_mri.png"))?;
    let mut density = Vec::new();
    for (name, options) in densities() {
        density.push(measure(name, &mri, &options)?);
    }
    table(
        "One image at three densities (the paper's Figure 8 / Table II: 17.2 s, 53.5 s, 128.8 s)",
        &density,
    );

    let camera = load(&fixtures_dir().join("skimage-camera.png"))?;
    let mut scaling = Vec::new();
    let mut side = 256;
    while side <= scaling_max {
        let resized = camera.resize_exact(side, side, image::imageops::FilterType::Triangle);
        scaling.push(measure(
            &format!("camera {side}²"),
            &resized,
            &MeshOptions::default(),
        )?);
        // Where the default reduces the image, the same run on its pixels.
        if scaling.last().is_some_and(|r| r.reduction > 1) {
            let pixels = MeshOptions {
                reduction: Some(1),
                ..MeshOptions::default()
            };
            let name = format!("camera {side}², --reduction 1");
            scaling.push(measure(&name, &resized, &pixels)?);
        }
        side *= 2;
    }
    table("Scaling: the camera fixture resized (seconds)", &scaling);
    let mut memory = format!(
        "\n### Scaling: peak heap per stage (MB)\n\n| image | {} |\n|---|{}\n",
        scaling
            .first()
            .map(|r| r
                .peak_bytes
                .iter()
                .map(|(s, _)| s.as_str())
                .collect::<Vec<_>>()
                .join(" | "))
            .unwrap_or_default(),
        "---|".repeat(scaling.first().map_or(0, |r| r.peak_bytes.len()))
    );
    for r in &scaling {
        let cells: Vec<String> = r
            .peak_bytes
            .iter()
            .map(|(_, b)| format!("{:.1}", *b as f64 / 1e6))
            .collect();
        memory.push_str(&format!("| {} | {} |\n", r.name, cells.join(" | ")));
    }
    println!("{memory}");
    markdown.push_str(&memory);

    let dir = crate::bench_dir()?;
    let json = serde_json::json!({
        "fixtures": fixtures,
        "graded": graded_fixtures,
        "uniform": uniform_fixtures,
        "densities": density,
        "scaling": scaling,
    });
    std::fs::write(
        dir.join("pipeline.json"),
        serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?,
    )
    .map_err(|e| format!("cannot write pipeline.json: {e}"))?;
    std::fs::write(dir.join("pipeline.md"), &markdown)
        .map_err(|e| format!("cannot write pipeline.md: {e}"))?;
    println!("written: {0}/pipeline.md, {0}/pipeline.json", dir.display());
    if readme {
        write_readme(&markdown)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count under 0.25 takes the values under it only, and wants the report's bins.
    #[test]
    fn quads_under_a_quarter_are_counted_from_the_histogram() {
        let values = [0.0, 0.1, 0.2499, 0.25, 0.3, 0.9, 1.0];
        let h = imesh_quality::Histogram::of(&values, 0.0, 1.0, 20);
        assert_eq!(under_a_quarter(&h), Ok(3));
        let other = imesh_quality::Histogram::of(&values, 0.0, 1.0, 10);
        assert!(under_a_quarter(&other).is_err());
    }

    #[test]
    fn the_readme_block_is_replaced_and_the_rest_kept() {
        let text = format!("# T\n\nbefore\n{README_BEGIN}\nold table\n{README_END}\nafter\n");
        let filled = fill_block(&text, "\n| new |\n").unwrap();
        assert_eq!(
            filled,
            format!("# T\n\nbefore\n{README_BEGIN}\n| new |\n{README_END}\nafter\n")
        );
        // Filling again gives the same text: the block is found by its markers, not its contents.
        assert_eq!(fill_block(&filled, "| new |").unwrap(), filled);
        assert!(fill_block("no markers", "x").is_err());
        let swapped = format!("{README_END}\n{README_BEGIN}");
        assert!(fill_block(&swapped, "x").is_err());
    }
}
