//! `lanterna scene …`: scene tooling. `generate` writes the procedurally built test
//! scenes (see `lanterna::scene::generate`); other subcommands (such as a Mitsuba export)
//! join the `Command` enum.

use anyhow::Context;
use lanterna::scene::generate::{self, Kind, Options, Shape};
use std::path::PathBuf;

#[derive(clap::Subcommand)]
pub enum Command {
    /// Generate a test scene as glTF 2.0 (.gltf + .bin + PNG textures), deterministic
    /// for a given --seed.
    Generate(GenerateArgs),
    /// Export a scene to Mitsuba 3 (XML + PLY meshes) for an independent reference: the
    /// same world-space triangles, camera, Lambertian materials and area emitters.
    ExportMitsuba(super::scene_export::ExportArgs),
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum KindArg {
    /// Night street lit by many lights (the Bistro stand-in); --lamps N.
    Street,
    /// Cornell box lit by N small coloured emitters; --lights N.
    CornellLights,
    /// Closed box/sphere of albedo ρ emitting Le inward; --albedo, --emission, --shape.
    Furnace,
    /// Plane under a square emitter (closed form); --albedo, --emission, --height, --size.
    PlaneQuad,
    /// Plane under a point or spot light (closed form); --albedo, --intensity, --height, --spot.
    PlanePoint,
    /// Room lit only through a doorway from a hidden emitter; --albedo, --emission.
    Gap,
    /// Alpha-masked checkerboard in front of an emitter; --emission.
    AlphaTest,
    /// Conformance: lamps on, near and inside walls and ledges, closed emissive boxes,
    /// a 1 cm lamp, a thin slab, a grazing strip, a large panel.
    Sconces,
    /// Conformance: point and spot lights 1–5 cm from surfaces; --intensity.
    PunctualNear,
    /// Conformance: a lantern, a lamp inside an alpha-masked lattice cage.
    AlphaLights,
    /// Night square with Bistro's character, most light indirect or through openings;
    /// --detail N.
    BistroNight,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum ShapeArg {
    Box,
    Sphere,
}

#[derive(clap::Args)]
pub struct GenerateArgs {
    /// Which scene to generate.
    #[arg(value_enum)]
    kind: KindArg,
    /// Output .gltf path; the .bin and textures are written beside it.
    #[arg(short, long)]
    output: PathBuf,
    /// Seed of the procedural placement.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Camera aspect ratio (width / height).
    #[arg(long)]
    aspect: Option<f32>,
    /// street: number of emissive light models (default 400).
    #[arg(long)]
    lamps: Option<u32>,
    /// cornell-lights: number of emissive quads (default 16).
    #[arg(long)]
    lights: Option<u32>,
    /// bistro-night: the square's area grows N× with more buildings, lamps and string
    /// lights (default 1, the shipped scene).
    #[arg(long)]
    detail: Option<u32>,
    /// Lambertian albedo of the main surface.
    #[arg(long)]
    albedo: Option<f32>,
    /// Emitted radiance of the main emitter.
    #[arg(long)]
    emission: Option<f32>,
    /// plane-quad, plane-point: height of the light above the plane, in metres.
    #[arg(long)]
    height: Option<f32>,
    /// plane-quad: side of the emitting square, in metres.
    #[arg(long)]
    size: Option<f32>,
    /// plane-point: radiant intensity of the light.
    #[arg(long)]
    intensity: Option<f32>,
    /// plane-point: a spot light pointing down instead of a point light.
    #[arg(long)]
    spot: bool,
    /// furnace: the enclosure's shape.
    #[arg(long, value_enum)]
    shape: Option<ShapeArg>,
    /// Any kind: move the whole scene (cameras and lights too) by X,Y,Z, e.g. to test
    /// precision far from the origin.
    #[arg(long, value_parser = parse_offset, allow_hyphen_values = true)]
    offset: Option<[f32; 3]>,
    /// Any kind: every material Lambertian and opaque (glossy, metal and dielectric
    /// materials become matte, alpha masks are dropped), so that `scene export-mitsuba`
    /// is exact and Mitsuba can check or race lanterna on the scene.
    #[arg(long)]
    matte: bool,
    /// bistro-night: the café wind screens of thin transmitting glass
    /// (KHR_materials_transmission) instead of opaque glossy panels; with --matte they
    /// stay glass, smooth and without reflection, so the export stays exact.
    #[arg(long)]
    glass: bool,
}

fn parse_offset(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("expected X,Y,Z: {e}"))?;
    <[f32; 3]>::try_from(v).map_err(|v| format!("expected three numbers X,Y,Z, got {}", v.len()))
}

pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Generate(a) => run_generate(a),
        Command::ExportMitsuba(a) => super::scene_export::run(a),
    }
}

fn run_generate(a: GenerateArgs) -> anyhow::Result<()> {
    let kind = match a.kind {
        KindArg::Street => Kind::Street,
        KindArg::CornellLights => Kind::CornellLights,
        KindArg::Furnace => Kind::Furnace,
        KindArg::PlaneQuad => Kind::PlaneQuad,
        KindArg::PlanePoint => Kind::PlanePoint,
        KindArg::Gap => Kind::Gap,
        KindArg::AlphaTest => Kind::AlphaTest,
        KindArg::Sconces => Kind::Sconces,
        KindArg::PunctualNear => Kind::PunctualNear,
        KindArg::AlphaLights => Kind::AlphaLights,
        KindArg::BistroNight => Kind::BistroNight,
    };
    let options = Options {
        seed: a.seed,
        aspect: a.aspect,
        lamps: a.lamps,
        lights: a.lights,
        detail: a.detail,
        albedo: a.albedo,
        emission: a.emission,
        height: a.height,
        size: a.size,
        intensity: a.intensity,
        spot: a.spot,
        shape: a.shape.map(|s| match s {
            ShapeArg::Box => Shape::Box,
            ShapeArg::Sphere => Shape::Sphere,
        }),
        offset: a.offset,
        matte: a.matte,
        glass: a.glass,
    };
    let start = std::time::Instant::now();
    if let Some(dir) = a.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("cannot create directory {}: {e}", dir.display()))?;
    }
    let s = generate::generate(kind, &options, &a.output)
        .with_context(|| format!("generating a `{kind}` scene into {}", a.output.display()))?;
    log::info!(
        "wrote {} ({} files, {:.2} MB) in {:.2} s",
        a.output.display(),
        s.files.len(),
        s.bytes as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
    log::info!(
        "{} nodes, {} triangles ({} stored), {} light models with {} emissive triangles, {} punctual lights",
        s.nodes,
        s.triangles,
        s.stored_triangles,
        s.light_models,
        s.emissive_triangles,
        s.punctual_lights
    );
    if s.light_models > 0 {
        log::info!(
            "light power from {:.3e} to {:.3e} ({:.0}x)",
            s.min_light_power,
            s.max_light_power,
            s.max_light_power / s.min_light_power
        );
    }
    Ok(())
}
