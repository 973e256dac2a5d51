//! Classifies an image into a label grid and writes it as a colour PNG.
//!
//! ```text
//! cargo run --release -p imesh-classify --example classify -- IMAGE [--classify SPEC] -o LABELS.png
//!     [--min-region N] [--majority R]
//! ```
//! SPEC: auto (default), labels, otsu, otsu:K, threshold:T1,T2,…, kmeans:K, texture:SAMPLES.toml.

use std::path::PathBuf;
use std::process::ExitCode;

use imesh_classify::{
    classify, load_image, majority_filter, remove_small_regions, Classifier, ClassifyOptions,
    DEFAULT_MAX_PIXELS,
};

const USAGE: &str =
    "usage: classify IMAGE [--classify SPEC] -o LABELS.png [--min-region N] [--majority R]";

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
    let mut args = std::env::args().skip(1);
    let (mut input, mut output, mut spec) = (None, None, Classifier::Auto);
    let (mut min_region, mut majority) = (0usize, 0u32);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--classify" => {
                spec = value("--classify")?
                    .parse()
                    .map_err(|e: imesh_classify::ClassifyError| e.to_string())?
            }
            "-o" | "--output" => output = Some(PathBuf::from(value("-o")?)),
            "--min-region" => {
                min_region = value("--min-region")?
                    .parse()
                    .map_err(|_| "--min-region takes a pixel count")?
            }
            "--majority" => {
                majority = value("--majority")?
                    .parse()
                    .map_err(|_| "--majority takes a radius in pixels")?
            }
            other if !other.starts_with('-') && input.is_none() => {
                input = Some(PathBuf::from(other))
            }
            other => return Err(format!("unexpected argument '{other}'")),
        }
    }
    let input = input.ok_or("give an image")?;
    let output = output.ok_or("give the output file with -o LABELS.png")?;
    let image = load_image(&input, DEFAULT_MAX_PIXELS).map_err(|e| e.to_string())?;
    let mut grid =
        classify(&image, &spec, &ClassifyOptions::default()).map_err(|e| e.to_string())?;
    if majority > 0 {
        grid = majority_filter(&grid, majority, 1);
    }
    if min_region > 1 {
        grid = remove_small_regions(&grid, min_region);
    }
    grid.save_png(&output).map_err(|e| e.to_string())?;
    println!(
        "{}×{} pixels, {} labels -> {}",
        grid.width(),
        grid.height(),
        grid.num_labels(),
        output.display()
    );
    for (region, count) in grid.regions().iter().zip(grid.counts()) {
        println!(
            "  {:<20} {:>9} px  #{:02x}{:02x}{:02x}",
            region.name, count, region.colour[0], region.colour[1], region.colour[2]
        );
    }
    Ok(())
}
