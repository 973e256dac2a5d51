//! VTK XML unstructured grid (`.vtu`, ASCII), with a label and any extra values per cell.

use std::fmt::Write as _;
use std::path::Path;

use crate::vtk::{vtk_node_count, vtk_type};
use crate::{check, push_lines, write_atomic, written_nodes, Frame, SegmentedMeshData, WriteError};

/// The `.vtu` text of `mesh`, with cell data `label` and each `(name, values)` of `cell_data`.
pub fn vtu_string(
    mesh: &SegmentedMeshData,
    frame: &Frame,
    cell_data: &[(String, Vec<f64>)],
) -> String {
    let mut s = String::new();
    let (n, m) = (mesh.node_count(), mesh.elements.len());
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{m}\">"
    );
    let _ = writeln!(
        s,
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    );
    push_lines(&mut s, n, |i, s| {
        let q = frame.map(mesh, mesh.node(i));
        let _ = writeln!(s, "{} {} 0", q[0], q[1]);
    });
    let _ = writeln!(s, "</DataArray>\n</Points>\n<Cells>");
    let _ = writeln!(
        s,
        "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    );
    push_lines(&mut s, m, |i, s| {
        for (k, v) in written_nodes(mesh, i, true).into_iter().enumerate() {
            let _ = write!(s, "{}{v}", if k == 0 { "" } else { " " });
        }
        s.push('\n');
    });
    let _ = writeln!(
        s,
        "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    );
    let mut offset = 0;
    for e in &mesh.elements {
        offset += vtk_node_count(mesh, e);
        let _ = writeln!(s, "{offset}");
    }
    let _ = writeln!(
        s,
        "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    );
    for e in &mesh.elements {
        let _ = writeln!(s, "{}", vtk_type(mesh, e));
    }
    let _ = writeln!(s, "</DataArray>\n</Cells>\n<CellData Scalars=\"label\">");
    let _ = writeln!(
        s,
        "<DataArray type=\"Int32\" Name=\"label\" format=\"ascii\">"
    );
    for l in &mesh.labels {
        let _ = writeln!(s, "{l}");
    }
    let _ = writeln!(s, "</DataArray>");
    for (name, values) in cell_data {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">",
            xml_escape(name)
        );
        for v in values {
            let _ = writeln!(s, "{v}");
        }
        let _ = writeln!(s, "</DataArray>");
    }
    let _ = writeln!(s, "</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>");
    s
}

/// Writes `mesh` as a VTK XML unstructured grid, atomically.
///
/// # Errors
/// [`WriteError`] when the mesh or the cell data are inconsistent or the file cannot be written.
pub fn write_vtu(
    path: &Path,
    mesh: &SegmentedMeshData,
    frame: &Frame,
    cell_data: &[(String, Vec<f64>)],
) -> Result<(), WriteError> {
    check(path, mesh)?;
    check_cell_data(path, mesh, cell_data)?;
    write_atomic(path, vtu_string(mesh, frame, cell_data).as_bytes())
}

/// Refuses cell data without exactly one value per element.
pub(crate) fn check_cell_data(
    path: &Path,
    mesh: &SegmentedMeshData,
    cell_data: &[(String, Vec<f64>)],
) -> Result<(), WriteError> {
    match cell_data
        .iter()
        .find(|(_, v)| v.len() != mesh.elements.len())
    {
        Some((name, _)) => Err(WriteError::Invalid {
            path: path.to_path_buf(),
            reason: format!("cell data {name} does not have one value per element"),
        }),
        None => Ok(()),
    }
}

pub(crate) fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
