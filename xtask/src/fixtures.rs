//! `cargo xtask fixtures quality`: regenerates the Verdict reference table with VTK itself.
//!
//! VTK comes from PyPI into a virtual environment under `target/` (never the system Python), pinned
//! to the version the reference notes were checked against.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The VTK release whose `vtkMeshQuality` defines the expected values.
const VTK_VERSION: &str = "9.7.2";
/// The files the script writes under `fixtures/quality/`.
const OUTPUTS: [&str; 2] = ["verdict-quads.csv", "verdict-triangles.csv"];

pub fn workspace_root() -> Result<PathBuf, String> {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .ok_or_else(|| "xtask is not inside the workspace".to_string())
}

fn run(cmd: &mut Command, what: &str) -> Result<(), String> {
    let status = cmd
        .status()
        .map_err(|e| format!("{what}: cannot start {:?}: {e}", cmd.get_program()))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed ({status})"))
    }
}

/// A virtual environment under `target/` with `vtk` installed; returns its Python.
fn vtk_python(root: &Path) -> Result<PathBuf, String> {
    venv_python(
        root,
        "venv-vtk",
        &format!("import vtk, sys; sys.exit(vtk.vtkVersion.GetVTKVersion() != '{VTK_VERSION}')"),
        &format!("vtk=={VTK_VERSION}"),
    )
}

/// The Python of `target/<venv>`, created if needed, with `requirement` installed from PyPI
/// unless `check` (a Python snippet) already succeeds.
pub fn venv_python(
    root: &Path,
    venv: &str,
    check: &str,
    requirement: &str,
) -> Result<PathBuf, String> {
    let venv = root.join("target").join(venv);
    let python = venv.join("bin").join("python");
    if !python.exists() {
        run(
            Command::new("python3").arg("-m").arg("venv").arg(&venv),
            "creating a Python virtual environment (is python3 with venv installed?)",
        )?;
    }
    let ready = Command::new(&python)
        .args(["-c", check])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !ready {
        run(
            Command::new(&python).args(["-m", "pip", "install", "--quiet", requirement]),
            &format!("installing {requirement} from PyPI (is PyPI reachable?)"),
        )?;
    }
    Ok(python)
}

pub fn quality() -> Result<(), String> {
    let root = workspace_root()?;
    let out = root.join("fixtures").join("quality");
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let before: Vec<Option<Vec<u8>>> = OUTPUTS
        .iter()
        .map(|f| std::fs::read(out.join(f)).ok())
        .collect();
    let python = vtk_python(&root)?;
    run(
        Command::new(&python)
            .arg(
                root.join("xtask")
                    .join("scripts")
                    .join("verdict_reference.py"),
            )
            .arg(&out),
        "running xtask/scripts/verdict_reference.py",
    )?;
    for (name, old) in OUTPUTS.iter().zip(before) {
        let new =
            std::fs::read(out.join(name)).map_err(|e| format!("{name} was not written: {e}"))?;
        let state = match old {
            None => "new",
            Some(old) if old == new => "unchanged",
            Some(_) => "CHANGED",
        };
        println!("fixtures/quality/{name}: {state}");
    }
    Ok(())
}
