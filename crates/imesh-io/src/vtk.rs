//! Legacy VTK (`.vtk`, ASCII unstructured grid) with the label and any extra values per cell.

use std::fmt::Write as _;
use std::path::Path;

use imesh_quality::Element;

use crate::{check, push_lines, write_atomic, written_nodes, Frame, SegmentedMeshData, WriteError};

/// The legacy `.vtk` text of `mesh`, with cell data `label` and each `(name, values)`.
pub fn vtk_string(
    mesh: &SegmentedMeshData,
    frame: &Frame,
    cell_data: &[(String, Vec<f64>)],
) -> String {
    let mut s = String::new();
    let (n, m) = (mesh.node_count(), mesh.elements.len());
    let _ = writeln!(s, "# vtk DataFile Version 3.0\nimesh {}x{} px image\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {n} double", mesh.width, mesh.height);
    push_lines(&mut s, n, |i, s| {
        let q = frame.map(mesh, mesh.node(i));
        let _ = writeln!(s, "{} {} 0", q[0], q[1]);
    });
    let size: usize = mesh
        .elements
        .iter()
        .map(|e| vtk_node_count(mesh, e) + 1)
        .sum();
    let _ = writeln!(s, "CELLS {m} {size}");
    push_lines(&mut s, m, |i, s| {
        let c = written_nodes(mesh, i, true);
        let _ = write!(s, "{}", c.len());
        for v in c {
            let _ = write!(s, " {v}");
        }
        s.push('\n');
    });
    let _ = writeln!(s, "CELL_TYPES {m}");
    for e in &mesh.elements {
        let _ = writeln!(s, "{}", vtk_type(mesh, e));
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

/// VTK's cell type: triangle 5, quad 9; second order, quadratic triangle 22, biquadratic
/// (9-node) quad 28.
pub(crate) fn vtk_type(mesh: &SegmentedMeshData, e: &Element) -> u8 {
    match (e, mesh.second_order.is_some()) {
        (Element::Triangle(_), false) => 5,
        (Element::Quad(_), false) => 9,
        (Element::Triangle(_), true) => 22,
        (Element::Quad(_), true) => 28,
    }
}

/// The nodes of a VTK cell of element `e`: its corners, and in a second-order mesh its sides'
/// middles and a quad's centre.
pub(crate) fn vtk_node_count(mesh: &SegmentedMeshData, e: &Element) -> usize {
    let n = e.corners().len();
    match mesh.second_order {
        None => n,
        Some(_) => 2 * n + usize::from(n == 4),
    }
}
