//! What the numbers were measured on: the Vulkan device, the CPU and its core count (on
//! lavapipe the "GPU" is those cores), the OS and lanterna's version. Saved in every
//! results file so that runs on different machines are never compared by accident.

use crate::vk::Device;

/// The machine and device of a bench run.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Machine {
    /// Vulkan device name, as `lanterna info` lists it.
    pub device: String,
    /// `CPU`, `discrete GPU`, …
    pub device_type: String,
    pub driver: String,
    pub vulkan_api: String,
    /// Logical CPU cores available to this process.
    pub cpu_cores: usize,
    pub cpu_model: String,
    /// lavapipe's thread count when `LP_NUM_THREADS` is set.
    pub lp_num_threads: Option<String>,
    pub os: String,
    pub lanterna_version: String,
}

impl Machine {
    pub fn describe(device: &Device) -> Machine {
        let info = &device.info;
        Machine {
            device: info.name.clone(),
            device_type: info.kind_name().to_string(),
            driver: info.driver.clone(),
            vulkan_api: info.api_version_string(),
            cpu_cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            cpu_model: cpu_model().unwrap_or_else(|| std::env::consts::ARCH.to_string()),
            lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
            os: os_name().unwrap_or_else(|| std::env::consts::OS.to_string()),
            lanterna_version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }

    /// A short file-name-safe name of the device: its name up to any parenthesis,
    /// lower-cased, runs of other characters turned into one `-` (`llvmpipe`,
    /// `nvidia-geforce-rtx-4090`).
    pub fn device_slug(&self) -> String {
        slug(self.device.split(" (").next().unwrap_or(&self.device))
    }
}

pub fn slug(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') && !out.is_empty() {
            out.push('-');
        }
    }
    let out = out.trim_end_matches('-').to_string();
    if out.is_empty() {
        "device".into()
    } else {
        out
    }
}

/// The 1, 5 and 15 minute load averages (Linux).
pub fn load_average() -> Option<String> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    Some(
        text.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" "),
    )
}

fn cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    text.lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split_once(':'))
        .map(|(_, v)| v.trim().to_string())
}

fn os_name() -> Option<String> {
    let text = std::fs::read_to_string("/etc/os-release").ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix("PRETTY_NAME="))
        .map(|v| v.trim_matches('"').to_string())
}

#[cfg(test)]
mod tests {
    use super::slug;

    #[test]
    fn slugs() {
        assert_eq!(slug("llvmpipe"), "llvmpipe");
        assert_eq!(slug("NVIDIA GeForce RTX 4090"), "nvidia-geforce-rtx-4090");
        assert_eq!(slug("  AMD Radeon™ (RADV)  "), "amd-radeon-radv");
        assert_eq!(slug("™"), "device");
    }
}
