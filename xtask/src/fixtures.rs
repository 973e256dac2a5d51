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

/// `fixtures/images`.
pub fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/images")
}

/// Every fixture image (`fixtures/images/*.png`), in name order.
pub fn fixture_images() -> Result<Vec<PathBuf>, String> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(fixtures_dir())
        .map_err(|e| format!("fixtures/images: {e}"))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    paths.sort();
    Ok(paths)
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
    // The probe's own error (a Python traceback when the package is missing) says nothing the
    // line below does not.
    let ready = Command::new(&python)
        .args(["-c", check])
        .stderr(std::process::Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !ready {
        eprintln!("installing {requirement} into {}", venv.display());
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

/// Whether `new` differs from what `path` held, as a word for the report.
fn change(path: &Path, new: &[u8]) -> &'static str {
    match std::fs::read(path) {
        Err(_) => "new",
        Ok(old) if old == new => "unchanged",
        Ok(_) => "CHANGED",
    }
}

/// The label of pixel `(col, row)` of the synthetic 64 × 64 image behind
/// `points/disc-boundary.txt`: 1 inside the disc (centre (30.3, 33.7), radius 21) but outside
/// the elliptic hole (centre (36, 30), semi-axes 7 and 4.5), tested at the pixel's centre.
fn disc_label(col: i32, row: i32) -> u8 {
    let (x, y) = (f64::from(col) + 0.5, f64::from(row) + 0.5);
    let disc = (x - 30.3).powi(2) + (y - 33.7).powi(2) <= 21.0 * 21.0;
    let hole = ((x - 36.0) / 7.0).powi(2) + ((y - 30.0) / 4.5).powi(2) <= 1.0;
    u8::from(disc && !hole)
}

/// The text of `fixtures/points/disc-boundary.txt`: the four domain corners, then the centre
/// of every pixel with a 4-neighbour of the other label, row by row.
fn disc_boundary() -> String {
    let mut text = String::from(
        "# Label-boundary pixel centres of a 64x64 synthetic image (a disc with an elliptic hole),\n\
         # plus the four domain corners. One point per line: x y (pixels, y down).\n\
         0 0\n64 0\n64 64\n0 64\n",
    );
    let inside = |c: i32, r: i32| (0..64).contains(&c) && (0..64).contains(&r);
    for row in 0..64 {
        for col in 0..64 {
            let l = disc_label(col, row);
            let boundary = [(-1, 0), (1, 0), (0, -1), (0, 1)]
                .iter()
                .any(|&(dc, dr)| inside(col + dc, row + dr) && disc_label(col + dc, row + dr) != l);
            if boundary {
                text.push_str(&format!(
                    "{} {}\n",
                    f64::from(col) + 0.5,
                    f64::from(row) + 0.5
                ));
            }
        }
    }
    text
}

/// `cargo xtask fixtures points`: regenerates `fixtures/points/disc-boundary.txt`.
pub fn points() -> Result<(), String> {
    let path = workspace_root()?.join("fixtures/points/disc-boundary.txt");
    let text = disc_boundary();
    let state = change(&path, text.as_bytes());
    std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    println!("fixtures/points/disc-boundary.txt: {state}");
    Ok(())
}

/// `cargo xtask fixtures`: regenerates everything under `fixtures/` this project derives (the
/// synthetic point set and the Verdict reference tables) and says what changed. The images are
/// byte-for-byte copies of `../shared/fixtures/` (see fixtures/README.md), not derived here.
pub fn all() -> Result<(), String> {
    points()?;
    quality()
}
