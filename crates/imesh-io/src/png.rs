//! PNG pictures: the mesh rasterised, elements filled with their label's colour, edges drawn.

use std::path::Path;

use image::{Rgb, RgbImage};
use imageproc::drawing::draw_line_segment_mut;

use crate::{check, write_atomic, SegmentedMeshData, WriteError};

/// Rasterises `mesh` at `scale` output pixels per image pixel: every output pixel whose centre
/// lies in an element (edges included) takes the element's label colour, then the edges are
/// drawn in dark grey when `edges` is set.
///
/// ```
/// use imesh_io::{rasterise, SegmentedMeshData};
/// use imesh_quality::Element;
/// let mesh = SegmentedMeshData {
///     vertices: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]],
///     elements: vec![Element::Quad([0, 1, 2, 3])],
///     labels: vec![0],
///     label_names: vec!["a".into()],
///     label_colours: vec![[10, 200, 30]],
///     width: 4,
///     height: 2,
///     second_order: None,
/// };
/// let picture = rasterise(&mesh, 2.0, false);
/// assert_eq!(picture.dimensions(), (8, 4));
/// assert_eq!(picture.get_pixel(3, 2).0, [10, 200, 30]);
/// ```
pub fn rasterise(mesh: &SegmentedMeshData, scale: f64, edges: bool) -> RgbImage {
    let (w, h) = (
        ((f64::from(mesh.width) * scale).round() as u32).max(1),
        ((f64::from(mesh.height) * scale).round() as u32).max(1),
    );
    let mut picture = RgbImage::from_pixel(w, h, Rgb([255, 255, 255]));
    for (e, &l) in mesh.elements.iter().zip(&mesh.labels) {
        let colour = Rgb(mesh
            .label_colours
            .get(l as usize)
            .copied()
            .unwrap_or([128; 3]));
        let p: Vec<[f64; 2]> = e
            .corners()
            .iter()
            .map(|&v| {
                let q = mesh.vertices[v as usize];
                [q[0] * scale, q[1] * scale]
            })
            .collect();
        let (lo, hi) = crate::msh::bounds(&p);
        let x0 = (lo[0].floor().max(0.0)) as u32;
        let y0 = (lo[1].floor().max(0.0)) as u32;
        let x1 = (hi[0].ceil() as u32).min(w);
        let y1 = (hi[1].ceil() as u32).min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let c = [f64::from(x) + 0.5, f64::from(y) + 0.5];
                // Valid elements (positive corners) are convex: inside means on the inner side
                // of every edge.
                let inside = (0..p.len()).all(|i| {
                    let (a, b) = (p[i], p[(i + 1) % p.len()]);
                    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) >= 0.0
                });
                if inside {
                    picture.put_pixel(x, y, colour);
                }
            }
        }
    }
    if edges {
        let ink = Rgb([32, 32, 32]);
        for e in &mesh.elements {
            let c = e.corners();
            for i in 0..c.len() {
                let (a, b) = (
                    mesh.vertices[c[i] as usize],
                    mesh.vertices[c[(i + 1) % c.len()] as usize],
                );
                draw_line_segment_mut(
                    &mut picture,
                    ((a[0] * scale) as f32, (a[1] * scale) as f32),
                    ((b[0] * scale) as f32, (b[1] * scale) as f32),
                    ink,
                );
            }
        }
    }
    picture
}

/// Writes the PNG picture of `mesh` (about 1200 pixels on its longer side, never less than one
/// output pixel per image pixel), atomically.
///
/// # Errors
/// [`WriteError`] when the mesh is inconsistent or the file cannot be written.
pub fn write_png(path: &Path, mesh: &SegmentedMeshData) -> Result<(), WriteError> {
    check(path, mesh)?;
    let scale = (1200.0 / f64::from(mesh.width.max(mesh.height).max(1))).max(1.0);
    let picture = rasterise(mesh, scale, true);
    let mut bytes = Vec::new();
    picture
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| WriteError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(e),
        })?;
    write_atomic(path, &bytes)
}
