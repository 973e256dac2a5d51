//! Abaqus `.inp`: nodes, CPS3/CPS4 elements (CPS6/CPS8 in a second-order mesh: Abaqus has no
//! 9-node plane quad, and the quads' centre nodes are left out) with an element set per label, a node set per
//! boundary (between two labels, and the domain border per label), and per side of the domain
//! (`left`, `right`, `bottom`, `top`) a node set and an element-based surface
//! (`left_surface`, ...) for boundary conditions and loads.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use crate::boundary::{boundaries, sanitize, Side};
use crate::{check, push_lines, write_atomic, written_nodes, Frame, SegmentedMeshData, WriteError};

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
    // The quads' centre nodes come last, and no Abaqus element uses them.
    let nodes = mesh.vertices.len() + mesh.second_order.as_ref().map_or(0, |s| s.edges.len());
    push_lines(&mut s, nodes, |i, s| {
        let q = frame.map(mesh, mesh.node(i));
        let _ = writeln!(s, "{}, {}, {}", i + 1, q[0], q[1]);
    });
    // Per label, its triangles and its quads, in one pass over the elements.
    let mut members: Vec<[Vec<usize>; 2]> = vec![Default::default(); mesh.label_names.len()];
    for (i, (e, &l)) in mesh.elements.iter().zip(&mesh.labels).enumerate() {
        if let Some(m) = members.get_mut(l as usize) {
            m[usize::from(e.corners().len() == 4)].push(i);
        }
    }
    // Each element's number in the file: by label, then kind.
    let mut number = vec![0usize; mesh.elements.len()];
    let mut tag = 0usize;
    for (name, kinds) in mesh.label_names.iter().zip(&members) {
        let names = match mesh.second_order {
            None => ["CPS3", "CPS4"],
            Some(_) => ["CPS6", "CPS8"],
        };
        for (kind, members) in names.into_iter().zip(kinds) {
            if members.is_empty() {
                continue;
            }
            let _ = writeln!(s, "*Element, type={kind}, elset={}", sanitize(name));
            for &i in members {
                tag += 1;
                number[i] = tag;
                let ids: Vec<String> = written_nodes(mesh, i, false)
                    .iter()
                    .map(|v| (v + 1).to_string())
                    .collect();
                let _ = writeln!(s, "{tag}, {}", ids.join(", "));
            }
        }
    }
    let curves = boundaries(mesh);
    let node_set = |s: &mut String, name: &str, vertices: &[u32]| {
        let _ = writeln!(s, "*Nset, nset={name}");
        let ids: Vec<usize> = vertices.iter().map(|&v| v as usize + 1).collect();
        write_ids(s, &ids);
    };
    for b in &curves {
        node_set(&mut s, &b.name(mesh), &mesh.edge_nodes(&b.edges));
    }
    // The sides of the domain, for boundary conditions: a node set each, and an element-based
    // surface (the element faces along it, by face number) for loads.
    let mut sides: [Vec<[u32; 2]>; 4] = Default::default();
    for b in &curves {
        for (all, edges) in sides.iter_mut().zip(b.sides(mesh)) {
            all.extend(edges);
        }
    }
    let faces = side_faces(mesh, &sides);
    for ((side, edges), faces) in Side::ALL.into_iter().zip(&sides).zip(faces) {
        if edges.is_empty() {
            continue;
        }
        node_set(&mut s, side.name(), &mesh.edge_nodes(edges));
        // Per face number, the elements with that face on the side.
        let mut by_face: [Vec<usize>; 4] = Default::default();
        for (element, face) in faces {
            by_face[face].push(number[element]);
        }
        by_face.iter_mut().for_each(|e| e.sort_unstable());
        for (face, elements) in by_face.iter().enumerate() {
            if elements.is_empty() {
                continue;
            }
            let _ = writeln!(s, "*Elset, elset={}_S{}", side.name(), face + 1);
            write_ids(&mut s, elements);
        }
        let _ = writeln!(s, "*Surface, type=ELEMENT, name={}_surface", side.name());
        for (face, elements) in by_face.iter().enumerate() {
            if !elements.is_empty() {
                let _ = writeln!(s, "{}_S{}, S{}", side.name(), face + 1, face + 1);
            }
        }
    }
    s
}

/// Writes `ids` sixteen to a line (the most an Abaqus data line holds).
fn write_ids(s: &mut String, ids: &[usize]) {
    for chunk in ids.chunks(16) {
        let line: Vec<String> = chunk.iter().map(|id| id.to_string()).collect();
        let _ = writeln!(s, "{}", line.join(", "));
    }
}

/// Per side of the domain (its border edges `sides`, [`Side::ALL`] order), the elements with a
/// face on it and that face's number less one (Abaqus numbers faces from the first written
/// corner: face k runs from corner k to the next).
fn side_faces(mesh: &SegmentedMeshData, sides: &[Vec<[u32; 2]>; 4]) -> [Vec<(usize, usize)>; 4] {
    let mut side_of: HashMap<[u32; 2], usize> = HashMap::new();
    let mut on_border = vec![false; mesh.vertices.len()];
    for (k, edges) in sides.iter().enumerate() {
        for &[a, b] in edges {
            side_of.insert([a.min(b), a.max(b)], k);
            on_border[a as usize] = true;
            on_border[b as usize] = true;
        }
    }
    let mut faces: [Vec<(usize, usize)>; 4] = Default::default();
    for (i, e) in mesh.elements.iter().enumerate() {
        let c = e.corners();
        let n = c.len();
        for k in 0..n {
            let (a, b) = (c[k], c[(k + 1) % n]);
            // Only a face with both ends on the border can be on it.
            if on_border[a as usize] && on_border[b as usize] {
                if let Some(&side) = side_of.get(&[a.min(b), a.max(b)]) {
                    // The written corners run the other way from the first ([`written_corners`]):
                    // corner k's side to the next is the written face n − 1 − k.
                    faces[side].push((i, n - 1 - k));
                }
            }
        }
    }
    faces
}

/// Writes `mesh` as an Abaqus input file, atomically.
///
/// # Errors
/// [`WriteError`] when the mesh is inconsistent or the file cannot be written.
pub fn write_inp(path: &Path, mesh: &SegmentedMeshData, frame: &Frame) -> Result<(), WriteError> {
    check(path, mesh)?;
    write_atomic(path, inp_string(mesh, frame).as_bytes())
}
