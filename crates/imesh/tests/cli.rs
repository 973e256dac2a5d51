//! The `imesh` program end to end on fixtures: outputs, exit codes, error messages, no half files.

use std::path::Path;
use std::process::Command;

mod support;

use support::fixture;
use support::program::{
    assert_same_statistics, imesh, imesh_ok, quality_block, quality_json, read_report,
};

/// The counts of an MSH 4.1 file: nodes, surface elements, physical surfaces, physical curves.
fn msh_counts(text: &str) -> (usize, usize, usize, usize) {
    let lines: Vec<&str> = text.lines().collect();
    let at = |tag: &str| {
        lines
            .iter()
            .position(|l| *l == tag)
            .expect("section present")
    };
    let field = |line: &str, k: usize| line.split(' ').nth(k).unwrap().parse::<usize>().unwrap();
    let names = at("$PhysicalNames");
    let n_names: usize = lines[names + 1].parse().unwrap();
    let named = |dim: &str| {
        lines[names + 2..names + 2 + n_names]
            .iter()
            .filter(|l| l.starts_with(dim))
            .count()
    };
    let mut surface_elements = 0;
    let mut k = at("$Elements") + 2;
    while lines[k] != "$EndElements" {
        let count = field(lines[k], 3);
        if field(lines[k], 0) == 2 {
            surface_elements += count;
        }
        k += 1 + count;
    }
    (
        field(lines[at("$Nodes") + 1], 1),
        surface_elements,
        named("2 "),
        named("1 "),
    )
}

/// Saves a 24 × 24 image of a white square, `side` wide in both directions, on black.
fn save_square(path: &Path, side: std::ops::Range<u32>) {
    let mut square = image::GrayImage::new(24, 24);
    for (x, y, p) in square.enumerate_pixels_mut() {
        p.0 = [if side.contains(&x) && side.contains(&y) {
            255
        } else {
            0
        }];
    }
    square.save(path).unwrap();
}

#[test]
fn mesh_writes_a_gmsh_file_a_picture_and_a_report() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("pyvista-channels_z050_labels.png");
    let out = imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "--svg",
            "m.svg",
            "--report",
            "m.json",
            "--png",
            "m.png",
        ],
        dir.path(),
    );
    // No progress bar when stderr is not a terminal (here a pipe): stderr stays clean.
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The default output: the image's name with .msh, in the working directory.
    let msh = std::fs::read_to_string(dir.path().join("pyvista-channels_z050_labels.msh")).unwrap();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("m.json")).unwrap()).unwrap();
    // The labels whose thin channels the clean-up merged away are named, with the share of
    // their area the mesh keeps, as the report's regions have it.
    let said = String::from_utf8_lossy(&out.stdout);
    let regions = report["fidelity"]["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 5);
    let shrunk: Vec<&serde_json::Value> = regions
        .iter()
        .filter(|g| g["area_px"].as_f64().unwrap() < 0.5 * g["pixels"].as_f64().unwrap())
        .collect();
    assert!(!shrunk.is_empty(), "{regions:?}");
    assert!(
        said.contains(&format!(
            "keep{} under half",
            if shrunk.len() == 1 { "s" } else { "" }
        )),
        "{said}"
    );
    for g in shrunk {
        let share = 100.0 * g["area_px"].as_f64().unwrap() / g["pixels"].as_f64().unwrap();
        let named = format!(
            "{} ({share:.0} % of its {} px)",
            g["name"].as_str().unwrap(),
            g["pixels"]
        );
        assert!(said.contains(&named), "{named}: {said}");
    }
    let (nodes, elements, names, curves) = msh_counts(&msh);
    assert_eq!(nodes as u64, report["counts"]["vertices"].as_u64().unwrap());
    assert_eq!(
        elements as u64,
        report["counts"]["elements"].as_u64().unwrap()
    );
    assert_eq!(
        names, 5,
        "one physical surface per label of the 5-label map"
    );
    assert!(
        curves >= 5,
        "a physical curve per boundary, each label's border among them"
    );
    assert_eq!(report["validation"]["valid"], true);
    assert!((report["validation"]["area_ratio"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    // Against the map's own labels: the default smooths them over about one quad first, and
    // straightens a curve where it would leave a corner under 30° (0.949 here).
    assert!(report["label_agreement"].as_f64().unwrap() > 0.94);
    assert!(report["counts"]["cleaned_pixels"].as_u64().unwrap() > 0);
    // DESIGN.md §6's stable keys.
    assert_eq!(
        report["fidelity"]["label_agreement"],
        report["label_agreement"]
    );
    let hausdorff = report["fidelity"]["boundary_hausdorff_px"]
        .as_f64()
        .unwrap();
    // Within the 2 px tolerance, but where a sharp tip was cut off: as far as the cut; and
    // where the optimiser moved a corner, that much farther.
    let cut = report["counts"]["blunted_depth_px"].as_f64().unwrap();
    let shift = report["optimisation"]["corner_shift_px"].as_f64().unwrap();
    let quad = report["counts"]["quad_size"].as_f64().unwrap();
    assert!(shift <= 1.1 * imesh_optim::CORNER_REACH * quad, "{shift}");
    assert!(
        hausdorff > 0.0 && hausdorff <= 2f64.max(cut) + shift + 1e-9,
        "within the 2 px tolerance or the cut, and the corners' shift: {hausdorff}"
    );
    let seconds = &report["timings_s"];
    let stage = |name: &str| {
        seconds[name]
            .as_f64()
            .unwrap_or_else(|| panic!("timings_s.{name} in the report"))
    };
    let stages = [
        "classify",
        "sample",
        "curves",
        "triangulate",
        "pairing",
        "templates",
        "adapt",
        "optimise",
        "write",
    ];
    // The stages are disjoint: together within the whole (which also holds the checks).
    let sum: f64 = stages.iter().map(|&s| stage(s)).sum();
    assert!(stage("write") > 0.0 && stage("optimise") > 0.0);
    assert!(
        sum > 0.0 && sum <= stage("total") + 1e-9,
        "{sum} of {}",
        stage("total")
    );
    for metric in ["shape_and_size", "shape", "scaled_jacobian"] {
        let block = &report["quality"][metric];
        assert_eq!(block["count"], report["counts"]["quads"]);
        assert!(block["min"].as_f64().unwrap() <= block["mean"].as_f64().unwrap());
        assert!(block["variance"].as_f64().unwrap() >= 0.0);
    }
    // Poor quads counted under the key DESIGN.md §6 names, with those of the other metrics
    // under their own thresholds' keys.
    let sas = &report["quality"]["shape_and_size"];
    assert_eq!(sas["below_0_2"], sas["below"]);
    assert_eq!(sas["threshold"], 0.2);
    assert_eq!(
        report["quality"]["scaled_jacobian"]["below_0_3"],
        report["quality"]["scaled_jacobian"]["below"]
    );
    assert_eq!(report["imesh_version"], env!("CARGO_PKG_VERSION"));
    assert!(report["input"]["path"]
        .as_str()
        .unwrap()
        .ends_with("pyvista-channels_z050_labels.png"));
    assert_eq!(report["input"]["width"], 250);
    // The default is an all-quad mesh, and the report says how it was made.
    assert_eq!(report["counts"]["triangles"], 0);
    assert_eq!(report["counts"]["quads"], report["counts"]["elements"]);
    assert!(report["counts"]["simplified_edges"].as_u64().unwrap() > 0);
    assert!(report["quality"]["shape_and_size"]["min"].as_f64().unwrap() > 0.0);
    assert!(
        report["quality"]["scaled_jacobian"]["min"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert_eq!(report["options"]["elements"], "quad");
    assert_eq!(report["options"]["tolerance"], 2.0);
    let png = std::fs::read(dir.path().join("m.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"), "a PNG picture");
    assert!(std::fs::read_to_string(dir.path().join("m.svg"))
        .unwrap()
        .contains("<polygon"));
}

#[test]
fn vtu_output_and_options() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("skimage-coins.png");
    let out = imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "-o",
            "coins.vtu",
            "--te",
            "0.2",
            "--min-angle",
            "20",
            "--pixel-size",
            "0.5",
            "-q",
        ],
        dir.path(),
    );
    assert!(out.stdout.is_empty(), "--quiet prints nothing");
    let vtu = std::fs::read_to_string(dir.path().join("coins.vtu")).unwrap();
    assert!(vtu.contains("Name=\"label\"") && vtu.contains("Name=\"shape\""));
}

#[test]
fn pixel_size_and_origin_place_the_image_in_the_written_frame() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("pyvista-channels_z050_labels.png"); // 250 × 250 px
    imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "-o",
            "m.msh",
            "--pixel-size",
            "0.5,2",
            "--origin",
            "-100,25.5",
            "--report",
            "r.json",
            "-q",
        ],
        dir.path(),
    );
    let msh = std::fs::read_to_string(dir.path().join("m.msh")).unwrap();
    let lines: Vec<&str> = msh.lines().collect();
    let at = lines.iter().position(|l| *l == "$Nodes").unwrap();
    let n: usize = lines[at + 1].split(' ').nth(1).unwrap().parse().unwrap();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for l in &lines[at + 3 + n..at + 3 + 2 * n] {
        let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    // The image's bottom-left corner at the origin, 250 px of 0.5 and 2 units to the right and up.
    assert_eq!((lo, hi), ([-100.0, 25.5], [25.0, 525.5]));
    let report: serde_json::Value = read_report(dir.path());
    assert_eq!(
        report["options"]["origin"],
        serde_json::json!([-100.0, 25.5])
    );
}

#[test]
fn abaqus_and_legacy_vtk_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("pyvista-channels_z050_labels.png");
    for name in ["m.inp", "m.vtk"] {
        imesh_ok(
            &["mesh", image.to_str().unwrap(), "-o", name, "-q"],
            dir.path(),
        );
    }
    let inp = std::fs::read_to_string(dir.path().join("m.inp")).unwrap();
    assert_eq!(
        inp.matches("*Element, type=CPS4").count(),
        5,
        "an element set of quads per label"
    );
    assert!(!inp.contains("CPS3"), "the default mesh is all quads");
    assert!(inp.contains("*Nset, nset=border_"));
    for side in ["left", "right", "bottom", "top"] {
        assert!(inp.contains(&format!("*Nset, nset={side}\n")), "{side}");
        assert!(
            inp.contains(&format!("*Surface, type=ELEMENT, name={side}_surface\n")),
            "{side}"
        );
    }
    let vtk = std::fs::read_to_string(dir.path().join("m.vtk")).unwrap();
    assert!(vtk.contains("SCALARS label int 1") && vtk.contains("SCALARS shape double 1"));
}

#[test]
fn the_triangle_mesh_and_quad_options() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("stardist-mask2d_labels.png");
    let image = image.to_str().unwrap();
    let run = |extra: &[&str], report: &str| {
        let mut args = vec!["mesh", image, "-o", "m.inp", "-q", "--report", report];
        args.extend_from_slice(extra);
        imesh_ok(&args, dir.path());
        let text = std::fs::read_to_string(dir.path().join(report)).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let tri = run(&["--elements", "tri"], "tri.json");
    assert_eq!(tri["counts"]["quads"], 0);
    assert!(tri["quality"]["min_angle_deg"]["mean"].as_f64().unwrap() > 30.0);
    let inp = std::fs::read_to_string(dir.path().join("m.inp")).unwrap();
    assert!(inp.contains("CPS3") && !inp.contains("CPS4"));
    // Graded, DT' does not depend on the level (a uniform size is the quads' own).
    let level1 = run(&["--pairing", "greedy", "--size", "graded"], "g1.json");
    let level2 = run(
        &[
            "--pairing",
            "greedy",
            "--size",
            "graded",
            "--template-level",
            "2",
        ],
        "g2.json",
    );
    let quads = |r: &serde_json::Value| r["counts"]["quads"].as_u64().unwrap();
    assert_eq!(
        quads(&level2),
        4 * quads(&level1),
        "level 2 splits every quad in four"
    );
    let matching = run(&["--pairing", "matching", "--size", "graded"], "m.json");
    let fewest = run(&["--pairing", "fewest", "--size", "graded"], "f.json");
    let unpaired = |r: &serde_json::Value| r["counts"]["unpaired_triangles"].as_u64().unwrap();
    assert!(unpaired(&fewest) < unpaired(&level1));
    assert!(unpaired(&fewest) <= unpaired(&matching));
    let coarse = run(&["--tolerance", "5", "--size", "graded"], "t5.json");
    let edges = |r: &serde_json::Value| r["counts"]["simplified_edges"].as_u64().unwrap();
    assert!(edges(&coarse) < edges(&matching));
    // Optimisation: the default (local, shape-and-size) reports the quality before it and
    // lowers the energy; `none` leaves the mesh as the quad stage made it.
    let energy = |r: &serde_json::Value, key: &str| r["optimisation"][key].as_f64().unwrap();
    assert_eq!(matching["optimisation"]["method"], "local");
    assert!(energy(&matching, "energy_after") < energy(&matching, "energy_before"));
    // ... and slides the boundary vertices along their curves.
    assert!(matching["optimisation"]["sliders"].as_u64().unwrap() > 0);
    let stat = |r: &serde_json::Value, block: &str, metric: &str, s: &str| {
        r[block][metric][s].as_f64().unwrap()
    };
    assert!(
        stat(&matching, "quality", "shape_and_size", "mean")
            > stat(
                &matching,
                "quality_before_optimisation",
                "shape_and_size",
                "mean"
            )
    );
    // Shape-and-size divides by the mean quad area, summed again after the optimiser moved the
    // vertices: an untouched worst quad may differ in the last bits.
    let (worst_after, worst_before) = (
        stat(&matching, "quality", "shape_and_size", "min"),
        stat(
            &matching,
            "quality_before_optimisation",
            "shape_and_size",
            "min",
        ),
    );
    assert!(
        worst_after >= worst_before * (1.0 - 1e-12),
        "worst shape-and-size {worst_before} → {worst_after}"
    );
    let none = run(&["--optimizer", "none", "--size", "graded"], "none.json");
    for metric in ["shape_and_size", "shape", "scaled_jacobian"] {
        for s in ["min", "mean"] {
            let unoptimised = stat(&none, "quality", metric, s);
            // Equal up to the order of parallel sums.
            let close = |x: f64| (x - unoptimised).abs() <= 1e-12 * unoptimised.abs().max(1.0);
            assert!(close(stat(&none, "quality_before_optimisation", metric, s)));
            assert!(close(stat(
                &matching,
                "quality_before_optimisation",
                metric,
                s
            )));
        }
    }
    let shape = run(
        &["--optimizer", "vertex", "--metric", "shape"],
        "shape.json",
    );
    assert!(
        stat(&shape, "quality", "shape", "mean")
            > stat(&shape, "quality_before_optimisation", "shape", "mean")
    );
    // A reduction by 2: meshed on 256 × 256 cells, written and measured on the 512 × 512 image.
    let halved = run(&["--reduction", "2"], "r2.json");
    let count = |r: &serde_json::Value, key: &str| r["counts"][key].as_u64().unwrap();
    assert_eq!(count(&halved, "reduction"), 2);
    assert_eq!(count(&halved, "grid_width"), 256);
    assert_eq!(count(&halved, "width"), 512);
    assert_eq!(count(&matching, "reduction"), 1);
    assert!((halved["validation"]["area_ratio"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    assert!(halved["label_agreement"].as_f64().unwrap() > 0.9);
    let out = imesh(
        &["mesh", image, "-o", "r2.msh", "--reduction", "2"],
        dir.path(),
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("512×512 px") && said.contains("meshed on a 256×256 grid"),
        "{said}"
    );
}

#[test]
fn bad_input_is_a_clear_error_with_exit_code_2_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("skimage-coins.png");
    let image = image.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["mesh", image, "--frobnicate"], "unexpected argument"),
        (
            &["mesh", image, "--classify", "bogus:3"],
            "unknown classifier",
        ),
        (&["mesh", image, "-o", "nodir/m.msh"], "does not exist"),
        (&["mesh", "missing.png"], "missing.png"),
        (&["mesh", image, "-o", "out.obj"], ".msh"),
        (&["mesh", image, "--te", "2"], "t_e"),
        (&["mesh", image, "--min-angle", "40"], "34"),
        (&["mesh", image, "--elements", "hex"], "quad"),
        (&["mesh", image, "--template-level", "9"], "1 to 8"),
        (&["mesh", image, "--order", "3"], "1..=2"),
        (&["mesh", image, "--tolerance=-1"], "tolerance"),
        (
            &["mesh", image, "--pairing", "best"],
            "matching, fewest or greedy",
        ),
        (
            &["mesh", image, "--majority", "some"],
            "neither auto nor a number",
        ),
        (&["mesh", image, "--min-width=-2"], "smallest region width"),
        (
            &["mesh", image, "--min-part-width=-2"],
            "smallest part width",
        ),
        (&["mesh", image, "--corner-reach", "2"], "corner reach"),
        (&["mesh", image, "--corner-reach=-0.1"], "corner reach"),
        (&["mesh", image, "--reduction", "0"], "a reduction of 0"),
        (&["mesh", image, "--origin", "5"], "give X,Y"),
        (&["mesh", image, "--msh-version", "3"], "4.1"),
        (
            &["mesh", image, "-o", "m.vtu", "--msh-version", "2.2"],
            "--msh-version is for a .msh output",
        ),
        (&["mesh", image, "--origin", "1,inf"], "finite number"),
        (
            &["mesh", image, "--reduction", "half"],
            "neither auto nor a number",
        ),
        (
            &["mesh", image, "--size", "big"],
            "auto, graded or a positive",
        ),
        (
            &["mesh", image, "--size", "0"],
            "auto, graded or a positive",
        ),
        (&["mesh", image, "-o", "m.msh", "--size", "0.01"], "--size"),
        (&["mesh", image, "--optimizer", "newton"], "local, global"),
        (
            &["mesh", image, "--metric", "jacobian"],
            "shape-and-size or shape",
        ),
        (
            &["mesh", image, "--elements", "tri", "--histogram", "h.png"],
            "drop --elements tri",
        ),
        // Resource limits: each refused with what to change, before anything is written.
        (
            &["mesh", image, "-o", "m.msh", "--max-elements", "1000"],
            "--max-elements",
        ),
        (
            &[
                "mesh",
                image,
                "-o",
                "m.msh",
                "--elements",
                "tri",
                "--max-elements",
                "500",
            ],
            "--max-elements",
        ),
        (
            &["mesh", image, "-o", "m.msh", "--max-size", "0.05"],
            "over the limit of 5000000 elements",
        ),
        (
            &["mesh", image, "-o", "m.msh", "--max-pixels", "1000"],
            "1000",
        ),
        (
            &["mesh", image, "--classify", "labels", "--max-labels", "10"],
            "--max-labels",
        ),
    ];
    for &(args, hint) in cases {
        let out = imesh(args, dir.path());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(hint), "{args:?}: {err}");
    }
    // A file that is not an image.
    std::fs::write(dir.path().join("notes.png"), b"not a png").unwrap();
    let out = imesh(&["mesh", "notes.png"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        left,
        vec![std::ffi::OsString::from("notes.png")],
        "no output was left behind"
    );
}

/// The same input and options give byte-identical files on 1 and 2 threads (every parallel stage
/// is ordered by index, never by completion).
#[test]
fn outputs_are_byte_identical_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    for (fixture_name, extra) in [
        ("skimage-coins.png", &[][..]),
        ("stardist-mask2d_labels.png", &["--template-level", "2"][..]),
        (
            "pyvista-channels_z050_labels.png",
            &["--elements", "tri"][..],
        ),
    ] {
        let image = fixture(fixture_name);
        let mut outputs = Vec::new();
        for threads in ["1", "2"] {
            let stem = format!("{fixture_name}-{threads}");
            let (msh, vtu, svg) = (
                format!("{stem}.msh"),
                format!("{stem}.vtu"),
                format!("{stem}.svg"),
            );
            for (output, picture) in [(&msh, Some(&svg)), (&vtu, None)] {
                let mut args = vec!["mesh", image.to_str().unwrap(), "-o", output.as_str()];
                if let Some(svg) = picture {
                    args.extend(["--svg", svg.as_str()]);
                }
                args.extend(extra);
                let out = Command::new(env!("CARGO_BIN_EXE_imesh"))
                    .args(&args)
                    .env("RAYON_NUM_THREADS", threads)
                    .current_dir(dir.path())
                    .output()
                    .unwrap();
                assert!(
                    out.status.success(),
                    "{args:?}: {}",
                    String::from_utf8_lossy(&out.stderr)
                );
            }
            outputs.push([msh, vtu, svg].map(|f| std::fs::read(dir.path().join(f)).unwrap()));
        }
        for (k, kind) in ["msh", "vtu", "svg"].iter().enumerate() {
            assert!(outputs[0][k].len() > 1000, "{fixture_name} {kind}");
            assert!(
                outputs[0][k] == outputs[1][k],
                "{fixture_name}: the .{kind} differs between 1 and 2 threads"
            );
        }
    }
}

#[test]
fn a_config_file_sets_options_and_unknown_keys_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("matplotlib-s1045_mri.png");
    std::fs::write(dir.path().join("good.toml"), "te = 0.3\nmin_angle = 22.0\n").unwrap();
    std::fs::write(dir.path().join("bad.toml"), "tee = 0.3\n").unwrap();
    imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "--config",
            "good.toml",
            "--report",
            "r.json",
            "-q",
        ],
        dir.path(),
    );
    let report: serde_json::Value = read_report(dir.path());
    assert_eq!(report["options"]["te"], 0.3);
    assert_eq!(report["options"]["min_angle"], 22.0);
    let out = imesh(
        &["mesh", image.to_str().unwrap(), "--config", "bad.toml"],
        dir.path(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("tee"));
}

#[test]
fn classify_writes_a_label_image() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("skimage-coffee.png");
    let out = imesh_ok(
        &[
            "classify",
            image.to_str().unwrap(),
            "--classify",
            "kmeans:3",
            "-o",
            "labels.png",
        ],
        dir.path(),
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("3 labels"));
    assert!(dir.path().join("labels.png").exists());
}

#[test]
fn batch_meshes_a_folder_and_reports_failures_without_stopping() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir(&input).unwrap();
    for name in [
        "matplotlib-s1045_mri.png",
        "pyvista-channels_z050_labels.png",
    ] {
        std::fs::copy(fixture(name), input.join(name)).unwrap();
    }
    std::fs::write(input.join("broken.png"), b"not an image").unwrap();
    std::fs::write(
        input.join("readme.txt"),
        b"not an image, and not a .png either",
    )
    .unwrap();
    let out = imesh(&["batch", "in", "-o", "out", "--format", "vtu"], dir.path());
    assert_eq!(out.status.code(), Some(2), "one image failed");
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("broken.png") && table.contains("FAILED"),
        "{table}"
    );
    assert_eq!(table.matches("FAILED").count(), 1, "{table}");
    // Labels meshed of the image's.
    let row = |name: &str| {
        table
            .lines()
            .find(|l| l.starts_with(name))
            .unwrap_or_default()
    };
    assert!(row("matplotlib-s1045_mri.png").contains(" 2/2 "), "{table}");
    assert!(
        row("pyvista-channels_z050_labels.png").contains(" 5/5 "),
        "{table}"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("1 of 3 images failed"));
    for stem in ["matplotlib-s1045_mri", "pyvista-channels_z050_labels"] {
        assert!(dir.path().join("out").join(format!("{stem}.vtu")).exists());
        assert!(dir.path().join("out").join(format!("{stem}.json")).exists());
    }
    // All good: exit code 0.
    std::fs::remove_file(input.join("broken.png")).unwrap();
    imesh_ok(&["batch", "in", "-o", "out2"], dir.path());
    assert!(dir.path().join("out2/matplotlib-s1045_mri.msh").exists());
}

#[test]
fn the_histogram_shows_quality_before_and_after_optimisation() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("stardist-mask2d_labels.png");
    imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "-o",
            "m.vtu",
            "--histogram",
            "h.png",
            "--report",
            "r.json",
            "-q",
        ],
        dir.path(),
    );
    let picture = image::open(dir.path().join("h.png")).unwrap().to_rgb8();
    assert_eq!(picture.dimensions(), (520, 520), "two panels");
    // Grey (before) and blue (after) bars are both there.
    let has = |c: [u8; 3]| picture.pixels().filter(|p| p.0 == c).count() > 200;
    assert!(has([150, 150, 150]) && has([40, 90, 200]));
    // The report carries the same histograms: every quad counted once, before and after.
    let report: serde_json::Value = read_report(dir.path());
    let quads = report["counts"]["quads"].as_u64().unwrap();
    for key in [
        "shape_and_size_before",
        "shape_and_size_after",
        "scaled_jacobian_before",
        "scaled_jacobian_after",
    ] {
        let counts = report["histograms"][key]["counts"].as_array().unwrap();
        assert_eq!(counts.len(), 20, "{key}");
        assert_eq!(
            counts.iter().map(|c| c.as_u64().unwrap()).sum::<u64>(),
            quads,
            "{key}"
        );
    }
}

#[test]
fn quality_measures_a_written_mesh_as_the_report_did() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("skimage-coins.png");
    // Second-order files are read as their elements' corners: the same statistics.
    for (name, elements, version, order) in [
        ("m.msh", "quad", "4.1", "1"),
        ("m22.msh", "tri", "2.2", "1"),
        ("m.vtk", "tri", "", "1"),
        ("q2.msh", "quad", "4.1", "2"),
        ("q2.vtk", "quad", "", "2"),
        ("t2.msh", "tri", "2.2", "2"),
        ("m.vtu", "quad", "", "1"),
        ("t.inp", "tri", "", "1"),
        ("q2.vtu", "quad", "", "2"),
        ("q2.inp", "quad", "", "2"),
    ] {
        let mut args = vec![
            "mesh",
            image.to_str().unwrap(),
            "-o",
            name,
            "--elements",
            elements,
            "--order",
            order,
            "--report",
            "r.json",
            "-q",
        ];
        if !version.is_empty() {
            args.extend(["--msh-version", version]);
        }
        imesh_ok(&args, dir.path());
        let report: serde_json::Value = read_report(dir.path());
        let measured = quality_json(dir.path(), name);
        // Abaqus has no 9-node plane quad: a second-order `.inp` leaves the centres out.
        let centres = if name.ends_with(".inp") && order == "2" {
            report["counts"]["quads"].as_u64().unwrap()
        } else {
            0
        };
        assert_eq!(
            measured["vertices"].as_u64(),
            report["counts"]["nodes"].as_u64().map(|n| n - centres),
            "{name}"
        );
        if order == "1" {
            assert_eq!(
                report["counts"]["nodes"], report["counts"]["vertices"],
                "{name}"
            );
        } else {
            let (nodes, vertices) = (&report["counts"]["nodes"], &report["counts"]["vertices"]);
            assert!(nodes.as_u64() > vertices.as_u64(), "{name}");
        }
        assert_eq!(measured["quads"], report["counts"]["quads"], "{name}");
        assert_eq!(
            measured["triangles"], report["counts"]["triangles"],
            "{name}"
        );
        // The written frame is y-up: the same shapes, so the same statistics (to rounding).
        assert_same_statistics(
            &measured[quality_block(elements)],
            &report["quality"],
            1e-9,
            name,
        );
        let table = imesh(&["quality", name], dir.path());
        assert!(String::from_utf8_lossy(&table.stdout).contains("scaled Jacobian"));
    }
    std::fs::write(
        dir.path().join("bad.msh"),
        "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n",
    )
    .unwrap();
    for (file, hint) in [
        ("bad.msh", "not 4.1 or 2.2"),
        ("missing.vtk", "cannot read"),
        ("m.json", ".inp"),
    ] {
        let out = imesh(&["quality", file], dir.path());
        assert_eq!(out.status.code(), Some(2), "{file}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(hint),
            "{file}"
        );
    }
}

#[test]
fn stages_draws_every_step_of_the_pipeline() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("stardist-mask2d_labels.png");
    imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "-o",
            "m.msh",
            "--stages",
            "stages",
            "--report",
            "r.json",
            "-q",
        ],
        dir.path(),
    );
    let report: serde_json::Value = read_report(dir.path());
    let mut names: Vec<String> = std::fs::read_dir(dir.path().join("stages"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "00-labels.png",
            "01-imesh.svg",
            "02-c-edges.svg",
            "03-simplified.svg",
            "04-dt.svg",
            "05-pairing.svg",
            "06-templates.svg",
            "07-adapted.svg",
            "08-result.svg"
        ]
    );
    let read = |name: &str| std::fs::read_to_string(dir.path().join("stages").join(name)).unwrap();
    let polygons = |svg: &str| svg.matches("<polygon").count() as u64;
    let segments = |svg: &str| svg.matches('M').count() as u64;
    let count = |key: &str| report["counts"][key].as_u64().unwrap();
    assert_eq!(segments(&read("02-c-edges.svg")), count("c_edges"));
    assert_eq!(
        segments(&read("03-simplified.svg")),
        count("simplified_edges")
    );
    assert_eq!(polygons(&read("04-dt.svg")), count("dt_triangles"));
    let pairs = count("dt_triangles") - count("unpaired_triangles");
    assert_eq!(
        polygons(&read("05-pairing.svg")),
        count("unpaired_triangles") + pairs / 2
    );
    for name in ["06-templates.svg", "07-adapted.svg", "08-result.svg"] {
        let svg = read(name);
        assert_eq!(polygons(&svg), count("quads"), "{name}");
        assert!(svg.contains("href=\"00-labels.png\"") && svg.trim_end().ends_with("</svg>"));
    }
    let labels = image::open(dir.path().join("stages/00-labels.png")).unwrap();
    assert_eq!((labels.width(), labels.height()), (512, 512));
}

#[test]
fn the_svg_can_be_drawn_over_the_input_image() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("skimage-coins.png");
    let args = [
        "mesh",
        image.to_str().unwrap(),
        "-o",
        "m.msh",
        "--svg",
        "m.svg",
        "-q",
    ];
    let out = imesh(&[&args[..], &["--svg-over-image"]].concat(), dir.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(dir.path().join("m.svg")).unwrap();
    let href = svg
        .split("<image href=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap();
    assert!(std::path::Path::new(href).is_absolute() && href.ends_with("skimage-coins.png"));
    assert!(std::path::Path::new(href).exists());
    assert!(svg.contains("fill-opacity=\"0.5\""));
    // Without the flag: no background, opaque elements.
    let out = imesh(&args, dir.path());
    assert!(out.status.success());
    let plain = std::fs::read_to_string(dir.path().join("m.svg")).unwrap();
    assert!(!plain.contains("<image") && plain.contains("fill-opacity=\"1\""));
}

/// The note on a forced worst corner appears only for a corner sharper than 30°: MRI's spike tip
/// (27.0°) when its sharp tips and thin parts are kept and its corners held where they are
/// (`--corner-reach 0`), not a square region's right angles. By default the spike, thinner than
/// a quad, goes with the thin parts; with them kept, the tip is cut off, and the command says
/// so.
#[test]
fn the_forced_corner_note_names_only_sharp_corners() {
    let dir = tempfile::tempdir().unwrap();
    let note = "between two boundaries";
    let mri = fixture("matplotlib-s1045_mri.png");
    let mri = mri.to_str().unwrap();
    let out = imesh(
        &[
            "mesh",
            mri,
            "-o",
            "mri.msh",
            "--keep-sharp-tips",
            "--min-part-width",
            "0",
            "--corner-reach",
            "0",
        ],
        dir.path(),
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains(&format!("a corner of 27.0° {note}")) && !said.contains("cut off"),
        "{said}"
    );
    let out = imesh(
        &["mesh", mri, "-o", "mri.msh", "--min-part-width", "0"],
        dir.path(),
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && !said.contains(note) && said.contains("cut off 3 region tips"),
        "{said}"
    );
    let out = imesh(&["mesh", mri, "-o", "mri.msh"], dir.path());
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && !said.contains(note) && !said.contains("cut off"),
        "{said}"
    );
    // A square of one label in another: the image's corners and the square's are right angles,
    // and a one-pixel image's four corners too.
    save_square(&dir.path().join("square.png"), 8..16);
    image::GrayImage::new(1, 1)
        .save(dir.path().join("one.png"))
        .unwrap();
    for name in ["square.png", "one.png"] {
        let out = imesh(&["mesh", name, "-o", "out.msh"], dir.path());
        assert!(out.status.success());
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            said.contains("scaled Jacobian worst") && !said.contains(note),
            "{said}"
        );
    }
}

/// One-pixel lines every third row are thinner than the smallest automatic quads: the clean-up
/// merges them all into the background, and the command says that a label of the image has no
/// elements and how many pixels were relabelled, with the options that keep them. With those
/// options the lines are meshed and the notes are gone; a square region needs no note.
#[test]
fn the_command_says_when_the_clean_up_drops_a_label() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines = image::GrayImage::new(30, 30);
    for (_, y, p) in lines.enumerate_pixels_mut() {
        p.0 = [if y % 3 == 0 { 255 } else { 0 }];
    }
    lines.save(dir.path().join("lines.png")).unwrap();
    let dropped = "1 of the image's 2 labels has no elements";
    let relabelled = "the clean-up relabelled 33.3 % of the pixels";
    let out = imesh(
        &["mesh", "lines.png", "-o", "out.msh", "--report", "r.json"],
        dir.path(),
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{said}");
    assert!(said.contains("30×30 px, 2 labels"), "{said}");
    assert!(
        said.contains(dropped) && said.contains(relabelled),
        "{said}"
    );
    assert!(
        said.contains("--majority 0 --min-width 0 --min-part-width 0"),
        "{said}"
    );
    let report: serde_json::Value = read_report(dir.path());
    assert_eq!(report["counts"]["image_labels"], 2);
    assert_eq!(report["counts"]["meshed_labels"], 1);
    let out = imesh(
        &[
            "mesh",
            "lines.png",
            "-o",
            "out.msh",
            "--majority",
            "0",
            "--min-width",
            "0",
            "--min-part-width",
            "0",
        ],
        dir.path(),
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{said}");
    assert!(
        !said.contains("has no elements") && !said.contains("relabelled"),
        "{said}"
    );
    save_square(&dir.path().join("square.png"), 6..18);
    let out = imesh(&["mesh", "square.png", "-o", "out.msh"], dir.path());
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && said.contains("2 labels") && !said.contains("no elements"),
        "{said}"
    );
}

#[test]
fn order_two_writes_quadratic_elements_and_says_what_bent() {
    let dir = tempfile::tempdir().unwrap();
    let image = fixture("skimage-coins.png");
    let out = imesh_ok(
        &[
            "mesh",
            image.to_str().unwrap(),
            "--order",
            "2",
            "-o",
            "c.inp",
            "--report",
            "r.json",
        ],
        dir.path(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let report: serde_json::Value = read_report(dir.path());
    let c = &report["counts"];
    assert_eq!(report["options"]["order"], 2);
    let note = format!(
        "second order: {} nodes; {} sides bent along the boundary curves",
        c["nodes"], c["curved_sides"]
    );
    assert!(stdout.contains(&note), "{stdout}");
    let inp = std::fs::read_to_string(dir.path().join("c.inp")).unwrap();
    // 8-node quads: an id and eight nodes per element line.
    let lines: Vec<&str> = inp.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("*Element, type=CPS8"))
        .unwrap();
    assert_eq!(lines[at + 1].split(", ").count(), 9);
    assert!(!inp.contains("type=CPS4"));
}
