//! The templates: a canonical triangle split into 3k² quads and a canonical square into 4k²
//! (DESIGN.md §2, step 8; the paper's Figure 3).
//!
//! Canonical domains: the triangle `(0, 0), (1, 0), (0, 1)` (coordinates = the weights of corners
//! 1 and 2) and the square `[0, 1]²` with corners `(0, 0), (1, 0), (1, 1), (0, 1)`, both
//! counter-clockwise. Level 1 joins the edge midpoints to the centroid (centre); level k splits each
//! of those quads k × k through its bilinear map. Points are computed in integers (multiples of
//! `1 / (6k²)`) so that points shared by two template quads are recognised exactly.

use std::collections::HashMap;

/// Where a template point lies on its canonical element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// At corner `i`.
    Corner(u8),
    /// On side `side` (from corner `side` to the next), at `position` of `2k` steps (0 < position
    /// < 2k).
    Side {
        /// The side.
        side: u8,
        /// Steps from the side's first corner.
        position: u32,
    },
    /// Strictly inside: the `i`-th inner point.
    Inside(u32),
}

/// A template at some level: its points (canonical coordinates and place) and its quads (indices
/// into the points, counter-clockwise).
#[derive(Clone, Debug)]
pub struct Template {
    /// Canonical coordinates of each point.
    pub coords: Vec<[f64; 2]>,
    /// Where each point lies.
    pub places: Vec<Place>,
    /// The quads.
    pub quads: Vec<[u32; 4]>,
    /// How many inner points there are.
    pub inside: u32,
    /// The level.
    pub level: u32,
    /// The Bézier basis weights of each point (see [`crate::patch::basis`]).
    pub weights: Vec<[f64; 16]>,
    /// The same weights without the zeros, as `(slot, weight)` in slot order: a corner has one,
    /// a point on a side four, so evaluating them costs a fraction of the sixteen-slot sum (and
    /// gives the same bits: the same products added in the same order).
    pub terms: Vec<Vec<(u8, f64)>>,
}

impl Template {
    /// The triangle template at level `k` (at least 1): 3k² quads.
    ///
    /// ```
    /// use imesh_quad::Template;
    /// let t = Template::triangle(2);
    /// assert_eq!(t.quads.len(), 12);
    /// ```
    pub fn triangle(k: u32) -> Self {
        let n = denominator(k);
        let (c0, c1, c2) = ([0, 0], [n, 0], [0, n]);
        let (m01, m12, m20) = ([n / 2, 0], [n / 2, n / 2], [0, n / 2]);
        let centre = [n / 3, n / 3];
        let coarse = [
            [c0, m01, centre, m20],
            [c1, m12, centre, m01],
            [c2, m20, centre, m12],
        ];
        build(k, &coarse, false, |[x, y]| classify_triangle(k, [x, y]))
    }

    /// The square template at level `k` (at least 1): 4k² quads.
    ///
    /// ```
    /// use imesh_quad::Template;
    /// assert_eq!(Template::quad(3).quads.len(), 36);
    /// ```
    pub fn quad(k: u32) -> Self {
        let n = denominator(k);
        let (c0, c1, c2, c3) = ([0, 0], [n, 0], [n, n], [0, n]);
        let (m01, m12, m23, m30) = ([n / 2, 0], [n, n / 2], [n / 2, n], [0, n / 2]);
        let centre = [n / 2, n / 2];
        let coarse = [
            [c0, m01, centre, m30],
            [c1, m12, centre, m01],
            [c2, m23, centre, m12],
            [c3, m30, centre, m23],
        ];
        build(k, &coarse, true, |[x, y]| classify_square(k, [x, y]))
    }
}

/// The common denominator of every template coordinate at level `k`.
fn denominator(k: u32) -> i64 {
    6 * i64::from(k) * i64::from(k)
}

/// Splits each coarse quad k × k and numbers the points, shared ones once.
fn build(
    k: u32,
    coarse: &[[[i64; 2]; 4]],
    quad: bool,
    classify: impl Fn([i64; 2]) -> Place,
) -> Template {
    let n = denominator(k) as f64;
    let ki = i64::from(k);
    let mut index: HashMap<[i64; 2], u32> = HashMap::new();
    let mut coords = Vec::new();
    let mut places = Vec::new();
    let mut inside = 0;
    let mut quads = Vec::new();
    let mut id = |p: [i64; 2]| {
        *index.entry(p).or_insert_with(|| {
            let mut place = classify(p);
            if let Place::Inside(i) = &mut place {
                *i = inside;
                inside += 1;
            }
            coords.push([p[0] as f64 / n, p[1] as f64 / n]);
            places.push(place);
            (coords.len() - 1) as u32
        })
    };
    for &[a, b, c, d] in coarse {
        // The bilinear map of the coarse quad at (i / k, j / k), exactly: every coordinate is a
        // multiple of 1 / (6k²).
        let at = |i: i64, j: i64| -> [i64; 2] {
            let f = |x: usize| {
                (a[x] * (ki - i) * (ki - j)
                    + b[x] * i * (ki - j)
                    + c[x] * i * j
                    + d[x] * (ki - i) * j)
                    / (ki * ki)
            };
            [f(0), f(1)]
        };
        for j in 0..ki {
            for i in 0..ki {
                quads.push([
                    id(at(i, j)),
                    id(at(i + 1, j)),
                    id(at(i + 1, j + 1)),
                    id(at(i, j + 1)),
                ]);
            }
        }
    }
    let weights: Vec<[f64; 16]> = coords
        .iter()
        .map(|&uv| crate::patch::basis(quad, uv))
        .collect();
    let terms = weights
        .iter()
        .map(|w| {
            (0u8..16)
                .zip(w)
                .filter(|&(_, &w)| w != 0.0)
                .map(|(slot, &w)| (slot, w))
                .collect()
        })
        .collect();
    Template {
        coords,
        places,
        quads,
        inside,
        level: k,
        weights,
        terms,
    }
}

fn classify_triangle(k: u32, [x, y]: [i64; 2]) -> Place {
    let n = denominator(k);
    let step = n / (2 * i64::from(k));
    match (x, y) {
        (0, 0) => Place::Corner(0),
        (x, 0) if x == n => Place::Corner(1),
        (0, y) if y == n => Place::Corner(2),
        (x, 0) => side(0, x / step),
        (x, y) if x + y == n => side(1, y / step),
        (0, y) => side(2, (n - y) / step),
        _ => Place::Inside(0),
    }
}

fn classify_square(k: u32, [x, y]: [i64; 2]) -> Place {
    let n = denominator(k);
    let step = n / (2 * i64::from(k));
    match (x, y) {
        (0, 0) => Place::Corner(0),
        (x, 0) if x == n => Place::Corner(1),
        (x, y) if x == n && y == n => Place::Corner(2),
        (0, y) if y == n => Place::Corner(3),
        (x, 0) => side(0, x / step),
        (x, y) if x == n => side(1, y / step),
        (x, y) if y == n => side(2, (n - x) / step),
        (0, y) => side(3, (n - y) / step),
        _ => Place::Inside(0),
    }
}

fn side(side: u8, position: i64) -> Place {
    Place::Side {
        side,
        position: position as u32,
    }
}
