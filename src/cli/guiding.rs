//! `lanterna guiding view SCENE --load-guiding FILE --pixel X,Y -o q.png`: the sampling
//! quadtree of the SD-tree leaf at a pixel's first hit, as an image of the (cosθ, φ)
//! square (log density, cell lines), with the leaf's bounds and sample count.

use super::common::{self, DeviceArgs, SceneArgs};
use anyhow::{Context, Result};
use lanterna::guiding::SdTree;
use lanterna::render::session;
use std::path::PathBuf;

#[derive(clap::Subcommand)]
pub enum Command {
    /// Show the sampling quadtree of the leaf a pixel's first hit falls in.
    View(ViewArgs),
}

#[derive(clap::Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub device: DeviceArgs,
    /// A trained SD-tree (`lanterna render --method guided --save-guiding FILE`).
    #[arg(long, value_name = "FILE")]
    pub load_guiding: PathBuf,
    /// The pixel whose first hit selects the leaf.
    #[arg(long, value_name = "X,Y", value_parser = super::render::parse_pixel)]
    pub pixel: (u32, u32),
    /// Output PNG of the (cosθ, φ) square: u = (cosθ+1)/2 to the right, v = φ/2π down.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Size of the image in pixels (at most 4096: the view is a picture of one leaf, and
    /// 4096² already takes 200 MB).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub size: u32,
}

pub fn run(command: Command) -> Result<()> {
    match command {
        Command::View(args) => view(args),
    }
}

fn view(args: ViewArgs) -> Result<()> {
    let (loaded, camera, width, height) = common::load(&args.scene)?;
    common::check_outputs(
        &args.scene,
        &loaded,
        &[("--load-guiding", &args.load_guiding)],
        &[("the PNG (-o)", &args.output)],
    )?;
    let (x, y) = args.pixel;
    anyhow::ensure!(
        x < width && y < height,
        "pixel ({x}, {y}) is outside the {width}×{height} image"
    );
    let tree = SdTree::load(
        &args.load_guiding,
        u64::from_str_radix(&loaded.scene.hash, 16).unwrap_or(0),
    )?;

    // The first hit: the position AOV of a few samples of the pixel.
    let device =
        session::open_device(&args.device.options()).context("cannot open a Vulkan device")?;
    let pos = session::first_hit(
        &device,
        &loaded,
        camera,
        width,
        height,
        (x, y),
        args.device.shaders(),
    )?
    .ok_or_else(|| anyhow::anyhow!("pixel ({x}, {y}) sees no surface"))?;

    let v = tree.leaf_view(pos, args.size);
    let rgb8: Vec<u8> = v
        .rgb
        .iter()
        .map(|c| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
        .collect();
    common::ensure_parent(&args.output)?;
    lanterna::image_io::write_png_rgb8(&args.output, v.width, v.height, &rgb8)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let i = &v.info;
    println!("first hit of pixel ({x}, {y}): {pos:?}");
    println!(
        "leaf {} at depth {}: box {:?} + {:?}",
        i.leaf, i.spatial_depth, i.box_min, i.box_size
    );
    println!(
        "sampling tree: learned from weight {:.0}, {} nodes, depth {}, density {:.3e} .. {:.3e}{}",
        i.sampling_weight,
        i.nodes,
        i.quad_depth,
        i.min_density,
        i.max_density,
        if i.uniform { " (uniform: no data)" } else { "" }
    );
    log::info!("wrote {}", args.output.display());
    Ok(())
}
