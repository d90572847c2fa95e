//! Suite `traversal`: ray traversal alone. The same camera, diffuse-bounce and shadow ray
//! sets (`render::trace`) traced by the device's ray queries and by the software
//! traversal over the CPU-built BVH, through the renderer's own `trace_closest` /
//! `visible` (the trace kernels), on each shipped scene (camera rays of an image twice the
//! throughput suite's width and height): M rays/s
//! of GPU time (median over the runs after a warm-up) and how many hits differ.

use super::spread::Spread;
use super::{Bench, Result};
use crate::gpu;
use crate::render::trace::{camera_rays, secondary_rays, RaySets};
use crate::render::{Method, Traversal, TraversalKind};

/// One ray set on one scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RaySetTiming {
    /// camera, bounce or shadow.
    pub set: String,
    pub rays: usize,
    /// M rays per GPU second, per traversal (`ray-query`, `software`).
    pub ray_query_mrays_per_s: Option<Spread>,
    pub software_mrays_per_s: Spread,
    /// Rays whose closest hit (instance, primitive) or visibility differs between the two
    /// (None without ray queries). Ties at equal t count here too.
    pub different_hits: Option<usize>,
}

/// One scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SceneTraversal {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub triangles: u64,
    pub bvh_nodes: usize,
    /// Most triangles per leaf of the software BVH.
    pub bvh_max_leaf: usize,
    pub bvh_depth: usize,
    pub sets: Vec<RaySetTiming>,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TraversalBench {
    pub scenes: Vec<SceneTraversal>,
}

pub fn run(bench: &Bench) -> Result<TraversalBench> {
    let mut scenes = Vec::new();
    let ray_queries = bench.device.info.features.ray_queries();
    for size in &bench.sizes.throughput {
        let path = bench.scene_path(&size.scene)?;
        log::info!("traversal: {} at width {}", size.scene, size.width);
        let mut sw = bench.open_with(
            &path,
            size.width,
            size.height,
            Method::Pt,
            Traversal::Software,
        )?;
        let mut rq = if ray_queries {
            Some(bench.open_with(
                &path,
                size.width,
                size.height,
                Method::Pt,
                Traversal::RayQuery,
            )?)
        } else {
            None
        };
        // Rays of a 2× larger image than the throughput's: dispatches of tens of
        // milliseconds, long enough to time.
        let camera = camera_rays(sw.renderer.camera(), 2 * sw.width, 2 * sw.height, 1);
        sw.renderer.prepare_trace()?;
        if let Some(r) = rq.as_mut() {
            r.renderer.prepare_trace()?;
        }
        let camera_hits = sw.renderer.trace(&camera)?.hits;
        let sets: RaySets = secondary_rays(
            &sw.loaded.scene,
            &sw.loaded.lights,
            &sw.renderer.gpu_scene.instance_order,
            camera,
            &camera_hits,
            2,
        );
        let mut timings = Vec::new();
        for (name, rays) in sets.sets() {
            let time = |r: &mut crate::render::Renderer| -> Result<(Spread, Vec<gpu::TraceHit>)> {
                let mut hits = r.trace(rays)?.hits; // warm-up
                let mut rates = Vec::new();
                for _ in 0..bench.repeat {
                    let out = r.trace(rays)?;
                    rates.push(rays.len() as f64 / out.gpu_seconds / 1e6);
                    hits = out.hits;
                }
                Ok((Spread::of(&rates), hits))
            };
            let (sw_rate, sw_hits) = time(&mut sw.renderer)?;
            let (rq_rate, different) = match rq.as_mut() {
                Some(r) => {
                    let (rate, hits) = time(&mut r.renderer)?;
                    let diff = rays
                        .iter()
                        .zip(hits.iter().zip(&sw_hits))
                        .filter(|(ray, (a, b))| {
                            if ray.kind == gpu::TRACE_VISIBLE {
                                a.primitive != b.primitive
                            } else {
                                (a.instance, a.primitive) != (b.instance, b.primitive)
                            }
                        })
                        .count();
                    (Some(rate), Some(diff))
                }
                None => (None, None),
            };
            log::info!(
                "  {} {name}: {} rays, software {:.2} M rays/s, ray query {}",
                size.scene,
                rays.len(),
                sw_rate.median,
                rq_rate
                    .map(|r| format!("{:.2} M rays/s", r.median))
                    .unwrap_or_else(|| "unavailable".into())
            );
            timings.push(RaySetTiming {
                set: name.into(),
                rays: rays.len(),
                ray_query_mrays_per_s: rq_rate,
                software_mrays_per_s: sw_rate,
                different_hits: different,
            });
        }
        let stats = sw.renderer.gpu_scene.bvh_stats;
        scenes.push(SceneTraversal {
            scene: size.scene.clone(),
            width: sw.width,
            height: sw.height,
            triangles: sw.loaded.scene.triangle_count(),
            bvh_nodes: stats.nodes,
            bvh_max_leaf: stats.max_leaf,
            bvh_depth: stats.depth,
            sets: timings,
        });
        debug_assert_eq!(sw.renderer.traversal.kind, TraversalKind::Software);
    }
    Ok(TraversalBench { scenes })
}
