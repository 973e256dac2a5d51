//! The default (quad) pipeline on degenerate images: every one gives a valid mesh.

mod support;

use imesh::{ElementSize, Elements, MeshOptions, PairingMethod, Pipeline};
use support::degenerate_images;

#[test]
fn degenerate_images_give_valid_all_quad_meshes() {
    let variants = [
        MeshOptions::default(),
        MeshOptions {
            pairing: PairingMethod::Greedy,
            template_level: 2,
            ..Default::default()
        },
        MeshOptions {
            tolerance: 0.0,
            ..Default::default()
        },
        MeshOptions {
            tolerance: 15.0,
            max_size: Some(3.0),
            ..Default::default()
        },
        MeshOptions {
            size: ElementSize::Pixels(1.5),
            ..Default::default()
        },
        MeshOptions {
            size: ElementSize::Auto,
            min_region: 4,
            majority: Some(1),
            ..Default::default()
        },
    ];
    for (name, picture) in degenerate_images() {
        for options in &variants {
            let result = Pipeline::new(options.clone())
                .run_image(&picture)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let r = &result.report;
            assert!(r.validation.valid, "{name}");
            assert!((r.validation.area_ratio - 1.0).abs() < 1e-9, "{name}");
            assert_eq!(r.counts.triangles, 0, "{name}: all quads");
            assert!(r.counts.quads > 0, "{name}");
            assert!(
                r.quality.scaled_jacobian().min > 0.0,
                "{name}: an inverted quad"
            );
        }
    }
}

#[test]
fn the_triangle_path_stays_available() {
    for (name, picture) in degenerate_images() {
        let options = MeshOptions {
            elements: Elements::Tri,
            ..Default::default()
        };
        let result = Pipeline::new(options)
            .run_image(&picture)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(result.report.validation.valid, "{name}");
        assert_eq!(result.report.counts.quads, 0, "{name}");
    }
}

#[test]
fn every_fixture_gives_a_valid_quad_mesh_and_a_valid_triangle_mesh() {
    let images = support::fixtures();
    assert!(images.len() >= 10, "{images:?}");
    for path in images {
        let quads = Pipeline::new(MeshOptions::default())
            .run_path(&path)
            .unwrap();
        let r = &quads.report;
        // The pipeline refuses to return a mesh that fails the validator; check it said so.
        assert!(r.validation.valid, "{}", path.display());
        assert!(
            (r.validation.area_ratio - 1.0).abs() < 1e-9,
            "{}",
            path.display()
        );
        assert!(
            r.counts.quads > 0 && r.counts.triangles == 0,
            "{}",
            path.display()
        );
        // Against the image's own labels: the default clean-up smooths them over about one
        // quad, which costs most on the pixel noise of a thresholded texture (grass: 0.83).
        assert!(
            r.label_agreement > 0.8,
            "{}: {}",
            path.display(),
            r.label_agreement
        );
        let tri = Pipeline::new(MeshOptions {
            elements: Elements::Tri,
            ..MeshOptions::default()
        })
        .run_path(&path)
        .unwrap();
        let t = &tri.report;
        assert!(t.validation.valid, "{}", path.display());
        assert!(
            t.counts.triangles > 0 && t.counts.quads == 0,
            "{}",
            path.display()
        );
    }
}

/// A uniform size (`--size`) lifts shape-and-size well above the graded DT' on a fixture, and
/// `min_region` merges the small regions away and `majority` smooths the labels first, each
/// saying how many pixels changed.
#[test]
fn a_uniform_size_gives_higher_shape_and_size_than_a_graded_one() {
    let path = support::fixtures()
        .into_iter()
        .find(|p| p.ends_with("matplotlib-s1045_mri.png"))
        .expect("the MRI fixture");
    let run = |options: MeshOptions| Pipeline::new(options).run_path(&path).unwrap().report;
    let graded = run(MeshOptions {
        size: ElementSize::Graded,
        ..Default::default()
    });
    let auto = run(MeshOptions::default());
    // No clean-up at all: the automatic majority filter and region merging off.
    let bare = MeshOptions {
        size: ElementSize::Pixels(3.0),
        majority: Some(0),
        min_width: Some(0.0),
        ..Default::default()
    };
    let uniform = run(bare.clone());
    let cleaned = run(MeshOptions {
        min_region: 50,
        ..bare.clone()
    });
    let smoothed = run(MeshOptions {
        min_region: 50,
        majority: Some(2),
        ..bare
    });
    for r in [&graded, &auto, &uniform, &cleaned, &smoothed] {
        assert!(r.validation.valid && r.quality.scaled_jacobian().min > 0.0);
    }
    let mean = |r: &imesh::Report| r.quality.shape_and_size().map_or(0.0, |s| s.mean);
    eprintln!(
        "mean shape-and-size: graded {:.3}, auto (default) {:.3}, size 3 {:.3}, + min region 50 {:.3}, + majority 2 {:.3}",
        mean(&graded),
        mean(&auto),
        mean(&uniform),
        mean(&cleaned),
        mean(&smoothed)
    );
    // The default: a uniform size from the image, the labels smoothed over about one quad and
    // the regions thinner than half a quad merged.
    assert!(auto.counts.quad_size >= imesh::MIN_AUTO_SIZE);
    assert!(auto.counts.cleaned_pixels > 0 && auto.counts.merged_regions > 0);
    assert!(mean(&auto) > 0.7, "default mean {:.3}", mean(&auto));
    assert!(mean(&auto) > mean(&smoothed));
    // Measured against the image's own labels, the clean-up costs some agreement, not much.
    assert!(auto.label_agreement > 0.95 && auto.label_agreement < uniform.label_agreement);
    assert!(mean(&uniform) > mean(&graded) + 0.2);
    assert!(mean(&cleaned) > mean(&uniform) + 0.1);
    assert_eq!(graded.counts.dt_spacing, 0.0);
    assert_eq!(graded.counts.quad_size, 0.0);
    assert_eq!(uniform.counts.dt_spacing, 6.0);
    assert_eq!(uniform.counts.cleaned_pixels, 0);
    assert_eq!(uniform.counts.merged_regions, 0);
    assert!(cleaned.counts.cleaned_pixels > 0);
    assert!(mean(&smoothed) > mean(&cleaned) + 0.05);
    assert!(smoothed.counts.cleaned_pixels > cleaned.counts.cleaned_pixels);
}
