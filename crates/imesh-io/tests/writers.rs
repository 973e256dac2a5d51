//! The writers: y-up counter-clockwise output, exact areas, atomic failure.

use imesh_io::{
    boundaries, inp_string, msh22_string, msh_string, read_mesh, vtk_string, vtu_string, write_msh,
    write_msh22, written_corners, Frame, SecondOrder, SegmentedMeshData, OUTSIDE,
};
use imesh_quality::Element;
use proptest::prelude::*;

/// A `w × h` grid of unit squares, each split into two triangles, labelled by column parity.
fn grid_mesh(w: u32, h: u32) -> SegmentedMeshData {
    let id = |c: u32, r: u32| r * (w + 1) + c;
    let vertices = (0..=h)
        .flat_map(|r| (0..=w).map(move |c| [f64::from(c), f64::from(r)]))
        .collect();
    let mut elements = Vec::new();
    let mut labels = Vec::new();
    for r in 0..h {
        for c in 0..w {
            // Counter-clockwise in image coordinates (positive signed area with y down).
            elements.push(Element::Triangle([
                id(c, r),
                id(c + 1, r),
                id(c + 1, r + 1),
            ]));
            elements.push(Element::Triangle([
                id(c, r),
                id(c + 1, r + 1),
                id(c, r + 1),
            ]));
            labels.extend([c % 2, c % 2]);
        }
    }
    SegmentedMeshData {
        vertices,
        elements,
        labels,
        label_names: vec!["even".into(), "odd".into()],
        label_colours: vec![[0, 0, 0], [255, 255, 255]],
        width: w,
        height: h,
        second_order: None,
    }
}

/// Parses the nodes and elements back from MSH 4.1 text.
fn parse_msh(text: &str) -> (Vec<[f64; 2]>, Vec<Vec<usize>>, Vec<String>) {
    let lines: Vec<&str> = text.lines().collect();
    let at = |tag: &str| lines.iter().position(|l| *l == tag).unwrap();
    let names: Vec<String> = {
        let i = at("$PhysicalNames");
        let n: usize = lines[i + 1].parse().unwrap();
        lines[i + 2..i + 2 + n]
            .iter()
            .map(|l| l.to_string())
            .collect()
    };
    let i = at("$Nodes");
    let n: usize = lines[i + 1].split(' ').nth(1).unwrap().parse().unwrap();
    let coords = &lines[i + 3 + n..i + 3 + 2 * n];
    let nodes = coords
        .iter()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1]]
        })
        .collect();
    // Surface blocks only (dimension 2); boundary lines are checked separately.
    let elements = msh_blocks(&lines)
        .into_iter()
        .filter(|(dim, _, _)| *dim == 2)
        .flat_map(|(_, _, elements)| elements)
        .collect();
    (nodes, elements, names)
}

/// The element blocks of MSH 4.1 lines: dimension, entity, and each element's nodes.
fn msh_blocks(lines: &[&str]) -> Vec<(usize, usize, Vec<Vec<usize>>)> {
    let mut k = lines.iter().position(|l| *l == "$Elements").unwrap() + 2;
    let mut blocks = Vec::new();
    while lines[k] != "$EndElements" {
        let head: Vec<usize> = lines[k].split(' ').map(|x| x.parse().unwrap()).collect();
        let count = head[3];
        let elements = lines[k + 1..k + 1 + count]
            .iter()
            .map(|l| l.split(' ').skip(1).map(|x| x.parse().unwrap()).collect())
            .collect();
        blocks.push((head[0], head[1], elements));
        k += 1 + count;
    }
    blocks
}

/// The shoelace area, from the first corner: far from the origin of coordinates (a written
/// frame's origin at 10³ units, pixels of 0.1), products of the coordinates themselves would
/// lose the area's digits.
fn signed_area(p: &[[f64; 2]]) -> f64 {
    let d = |q: [f64; 2]| [q[0] - p[0][0], q[1] - p[0][1]];
    (1..p.len().saturating_sub(1))
        .map(|i| {
            let (a, b) = (d(p[i]), d(p[i + 1]));
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        / 2.0
}

proptest! {
    #[test]
    fn msh_is_y_up_counter_clockwise_and_covers_the_scaled_domain(
        w in 1u32..8, h in 1u32..8, sx in 0.1f64..3.0, sy in 0.1f64..3.0,
        ox in -1e3f64..1e3, oy in -1e3f64..1e3,
    ) {
        let mesh = grid_mesh(w, h);
        let frame = Frame { pixel_size: [sx, sy], origin: [ox, oy] };
        let (nodes, elements, names) = parse_msh(&msh_string(&mesh, &frame));
        prop_assert_eq!(nodes.len(), mesh.vertices.len());
        prop_assert_eq!(elements.len(), mesh.elements.len());
        // Surfaces: one per label used; curves: a border per label, even|odd when both exist,
        // and the four sides of the domain.
        let surfaces = names.iter().filter(|n| n.starts_with("2 ")).count();
        let curves = names.iter().filter(|n| n.starts_with("1 ")).count();
        prop_assert_eq!(surfaces, if w > 1 { 2 } else { 1 });
        prop_assert_eq!(curves, if w > 1 { 3 } else { 1 } + 4);
        let mut total = 0.0;
        for e in &elements {
            let p: Vec<[f64; 2]> = e.iter().map(|&v| nodes[v - 1]).collect();
            let a = signed_area(&p);
            prop_assert!(a > 0.0, "element {:?} is clockwise in the written frame", e);
            total += a;
        }
        let want = f64::from(w) * sx * f64::from(h) * sy;
        prop_assert!((total - want).abs() <= 1e-9 * want);
        // y up: image row 0 is at the top; the image's bottom-left corner at the origin.
        prop_assert_eq!(nodes[0], [ox, f64::from(h) * sy + oy]);
        let bottom_left = (h * (w + 1)) as usize;
        prop_assert_eq!(nodes[bottom_left], [ox, oy]);
    }
}

#[test]
fn written_corners_reverse_the_order_but_keep_the_first() {
    assert_eq!(
        written_corners(&Element::Quad([4, 5, 6, 7])),
        vec![4, 7, 6, 5]
    );
    assert_eq!(
        written_corners(&Element::Triangle([1, 2, 3])),
        vec![1, 3, 2]
    );
}

#[test]
fn vtu_has_every_cell_with_its_label() {
    let mesh = grid_mesh(3, 2);
    let text = vtu_string(&mesh, &Frame::default(), &[("shape".into(), vec![1.0; 12])]);
    assert!(text.contains("NumberOfPoints=\"12\" NumberOfCells=\"12\""));
    assert!(text.contains("Name=\"label\""));
    assert!(text.contains("Name=\"shape\""));
    // Twelve triangles: VTK cell type 5, one per line (no other line is a lone 5 here).
    assert_eq!(text.lines().filter(|l| *l == "5").count(), 12);
}

#[test]
fn a_failed_write_leaves_no_file_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir/out.msh");
    let e = write_msh(&missing, &grid_mesh(2, 2), &Frame::default()).unwrap_err();
    assert!(e.to_string().contains("cannot write"));
    assert!(!missing.exists());
    // An inconsistent mesh is refused before anything is written.
    let mut bad = grid_mesh(2, 2);
    bad.labels.pop();
    let path = dir.path().join("bad.msh");
    assert!(write_msh(&path, &bad, &Frame::default()).is_err());
    assert!(!path.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "a temporary file was left"
    );
}

#[test]
fn boundaries_separate_labels_and_the_border() {
    // 4 × 2 squares, labels by column parity: three inner boundaries even|odd, and the border.
    let mesh = grid_mesh(4, 2);
    let b = boundaries(&mesh);
    let labels: Vec<[u32; 2]> = b.iter().map(|b| b.labels).collect();
    assert_eq!(labels, vec![[0, 1], [0, OUTSIDE], [1, OUTSIDE]]);
    assert_eq!(b[0].edges.len(), 3 * 2, "three vertical lines of two edges");
    let border: usize = b[1].edges.len() + b[2].edges.len();
    assert_eq!(border, 2 * (4 + 2));
    assert_eq!(b[1].name(&mesh), "border_even");
    assert_eq!(b[0].name(&mesh), "even_odd");
}

/// The boundaries the slow way: each edge's labels in a map, the edges in the order first met.
fn boundaries_by_map(mesh: &SegmentedMeshData) -> Vec<(u32, u32, Vec<[u32; 2]>)> {
    let mut sides: std::collections::BTreeMap<[u32; 2], (usize, Vec<u32>)> = Default::default();
    let mut met = 0;
    for (e, &l) in mesh.elements.iter().zip(&mesh.labels) {
        let c = e.corners();
        for i in 0..c.len() {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            let side = sides.entry([a.min(b), a.max(b)]).or_insert_with(|| {
                met += 1;
                (met, Vec::new())
            });
            side.1.push(l);
        }
    }
    let mut found: Vec<([u32; 2], usize, [u32; 2])> = Vec::new();
    for (edge, (first, labels)) in sides {
        match labels[..] {
            [a] => found.push(([a, OUTSIDE], first, edge)),
            [a, b] if a != b => found.push(([a.min(b), a.max(b)], first, edge)),
            _ => {}
        }
    }
    found.sort_unstable();
    let mut out: Vec<(u32, u32, Vec<[u32; 2]>)> = Vec::new();
    for (labels, _, edge) in found {
        match out.last_mut() {
            Some(last) if [last.0, last.1] == labels => last.2.push(edge),
            _ => out.push((labels[0], labels[1], vec![edge])),
        }
    }
    out
}

proptest! {
    /// On grids of triangles labelled at random, [`boundaries`] lists what a map of every edge's
    /// sides does: the same boundaries, the same edges, in the order first met.
    #[test]
    fn boundaries_are_those_of_a_map_of_edges(
        w in 1u32..7, h in 1u32..7, seed in proptest::collection::vec(0u32..3, 72),
    ) {
        let mut mesh = grid_mesh(w, h);
        for (k, l) in mesh.labels.iter_mut().enumerate() {
            *l = seed[k % seed.len()];
        }
        mesh.label_names = vec!["a".into(), "b".into(), "c".into()];
        mesh.label_colours = vec![[0, 0, 0]; 3];
        let ours: Vec<(u32, u32, Vec<[u32; 2]>)> = boundaries(&mesh)
            .into_iter()
            .map(|b| (b.labels[0], b.labels[1], b.edges))
            .collect();
        prop_assert_eq!(ours, boundaries_by_map(&mesh));
    }
}

/// The `$PhysicalNames` of MSH text (either version) by dimension and tag.
fn physical_names(lines: &[&str]) -> std::collections::HashMap<(usize, usize), String> {
    let i = lines.iter().position(|l| *l == "$PhysicalNames").unwrap();
    let n: usize = lines[i + 1].parse().unwrap();
    lines[i + 2..i + 2 + n]
        .iter()
        .map(|l| {
            let (head, name) = l.split_once(" \"").unwrap();
            let v: Vec<usize> = head.split(' ').map(|x| x.parse().unwrap()).collect();
            ((v[0], v[1]), name.trim_end_matches('"').to_string())
        })
        .collect()
}

/// The line elements of each named physical curve of MSH 4.1 text, as node pairs (an entity's
/// lines belong to every physical curve it carries).
fn msh_curves(text: &str) -> std::collections::BTreeMap<String, Vec<[usize; 2]>> {
    let lines: Vec<&str> = text.lines().collect();
    let at = |tag: &str| lines.iter().position(|l| *l == tag).unwrap();
    let names = physical_names(&lines);
    let i = at("$Entities");
    let curves: usize = lines[i + 1].split(' ').nth(1).unwrap().parse().unwrap();
    let mut physical_of = std::collections::HashMap::new();
    for l in &lines[i + 2..i + 2 + curves] {
        let v: Vec<usize> = l
            .split(' ')
            .map(|x| x.parse::<f64>().unwrap() as usize)
            .collect();
        physical_of.insert(v[0], v[8..8 + v[7]].to_vec());
    }
    let mut out: std::collections::BTreeMap<String, Vec<[usize; 2]>> = Default::default();
    for (_, entity, lines) in msh_blocks(&lines).into_iter().filter(|b| b.0 == 1) {
        for v in lines {
            for tag in &physical_of[&entity] {
                out.entry(names[&(1, *tag)].clone())
                    .or_default()
                    .push([v[0], v[1]]);
            }
        }
    }
    out
}

/// The line the named side lies on in the written frame: (coordinate, value), and its length.
fn side_line(name: &str, width: f64, height: f64) -> (usize, f64, f64) {
    match name {
        "left" => (0, 0.0, height),
        "right" => (0, width, height),
        "bottom" => (1, 0.0, width),
        "top" => (1, height, width),
        _ => unreachable!("{name}"),
    }
}

proptest! {
    /// The sides of the domain are physical curves whose lines lie on the side's own line and
    /// cover it exactly once, each also in its label's border; the borders hold every side line.
    #[test]
    fn msh_sides_are_the_domain_border_split_four_ways(
        w in 1u32..7, h in 1u32..7, sx in 0.1f64..3.0, sy in 0.1f64..3.0,
        ox in -1e3f64..1e3, oy in -1e3f64..1e3,
        seed in proptest::collection::vec(0u32..3, 72),
    ) {
        let mut mesh = grid_mesh(w, h);
        for (k, l) in mesh.labels.iter_mut().enumerate() {
            *l = seed[k % seed.len()];
        }
        mesh.label_names = vec!["a".into(), "b".into(), "c".into()];
        mesh.label_colours = vec![[0, 0, 0]; 3];
        let text = msh_string(&mesh, &Frame { pixel_size: [sx, sy], origin: [ox, oy] });
        let (nodes, _, _) = parse_msh(&text);
        let curves = msh_curves(&text);
        let (width, height) = (f64::from(w) * sx, f64::from(h) * sy);
        let mut on_sides = 0;
        for name in ["left", "right", "bottom", "top"] {
            let (axis, value, length) = side_line(name, width, height);
            // The writer's own arithmetic: `0 · s + o` and `W · s + o`, exactly.
            let value = value + [ox, oy][axis];
            let lines = &curves[name];
            let mut covered = 0.0;
            for &[a, b] in lines {
                let (p, q) = (nodes[a - 1], nodes[b - 1]);
                prop_assert!(p[axis] == value && q[axis] == value, "{} line off its side", name);
                covered += (p[1 - axis] - q[1 - axis]).abs();
            }
            let tolerance = 1e-9 * (length + ox.abs() + oy.abs());
            prop_assert!((covered - length).abs() <= tolerance, "{}: {} of {}", name, covered, length);
            on_sides += lines.len();
        }
        let borders: usize = curves
            .iter()
            .filter(|(n, _)| n.starts_with("border_"))
            .map(|(_, l)| l.len())
            .sum();
        prop_assert_eq!(borders, on_sides);
        prop_assert_eq!(on_sides, 2 * (w + h) as usize);
    }
}

/// The physical groups of MSH 2.2 text by name: their elements as node lists (lines and
/// surfaces alike), and the nodes.
#[allow(clippy::type_complexity)]
fn msh22_groups(
    text: &str,
) -> (
    std::collections::BTreeMap<String, Vec<Vec<usize>>>,
    Vec<[f64; 2]>,
) {
    let lines: Vec<&str> = text.lines().collect();
    let at = |tag: &str| lines.iter().position(|l| *l == tag).unwrap();
    let name_of = physical_names(&lines);
    let i = at("$Nodes");
    let n: usize = lines[i + 1].parse().unwrap();
    let nodes = lines[i + 2..i + 2 + n]
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            assert_eq!(v[0] as usize, k + 1, "nodes numbered in order");
            [v[1], v[2]]
        })
        .collect();
    let i = at("$Elements");
    let m: usize = lines[i + 1].parse().unwrap();
    let mut groups: std::collections::BTreeMap<String, Vec<Vec<usize>>> = Default::default();
    for l in &lines[i + 2..i + 2 + m] {
        let v: Vec<usize> = l.split(' ').map(|x| x.parse().unwrap()).collect();
        let (kind, tags) = (v[1], v[2]);
        assert_eq!(tags, 2, "a physical and an elementary tag");
        let dim = if kind == 1 { 1 } else { 2 };
        let name = name_of[&(dim, v[3])].clone();
        groups.entry(name).or_default().push(v[3 + tags..].to_vec());
    }
    assert_eq!(lines[i + 2 + m], "$EndElements");
    (groups, nodes)
}

proptest! {
    /// Version 2.2 holds the same nodes and the same physical groups, each of the same
    /// elements, as version 4.1 (a border line written once per group it belongs to).
    #[test]
    fn msh22_has_the_groups_of_msh41(
        w in 1u32..6, h in 1u32..6, sx in 0.1f64..3.0, ox in -10f64..10.0,
        seed in proptest::collection::vec(0u32..3, 50),
    ) {
        let mut mesh = grid_mesh(w, h);
        for (k, l) in mesh.labels.iter_mut().enumerate() {
            *l = seed[k % seed.len()];
        }
        mesh.label_names = vec!["a".into(), "b b".into(), "c".into()];
        mesh.label_colours = vec![[0, 0, 0]; 3];
        let frame = Frame { pixel_size: [sx, 2.0 * sx], origin: [ox, -ox] };
        let text = msh22_string(&mesh, &frame);
        prop_assert!(text.starts_with("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"));
        let (groups, nodes) = msh22_groups(&text);
        let four = msh_string(&mesh, &frame);
        let (nodes4, elements4, _) = parse_msh(&four);
        prop_assert_eq!(&nodes, &nodes4);
        // Curves: the same lines per name.
        let mut curves4 = msh_curves(&four);
        for lines in curves4.values_mut() {
            lines.sort_unstable();
        }
        let mut curves2: std::collections::BTreeMap<String, Vec<[usize; 2]>> = groups
            .iter()
            .filter(|(_, e)| e[0].len() == 2)
            .map(|(n, e)| (n.clone(), e.iter().map(|l| [l[0], l[1]]).collect()))
            .collect();
        for lines in curves2.values_mut() {
            lines.sort_unstable();
        }
        prop_assert_eq!(curves2, curves4);
        // Surfaces: every element once, in its label's group, its corners as version 4.1 writes
        // them.
        let mut want: Vec<(usize, Vec<usize>)> = mesh
            .elements
            .iter()
            .zip(&mesh.labels)
            .map(|(e, &l)| {
                let corners: Vec<usize> = written_corners(e).iter().map(|&v| v as usize + 1).collect();
                (l as usize, corners)
            })
            .collect();
        let mut found: Vec<(usize, Vec<usize>)> = Vec::new();
        for (name, elements) in groups.iter().filter(|(_, e)| e[0].len() > 2) {
            let label = mesh.label_names.iter().position(|l| l == name).unwrap();
            found.extend(elements.iter().map(|e| (label, e.clone())));
        }
        want.sort();
        found.sort();
        prop_assert_eq!(&found, &want);
        let mut four: Vec<Vec<usize>> = elements4;
        four.sort();
        let mut corners: Vec<Vec<usize>> = found.into_iter().map(|(_, c)| c).collect();
        corners.sort();
        prop_assert_eq!(corners, four);
        // Read back as `imesh quality` reads it: the same elements.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.msh");
        imesh_io::write_msh22(&path, &mesh, &frame).unwrap();
        let read = imesh_io::read_mesh(&path).unwrap();
        prop_assert_eq!(read.vertices, nodes);
        prop_assert_eq!(read.elements.len(), mesh.elements.len());
    }
}

/// The corner polygons of `elements` over `vertices`, each as its points in order, sorted: the
/// same mesh whatever order a format lists its nodes and elements in.
fn corner_polygons(vertices: &[[f64; 2]], elements: &[Element]) -> Vec<String> {
    let mut all: Vec<String> = elements
        .iter()
        .map(|e| {
            let points: Vec<[f64; 2]> = e.corners().iter().map(|&v| vertices[v as usize]).collect();
            format!("{points:?}")
        })
        .collect();
    all.sort();
    all
}

proptest! {
    /// Every format the writers give reads back (`imesh quality`'s reader) as the written
    /// elements' corner polygons, in the written frame: MSH 4.1 and 2.2, legacy VTK, VTK XML
    /// and Abaqus.
    #[test]
    fn every_written_format_reads_back_as_its_elements(
        w in 1u32..5, h in 1u32..5, quads in any::<bool>(), sx in 0.1f64..3.0, ox in -10f64..10.0,
        seed in proptest::collection::vec(0u32..2, 30),
    ) {
        let mut mesh = if quads { quad_grid(w, h) } else { grid_mesh(w, h) };
        for (k, l) in mesh.labels.iter_mut().enumerate() {
            *l = seed[k % seed.len()];
        }
        let frame = Frame { pixel_size: [sx, 2.0 * sx], origin: [ox, -ox] };
        let written: Vec<Element> = mesh
            .elements
            .iter()
            .map(|e| match *written_corners(e).as_slice() {
                [a, b, c] => Element::Triangle([a, b, c]),
                [a, b, c, d] => Element::Quad([a, b, c, d]),
                _ => unreachable!("a triangle or a quad"),
            })
            .collect();
        let points: Vec<[f64; 2]> = mesh.vertices.iter().map(|&p| frame.map(&mesh, p)).collect();
        let want = corner_polygons(&points, &written);
        let dir = tempfile::tempdir().unwrap();
        let files = [
            ("m.msh", msh_string(&mesh, &frame)),
            ("m22.msh", msh22_string(&mesh, &frame)),
            ("m.vtk", vtk_string(&mesh, &frame, &[])),
            ("m.vtu", vtu_string(&mesh, &frame, &[])),
            ("m.inp", inp_string(&mesh, &frame)),
        ];
        for (name, text) in files {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            let read = read_mesh(&path).unwrap();
            prop_assert_eq!(read.vertices.len(), mesh.vertices.len(), "{}", name);
            prop_assert_eq!(corner_polygons(&read.vertices, &read.elements), want.clone(), "{}", name);
        }
    }
}

/// The grid of [`grid_mesh`] with its squares as quads.
fn quad_grid(w: u32, h: u32) -> SegmentedMeshData {
    let triangles = grid_mesh(w, h);
    let mut quads = triangles.clone();
    quads.elements = triangles
        .elements
        .chunks(2)
        .map(|pair| match pair {
            [Element::Triangle([a, b, c]), Element::Triangle([_, _, d])] => {
                Element::Quad([*a, *b, *c, *d])
            }
            _ => unreachable!("grid_mesh gives triangles in pairs"),
        })
        .collect();
    quads.labels = triangles.labels.iter().step_by(2).copied().collect();
    quads
}

#[test]
fn abaqus_sides_have_node_sets_and_surfaces_of_element_faces_on_them() {
    // Triangles, and the same grid's squares as quads.
    for mesh in [grid_mesh(3, 2), quad_grid(3, 2)] {
        abaqus_sides_of(&mesh);
        // Second order: the sides' middle nodes join the sides' node sets.
        let second = SegmentedMeshData {
            second_order: Some(SecondOrder::new(&mesh, &[])),
            ..mesh
        };
        abaqus_sides_of(&second);
    }
}

/// The checks of [`abaqus_sides_have_node_sets_and_surfaces_of_element_faces_on_them`] on a
/// 3 × 2 grid.
fn abaqus_sides_of(mesh: &SegmentedMeshData) {
    let text = inp_string(mesh, &Frame::default());
    let lines: Vec<&str> = text.lines().collect();
    let ids = |l: &str| -> Vec<usize> { l.split(", ").map(|x| x.parse().unwrap()).collect() };
    // Nodes and elements as written (every line between keywords).
    let mut nodes = std::collections::HashMap::new();
    let mut elements = std::collections::HashMap::new();
    let mut sets: std::collections::HashMap<String, Vec<usize>> = Default::default();
    let mut keyword = "";
    for l in &lines {
        if l.starts_with('*') {
            keyword = l;
            continue;
        }
        if keyword == "*Node" {
            let v: Vec<f64> = l.split(", ").map(|x| x.parse().unwrap()).collect();
            nodes.insert(v[0] as usize, [v[1], v[2]]);
        } else if keyword.starts_with("*Element") {
            let v = ids(l);
            elements.insert(v[0], v[1..].to_vec());
        } else if let Some(name) = keyword
            .strip_prefix("*Nset, nset=")
            .or(keyword.strip_prefix("*Elset, elset="))
        {
            sets.entry(name.to_string()).or_default().extend(ids(l));
        }
    }
    for name in ["left", "right", "bottom", "top"] {
        let (axis, value, length) = side_line(name, 3.0, 2.0);
        // The node set: every node on the side's line, and only those.
        let mut want: Vec<usize> = nodes
            .iter()
            .filter(|(_, p)| p[axis] == value)
            .map(|(&k, _)| k)
            .collect();
        want.sort_unstable();
        assert_eq!(sets[name], want, "{name}");
        // The surface: its faces lie on the line and cover it once.
        let surface = format!("*Surface, type=ELEMENT, name={name}_surface");
        let at = lines
            .iter()
            .position(|l| *l == surface)
            .expect("a surface per side");
        let mut covered = 0.0;
        for l in lines[at + 1..].iter().take_while(|l| !l.starts_with('*')) {
            let (set, face) = l.split_once(", S").unwrap();
            let face: usize = face.parse().unwrap();
            assert_eq!(set, format!("{name}_S{face}"));
            for e in &sets[set] {
                let corners = &elements[e];
                // 3 or 4 corners first (then a second-order element's side middles).
                let n = if corners.len() % 3 == 0 { 3 } else { 4 };
                let (p, q) = (nodes[&corners[face - 1]], nodes[&corners[face % n]]);
                assert!(
                    p[axis] == value && q[axis] == value,
                    "{name}: element {e} face {face}"
                );
                covered += (p[1 - axis] - q[1 - axis]).abs();
            }
        }
        assert_eq!(covered, length, "{name}");
    }
}

#[test]
fn abaqus_has_element_sets_per_label_and_node_sets_per_boundary() {
    let mesh = grid_mesh(2, 1);
    let text = inp_string(&mesh, &Frame::default());
    assert!(text.contains("*Element, type=CPS3, elset=even"));
    assert!(text.contains("*Element, type=CPS3, elset=odd"));
    assert!(text.contains("*Nset, nset=even_odd\n2, 5\n"));
    assert!(text.contains("*Nset, nset=border_even"));
}

#[test]
fn legacy_vtk_counts_and_labels() {
    let mesh = grid_mesh(3, 2);
    let text = vtk_string(&mesh, &Frame::default(), &[("shape".into(), vec![1.0; 12])]);
    assert!(text.starts_with("# vtk DataFile Version 3.0\n"));
    assert!(text.contains("POINTS 12 double"));
    assert!(text.contains("CELLS 12 48"));
    assert!(text.contains("SCALARS label int 1"));
    assert!(text.contains("SCALARS shape double 1"));
}

/// The 3 × 2 grid of [`grid_mesh`] with its squares as quads, in second order, the side
/// between the first two columns' top quads bent 0.2 to the right: the point it was given.
fn second_order_quads() -> (SegmentedMeshData, [f64; 2]) {
    let mut mesh = quad_grid(3, 2);
    // Vertices 1 = (1, 0) and 5 = (1, 1).
    let bent = [1.2, 0.5];
    let so = SecondOrder::new(&mesh, &[([1, 5], bent)]);
    assert_eq!(so.curved, 1);
    mesh.second_order = Some(so);
    (mesh, bent)
}

#[test]
fn second_order_msh_lists_each_element_s_side_middles_in_its_written_order() {
    let frame = Frame {
        pixel_size: [2.0, 0.5],
        origin: [10.0, -3.0],
    };
    let triangles = {
        let mut t = grid_mesh(3, 2);
        t.second_order = Some(SecondOrder::new(&t, &[]));
        t
    };
    let (quads, bent) = second_order_quads();
    for mesh in [triangles, quads] {
        let text = msh_string(&mesh, &frame);
        let (nodes, elements, _) = parse_msh(&text);
        assert_eq!(nodes.len(), mesh.node_count());
        let bent = frame.map(&mesh, bent);
        let half = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 1e-12;
        let mut total = 0.0;
        let mut bent_seen = 0;
        for e in &elements {
            let p: Vec<[f64; 2]> = e.iter().map(|&v| nodes[v - 1]).collect();
            let n = if p.len() == 6 { 3 } else { 4 };
            assert!(p.len() == 6 || p.len() == 9, "{} nodes", p.len());
            for k in 0..n {
                let (m, straight) = (p[n + k], half(p[k], p[(k + 1) % n]));
                if close(m, bent) {
                    bent_seen += 1;
                } else {
                    assert!(close(m, straight), "side {k} of {e:?}: {m:?}");
                }
            }
            total += if n == 3 {
                signed_area(&p[..3])
            } else {
                let q: [[f64; 2]; 9] = p.clone().try_into().unwrap();
                let a = imesh_quality::curved::area(&q);
                assert!(imesh_quality::curved::jacobian_bounds(&q)[0] > 0.0);
                a
            };
        }
        // The bent side's two quads both list it; the areas still sum to the domain's.
        assert_eq!(bent_seen, if n_quads(&mesh) > 0 { 2 } else { 0 });
        assert!((total - 6.0 * 2.0 * 0.5).abs() < 1e-9, "{total}");
        // Every boundary line has 3 nodes, its middle the side's middle node.
        let lines: Vec<&str> = text.lines().collect();
        for (dim, _, lines) in msh_blocks(&lines) {
            if dim == 1 {
                for l in lines {
                    assert_eq!(l.len(), 3);
                    let m = nodes[l[2] - 1];
                    assert!(close(m, half(nodes[l[0] - 1], nodes[l[1] - 1])) || close(m, bent));
                }
            }
        }
    }
}

fn n_quads(mesh: &SegmentedMeshData) -> usize {
    mesh.elements
        .iter()
        .filter(|e| matches!(e, Element::Quad(_)))
        .count()
}

#[test]
fn svg_draws_a_bent_side_as_the_parabola_through_its_middle_node() {
    let (mesh, bent) = second_order_quads();
    let svg = imesh_io::svg_string(&mesh, &imesh_io::SvgOptions::default());
    // The two quads either side of it are paths; the other four stay polygons.
    assert_eq!(svg.matches("<polygon ").count(), 4);
    assert_eq!(svg.matches("<path d=").count(), 2);
    // The quadratic Bézier from (1, 0) to (1, 1) through (1.2, 0.5) has its control point at
    // 2 · (1.2, 0.5) − (1, 0.5) = (1.4, 0.5), either way along it.
    assert_eq!(bent, [1.2, 0.5]);
    assert_eq!(svg.matches("Q1.4000 0.5000 ").count(), 2);
}

#[test]
fn second_order_files_of_every_format_read_back_as_their_corners() {
    let (mesh, _) = second_order_quads();
    let frame = Frame::default();
    let dir = tempfile::tempdir().unwrap();
    let msh22 = dir.path().join("q.msh");
    write_msh22(&msh22, &mesh, &frame).unwrap();
    let text = std::fs::read_to_string(&msh22).unwrap();
    // Quads of type 10 with 9 nodes, lines of type 8 with 3.
    assert!(text
        .lines()
        .any(|l| l.starts_with("1 10 2 1 1 ") && l.split(' ').count() == 5 + 9));
    assert!(text
        .lines()
        .any(|l| l.split(' ').nth(1) == Some("8") && l.split(' ').count() == 5 + 3));
    let written_nodes = |path: &std::path::Path| match path.extension().unwrap().to_str() {
        // Abaqus has no 9-node plane quad: the quads' centre nodes are not written.
        Some("inp") => mesh.node_count() - mesh.elements.len(),
        _ => mesh.node_count(),
    };
    for path in [
        msh22,
        dir.path().join("q41.msh"),
        dir.path().join("q.vtk"),
        dir.path().join("q.vtu"),
        dir.path().join("q.inp"),
    ] {
        match path.extension().unwrap().to_str() {
            Some("vtk") => imesh_io::write_vtk(&path, &mesh, &frame, &[]).unwrap(),
            Some("vtu") => imesh_io::write_vtu(&path, &mesh, &frame, &[]).unwrap(),
            Some("inp") => imesh_io::write_inp(&path, &mesh, &frame).unwrap(),
            _ if path.ends_with("q41.msh") => write_msh(&path, &mesh, &frame).unwrap(),
            _ => {}
        }
        let read = read_mesh(&path).unwrap();
        assert_eq!(read.vertices.len(), written_nodes(&path), "{path:?}");
        // The same corner polygons (MSH 4.1 lists the elements by label).
        let written: Vec<Element> = mesh
            .elements
            .iter()
            .map(|e| Element::Quad(written_corners(e).try_into().unwrap()))
            .collect();
        let mapped: Vec<[f64; 2]> = mesh.vertices.iter().map(|&p| frame.map(&mesh, p)).collect();
        assert_eq!(
            corner_polygons(&read.vertices, &read.elements),
            corner_polygons(&mapped, &written),
            "{path:?}"
        );
    }
    // VTK: 9-node biquadratic quads (28); the XML file the same.
    let vtk = vtk_string(&mesh, &frame, &[]);
    assert!(vtk.contains("CELLS 6 60\n9 "));
    assert_eq!(vtk.lines().filter(|l| *l == "28").count(), 6);
    let vtu = vtu_string(&mesh, &frame, &[]);
    assert!(vtu.contains("Name=\"offsets\" format=\"ascii\">\n9\n18\n"));
    // Abaqus: 8-node quads, no centre nodes written.
    let inp = inp_string(&mesh, &frame);
    assert!(inp.contains("*Element, type=CPS8, elset=even\n"));
    let so = mesh.second_order.as_ref().unwrap();
    let written_nodes = inp
        .lines()
        .skip_while(|l| *l != "*Node")
        .skip(1)
        .take_while(|l| !l.starts_with('*'))
        .count();
    assert_eq!(written_nodes, mesh.vertices.len() + so.edges.len());
}
