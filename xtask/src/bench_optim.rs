//! `cargo xtask bench optim`: the quad optimisers side by side on the fixtures, through the
//! whole pipeline (same image, same options but `--optimizer`): worst and mean quality after
//! `none`, `laplacian`, `vertex`, `local` and (on the small fixtures) `global`, with the
//! optimiser's seconds.

use imesh::{MeshOptions, OptimizerMethod, Pipeline};
use serde::Serialize;

/// Fixtures of the comparison; `true` where the global mode runs too (the two of about 10 000
/// quads: it takes a minute each).
const FIXTURES: [(&str, bool); 6] = [
    ("matplotlib-s1045_mri.png", true),
    ("stardist-mask2d_labels.png", false),
    ("skimage-camera.png", true),
    ("skimage-coins.png", false),
    ("pyvista-channels_z050_labels.png", false),
    ("skimage-gravel.png", false),
];

#[derive(Serialize)]
struct Row {
    fixture: String,
    method: String,
    quads: usize,
    energy_before: f64,
    energy_after: f64,
    shape_and_size_min: f64,
    shape_and_size_mean: f64,
    shape_min: f64,
    shape_mean: f64,
    scaled_jacobian_min: f64,
    scaled_jacobian_mean: f64,
    sweeps: usize,
    optimise_seconds: f64,
    total_seconds: f64,
}

/// Runs the comparison; the global mode gets `global_iterations` Powell iterations.
pub fn run(global_iterations: u64) -> Result<(), String> {
    let mut rows = Vec::new();
    println!("| fixture | method | quads | S&S worst / mean | shape worst / mean | SJ worst / mean | energy | sweeps | optimise s |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for (file, small) in FIXTURES {
        let path = crate::fixtures::fixtures_dir().join(file);
        let mut methods = vec![
            OptimizerMethod::None,
            OptimizerMethod::Laplacian,
            OptimizerMethod::Vertex,
            OptimizerMethod::Local,
        ];
        if small {
            methods.push(OptimizerMethod::Global);
        }
        for method in methods {
            let options = MeshOptions {
                optimizer: method,
                global_iterations,
                ..MeshOptions::default()
            };
            let result = Pipeline::new(options)
                .run_path(&path)
                .map_err(|e| format!("{file}: {e}"))?;
            let r = &result.report;
            let q = &r.quality;
            let o = r.optimisation.as_ref().ok_or("no optimisation report")?;
            let sas = q.shape_and_size().ok_or("no quad quality")?;
            let row = Row {
                fixture: file.to_string(),
                method: format!("{method:?}").to_lowercase(),
                quads: r.counts.quads,
                energy_before: o.energy_before,
                energy_after: o.energy_after,
                shape_and_size_min: sas.min,
                shape_and_size_mean: sas.mean,
                shape_min: q.shape().min,
                shape_mean: q.shape().mean,
                scaled_jacobian_min: q.scaled_jacobian().min,
                scaled_jacobian_mean: q.scaled_jacobian().mean,
                sweeps: o.sweeps,
                optimise_seconds: r.seconds.optimise,
                total_seconds: r.seconds.total,
            };
            println!(
                "| {} | {} | {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.3} / {:.3} | {:.0} → {:.0} | {} | {:.3} |",
                row.fixture,
                row.method,
                row.quads,
                row.shape_and_size_min,
                row.shape_and_size_mean,
                row.shape_min,
                row.shape_mean,
                row.scaled_jacobian_min,
                row.scaled_jacobian_mean,
                row.energy_before,
                row.energy_after,
                row.sweeps,
                row.optimise_seconds
            );
            rows.push(row);
        }
    }
    let out = crate::bench_dir()?.join("optim.json");
    let text = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
    std::fs::write(&out, text).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    println!("\nwritten {}", out.display());
    Ok(())
}
