//! Interop: meshio (the Python mesh I/O library most solvers' users have) reads what we write, and
//! Gmsh itself opens our `.msh` files with the same physical groups. `.ci/run` installs meshio and
//! gmsh into `target/venv-io` and points `IMESH_PYTHON` at its Python; run locally the same way,
//! or the tests say how and pass without checking.

use std::path::Path;
use std::process::Command;

mod support;

use support::program::{
    assert_same_statistics, imesh_ok, quality_block, quality_json, read_report,
};

/// The sides of the domain, as the writers name them.
const SIDES: [&str; 4] = ["left", "right", "bottom", "top"];

/// The strings of a JSON array.
fn strings(array: &serde_json::Value) -> Vec<&str> {
    array
        .as_array()
        .expect("an array")
        .iter()
        .map(|n| n.as_str().expect("a string"))
        .collect()
}

/// What `tests/scripts/SCRIPT` prints (JSON) about `file`, run by `python`.
fn python_json(python: &str, script: &str, file: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/scripts")
        .join(script);
    let out = Command::new(python)
        .arg(&script)
        .arg(file)
        .output()
        .expect("the Python of IMESH_PYTHON runs");
    assert!(
        out.status.success(),
        "{} could not read {}: {}",
        script.display(),
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the script prints JSON")
}

/// Runs `imesh` with `args` and `--report r.json -q` in `dir`; the report.
fn mesh_with_report(dir: &Path, args: &[&str]) -> serde_json::Value {
    imesh_ok(&[args, &["--report", "r.json", "-q"]].concat(), dir);
    read_report(dir)
}

#[test]
fn meshio_reads_every_format_we_write() {
    let Ok(python) = std::env::var("IMESH_PYTHON") else {
        eprintln!("IMESH_PYTHON is not set: skipping the meshio check (.ci/run sets it up: python3 -m venv target/venv-io && target/venv-io/bin/pip install meshio)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let fixtures = [
        ("pyvista-channels_z050_labels.png", 250.0, 250.0),
        ("stardist-mask2d_labels.png", 512.0, 512.0),
    ];
    for (fixture, width, height) in fixtures {
        let image = support::fixture(fixture);
        for (name, pixel, version) in [
            ("m.msh", "1", "4.1"),
            ("m22.msh", "1", "2.2"),
            ("m.vtu", "0.5", ""),
            ("m.vtk", "2", ""),
            ("m.inp", "1", ""),
        ] {
            let version: &[&str] = if version.is_empty() {
                &[]
            } else {
                &["--msh-version", version]
            };
            let mut args = vec!["mesh", image.to_str().unwrap(), "-o", name];
            args.extend(["--pixel-size", pixel]);
            args.extend(version);
            let report = mesh_with_report(dir.path(), &args);
            let what = format!("{fixture} {name}");
            let read = python_json(&python, "read_mesh.py", &dir.path().join(name));
            assert_eq!(read["points"], report["counts"]["vertices"], "{what}");
            // The default mesh is all quads.
            assert_eq!(read["cells"]["quad"], report["counts"]["quads"], "{what}");
            assert_eq!(
                read["cells"]["quad"], report["counts"]["elements"],
                "{what}"
            );
            assert!(read["cells"]["triangle"].is_null(), "{what}: no triangles");
            assert_eq!(
                read["negative"], 0,
                "{what}: clockwise elements in the written frame"
            );
            let s: f64 = pixel.parse().unwrap();
            let want = width * height * s * s;
            assert!(
                (read["area"].as_f64().unwrap() - want).abs() < 1e-6 * want,
                "{what}: area {}",
                read["area"]
            );
            let labels = report["counts"]["meshed_labels"].as_u64().unwrap();
            let count = |key: &str| read[key].as_array().unwrap().len() as u64;
            if name.ends_with(".msh") {
                assert_eq!(count("physical"), labels, "{what}");
                // Named surfaces, and named curves for the boundaries, the border among them.
                let names = strings(&read["names"]);
                assert!(names.len() as u64 > labels, "{what}: {names:?}");
                assert!(names.iter().any(|n| n.starts_with("border_")), "{what}");
                assert!(read["cells"]["line"].as_u64().unwrap() > 0, "{what}");
                // Where meshio keeps one group per line, a border line keeps its side: the
                // lines' groups are the sides and the boundaries between labels.
                let line_groups = strings(&read["line_groups"]);
                for side in SIDES {
                    assert!(line_groups.contains(&side), "{what}: {line_groups:?}");
                }
                if name == "m.msh" {
                    assert!(
                        line_groups.iter().all(|n| !n.starts_with("border_")),
                        "{what}: {line_groups:?}"
                    );
                }
            } else if name.ends_with(".inp") {
                // An element set per label, and per side of the domain those of the faces of
                // its surface; a node set per side.
                let sets = strings(&read["cell_sets"]);
                let is_face_set = |n: &str| {
                    SIDES
                        .iter()
                        .any(|side| n.strip_prefix(side).is_some_and(|f| f.starts_with("_S")))
                };
                let label_sets = sets.iter().filter(|n| !is_face_set(n)).count();
                assert_eq!(label_sets as u64, labels, "{what}: {sets:?}");
                for side in SIDES {
                    assert!(
                        sets.iter().any(|n| n.starts_with(&format!("{side}_S"))),
                        "{what}: {side}"
                    );
                    assert!(
                        strings(&read["point_sets"]).contains(&side),
                        "{what}: {side}"
                    );
                }
            } else {
                // Every label the elements carry, each a label of the grid.
                assert_eq!(count("labels"), labels, "{what}");
                let of_grid = report["counts"]["labels"].as_u64().unwrap();
                assert!(
                    read["labels"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .all(|l| l.as_u64().is_some_and(|l| l < of_grid)),
                    "{what}"
                );
            }
        }
    }
}

#[test]
fn imesh_quality_reads_what_meshio_writes() {
    let Ok(python) = std::env::var("IMESH_PYTHON") else {
        eprintln!("IMESH_PYTHON is not set: skipping the meshio check (.ci/run sets it up)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let image = support::fixture("skimage-coins.png");
    for elements in ["quad", "tri"] {
        let name = format!("{elements}.msh");
        mesh_with_report(
            dir.path(),
            &[
                "mesh",
                image.to_str().unwrap(),
                "-o",
                &name,
                "--elements",
                elements,
            ],
        );
        let ours = quality_json(dir.path(), &name);
        let written = python_json(&python, "meshio_write.py", &dir.path().join(&name));
        for format in ["vtu", "inp"] {
            let file = written[format].as_str().unwrap();
            let theirs = quality_json(dir.path(), file);
            for key in ["vertices", "quads", "triangles"] {
                assert_eq!(theirs[key], ours[key], "{file} {key}");
            }
            // meshio writes ASCII coordinates to about 12 significant digits.
            let block = quality_block(elements);
            assert_same_statistics(&theirs[block], &ours[block], 1e-6, file);
        }
    }
}

#[test]
fn gmsh_opens_our_msh_with_the_same_physical_groups() {
    let Ok(python) = std::env::var("IMESH_PYTHON") else {
        eprintln!("IMESH_PYTHON is not set: skipping the Gmsh check (.ci/run sets it up: python3 -m venv target/venv-io && target/venv-io/bin/pip install gmsh)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for (fixture, version) in [
        ("stardist-mask2d_labels.png", "4.1"),
        ("skimage-coins.png", "4.1"),
        ("skimage-coins.png", "2.2"),
    ] {
        let fixture_name = fixture;
        let fixture = format!("{fixture_name} (MSH {version})");
        let image = support::fixture(fixture_name);
        let args = ["mesh", image.to_str().unwrap(), "-o", "m.msh"];
        let report = mesh_with_report(
            dir.path(),
            &[&args[..], &["--msh-version", version]].concat(),
        );
        // Gmsh opens it (or the script fails, and says why).
        let seen = python_json(&python, "gmsh_read.py", &dir.path().join("m.msh"));
        assert_eq!(seen["nodes"], report["counts"]["vertices"], "{fixture}");
        assert_eq!(
            seen["elements"]["Quadrilateral 4"], report["counts"]["quads"],
            "{fixture}"
        );
        assert!(
            seen["elements"]["Triangle 3"].is_null(),
            "{fixture}: no triangles"
        );
        let groups = seen["groups"].as_array().unwrap();
        let surfaces: Vec<&serde_json::Value> = groups.iter().filter(|g| g["dim"] == 2).collect();
        // One named physical surface per label, together holding every quad once.
        assert_eq!(
            surfaces.len() as u64,
            report["counts"]["meshed_labels"].as_u64().unwrap(),
            "{fixture}"
        );
        assert!(surfaces
            .iter()
            .all(|g| !g["name"].as_str().unwrap().is_empty()));
        let held: u64 = surfaces
            .iter()
            .map(|g| g["elements"].as_u64().unwrap())
            .sum();
        assert_eq!(
            held,
            report["counts"]["quads"].as_u64().unwrap(),
            "{fixture}"
        );
        // Named boundary curves, the domain border among them, with line elements.
        let curves: Vec<&serde_json::Value> = groups.iter().filter(|g| g["dim"] == 1).collect();
        assert!(!curves.is_empty(), "{fixture}");
        assert!(curves
            .iter()
            .any(|g| g["name"].as_str().unwrap().starts_with("border_")));
        assert!(curves.iter().all(|g| g["elements"].as_u64().unwrap() > 0));
        // The four sides of the domain, each a curve of lines whose nodes lie on its line (the
        // written frame: y up, a pixel a unit).
        let (w, h) = (
            report["input"]["width"].as_f64().unwrap(),
            report["input"]["height"].as_f64().unwrap(),
        );
        for (side, axis, at, along) in [
            ("left", "x", 0.0, h),
            ("right", "x", w, h),
            ("bottom", "y", 0.0, w),
            ("top", "y", h, w),
        ] {
            let g = curves
                .iter()
                .find(|g| g["name"] == side)
                .unwrap_or_else(|| panic!("{fixture}: no {side} curve"));
            assert!(g["elements"].as_u64().unwrap() > 0, "{fixture}: {side}");
            assert_eq!(g[axis], serde_json::json!([at, at]), "{fixture}: {side}");
            let across = if axis == "x" { "y" } else { "x" };
            assert_eq!(
                g[across],
                serde_json::json!([0.0, along]),
                "{fixture}: {side}"
            );
        }
    }
}

/// `--order 2`: meshio reads 9-node quads and 3-node boundary lines from MSH 4.1, MSH 2.2 and
/// VTU files, their curved areas sum to the image's, and no quad's Jacobian determinant is
/// anywhere near zero at its Gauss points, as meshio's data and Gmsh's own
/// `getJacobians` give them.
#[test]
fn second_order_files_open_as_valid_curved_quads() {
    let Ok(python) = std::env::var("IMESH_PYTHON") else {
        eprintln!("IMESH_PYTHON is not set: skipping the second-order check (.ci/run sets it up: python3 -m venv target/venv-io && target/venv-io/bin/pip install meshio gmsh)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let image = support::fixture("skimage-coins.png");
    for (name, version) in [("q.msh", "4.1"), ("q22.msh", "2.2"), ("q.vtu", "")] {
        let mut args = vec!["mesh", image.to_str().unwrap(), "--order", "2", "-o", name];
        if !version.is_empty() {
            args.extend(["--msh-version", version]);
        }
        let report = mesh_with_report(dir.path(), &args);
        let seen = python_json(&python, "curved_check.py", &dir.path().join(name));
        assert_eq!(seen["cells"]["quad9"], report["counts"]["quads"], "{name}");
        if version.is_empty() {
            assert!(seen["cells"]["line3"].is_null(), "{name}");
        } else {
            assert!(seen["cells"]["line3"].as_u64().unwrap() > 0, "{name}");
            assert!(seen["cells"]["line"].is_null(), "{name}");
        }
        let area = seen["area"].as_f64().unwrap();
        assert!(
            (area / (384.0 * 303.0) - 1.0).abs() < 1e-9,
            "{name}: {area}"
        );
        // At every Gauss point of every quad the determinant stays well above zero (the
        // straight quads' smallest corner values are about a pixel², and a curved quad keeps
        // half of its straight self's).
        assert!(
            seen["min_jacobian"].as_f64().unwrap() > 0.05,
            "{name}: {seen}"
        );
        if name.ends_with(".msh") {
            assert_eq!(
                seen["gmsh_elements"],
                serde_json::json!(["Quadrilateral 9"])
            );
            // Gmsh's reference square is [−1, 1]²: a quarter of the determinant on ours.
            let gmsh = seen["gmsh_min_jacobian"].as_f64().unwrap();
            assert!(gmsh > 0.05 / 4.0, "{name}: {seen}");
        }
    }
}
