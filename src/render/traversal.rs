//! Which ray traversal the kernels use: the driver's ray queries against a TLAS, or the
//! software traversal of `inc/bvh.glsl` over a BVH built on the CPU (`bvh.rs`). The
//! choice is a setting (`--traversal auto|ray-query|software`), resolved against the
//! device once, with the reason kept for `lanterna info`, `render` and the EXR metadata.

use crate::vk::DeviceInfo;
use std::fmt;

/// The requested traversal (`--traversal`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum Traversal {
    /// Software on CPU devices (measured faster on lavapipe) and on devices without ray
    /// queries; ray queries on GPUs that have them.
    #[default]
    Auto,
    RayQuery,
    Software,
}

/// The traversal in use.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum TraversalKind {
    RayQuery,
    Software,
}

impl TraversalKind {
    pub fn name(self) -> &'static str {
        match self {
            TraversalKind::RayQuery => "ray-query",
            TraversalKind::Software => "software",
        }
    }

    /// The kernel name with this traversal's suffix (`render` → `render_sw`).
    pub fn kernel(self, base: &str) -> String {
        match self {
            TraversalKind::RayQuery => base.to_string(),
            TraversalKind::Software => format!("{base}_sw"),
        }
    }
}

impl fmt::Display for TraversalKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A resolved traversal and why it was chosen.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TraversalChoice {
    pub kind: TraversalKind,
    pub reason: String,
}

/// `--traversal ray-query` on a device without ray queries.
#[derive(Debug, thiserror::Error)]
#[error("--traversal ray-query: {0} has no ray queries (VK_KHR_ray_query and VK_KHR_acceleration_structure); use --traversal software or auto")]
pub struct NoRayQueries(pub String);

impl Traversal {
    /// The traversal `self` asks for on `device`.
    pub fn resolve(self, device: &DeviceInfo) -> Result<TraversalChoice, NoRayQueries> {
        let rq = device.features.ray_queries();
        let cpu = device.kind == ash::vk::PhysicalDeviceType::CPU;
        let choice = |kind, reason: &str| TraversalChoice {
            kind,
            reason: reason.to_string(),
        };
        Ok(match self {
            Traversal::RayQuery if !rq => return Err(NoRayQueries(device.name.clone())),
            Traversal::RayQuery => choice(TraversalKind::RayQuery, "requested (--traversal)"),
            Traversal::Software => choice(TraversalKind::Software, "requested (--traversal)"),
            Traversal::Auto if !rq => choice(
                TraversalKind::Software,
                if device.features.ray_queries_hidden {
                    "ray queries reported unavailable (LANTERNA_NO_RAY_QUERY)"
                } else {
                    "the device has no ray queries"
                },
            ),
            Traversal::Auto if cpu => choice(
                TraversalKind::Software,
                "CPU device: software traversal is faster than its ray queries (bench traversal suite)",
            ),
            Traversal::Auto => choice(TraversalKind::RayQuery, "GPU with ray queries"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::FeatureReport;
    use ash::vk::PhysicalDeviceType as Kind;

    fn device(kind: Kind, ray_queries: bool) -> DeviceInfo {
        DeviceInfo {
            index: 0,
            name: "test".into(),
            kind,
            api_version: 0,
            driver: String::new(),
            features: FeatureReport {
                ray_query: ray_queries,
                acceleration_structure: ray_queries,
                ..Default::default()
            },
            timestamp_period_ns: 1.0,
            min_scratch_alignment: 1,
            subgroup_size: 8,
        }
    }

    #[test]
    fn auto_takes_software_on_cpus_and_without_ray_queries() {
        let auto = |k, rq| Traversal::Auto.resolve(&device(k, rq)).unwrap().kind;
        assert_eq!(auto(Kind::CPU, true), TraversalKind::Software);
        assert_eq!(auto(Kind::DISCRETE_GPU, true), TraversalKind::RayQuery);
        assert_eq!(auto(Kind::DISCRETE_GPU, false), TraversalKind::Software);
        assert!(Traversal::RayQuery
            .resolve(&device(Kind::DISCRETE_GPU, false))
            .is_err());
        let sw = Traversal::Software.resolve(&device(Kind::DISCRETE_GPU, true));
        assert_eq!(sw.unwrap().kind, TraversalKind::Software);
    }
}
