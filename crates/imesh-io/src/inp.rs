//! Abaqus `.inp`: nodes, CPS3/CPS4 elements with an element set per label, and a node set per
//! boundary (between two labels, and the domain border per label).

use std::fmt::Write as _;
use std::path::Path;

use imesh_quality::Element;

use crate::boundary::{boundaries, sanitize};
use crate::{
    check, push_lines, write_atomic, written_corners, Frame, SegmentedMeshData, WriteError,
};

/// The `.inp` text of `mesh`.
pub fn inp_string(mesh: &SegmentedMeshData, frame: &Frame) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "*Heading\nimesh: {}x{} px image, {} elements\n*Node",
        mesh.width,
        mesh.height,
        mesh.elements.len()
    );
    push_lines(&mut s, mesh.vertices.len(), |i, s| {
        let q = frame.map(mesh, mesh.vertices[i]);
        let _ = writeln!(s, "{}, {}, {}", i + 1, q[0], q[1]);
    });
    let mut tag = 0usize;
    for (l, name) in mesh.label_names.iter().enumerate() {
        for (kind, corners) in [("CPS3", 3usize), ("CPS4", 4)] {
            let members: Vec<&Element> = mesh
                .elements
                .iter()
                .zip(&mesh.labels)
                .filter(|(e, &m)| m as usize == l && e.corners().len() == corners)
                .map(|(e, _)| e)
                .collect();
            if members.is_empty() {
                continue;
            }
            let _ = writeln!(s, "*Element, type={kind}, elset={}", sanitize(name));
            for e in members {
                tag += 1;
                let ids: Vec<String> = written_corners(e)
                    .iter()
                    .map(|v| (v + 1).to_string())
                    .collect();
                let _ = writeln!(s, "{tag}, {}", ids.join(", "));
            }
        }
    }
    for b in boundaries(mesh) {
        let _ = writeln!(s, "*Nset, nset={}", b.name(mesh));
        for chunk in b.vertices().chunks(16) {
            let ids: Vec<String> = chunk.iter().map(|v| (v + 1).to_string()).collect();
            let _ = writeln!(s, "{}", ids.join(", "));
        }
    }
    s
}

/// Writes `mesh` as an Abaqus input file, atomically.
///
/// # Errors
/// [`WriteError`] when the mesh is inconsistent or the file cannot be written.
pub fn write_inp(path: &Path, mesh: &SegmentedMeshData, frame: &Frame) -> Result<(), WriteError> {
    check(path, mesh)?;
    write_atomic(path, inp_string(mesh, frame).as_bytes())
}
