//! Readers for the meshes `imesh quality` measures: Gmsh MSH 4.1 and 2.2 ASCII, legacy VTK ASCII
//! and VTK XML (`.vtu`, ASCII data arrays) unstructured grids, and Abaqus `.inp` files, keeping
//! their 2D points, triangles and quads (other cells are skipped; a second-order element is read
//! as its corners). Every format imesh writes reads back.

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
    #[error("cannot read {path}: give a .msh (Gmsh 4.1 or 2.2 ASCII), .vtk (legacy ASCII), .vtu (VTK XML, ASCII data) or .inp (Abaqus) mesh")]
    Unsupported {
        /// The file.
        path: PathBuf,
    },
}

/// The mesh file formats [`read_mesh`] and [`parse_mesh`] read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Gmsh MSH 4.1 or 2.2, ASCII (`.msh`).
    Msh,
    /// Legacy VTK unstructured grid, ASCII (`.vtk`).
    Vtk,
    /// VTK XML unstructured grid with ASCII data arrays (`.vtu`).
    Vtu,
    /// Abaqus input file (`.inp`).
    Inp,
}

impl MeshFormat {
    /// Every format.
    pub const ALL: [MeshFormat; 4] = [Self::Msh, Self::Vtk, Self::Vtu, Self::Inp];

    /// The format a path's extension names (in any case), if any.
    ///
    /// ```
    /// use imesh_io::MeshFormat;
    /// assert_eq!(MeshFormat::of_path("out/coins.VTU".as_ref()), Some(MeshFormat::Vtu));
    /// assert_eq!(MeshFormat::of_path("coins.json".as_ref()), None);
    /// ```
    pub fn of_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "msh" => Some(Self::Msh),
            "vtk" => Some(Self::Vtk),
            "vtu" => Some(Self::Vtu),
            "inp" => Some(Self::Inp),
            _ => None,
        }
    }
}

/// Why a mesh text could not be parsed: the format expected and what is wrong, and where.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("not a valid {format} file: {reason}")]
pub struct ParseError {
    /// The format expected (`"Gmsh MSH 4.1"`, `"Abaqus .inp"`, …).
    pub format: &'static str,
    /// What is wrong, and where.
    pub reason: String,
}

/// Parses a mesh held in memory, in `format`: its 2D points and its triangles and quads (a
/// second-order element as its corners). Every element's corners index the points.
///
/// # Errors
/// [`ParseError`], saying what is wrong and where.
///
/// ```
/// use imesh_io::{parse_mesh, MeshFormat};
/// use imesh_quality::Element;
/// let inp = "*Node\n1, 0, 0\n2, 1, 0\n3, 0, 1\n*Element, type=CPS3\n1, 1, 2, 3\n";
/// let mesh = parse_mesh(inp, MeshFormat::Inp)?;
/// assert_eq!(mesh.elements, vec![Element::Triangle([0, 1, 2])]);
/// assert!(parse_mesh("*Node\n1, 0\n", MeshFormat::Inp).is_err());
/// # Ok::<(), imesh_io::ParseError>(())
/// ```
pub fn parse_mesh(text: &str, format: MeshFormat) -> Result<ReadMesh, ParseError> {
    let parse = match format {
        MeshFormat::Msh => parse_msh,
        MeshFormat::Vtk => parse_vtk,
        MeshFormat::Vtu => parse_vtu,
        MeshFormat::Inp => parse_inp,
    };
    parse(text).map_err(|(format, reason)| ParseError { format, reason })
}

/// Reads the mesh at `path` by its extension (`.msh`, `.vtk`, `.vtu` or `.inp`; [`parse_mesh`]).
///
/// # Errors
/// [`ReadError`], saying what is wrong.
pub fn read_mesh(path: &Path) -> Result<ReadMesh, ReadError> {
    let Some(format) = MeshFormat::of_path(path) else {
        return Err(ReadError::Unsupported {
            path: path.to_path_buf(),
        });
    };
    let text = std::fs::read_to_string(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_mesh(&text, format).map_err(|ParseError { format, reason }| ReadError::Format {
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

    /// The tokens not yet read: a bound on any count the file announces (each item takes at
    /// least one), so that no header can make a reader reserve more than the file holds.
    fn left(&self) -> usize {
        self.tokens.len().saturating_sub(self.at)
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
    let mut lists = Vec::with_capacity(cells.min(t.left()));
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
        mesh.elements.extend(vtk_element(t.number::<u32>()?, &ids));
    }
    Ok(mesh)
}

/// The triangle or quad of a VTK cell of type `kind` with points `ids` (a second-order one as
/// its corners); `None` for any other cell.
fn vtk_element(kind: u32, ids: &[u32]) -> Option<Element> {
    match (kind, ids) {
        (5, &[a, b, c]) | (22, &[a, b, c, _, _, _]) => Some(Element::Triangle([a, b, c])),
        (9, &[a, b, c, d])
        | (23, &[a, b, c, d, _, _, _, _])
        | (28, &[a, b, c, d, _, _, _, _, _]) => Some(Element::Quad([a, b, c, d])),
        _ => None,
    }
}

/// The line (1-based) that byte `at` of `text` is on.
fn line_of(text: &str, at: usize) -> usize {
    1 + text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// The value of attribute `name` in the start tag `tag` (`<DataArray … name="value" …>`).
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let mut rest = tag;
    while let Some(at) = rest.find(name) {
        let before = rest[..at].chars().next_back();
        let after = rest[at + name.len()..].trim_start();
        rest = &rest[at + name.len()..];
        if before.is_some_and(char::is_whitespace) {
            if let Some(value) = after.strip_prefix('=') {
                let value = value.trim_start();
                let quote = value.chars().next().filter(|&q| q == '"' || q == '\'')?;
                let value = &value[1..];
                return value.find(quote).map(|end| &value[..end]);
            }
        }
    }
    None
}

/// A `<DataArray>` of a `.vtu` file: its start tag, its content, and the byte of the file its
/// content starts at.
#[derive(Clone, Copy)]
struct DataArray<'a> {
    tag: &'a str,
    content: &'a str,
    at: usize,
}

/// The `<DataArray>`s of `section` (which starts at byte `offset` of the file `text`).
fn data_arrays<'a>(
    text: &str,
    section: &'a str,
    offset: usize,
) -> Result<Vec<DataArray<'a>>, (&'static str, String)> {
    const F: &str = VTU;
    let mut arrays = Vec::new();
    let mut rest = 0;
    while let Some(open) = section[rest..].find("<DataArray") {
        let start = rest + open;
        let line = line_of(text, offset + start);
        let end_tag = section[start..]
            .find('>')
            .ok_or((F, format!("line {line}: a <DataArray> tag is not closed")))?;
        let tag = &section[start..start + end_tag];
        let body = start + end_tag + 1;
        if tag.ends_with('/') {
            arrays.push(DataArray {
                tag,
                content: "",
                at: offset + body,
            });
            rest = body;
            continue;
        }
        let close = section[body..]
            .find("</DataArray>")
            .ok_or((F, format!("line {line}: a <DataArray> has no </DataArray>")))?;
        arrays.push(DataArray {
            tag,
            content: &section[body..body + close],
            at: offset + body,
        });
        rest = body + close;
    }
    Ok(arrays)
}

const VTU: &str = "VTK XML (.vtu)";

/// The numbers of `array` (of the file `text`), whose data must be ASCII.
fn array_numbers<T: std::str::FromStr>(
    text: &str,
    DataArray { tag, content, at }: DataArray<'_>,
) -> Result<Vec<T>, (&'static str, String)> {
    let line = line_of(text, at);
    match attribute(tag, "format") {
        Some("ascii") => {}
        other => {
            let format = other.map_or("no format attribute".to_string(), |f| {
                format!("format {f:?}")
            });
            return Err((
                VTU,
                format!(
                    "line {line}: a data array with {format}: only ASCII data arrays are read \
                     (write the file with ASCII data, e.g. meshio's binary=False)"
                ),
            ));
        }
    }
    content
        .split_whitespace()
        .map(|t| {
            t.parse()
                .map_err(|_| (VTU, format!("near line {line}: {t:?} is not a number")))
        })
        .collect()
}

/// The part of `text` from `open` to the end of the next `close` after it, with its offset.
fn section<'a>(text: &'a str, from: usize, open: &str, close: &str) -> Option<(&'a str, usize)> {
    let start = from + text[from..].find(open)?;
    let end = start + text[start..].find(close)? + close.len();
    Some((&text[start..end], start))
}

fn parse_vtu(text: &str) -> Parsed {
    const F: &str = VTU;
    if !text.contains("<VTKFile") || !text.contains("type=\"UnstructuredGrid\"") {
        return Err((
            F,
            "not a VTK XML unstructured grid (<VTKFile type=\"UnstructuredGrid\">)".into(),
        ));
    }
    let mut mesh = ReadMesh::default();
    let mut from = 0;
    let mut pieces = 0;
    while let Some((piece, at)) = section(text, from, "<Piece", "</Piece>") {
        pieces += 1;
        from = at + piece.len();
        let base = mesh.vertices.len() as u32;
        let (points, points_at) = section(piece, 0, "<Points", "</Points>").ok_or((
            F,
            format!("line {}: a piece has no <Points>", line_of(text, at)),
        ))?;
        let array = data_arrays(text, points, at + points_at)?
            .into_iter()
            .next()
            .ok_or((
                F,
                format!(
                    "line {}: <Points> has no data array",
                    line_of(text, at + points_at)
                ),
            ))?;
        let components: usize = attribute(array.tag, "NumberOfComponents")
            .unwrap_or("1")
            .parse()
            .map_err(|_| (F, "NumberOfComponents is not a number".to_string()))?;
        if components == 0 {
            return Err((F, "points with no components".into()));
        }
        let coordinates: Vec<f64> = array_numbers(text, array)?;
        mesh.vertices.extend(
            coordinates
                .chunks_exact(components)
                .map(|c| [c[0], c.get(1).copied().unwrap_or(0.0)]),
        );
        let n = mesh.vertices.len() as u32 - base;
        let (cells, cells_at) = section(piece, 0, "<Cells", "</Cells>").ok_or((
            F,
            format!("line {}: a piece has no <Cells>", line_of(text, at)),
        ))?;
        let arrays = data_arrays(text, cells, at + cells_at)?;
        let named = |name: &str| {
            arrays
                .iter()
                .copied()
                .find(|a| attribute(a.tag, "Name") == Some(name))
                .ok_or((F, format!("<Cells> has no {name} array")))
        };
        let connectivity: Vec<u32> = array_numbers(text, named("connectivity")?)?;
        let offsets: Vec<usize> = array_numbers(text, named("offsets")?)?;
        let types: Vec<u32> = array_numbers(text, named("types")?)?;
        if offsets.len() != types.len() {
            return Err((
                F,
                format!("{} offsets for {} cell types", offsets.len(), types.len()),
            ));
        }
        let mut start = 0;
        for (&end, &kind) in offsets.iter().zip(&types) {
            let ids = connectivity.get(start..end).ok_or((
                F,
                format!("a cell's offset {end} is outside the connectivity"),
            ))?;
            if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
                return Err((F, format!("a cell uses point {bad} of {n}")));
            }
            let ids: Vec<u32> = ids.iter().map(|&i| base + i).collect();
            mesh.elements.extend(vtk_element(kind, &ids));
            start = end;
        }
    }
    if pieces == 0 {
        return Err((F, "the file has no <Piece>".into()));
    }
    Ok(mesh)
}

/// The nodes and corners of an Abaqus element type, for the plane, axisymmetric, shell,
/// membrane, surface, rigid-surface and heat-transfer families (`CPS4R`, `CPE8`, `CAX6`, `S4R`,
/// `S9R5`, `R3D3`, `DC2D3`, …; meshio writes triangles as `R3D3`): 3 or 4 corners; `None` for
/// any other element (lines, solids, …), which is skipped.
fn inp_corners(kind: &str) -> Option<(usize, usize)> {
    const FAMILIES: [&str; 13] = [
        "CPEG", "CPS", "CPE", "CGAX", "CAX", "DC2D", "DCAX", "STRI", "SFM3D", "SC", "S", "M3D",
        "R3D",
    ];
    let kind = kind.to_ascii_uppercase();
    let family = FAMILIES.into_iter().find(|f| kind.starts_with(f))?;
    let digits: String = kind[family.len()..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    match digits.as_str() {
        "3" => Some((3, 3)),
        "4" => Some((4, 4)),
        "6" | "65" => Some((6, 3)),
        "8" => Some((8, 4)),
        "9" => Some((9, 4)),
        _ => None,
    }
}

fn parse_inp(text: &str) -> Parsed {
    const F: &str = "Abaqus .inp";
    enum Block {
        Nodes,
        Elements(usize, usize),
        Other,
    }
    let mut block = Block::Other;
    let mut index: HashMap<usize, u32> = HashMap::new();
    let mut mesh = ReadMesh::default();
    // An element's numbers so far (its data lines may continue on the next line).
    let mut element: Vec<usize> = Vec::new();
    fn number<T: std::str::FromStr>(line: usize, t: &str) -> Result<T, (&'static str, String)> {
        t.trim()
            .parse()
            .map_err(|_| (F, format!("line {line}: {:?} is not a number", t.trim())))
    }
    for (n, raw) in text.lines().enumerate() {
        let (line, l) = (n + 1, raw.trim());
        if l.is_empty() || l.starts_with("**") {
            continue;
        }
        if let Some(keyword) = l.strip_prefix('*') {
            if !element.is_empty() {
                return Err((
                    F,
                    format!("line {line}: the element before it is cut short"),
                ));
            }
            let mut parts = keyword.split(',');
            let name = parts.next().unwrap_or("").trim().to_ascii_lowercase();
            block = match name.as_str() {
                "node" => Block::Nodes,
                "element" => {
                    let kind = parts
                        .filter_map(|p| p.split_once('='))
                        .find(|(k, _)| k.trim().eq_ignore_ascii_case("type"))
                        .map(|(_, v)| v.trim())
                        .ok_or((F, format!("line {line}: *Element without a type")))?;
                    match inp_corners(kind) {
                        Some((nodes, corners)) => Block::Elements(nodes, corners),
                        None => Block::Other,
                    }
                }
                _ => Block::Other,
            };
            continue;
        }
        match block {
            Block::Other => {}
            Block::Nodes => {
                let fields: Vec<&str> = l.split(',').collect();
                if fields.len() < 3 {
                    return Err((F, format!("line {line}: a node needs a number, x and y")));
                }
                let id: usize = number(line, fields[0])?;
                let (x, y): (f64, f64) = (number(line, fields[1])?, number(line, fields[2])?);
                index.insert(id, mesh.vertices.len() as u32);
                mesh.vertices.push([x, y]);
            }
            Block::Elements(nodes, corners) => {
                for t in l.split(',').filter(|t| !t.trim().is_empty()) {
                    element.push(number(line, t)?);
                }
                if element.len() > nodes + 1 {
                    return Err((
                        F,
                        format!("line {line}: an element with more than {nodes} nodes"),
                    ));
                }
                if element.len() < nodes + 1 {
                    continue; // continued on the next line
                }
                let mut c = [0u32; 4];
                for (slot, &id) in c.iter_mut().zip(&element[1..=corners]) {
                    *slot = *index
                        .get(&id)
                        .ok_or((F, format!("line {line}: no node {id}")))?;
                }
                mesh.elements.push(match corners {
                    3 => Element::Triangle([c[0], c[1], c[2]]),
                    _ => Element::Quad(c),
                });
                element.clear();
            }
        }
    }
    if !element.is_empty() {
        return Err((F, "the file ends inside an element".into()));
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
    fn a_hand_written_vtu_and_inp_give_their_elements() {
        // Two pieces (the second's points numbered from its own 0), a line cell skipped, a
        // 9-node quad read as its corners, and an empty cell-data array.
        let vtu = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0">
<UnstructuredGrid>
<Piece NumberOfPoints="4" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">
0 0 0 1 0 0 1 1 0 0 1 0</DataArray></Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3 0 2</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">4 6</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">9 3</DataArray>
</Cells>
<CellData><DataArray type="Int32" Name="label" format="ascii"/></CellData>
</Piece>
<Piece NumberOfPoints="9" NumberOfCells="2">
<Points><DataArray NumberOfComponents='2' type="Float64" format="ascii">
2 0 3 0 3 1 2 1 2.5 0 3 0.5 2.5 1 2 0.5 2.5 0.5</DataArray></Points>
<Cells>
<DataArray Name="types" type="UInt8" format="ascii">28 5</DataArray>
<DataArray Name="offsets" type="Int64" format="ascii">9 12</DataArray>
<DataArray Name="connectivity" type="Int64" format="ascii">0 1 2 3 4 5 6 7 8 0 1 2</DataArray>
</Cells>
</Piece>
</UnstructuredGrid>
</VTKFile>
"#;
        let v = parse_vtu(vtu).unwrap();
        assert_eq!(v.vertices.len(), 13);
        assert_eq!(v.vertices[5], [3.0, 0.0]);
        assert_eq!(
            v.elements,
            vec![
                Element::Quad([0, 1, 2, 3]),
                Element::Quad([4, 5, 6, 7]),
                Element::Triangle([4, 5, 6])
            ]
        );
        // Abaqus: comments, a node set and a truss element skipped, an 8-node quad continued
        // on a second line, keywords in any case.
        let inp = "*Heading\n** a comment\n*NODE\n10, 0., 0.\n11, 1., 0.\n12, 1., 1.\n13, 0., 1.\n\
                   14, 2., 0.\n15, 0.5, 0.\n16, 1., 0.5\n17, 0.5, 1.\n18, 0., 0.5\n\
                   *Element, type=CPS3, elset=a\n1, 11, 14, 12\n\
                   *element, TYPE=cps8r, elset=b\n2, 10, 11, 12, 13,\n15, 16, 17, 18\n\
                   *Element, type=T2D2\n3, 10, 11\n*Nset, nset=left\n10, 13\n";
        let m = parse_inp(inp).unwrap();
        assert_eq!(m.vertices.len(), 9);
        assert_eq!(m.vertices[4], [2.0, 0.0]);
        assert_eq!(
            m.elements,
            vec![Element::Triangle([1, 4, 2]), Element::Quad([0, 1, 2, 3])]
        );
    }

    proptest::proptest! {
        /// Any text, and any valid file cut or with a character put anywhere, gives a mesh or an
        /// error: never a panic (`imesh quality` reads whatever a user gives it).
        #[test]
        fn no_text_makes_a_reader_panic(
            text in ".{0,200}", cut in 0usize..2000, at in 0usize..2000, c in proptest::char::any(),
        ) {
            let files = [
                "<VTKFile type=\"UnstructuredGrid\"><Piece><Points><DataArray NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0</DataArray></Points><Cells><DataArray Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray><DataArray Name=\"offsets\" format=\"ascii\">3</DataArray><DataArray Name=\"types\" format=\"ascii\">5</DataArray></Cells></Piece></VTKFile>",
                "*Node\n1, 0, 0\n2, 1, 0\n3, 1, 1\n*Element, type=CPS3, elset=a\n1, 1, 2,\n3\n",
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n1 1 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n",
                "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n0 0 0 1 0 0 1 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n",
            ];
            for parse in [parse_vtu, parse_inp, parse_msh, parse_vtk] {
                let _ = parse(&text);
                for file in files {
                    let cut = file.char_indices().map(|(i, _)| i).nth(cut % file.chars().count()).unwrap_or(0);
                    let _ = parse(&file[..cut]);
                    let at = file.char_indices().map(|(i, _)| i).nth(at % file.chars().count()).unwrap_or(0);
                    let _ = parse(&format!("{}{c}{}", &file[..at], &file[at..]));
                }
            }
        }
    }

    #[test]
    fn abaqus_area_elements_are_known_by_family_and_node_count() {
        for (kind, want) in [
            ("CPS3", Some((3, 3))),
            ("cpe4r", Some((4, 4))),
            ("CAX4P", Some((4, 4))),
            ("R3D3", Some((3, 3))),
            ("S4R5", Some((4, 4))),
            ("STRI65", Some((6, 3))),
            ("CPS6M", Some((6, 3))),
            ("S8R", Some((8, 4))),
            ("S9R5", Some((9, 4))),
            ("DC2D4", Some((4, 4))),
            ("T2D2", None),
            ("B21", None),
            ("C3D8R", None),
            ("CPS", None),
        ] {
            assert_eq!(inp_corners(kind), want, "{kind}");
        }
    }

    #[test]
    fn broken_vtu_and_inp_files_are_clear_errors() {
        let binary = r#"<VTKFile type="UnstructuredGrid"><Piece><Points><DataArray NumberOfComponents="3" format="binary">AAAA</DataArray></Points><Cells></Cells></Piece></VTKFile>"#;
        let e = parse_vtu(binary).unwrap_err();
        assert!(e.1.contains("only ASCII data arrays"), "{e:?}");
        // An attribute's value must be quoted; a multi-byte character where the quote should be
        // is no value (and no panic).
        assert_eq!(
            attribute("<DataArray format='ascii'", "format"),
            Some("ascii")
        );
        assert_eq!(attribute("<DataArray format=éasciié", "format"), None);
        assert_eq!(
            attribute("<DataArray Xformat=\"a\" format = \"b\"", "format"),
            Some("b")
        );
        assert!(parse_vtu("<VTKFile type=\"PolyData\">").is_err());
        let e = parse_vtu(r#"<VTKFile type="UnstructuredGrid"></VTKFile>"#).unwrap_err();
        assert!(e.1.contains("no <Piece>"), "{e:?}");
        let beyond = r#"<VTKFile type="UnstructuredGrid"><Piece><Points><DataArray NumberOfComponents="3" format="ascii">0 0 0</DataArray></Points><Cells><DataArray Name="connectivity" format="ascii">0 1 2</DataArray><DataArray Name="offsets" format="ascii">3</DataArray><DataArray Name="types" format="ascii">5</DataArray></Cells></Piece></VTKFile>"#;
        let e = parse_vtu(beyond).unwrap_err();
        assert!(e.1.contains("point 1 of 1"), "{e:?}");
        let e = parse_vtu(&beyond.replace(">3<", ">7<")).unwrap_err();
        assert!(e.1.contains("outside the connectivity"), "{e:?}");
        let e = parse_inp("*Node\n1, 0, 0\n*Element, type=CPS3\n1, 1, 2, 3\n").unwrap_err();
        assert!(e.1.contains("line 4: no node 2"), "{e:?}");
        let e = parse_inp("*Node\n1, 0, 0\n*Element, type=CPS4\n1, 1, 1,\n*Nset\n").unwrap_err();
        assert!(e.1.contains("cut short"), "{e:?}");
        let e = parse_inp("*Node\n1, zero, 0\n").unwrap_err();
        assert!(e.1.contains("line 2: \"zero\" is not a number"), "{e:?}");
        let e = parse_inp("*Element\n1, 2, 3\n").unwrap_err();
        assert!(e.1.contains("without a type"), "{e:?}");
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
        // A header announcing more cells than memory holds: an error, not an allocation failure
        // (the reader reserved what the header said; found while the `read` fuzz target ran).
        let e = parse_vtk("# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n0 0 0 1 0 0 0 1 0\nCELLS 99999999999999 5\n3 0 1 2\nCELL_TYPES 1\n5\n")
            .unwrap_err();
        assert!(e.1.contains("\"CELL_TYPES\" is not a number"), "{e:?}");
        assert!(parse_vtk("hello").is_err());
    }
}
