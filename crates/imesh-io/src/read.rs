//! Readers for the meshes `imesh quality` measures: Gmsh MSH 4.1 and 2.2 ASCII and legacy VTK ASCII
//! unstructured grids, keeping their 2D points, triangles and quads (other cells are skipped).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use imesh_quality::Element;

/// A mesh read back: points (x, y) and its triangles and quads as 0-based point indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadMesh {
    /// Points.
    pub vertices: Vec<[f64; 2]>,
    /// Triangles and quads.
    pub elements: Vec<Element>,
}

/// Why a mesh file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not what its extension says.
    #[error("{path} is not a valid {format} file: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// The format expected.
        format: &'static str,
        /// What is wrong, and where.
        reason: String,
    },
    /// An extension no reader handles.
    #[error("cannot read {path}: give a .msh (Gmsh 4.1 or 2.2 ASCII) or .vtk (legacy ASCII) mesh")]
    Unsupported {
        /// The file.
        path: PathBuf,
    },
}

/// Reads the mesh at `path` by its extension (`.msh` or `.vtk`).
///
/// # Errors
/// [`ReadError`], saying what is wrong.
pub fn read_mesh(path: &Path) -> Result<ReadMesh, ReadError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let parse = match ext.as_deref() {
        Some("msh") => parse_msh,
        Some("vtk") => parse_vtk,
        _ => {
            return Err(ReadError::Unsupported {
                path: path.to_path_buf(),
            })
        }
    };
    let text = std::fs::read_to_string(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text).map_err(|(format, reason)| ReadError::Format {
        path: path.to_path_buf(),
        format,
        reason,
    })
}

type Parsed = Result<ReadMesh, (&'static str, String)>;

/// Whitespace-separated tokens with their line numbers.
struct Tokens<'a> {
    tokens: Vec<(usize, &'a str)>,
    at: usize,
    format: &'static str,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, format: &'static str) -> Self {
        let tokens = text
            .lines()
            .enumerate()
            .flat_map(|(n, line)| line.split_whitespace().map(move |t| (n + 1, t)))
            .collect();
        Self {
            tokens,
            at: 0,
            format,
        }
    }

    fn next(&mut self) -> Result<(usize, &'a str), (&'static str, String)> {
        let t = self
            .tokens
            .get(self.at)
            .copied()
            .ok_or((self.format, "the file ends too early".to_string()))?;
        self.at += 1;
        Ok(t)
    }

    fn number<T: std::str::FromStr>(&mut self) -> Result<T, (&'static str, String)> {
        let (line, t) = self.next()?;
        t.parse()
            .map_err(|_| (self.format, format!("line {line}: {t:?} is not a number")))
    }

    /// Skips to just after the token `word`.
    fn seek(&mut self, word: &str) -> Result<(), (&'static str, String)> {
        while self.next()?.1 != word {}
        Ok(())
    }
}

/// The nodes an MSH element type has and its corners, for the types read: lines (2- and
/// 3-node) and points are skipped, a second-order triangle (6 nodes) or quad (8 or 9) is read
/// as its corners.
fn msh_corners(kind: u32, format: &'static str) -> Result<(usize, usize), (&'static str, String)> {
    match kind {
        1 => Ok((2, 0)),
        8 => Ok((3, 0)),
        2 => Ok((3, 3)),
        9 => Ok((6, 3)),
        3 => Ok((4, 4)),
        16 => Ok((8, 4)),
        10 => Ok((9, 4)),
        15 => Ok((1, 0)),
        other => Err((format, format!("element type {other} is not read"))),
    }
}

/// Reads `nodes` node tags into an element of the first `corners` (none for a line or a
/// point).
fn msh_element(
    t: &mut Tokens<'_>,
    index: &HashMap<usize, u32>,
    (nodes, corners): (usize, usize),
) -> Result<Option<Element>, (&'static str, String)> {
    let format = t.format;
    let mut c = [0u32; 4];
    for k in 0..nodes {
        let (line, tag) = t.next()?;
        let tag: usize = tag
            .parse()
            .map_err(|_| (format, format!("line {line}: {tag:?} is not a node tag")))?;
        let node = *index
            .get(&tag)
            .ok_or((format, format!("line {line}: no node {tag}")))?;
        if let Some(slot) = c.get_mut(k).filter(|_| k < corners) {
            *slot = node;
        }
    }
    Ok(match corners {
        3 => Some(Element::Triangle([c[0], c[1], c[2]])),
        4 => Some(Element::Quad(c)),
        _ => None,
    })
}

fn parse_msh(text: &str) -> Parsed {
    const F: &str = "Gmsh MSH 4.1";
    let mut t = Tokens::new(text, F);
    t.seek("$MeshFormat")?;
    let (line, version) = t.next()?;
    if version.starts_with('2') {
        t.format = "Gmsh MSH 2.2";
        return parse_msh2(t);
    }
    if !version.starts_with('4') {
        return Err((F, format!("line {line}: version {version}, not 4.1 or 2.2")));
    }
    if t.number::<u32>()? != 0 {
        return Err((F, "binary files are not read: write it as ASCII".into()));
    }
    t.seek("$Nodes")?;
    let blocks: usize = t.number()?;
    let _total: usize = t.number()?;
    let (_min, _max): (usize, usize) = (t.number()?, t.number()?);
    let mut index: HashMap<usize, u32> = HashMap::new();
    let mut mesh = ReadMesh::default();
    for _ in 0..blocks {
        let (_dim, _entity, parametric): (u32, i64, u32) = (t.number()?, t.number()?, t.number()?);
        let n: usize = t.number()?;
        let tags: Vec<usize> = (0..n).map(|_| t.number()).collect::<Result<_, _>>()?;
        for tag in tags {
            let (x, y, _z): (f64, f64, f64) = (t.number()?, t.number()?, t.number()?);
            for _ in 0..parametric {
                let _: f64 = t.number()?;
            }
            index.insert(tag, mesh.vertices.len() as u32);
            mesh.vertices.push([x, y]);
        }
    }
    t.seek("$Elements")?;
    let blocks: usize = t.number()?;
    let (_total, _min, _max): (usize, usize, usize) = (t.number()?, t.number()?, t.number()?);
    for _ in 0..blocks {
        let (_dim, _entity, kind): (u32, i64, u32) = (t.number()?, t.number()?, t.number()?);
        let n: usize = t.number()?;
        let corners = msh_corners(kind, F)?;
        for _ in 0..n {
            let _tag: usize = t.number()?;
            mesh.elements.extend(msh_element(&mut t, &index, corners)?);
        }
    }
    Ok(mesh)
}

/// MSH 2.2 ASCII, from the tokens just after its version: one node list, one element list
/// whose lines carry their own tags.
fn parse_msh2(mut t: Tokens<'_>) -> Parsed {
    let format = t.format;
    if t.number::<u32>()? != 0 {
        return Err((
            format,
            "binary files are not read: write it as ASCII".into(),
        ));
    }
    t.seek("$Nodes")?;
    let n: usize = t.number()?;
    let mut index: HashMap<usize, u32> = HashMap::new();
    let mut mesh = ReadMesh::default();
    for _ in 0..n {
        let tag: usize = t.number()?;
        let (x, y, _z): (f64, f64, f64) = (t.number()?, t.number()?, t.number()?);
        index.insert(tag, mesh.vertices.len() as u32);
        mesh.vertices.push([x, y]);
    }
    t.seek("$Elements")?;
    let m: usize = t.number()?;
    for _ in 0..m {
        let (_tag, kind, tags): (usize, u32, usize) = (t.number()?, t.number()?, t.number()?);
        for _ in 0..tags {
            let _: i64 = t.number()?;
        }
        let corners = msh_corners(kind, format)?;
        mesh.elements.extend(msh_element(&mut t, &index, corners)?);
    }
    Ok(mesh)
}

fn parse_vtk(text: &str) -> Parsed {
    const F: &str = "legacy VTK";
    if !text.starts_with("# vtk DataFile") {
        return Err((F, "the first line is not '# vtk DataFile Version …'".into()));
    }
    // The header's second line is free text: tokenise after it.
    let body = text.splitn(3, '\n').nth(2).unwrap_or("");
    let mut t = Tokens::new(body, F);
    if t.next()?.1 != "ASCII" {
        return Err((F, "binary files are not read: write it as ASCII".into()));
    }
    t.seek("DATASET")?;
    let (line, kind) = t.next()?;
    if kind != "UNSTRUCTURED_GRID" {
        return Err((
            F,
            format!("line {line}: {kind} is not an UNSTRUCTURED_GRID"),
        ));
    }
    t.seek("POINTS")?;
    let n: usize = t.number()?;
    let _ = t.next()?;
    let mut mesh = ReadMesh::default();
    for _ in 0..n {
        let (x, y, _z): (f64, f64, f64) = (t.number()?, t.number()?, t.number()?);
        mesh.vertices.push([x, y]);
    }
    t.seek("CELLS")?;
    let cells: usize = t.number()?;
    let _size: usize = t.number()?;
    let mut lists = Vec::with_capacity(cells);
    for _ in 0..cells {
        let k: usize = t.number()?;
        let ids: Vec<u32> = (0..k).map(|_| t.number()).collect::<Result<_, _>>()?;
        if let Some(&bad) = ids.iter().find(|&&i| i as usize >= n) {
            return Err((F, format!("a cell uses point {bad} of {n}")));
        }
        lists.push(ids);
    }
    t.seek("CELL_TYPES")?;
    let _: usize = t.number()?;
    for ids in lists {
        match (t.number::<u32>()?, ids.as_slice()) {
            (5, &[a, b, c]) | (22, &[a, b, c, _, _, _]) => {
                mesh.elements.push(Element::Triangle([a, b, c]))
            }
            (9, &[a, b, c, d]) | (23 | 28, &[a, b, c, d, ..]) => {
                mesh.elements.push(Element::Quad([a, b, c, d]))
            }
            _ => {}
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hand_written_msh_and_vtk_give_their_elements() {
        let msh = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 5 1 5\n2 1 0 5\n1\n2\n3\n4\n5\n\
                   0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n$EndNodes\n$Elements\n2 2 1 2\n\
                   2 1 3 1\n1 1 2 3 4\n2 1 2 1\n2 2 5 3\n$EndElements\n";
        let m = parse_msh(msh).unwrap();
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(
            m.elements,
            vec![Element::Quad([0, 1, 2, 3]), Element::Triangle([1, 4, 2])]
        );
        // The same mesh in version 2.2, with a line element (skipped) and tags of any count.
        let msh2 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n\
                    3 1 1 0\n4 0 1 0\n5 2 0 0\n$EndNodes\n$Elements\n3\n1 3 2 1 1 1 2 3 4\n\
                    2 1 3 5 7 9 1 2\n3 2 0 2 5 3\n$EndElements\n";
        assert_eq!(parse_msh(msh2).unwrap(), m);
        let vtk =
            "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n\
                   0 0 0 1 0 0 1 1 0 0 1 0\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n9\n";
        let v = parse_vtk(vtk).unwrap();
        assert_eq!(v.elements, vec![Element::Quad([0, 1, 2, 3])]);
        assert_eq!(v.vertices[2], [1.0, 1.0]);
    }

    #[test]
    fn broken_files_are_clear_errors() {
        let e = parse_msh("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n").unwrap_err();
        assert!(e.1.contains("not 4.1 or 2.2"), "{e:?}");
        // Version 2.2 without its nodes; a header promising more nodes than there are; a
        // binary file.
        let e = parse_msh("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n").unwrap_err();
        assert_eq!(e, ("Gmsh MSH 2.2", "the file ends too early".to_string()));
        let e =
            parse_msh("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n99999999999999\n1 0 0 0\n")
                .unwrap_err();
        assert!(e.1.contains("ends too early"), "{e:?}");
        let e = parse_msh("$MeshFormat\n2.2 1 8\n$EndMeshFormat\n").unwrap_err();
        assert!(e.1.contains("binary"), "{e:?}");
        let e =
            parse_msh("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 x 0\n")
                .unwrap_err();
        assert!(e.1.contains("\"x\" is not a number"), "{e:?}");
        let e = parse_vtk("# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 double\n0 0 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n")
            .unwrap_err();
        assert!(e.1.contains("point 1 of 1"), "{e:?}");
        assert!(parse_vtk("hello").is_err());
    }
}
