//! Parameter sweeps (issue 11): over t_e, curve tolerance, smallest angle, largest size, template
//! level, pairing, optimiser and element kind, on crops of every fixture's label grid, the same
//! invariants hold for every combination: a valid mesh (conforming, no inverted element, exact
//! area, one known label per element).

mod support;

use std::str::FromStr;
use std::sync::OnceLock;

use imesh::{ElementSize, Elements, MeshOptions, OptimizerMethod, PairingMethod, Pipeline};
use imesh_classify::{classify, Classifier, ClassifyOptions, LabelGrid};
use proptest::prelude::*;

/// Every fixture's label grid, as the default classifier sees it.
fn grids() -> &'static [(String, LabelGrid)] {
    static GRIDS: OnceLock<Vec<(String, LabelGrid)>> = OnceLock::new();
    GRIDS.get_or_init(|| {
        support::fixtures()
            .into_iter()
            .map(|path| {
                let image =
                    imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS).unwrap();
                let grid = classify(
                    &image,
                    &Classifier::from_str("auto").unwrap(),
                    &ClassifyOptions::default(),
                )
                .unwrap();
                (
                    path.file_name().unwrap().to_string_lossy().into_owned(),
                    grid,
                )
            })
            .collect()
    })
}

/// The `w × h` crop of `grid` at `(x, y)` (fractions of the free range).
fn crop(grid: &LabelGrid, fx: f64, fy: f64, w: u32, h: u32) -> LabelGrid {
    let (w, h) = (w.min(grid.width()), h.min(grid.height()));
    let x0 = (fx * f64::from(grid.width() - w)) as u32;
    let y0 = (fy * f64::from(grid.height() - h)) as u32;
    let labels = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| grid.label(x0 + c, y0 + r))
        .collect();
    LabelGrid::new(w, h, labels, grid.regions().to_vec()).expect("a crop of a valid grid")
}

fn options() -> impl Strategy<Value = MeshOptions> {
    (
        prop::sample::select(vec![0.05, 0.1, 0.3, 0.6]),
        0.0..15.0f64,
        prop::option::of(10.0..33.0f64),
        prop::option::of(2.0..24.0f64),
        1u32..=3,
        prop::sample::select(vec![
            PairingMethod::Matching,
            PairingMethod::Fewest,
            PairingMethod::Greedy,
        ]),
        prop::sample::select(vec![
            OptimizerMethod::Local,
            OptimizerMethod::Global,
            OptimizerMethod::Laplacian,
            OptimizerMethod::Vertex,
            OptimizerMethod::None,
        ]),
        prop::sample::select(vec![Elements::Quad, Elements::Quad, Elements::Tri]),
        prop::sample::select(vec![
            ElementSize::Graded,
            ElementSize::Auto,
            ElementSize::Pixels(1.0),
            ElementSize::Pixels(4.0),
        ]),
        prop::sample::select(vec![
            (0usize, None),
            (0, Some(0u32)),
            (30, Some(0)),
            (0, Some(2)),
            (20, Some(1)),
        ]),
    )
        .prop_map(
            |(
                te,
                tolerance,
                min_angle,
                max_size,
                level,
                pairing,
                optimizer,
                elements,
                size,
                (min_region, majority),
            )| {
                MeshOptions {
                    size,
                    min_region,
                    majority,
                    te,
                    tolerance: Some(tolerance),
                    min_angle,
                    max_size,
                    template_level: level,
                    pairing,
                    optimizer,
                    global_iterations: 2,
                    elements,
                    ..MeshOptions::default()
                }
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn every_combination_gives_a_valid_mesh(
        fixture in 0usize..10,
        (fx, fy) in (0.0..1.0f64, 0.0..1.0f64),
        (w, h) in (24u32..80, 24u32..80),
        options in options(),
    ) {
        let all = grids();
        prop_assert!(all.len() >= 10);
        let (name, grid) = &all[fixture % all.len()];
        let grid = crop(grid, fx, fy, w, h);
        let result = Pipeline::new(options.clone())
            .run_grid(&grid, 0.0)
            .map_err(|e| TestCaseError::fail(format!("{name} {w}×{h}: {e} with {options:?}")))?;
        let r = &result.report;
        prop_assert!(r.validation.valid);
        prop_assert!((r.validation.area_ratio - 1.0).abs() < 1e-9, "area {}", r.validation.area_ratio);
        prop_assert!(r.quality.scaled_jacobian().min > 0.0, "an inverted element");
        prop_assert_eq!(result.mesh.labels.len(), result.mesh.elements.len());
        prop_assert!(result.mesh.labels.iter().all(|&l| (l as usize) < grid.num_labels()));
        match options.elements {
            Elements::Quad => prop_assert_eq!(r.counts.triangles, 0),
            Elements::Tri => prop_assert_eq!(r.counts.quads, 0),
        }
        if let (Elements::Quad, Some(before)) = (options.elements, &r.quality_before_optimisation) {
            // The optimiser never lowers the worst shape.
            prop_assert!(r.quality.shape().min >= before.shape().min - 1e-12);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Reduced grids: whatever the factor and the crop's sizes (divisible or not), the mesh of
    /// the cells lands on the crop's own frame, valid, with the crop's area.
    #[test]
    fn a_reduced_grid_gives_a_valid_mesh_of_the_image(
        fixture in 0usize..10,
        (fx, fy) in (0.0..1.0f64, 0.0..1.0f64),
        (w, h) in (20u32..120, 20u32..120),
        factor in 2u32..6,
        size in prop::sample::select(vec![ElementSize::Auto, ElementSize::Graded, ElementSize::Pixels(3.0)]),
        elements in prop::sample::select(vec![Elements::Quad, Elements::Quad, Elements::Tri]),
    ) {
        let all = grids();
        let (name, grid) = &all[fixture % all.len()];
        let grid = crop(grid, fx, fy, w, h);
        let options = MeshOptions { reduction: Some(factor), size, elements, ..MeshOptions::default() };
        let result = Pipeline::new(options.clone())
            .run_grid(&grid, 0.0)
            .map_err(|e| TestCaseError::fail(format!("{name} {w}×{h}: {e} with {options:?}")))?;
        let r = &result.report;
        let (gw, gh) = (grid.width(), grid.height());
        prop_assert!(r.validation.valid);
        prop_assert!((r.validation.area_ratio - 1.0).abs() < 1e-9, "area {}", r.validation.area_ratio);
        prop_assert!(r.quality.scaled_jacobian().min > 0.0, "an inverted element");
        prop_assert_eq!((result.mesh.width, result.mesh.height), (gw, gh));
        prop_assert_eq!(r.counts.reduction, factor);
        let cells = |n: u32| ((n + factor / 2) / factor).max(1);
        prop_assert_eq!((r.counts.grid_width, r.counts.grid_height), (cells(gw), cells(gh)));
        let inside = |v: &[f64; 2]| (0.0..=f64::from(gw)).contains(&v[0]) && (0.0..=f64::from(gh)).contains(&v[1]);
        prop_assert!(result.mesh.vertices.iter().all(inside));
        // A mesh in the wrong frame (flipped, or offset) agrees with the crop less than with the
        // crop turned half round. A low agreement alone is no sign of it: where the crop's
        // bands are thinner than a cell, the clean-ups keep one or two of them (aloe's corner,
        // 20 × 20 px of twelve bands a pixel or three high, cells of 4 px: one region, 14 %).
        let turned = LabelGrid::new(
            gw,
            gh,
            (0..gh)
                .flat_map(|r| (0..gw).map(move |c| (c, r)))
                .map(|(c, r)| grid.label(gw - 1 - c, gh - 1 - r))
                .collect(),
            grid.regions().to_vec(),
        )
        .expect("the crop turned half round");
        let against_turned = imesh::label_agreement(&result.mesh, &turned);
        prop_assert!(
            r.label_agreement > 0.3 || r.label_agreement >= against_turned - 1e-9,
            "agreement {} against {} with the crop turned",
            r.label_agreement,
            against_turned
        );
    }
}
