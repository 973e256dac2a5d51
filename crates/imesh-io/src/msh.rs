//! Gmsh MSH 4.1 ASCII (and 2.2 for older readers): a named physical surface per label, and named
//! physical curves for the boundaries and the sides of the domain.

use std::fmt::Write as _;
use std::path::Path;

use imesh_quality::Element;

use crate::boundary::{boundaries, edge_vertices, Boundary, Side, OUTSIDE};
use crate::{check, push_lines, write_atomic, written_nodes, Frame, SegmentedMeshData, WriteError};

/// The MSH 4.1 text of `mesh`: nodes (all in one block), then one element block per label,
/// each on its own surface entity carrying the physical surface `label + 1` named after the
/// label, then the boundary edges as lines: a named physical curve per side of the domain
/// (`left`, `right`, `bottom`, `top`: tags 1 to 4), for boundary conditions, and one per
/// boundary (between two labels, or between a label and the domain border, tags from 5). A
/// boundary between labels is one curve entity; a label's border is one per side it runs along,
/// in both its physical curves, the side's first and with the smaller tag: a reader that keeps
/// one group per line (meshio's `gmsh:physical` keeps the first) keeps the side.
pub fn msh_string(mesh: &SegmentedMeshData, frame: &Frame) -> String {
    let mut s = String::new();
    // Writing to a String cannot fail; the results are ignored on purpose.
    let _ = writeln!(s, "$MeshFormat\n4.1 0 8\n$EndMeshFormat");
    let groups = Groups::of(mesh);
    groups.write_names(mesh, &mut s);
    let Groups { used, entities, .. } = &groups;
    let mapped: Vec<[f64; 2]> = (0..mesh.node_count())
        .map(|i| frame.map(mesh, mesh.node(i)))
        .collect();
    let (lo, hi) = bounds(&mapped);
    let _ = writeln!(s, "$Entities\n0 {} {} 0", entities.len(), used.len());
    for (j, (i, side, edges)) in entities.iter().enumerate() {
        let ends: Vec<[f64; 2]> = edge_vertices(edges)
            .iter()
            .map(|&v| mapped[v as usize])
            .collect();
        let (clo, chi) = bounds(&ends);
        let tags = Groups::physical_tags(*i, *side);
        let physical: Vec<String> = tags.iter().map(|t| t.to_string()).collect();
        let physical = format!("{} {}", tags.len(), physical.join(" "));
        let _ = writeln!(
            s,
            "{} {} {} 0 {} {} 0 {physical} 0",
            j + 1,
            clo[0],
            clo[1],
            chi[0],
            chi[1],
        );
    }
    for &l in used {
        let _ = writeln!(
            s,
            "{} {} {} 0 {} {} 0 1 {} 0",
            l + 1,
            lo[0],
            lo[1],
            hi[0],
            hi[1],
            l + 1
        );
    }
    let _ = writeln!(s, "$EndEntities");
    let n = mapped.len();
    let entity = used.first().map_or(1, |&l| l + 1);
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 {entity} 0 {n}");
    push_lines(&mut s, n, |i, s| {
        let _ = writeln!(s, "{}", i + 1);
    });
    push_lines(&mut s, n, |i, s| {
        let _ = writeln!(s, "{} {} 0", mapped[i][0], mapped[i][1]);
    });
    let _ = writeln!(s, "$EndNodes");
    // Blocks: per label, per element type (triangles first), in one pass over the elements.
    let labels = used.iter().max().map_or(0, |&l| l as usize + 1);
    let mut members: Vec<[Vec<usize>; 2]> = vec![Default::default(); labels];
    for (i, (e, &l)) in mesh.elements.iter().zip(&mesh.labels).enumerate() {
        members[l as usize][usize::from(matches!(e, Element::Quad(_)))].push(i);
    }
    let mut blocks: Vec<(u32, u32, Vec<usize>)> = Vec::new();
    let kinds = [false, true].map(|quad| gmsh_type(mesh, quad));
    for &l in used {
        for (kind, members) in kinds
            .into_iter()
            .zip(std::mem::take(&mut members[l as usize]))
        {
            if !members.is_empty() {
                blocks.push((l, kind, members));
            }
        }
    }
    let lines: usize = entities.iter().map(|e| e.2.len()).sum();
    let m = mesh.elements.len() + lines;
    let _ = writeln!(s, "$Elements\n{} {m} 1 {m}", blocks.len() + entities.len());
    let mut tag = 1usize;
    for (l, kind, members) in &blocks {
        let _ = writeln!(s, "2 {} {kind} {}", l + 1, members.len());
        push_lines(&mut s, members.len(), |k, s| {
            let _ = write!(s, "{}", tag + k);
            for v in written_nodes(mesh, members[k], true) {
                let _ = write!(s, " {}", v + 1);
            }
            s.push('\n');
        });
        tag += members.len();
    }
    // Boundary edges as lines on their curve entities: 2-node (type 1), or 3-node (type 8,
    // the middle last) in a second-order mesh.
    for (j, (_, _, edges)) in entities.iter().enumerate() {
        let _ = writeln!(s, "1 {} {} {}", j + 1, line_type(mesh), edges.len());
        for &e in edges {
            let _ = writeln!(s, "{tag} {}", line_nodes(mesh, e));
            tag += 1;
        }
    }
    let _ = writeln!(s, "$EndElements");
    s
}

/// The physical groups of a mesh's MSH file, and the curve entities that carry the curves.
struct Groups {
    /// The labels the elements carry (a physical surface each, tag `label + 1`).
    used: Vec<u32>,
    /// The boundaries (a physical curve each, tags after the sides').
    curves: Vec<Boundary>,
    /// The curve entities: its boundary, its side of the domain if on the border, its edges.
    entities: Vec<(usize, Option<Side>, Vec<[u32; 2]>)>,
    /// The sides of the domain with edges (a physical curve each, tags 1 to 4 in
    /// [`Side::ALL`] order).
    sides: Vec<Side>,
}

impl Groups {
    /// A boundary between labels is one curve entity; a label's border is one per side of
    /// the domain it runs along.
    fn of(mesh: &SegmentedMeshData) -> Self {
        let curves = boundaries(mesh);
        let mut entities = Vec::new();
        for (i, b) in curves.iter().enumerate() {
            if b.labels[1] == OUTSIDE {
                for (side, edges) in Side::ALL.into_iter().zip(b.sides(mesh)) {
                    if !edges.is_empty() {
                        entities.push((i, Some(side), edges));
                    }
                }
            } else {
                entities.push((i, None, b.edges.clone()));
            }
        }
        let sides = Side::ALL
            .into_iter()
            .filter(|&side| entities.iter().any(|e| e.1 == Some(side)))
            .collect();
        Self {
            used: mesh.used_labels(),
            curves,
            entities,
            sides,
        }
    }

    /// The physical curve of `side`.
    fn side_tag(side: Side) -> usize {
        1 + side as usize
    }

    /// The physical curve of boundary `boundary`.
    fn boundary_tag(boundary: usize) -> usize {
        1 + Side::ALL.len() + boundary
    }

    /// The physical curves of an entity of boundary `boundary` along `side`: the side's, then
    /// the boundary's.
    fn physical_tags(boundary: usize, side: Option<Side>) -> Vec<usize> {
        side.map(Self::side_tag)
            .into_iter()
            .chain([Self::boundary_tag(boundary)])
            .collect()
    }

    /// The `$PhysicalNames` section (the same in both versions).
    fn write_names(&self, mesh: &SegmentedMeshData, s: &mut String) {
        let count = self.used.len() + self.curves.len() + self.sides.len();
        let _ = writeln!(s, "$PhysicalNames\n{count}");
        for &side in &self.sides {
            let _ = writeln!(s, "1 {} \"{}\"", Self::side_tag(side), side.name());
        }
        for (i, b) in self.curves.iter().enumerate() {
            let _ = writeln!(s, "1 {} \"{}\"", Self::boundary_tag(i), b.name(mesh));
        }
        for &l in &self.used {
            let name = mesh.label_names[l as usize].replace('"', "'");
            let _ = writeln!(s, "2 {} \"{}\"", l + 1, name);
        }
        let _ = writeln!(s, "$EndPhysicalNames");
    }
}

/// The MSH 2.2 text of `mesh`, for readers that know no other (MFEM, OpenFOAM's `gmshToFoam`,
/// older FEniCS tools): the same physical groups as [`msh_string`], each element tagged with
/// its physical group and its entity (a label's surface, or its [`msh_string`] curve entity).
/// Version 2 gives an element one physical group, so a border line is written once for its
/// side of the domain and once again for its label's border, as Gmsh itself writes an element
/// of two groups.
///
/// ```
/// use imesh_io::{msh22_string, Frame, SegmentedMeshData};
/// use imesh_quality::Element;
/// let mesh = SegmentedMeshData {
///     vertices: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]],
///     elements: vec![Element::Quad([0, 1, 2, 3])],
///     labels: vec![0], label_names: vec!["steel".into()], label_colours: vec![[0; 3]],
///     width: 2, height: 1, second_order: None,
/// };
/// let text = msh22_string(&mesh, &Frame::default());
/// assert!(text.starts_with("$MeshFormat\n2.2 0 8\n"));
/// // The quad (type 3) in physical surface 1 "steel"; four border lines, each twice.
/// assert!(text.contains("\n$Elements\n9\n1 3 2 1 1 "));
/// ```
pub fn msh22_string(mesh: &SegmentedMeshData, frame: &Frame) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "$MeshFormat\n2.2 0 8\n$EndMeshFormat");
    let groups = Groups::of(mesh);
    groups.write_names(mesh, &mut s);
    let n = mesh.node_count();
    let _ = writeln!(s, "$Nodes\n{n}");
    push_lines(&mut s, n, |i, s| {
        let q = frame.map(mesh, mesh.node(i));
        let _ = writeln!(s, "{} {} {} 0", i + 1, q[0], q[1]);
    });
    let _ = writeln!(s, "$EndNodes");
    let lines: Vec<(usize, usize, [u32; 2])> = groups
        .entities
        .iter()
        .enumerate()
        .flat_map(|(j, (i, side, edges))| {
            let tags = Groups::physical_tags(*i, *side);
            edges
                .iter()
                .flat_map(move |&e| tags.clone().into_iter().map(move |tag| (tag, j + 1, e)))
        })
        .collect();
    let _ = writeln!(s, "$Elements\n{}", mesh.elements.len() + lines.len());
    push_lines(&mut s, mesh.elements.len(), |i, s| {
        let (e, l) = (&mesh.elements[i], mesh.labels[i] + 1);
        let quad = matches!(e, Element::Quad(_));
        let _ = write!(s, "{} {} 2 {l} {l}", i + 1, gmsh_type(mesh, quad));
        for v in written_nodes(mesh, i, true) {
            let _ = write!(s, " {}", v + 1);
        }
        s.push('\n');
    });
    let first = mesh.elements.len() + 1;
    let kind = line_type(mesh);
    for (k, &(tag, entity, e)) in lines.iter().enumerate() {
        let nodes = line_nodes(mesh, e);
        let _ = writeln!(s, "{} {kind} 2 {tag} {entity} {nodes}", first + k);
    }
    let _ = writeln!(s, "$EndElements");
    s
}

/// Writes `mesh` as Gmsh MSH 2.2 ASCII ([`msh22_string`]), atomically.
///
/// # Errors
/// [`WriteError`] when the mesh is inconsistent or the file cannot be written.
pub fn write_msh22(path: &Path, mesh: &SegmentedMeshData, frame: &Frame) -> Result<(), WriteError> {
    check(path, mesh)?;
    write_atomic(path, msh22_string(mesh, frame).as_bytes())
}

/// Writes `mesh` as Gmsh MSH 4.1 ASCII, atomically.
///
/// # Errors
/// [`WriteError`] when the mesh is inconsistent or the file cannot be written.
pub fn write_msh(path: &Path, mesh: &SegmentedMeshData, frame: &Frame) -> Result<(), WriteError> {
    check(path, mesh)?;
    write_atomic(path, msh_string(mesh, frame).as_bytes())
}

/// Gmsh's type of a triangle or a `quad`: 3-node triangle 2, 4-node quad 3; second order,
/// 6-node triangle 9, 9-node quad 10.
fn gmsh_type(mesh: &SegmentedMeshData, quad: bool) -> u32 {
    match (quad, mesh.second_order.is_some()) {
        (false, false) => 2,
        (true, false) => 3,
        (false, true) => 9,
        (true, true) => 10,
    }
}

/// Gmsh's type of the boundary lines: 2-node 1, 3-node 8.
fn line_type(mesh: &SegmentedMeshData) -> u32 {
    if mesh.second_order.is_some() {
        8
    } else {
        1
    }
}

/// A boundary line's node numbers as Gmsh lists them: its ends, then its middle node in a
/// second-order mesh.
fn line_nodes(mesh: &SegmentedMeshData, [a, b]: [u32; 2]) -> String {
    let middle = mesh.second_order.as_ref().and_then(|s| s.middle([a, b]));
    match middle {
        Some(m) => format!("{} {} {}", a + 1, b + 1, m + 1),
        None => format!("{} {}", a + 1, b + 1),
    }
}

pub(crate) fn bounds(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    points.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}
