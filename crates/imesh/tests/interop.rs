//! Interop: meshio (the Python mesh I/O library most solvers' users have) reads what we write.
//! `.ci/run` installs meshio into `target/venv-io` and points `IMESH_PYTHON` at its Python; run
//! locally the same way, or the test says how and passes without checking.

use std::path::Path;
use std::process::Command;

fn meshio_read(python: &str, file: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/read_mesh.py");
    let out = Command::new(python)
        .arg(script)
        .arg(file)
        .output()
        .expect("the Python of IMESH_PYTHON runs");
    assert!(
        out.status.success(),
        "meshio could not read {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the script prints JSON")
}

#[test]
fn meshio_reads_our_msh_and_vtu() {
    let Ok(python) = std::env::var("IMESH_PYTHON") else {
        eprintln!("IMESH_PYTHON is not set: skipping the meshio check (.ci/run sets it up: python3 -m venv target/venv-io && target/venv-io/bin/pip install meshio)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let image = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images/pyvista-channels_z050_labels.png");
    for (name, pixel) in [("m.msh", "1"), ("m.vtu", "0.5")] {
        let out = Command::new(env!("CARGO_BIN_EXE_imesh"))
            .args([
                "mesh",
                image.to_str().unwrap(),
                "-o",
                name,
                "--pixel-size",
                pixel,
                "--report",
                "r.json",
                "-q",
            ])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("r.json")).unwrap())
                .unwrap();
        let read = meshio_read(&python, &dir.path().join(name));
        assert_eq!(read["points"], report["counts"]["vertices"], "{name}");
        // The default mesh is all quads.
        assert_eq!(read["cells"]["quad"], report["counts"]["quads"], "{name}");
        assert_eq!(
            read["cells"]["quad"], report["counts"]["elements"],
            "{name}"
        );
        assert!(read["cells"]["triangle"].is_null(), "{name}: no triangles");
        assert_eq!(
            read["negative"], 0,
            "{name}: clockwise elements in the written frame"
        );
        let s: f64 = pixel.parse().unwrap();
        let want = 250.0 * 250.0 * s * s;
        assert!(
            (read["area"].as_f64().unwrap() - want).abs() < 1e-6 * want,
            "{name}: area {}",
            read["area"]
        );
        if name.ends_with(".msh") {
            assert_eq!(read["physical"], serde_json::json!([1, 2, 3, 4, 5]));
            // Five named surfaces, and named curves for the boundaries, the border among them.
            let names: Vec<&str> = read["names"]
                .as_array()
                .unwrap()
                .iter()
                .map(|n| n.as_str().unwrap())
                .collect();
            assert!(names.len() > 5, "{names:?}");
            assert!(names.iter().any(|n| n.starts_with("border_")), "{names:?}");
            assert!(read["cells"]["line"].as_u64().unwrap() > 0);
        } else {
            assert_eq!(read["labels"], serde_json::json!([0, 1, 2, 3, 4]));
        }
    }
}
