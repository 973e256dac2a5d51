//! `cargo xtask bench random`: the defaults on a reproducible set of random label images, the
//! measure a change of the pipeline is judged by where one image's worst quads move by chance.
//!
//! A third of the images are Voronoi diagrams (4–40 cells in 3–6 labels: junctions, straight
//! boundaries at every angle), a third smoothed noise cut at 2–4 quantiles (curved boundaries,
//! necks, thin strips), the rest discs and rectangles over a background (corners, touching
//! shapes), each 120–300 px a side, all drawn from one seed. For each image: the mean and the
//! worst shape-and-size, the quads under 0.25 in it, and the quads under 0.5 in shape and in
//! scaled Jacobian. Written to `target/bench/random.json` with the sums, which are what to
//! compare: the worst quads of one image move when anything changes (renumbering one mesh's
//! triangles moved the count under 0.5 in shape by about 7 over 150 images).

use std::path::Path;
use std::time::Instant;

use image::{DynamicImage, GrayImage, Luma};
use imesh::{MeshOptions, Pipeline};
use imesh_quality::quad::{scaled_jacobian, shape, shape_and_size};
use rand_chacha::rand_core::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// One image's figures.
#[derive(Serialize)]
struct Row {
    name: String,
    width: u32,
    height: u32,
    quads: usize,
    mean: f64,
    worst: f64,
    under_a_quarter: usize,
    shape_under_half: usize,
    jacobian_under_half: usize,
    /// The share of the image's area whose label the mesh keeps (the report's).
    label_agreement: f64,
    seconds: f64,
}

/// The sums over the set.
#[derive(Serialize)]
struct Summary {
    images: usize,
    seed: u64,
    mean_of_means: f64,
    mean_of_worst: f64,
    /// The mean of the images' label agreements: what the clean-ups give away for quality.
    mean_label_agreement: f64,
    quads: usize,
    under_a_quarter: usize,
    shape_under_half: usize,
    jacobian_under_half: usize,
    seconds: f64,
}

/// Meshes `count` random images drawn from `seed` with `options` (the defaults, or another
/// optimiser) and writes the figures; with `images`, also each image as a PNG in that folder.
pub fn run(
    count: usize,
    seed: u64,
    options: &MeshOptions,
    images: Option<&Path>,
) -> Result<(), String> {
    if let Some(dir) = images {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rows = Vec::with_capacity(count);
    for i in 0..count {
        let (kind, image) = match i % 3 {
            0 => ("voronoi", voronoi(&mut rng)),
            1 => ("noise", smoothed_noise(&mut rng)),
            _ => ("shapes", shapes(&mut rng)),
        };
        let name = format!("{i:03}-{kind}");
        if let Some(dir) = images {
            let path = dir.join(format!("{name}.png"));
            image
                .save(&path)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        let row = measure(&name, image, options)?;
        eprintln!(
            "{name}: {} quads, mean {:.4}, worst {:.4}",
            row.quads, row.mean, row.worst
        );
        rows.push(row);
    }
    let n = rows.len().max(1) as f64;
    let summary = Summary {
        images: rows.len(),
        seed,
        mean_of_means: rows.iter().map(|r| r.mean).sum::<f64>() / n,
        mean_of_worst: rows.iter().map(|r| r.worst).sum::<f64>() / n,
        mean_label_agreement: rows.iter().map(|r| r.label_agreement).sum::<f64>() / n,
        quads: rows.iter().map(|r| r.quads).sum(),
        under_a_quarter: rows.iter().map(|r| r.under_a_quarter).sum(),
        shape_under_half: rows.iter().map(|r| r.shape_under_half).sum(),
        jacobian_under_half: rows.iter().map(|r| r.jacobian_under_half).sum(),
        seconds: rows.iter().map(|r| r.seconds).sum(),
    };
    println!(
        "{} random images (seed {seed}): mean of means {:.5}, mean of worst {:.4}, quads {}, \
         under 0.25 {}, under 0.5 in shape {} and in scaled Jacobian {}, {:.1} s",
        summary.images,
        summary.mean_of_means,
        summary.mean_of_worst,
        summary.quads,
        summary.under_a_quarter,
        summary.shape_under_half,
        summary.jacobian_under_half,
        summary.seconds
    );
    let path = crate::bench_dir()?.join("random.json");
    let json = serde_json::to_string_pretty(&serde_json::json!({
        "summary": summary,
        "images": rows,
    }))
    .map_err(|e| e.to_string())?;
    std::fs::write(&path, json).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    println!("written: {}", path.display());
    Ok(())
}

/// The pipeline with `options` on `image`, its quads measured as the report measures them.
fn measure(name: &str, image: GrayImage, options: &MeshOptions) -> Result<Row, String> {
    let (width, height) = image.dimensions();
    let clock = Instant::now();
    let result = Pipeline::new(options.clone())
        .run_image(&DynamicImage::ImageLuma8(image))
        .map_err(|e| format!("{name}: {e}"))?;
    let seconds = clock.elapsed().as_secs_f64();
    let mesh = &result.mesh;
    let quads: Vec<[[f64; 2]; 4]> = mesh
        .elements
        .iter()
        .filter_map(|e| match e {
            imesh_quality::Element::Quad(q) => Some(q.map(|v| mesh.vertices[v as usize])),
            imesh_quality::Element::Triangle(_) => None,
        })
        .collect();
    if !result.report.validation.valid || quads.is_empty() {
        return Err(format!("{name}: no valid quad mesh"));
    }
    let average = quads.iter().map(imesh_quality::quad::area).sum::<f64>() / quads.len() as f64;
    let scores: Vec<f64> = quads.iter().map(|q| shape_and_size(q, average)).collect();
    Ok(Row {
        name: name.to_string(),
        width,
        height,
        quads: quads.len(),
        mean: scores.iter().sum::<f64>() / scores.len() as f64,
        worst: scores.iter().copied().fold(f64::INFINITY, f64::min),
        under_a_quarter: scores.iter().filter(|&&s| s < 0.25).count(),
        // A hair under 0.5: the repairs hold corners at 0.5 to within rounding.
        shape_under_half: quads.iter().filter(|q| shape(q) < 0.5 - 1e-9).count(),
        jacobian_under_half: quads
            .iter()
            .filter(|q| scaled_jacobian(q) < 0.5 - 1e-9)
            .count(),
        label_agreement: result.report.label_agreement,
        seconds,
    })
}

/// A uniform number in `[0, 1)`.
fn unit(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A uniform integer in `lo..hi`.
fn between(rng: &mut ChaCha8Rng, lo: u32, hi: u32) -> u32 {
    lo + (unit(rng) * f64::from(hi - lo)) as u32
}

/// An image 120–300 px a side, each pixel's grey from `label(x, y)` (labels spread over 0–255).
fn labelled(
    rng: &mut ChaCha8Rng,
    labels: u32,
    mut label: impl FnMut(u32, u32) -> u32,
) -> GrayImage {
    let (w, h) = (between(rng, 120, 300), between(rng, 120, 300));
    let step = 255 / (labels - 1).max(1);
    GrayImage::from_fn(w, h, |x, y| Luma([(label(x, y) * step).min(255) as u8]))
}

/// Voronoi cells of 4–40 random sites, in 3–6 labels.
fn voronoi(rng: &mut ChaCha8Rng) -> GrayImage {
    let sites: Vec<(f64, f64)> = (0..between(rng, 4, 40))
        .map(|_| (unit(rng) * 300.0, unit(rng) * 300.0))
        .collect();
    let labels = between(rng, 3, 7);
    labelled(rng, labels, |x, y| {
        let d = |&(sx, sy): &(f64, f64)| (f64::from(x) - sx).powi(2) + (f64::from(y) - sy).powi(2);
        let nearest = (0..sites.len())
            .min_by(|&a, &b| d(&sites[a]).total_cmp(&d(&sites[b])))
            .unwrap_or(0);
        nearest as u32 % labels
    })
}

/// White noise blurred by three box passes of radius 3–12, cut at 2–4 quantiles.
fn smoothed_noise(rng: &mut ChaCha8Rng) -> GrayImage {
    let (w, h) = (
        between(rng, 120, 300) as usize,
        between(rng, 120, 300) as usize,
    );
    let mut field: Vec<f64> = (0..w * h).map(|_| unit(rng)).collect();
    let radius = between(rng, 3, 13) as usize;
    for _ in 0..3 {
        box_blur(&mut field, w, h, radius);
    }
    let levels = between(rng, 2, 5);
    let mut sorted = field.clone();
    sorted.sort_by(f64::total_cmp);
    let cuts: Vec<f64> = (1..levels)
        .map(|k| sorted[k as usize * sorted.len() / levels as usize])
        .collect();
    let step = 255 / (levels - 1);
    GrayImage::from_fn(w as u32, h as u32, |x, y| {
        let v = field[y as usize * w + x as usize];
        let label = cuts.iter().filter(|&&c| v >= c).count() as u32;
        Luma([(label * step).min(255) as u8])
    })
}

/// Averages `field` (`w × h`, row by row) over a `2 radius + 1` window along the rows, then the
/// columns (clamped at the borders).
fn box_blur(field: &mut [f64], w: usize, h: usize, radius: usize) {
    let mut line = Vec::new();
    for (len, stride, count, step) in [(w, 1, h, w), (h, w, w, 1)] {
        for i in 0..count {
            let at = |k: usize| i * step + k * stride;
            line.clear();
            line.extend((0..len).map(|k| field[at(k)]));
            for k in 0..len {
                let (lo, hi) = (k.saturating_sub(radius), (k + radius).min(len - 1));
                field[at(k)] = line[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
            }
        }
    }
}

/// 3–14 discs (radius 4–40) and rectangles (half-sides 3–50) in labels 1–4 over label 0, later
/// shapes over earlier ones.
fn shapes(rng: &mut ChaCha8Rng) -> GrayImage {
    let shapes: Vec<(bool, f64, f64, f64, f64, u32)> = (0..between(rng, 3, 15))
        .map(|_| {
            let disc = unit(rng) < 0.5;
            let (cx, cy) = (unit(rng) * 300.0, unit(rng) * 300.0);
            let (a, b) = if disc {
                let r = 4.0 + 36.0 * unit(rng);
                (r, r)
            } else {
                (3.0 + 47.0 * unit(rng), 3.0 + 47.0 * unit(rng))
            };
            (disc, cx, cy, a, b, between(rng, 1, 5))
        })
        .collect();
    labelled(rng, 5, |x, y| {
        let (x, y) = (f64::from(x), f64::from(y));
        shapes
            .iter()
            .rev()
            .find(|&&(disc, cx, cy, a, b, _)| {
                if disc {
                    (x - cx).powi(2) + (y - cy).powi(2) < a * a
                } else {
                    (x - cx).abs() < a && (y - cy).abs() < b
                }
            })
            .map_or(0, |s| s.5)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One seed gives the same images; each kind has the labels it promises.
    #[test]
    fn the_images_are_reproducible_and_labelled() {
        let draw = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            [
                voronoi(&mut rng),
                smoothed_noise(&mut rng),
                shapes(&mut rng),
            ]
        };
        let (a, b) = (draw(52), draw(52));
        assert!(a.iter().zip(&b).all(|(x, y)| x == y));
        assert!(draw(53)[0] != a[0]);
        for image in &a {
            let (w, h) = image.dimensions();
            assert!((120..300).contains(&w) && (120..300).contains(&h));
            let mut greys: Vec<u8> = image.pixels().map(|p| p.0[0]).collect();
            greys.sort_unstable();
            greys.dedup();
            assert!((2..=6).contains(&greys.len()), "{} greys", greys.len());
        }
    }

    /// The blur keeps a constant field and the field's sum away from the borders.
    #[test]
    fn the_box_blur_averages() {
        let mut flat = vec![0.5; 30 * 20];
        box_blur(&mut flat, 30, 20, 4);
        assert!(flat.iter().all(|&v| (v - 0.5).abs() < 1e-12));
        let mut spike = vec![0.0; 31 * 31];
        spike[15 * 31 + 15] = 1.0;
        box_blur(&mut spike, 31, 31, 2);
        assert!((spike.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((spike[15 * 31 + 15] - 1.0 / 25.0).abs() < 1e-12);
    }
}
