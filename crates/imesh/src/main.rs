//! The `imesh` command line: parses arguments, runs the [`imesh::Pipeline`], writes the outputs.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use imesh::{Elements, MeshOptions, Pipeline, PipelineResult};
use imesh_classify::{classify, load_image, Classifier, ClassifyOptions, DEFAULT_MAX_PIXELS};
use imesh_io::{
    write_atomic, write_inp, write_msh, write_svg, write_vtk, write_vtu, Frame, SvgOptions,
};

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
}

#[derive(Args)]
struct MeshArgs {
    /// The image (PNG, JPEG, TIFF, BMP, ...).
    image: PathBuf,
    /// Output mesh: .msh (Gmsh 4.1), .vtu (VTK XML), .vtk (legacy VTK) or .inp (Abaqus).
    /// Default: IMAGE's name with .msh, in the current directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Options from a TOML file (command-line options override it).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Classifier: auto, labels, otsu[:K], threshold:T1,T2, kmeans:K, texture:SAMPLES.toml.
    #[arg(long)]
    classify: Option<String>,
    /// Imesh error threshold (smaller: more vertices, closer boundaries) [default: 0.1].
    #[arg(long)]
    te: Option<f64>,
    /// Smallest triangle angle in degrees, at most 34 [default: 26.4].
    #[arg(long)]
    min_angle: Option<f64>,
    /// Most points the quality refinement may insert.
    #[arg(long)]
    max_steiner: Option<usize>,
    /// Largest element edge in pixels: no triangle gets larger than the equilateral one of this side.
    #[arg(long)]
    max_size: Option<f64>,
    /// Element kind: tri (today's output) or quad (coming).
    #[arg(long)]
    elements: Option<Elements>,
    /// Physical size of a pixel: SX or SX,SY.
    #[arg(long, value_parser = parse_pixel_size)]
    pixel_size: Option<[f64; 2]>,
    /// Also draw the mesh as SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Also write the JSON report (counts, per-stage seconds, quality, label agreement).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(short, long)]
    quiet: bool,
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

fn parse_pixel_size(s: &str) -> Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let parse = |p: &str| {
        p.trim()
            .parse::<f64>()
            .map_err(|_| format!("{p:?} is not a number"))
    };
    match parts.as_slice() {
        [x] => {
            let x = parse(x)?;
            Ok([x, x])
        }
        [x, y] => Ok([parse(x)?, parse(y)?]),
        _ => Err("give SX or SX,SY".into()),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Mesh(args) => mesh(&args),
        Command::Classify(args) => classify_command(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("imesh: {message}");
            ExitCode::from(2)
        }
    }
}

fn options(args: &MeshArgs) -> Result<MeshOptions, String> {
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
        o.min_angle = a;
    }
    if let Some(n) = args.max_steiner {
        o.max_steiner = Some(n);
    }
    if let Some(s) = args.max_size {
        // An equilateral triangle of side s.
        o.max_area = Some(s * s * 3f64.sqrt() / 4.0);
    }
    if let Some(e) = args.elements {
        o.elements = e;
    }
    if let Some(p) = args.pixel_size {
        o.pixel_size = p;
    }
    Ok(o)
}

fn toml_options(text: &str) -> Result<MeshOptions, String> {
    toml::from_str(text).map_err(|e| e.to_string())
}

fn mesh(args: &MeshArgs) -> Result<(), String> {
    let options = options(args)?;
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
    let format = output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !matches!(format.as_str(), "msh" | "vtu" | "vtk" | "inp") {
        return Err(format!(
            "cannot write {}: use an output ending in .msh (Gmsh), .vtu (VTK XML), .vtk (legacy VTK) or .inp (Abaqus)",
            output.display()
        ));
    }
    let frame = Frame {
        pixel_size: options.pixel_size,
    };
    let PipelineResult { mesh, report } = Pipeline::new(options)
        .run_path(&args.image)
        .map_err(|e| e.to_string())?;
    let io = |e: imesh_io::WriteError| e.to_string();
    let cell_data = || {
        let shape: Vec<f64> = mesh
            .elements
            .iter()
            .map(|e| {
                let c = e.corners();
                imesh_quality::tri::shape(&[c[0], c[1], c[2]].map(|v| mesh.vertices[v as usize]))
            })
            .collect();
        vec![("shape".to_string(), shape)]
    };
    match format.as_str() {
        "msh" => write_msh(&output, &mesh, &frame).map_err(io)?,
        "inp" => write_inp(&output, &mesh, &frame).map_err(io)?,
        "vtk" => write_vtk(&output, &mesh, &frame, &cell_data()).map_err(io)?,
        _ => write_vtu(&output, &mesh, &frame, &cell_data()).map_err(io)?,
    }
    if let Some(svg) = &args.svg {
        write_svg(svg, &mesh, &SvgOptions::default()).map_err(io)?;
    }
    if let Some(path) = &args.report {
        let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        write_atomic(path, json.as_bytes()).map_err(io)?;
    }
    if !args.quiet {
        let c = &report.counts;
        let q = &report.quality;
        println!(
            "{}: {}×{} px, {} labels → {} ({} vertices, {} triangles) in {:.3} s",
            args.image.display(),
            c.width,
            c.height,
            c.labels,
            output.display(),
            c.vertices,
            c.elements,
            report.seconds.total
        );
        println!(
            "label agreement {:.2} %; smallest angle worst {:.1}°, mean {:.1}°; shape worst {:.3}, mean {:.3}",
            100.0 * report.label_agreement,
            q.min_angle_deg.min,
            q.min_angle_deg.mean,
            q.shape.min,
            q.shape.mean
        );
    }
    Ok(())
}

fn classify_command(args: &ClassifyArgs) -> Result<(), String> {
    let image = load_image(&args.image, DEFAULT_MAX_PIXELS).map_err(|e| e.to_string())?;
    let classifier: Classifier = args
        .classify
        .parse()
        .map_err(|e: imesh_classify::ClassifyError| e.to_string())?;
    let grid =
        classify(&image, &classifier, &ClassifyOptions::default()).map_err(|e| e.to_string())?;
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
