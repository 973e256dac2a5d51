//! Legacy VTK (`.vtk`, ASCII unstructured grid) with the label and any extra values per cell.

use std::fmt::Write as _;
use std::path::Path;

use imesh_quality::Element;

use crate::{
    check, push_lines, write_atomic, written_corners, Frame, SegmentedMeshData, WriteError,
};

/// The legacy `.vtk` text of `mesh`, with cell data `label` and each `(name, values)`.
pub fn vtk_string(
    mesh: &SegmentedMeshData,
    frame: &Frame,
    cell_data: &[(String, Vec<f64>)],
) -> String {
    let mut s = String::new();
    let (n, m) = (mesh.vertices.len(), mesh.elements.len());
    let _ = writeln!(s, "# vtk DataFile Version 3.0\nimesh {}x{} px image\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {n} double", mesh.width, mesh.height);
    push_lines(&mut s, n, |i, s| {
        let q = frame.map(mesh, mesh.vertices[i]);
        let _ = writeln!(s, "{} {} 0", q[0], q[1]);
    });
    let size: usize = mesh.elements.iter().map(|e| e.corners().len() + 1).sum();
    let _ = writeln!(s, "CELLS {m} {size}");
    push_lines(&mut s, m, |i, s| {
        let c = written_corners(&mesh.elements[i]);
        let _ = write!(s, "{}", c.len());
        for v in c {
            let _ = write!(s, " {v}");
        }
        s.push('\n');
    });
    let _ = writeln!(s, "CELL_TYPES {m}");
    for e in &mesh.elements {
        let _ = writeln!(
            s,
            "{}",
            match e {
                Element::Triangle(_) => 5,
                Element::Quad(_) => 9,
            }
        );
    }
    let _ = writeln!(
        s,
        "CELL_DATA {m}\nSCALARS label int 1\nLOOKUP_TABLE default"
    );
    for l in &mesh.labels {
        let _ = writeln!(s, "{l}");
    }
    for (name, values) in cell_data {
        let _ = writeln!(
            s,
            "SCALARS {} double 1\nLOOKUP_TABLE default",
            crate::boundary::sanitize(name)
        );
        for v in values {
            let _ = writeln!(s, "{v}");
        }
    }
    s
}

/// Writes `mesh` as a legacy VTK file, atomically.
///
/// # Errors
/// [`WriteError`] when the mesh or the cell data are inconsistent or the file cannot be written.
pub fn write_vtk(
    path: &Path,
    mesh: &SegmentedMeshData,
    frame: &Frame,
    cell_data: &[(String, Vec<f64>)],
) -> Result<(), WriteError> {
    check(path, mesh)?;
    crate::vtu::check_cell_data(path, mesh, cell_data)?;
    write_atomic(path, vtk_string(mesh, frame, cell_data).as_bytes())
}
