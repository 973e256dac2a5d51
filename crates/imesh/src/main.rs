//! The `imesh` command line: parses arguments, runs the [`imesh::Pipeline`], writes the outputs.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use imesh::{
    Elements, MeshOptions, MetricName, OptimizerMethod, PairingMethod, Pipeline, PipelineResult,
};
use imesh_classify::{classify, load_image, Classifier, ClassifyOptions, DEFAULT_MAX_PIXELS};
use imesh_io::SegmentedMeshData;
use imesh_io::{
    read_mesh, svg_string, write_atomic, write_histogram, write_inp, write_msh, write_msh22,
    write_png, write_svg, write_vtk, write_vtu, Frame, HistogramPanel, SvgOptions,
};
use imesh_quality::{Element, QuadQuality, TriangleQuality};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

#[derive(Parser)]
#[command(
    name = "imesh",
    version,
    about = "Image to segmented, simulation-ready mesh: every region of the image becomes a conforming set of good elements."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh an image: classify its pixels into regions, sample it with Imesh, and write a labelled
    /// mesh with one physical group per region.
    #[command(
        after_help = "Example:\n  imesh mesh fixtures/images/skimage-coins.png -o coins.msh --svg coins.svg --report coins.json"
    )]
    Mesh(MeshArgs),
    /// Classify an image into labelled regions and save the label image (one colour per label).
    #[command(
        after_help = "Example:\n  imesh classify fixtures/images/skimage-coffee.png --classify kmeans:4 -o coffee-labels.png"
    )]
    Classify(ClassifyArgs),
    /// Measure a mesh file's quality with Verdict's metrics (as VTK computes them): Gmsh MSH 4.1 or
    /// 2.2, legacy VTK or VTK XML (ASCII), or Abaqus .inp.
    #[command(after_help = "Example:\n  imesh quality coins.msh --json")]
    Quality(QualityArgs),
    /// Mesh every image of a folder, in parallel; one failure does not stop the others.
    #[command(after_help = "Example:\n  imesh batch fixtures/images -o meshes --format vtu")]
    Batch(BatchArgs),
}

#[derive(Args)]
struct MeshArgs {
    /// The image (PNG, JPEG, TIFF, BMP, ...).
    image: PathBuf,
    /// Output mesh: .msh (Gmsh 4.1, or 2.2 with --msh-version), .vtu (VTK XML), .vtk (legacy
    /// VTK) or .inp (Abaqus). Default: IMAGE's name with .msh, in the current directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[command(flatten)]
    flags: MeshFlags,
    /// Also draw the mesh as SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Draw the SVG over the input image (referred to by its absolute path), elements
    /// half-transparent.
    #[arg(long, requires = "svg")]
    svg_over_image: bool,
    /// Also draw the mesh as PNG.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Also draw the quality histograms before and after optimisation (PNG; quads only).
    #[arg(long)]
    histogram: Option<PathBuf>,
    /// Also draw every stage into this folder (created if needed): the labels, the Imesh
    /// triangles, the c-edges, the simplified boundaries G', DT', the pairing, the template
    /// mesh, the adapted mesh and the result, as SVG over the label image.
    #[arg(long)]
    stages: Option<PathBuf>,
    /// Also write the JSON report (counts, per-stage seconds, quality, label agreement).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct BatchArgs {
    /// The folder of images (PNG, JPEG, TIFF, BMP, PNM files in it; not its subfolders).
    dir: PathBuf,
    /// The folder for the meshes and their JSON reports (created if missing).
    #[arg(short, long)]
    output: PathBuf,
    /// Mesh format: msh, vtu, vtk or inp.
    #[arg(long, default_value = "msh")]
    format: String,
    #[command(flatten)]
    flags: MeshFlags,
}

/// The mesh options `mesh` and `batch` share.
#[derive(Args)]
struct MeshFlags {
    /// Gmsh file version of a .msh output: 4.1, or 2.2 for readers that know no other (MFEM,
    /// OpenFOAM's gmshToFoam, older FEniCS tools) [default: 4.1].
    #[arg(long, value_parser = ["4.1", "2.2"])]
    msh_version: Option<String>,
    /// Options from a TOML file (command-line options override it).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Classifier: auto, labels, otsu[:K], threshold:T1,T2, kmeans:K, texture:SAMPLES.toml.
    #[arg(long)]
    classify: Option<String>,
    /// Imesh error threshold (smaller: more vertices, closer boundaries) [default: 0.1].
    #[arg(long)]
    te: Option<f64>,
    /// Smallest triangle angle in degrees, at most 34: of the triangles paired into quads
    /// [default: 20.7], or of the triangle mesh [default: 26.4].
    #[arg(long)]
    min_angle: Option<f64>,
    /// Most points the quality refinement may insert.
    #[arg(long)]
    max_steiner: Option<usize>,
    /// Largest element size in pixels: no triangle (before pairing) gets larger than the
    /// equilateral one of this side.
    #[arg(long)]
    max_size: Option<f64>,
    /// Quad size: auto (uniform, a side chosen from the image: about 10 000 quads, finer where
    /// its regions are narrow), a side in pixels (uniform: a square lattice inside, refined
    /// along the boundaries), or graded (the paper's: fine at the boundaries, coarse inside;
    /// fewer quads, lower shape-and-size) [default: auto].
    #[arg(long)]
    size: Option<imesh::ElementSize>,
    /// Merge regions smaller than this many pixels into their neighbour before meshing
    /// [default: 0, keep every region].
    #[arg(long)]
    min_region: Option<usize>,
    /// Majority filter of this radius over the labels before meshing: removes specks, notches
    /// and strips thinner than about the radius; 0 for none [default: auto, about one quad side
    /// for uniform quads, none otherwise].
    #[arg(long)]
    majority: Option<AutoOr<u32>>,
    /// Merge regions thinner than this many pixels (twice their area over their perimeter) into
    /// their neighbour (quads); 0 keeps every region [default: auto, three quarters of the
    /// finest quad side for uniform quads (1.5 px at the 2 px floor), none otherwise].
    #[arg(long)]
    min_width: Option<AutoOr<f64>>,
    /// Give the parts of regions thinner than this many pixels (strips, necks, arms between
    /// wider parts) to the regions beside them before meshing; 0 keeps every part [default:
    /// auto, one quad side for uniform quads, none otherwise].
    #[arg(long)]
    min_part_width: Option<AutoOr<f64>>,
    /// Keep the regions' tips sharper than 30° as the image has them (the quad there keeps a
    /// corner that sharp) instead of cutting them off where they are a quad side or two wide
    /// (uniform quads; the report's counts.blunted_tips and blunted_area_px).
    #[arg(long)]
    keep_sharp_tips: bool,
    /// How far the optimiser may move a corner or a junction of the boundaries (off the image's
    /// border) to open a corner under 30° or give a small quad room, as a share of the quad
    /// side; 0 keeps them where the boundaries put them [default: 0.35].
    #[arg(long)]
    corner_reach: Option<f64>,
    /// Mesh a reduced grid whose cells are the most common label of about F × F pixels, then
    /// scale the mesh back: auto (uniform quads 8 px wide or more, e.g. a large image or a
    /// large --size: F makes them 4 to 8 cells wide), 1 (never) or F. Options given in pixels
    /// are converted to cells [default: auto].
    #[arg(long)]
    reduction: Option<AutoOr<u32>>,
    /// Curve simplification tolerance in pixels [default: 2, or 2 cells of a reduced grid].
    #[arg(long)]
    tolerance: Option<f64>,
    /// Template level k: each triangle gives 3k² quads, each paired quad 4k² [default: 1].
    #[arg(long)]
    template_level: Option<u32>,
    /// Pairing of triangles into quads: matching (best quads first, every corner within
    /// 30°–150°), fewest (the matching with corners down to 20.5°: fewest triangles left) or
    /// greedy (the paper's) [default: matching].
    #[arg(long)]
    pairing: Option<PairingMethod>,
    /// Element kind: quad (all-quad mesh) or tri (the Imesh triangle mesh) [default: quad].
    #[arg(long)]
    elements: Option<Elements>,
    /// Element order: 1 (linear) or 2 (quadratic: a node in the middle of every side, on the
    /// boundary curve where the side follows one, and one at each quad's centre; 9-node quads
    /// and 6-node triangles, 8-node quads in .inp) [default: 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=2))]
    order: Option<u32>,
    /// Quad optimisation: local (control points, block by block), global (the paper's single
    /// Powell run; slow), laplacian or vertex (baselines), none [default: local].
    #[arg(long)]
    optimizer: Option<OptimizerMethod>,
    /// The quality the optimiser maximises: shape-and-size or shape [default: shape-and-size].
    #[arg(long)]
    metric: Option<MetricName>,
    /// Physical size of a pixel: SX or SX,SY.
    #[arg(long, value_parser = parse_pixel_size)]
    pixel_size: Option<[f64; 2]>,
    /// Where the image's bottom-left corner lies in the written mesh: X,Y, in the pixel size's
    /// units [default: 0,0].
    #[arg(long, value_parser = parse_origin, allow_hyphen_values = true)]
    origin: Option<[f64; 2]>,
    /// Largest image accepted, in pixels [default: 268435456, a 16384 × 16384 image].
    #[arg(long)]
    max_pixels: Option<u64>,
    /// Most labels a label map may have [default: 65536].
    #[arg(long)]
    max_labels: Option<usize>,
    /// Most elements the mesh may have; a run that would make more stops early with an error
    /// [default: 5000000].
    #[arg(long)]
    max_elements: Option<u64>,
}

#[derive(Args)]
struct QualityArgs {
    /// The mesh (.msh, .vtk, .vtu or .inp).
    mesh: PathBuf,
    /// Print the statistics as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct ClassifyArgs {
    /// The image.
    image: PathBuf,
    /// Classifier: auto, labels, otsu[:K], threshold:T1,T2, kmeans:K, texture:SAMPLES.toml.
    #[arg(long, default_value = "auto")]
    classify: String,
    /// The label image to write (PNG).
    #[arg(short, long)]
    output: PathBuf,
}

/// A finite number of a comma-separated option.
fn finite_number(p: &str) -> Result<f64, String> {
    match p.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{p:?} is not a finite number")),
    }
}

fn parse_pixel_size(s: &str) -> Result<[f64; 2], String> {
    match s.split(',').collect::<Vec<_>>().as_slice() {
        [x] => {
            let x = finite_number(x)?;
            Ok([x, x])
        }
        [x, y] => Ok([finite_number(x)?, finite_number(y)?]),
        _ => Err("give SX or SX,SY".into()),
    }
}

fn parse_origin(s: &str) -> Result<[f64; 2], String> {
    match s.split(',').collect::<Vec<_>>().as_slice() {
        [x, y] => Ok([finite_number(x)?, finite_number(y)?]),
        _ => Err("give X,Y".into()),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Mesh(args) => mesh(&args),
        Command::Classify(args) => classify_command(&args),
        Command::Quality(args) => quality_command(&args),
        Command::Batch(args) => batch(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("imesh: {message}");
            ExitCode::from(2)
        }
    }
}

fn options(args: &MeshFlags) -> Result<MeshOptions, String> {
    let mut o = match &args.config {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read the config {}: {e}", path.display()))?;
            toml_options(&text).map_err(|e| format!("config {}: {e}", path.display()))?
        }
        None => MeshOptions::default(),
    };
    if let Some(c) = &args.classify {
        o.classify.clone_from(c);
    }
    if let Some(te) = args.te {
        o.te = te;
    }
    if let Some(a) = args.min_angle {
        o.min_angle = Some(a);
    }
    if let Some(t) = args.tolerance {
        o.tolerance = Some(t);
    }
    if let Some(k) = args.template_level {
        o.template_level = k;
    }
    if let Some(k) = args.order {
        o.order = k;
    }
    if let Some(p) = args.pairing {
        o.pairing = p;
    }
    if let Some(m) = args.optimizer {
        o.optimizer = m;
    }
    if let Some(m) = args.metric {
        o.metric = m;
    }
    if let Some(n) = args.max_steiner {
        o.max_steiner = Some(n);
    }
    if let Some(s) = args.max_size {
        o.max_size = Some(s);
    }
    if let Some(s) = args.size {
        o.size = s;
    }
    if let Some(n) = args.min_region {
        o.min_region = n;
    }
    if let Some(r) = args.majority {
        o.majority = r.value();
    }
    if let Some(w) = args.min_width {
        o.min_width = w.value();
    }
    if let Some(w) = args.min_part_width {
        o.min_part_width = w.value();
    }
    if let Some(f) = args.reduction {
        o.reduction = f.value();
    }
    if args.keep_sharp_tips {
        o.keep_sharp_tips = true;
    }
    if let Some(r) = args.corner_reach {
        o.corner_reach = r;
    }
    if let Some(e) = args.elements {
        o.elements = e;
    }
    if let Some(p) = args.pixel_size {
        o.pixel_size = p;
    }
    if let Some(p) = args.origin {
        o.origin = p;
    }
    if let Some(n) = args.max_pixels {
        o.max_pixels = n;
    }
    if let Some(n) = args.max_labels {
        o.max_labels = n;
    }
    if let Some(n) = args.max_elements {
        o.max_elements = n;
    }
    Ok(o)
}

fn toml_options(text: &str) -> Result<MeshOptions, String> {
    toml::from_str(text).map_err(|e| e.to_string())
}

/// The mesh formats, by file extension.
const FORMATS: [&str; 4] = ["msh", "vtu", "vtk", "inp"];

fn format_of(output: &Path) -> Result<String, String> {
    let format = output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if FORMATS.contains(&format.as_str()) {
        Ok(format)
    } else {
        Err(format!(
            "cannot write {}: use an output ending in .msh (Gmsh), .vtu (VTK XML), .vtk (legacy VTK) or .inp (Abaqus)",
            output.display()
        ))
    }
}

/// What `--order 2` made: the node count, and the sides that follow the boundary curves.
fn second_order_note(c: &imesh::Counts) -> String {
    let mut note = format!(
        "second order: {} nodes; {} side{} bent along the boundary curves",
        c.nodes,
        c.curved_sides,
        if c.curved_sides == 1 { "" } else { "s" }
    );
    if c.damped_sides + c.straightened_sides > 0 {
        note += &format!(
            " ({} of them only part of the way and {} left straight, so that no quad's Jacobian falls under half its straight self's)",
            c.damped_sides, c.straightened_sides
        );
    }
    note
}

/// `format` (a name of [`FORMATS`]) as [`write_mesh`] takes it: `msh22` for a .msh output of
/// version 2.2.
fn with_msh_version(format: String, version: Option<&str>) -> Result<String, String> {
    match (format.as_str(), version) {
        ("msh", Some("2.2")) => Ok("msh22".into()),
        ("msh", _) | (_, None) => Ok(format),
        (other, Some(_)) => Err(format!(
            "--msh-version is for a .msh output, not .{other}: drop it or write a .msh file"
        )),
    }
}

/// The file extension of a [`write_mesh`] format.
fn extension_of(format: &str) -> &str {
    if format == "msh22" {
        "msh"
    } else {
        format
    }
}

/// Writes the mesh in the format its name says, with the elements' shape as cell data where the
/// format holds it.
fn write_mesh(
    output: &Path,
    format: &str,
    mesh: &SegmentedMeshData,
    frame: &Frame,
) -> Result<(), String> {
    let io = |e: imesh_io::WriteError| e.to_string();
    let cell_data = || {
        let shape: Vec<f64> = mesh
            .elements
            .iter()
            .map(|e| {
                let p = |v: u32| mesh.vertices[v as usize];
                match *e {
                    imesh_quality::Element::Triangle(t) => imesh_quality::tri::shape(&t.map(p)),
                    imesh_quality::Element::Quad(q) => imesh_quality::quad::shape(&q.map(p)),
                }
            })
            .collect();
        vec![("shape".to_string(), shape)]
    };
    match format {
        "msh" => write_msh(output, mesh, frame).map_err(io),
        "msh22" => write_msh22(output, mesh, frame).map_err(io),
        "inp" => write_inp(output, mesh, frame).map_err(io),
        "vtk" => write_vtk(output, mesh, frame, &cell_data()).map_err(io),
        _ => write_vtu(output, mesh, frame, &cell_data()).map_err(io),
    }
}

/// [`write_mesh`], its seconds added to the report's (`timings_s.write`, and the total).
fn write_timed_mesh(
    output: &Path,
    format: &str,
    mesh: &SegmentedMeshData,
    frame: &Frame,
    report: &mut imesh::Report,
) -> Result<(), String> {
    let clock = std::time::Instant::now();
    write_mesh(output, format, mesh, frame)?;
    let seconds = clock.elapsed().as_secs_f64();
    report.seconds.write = seconds;
    report.seconds.total += seconds;
    Ok(())
}

fn write_report(path: &Path, report: &imesh::Report) -> Result<(), String> {
    let json = serde_json::to_string_pretty(report).map_err(|e| e.to_string())?;
    write_atomic(path, json.as_bytes()).map_err(|e| e.to_string())
}

/// Writes the label image and one SVG per stage picture into `dir`.
fn write_stages(
    dir: &Path,
    mesh: &SegmentedMeshData,
    stages: &[imesh::StagePicture],
    labels: Option<&image::RgbImage>,
) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the stages folder {}: {e}", dir.display()))?;
    let background = "00-labels.png";
    if let Some(picture) = labels {
        let mut png = Vec::new();
        picture
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| e.to_string())?;
        write_atomic(&dir.join(background), &png).map_err(|e| e.to_string())?;
    }
    for stage in stages {
        let picture = SegmentedMeshData {
            vertices: stage.vertices.clone(),
            elements: stage.elements.clone(),
            labels: stage.labels.clone(),
            second_order: None,
            ..mesh.clone()
        };
        let options = SvgOptions {
            background: Some(background.into()),
            fill_opacity: 0.75,
            overlay: stage.lines.clone(),
            ..SvgOptions::default()
        };
        let path = dir.join(format!("{}.svg", stage.name));
        write_atomic(&path, svg_string(&picture, &options).as_bytes())
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn quality_command(args: &QualityArgs) -> Result<(), String> {
    let mesh = read_mesh(&args.mesh).map_err(|e| e.to_string())?;
    let (mut quads, mut triangles) = (Vec::new(), Vec::new());
    for e in &mesh.elements {
        match *e {
            Element::Quad(q) => quads.push(q),
            Element::Triangle(t) => triangles.push(t),
        }
    }
    if quads.is_empty() && triangles.is_empty() {
        return Err(format!(
            "{} holds no triangles or quads: nothing to measure",
            args.mesh.display()
        ));
    }
    let quad_quality = (!quads.is_empty()).then(|| QuadQuality::of(&mesh.vertices, &quads));
    let triangle_quality =
        (!triangles.is_empty()).then(|| TriangleQuality::of(&mesh.vertices, &triangles));
    if args.json {
        let json = serde_json::json!({
            "vertices": mesh.vertices.len(),
            "quads": quads.len(),
            "triangles": triangles.len(),
            "quad_quality": quad_quality,
            "triangle_quality": triangle_quality,
        });
        println!("{json:#}");
        return Ok(());
    }
    println!(
        "{}: {} vertices, {} quads, {} triangles",
        args.mesh.display(),
        mesh.vertices.len(),
        quads.len(),
        triangles.len()
    );
    let row = |name: &str, s: &imesh_quality::Statistics| {
        println!(
            "  {name:<16} min {:>9.4}  mean {:>9.4}  max {:>9.4}  variance {:>9.2e}  below {} {:>6}",
            s.min, s.mean, s.max, s.variance, s.threshold, s.below
        );
    };
    if let Some(q) = &quad_quality {
        println!(
            "quads (shape-and-size against the mean quad area {:.4}):",
            q.average_area
        );
        row("shape-and-size", &q.shape_and_size);
        row("shape", &q.shape);
        row("scaled Jacobian", &q.scaled_jacobian);
        row("min angle (°)", &q.min_angle_deg);
        row("max angle (°)", &q.max_angle_deg);
    }
    if let Some(t) = &triangle_quality {
        println!("triangles:");
        row("shape", &t.shape);
        row("scaled Jacobian", &t.scaled_jacobian);
        row("min angle (°)", &t.min_angle_deg);
        row("max angle (°)", &t.max_angle_deg);
    }
    Ok(())
}

fn mesh(args: &MeshArgs) -> Result<(), String> {
    let options = options(&args.flags)?;
    let output = match &args.output {
        Some(p) => p.clone(),
        None => {
            let stem = args
                .image
                .file_stem()
                .ok_or_else(|| format!("{} has no file name", args.image.display()))?;
            PathBuf::from(stem).with_extension("msh")
        }
    };
    let format = with_msh_version(format_of(&output)?, args.flags.msh_version.as_deref())?;
    // Refuse a missing output folder before the work, not after it.
    for path in [
        Some(&output),
        args.svg.as_ref(),
        args.png.as_ref(),
        args.histogram.as_ref(),
        args.report.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
        if let Some(folder) = parent {
            if !folder.is_dir() {
                return Err(format!(
                    "the folder {} of {} does not exist: create it or write elsewhere",
                    folder.display(),
                    path.display()
                ));
            }
        }
    }
    if args.histogram.is_some() && options.elements == Elements::Tri {
        return Err(
            "--histogram shows the quads' quality before and after optimisation: drop --elements tri"
                .into(),
        );
    }
    let frame = Frame {
        pixel_size: options.pixel_size,
        origin: options.origin,
    };
    // A spinner naming the running stage, on stderr, only for a person watching.
    let bar = if args.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new_spinner();
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
            bar.set_style(style);
        }
        bar.enable_steady_tick(std::time::Duration::from_millis(100));
        bar
    };
    let shown = bar.clone();
    let mut pipeline =
        Pipeline::new(options).with_progress(move |stage| shown.set_message(stage.description()));
    if args.stages.is_some() {
        pipeline = pipeline.with_stages();
    }
    let result = pipeline.run_path(&args.image);
    bar.finish_and_clear();
    let PipelineResult {
        mesh,
        mut report,
        stages,
        label_picture,
    } = result.map_err(|e| e.to_string())?;
    if let Some(dir) = &args.stages {
        write_stages(dir, &mesh, &stages, label_picture.as_ref())?;
    }
    write_timed_mesh(&output, &format, &mesh, &frame, &mut report)?;
    if let Some(svg) = &args.svg {
        let options = if args.svg_over_image {
            let image = std::fs::canonicalize(&args.image)
                .map_err(|e| format!("cannot resolve {}: {e}", args.image.display()))?;
            SvgOptions {
                background: Some(image.display().to_string()),
                fill_opacity: 0.5,
                ..SvgOptions::default()
            }
        } else {
            SvgOptions::default()
        };
        write_svg(svg, &mesh, &options).map_err(|e| e.to_string())?;
    }
    if let Some(png) = &args.png {
        write_png(png, &mesh).map_err(|e| e.to_string())?;
    }
    if let Some(path) = &args.histogram {
        let h = report
            .histograms
            .as_ref()
            .ok_or("the quad mesh has no histograms")?;
        let panels = [
            HistogramPanel {
                title: "SHAPE AND SIZE",
                before: &h.shape_and_size_before,
                after: &h.shape_and_size_after,
            },
            HistogramPanel {
                title: "SCALED JACOBIAN",
                before: &h.scaled_jacobian_before,
                after: &h.scaled_jacobian_after,
            },
        ];
        write_histogram(path, &panels).map_err(|e| e.to_string())?;
    }
    if let Some(path) = &args.report {
        write_report(path, &report)?;
    }
    if !args.quiet {
        let c = &report.counts;
        let q = &report.quality;
        println!(
            "{}: {}×{} px, {} label{} → {} ({} vertices, {} quads, {} triangles) in {:.3} s",
            args.image.display(),
            c.width,
            c.height,
            c.image_labels,
            if c.image_labels == 1 { "" } else { "s" },
            output.display(),
            c.vertices,
            c.quads,
            c.triangles,
            report.seconds.total
        );
        let mut line = format!(
            "label agreement {:.2} %; smallest angle worst {:.1}°, mean {:.1}°; scaled Jacobian worst {:.3}, mean {:.3}",
            100.0 * report.label_agreement,
            q.min_angle_deg().min,
            q.min_angle_deg().mean,
            q.scaled_jacobian().min,
            q.scaled_jacobian().mean,
        );
        if let imesh::MeshQuality::Quads(quads) = q {
            line += &format!(
                "; shape-and-size worst {:.3}, mean {:.3}",
                quads.shape_and_size.min, quads.shape_and_size.mean
            );
        }
        println!("{line}");
        // A worst corner the boundaries force: say so, and where. Only a corner sharper than a
        // quad's should be (30°) is forced: a wider one is the mesh's own choice.
        if let Some(corner) = report.sharpest_boundary_corner {
            if corner.angle_deg < imesh_curves::MIN_CORNER_DEG
                && q.scaled_jacobian().min >= corner.scaled_jacobian - 1e-9
            {
                println!(
                    "the worst scaled Jacobian is a corner of {:.1}° between two boundaries at ({:.1}, {:.1}) px, which the quad there must keep (sharp in the image, and not widened within the curve tolerance)",
                    corner.angle_deg, corner.at[0], corner.at[1]
                );
            }
        }
        if c.nodes > c.vertices {
            println!("{}", second_order_note(c));
        }
        if c.blunted_tips > 0 {
            println!(
                "cut off {} region tip{} sharper than 30° where a quad side or two wide ({:.1} px² to their neighbours; --keep-sharp-tips keeps them)",
                c.blunted_tips,
                if c.blunted_tips == 1 { "" } else { "s" },
                c.blunted_area_px
            );
        }
        for note in clean_up_notes(c, &report.fidelity) {
            println!("{note}");
        }
        if c.reduction > 1 {
            println!(
                "meshed on a {}×{} grid of cells of about {f}×{f} px (--reduction 1 meshes every pixel)",
                c.grid_width,
                c.grid_height,
                f = c.reduction
            );
        }
    }
    Ok(())
}

/// Label agreement under which the command says how much the clean-up relabelled.
const LOW_AGREEMENT: f64 = 0.9;

/// Share of a label's pixels under which the area of its elements is worth a note.
const LOW_AREA: f64 = 0.5;

/// What the clean-up cost, when a user would want to know: labels of the image that no element
/// carries, labels whose elements cover under [`LOW_AREA`] of their pixels' area (a phase
/// fraction the mesh does not keep), and a label agreement under [`LOW_AGREEMENT`].
fn clean_up_notes(c: &imesh::Counts, fidelity: &imesh::Fidelity) -> Vec<String> {
    let quads = if c.quad_size > 0.0 {
        format!("the {:.1} px quads", c.quad_size)
    } else {
        "the mesh".to_string()
    };
    let keep = if c.reduction > 1 {
        "a smaller --size, --reduction 1, or --majority 0 --min-width 0 --min-part-width 0, keeps \
         more of them"
    } else {
        "a smaller --size, or --majority 0 --min-width 0 --min-part-width 0, keeps more of them"
    };
    let mut notes = Vec::new();
    if c.meshed_labels < c.image_labels {
        let gone = c.image_labels - c.meshed_labels;
        let (has, their) = if gone == 1 {
            ("has", "its")
        } else {
            ("have", "their")
        };
        notes.push(format!(
            "{gone} of the image's {} labels {has} no elements: {their} regions were thinner or smaller than {quads} can follow, and were merged into their neighbours ({keep})",
            c.image_labels
        ));
    }
    let shrunk: Vec<&imesh::RegionFidelity> = fidelity
        .regions
        .iter()
        .filter(|g| g.elements > 0 && g.area_px < LOW_AREA * g.pixels as f64)
        .collect();
    if !shrunk.is_empty() {
        let named: Vec<String> = shrunk
            .iter()
            .take(3)
            .map(|g| {
                format!(
                    "{} ({:.0} % of its {} px)",
                    g.name,
                    100.0 * g.area_px / g.pixels as f64,
                    g.pixels
                )
            })
            .collect();
        let more = if shrunk.len() > 3 { ", ..." } else { "" };
        let (count, keeps) = if shrunk.len() == 1 {
            ("1 label keeps".to_string(), "its")
        } else {
            (format!("{} labels keep", shrunk.len()), "their")
        };
        notes.push(format!(
            "{count} under half {keeps} area in the mesh: {}{more}; most of {keeps} regions were thinner or smaller than {quads} can follow ({keep}; the report's fidelity.regions lists every label)",
            named.join(", ")
        ));
    }
    let pixels = f64::from(c.grid_width) * f64::from(c.grid_height);
    let label_agreement = fidelity.label_agreement;
    if label_agreement < LOW_AGREEMENT && c.cleaned_pixels > 0 && pixels > 0.0 {
        notes.push(format!(
            "label agreement is under {:.0} %: the clean-up relabelled {:.1} % of the pixels, specks, notches and strips thinner than {quads} can follow ({keep})",
            100.0 * LOW_AGREEMENT,
            100.0 * c.cleaned_pixels as f64 / pixels
        ));
    }
    notes
}

/// Image files of a folder, sorted by name.
fn images_in(dir: &Path) -> Result<Vec<PathBuf>, String> {
    const IMAGES: [&str; 10] = [
        "png", "jpg", "jpeg", "tif", "tiff", "bmp", "pnm", "pgm", "ppm", "pbm",
    ];
    let entries = std::fs::read_dir(dir)
        .map_err(|e| format!("cannot read the folder {}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.is_file()
                && p.extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| IMAGES.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    files.sort();
    Ok(files)
}

fn batch(args: &BatchArgs) -> Result<(), String> {
    let options = options(&args.flags)?;
    let format = args.format.to_ascii_lowercase();
    if !FORMATS.contains(&format.as_str()) {
        return Err(format!(
            "unknown format {:?}: use msh, vtu, vtk or inp",
            args.format
        ));
    }
    let format = with_msh_version(format, args.flags.msh_version.as_deref())?;
    let images = images_in(&args.dir)?;
    if images.is_empty() {
        return Err(format!(
            "no images (png, jpg, tif, bmp, pnm) in {}",
            args.dir.display()
        ));
    }
    std::fs::create_dir_all(&args.output)
        .map_err(|e| format!("cannot create the folder {}: {e}", args.output.display()))?;
    let frame = Frame {
        pixel_size: options.pixel_size,
        origin: options.origin,
    };
    let pipeline = Pipeline::new(options);
    // One image per task; each image's stages use the same pool for their own parallel work.
    let results: Vec<Result<imesh::Report, String>> = images
        .par_iter()
        .map(|image| {
            let stem = image
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let PipelineResult {
                mesh, mut report, ..
            } = pipeline.run_path(image).map_err(|e| e.to_string())?;
            let output = args
                .output
                .join(&stem)
                .with_extension(extension_of(&format));
            write_timed_mesh(&output, &format, &mesh, &frame, &mut report)?;
            write_report(&args.output.join(format!("{stem}.json")), &report)?;
            Ok(report)
        })
        .collect();
    println!(
        "{:<40} {:>9} {:>9} {:>10} {:>8}  label agreement / error",
        "image", "labels", "vertices", "elements", "seconds"
    );
    let mut failed = 0;
    for (image, result) in images.iter().zip(&results) {
        let name = image
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        match result {
            // Labels meshed of the image's: fewer where the clean-up merged one away.
            Ok(r) => println!(
                "{:<40} {:>9} {:>9} {:>10} {:>8.3}  {:.2} %",
                name,
                format!("{}/{}", r.counts.meshed_labels, r.counts.image_labels),
                r.counts.vertices,
                r.counts.elements,
                r.seconds.total,
                100.0 * r.label_agreement
            ),
            Err(e) => {
                failed += 1;
                println!(
                    "{name:<40} {:>9} {:>9} {:>10} {:>8}  FAILED: {e}",
                    "-", "-", "-", "-"
                );
            }
        }
    }
    if failed > 0 {
        return Err(format!(
            "{failed} of {} images failed (see the table)",
            images.len()
        ));
    }
    Ok(())
}

fn classify_command(args: &ClassifyArgs) -> Result<(), String> {
    let image = load_image(&args.image, DEFAULT_MAX_PIXELS).map_err(|e| e.to_string())?;
    let classifier: Classifier = args
        .classify
        .parse()
        .map_err(|e: imesh_classify::ClassifyError| e.to_string())?;
    let options = ClassifyOptions {
        lossy: imesh_classify::is_lossy_file(&args.image),
        ..ClassifyOptions::default()
    };
    let grid = classify(&image, &classifier, &options).map_err(|e| e.to_string())?;
    check_png(&args.output)?;
    grid.save_png(&args.output).map_err(|e| e.to_string())?;
    println!(
        "{}: {} labels → {}",
        args.image.display(),
        grid.num_labels(),
        args.output.display()
    );
    Ok(())
}

fn check_png(path: &Path) -> Result<(), String> {
    let png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        Ok(())
    } else {
        Err(format!(
            "cannot write {}: the label image is a PNG, use a name ending in .png",
            path.display()
        ))
    }
}

/// An option value that may be `auto` (the pipeline chooses).
#[derive(Clone, Copy, Debug, PartialEq)]
enum AutoOr<T> {
    Auto,
    Value(T),
}

impl<T> AutoOr<T> {
    /// `None` for auto, as the pipeline's options say it.
    fn value(self) -> Option<T> {
        match self {
            Self::Auto => None,
            Self::Value(v) => Some(v),
        }
    }
}

impl<T: std::str::FromStr> std::str::FromStr for AutoOr<T> {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Self::Auto);
        }
        s.parse()
            .map(Self::Value)
            .map_err(|_| format!("{s:?} is neither auto nor a number"))
    }
}
