//! `lanterna merge a.exr b.exr … -o out.exr`: combines renders of disjoint sample ranges
//! of one scene into one image — exactly, by adding film sums, when every input has them.

use std::path::PathBuf;

use anyhow::Context;
use lanterna::eval::merge::merge;
use lanterna::image_io::{read_exr, write_exr};

#[derive(clap::Args)]
pub struct Args {
    /// EXR renders of the same scene, method, seed and depth over disjoint sample ranges.
    #[arg(required = true, num_args = 2..)]
    inputs: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut plan = lanterna::files::FilePlan::new();
    plan.inputs("an input", &args.inputs)
        .output("the merged image (-o)", &args.output);
    plan.check()?;
    let images = args
        .inputs
        .iter()
        .map(|p| read_exr(p).context("reading an input to merge"))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let names: Vec<String> = args
        .inputs
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let pairs: Vec<(&str, &lanterna::image_io::Image)> =
        names.iter().map(String::as_str).zip(&images).collect();
    let merged = merge(&pairs)?;
    for w in &merged.warnings {
        log::warn!("{w}");
    }
    let summary = write_exr(&args.output, &merged.image)
        .with_context(|| format!("writing the merged image {}", args.output.display()))?;
    if summary.nonfinite > 0 {
        log::warn!(
            "{}: {} non-finite values",
            args.output.display(),
            summary.nonfinite
        );
    }
    let m = &merged.image.meta;
    log::info!(
        "{}: {} spp from sample {} ({} inputs, {})",
        args.output.display(),
        m.spp.unwrap_or(0),
        m.sample_offset.unwrap_or(0),
        images.len(),
        if merged.exact {
            "exact"
        } else {
            "weighted means, not exact"
        }
    );
    Ok(())
}
