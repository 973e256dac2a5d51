//! Builds one large triangulation, for profilers: `profile_grid grid|uniform N`.
use imesh_geom::{Point, Triangulation};
fn main() {
    let kind = std::env::args().nth(1).unwrap_or_else(|| "grid".into());
    let n: u32 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    let pts: Vec<Point> = if kind == "grid" {
        (0..n)
            .flat_map(|r| (0..n).map(move |c| Point::pixel_centre(c, r)))
            .collect()
    } else {
        let mut s = 0x8765_4321u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 1000.0
        };
        (0..n).map(|_| Point::new(next(), next())).collect()
    };
    let (t, _) = Triangulation::from_points(&pts).unwrap();
    println!("{}", t.num_triangles());
}
