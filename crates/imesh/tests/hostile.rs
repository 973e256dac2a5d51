//! Hostile and degenerate inputs (issue 11): every run gives a mesh that passes the validator, or
//! a clear error; never a panic, a hang or an invalid mesh. Each run's faithfulness (label
//! agreement, boundary Hausdorff distance) is printed (`cargo test --test hostile -- --nocapture`).

mod support;

use std::path::Path;

use imesh::{Elements, MeshOptions, Pipeline, PipelineError, PipelineResult};

/// Checks everything the validator promises, and that the report agrees with the mesh.
fn assert_valid(name: &str, result: &PipelineResult) {
    let r = &result.report;
    assert!(r.validation.valid, "{name}: invalid");
    assert!(
        (r.validation.area_ratio - 1.0).abs() < 1e-9,
        "{name}: the elements cover {} of the image",
        r.validation.area_ratio
    );
    assert!(r.counts.elements > 0, "{name}: no elements");
    assert!(
        r.quality.scaled_jacobian().min > 0.0,
        "{name}: an inverted element"
    );
    let m = &result.mesh;
    assert_eq!(m.labels.len(), m.elements.len(), "{name}: one label each");
    assert!(
        m.labels.iter().all(|&l| (l as usize) < m.label_names.len()),
        "{name}: an element with an unknown label"
    );
    assert!((0.0..=1.0).contains(&r.label_agreement), "{name}");
    assert!(r.fidelity.boundary_hausdorff_px.is_finite(), "{name}");
}

/// Writes `image` as a PNG and meshes the file (the loader included), on both element kinds.
/// Returns the lines of the faithfulness table.
fn mesh_file(dir: &Path, name: &str, image: &image::DynamicImage) -> Vec<String> {
    let path = dir.join(format!(
        "{}.png",
        name.replace(|c: char| !c.is_alphanumeric(), "_")
    ));
    image.save(&path).expect("the image is written");
    let mut rows = Vec::new();
    let classify = if name.contains("label map") {
        "labels"
    } else {
        "auto"
    };
    for elements in [Elements::Quad, Elements::Tri] {
        let options = MeshOptions {
            elements,
            classify: classify.into(),
            ..MeshOptions::default()
        };
        let result = Pipeline::new(options)
            .run_path(&path)
            .unwrap_or_else(|e| panic!("{name} ({elements:?}): {e}"));
        assert_valid(name, &result);
        let r = &result.report;
        rows.push(format!(
            "| {name} | {elements:?} | {} × {} | {} | {} | {:.1} % | {:.2} | {:.3} |",
            r.counts.width,
            r.counts.height,
            r.counts.labels,
            r.counts.elements,
            100.0 * r.label_agreement,
            r.fidelity.boundary_hausdorff_px,
            r.quality.scaled_jacobian().min,
        ));
    }
    rows
}

#[test]
fn hostile_images_give_valid_meshes_on_both_paths() {
    let dir = tempfile::tempdir().unwrap();
    let mut table = vec![
        "| image | elements | size | labels | elements | label agreement | Hausdorff px | worst SJ |"
            .to_string(),
        "|---|---|---|---|---|---|---|---|".to_string(),
    ];
    let images = support::hostile_images();
    assert!(images.len() >= 18);
    for (name, image) in &images {
        table.extend(mesh_file(dir.path(), name, image));
    }
    println!("{}", table.join("\n"));
}

#[test]
fn hostile_label_counts_are_read_as_label_maps() {
    let images = support::hostile_images();
    let labels = |name: &str| {
        let (_, image) = images.iter().find(|(n, _)| n.starts_with(name)).unwrap();
        Pipeline::new(MeshOptions {
            classify: "labels".into(),
            ..MeshOptions::default()
        })
        .run_image(image)
        .unwrap()
        .report
        .counts
        .labels
    };
    assert_eq!(labels("64 × 64 noise"), 4096, "every pixel its own label");
    assert_eq!(labels("255 labels"), 255);
    assert_eq!(labels("single label"), 1);
}

#[test]
fn too_many_labels_is_a_clear_error() {
    let images = support::hostile_images();
    let (_, noise) = images
        .iter()
        .find(|(n, _)| n.starts_with("64 × 64 noise"))
        .unwrap();
    let err = Pipeline::new(MeshOptions {
        classify: "labels".into(),
        max_labels: 1000,
        ..MeshOptions::default()
    })
    .run_image(noise)
    .unwrap_err();
    assert!(err.to_string().contains("--max-labels"), "{err}");
}

/// A texture sample file for `image`: two labels, trained on its top-left and bottom-right
/// corners.
fn texture_samples(dir: &Path, width: u32, height: u32) -> String {
    let (w, h) = (width / 4, height / 4);
    let path = dir.join(format!("samples-{width}x{height}.toml"));
    let text = format!(
        "window = 5\nlevels = 8\noffsets = 4\n\n[[label]]\nname = \"a\"\nrectangles = [[0, 0, {w}, {h}]]\n\n[[label]]\nname = \"b\"\nrectangles = [[{}, {}, {w}, {h}]]\n",
        width - w,
        height - h
    );
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// Every fixture under one classifier: a valid mesh, or (a photograph read as a label map) a
/// clear error about labels or size. Photographs read as label maps (hundreds of labels of a
/// few pixels each) are held to 250 000 elements, to check the limit's error without meshing
/// a million quads.
fn fixtures_under(classifier: impl Fn(&Path, u32, u32) -> String) {
    let dir = tempfile::tempdir().unwrap();
    for path in support::fixtures() {
        let image = imesh_classify::load_image(&path, imesh_classify::DEFAULT_MAX_PIXELS).unwrap();
        let spec = classifier(dir.path(), image.width(), image.height());
        let name = format!("{} --classify {spec}", path.display());
        let photo_as_labels = spec == "labels" && !path.display().to_string().contains("labels");
        let options = MeshOptions {
            classify: spec.clone(),
            max_elements: if photo_as_labels {
                250_000
            } else {
                imesh::DEFAULT_MAX_ELEMENTS
            },
            ..MeshOptions::default()
        };
        match Pipeline::new(options).run_path(&path) {
            Ok(result) => {
                assert_valid(&name, &result);
                println!(
                    "{name}: {} quads, {} labels, label agreement {:.3}, Hausdorff {:.2} px",
                    result.report.counts.quads,
                    result.report.counts.labels,
                    result.report.label_agreement,
                    result.report.fidelity.boundary_hausdorff_px
                );
            }
            Err(e @ (PipelineError::Classify(_) | PipelineError::Limit(_))) => {
                assert!(photo_as_labels, "{name}: {e}");
                assert!(
                    e.to_string().contains("--max-labels")
                        || e.to_string().contains("--max-elements"),
                    "{name}: the error says what to do: {e}"
                );
                println!("{name}: refused: {e}");
            }
            Err(e) => panic!("{name}: {e}"),
        }
    }
}

#[test]
fn every_fixture_under_the_threshold_classifiers() {
    for spec in ["auto", "otsu", "otsu:3", "threshold:60,180"] {
        fixtures_under(|_, _, _| spec.to_string());
    }
}

#[test]
fn every_fixture_under_kmeans_and_as_a_label_map() {
    fixtures_under(|_, _, _| "kmeans:3".to_string());
    fixtures_under(|_, _, _| "labels".to_string());
}

#[test]
fn every_fixture_under_the_texture_classifier() {
    fixtures_under(|dir, w, h| format!("texture:{}", texture_samples(dir, w, h)));
}
