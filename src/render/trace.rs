//! Tracing given rays alone, through the renderer's own `trace_closest` / `visible`
//! (kernel `tests/trace`, or `tests/trace_sw` with the software traversal), and the ray
//! sets that the traversal tests and `lanterna bench --suite traversal` use: camera rays,
//! diffuse bounce rays from the camera rays' hits, shadow rays from those hits to points
//! on emissive triangles (or, without any, on random scene triangles), and the bounce
//! rays again as the path loop traces them, from along their own line with a probe.

use super::{Renderer, Result};
use crate::gpu;
use crate::lights::LightTable;
use crate::scene::{Camera, Projection, Scene};
use crate::vk::{BindingSpec, Buffer, ComputePipeline, DescriptorSet};
use ash::vk as raw;
use glam::Vec3;
use std::time::Instant;

/// Hits of one trace, with its GPU and wall time.
pub struct TraceOutcome {
    pub hits: Vec<gpu::TraceHit>,
    /// GPU time of the dispatches (timestamps; the wall time where there are none).
    pub gpu_seconds: f64,
    pub wall_seconds: f64,
}

/// Rays per dispatch (keeps each submission short).
const RAYS_PER_DISPATCH: u32 = 1 << 16;

impl Renderer {
    /// Trace `rays` with this renderer's traversal.
    pub fn trace(&mut self, rays: &[gpu::TraceRay]) -> Result<TraceOutcome> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        let n = rays.len().max(1);
        self.trace_rays = Buffer::from_slice(&self.device, rays, usage, "trace rays")?;
        self.trace_hits = Buffer::zeroed(
            &self.device,
            (n * std::mem::size_of::<gpu::TraceHit>()) as u64,
            usage | raw::BufferUsageFlags::TRANSFER_SRC,
            "trace hits",
        )?;
        self.set = None;
        if self.trace_pipeline.is_none() {
            let spirv = self
                .shaders
                .load(&self.traversal.kind.kernel("tests/trace"))?;
            let bindings: Vec<BindingSpec> = self.bindings();
            let p = ComputePipeline::new(
                &self.device,
                &spirv,
                &bindings,
                std::mem::size_of::<gpu::PushConstants>() as u32,
                // Only specialization constant 7 (SCENE_ADDRESSES) is in this kernel.
                &[0, 0, 0, 0, 0, 0, 0, self.scene_addresses() as u32],
                &format!("trace ({})", self.traversal.kind),
            )?;
            self.trace_pipeline = Some(p);
        }
        let pipeline = self.trace_pipeline.as_ref().unwrap();
        let set = DescriptorSet::new(&self.device, pipeline)?;
        self.write_scene_descriptors(&set);
        let started = Instant::now();
        let mut gpu_seconds = 0.0;
        let mut begin = 0u32;
        while (begin as usize) < rays.len() {
            let count = RAYS_PER_DISPATCH.min(rays.len() as u32 - begin);
            let push = gpu::PushConstants {
                sample_begin: begin,
                sample_count: count,
                ..Default::default()
            };
            let ((), t) = self.device.submit_timed(
                |cmd| {
                    pipeline.cmd_dispatch(
                        cmd,
                        set.raw,
                        bytemuck::bytes_of(&push),
                        [count.div_ceil(64), 1, 1],
                    )
                },
                true,
            )?;
            gpu_seconds += t.unwrap_or(0.0);
            begin += count;
        }
        let wall_seconds = started.elapsed().as_secs_f64();
        if gpu_seconds == 0.0 {
            gpu_seconds = wall_seconds;
        }
        let hits = self.trace_hits.read(rays.len())?;
        Ok(TraceOutcome {
            hits,
            gpu_seconds,
            wall_seconds,
        })
    }

    /// Compile the trace kernel and run it once on one ray (lavapipe compiles at the
    /// first dispatch), so that a timed trace measures traversal alone.
    pub fn prepare_trace(&mut self) -> Result<()> {
        self.trace(&[trace_ray(Vec3::ZERO, Vec3::Z, 1.0, gpu::TRACE_CLOSEST)])?;
        Ok(())
    }
}

/// A ray of the trace kernel of kind `kind` (`TRACE_CLOSEST` or `TRACE_VISIBLE`).
fn trace_ray(origin: Vec3, dir: Vec3, tmax: f32, kind: u32) -> gpu::TraceRay {
    gpu::TraceRay {
        origin: origin.to_array(),
        tmax,
        dir: dir.to_array(),
        kind,
        probe_origin: [0.0; 3],
        probe_dir: [0.0; 3],
    }
}

/// The four ray sets of one view.
pub struct RaySets {
    pub camera: Vec<gpu::TraceRay>,
    pub bounce: Vec<gpu::TraceRay>,
    pub shadow: Vec<gpu::TraceRay>,
    /// Bounce rays that start along their own line, each with the probe of the stretch
    /// its origin skipped (`TRACE_PROBED`; bounce_origin in inc/trace.glsl).
    pub probed: Vec<gpu::TraceRay>,
}

impl RaySets {
    pub fn sets(&self) -> [(&'static str, &[gpu::TraceRay]); 4] {
        [
            ("camera", &self.camera),
            ("bounce", &self.bounce),
            ("shadow", &self.shadow),
            ("probed", &self.probed),
        ]
    }
}

/// A small xorshift generator (ray sets must not depend on the kernels' random numbers).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Camera rays through jittered positions in each pixel of a `width`×`height` image
/// (perspective cameras; an orthographic one is replaced by a 45° perspective view from
/// the same place).
pub fn camera_rays(camera: &Camera, width: u32, height: u32, seed: u64) -> Vec<gpu::TraceRay> {
    let to_world = camera.rigid_to_world();
    let tan = match camera.projection {
        Projection::Perspective { yfov, .. } => (0.5 * yfov).tan(),
        Projection::Orthographic { .. } => (22.5f32).to_radians().tan(),
    };
    let aspect = width as f32 / height as f32;
    let origin = to_world.transform_point3(Vec3::ZERO);
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut rays = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let sx = (2.0 * (x as f32 + rng.next()) / width as f32 - 1.0) * tan * aspect;
            let sy = (1.0 - 2.0 * (y as f32 + rng.next()) / height as f32) * tan;
            let d = to_world
                .transform_vector3(Vec3::new(sx, sy, -1.0))
                .normalize();
            rays.push(trace_ray(origin, d, 1e30, gpu::TRACE_CLOSEST));
        }
    }
    rays
}

/// World-space corners of the triangle `primitive` of GPU instance `instance`.
fn triangle(scene: &Scene, order: &[usize], instance: u32, primitive: u32) -> [Vec3; 3] {
    let inst = &scene.instances[order[instance as usize]];
    let p = &scene.primitives[inst.primitive as usize];
    let base = (p.index_offset + 3 * primitive) as usize;
    [0, 1, 2].map(|j| {
        let v = p.vertex_offset + scene.indices[base + j];
        inst.transform
            .transform_point3(Vec3::from(scene.vertices[v as usize].position))
    })
}

/// Camera, bounce and shadow rays of a view: `camera_hits` are the hits of `camera`
/// (traced with either traversal). Bounce rays leave each hit point (moved off the surface
/// by 10⁻⁴ of the scene's extent) in a cosine-distributed direction; shadow rays go from
/// there to a uniform point on a random emissive triangle, as segments with tmax < 1;
/// probed rays are the bounce rays with their probes (`probed_ray`, with 10⁻³ of the
/// extent for offset_ray's distance: far more than it is, so that more probes meet
/// geometry).
pub fn secondary_rays(
    scene: &Scene,
    lights: &LightTable,
    gpu_instance_order: &[usize],
    camera: Vec<gpu::TraceRay>,
    camera_hits: &[gpu::TraceHit],
    seed: u64,
) -> RaySets {
    let mut rng = Rng(seed.wrapping_mul(0xd1b5_4a32_d192_ed03) | 1);
    let eps = 1e-4 * scene.extent().max(1e-3);
    let mut bounce = Vec::new();
    let mut shadow = Vec::new();
    let mut probed = Vec::new();
    for (ray, hit) in camera.iter().zip(camera_hits) {
        if hit.instance == gpu::INVALID_INDEX {
            continue;
        }
        let d = Vec3::from(ray.dir);
        let p = Vec3::from(ray.origin) + hit.t * d;
        let [a, b, c] = triangle(scene, gpu_instance_order, hit.instance, hit.primitive);
        let mut n = (b - a).cross(c - a).normalize_or_zero();
        if n == Vec3::ZERO {
            continue;
        }
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let o = p + eps * n;
        // Cosine-weighted direction around n.
        let (u1, u2) = (rng.next(), rng.next());
        let r = u1.sqrt();
        let phi = std::f32::consts::TAU * u2;
        let (t1, t2) = n.any_orthonormal_pair();
        let dir =
            (r * phi.cos() * t1 + r * phi.sin() * t2 + (1.0 - u1).max(0.0).sqrt() * n).normalize();
        bounce.push(trace_ray(o, dir, 1e30, gpu::TRACE_CLOSEST));
        probed.push(probed_ray(p, n, dir, 10.0 * eps));
        let target = if lights.triangles.is_empty() {
            let k = gpu_instance_order.len() as f32 * rng.next();
            let inst = (k as usize).min(gpu_instance_order.len() - 1);
            let prim =
                &scene.primitives[scene.instances[gpu_instance_order[inst]].primitive as usize];
            let t = ((prim.triangle_count as f32 * rng.next()) as u32)
                .min(prim.triangle_count.saturating_sub(1));
            triangle(scene, gpu_instance_order, inst as u32, t)
        } else {
            let k = ((lights.triangles.len() as f32 * rng.next()) as usize)
                .min(lights.triangles.len() - 1);
            let l = &lights.triangles[k];
            [l.p0, l.p1, l.p2].map(Vec3::from)
        };
        let (mut u, mut v) = (rng.next(), rng.next());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let q = target[0] + u * (target[1] - target[0]) + v * (target[2] - target[0]);
        shadow.push(trace_ray(o, q - o, 1.0 - 1e-3, gpu::TRACE_VISIBLE));
    }
    RaySets {
        camera,
        bounce,
        shadow,
        probed,
    }
}

/// The bounce ray leaving surface point `p` (unit normal `n` on its side) in unit
/// direction `w` as the path loop traces it, with `clearance` for offset_ray's distance
/// off the surface (bounce_origin in inc/trace.glsl, GRAZING_STRETCH 64): from the point
/// of its own line that far off the surface (at most 64 × `clearance` along it), with the
/// probe from `p + clearance·n` to that point.
fn probed_ray(p: Vec3, n: Vec3, w: Vec3, clearance: f32) -> gpu::TraceRay {
    let cos_w = w.dot(n);
    let t = if cos_w * 64.0 >= 1.0 {
        clearance / cos_w
    } else {
        64.0 * clearance
    };
    let lifted = p + clearance * n;
    let along = p + t * w + (clearance - t * cos_w) * n;
    gpu::TraceRay {
        probe_origin: lifted.to_array(),
        probe_dir: (along - lifted).to_array(),
        ..trace_ray(along, w, 1e30, gpu::TRACE_PROBED)
    }
}
