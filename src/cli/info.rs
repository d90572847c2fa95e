//! `lanterna info [SCENE]`: the Vulkan devices and what each supports of what lanterna
//! needs, or a scene's statistics.

use anyhow::{Context, Result};
use lanterna::render::Traversal;
use lanterna::scene::SceneStats;
use lanterna::vk::{Device, Instance, InstanceOptions};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Print this scene's statistics instead of the device list.
    pub scene: Option<PathBuf>,
    /// Print as JSON.
    #[arg(long)]
    pub json: bool,
    /// Follow buffer and image URIs that lead outside the scene's folder.
    #[arg(long)]
    pub allow_outside_uris: bool,
    #[command(flatten)]
    pub version: super::common::VersionArgs,
}

pub fn run(args: Args) -> Result<()> {
    match &args.scene {
        Some(path) => {
            let options = args.version.load_options(args.allow_outside_uris);
            scene_info(path, args.json, &options)
        }
        None => device_info(args.json),
    }
}

fn scene_info(
    path: &std::path::Path,
    json: bool,
    options: &lanterna::scene::LoadOptions,
) -> Result<()> {
    // A scene without lights cannot be rendered, but its statistics can still say what
    // it holds (and so why nothing lights it).
    let scene = lanterna::scene::Scene::load(path, options)?;
    let stats = match lanterna::lights::LightTable::build(&scene) {
        Ok(lights) => SceneStats::new(&scene, &lights),
        Err(e @ lanterna::scene::SceneError::NoLights { .. }) => {
            log::warn!("{e}: it cannot be rendered");
            SceneStats::unlit(&scene)
        }
        Err(e) => return Err(e.into()),
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&stats)?);
    } else {
        println!("{}", path.display());
        println!("{stats}");
        if !scene.cameras.is_empty() {
            let names: Vec<String> = scene
                .cameras
                .iter()
                .enumerate()
                .map(|(i, c)| match (c.clip.is_none(), c.clip.far.is_finite()) {
                    (true, _) => format!("{i}: {}", c.name),
                    (false, true) => {
                        format!("{i}: {} (clip {}–{})", c.name, c.clip.near, c.clip.far)
                    }
                    (false, false) => format!("{i}: {} (clip from {})", c.name, c.clip.near),
                })
                .collect();
            println!("cameras             {}", names.join(", "));
        }
        if !scene.animations.is_empty() {
            let seconds = |t: Option<f32>| t.map_or("?".to_string(), |t| format!("{t}"));
            let list: Vec<String> = scene
                .animations
                .iter()
                .map(|a| {
                    format!(
                        "{}: {}–{} s, {} channel{}",
                        a.name,
                        seconds(a.start),
                        seconds(a.end),
                        a.channels,
                        if a.channels == 1 { "" } else { "s" }
                    )
                })
                .collect();
            println!("animations          {} (--animation-time)", list.join("; "));
        }
        if !scene.variants.is_empty() {
            let list: Vec<String> = scene
                .variants
                .iter()
                .enumerate()
                .map(|(i, n)| format!("{i}: {n}"))
                .collect();
            println!("material variants   {} (--variant)", list.join(", "));
        }
    }
    Ok(())
}

fn device_info(json: bool) -> Result<()> {
    let instance =
        Instance::new(&InstanceOptions::from_env()).context("cannot create a Vulkan instance")?;
    let devices = Device::list(&instance)?;
    if json {
        let list: Vec<serde_json::Value> = devices
            .iter()
            .map(|d| {
                serde_json::json!({
                    "index": d.index,
                    "name": d.name,
                    "type": d.kind_name(),
                    "api_version": d.api_version_string(),
                    "driver": d.driver,
                    "subgroup_size": d.subgroup_size,
                    "missing": d.features.missing(),
                    "traversal": Traversal::Auto.resolve(d).map(|c| serde_json::json!({"kind": c.kind, "reason": c.reason})).ok(),
                    "features": d.features.rows().iter().map(|(n, ok, _)| (n.to_string(), *ok)).collect::<std::collections::BTreeMap<_, _>>(),
                })
            })
            .collect();
        println!("{}", serde_json::to_string_pretty(&list)?);
        return Ok(());
    }
    if devices.is_empty() {
        println!("no Vulkan devices (run scripts/setup to install lavapipe)");
    }
    for d in &devices {
        let missing = d.features.missing();
        println!(
            "[{}] {} — {}, Vulkan {}, {}: {}",
            d.index,
            d.name,
            d.kind_name(),
            d.api_version_string(),
            d.driver,
            if missing.is_empty() {
                "can render"
            } else {
                "cannot render"
            }
        );
        if d.kind == lanterna::vk::vk::PhysicalDeviceType::CPU {
            println!(
                "      SIMD lanes per subgroup: {} ({}={}; --lavapipe-lanes)",
                d.subgroup_size,
                lanterna::vk::lavapipe::WIDTH_VARIABLE,
                lanterna::vk::lavapipe::width_setting()
            );
        }
        if let Ok(c) = Traversal::Auto.resolve(d) {
            println!(
                "      traversal (--traversal auto): {} — {}",
                c.kind, c.reason
            );
        }
        for (name, ok, need) in d.features.rows() {
            println!(
                "      {} {name:<34} ({need})",
                if ok { "yes" } else { " no" }
            );
        }
    }
    Ok(())
}
