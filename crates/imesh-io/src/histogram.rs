//! Quality histograms before and after optimisation as a PNG, like the paper's Figure 7: one
//! panel per metric, the bins of the "before" distribution in grey beside those of "after" in
//! blue, on a common count axis.

use std::path::Path;

use image::{ImageFormat, Rgb, RgbImage};
use imageproc::drawing::{draw_filled_rect_mut, draw_line_segment_mut};
use imageproc::rect::Rect;
use imesh_quality::Histogram;

use crate::{write_atomic, WriteError};

/// One panel: a title (capitals, digits and spaces) and the two distributions over the same bins.
#[derive(Clone, Copy, Debug)]
pub struct HistogramPanel<'a> {
    /// The metric's name, e.g. `"SHAPE AND SIZE"`.
    pub title: &'a str,
    /// Before optimisation.
    pub before: &'a Histogram,
    /// After optimisation.
    pub after: &'a Histogram,
}

const PANEL_W: u32 = 520;
const PANEL_H: u32 = 260;
const MARGIN: u32 = 40;
const GREY: Rgb<u8> = Rgb([150, 150, 150]);
const BLUE: Rgb<u8> = Rgb([40, 90, 200]);
const INK: Rgb<u8> = Rgb([30, 30, 30]);

/// 3 × 5 pixel glyphs: each row three bits, left to right.
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        'A' => [2, 5, 7, 5, 5],
        'B' => [6, 5, 6, 5, 6],
        'C' => [7, 4, 4, 4, 7],
        'D' => [6, 5, 5, 5, 6],
        'E' => [7, 4, 6, 4, 7],
        'F' => [7, 4, 6, 4, 4],
        'H' => [5, 5, 7, 5, 5],
        'I' => [7, 2, 2, 2, 7],
        'J' => [1, 1, 1, 5, 7],
        'L' => [4, 4, 4, 4, 7],
        'N' => [5, 7, 7, 7, 5],
        'O' => [7, 5, 5, 5, 7],
        'P' => [7, 5, 7, 4, 4],
        'R' => [6, 5, 6, 5, 5],
        'S' => [7, 4, 7, 1, 7],
        'T' => [7, 2, 2, 2, 2],
        'Z' => [7, 1, 2, 4, 7],
        _ => return None,
    })
}

/// Writes `text` with its top-left corner at `(x, y)`, each glyph pixel a `scale` × `scale`
/// square; characters without a glyph are spaces.
fn draw_text(img: &mut RgbImage, x: i32, y: i32, scale: u32, text: &str, colour: Rgb<u8>) {
    for (k, c) in text.chars().enumerate() {
        let Some(rows) = glyph(c) else { continue };
        let x0 = x + (k as i32) * 4 * scale as i32;
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    let rect = Rect::at(x0 + col * scale as i32, y + r as i32 * scale as i32)
                        .of_size(scale, scale);
                    draw_filled_rect_mut(img, rect, colour);
                }
            }
        }
    }
}

/// Draws the panels one above the other.
///
/// ```
/// use imesh_io::{histogram_picture, HistogramPanel};
/// use imesh_quality::Histogram;
/// let before = Histogram::of(&[0.1, 0.2, 0.2, 0.5], 0.0, 1.0, 10);
/// let after = Histogram::of(&[0.6, 0.7, 0.9, 0.9], 0.0, 1.0, 10);
/// let picture = histogram_picture(&[HistogramPanel { title: "SHAPE", before: &before, after: &after }]);
/// assert_eq!(picture.height(), 260);
/// ```
pub fn histogram_picture(panels: &[HistogramPanel<'_>]) -> RgbImage {
    let mut img = RgbImage::from_pixel(
        PANEL_W,
        PANEL_H * panels.len().max(1) as u32,
        Rgb([255, 255, 255]),
    );
    for (p, panel) in panels.iter().enumerate() {
        let top = (PANEL_H * p as u32) as f32;
        let (x0, x1) = (MARGIN as f32, (PANEL_W - 10) as f32);
        let (y0, y1) = (top + 30.0, top + (PANEL_H - MARGIN) as f32);
        draw_text(&mut img, MARGIN as i32, top as i32 + 8, 2, panel.title, INK);
        // Legend: grey before, blue after.
        let legend = PANEL_W as i32 - 190;
        draw_filled_rect_mut(
            &mut img,
            Rect::at(legend, top as i32 + 8).of_size(10, 10),
            GREY,
        );
        draw_text(&mut img, legend + 14, top as i32 + 8, 2, "BEFORE", INK);
        draw_filled_rect_mut(
            &mut img,
            Rect::at(legend + 80, top as i32 + 8).of_size(10, 10),
            BLUE,
        );
        draw_text(&mut img, legend + 94, top as i32 + 8, 2, "AFTER", INK);
        let bins = panel
            .before
            .counts
            .len()
            .max(panel.after.counts.len())
            .max(1);
        let highest = panel
            .before
            .counts
            .iter()
            .chain(&panel.after.counts)
            .copied()
            .max()
            .unwrap_or(0)
            .max(1) as f32;
        let slot = (x1 - x0) / bins as f32;
        for b in 0..bins {
            for (k, (h, colour)) in [(panel.before, GREY), (panel.after, BLUE)]
                .into_iter()
                .enumerate()
            {
                let count = h.counts.get(b).copied().unwrap_or(0) as f32;
                let height = ((y1 - y0) * count / highest).round() as u32;
                if height == 0 {
                    continue;
                }
                let left = x0 + slot * b as f32 + 1.0 + k as f32 * (slot - 2.0) / 2.0;
                let width = (((slot - 2.0) / 2.0).floor() as u32).max(1);
                let rect =
                    Rect::at(left as i32, (y1 as u32 - height) as i32).of_size(width, height);
                draw_filled_rect_mut(&mut img, rect, colour);
            }
        }
        draw_line_segment_mut(&mut img, (x0, y1), (x1, y1), INK);
        draw_line_segment_mut(&mut img, (x0, y0), (x0, y1), INK);
        // Ticks and labels at the range's ends and middle, and the highest count.
        let (lo, hi) = (panel.before.lo, panel.before.hi);
        for (t, v) in [(0.0f32, lo), (0.5, 0.5 * (lo + hi)), (1.0, hi)] {
            let x = x0 + t * (x1 - x0);
            draw_line_segment_mut(&mut img, (x, y1), (x, y1 + 4.0), INK);
            let label = format!("{v}");
            draw_text(&mut img, x as i32 - 6, y1 as i32 + 8, 2, &label, INK);
        }
        draw_text(
            &mut img,
            2,
            y0 as i32,
            2,
            &format!("{}", highest as usize),
            INK,
        );
    }
    img
}

/// Writes the panels as a PNG at `path` (atomically).
///
/// # Errors
/// [`WriteError`] when the file cannot be written.
pub fn write_histogram(path: &Path, panels: &[HistogramPanel<'_>]) -> Result<(), WriteError> {
    let img = histogram_picture(panels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, ImageFormat::Png)
        .map_err(|e| WriteError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(e),
        })?;
    write_atomic(path, bytes.get_ref())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bars_are_as_tall_as_their_counts_and_coloured_by_series() {
        let before = Histogram::of(&[0.05, 0.05, 0.05, 0.05], 0.0, 1.0, 10);
        let after = Histogram::of(&[0.95, 0.95], 0.0, 1.0, 10);
        let img = histogram_picture(&[HistogramPanel {
            title: "SHAPE",
            before: &before,
            after: &after,
        }]);
        let count = |colour: Rgb<u8>| img.pixels().filter(|&&p| p == colour).count();
        // The after bar has half the count of the before bar: about half its pixels (besides the
        // legend swatches, 100 pixels each).
        let (grey, blue) = (count(GREY) - 100, count(BLUE) - 100);
        assert!(grey > 0 && blue > 0);
        let ratio = blue as f64 / grey as f64;
        assert!((ratio - 0.5).abs() < 0.02, "{ratio}");
        // The grey bar is in the first slot (left), the blue one in the last (right).
        let column_of = |colour: Rgb<u8>| {
            (0..img.width())
                .find(|&x| (40..200).any(|y| *img.get_pixel(x, y) == colour))
                .unwrap()
        };
        assert!(column_of(GREY) < 100 && column_of(BLUE) > 400);
    }
}
