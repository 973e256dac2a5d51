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
            tolerance: Some(0.0),
            ..Default::default()
        },
        MeshOptions {
            tolerance: Some(15.0),
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
        // Cells of 3 × 3 pixels: a 1-pixel image is one cell, a 1-pixel line half a cell.
        MeshOptions {
            reduction: Some(3),
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
            check_regions(r, name);
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
        for reduction in [None, Some(2)] {
            let options = MeshOptions {
                elements: Elements::Tri,
                reduction,
                ..Default::default()
            };
            let result = Pipeline::new(options)
                .run_image(&picture)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let r = &result.report;
            assert!(r.validation.valid, "{name}");
            assert!((r.validation.area_ratio - 1.0).abs() < 1e-9, "{name}");
            assert_eq!(r.counts.quads, 0, "{name}");
            check_regions(r, name);
            // A reduction only where the image spans more than a cell.
            let expected = match reduction {
                Some(f) if r.counts.width.max(r.counts.height) > 1 => f,
                _ => 1,
            };
            assert_eq!(r.counts.reduction, expected, "{name}");
            let cells = |n: u32| (n + expected / 2) / expected;
            assert_eq!(r.counts.grid_width, cells(r.counts.width).max(1), "{name}");
        }
    }
}

/// The report's regions: one per label of the image, their pixels the image's, their element
/// areas the mesh's (the whole domain between them), and their agreements the whole one's.
fn check_regions(r: &imesh::Report, what: &str) {
    let regions = &r.fidelity.regions;
    assert_eq!(regions.len(), r.counts.image_labels, "{what}");
    let area = f64::from(r.input.width) * f64::from(r.input.height);
    let pixels: u64 = regions.iter().map(|g| g.pixels).sum();
    assert_eq!(pixels as f64, area, "{what}");
    let meshed: f64 = regions.iter().map(|g| g.area_px).sum();
    assert!(
        (meshed / area - 1.0).abs() < 1e-9,
        "{what}: {meshed} of {area}"
    );
    let elements: usize = regions.iter().map(|g| g.elements).sum();
    assert_eq!(elements, r.counts.elements, "{what}");
    let agreeing: f64 = regions.iter().map(|g| g.agreement * g.pixels as f64).sum();
    assert!(
        (agreeing / area - r.label_agreement).abs() < 1e-9,
        "{what}: {} against {}",
        agreeing / area,
        r.label_agreement
    );
    for g in regions {
        assert!((0.0..=1.0).contains(&g.agreement), "{what}: {g:?}");
        assert_eq!(g.elements == 0, g.area_px == 0.0, "{what}: {g:?}");
        assert!(g.area_px >= 0.0, "{what}: {g:?}");
    }
}

#[test]
fn every_fixture_gives_a_valid_quad_mesh_and_a_valid_triangle_mesh() {
    let images = support::fixtures();
    assert!(images.len() >= 10, "{images:?}");
    let mut at_a_bound = 0;
    for path in images {
        let quads = Pipeline::new(MeshOptions::default())
            .run_path(&path)
            .unwrap();
        let r = &quads.report;
        // The pipeline refuses to return a mesh that fails the validator; check it said so.
        assert!(r.validation.valid, "{}", path.display());
        check_regions(r, &path.display().to_string());
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
        // A corner between two boundary edges fills a sector alone: its sine bounds the worst
        // scaled Jacobian; on all fixtures but two the worst is either such a corner, where the
        // curves could not be turned wider within the tolerance nor the tip cut, or at the
        // repair's bar of 0.5 (coffee's, in a strip a pixel wide, since refinement leaves such
        // strips alone). Gravel's, 0.484 once its tips were cut (0.459 at a 27° corner
        // before), a quad of a strip 1.5 px wide along the border, under its 29.6° corner, is
        // at 0.5 since its neighbourhood moves as a whole (below); grass's, 0.485 once its tips with a short side are cut from that side's end (0.447
        // at a 27° corner before), a quad of a gap 1.4 px wide between two regions; aloe's,
        // 0.361 once junctions three quarters of a quad apart were merged (0.352 at a 20.7°
        // corner before), a quad of its tangles of pixel-wide regions, and now at its sharpest
        // corner's bound (23.9°) since unpaired triangles sharp beside a boundary are refined
        // once more.
        let corner = r
            .sharpest_boundary_corner
            .expect("a quad mesh has boundary corners");
        let worst = r.quality.scaled_jacobian().min;
        assert!(
            worst <= corner.scaled_jacobian + 1e-12,
            "{}",
            path.display()
        );
        if worst >= corner.scaled_jacobian - 1e-9 || worst >= 0.5 {
            at_a_bound += 1;
        }
        // The worst shape: once the repairs stall, each poor quad's neighbourhood moves as a
        // whole (camera's kite of four quads in a 37° wedge 0.251 → 0.480, coffee 0.306 →
        // 0.431, brick 0.383 → 0.462, gravel 0.321 → 0.414, grass 0.302 → 0.388). Aloe keeps
        // poorer quads in its tangles of pixel-wide regions (0.294).
        let shape = r.quality.shape().min;
        let bound = if path.ends_with("opencv-aloeGT.png") {
            0.25
        } else if path.ends_with("skimage-grass.png") || path.ends_with("skimage-gravel.png") {
            // Grass 0.347 since thin strips' boundary pieces are cut to the strips' depth
            // (session 43): a boundary quad at (270.5, 485.5) that other changes moved between
            // 0.30 and 0.42. Since session 57's lattice tries (both lattices × 0.909, 5–8 % more
            // quads) grass 0.429 → 0.233, a quad at a junction of four blades near (297.5,
            // 315.5), and gravel 0.500 → 0.313, a quad in a sliver's wedge near (444, 27); over
            // 1 050 random images the quads under 0.5 in shape went 204 → 158.
            0.2
        } else {
            0.4
        };
        assert!(shape > bound, "{}: worst shape {shape}", path.display());
        if path.ends_with("pyvista-channels_z050_labels.png")
            || path.ends_with("skimage-gravel.png")
        {
            // Boundaries met at 16° and 17°: turned apart within the tolerance (the worst
            // scaled Jacobian was 0.275 and 0.294 with the curves as fitted).
            assert!(r.counts.opened_corners > 0 && r.counts.turned_curves > 0);
            assert!(
                r.quality.scaled_jacobian().min > 0.4,
                "{}: worst scaled Jacobian {}",
                path.display(),
                r.quality.scaled_jacobian().min
            );
        }
        if path.ends_with("opencv-aloeGT.png") {
            // Its pixel spikes and staircases: 234 tips cut (180 before they could be cut from
            // a short side's end; none at all if one bad cut dropped every cut), 197 since
            // session 58's thin parts took the thinnest spikes first.
            assert!(
                r.counts.blunted_tips > 170,
                "aloe: {} tips",
                r.counts.blunted_tips
            );
        }
        if path.ends_with("skimage-grass.png") {
            // Its 26.6° tip, whose shorter side ends 3 px out, is cut from that side's end.
            assert!(r.counts.blunted_tips > 0);
            assert!(worst > 0.48, "grass: worst scaled Jacobian {worst}");
        }
        if path.ends_with("skimage-brick.png") {
            // Simplified, boundaries met the border and each other at 8–15°; the boundaries'
            // own directions are kept there, and no corner is that sharp.
            assert!(r.counts.kept_at_sharp_sectors > 0);
            assert!(
                r.quality.scaled_jacobian().min > 0.3,
                "brick: worst scaled Jacobian {}",
                r.quality.scaled_jacobian().min
            );
        }
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
        assert!(t.sharpest_boundary_corner.is_none());
    }
    assert!(at_a_bound >= 8, "{at_a_bound}");
}

/// A uniform size (`--size`) lifts shape-and-size well above the graded DT' on a fixture, and
/// `min_region` merges the small regions away and `majority` smooths the labels first, each
/// saying how many pixels changed.
#[test]
fn a_uniform_size_gives_higher_shape_and_size_than_a_graded_one() {
    let path = support::fixture("matplotlib-s1045_mri.png");
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
        min_part_width: Some(0.0),
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

#[test]
fn the_automatic_size_is_finer_where_boundaries_would_take_too_many_quads() {
    let path = support::fixture("skimage-coins.png");
    let run = |options: MeshOptions| Pipeline::new(options).run_path(&path).unwrap().report;
    let auto = run(MeshOptions::default());
    // The size from the quad count alone (coins' regions are wide): the clean-ups' size, and
    // the mesh's before the boundaries were measured.
    let by_count = (384.0 * 303.0 / imesh::AUTO_QUADS).sqrt();
    // With the automatic size, regions are merged below three quarters of the finest side it
    // may refine to; the coarse run is given the same width.
    let finest = (by_count / imesh::AUTO_BAND_REFINEMENT).max(imesh::MIN_AUTO_SIZE);
    let coarse = run(MeshOptions {
        size: ElementSize::Pixels(by_count),
        min_width: Some(imesh::THIN_REGION_SHARE * finest),
        ..Default::default()
    });
    let mean = |r: &imesh::Report| r.quality.shape_and_size().map_or(0.0, |s| s.mean);
    eprintln!(
        "coins: auto {:.2} px, {} quads, mean S&S {:.4}; {by_count:.2} px: {} quads, {:.4}",
        auto.counts.quad_size,
        auto.counts.quads,
        mean(&auto),
        coarse.counts.quads,
        mean(&coarse)
    );
    assert!(auto.validation.valid && coarse.validation.valid);
    assert!(auto.counts.quad_size < 0.9 * by_count);
    assert!(auto.counts.quad_size >= by_count / imesh::AUTO_BAND_REFINEMENT - 1e-9);
    // The same clean-up (majority filter, thin regions) at both sizes.
    assert_eq!(auto.counts.cleaned_pixels, coarse.counts.cleaned_pixels);
    assert_eq!(auto.counts.merged_regions, coarse.counts.merged_regions);
    assert!(auto.counts.quads > coarse.counts.quads);
    // The paper's Table I mean, which the coarser mesh misses.
    assert!(mean(&auto) >= 0.85, "default mean {:.4}", mean(&auto));
    assert!(mean(&auto) > mean(&coarse) + 0.02);
}

/// Where the band along the boundaries pulls the mean quad area off the lattice's (the camera:
/// the median quad, a lattice one, is 1.013 times the mean at first; the MRI scan 1.007), the
/// lattice is scaled towards the mean, twice at most, and the best try kept for its higher
/// shape-and-size; where the lattice fits (pyvista's channels, within 0.2 %), it stays.
/// (Pyvista's channels were the scaled example, 0.971 and then 0.987 of the mean, until the
/// matching left its large band pairs as triangles: their quads, two thirds as large, bring the
/// mean to the lattice's.)
#[test]
fn the_lattice_is_scaled_to_the_mean_quad() {
    let run = |name: &str| {
        Pipeline::new(MeshOptions::default())
            .run_path(&support::fixture(name))
            .unwrap()
            .report
    };
    let mean = |r: &imesh::Report| r.quality.shape_and_size().map_or(0.0, |s| s.mean);
    let camera = run("skimage-camera.png");
    let mri = run("matplotlib-s1045_mri.png");
    let pyvista = run("pyvista-channels_z050_labels.png");
    eprintln!(
        "camera: lattice × {:.4}, mean S&S {:.4}; MRI: × {:.4}, {:.4}; pyvista: × {:.4}, {:.4}",
        camera.counts.lattice_scale,
        mean(&camera),
        mri.counts.lattice_scale,
        mean(&mri),
        pyvista.counts.lattice_scale,
        mean(&pyvista)
    );
    assert!(camera.validation.valid && mri.validation.valid && pyvista.validation.valid);
    // Session 56's single try of the plain ratio: camera × 0.987, 0.9139; MRI × 1 (it was
    // within 1 %), 0.9052.
    assert!((0.93..=0.97).contains(&camera.counts.lattice_scale));
    assert!(mean(&camera) >= 0.92, "{}", mean(&camera));
    // MRI × 0.93–0.99 in session 57; since session 58's thin parts its median is within
    // 0.2 % of the mean at the first lattice (× 1, 0.9151).
    assert!((0.93..=1.0).contains(&mri.counts.lattice_scale));
    assert!(mean(&mri) >= 0.91, "{}", mean(&mri));
    assert_eq!(pyvista.counts.lattice_scale, 1.0);
}

/// The lattice's tries are only tries: on grass the kept one is finer (× 0.909) and makes
/// 78 095 quads; under a limit of 73 000 the run keeps the first mesh (69 218) instead of
/// failing.
#[test]
fn a_second_lattice_over_a_limit_keeps_the_first() {
    let run = |max_elements: u64| {
        Pipeline::new(MeshOptions {
            max_elements,
            ..Default::default()
        })
        .run_path(&support::fixture("skimage-grass.png"))
        .unwrap()
        .report
    };
    let free = run(MeshOptions::default().max_elements);
    let limited = run(73_000);
    eprintln!(
        "grass: × {:.4}, {} quads; limited: × {:.4}, {} quads",
        free.counts.lattice_scale,
        free.counts.quads,
        limited.counts.lattice_scale,
        limited.counts.quads
    );
    assert!(free.counts.lattice_scale < 1.0 && free.counts.quads > 73_000);
    assert_eq!(limited.counts.lattice_scale, 1.0);
    assert!(limited.counts.quads <= 73_000);
    assert!(limited.validation.valid);
}

#[test]
fn a_large_image_is_meshed_on_a_reduced_grid_and_scaled_back() {
    let path = support::fixture("skimage-camera.png");
    // The camera at 1300 × 1100: quads of the automatic size are about 12 pixels wide.
    let image = image::open(&path)
        .expect("the camera fixture loads")
        .resize_exact(1300, 1100, image::imageops::FilterType::Triangle);
    let result = Pipeline::new(MeshOptions::default())
        .with_stages()
        .run_image(&image)
        .unwrap();
    let (mesh, reduced) = (result.mesh, result.report);
    // The stage pictures are scaled onto the image's frame too: each spans it.
    for stage in &result.stages {
        let xs = stage
            .vertices
            .iter()
            .map(|v| v[0])
            .chain(stage.lines.iter().flatten().map(|p| p[0]));
        let (lo, hi) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
        assert!(lo >= 0.0 && hi <= 1300.0, "{}: {lo}..{hi}", stage.name);
        assert!(hi > 1290.0, "{}: up to {hi}", stage.name);
    }
    let run = |options: MeshOptions| {
        let result = Pipeline::new(options).run_image(&image).unwrap();
        (result.mesh, result.report)
    };
    let (_, pixels) = run(MeshOptions {
        reduction: Some(1),
        ..Default::default()
    });
    let c = &reduced.counts;
    // q ≈ 12 px, so ⌊q / 4⌋ = 2: cells of 2 × 2 pixels, quads about 6 cells wide.
    assert_eq!(
        (c.reduction, c.grid_width, c.grid_height),
        (2, 650, 550),
        "quad size {}",
        c.quad_size
    );
    assert_eq!((c.width, c.height), (1300, 1100));
    assert_eq!((mesh.width, mesh.height), (1300, 1100));
    assert_eq!(pixels.counts.reduction, 1);
    assert_eq!(
        (pixels.counts.grid_width, pixels.counts.grid_height),
        (1300, 1100)
    );
    // Scaled back exactly onto the image: its corners and border, the whole area.
    assert!(reduced.validation.valid);
    check_regions(&reduced, "reduced");
    check_regions(&pixels, "pixels");
    assert!((reduced.validation.area_ratio - 1.0).abs() < 1e-9);
    for corner in [[0.0, 0.0], [1300.0, 0.0], [1300.0, 1100.0], [0.0, 1100.0]] {
        assert!(mesh.vertices.contains(&corner), "corner {corner:?}");
    }
    assert!(mesh
        .vertices
        .iter()
        .all(|v| (0.0..=1300.0).contains(&v[0]) && (0.0..=1100.0).contains(&v[1])));
    // Quads of about the same size either way, and the same share of the labels followed...
    let quads = |r: &imesh::Report| r.counts.quads as f64;
    assert!((quads(&reduced) / quads(&pixels) - 1.0).abs() < 0.25);
    assert!((reduced.counts.quad_size / pixels.counts.quad_size - 1.0).abs() < 0.1);
    assert!(reduced.label_agreement > 0.96);
    assert!(reduced.label_agreement > pixels.label_agreement - 0.01);
    // ... but better quads on the reduced grid.
    let sns = |r: &imesh::Report| r.quality.shape_and_size().map_or(0.0, |s| s.mean);
    let sj = |r: &imesh::Report| r.quality.scaled_jacobian().min;
    eprintln!(
        "reduced: mean S&S {:.3}, worst SJ {:.3}, agreement {:.4}; pixels: {:.3}, {:.3}, {:.4}",
        sns(&reduced),
        sj(&reduced),
        reduced.label_agreement,
        sns(&pixels),
        sj(&pixels),
        pixels.label_agreement
    );
    assert!(sns(&reduced) > sns(&pixels));
    assert!(sns(&reduced) > 0.85);
    assert!(sj(&reduced) > 0.3);
    // A size given in pixels reduces too (⌊12 / 4⌋ = 3), and is kept in pixels.
    let (_, given) = run(MeshOptions {
        size: ElementSize::Pixels(12.0),
        ..Default::default()
    });
    assert_eq!(given.counts.reduction, 3);
    assert!((given.counts.quad_size / 12.0 - 1.0).abs() < 0.01);
    assert_eq!(given.options.size, ElementSize::Pixels(12.0));
    assert!(given.validation.valid && sns(&given) > 0.85);
}

/// A disc that comes within 6 px of the image's left side and 10 px of its top and bottom,
/// meshed on cells of 3 × 3 pixels (the retina of a fundus photograph, nearly filling its
/// frame): the majority filter's window is cut off at the border, and the gaps tapering to
/// two cells between the disc and the border kept their pixels, which the mesh filled with
/// quads a few hundredths of the mean area (mean shape-and-size 0.877, worst scaled Jacobian
/// 0.455 before the border's thin parts were given to the disc).
#[test]
fn a_region_nearly_touching_the_border_leaves_no_sliver_of_small_quads() {
    let disc = support::grey(1400, 1400, |x, y| {
        let (dx, dy) = (f64::from(x) - 696.5, f64::from(y) - 700.0);
        if dx * dx + dy * dy < 690.0 * 690.0 {
            255
        } else {
            0
        }
    });
    let r = Pipeline::new(MeshOptions::default())
        .run_image(&disc)
        .unwrap()
        .report;
    assert!(r.validation.valid);
    assert_eq!(r.counts.reduction, 3);
    let ss = r.quality.shape_and_size().expect("quads");
    assert!(ss.mean > 0.93, "mean shape-and-size {}", ss.mean);
    assert!(r.quality.scaled_jacobian().min >= 0.5 - 1e-9);
    // The gaps given away are a sliver of the background: under 0.2 % of the pixels.
    assert!(
        r.label_agreement > 0.99,
        "label agreement {}",
        r.label_agreement
    );
}

/// Vertical stripes 36 px wide, off the lattice's columns: the lattice's rows cut every
/// boundary as they cut the border, so the band along each boundary is rectangles and every
/// quad has square corners. Cut into equal pieces and refined instead, the bands left 278
/// triangles unpaired and skewed quads: worst scaled Jacobian 0.500, mean shape-and-size 0.846.
#[test]
fn axis_parallel_boundaries_are_met_square_on() {
    let stripes = support::grey(300, 200, |x, _| if (x / 36) % 2 == 0 { 0 } else { 255 });
    let r = Pipeline::new(MeshOptions::default())
        .run_image(&stripes)
        .unwrap()
        .report;
    assert!(r.validation.valid);
    assert_eq!(r.counts.unpaired_triangles, 0);
    let sj = r.quality.scaled_jacobian();
    assert!(sj.min > 0.999, "worst scaled Jacobian {}", sj.min);
    let ss = r.quality.shape_and_size().expect("quads");
    assert!(ss.mean > 0.88, "mean shape-and-size {}", ss.mean);
}

/// A rectangle 2 px from the image's left side, meshed with quads of 2.6 px (the side that
/// gives about 10 000 quads): the majority filter (radius 3) leaves a strip one pixel wide
/// between the rectangle and the border, a quarter of the radius is under a pixel, and the
/// strip was kept: quads of 0.2–5 % of the mean area along it (worst shape 0.31, worst
/// shape-and-size 0.0002, worst scaled Jacobian 0.43, label agreement 98.98 %).
#[test]
fn a_strip_a_pixel_wide_along_the_border_goes_to_its_neighbour() {
    let image = support::grey(235, 291, |x, y| {
        if (2..13).contains(&x) && (100..256).contains(&y) {
            255
        } else {
            0
        }
    });
    let r = Pipeline::new(MeshOptions::default())
        .run_image(&image)
        .unwrap()
        .report;
    assert!(r.validation.valid);
    assert!(
        (r.counts.quad_size - 2.615).abs() < 0.01,
        "{}",
        r.counts.quad_size
    );
    let ss = r.quality.shape_and_size().expect("quads");
    assert!(ss.min > 0.2, "worst shape-and-size {}", ss.min);
    assert!(r.quality.shape().min >= 0.5 - 1e-9);
    assert!(r.quality.scaled_jacobian().min >= 0.5 - 1e-9);
    // The strip given away is 2 × 156 pixels of the background, and the mesh follows the
    // rectangle closer than it followed the strip.
    assert!(
        r.label_agreement > 0.993,
        "label agreement {}",
        r.label_agreement
    );
}

/// Two discs joined by an arm 3 px wide, meshed with quads of 6 px (no majority filter, which
/// would thin the arm but here is off to show the rule alone): the arm is a part of the
/// region thinner than a quad, whose quads can only be a fraction of the mean area. Given to
/// the background (`min_part_width`, automatic: one quad side), the discs are meshed apart;
/// kept, the arm's quads score far under the paper's 0.25.
#[test]
fn a_thin_arm_between_two_wide_parts_goes_to_its_neighbour() {
    let image = support::grey(240, 120, |x, y| {
        let disc = |cx: f64| (f64::from(x) - cx).powi(2) + (f64::from(y) - 60.0).powi(2) < 900.0;
        if disc(60.0) || disc(180.0) || ((80..160).contains(&x) && (59..62).contains(&y)) {
            255
        } else {
            0
        }
    });
    let run = |min_part_width: Option<f64>| {
        let options = MeshOptions {
            size: ElementSize::Pixels(6.0),
            majority: Some(0),
            min_part_width,
            ..Default::default()
        };
        Pipeline::new(options).run_image(&image).unwrap().report
    };
    let given = run(None);
    let kept = run(Some(0.0));
    fn ss(r: &imesh::Report) -> &imesh_quality::Statistics {
        r.quality.shape_and_size().expect("quads")
    }
    eprintln!(
        "arm given away: worst {:.3}, mean {:.3}, {} px changed; kept: worst {:.3}, mean {:.3}",
        ss(&given).min,
        ss(&given).mean,
        given.counts.cleaned_pixels,
        ss(&kept).min,
        ss(&kept).mean
    );
    assert!(given.validation.valid && kept.validation.valid);
    // The arm between the discs (3 × 60 pixels outside them), and nothing else.
    assert!((170..=200).contains(&given.counts.cleaned_pixels));
    assert_eq!(kept.counts.cleaned_pixels, 0);
    assert!(ss(&kept).min < 0.1);
    assert!(ss(&given).min > 0.25);
    assert!(ss(&given).mean > ss(&kept).mean);
}

/// Under a reduction the options given in pixels are converted to cells, the defaults apply to
/// the cells: a 2 px tolerance keeps the boundaries within 2 px of the image's, the default
/// within 2 cells, each beyond that by the farthest the optimiser moved a corner, in pixels too.
/// (Graded: no quad-sized joining of short pieces, so the tolerance is the bound.)
#[test]
fn options_given_in_pixels_stay_in_pixels_on_a_reduced_grid() {
    let path = support::fixture("stardist-mask2d_labels.png");
    let run = |tolerance: Option<f64>| {
        let options = MeshOptions {
            size: ElementSize::Graded,
            reduction: Some(4),
            tolerance,
            ..Default::default()
        };
        Pipeline::new(options).run_path(&path).unwrap().report
    };
    let given = run(Some(2.0));
    let default = run(None);
    let hausdorff = |r: &imesh::Report| r.fidelity.boundary_hausdorff_px;
    let shift = |r: &imesh::Report| r.optimisation.as_ref().unwrap().corner_shift_px;
    assert_eq!(given.counts.reduction, 4);
    assert_eq!(given.options.tolerance, Some(2.0));
    assert!(hausdorff(&given) > 0.0 && hausdorff(&given) <= 2.0 + shift(&given) + 1e-9);
    // The default: 2 cells of 4 px, reported as used.
    assert_eq!(default.options.tolerance, Some(8.0));
    assert!(hausdorff(&default) > 2.0 && hausdorff(&default) <= 8.0 + shift(&default) + 1e-9);
    // A corner moves by a share of the mean quad side at most, the cells scaled to pixels.
    for r in [&given, &default] {
        let side =
            (f64::from(r.counts.width) * f64::from(r.counts.height) / r.counts.quads as f64).sqrt();
        assert!(
            shift(r) <= imesh_optim::CORNER_REACH * side * (1.0 + 1e-9),
            "{}",
            shift(r)
        );
    }
    assert!(default.counts.quads < given.counts.quads);
}

/// The whole run is reproducible: on one thread and on two, the same mesh to the bit and the
/// same report but for its seconds (the mean quad area, which every shape-and-size in it is
/// measured against, was a parallel sum whose rounding followed the work's split).
#[test]
fn the_mesh_and_the_report_are_the_same_on_one_and_two_threads() {
    let path = support::fixture("skimage-coins.png");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let result = pool.install(|| Pipeline::new(MeshOptions::default()).run_path(&path));
        let result = result.unwrap();
        let mut report = serde_json::to_value(&result.report).unwrap();
        report.as_object_mut().unwrap().remove("timings_s");
        (result.mesh.vertices, result.mesh.labels, report)
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.0.len(), two.0.len());
    assert!(one
        .0
        .iter()
        .zip(&two.0)
        .all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits)));
    assert_eq!(one.1, two.1);
    assert_eq!(one.2, two.2);
}

/// The MRI's spike tips (27° between the curves, which turning within the tolerance could not
/// open) are cut off where they are a quad side or two wide: the worst scaled Jacobian reaches
/// 0.5 instead of the tips' sine, for a few pixels given to the neighbour region. (With the
/// defaults the spikes, thinner than a quad, go with the thin parts first; here those are
/// kept.) Kept, a tip stays as sharp only with its corners held (`corner_reach` 0): by default
/// the optimiser moves the tip's vertex a fraction of a quad side into the spike, which opens
/// it to 30° and cuts nothing off.
#[test]
fn sharp_tips_are_cut_unless_kept() {
    let path = support::fixture("matplotlib-s1045_mri.png");
    let run = |keep_sharp_tips: bool, corner_reach: f64| {
        Pipeline::new(MeshOptions {
            keep_sharp_tips,
            corner_reach,
            min_part_width: Some(0.0),
            ..MeshOptions::default()
        })
        .run_path(&path)
        .unwrap()
        .report
    };
    let (cut, kept) = (run(false, 0.0), run(true, 0.0));
    assert!(cut.validation.valid && kept.validation.valid);
    assert_eq!(kept.counts.blunted_tips, 0);
    assert!(cut.counts.blunted_tips > 0 && cut.counts.blunted_area_px > 0.0);
    let sj = |r: &imesh::Report| r.quality.scaled_jacobian().min;
    assert!(sj(&kept) < 0.46, "{}", sj(&kept));
    assert!(sj(&cut) >= 0.5, "{}", sj(&cut));
    // The tips' area is a few pixels of the 65 536: the agreement moves by under 0.1 point.
    assert!(cut.counts.blunted_area_px < 50.0);
    assert!((kept.label_agreement - cut.label_agreement).abs() < 1e-3);
    // The boundary moved by the cut's depth at most, and the report's fidelity says so.
    assert!(cut.fidelity.boundary_hausdorff_px >= kept.fidelity.boundary_hausdorff_px);
    // Kept, with the corners free to move by default: nothing cut off, the tips opened.
    let opened = run(true, imesh_optim::CORNER_REACH);
    assert!(opened.validation.valid);
    assert_eq!(opened.counts.blunted_tips, 0);
    assert!(sj(&opened) >= 0.5 - 1e-9, "{}", sj(&opened));
    let moves = opened.optimisation.as_ref().unwrap();
    let reach = imesh_optim::CORNER_REACH * opened.counts.quad_size;
    assert!(moves.moved_corners > 0 && moves.corner_shift_px > 0.0);
    // The mean quad side is within a few percent of the chosen size.
    assert!(
        moves.corner_shift_px <= 1.1 * reach,
        "{moves:?}, reach {reach}"
    );
    assert!(
        opened.fidelity.boundary_hausdorff_px
            >= kept.fidelity.boundary_hausdorff_px + moves.corner_shift_px - 1e-9
    );
    assert!((kept.label_agreement - opened.label_agreement).abs() < 1e-3);
}

/// `--order 2` on a fixture of curved boundaries, meshed on its pixels and on a reduced grid
/// (whose mesh is scaled back, the second-order nodes too): the linear mesh is the order-1 mesh,
/// every quad keeps its Jacobian above half its straight self's everywhere (proved by the
/// Bernstein bound), the curved quads cover the image exactly, only sides between two labels
/// bend, and the report counts what was made.
#[test]
fn second_order_meshes_bend_the_boundary_sides_and_stay_valid() {
    let image = image::open(support::fixture("skimage-coins.png")).expect("the coins load");
    for reduction in [1, 2] {
        let run = |order: u32| {
            Pipeline::new(MeshOptions {
                order,
                reduction: Some(reduction),
                ..Default::default()
            })
            .run_image(&image)
            .unwrap()
        };
        let (linear, quadratic) = (run(1), run(2));
        let (mesh, report) = (&quadratic.mesh, &quadratic.report);
        assert_eq!(mesh.vertices, linear.mesh.vertices);
        assert_eq!(mesh.elements, linear.mesh.elements);
        assert_eq!(mesh.labels, linear.mesh.labels);
        let so = mesh.second_order.as_ref().expect("second-order nodes");
        let c = &report.counts;
        assert_eq!(c.nodes, mesh.node_count());
        assert_eq!(c.nodes, c.vertices + so.edges.len() + c.quads);
        assert_eq!((c.curved_sides, c.damped_sides), (so.curved, so.damped));
        assert!(c.curved_sides > 200, "{} sides bent", c.curved_sides);
        assert!(c.straightened_sides * 50 < c.curved_sides);
        let (w, h) = (f64::from(mesh.width), f64::from(mesh.height));
        let mut total = 0.0;
        let between_labels: std::collections::HashSet<[u32; 2]> = imesh_io::boundaries(mesh)
            .into_iter()
            .filter(|b| b.labels[1] != imesh_io::OUTSIDE)
            .flat_map(|b| b.edges)
            .collect();
        let mut bent = 0;
        for (i, e) in mesh.elements.iter().enumerate() {
            let imesh_quality::Element::Quad(corners) = *e else {
                panic!("quads only");
            };
            let q = so.quad9(mesh, i).expect("a quad");
            // The centre node written is the one the quad's nodes give (to the rounding of the
            // scaling back from a reduced grid).
            let centre = mesh.node(so.centres[i] as usize);
            assert!((centre[0] - q[8][0]).hypot(centre[1] - q[8][1]) < 1e-9);
            for k in 0..4 {
                let (a, b) = (q[k], q[(k + 1) % 4]);
                let straight = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                let d = (q[4 + k][0] - straight[0]).hypot(q[4 + k][1] - straight[1]);
                if d > 1e-9 {
                    let (u, v) = (corners[k], corners[(k + 1) % 4]);
                    assert!(
                        between_labels.contains(&[u.min(v), u.max(v)]),
                        "quad {i} side {k}: {a:?} → {b:?}, middle {:?} off by {d}",
                        q[4 + k]
                    );
                    bent += 1;
                }
            }
            assert!(
                imesh_quality::curved::keeps_share_of_straight(&q, 0.5),
                "quad {i} (reduction {reduction})"
            );
            total += mesh.element_area(i);
        }
        // Each bent side counted once from either quad.
        assert_eq!(bent, 2 * so.curved);
        assert!((total / (w * h) - 1.0).abs() < 1e-9, "{total} of {}", w * h);
        let regions: f64 = report.fidelity.regions.iter().map(|r| r.area_px).sum();
        assert!((regions / (w * h) - 1.0).abs() < 1e-9);
    }
}

/// Thirty Voronoi grains, 240 × 200 (seeds from a 64-bit linear congruential generator),
/// labelled by the nearest seed (the first on a tie), grey level `7 × grain`.
fn voronoi_grains(seed: u64) -> image::DynamicImage {
    let (w, h) = (240u32, 200u32);
    let mut x = seed;
    let mut next = |modulus: u32| {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((x >> 33) % u64::from(modulus)) as i64
    };
    let seeds: Vec<(i64, i64)> = (0..30).map(|_| (next(w), next(h))).collect();
    support::grey(w, h, |px, py| {
        let d = |&(sx, sy): &(i64, i64)| (i64::from(px) - sx).pow(2) + (i64::from(py) - sy).pow(2);
        let grain = (0..seeds.len())
            .min_by_key(|&k| (d(&seeds[k]), k))
            .unwrap_or(0);
        (grain * 7 % 256) as u8
    })
}

/// A grain ending in a sliver thinner than a quad (a 23° tip at (181.5, 50.5) here) held a
/// quad at the tip's angle, a scaled Jacobian of 0.388: no cut a quad side long meets the
/// sliver's side at 30° or more, so the tip is cut square, from where its shorter side ends.
#[test]
fn a_sliver_tip_is_cut_square() {
    let r = Pipeline::new(MeshOptions::default())
        .run_image(&voronoi_grains(20))
        .unwrap()
        .report;
    assert!(r.validation.valid);
    assert!(r.counts.blunted_tips > 0);
    let sj = r.quality.scaled_jacobian().min;
    assert!(sj >= 0.5 - 1e-9, "worst scaled Jacobian {sj}");
    assert!(r.quality.shape().min >= 0.5 - 1e-9);
}

/// A street grid, 240 × 200: six blocks in three labels, streets 8 px wide, a band 6 px
/// tall along the top border and one 2 px wide along the right border.
fn street_grid() -> image::DynamicImage {
    let columns = [(6, 60), (68, 130), (138, 238)];
    let rows = [(6, 90), (98, 200)];
    support::grey(240, 200, |x, y| {
        let block = |spans: &[(u32, u32)], v: u32| spans.iter().position(|&(a, b)| a <= v && v < b);
        match (block(&columns, x), block(&rows, y)) {
            (Some(i), Some(j)) => (60 * (1 + (i + 2 * j) % 3)) as u8,
            _ => 0,
        }
    })
}

/// Streets and bands along the border thinner than a quad held quads under 0.5 in scaled
/// Jacobian (0.36 here): the pieces of a strip's two sides were cut each on its own and fell
/// between each other's, and the strips' triangles paired into rhombi; slivers Imesh's
/// sampling leaves across a street's mouth kept tips of a few degrees. The strips' sides are
/// now cut on the lattice's lines, and those tips cut off.
#[test]
fn street_grids_keep_every_corner_within_30_to_150_degrees() {
    let r = Pipeline::new(MeshOptions::default())
        .run_image(&street_grid())
        .unwrap()
        .report;
    assert!(r.validation.valid);
    let sj = r.quality.scaled_jacobian().min;
    assert!(sj >= 0.5 - 1e-9, "worst scaled Jacobian {sj}");
}
