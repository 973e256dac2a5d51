//! The default (quad) pipeline on degenerate images: every one gives a valid mesh.

use image::{DynamicImage, GrayImage, Luma};
use imesh::{Elements, MeshOptions, PairingMethod, Pipeline};

fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> u8) -> DynamicImage {
    DynamicImage::ImageLuma8(GrayImage::from_fn(w, h, |x, y| Luma([f(x, y)])))
}

/// A deterministic pseudo-random byte per pixel.
fn noise(x: u32, y: u32, levels: u32) -> u8 {
    let mut s = x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663) ^ 0x9e37_79b9;
    s ^= s >> 13;
    s = s.wrapping_mul(0x5bd1_e995);
    s ^= s >> 15;
    ((s % levels) * (255 / (levels - 1))) as u8
}

fn degenerate_images() -> Vec<(&'static str, DynamicImage)> {
    vec![
        ("one pixel", image(1, 1, |_, _| 0)),
        (
            "two pixels",
            image(2, 1, |x, _| if x == 0 { 0 } else { 255 }),
        ),
        ("flat", image(20, 20, |_, _| 7)),
        (
            "checkerboard",
            image(16, 16, |x, y| if (x + y) % 2 == 0 { 0 } else { 255 }),
        ),
        (
            "2-pixel checkerboard",
            image(
                40,
                30,
                |x, y| if (x / 2 + y / 2) % 2 == 0 { 0 } else { 255 },
            ),
        ),
        ("binary noise", image(64, 64, |x, y| noise(x, y, 2))),
        ("three-level noise", image(50, 40, |x, y| noise(x, y, 3))),
        (
            "1-pixel line",
            image(32, 32, |x, _| if x == 16 { 255 } else { 0 }),
        ),
        (
            "1-pixel diagonal",
            image(32, 32, |x, y| if x == y { 255 } else { 0 }),
        ),
        (
            "corner-touching pixels",
            image(10, 10, |x, y| {
                if (x, y) == (3, 3) || (x, y) == (4, 4) {
                    255
                } else {
                    0
                }
            }),
        ),
        (
            "thin strip",
            image(200, 3, |_, y| if y == 1 { 255 } else { 0 }),
        ),
    ]
}

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
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images");
    let mut images: Vec<_> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    images.sort();
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
        assert!(
            r.label_agreement > 0.9,
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
