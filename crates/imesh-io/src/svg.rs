//! SVG pictures: elements filled with their label's colour, edges drawn (a second-order mesh's
//! bent sides as the curves they are), optionally over the image. SVG's own frame is y-down
//! like the image, so coordinates are pixels as they are.

use std::fmt::Write as _;
use std::path::Path;

use crate::vtu::xml_escape;
use crate::{check, write_atomic, SegmentedMeshData, WriteError};

/// How to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct SvgOptions {
    /// An image drawn underneath (a path or URL the SVG refers to), if any.
    pub background: Option<String>,
    /// Opacity of the element fill (0 to 1; lower shows more of the background).
    pub fill_opacity: f64,
    /// Edge width in pixels.
    pub stroke_width: f64,
    /// Line segments drawn over the elements (boundaries of a stage), in image coordinates.
    pub overlay: Vec<[[f64; 2]; 2]>,
}

impl Default for SvgOptions {
    fn default() -> Self {
        Self {
            background: None,
            fill_opacity: 1.0,
            stroke_width: 0.1,
            overlay: Vec::new(),
        }
    }
}

/// The SVG text of `mesh`.
pub fn svg_string(mesh: &SegmentedMeshData, options: &SvgOptions) -> String {
    let (w, h) = (mesh.width, mesh.height);
    let mut s = String::new();
    let scale = (1200.0 / f64::from(w.max(h).max(1))).max(1.0);
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" viewBox=\"0 0 {w} {h}\" width=\"{}\" height=\"{}\">",
        f64::from(w) * scale,
        f64::from(h) * scale
    );
    if let Some(bg) = &options.background {
        let _ = writeln!(
            s,
            "<image href=\"{}\" x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" style=\"image-rendering:pixelated\"/>",
            xml_escape(bg)
        );
    }
    let _ = writeln!(
        s,
        "<g stroke=\"#202020\" stroke-width=\"{}\" stroke-linejoin=\"round\" fill-opacity=\"{}\">",
        options.stroke_width, options.fill_opacity
    );
    for (i, (e, &l)) in mesh.elements.iter().zip(&mesh.labels).enumerate() {
        let [r, g, b] = mesh
            .label_colours
            .get(l as usize)
            .copied()
            .unwrap_or([128; 3]);
        if let Some(d) = curved_outline(mesh, i) {
            let _ = writeln!(s, "<path d=\"{d}\" fill=\"#{r:02x}{g:02x}{b:02x}\"/>");
            continue;
        }
        let points: Vec<String> = e
            .corners()
            .iter()
            .map(|&v| {
                let p = mesh.vertices[v as usize];
                format!("{:.4},{:.4}", p[0], p[1])
            })
            .collect();
        let _ = writeln!(
            s,
            "<polygon points=\"{}\" fill=\"#{r:02x}{g:02x}{b:02x}\"/>",
            points.join(" ")
        );
    }
    let _ = writeln!(s, "</g>");
    if !options.overlay.is_empty() {
        let _ = write!(
            s,
            "<path fill=\"none\" stroke=\"#e02020\" stroke-width=\"{}\" stroke-linecap=\"round\" d=\"",
            3.0 * options.stroke_width
        );
        for [a, b] in &options.overlay {
            let _ = write!(s, "M{:.4} {:.4}L{:.4} {:.4}", a[0], a[1], b[0], b[1]);
        }
        let _ = writeln!(s, "\"/>");
    }
    let _ = writeln!(s, "</svg>");
    s
}

/// The outline of element `i` of a second-order mesh as an SVG path, when a side of it is bent:
/// each bent side the quadratic Bézier through its middle node (control point `2m − (a + b)/2`),
/// each straight one a line. `None` for an element with straight sides (drawn as a polygon).
fn curved_outline(mesh: &SegmentedMeshData, i: usize) -> Option<String> {
    let so = mesh.second_order.as_ref()?;
    let c = mesh.elements[i].corners();
    let n = c.len();
    let mut d = String::new();
    let mut bent = false;
    let corner = |k: usize| mesh.vertices[c[k % n] as usize];
    let _ = write!(d, "M{:.4} {:.4}", corner(0)[0], corner(0)[1]);
    for k in 0..n {
        let (a, b, m) = (corner(k), corner(k + 1), mesh.node(so.sides[i][k] as usize));
        let control = [
            2.0 * m[0] - 0.5 * (a[0] + b[0]),
            2.0 * m[1] - 0.5 * (a[1] + b[1]),
        ];
        if m != [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])] {
            bent = true;
            let _ = write!(d, "Q{:.4} {:.4} ", control[0], control[1]);
        } else {
            d.push('L');
        }
        let _ = write!(d, "{:.4} {:.4}", b[0], b[1]);
    }
    d.push('Z');
    bent.then_some(d)
}

/// Writes the SVG picture of `mesh`, atomically.
///
/// # Errors
/// [`WriteError`] when the mesh is inconsistent or the file cannot be written.
pub fn write_svg(
    path: &Path,
    mesh: &SegmentedMeshData,
    options: &SvgOptions,
) -> Result<(), WriteError> {
    check(path, mesh)?;
    write_atomic(path, svg_string(mesh, options).as_bytes())
}
