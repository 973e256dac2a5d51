//! Builds one large triangulation, for profilers: `profile_grid grid|uniform N`.
use imesh_geom::{Point, Triangulation};
fn main() {
    let kind = std::env::args().nth(1).unwrap_or_else(|| "grid".into());
    let n: u32 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    let pts: Vec<Point> = if kind == "grid" {
        imesh_geom::sample::pixel_centres(n, n)
    } else {
        imesh_geom::sample::uniform_points(n as usize, 0x8765_4321, 1000.0)
    };
    let (t, _) = Triangulation::from_points(&pts).unwrap();
    println!("{}", t.num_triangles());
}
