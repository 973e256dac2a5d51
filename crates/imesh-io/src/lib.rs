//! Writers for segmented 2D meshes: Gmsh MSH 4.1 and 2.2 (a named physical surface per label, and a
//! physical curve per boundary and per side of the domain), VTK XML `.vtu` and legacy `.vtk`
//! (cell data: label and quality), Abaqus `.inp` (an element set per label, a node set per
//! boundary and per side, a surface per side), and SVG and PNG pictures. Every file is written
//! atomically (a temporary file in the same directory, renamed into place), so a failed run
//! never leaves half a file.
//!
//! Meshes come in image coordinates (y down, elements counter-clockwise there); writers emit the
//! y-up frame `(x·sx, (H − y)·sy)` with every element counter-clockwise in it.
//!
//! ```
//! use imesh_io::{write_msh, Frame, SegmentedMeshData};
//! use imesh_quality::Element;
//! let mesh = SegmentedMeshData {
//!     vertices: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]],
//!     elements: vec![Element::Quad([0, 1, 2, 3])],
//!     labels: vec![0],
//!     label_names: vec!["steel".into()],
//!     label_colours: vec![[200, 200, 200]],
//!     width: 2,
//!     height: 1,
//!     second_order: None,
//! };
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("plate.msh");
//! write_msh(&path, &mesh, &Frame::default()).unwrap();
//! let text = std::fs::read_to_string(&path).unwrap();
//! assert!(text.starts_with("$MeshFormat\n4.1 0 8\n"));
//! assert!(text.contains("2 1 \"steel\""));
//! ```

#![warn(missing_docs)]

mod boundary;
mod histogram;
mod inp;
mod msh;
mod png;
mod read;
mod second_order;
mod svg;
mod vtk;
mod vtu;

use std::io::Write;
use std::path::{Path, PathBuf};

use imesh_quality::Element;

pub use boundary::{boundaries, sanitize, Boundary, Side, OUTSIDE};
pub use histogram::{histogram_picture, write_histogram, HistogramPanel};
pub use inp::{inp_string, write_inp};
pub use msh::{msh22_string, msh_string, write_msh, write_msh22};
pub use png::{rasterise, write_png};
pub use read::{parse_mesh, read_mesh, MeshFormat, ParseError, ReadError, ReadMesh};
pub use second_order::{SecondOrder, CURVED_JACOBIAN_SHARE, NO_NODE};
pub use svg::{svg_string, write_svg, SvgOptions};
pub use vtk::{vtk_string, write_vtk};
pub use vtu::{vtu_string, write_vtu};

/// A labelled 2D mesh as the writers take it.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentedMeshData {
    /// Vertex positions in image coordinates (pixels, y down).
    pub vertices: Vec<[f64; 2]>,
    /// Triangles and quads, counter-clockwise in image coordinates.
    pub elements: Vec<Element>,
    /// A label per element (an index into `label_names`).
    pub labels: Vec<u32>,
    /// The name of each label.
    pub label_names: Vec<String>,
    /// The display colour of each label.
    pub label_colours: Vec<[u8; 3]>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The extra nodes of second-order elements ([`SecondOrder::new`]); `None` for a linear
    /// mesh.
    pub second_order: Option<SecondOrder>,
}

impl SegmentedMeshData {
    /// The labels the elements carry, ascending, each once (one physical group each in the
    /// written files).
    ///
    /// ```
    /// use imesh_io::SegmentedMeshData;
    /// let mesh = SegmentedMeshData {
    ///     vertices: vec![], elements: vec![], labels: vec![3, 0, 3, 2],
    ///     label_names: vec![], label_colours: vec![], width: 1, height: 1, second_order: None,
    /// };
    /// assert_eq!(mesh.used_labels(), vec![0, 2, 3]);
    /// ```
    pub fn used_labels(&self) -> Vec<u32> {
        let mut used = self.labels.clone();
        used.sort_unstable();
        used.dedup();
        used
    }

    /// The nodes a writer lists: the vertices, then the second-order nodes.
    pub fn node_count(&self) -> usize {
        self.vertices.len() + self.second_order.as_ref().map_or(0, |s| s.points.len())
    }

    /// Node `i` ([`SegmentedMeshData::node_count`]), image coordinates.
    pub fn node(&self, i: usize) -> [f64; 2] {
        match (i.checked_sub(self.vertices.len()), &self.second_order) {
            (Some(k), Some(s)) => s.points[k],
            _ => self.vertices[i],
        }
    }

    /// The area element `i` covers: its corners' polygon, or with second-order nodes a quad's
    /// curved area ([`imesh_quality::curved::area`]; a triangle's sides stay straight).
    pub fn element_area(&self, i: usize) -> f64 {
        match self.second_order.as_ref().and_then(|s| s.quad9(self, i)) {
            Some(q) => imesh_quality::curved::area(&q),
            None => {
                let corner = |v: &u32| self.vertices[*v as usize];
                let corners: Vec<[f64; 2]> =
                    self.elements[i].corners().iter().map(corner).collect();
                imesh_quality::signed_area(&corners)
            }
        }
    }

    /// The nodes of the boundary `edges`, sorted, each once: their ends, and their middle
    /// nodes in a second-order mesh.
    pub fn edge_nodes(&self, edges: &[[u32; 2]]) -> Vec<u32> {
        let mut nodes = boundary::edge_vertices(edges);
        if let Some(s) = &self.second_order {
            nodes.extend(edges.iter().filter_map(|&e| s.middle(e)));
            nodes.sort_unstable();
        }
        nodes
    }
}

/// The written frame: y up, scaled by a physical pixel size, and placed with the image's
/// bottom-left corner at an origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Size of a pixel along x and y (default 1).
    pub pixel_size: [f64; 2],
    /// Where the image's bottom-left corner goes (default 0, 0).
    pub origin: [f64; 2],
}

impl Default for Frame {
    fn default() -> Self {
        Self {
            pixel_size: [1.0, 1.0],
            origin: [0.0, 0.0],
        }
    }
}

impl Frame {
    /// A vertex in the written frame: `(x · sx + ox, (H − y) · sy + oy)`.
    ///
    /// ```
    /// use imesh_io::{Frame, SegmentedMeshData};
    /// let mesh = SegmentedMeshData {
    ///     vertices: vec![], elements: vec![], labels: vec![],
    ///     label_names: vec![], label_colours: vec![], width: 4, height: 3, second_order: None,
    /// };
    /// // Pixels of 0.5 mm, the image's bottom-left corner at (10, 20) mm.
    /// let frame = Frame { pixel_size: [0.5, 0.5], origin: [10.0, 20.0] };
    /// assert_eq!(frame.map(&mesh, [0.0, 3.0]), [10.0, 20.0]); // the bottom-left corner
    /// assert_eq!(frame.map(&mesh, [4.0, 0.0]), [12.0, 21.5]); // the top-right one
    /// ```
    pub fn map(&self, mesh: &SegmentedMeshData, p: [f64; 2]) -> [f64; 2] {
        [
            p[0] * self.pixel_size[0] + self.origin[0],
            (f64::from(mesh.height) - p[1]) * self.pixel_size[1] + self.origin[1],
        ]
    }
}

/// An element's corners in the written frame's counter-clockwise order (flipping y reverses the
/// orientation, so the order is reversed, keeping the first corner).
pub fn written_corners(e: &Element) -> Vec<u32> {
    let c = e.corners();
    std::iter::once(c[0])
        .chain(c[1..].iter().rev().copied())
        .collect()
}

/// Element `i`'s nodes in the written frame's order: its [`written_corners`], then in a
/// second-order mesh the middle node of each written side (from written corner k to the next),
/// then, with `centre`, a quad's centre node (Gmsh's and VTK's 9-node quad; Abaqus's 8-node
/// quad has none).
pub fn written_nodes(mesh: &SegmentedMeshData, i: usize, centre: bool) -> Vec<u32> {
    let e = &mesh.elements[i];
    let mut nodes = written_corners(e);
    if let Some(s) = &mesh.second_order {
        let n = e.corners().len();
        // Written side k is the element's side n − 1 − k, run the other way.
        nodes.extend((0..n).map(|k| s.sides[i][n - 1 - k]));
        if centre && s.centres[i] != NO_NODE {
            nodes.push(s.centres[i]);
        }
    }
    nodes
}

/// A write that failed.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The file or its temporary could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The mesh breaks an invariant the format needs.
    #[error("refusing to write {path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// Writes `contents` to `path` atomically: a temporary file in the same directory, flushed, then
/// renamed over `path`.
///
/// # Errors
/// [`WriteError::Io`] when the directory is not writable or the disk is full.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), WriteError> {
    let io = |source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(io)?;
    tmp.write_all(contents).map_err(io)?;
    tmp.as_file().sync_all().map_err(io)?;
    // Temporary files are private; the result is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(io)?;
    }
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

/// Appends `n` lines to `s`, line `i` written by `line(i, part)` into the part being built:
/// parts of [`LINE_CHUNK`] lines formatted in parallel, then laid end to end in order (the same
/// text as one line after the other; formatting floats is most of a writer's time).
pub(crate) fn push_lines(s: &mut String, n: usize, line: impl Fn(usize, &mut String) + Sync) {
    use rayon::prelude::*;
    let parts: Vec<String> = (0..n.div_ceil(LINE_CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut part = String::new();
            for i in c * LINE_CHUNK..((c + 1) * LINE_CHUNK).min(n) {
                line(i, &mut part);
            }
            part
        })
        .collect();
    s.reserve(parts.iter().map(String::len).sum());
    for part in parts {
        s.push_str(&part);
    }
}

/// Lines per part of [`push_lines`].
const LINE_CHUNK: usize = 4096;

/// Checks what every writer needs: labels for every element, known vertices.
pub(crate) fn check(path: &Path, mesh: &SegmentedMeshData) -> Result<(), WriteError> {
    let invalid = |reason: String| WriteError::Invalid {
        path: path.to_path_buf(),
        reason,
    };
    if mesh.labels.len() != mesh.elements.len() {
        return Err(invalid(format!(
            "{} labels for {} elements",
            mesh.labels.len(),
            mesh.elements.len()
        )));
    }
    let n = mesh.vertices.len() as u32;
    if mesh
        .elements
        .iter()
        .any(|e| e.corners().iter().any(|&v| v >= n))
    {
        return Err(invalid("an element refers to a missing vertex".into()));
    }
    if let Some(so) = &mesh.second_order {
        let nodes = mesh.node_count() as u32;
        let in_range = |v: &u32| *v < nodes;
        if so.sides.len() != mesh.elements.len()
            || so.centres.len() != mesh.elements.len()
            || mesh
                .elements
                .iter()
                .zip(&so.sides)
                .zip(&so.centres)
                .any(|((e, s), c)| {
                    let k = e.corners().len();
                    !s[..k].iter().all(in_range) || (k == 4) != in_range(c)
                })
        {
            return Err(invalid(
                "the second-order nodes do not match the elements".into(),
            ));
        }
    }
    if let Some(&l) = mesh
        .labels
        .iter()
        .find(|&&l| l as usize >= mesh.label_names.len())
    {
        return Err(invalid(format!("label {l} has no name")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{push_lines, LINE_CHUNK};
    use std::fmt::Write as _;

    /// The parts formatted in parallel make the text one line after the other would, whatever
    /// the count against the part size (none, one, a part less one, a part, a part and one, and
    /// several parts).
    #[test]
    fn lines_formatted_in_parts_are_the_lines_in_order() {
        let value = |i: usize| (i as f64).sqrt() * if i % 2 == 0 { 1.0 } else { -1e-7 };
        for n in [
            0,
            1,
            LINE_CHUNK - 1,
            LINE_CHUNK,
            LINE_CHUNK + 1,
            3 * LINE_CHUNK + 17,
        ] {
            let mut expected = String::from("head\n");
            for i in 0..n {
                let _ = writeln!(expected, "{i} {}", value(i));
            }
            let mut s = String::from("head\n");
            push_lines(&mut s, n, |i, s| {
                let _ = writeln!(s, "{i} {}", value(i));
            });
            assert_eq!(s, expected, "{n} lines");
        }
    }
}
