//! Command-line front end: argument parsing, logging, and error reporting. Each
//! subcommand is one file with an `Args` struct and a `run` function; errors travel as
//! `anyhow::Error` with context and are printed once, here, with a non-zero exit.
//!
//! Exit statuses: 0 done; 1 error; 2 bad command line (clap); 75 interrupted by a
//! signal with the partial result written ([`common::EXIT_INTERRUPTED_SAVED`]); 130
//! interrupted before anything was written, or by a second signal.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod bench;
mod common;
mod compare;
mod guiding;
mod info;
mod merge;
mod reference;
mod render;
mod scene;
mod scene_export;

#[derive(Parser)]
#[command(
    name = "lanterna",
    version,
    about = "A GPU path tracer for scenes lit by many lights"
)]
struct Cli {
    /// Log verbosity (error, warn, info, debug, trace); RUST_LOG overrides it.
    #[arg(long, global = true, default_value = "info")]
    log: String,
    /// SIMD lanes lavapipe compiles kernels for: 4 or 8 (AVX2's full width) or 16. By
    /// default a `render` or `reference` of `ris` takes 8 (12–18 % faster there) and
    /// everything else 4 (`pt` and `guided` 10 % faster there, `guided-ris` level), unless
    /// LP_NATIVE_VECTOR_WIDTH is set. Sets LP_NATIVE_VECTOR_WIDTH; other devices ignore
    /// it.
    #[arg(long, global = true, value_name = "N", value_parser = parse_lanes)]
    lavapipe_lanes: Option<u32>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene.
    Render(render::Args),
    /// List Vulkan devices and their features, or print a scene's statistics.
    Info(info::Args),
    /// Generate or export scenes.
    #[command(subcommand)]
    Scene(scene::Command),
    /// Render a high-spp reference with checkpoints and resume.
    Reference(reference::Args),
    /// Merge renders of disjoint sample ranges into one image.
    Merge(merge::Args),
    /// Compare methods against a reference: error vs spp and vs time, with figures.
    Compare(compare::Args),
    /// Run the performance suite and write bench/results/<date>-<device>.json and .md.
    Bench(bench::Args),
    /// Inspect trained SD-trees.
    #[command(subcommand)]
    Guiding(guiding::Command),
}

impl Command {
    /// The lavapipe SIMD width a command renders fastest with, where it renders one
    /// method: 8 lanes for `ris`, whose 32 RIS candidates per vertex are coherent
    /// arithmetic that keeps every lane busy (measured 2026-11-24, M samples/s at 8
    /// against 4 lanes: ×1.18 on `cornell-lights`, ×1.13 on `street-matte`); None (the
    /// default of 4, best for the divergent traversal of the other methods: `pt` and
    /// `guided` ×0.90 at 8 lanes, `guided-ris` level) otherwise.
    fn preferred_lanes(&self) -> Option<u32> {
        let method = match self {
            Command::Render(a) => a.method.method,
            Command::Reference(a) => a.method.method,
            _ => return None,
        };
        (method == lanterna::render::Method::Ris).then_some(8)
    }
}

fn parse_lanes(text: &str) -> Result<u32, String> {
    let choices = lanterna::vk::lavapipe::LANE_CHOICES;
    text.parse::<u32>()
        .ok()
        .filter(|n| choices.contains(n))
        .ok_or_else(|| format!("expected one of {choices:?}"))
}

pub fn main() -> ExitCode {
    let cli = Cli::parse();
    // While the process has one thread, before any Vulkan instance: the flag, else the
    // user's LP_NATIVE_VECTOR_WIDTH, else the width the command renders fastest with.
    use lanterna::vk::lavapipe;
    let lanes = cli.lavapipe_lanes.or_else(|| {
        std::env::var_os(lavapipe::WIDTH_VARIABLE)
            .is_none()
            .then(|| cli.command.preferred_lanes())
            .flatten()
    });
    if let Some(lanes) = lanes {
        lavapipe::request_lanes(lanes);
    }
    env_logger::Builder::new()
        .parse_filters(&cli.log)
        .parse_env("RUST_LOG")
        .format_timestamp(None)
        .format_target(false)
        .init();
    let result = match cli.command {
        Command::Render(a) => render::run(a),
        Command::Info(a) => info::run(a),
        Command::Scene(c) => scene::run(c),
        Command::Reference(a) => reference::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Guiding(c) => guiding::run(c),
        Command::Bench(a) => bench::run(a),
    };
    // With validation on, a validation error is a failure even if the command finished.
    let result = result.and_then(|()| match lanterna::vk::validation_error_count() {
        0 => Ok(()),
        n => Err(anyhow::anyhow!(
            "{n} Vulkan validation error(s) were reported (see the log)"
        )),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => match e.downcast_ref::<common::Interrupted>() {
            Some(i @ common::Interrupted::Saved(_)) => {
                eprintln!("{i}");
                ExitCode::from(common::EXIT_INTERRUPTED_SAVED)
            }
            Some(i @ common::Interrupted::Nothing) => {
                eprintln!("{i}");
                ExitCode::from(common::EXIT_INTERRUPTED_NOTHING)
            }
            None => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        },
    }
}

#[cfg(test)]
mod tests {
    /// No command has two arguments with one name (as `--time`, a render's budget and an
    /// animation pose, once had: clap then refuses every render that uses either). clap's
    /// own `debug_assert` checks this only in debug builds, and the tests run in release.
    #[test]
    fn no_command_has_two_arguments_with_one_name() {
        use clap::CommandFactory;
        fn check(cmd: &clap::Command, path: &str) {
            let mut seen = std::collections::HashSet::new();
            for a in cmd.get_arguments() {
                let names = a
                    .get_long()
                    .map(|l| format!("--{l}"))
                    .into_iter()
                    .chain(a.get_short().map(|c| format!("-{c}")));
                for name in names {
                    assert!(
                        seen.insert(name.clone()),
                        "`{path}` has two arguments {name}"
                    );
                }
            }
            for sub in cmd.get_subcommands() {
                check(sub, &format!("{path} {}", sub.get_name()));
            }
        }
        let mut cmd = super::Cli::command();
        cmd.build();
        check(&cmd, "lanterna");
    }
}
