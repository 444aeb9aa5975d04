//! `komplex`: the command line of the Komplex quadric-CSG ray caster.
//!
//! Thin by design: parse arguments, call the `render` crate, print, and map
//! errors to exit codes (see docs/cli.md).

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::{Parser, Subcommand};
use render::exr::ColorType;
use render::Error;

/// Exit status for an invalid scene or invalid option values.
const EXIT_INPUT: u8 = 1;
/// Exit status for I/O and encoding failures.
const EXIT_IO: u8 = 3;
/// Exit status after Ctrl-C (SIGINT) or SIGTERM: 128 + SIGINT, as shells report it.
const EXIT_INTERRUPTED: u8 = 130;

#[derive(Parser)]
#[command(name = "komplex", version, about = "Quadric-CSG ray caster: a JSON scene becomes an OpenEXR image")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to OpenEXR (and optionally a PNG preview).
    Render(RenderArgs),
    /// Join the parts of a render made with --tile into the whole image.
    Merge(MergeArgs),
    /// Trace one ray and print every block's intervals, the partition and the first hit
    /// (or, with --rays, every ray of a file and its partition).
    Trace(TraceArgs),
    /// Write the ownership map of a plane (PNG: coloured, boundaries drawn, overlaps hatched; EXR: ids).
    Slice(SliceArgs),
    /// Validate a scene and print a summary with warnings.
    Check {
        /// The scene file (JSON).
        scene: PathBuf,
    },
    /// Print the JSON Schema (draft-07) of the scene format.
    Schema,
    /// Write the scene for POV-Ray 3.7 (for comparison renders).
    ExportPov(ExportPovArgs),
    /// Render scenes once each and print rays per second (primary and all rays).
    Bench(BenchArgs),
    /// Write a benchmark scene (JSON).
    Generate(GenerateArgs),
    /// Measure every block's volume (owned, own) and the union's, with standard errors.
    Volume(VolumeArgs),
    /// List the pairs of blocks that share a positive volume.
    Overlaps(OverlapsArgs),
    /// Convert an OpenMC geometry.xml (or the <geometry> of a model.xml) into a scene.
    ImportOpenmc(ImportOpenmcArgs),
}

// The argument structs carry no doc comment of their own: the variant's
// is the command's help.

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (JSON).
    scene: PathBuf,
    /// Output EXR file [default: the scene's stem + .exr in the current directory].
    #[arg(short, long, value_name = "OUT.exr")]
    output: Option<PathBuf>,
    /// Also write an sRGB PNG preview.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    #[command(flatten)]
    size: SizeArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Anti-aliasing: an N×N grid of rays per pixel (overrides settings.samples).
    #[arg(long, value_name = "N")]
    samples: Option<u32>,
    /// Samples per pixel, each at a random point of the pixel and lens (overrides settings.spp).
    #[arg(long, value_name = "N")]
    spp: Option<u32>,
    /// Adaptive sampling: sample a pixel until the relative standard error of its mean is below T, with at most --spp samples (overrides settings.noise).
    #[arg(long, value_name = "T")]
    noise: Option<f64>,
    /// The seed of the random samples (overrides settings.seed).
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// Write the colour channels as 16-bit half floats.
    #[arg(long)]
    half: bool,
    /// Exposure of the PNG preview in stops (pixel values are scaled by 2^E).
    #[arg(long, value_name = "E", default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Render only part I (0-based) of N, a band of rows, to OUT.tile-I-of-N.exr;
    /// auto/N takes I from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX.
    #[arg(long, value_name = "I/N")]
    tile: Option<String>,
    /// Skip the part if its file already holds this very tile of this very render.
    #[arg(long, requires = "tile")]
    resume: bool,
    /// Render frame K of an animated scene to OUT.KKKK.exr (and the PNG likewise).
    #[arg(long, value_name = "K", conflicts_with = "frames")]
    frame: Option<u32>,
    /// Render frames A to B, both included, one after another, each to its own OUT.KKKK.exr;
    /// without A..B the scene's animation.frames.
    #[arg(long, value_name = "A..B", num_args = 0..=1, default_missing_value = "")]
    frames: Option<String>,
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The parts (the files of render --tile), in any order.
    #[arg(required = true, value_name = "PARTS")]
    parts: Vec<PathBuf>,
    /// Output EXR file.
    #[arg(short, long, value_name = "OUT.exr", required = true)]
    output: PathBuf,
    /// Also write an sRGB PNG preview.
    #[arg(long, value_name = "OUT.png")]
    png: Option<PathBuf>,
    /// Exposure of the PNG preview in stops (pixel values are scaled by 2^E).
    #[arg(long, value_name = "E", default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
}

#[derive(clap::Args)]
struct TraceArgs {
    /// The scene file (JSON).
    scene: PathBuf,
    /// Ray origin.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    #[arg(required_unless_present = "rays", conflicts_with = "rays")]
    origin: Vec<f64>,
    /// Ray direction (normalised before use).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    #[arg(required_unless_present = "rays", conflicts_with = "rays")]
    direction: Vec<f64>,
    /// Trace every ray of a file (CSV rows ox,oy,oz,dx,dy,dz, or .npy of shape (N, 6) or (N, 2, 3))
    /// and write each one's partition as CSV (or JSON with --json).
    #[arg(long, value_name = "FILE")]
    rays: Option<PathBuf>,
    /// Output file of --rays [default: stdout].
    #[arg(short, long, value_name = "OUT")]
    output: Option<PathBuf>,
    /// Print JSON instead of text (with --rays: instead of CSV).
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct SliceArgs {
    /// The scene file (JSON).
    scene: PathBuf,
    /// An axis-aligned plane: x=C, y=C or z=C.
    #[arg(long, value_name = "AXIS=C", required_unless_present = "normal", conflicts_with_all = ["origin", "normal", "up"])]
    plane: Option<String>,
    /// A point of the plane (with --normal) [default: 0 0 0].
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true, requires = "normal")]
    origin: Option<Vec<f64>>,
    /// The plane's normal.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    normal: Option<Vec<f64>>,
    /// The image's up direction (its part along the plane) [default: z, or y for a normal near z].
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true, requires = "normal")]
    up: Option<Vec<f64>>,
    /// Image size in pixels [default: 800 on the longer side, the other from the extent].
    #[arg(long, num_args = 2, value_names = ["W", "H"])]
    size: Option<Vec<u32>>,
    /// The rectangle of plane coordinates shown [default: where the plane cuts the scene's box, 5 % margin].
    #[arg(long, num_args = 4, value_names = ["U0", "U1", "V0", "V1"], allow_negative_numbers = true)]
    extent: Option<Vec<f64>>,
    /// Output image, by extension: .png (coloured map) or .exr (id.block, id.material, overlap).
    #[arg(short, long, value_name = "OUT.png|OUT.exr", required = true)]
    output: PathBuf,
    /// What colours the PNG.
    #[arg(long, value_enum, default_value_t = ColorByArg::Block)]
    color_by: ColorByArg,
    /// Worker threads [default: one per core].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
}

/// `--color-by`.
#[derive(Clone, Copy, clap::ValueEnum)]
enum ColorByArg {
    /// One colour per block.
    Block,
    /// One colour per material.
    Material,
    /// One colour per block name (an imported OpenMC cell's blocks are one region).
    Name,
}

#[derive(clap::Args)]
struct ExportPovArgs {
    /// The scene file (JSON).
    scene: PathBuf,
    /// Output .pov file [default: stdout].
    #[arg(short, long, value_name = "OUT.pov")]
    output: Option<PathBuf>,
    /// Flat block colours encoding the 1-based block id (an id mask), no lights.
    #[arg(long)]
    mask: bool,
    #[command(flatten)]
    size: SizeArgs,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// The scene files (JSON).
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    #[command(flatten)]
    size: SizeArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Renders per scene (loaded once): the render time is the fastest, the median is printed too.
    #[arg(long, value_name = "R", default_value_t = 1)]
    runs: u32,
    /// After each row, the load time by stage (read, parse, flatten, build).
    #[arg(long)]
    stages: bool,
}

#[derive(clap::Args)]
struct GenerateArgs {
    #[command(subcommand)]
    kind: Generator,
    /// Output file [default: stdout].
    #[arg(short, long, value_name = "OUT.json", global = true)]
    output: Option<PathBuf>,
}

#[derive(clap::Args)]
struct VolumeArgs {
    #[command(flatten)]
    measure: MeasureArgs,
    /// One row per block name: the volume the blocks of that name own together
    /// (an imported OpenMC cell's), converged per name rather than per block.
    #[arg(long)]
    by_name: bool,
}

#[derive(clap::Args)]
struct OverlapsArgs {
    #[command(flatten)]
    measure: MeasureArgs,
    /// Only pairs of blocks of different names (an imported OpenMC cell's blocks are one region).
    #[arg(long)]
    by_name: bool,
}

#[derive(clap::Args)]
struct ImportOpenmcArgs {
    /// OpenMC's geometry.xml, or a model.xml holding a <geometry>.
    xml: PathBuf,
    /// Output scene file [default: stdout; nothing with --check].
    #[arg(short, long, value_name = "OUT.json")]
    output: Option<PathBuf>,
    /// Print cells, blocks, bounds and the overlaps between different cells.
    #[arg(long)]
    check: bool,
    /// Random points --check samples for overlaps.
    #[arg(long, value_name = "N", default_value_t = 1_000_000, requires = "check")]
    points: u64,
}

/// The options `volume` and `overlaps` share.
#[derive(clap::Args)]
struct MeasureArgs {
    /// The scene file (JSON).
    scene: PathBuf,
    /// Target relative standard error of every volume.
    #[arg(long, value_name = "REL", default_value_t = render::measure::MeasureOptions::default().tolerance, allow_hyphen_values = true)]
    tolerance: f64,
    /// Clip everything to this box (then unbounded blocks get a volume too).
    #[arg(long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true)]
    bounds: Option<Vec<f64>>,
    /// Seed of the random lines.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads [default: one per core].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Output file [default: stdout].
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
}

impl MeasureArgs {
    /// The scene and the measurement options, checked (and the output
    /// writable, the thread count set) before the scene is loaded.
    fn prepare(&self) -> Result<(render::world::World, render::measure::MeasureOptions), Error> {
        if let Some(p) = &self.output {
            render::output::check_writable(p)?;
        }
        render::frame::set_global_threads(self.threads)?;
        let bounds = self.bounds.as_deref().map(|b| [b[0], b[1], b[2], b[3], b[4], b[5]]);
        let options = render::measure::MeasureOptions { tolerance: self.tolerance, seed: self.seed, bounds };
        options.validate()?;
        Ok((render::load(&self.scene)?, options))
    }

    /// Prints (or writes) the report as JSON or as text.
    fn emit(&self, json: impl FnOnce() -> String, text: impl FnOnce() -> String) -> Result<(), Error> {
        let text = if self.json { json() } else { text() };
        write_text(self.output.as_deref(), &text)
    }
}

/// `--threads`/`--precision`, shared by the commands that render.
#[derive(clap::Args)]
struct RunArgs {
    /// Worker threads [default: one per core].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Precision mode of the kernel (docs/accuracy.md).
    #[arg(long, value_enum, default_value_t = PrecisionArg::Accurate)]
    precision: PrecisionArg,
}

/// `--width`/`--height`, shared by the commands that make an image.
#[derive(clap::Args)]
struct SizeArgs {
    /// Image width (overrides the scene; alone, keeps the aspect ratio).
    #[arg(long, value_name = "W")]
    width: Option<u32>,
    /// Image height (overrides the scene; alone, keeps the aspect ratio).
    #[arg(long, value_name = "H")]
    height: Option<u32>,
}

impl SizeArgs {
    /// Applies the overrides to the world's camera.
    fn apply(&self, world: &mut render::world::World) -> Result<(), Error> {
        world.camera = world
            .camera
            .resized(self.width, self.height)
            .map_err(|e| Error::Options(format!("--width/--height: {e}")))?;
        Ok(())
    }
}

/// `--precision`: the kernel's precision modes (`quadric::Precision`).
#[derive(Clone, Copy, clap::ValueEnum)]
enum PrecisionArg {
    /// World-space roots: the cheapest, inaccurate far from the origin.
    Fast,
    /// Re-based, compensated roots and hit points refined onto the surface (the default).
    Accurate,
    /// Rigorous root bounds, ambiguous cases settled exactly (several times slower).
    Certified,
}

impl From<PrecisionArg> for render::Precision {
    fn from(p: PrecisionArg) -> Self {
        match p {
            PrecisionArg::Fast => render::Precision::Fast,
            PrecisionArg::Accurate => render::Precision::Accurate,
            PrecisionArg::Certified => render::Precision::Certified,
        }
    }
}

#[derive(Subcommand)]
enum Generator {
    /// Haines' sphereflake: 1 + 9 + … + 9^L reflective spheres on a ground plane, three lights.
    Sphereflake {
        /// Recursion depth L (3: 820 spheres, 4: 7,381).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=6))]
        level: u32,
    },
    /// N random bounded blocks (spheres, capped cylinders, boxes; rotated) on a cubic grid.
    Grid {
        /// Number of blocks.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
        count: u32,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// An OUTER × OUTER lattice of tiles, each an INNER × INNER lattice of a small ball, on a ground plane.
    Lattice {
        /// Tiles along x and z.
        #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(1..=65_536))]
        outer: u32,
        /// Balls along x and z in a tile.
        #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=65_536))]
        inner: u32,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(match e {
                Error::Interrupted => EXIT_INTERRUPTED,
                e if e.is_input_error() => EXIT_INPUT,
                _ => EXIT_IO,
            })
        }
    }
}

fn triple(v: &[f64]) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

fn run(command: Command) -> Result<(), Error> {
    match command {
        Command::Render(args) => render(args),
        Command::Merge(args) => merge(args),
        Command::Trace(args) => trace(args),
        Command::Slice(args) => slice(args),
        Command::Check { scene } => check(&scene),
        Command::Schema => schema(),
        Command::ExportPov(args) => export_pov(args),
        Command::Bench(args) => bench(args),
        Command::Generate(args) => generate(args),
        Command::Volume(args) => volume(args),
        Command::Overlaps(args) => overlaps(args),
        Command::ImportOpenmc(args) => import_openmc(args),
    }
}

/// `komplex render`: the EXR (and the PNG preview), both checked writable
/// before the render and written only once it is complete; with `--frame`
/// or `--frames`, one such pair per frame, each written as it is done.
fn render(args: RenderArgs) -> Result<(), Error> {
    render::frame::set_global_threads(args.run.threads)?;
    let cancel = interrupt_flag();
    if !args.exposure.is_finite() {
        return Err(Error::Options(format!("--exposure must be a finite number of stops, got {}", args.exposure)));
    }
    let tile = args.tile.as_ref().map(|t| render::tiles::Tile::parse(t, |v| std::env::var(v).ok())).transpose()?;
    if tile.is_some() && args.png.is_some() {
        return Err(Error::Options("--png goes with a whole image, not --tile: give it to komplex merge".into()));
    }
    let output = args.output.clone().unwrap_or_else(|| default_output(&args.scene));
    if args.frame.is_none() && args.frames.is_none() {
        let world = render::load(&args.scene)?;
        return render_image(world, &args, &output, args.png.as_deref(), None, tile, &cancel);
    }
    let animation = render::animate::Animation::read(&args.scene)?;
    let frames = match (args.frame, args.frames.as_deref()) {
        (Some(k), _) => k..=k,
        (None, Some("") | None) => animation.frames().ok_or_else(|| {
            Error::Options(format!(
                "--frames without A..B renders the scene's \"animation\": {{\"frames\": [A, B]}}, which {} lacks",
                args.scene.display()
            ))
        })?,
        (None, Some(range)) => render::animate::parse_frames(range)?,
    };
    for k in frames {
        if cancel.load(Ordering::Relaxed) {
            return Err(Error::Interrupted);
        }
        let world = animation.world_at(k)?;
        let png = args.png.as_deref().map(|p| render::output::part_path(p, Some(k), None));
        render_image(world, &args, &output, png.as_deref(), Some(k), tile, &cancel)?;
    }
    Ok(())
}

/// One image of `komplex render` (frame `frame` of an animation, if
/// given, or tile `tile` of it): the options applied to `world`, the
/// outputs checked writable, the render, then the PNG and the EXR (or the
/// part, named by [`render::output::part_path`]).
fn render_image(
    mut world: render::world::World,
    args: &RenderArgs,
    output: &Path,
    png: Option<&Path>,
    frame: Option<u32>,
    tile: Option<render::tiles::Tile>,
    cancel: &Arc<AtomicBool>,
) -> Result<(), Error> {
    let RenderArgs {
        scene,
        size,
        run: RunArgs { threads, precision },
        samples,
        spp,
        noise,
        seed,
        half,
        exposure,
        resume,
        ..
    } = args;
    let (threads, half, exposure, resume) = (*threads, *half, *exposure, *resume);
    if let Some(n) = *samples {
        if !(1..=16).contains(&n) {
            return Err(Error::Options(format!("--samples must be between 1 and 16, got {n}")));
        }
        world.settings.samples = n;
    }
    if let Some(n) = *spp {
        if !(1..=render::limits::MAX_SPP).contains(&n) {
            return Err(Error::Options(format!("--spp must be between 1 and {}, got {n}", render::limits::MAX_SPP)));
        }
        world.settings.spp = Some(n);
    }
    if let Some(t) = *noise {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::Options(format!("--noise must be a finite number > 0, got {t}")));
        }
        world.settings.noise = Some(t);
    }
    if let Some(s) = *seed {
        world.settings.seed = s;
    }
    size.apply(&mut world)?;
    world.complex.set_precision((*precision).into());
    let output = render::output::part_path(output, frame, tile.map(|t| (t.index, t.count)));
    let (width, height) = (world.camera.width(), world.camera.height());
    let fingerprint = match tile {
        Some(t) => {
            t.check_height(height)?;
            let text = std::fs::read(scene).map_err(|source| Error::Io { path: scene.clone(), source })?;
            let mut fingerprint = render::tiles::render_fingerprint(&text, &world, half);
            if let Some(k) = frame {
                // The parts of different frames of one scene are foreign to each other.
                fingerprint = fingerprint.bytes("frame", &k.to_le_bytes());
            }
            let fingerprint = fingerprint.hex();
            if resume && output.exists() {
                match render::tiles::check_complete(&output, t, &fingerprint, (width, height)) {
                    Ok(()) => {
                        eprintln!("{}: tile {t} is already complete; skipped (--resume)", output.display());
                        return Ok(());
                    }
                    Err(why) => eprintln!("{}: rendering tile {t} again (--resume): {why}", output.display()),
                }
            }
            fingerprint
        }
        None => String::new(),
    };
    let rows = tile.map(|t| t.rows(height));
    // Fail before the render, not after it, if an output cannot be written.
    render::output::check_writable(&output)?;
    if let Some(p) = png {
        render::output::check_writable(p)?;
    }
    let rows_rendered = rows.map_or(height, |(a, b)| b - a);
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(u64::from(rows_rendered));
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rows {elapsed}") {
            bar.set_style(style);
        }
        bar
    });
    let tick = || {
        if let Some(b) = &bar {
            b.inc(1);
        }
    };
    let options = render::frame::Options { threads, rows, ..Default::default() };
    let (frame, stats) = render::frame::render_until(&world, options, &tick, cancel)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    // A Ctrl-C from here on lets the (short) writing finish, so the
    // files on disk are both old or both new.
    if cancel.load(Ordering::Relaxed) {
        return Err(Error::Interrupted);
    }
    let color = if half { ColorType::F16 } else { ColorType::F32 };
    // The preview first: the EXR writer takes the frame's planes over.
    if let Some(p) = png {
        render::png::write_png(&frame, p, exposure)?;
    }
    let part = match (tile, rows) {
        (Some(t), Some((a, b))) => {
            render::tiles::write_part(frame, &output, color, t, &fingerprint)?;
            format!(" tile {t}, rows {a}..{b},")
        }
        _ => {
            render::exr::write_exr(frame, &output, color)?;
            String::new()
        }
    };
    eprintln!(
        "{}: {}x{}{part} in {:.2} s, {} rays, {:.2} Mrays/s",
        output.display(),
        width,
        height,
        stats.elapsed.as_secs_f64(),
        stats.rays,
        stats.rays_per_second() / 1e6
    );
    Ok(())
}

/// `komplex merge`: the parts of a tiled render joined into the whole
/// image (and its preview), every part checked before anything is written.
fn merge(args: MergeArgs) -> Result<(), Error> {
    let MergeArgs { parts, output, png, exposure } = args;
    if !exposure.is_finite() {
        return Err(Error::Options(format!("--exposure must be a finite number of stops, got {exposure}")));
    }
    render::output::check_writable(&output)?;
    if let Some(p) = &png {
        render::output::check_writable(p)?;
    }
    let start = std::time::Instant::now();
    let merge = render::tiles::merge(&parts)?;
    let (width, height, count) = (merge.width, merge.height, merge.parts.len());
    if let Some(p) = &png {
        render::png::write_png_planes(p, (width, height), &merge.rgb()?, exposure)?;
    }
    merge.write(&output)?;
    eprintln!("{}: {width}x{height} from {count} parts in {:.2} s", output.display(), start.elapsed().as_secs_f64());
    Ok(())
}

/// `komplex trace`: one ray's report, as text or JSON; with `--rays`, every
/// ray's partition, as CSV or JSON.
fn trace(args: TraceArgs) -> Result<(), Error> {
    let TraceArgs { scene, origin, direction, rays, output, json } = args;
    if let Some(rays) = rays {
        if let Some(p) = &output {
            render::output::check_writable(p)?;
        }
        let rays = render::rays::read(&rays)?;
        let world = render::load(&scene)?;
        let traces = render::rays::trace(&world, &rays);
        let text = if json { render::rays::to_json(&world, &traces)? } else { render::rays::to_csv(&world, &traces) };
        return write_text(output.as_deref(), &text);
    }
    if output.is_some() {
        return Err(Error::Options("-o/--output goes with --rays; one ray's report is printed".into()));
    }
    let world = render::load(&scene)?;
    let report = render::trace::trace(&world, triple(&origin), triple(&direction))?;
    if json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| Error::Options(e.to_string()))?;
        println!("{text}");
    } else {
        print!("{report}");
    }
    Ok(())
}

/// `komplex slice`: the ownership map of a plane, checked writable before
/// the work and written atomically.
fn slice(args: SliceArgs) -> Result<(), Error> {
    use render::slice::{ColorBy, Extent, Plane, Raster};
    let SliceArgs { scene, plane, origin, normal, up, size, extent, output, color_by, threads } = args;
    render::frame::set_global_threads(threads)?;
    let plane = match (plane, normal) {
        (Some(text), _) => Plane::axis(&text)?,
        (None, Some(n)) => Plane::new(origin.map_or([0.0; 3], |o| triple(&o)), triple(&n), up.map(|u| triple(&u)))?,
        // clap requires one of them.
        (None, None) => return Err(Error::Options("give --plane or --normal".into())),
    };
    let extent = extent.map(|e| Extent::new(e[0], e[1], e[2], e[3])).transpose()?;
    render::slice::ImageType::of(&output)?;
    render::output::check_writable(&output)?;
    let world = render::load(&scene)?;
    let extent = match extent {
        Some(e) => e,
        None => plane.extent_of(&world.complex.aabb())?,
    };
    let raster = Raster::new(plane, extent, size.map(|s| (s[0], s[1])))?;
    let map = render::slice::slice(&world, &raster);
    let by = match color_by {
        ColorByArg::Block => ColorBy::Block,
        ColorByArg::Material => ColorBy::Material,
        ColorByArg::Name => ColorBy::Name,
    };
    render::slice::write(map, &output, by)?;
    let Extent { u0, u1, v0, v1 } = extent;
    eprintln!("{}: {}x{}, u {u0:?} to {u1:?}, v {v0:?} to {v1:?}", output.display(), raster.width, raster.height);
    Ok(())
}

/// `komplex check`: the summary and warnings of a valid scene.
fn check(scene: &Path) -> Result<(), Error> {
    let world = render::load(scene)?;
    print!("{}", render::check::check(&world));
    Ok(())
}

/// `komplex schema`.
fn schema() -> Result<(), Error> {
    print!("{}", render::format::schema_json());
    Ok(())
}

/// `komplex export-pov`: the POV-Ray scene, to a file or stdout.
fn export_pov(args: ExportPovArgs) -> Result<(), Error> {
    let ExportPovArgs { scene, output, mask, size } = args;
    // Fail before loading, not after, if the output cannot be written.
    if let Some(p) = &output {
        render::output::check_writable(p)?;
    }
    let mut world = render::load(&scene)?;
    size.apply(&mut world)?;
    let text = render::pov::export(&world, render::pov::PovOptions { mask })?;
    write_text(output.as_deref(), &text)
}

/// `komplex bench`: one table row per scene.
fn bench(args: BenchArgs) -> Result<(), Error> {
    let BenchArgs { scenes, size, run: RunArgs { threads, precision }, runs, stages } = args;
    if !(1..=1000).contains(&runs) {
        return Err(Error::Options(format!("--runs must be between 1 and 1000, got {runs}")));
    }
    render::frame::set_global_threads(threads)?;
    println!(
        "{:<28} {:>8} {:>9} {:>9} {:>9} {:>12} {:>12} {:>14} {:>14} {:>9} {:>5}",
        "scene",
        "blocks",
        "load s",
        "size",
        "render s",
        "primary",
        "all rays",
        "primary/s",
        "all rays/s",
        "median s",
        "runs"
    );
    for scene in scenes {
        let m = render::bench::measure_runs(&scene, (size.width, size.height), threads, precision.into(), runs)?;
        println!(
            "{:<28} {:>8} {:>9.3} {:>9} {:>9.3} {:>12} {:>12} {:>14.0} {:>14.0} {:>9.3} {:>5}",
            scene.file_stem().map_or_else(|| scene.display().to_string(), |s| s.to_string_lossy().into()),
            m.blocks,
            m.load.as_secs_f64(),
            format!("{}x{}", m.width, m.height),
            m.render.as_secs_f64(),
            m.primary,
            m.rays,
            m.primary_per_second(),
            m.rays_per_second(),
            m.median.as_secs_f64(),
            m.runs
        );
        if stages {
            let s = m.stages;
            let secs = |d: std::time::Duration| d.as_secs_f64();
            println!(
                "  load stages s: read {:.3}, parse {:.3}, flatten {:.3}, build {:.3}",
                secs(s.read),
                secs(s.parse),
                secs(s.flatten),
                secs(s.build)
            );
        }
    }
    Ok(())
}

/// `komplex generate`: a benchmark scene, to a file or stdout.
fn generate(args: GenerateArgs) -> Result<(), Error> {
    if let Some(p) = &args.output {
        render::output::check_writable(p)?;
    }
    let scene = match args.kind {
        Generator::Sphereflake { level } => render::generate::sphereflake(level),
        Generator::Grid { count, seed } => render::generate::grid(count, seed),
        Generator::Lattice { outer, inner } => render::generate::nested_lattice(outer, inner),
    };
    write_text(args.output.as_deref(), &render::generate::to_json(&scene))
}

/// `komplex volume`: every block's volumes and the union's.
fn volume(args: VolumeArgs) -> Result<(), Error> {
    let (world, options) = args.measure.prepare()?;
    if args.by_name {
        let report = render::measure::volumes_by_name(&world, &options)?;
        return args.measure.emit(|| report.to_json(), || report.to_string());
    }
    let report = render::measure::volumes(&world, &options)?;
    args.measure.emit(|| report.to_json(), || report.to_string())
}

/// `komplex overlaps`: the pairs of blocks that share a positive volume.
fn overlaps(args: OverlapsArgs) -> Result<(), Error> {
    let (world, options) = args.measure.prepare()?;
    let report = if args.by_name {
        render::measure::overlaps_between_names(&world, &options)?
    } else {
        render::measure::overlaps(&world, &options)?
    };
    args.measure.emit(|| report.to_json(), || report.to_string())
}

/// `komplex import-openmc`: the scene to a file or stdout; with `--check`
/// the summary instead of (or besides) the scene.
fn import_openmc(args: ImportOpenmcArgs) -> Result<(), Error> {
    if let Some(p) = &args.output {
        render::output::check_writable(p)?;
    }
    let imported = render::openmc::import_file(&args.xml)?;
    for w in &imported.warnings {
        eprintln!("warning: {}: {w}", args.xml.display());
    }
    if args.output.is_some() || !args.check {
        write_text(args.output.as_deref(), &render::generate::to_json(&imported.scene))?;
    }
    if args.check {
        let world = imported.scene.to_world().map_err(|source| Error::Scene { file: args.xml.clone(), source })?;
        print!("{}", render::openmc::summary(&imported, &world, args.points.max(1)));
    }
    Ok(())
}

/// Writes `text` to `path`, or to stdout without a path. A file is
/// written as every output is: to a temporary file beside it, renamed over
/// it only when complete, so a failed write leaves the earlier file.
fn write_text(path: Option<&Path>, text: &str) -> Result<(), Error> {
    match path {
        Some(path) => render::output::write_atomic(path, |w| w.write_all(text.as_bytes()).map_err(|e| e.to_string())),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// A flag set by the first Ctrl-C (SIGINT) or SIGTERM; the render loop
/// stops, every temporary file is removed as it drops, and nothing is
/// renamed into place. A second signal exits at once with status 130 (an
/// image being encoded at that moment may leave its `.komplex-*.tmp` file).
fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Registration fails only for forbidden signals; these two are not.
        // Conditional shutdown first: it sees the flag as the previous signal left it.
        let _ =
            signal_hook::flag::register_conditional_shutdown(signal, i32::from(EXIT_INTERRUPTED), Arc::clone(&flag));
        let _ = signal_hook::flag::register(signal, Arc::clone(&flag));
    }
    flag
}

/// The scene's stem with `.exr`, in the current directory.
fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map_or_else(|| "out".into(), |s| s.to_os_string());
    let mut p = PathBuf::from(stem);
    p.set_extension("exr");
    p
}
