//! lavapipe's SIMD width, chosen before the first Vulkan instance of the process.
//!
//! lavapipe (llvmpipe's gallivm) compiles a compute kernel for a fixed number of SIMD
//! lanes — one invocation per lane, 8 lanes of 32 bits with AVX2 — read once per process
//! from `LP_NATIVE_VECTOR_WIDTH` (bits). The path kernel's loops diverge: a lane whose ray
//! left the BVH, or whose path ended, waits for the slowest of its subgroup. With 4 lanes
//! fewer wait, and measured on AVX2 (README, Benchmarks: "SIMD width") `pt` and `guided`
//! render 10–20 % more samples per second, `guided-ris` 4–13 %, and kernels compile in
//! half the time, while `ris`, whose 32 candidates per vertex keep all lanes busy, loses
//! 6–13 %.
//! So lanterna asks for 4 lanes unless told otherwise (`--lavapipe-lanes`, or the variable
//! itself).
//!
//! Mesa's shader cache keys a compiled kernel by its shader and layout but not by the
//! width it was compiled for, and serves a kernel compiled for 8 lanes to a process
//! running 4 (it runs, at the old width's speed). So each width gets its own cache
//! folder, unless the user chose one with `MESA_SHADER_CACHE_DIR`.
//!
//! Other drivers ignore `LP_NATIVE_VECTOR_WIDTH`; on them only the cache folder moves.

use std::path::PathBuf;
use std::sync::Once;

/// The variable gallivm reads its vector width (bits) from.
pub const WIDTH_VARIABLE: &str = "LP_NATIVE_VECTOR_WIDTH";
/// SIMD lanes lanterna asks lavapipe for when nobody has chosen.
pub const DEFAULT_LANES: u32 = 4;
/// Lane counts `--lavapipe-lanes` accepts (128-, 256- and 512-bit vectors).
pub const LANE_CHOICES: [u32; 3] = [4, 8, 16];

static CONFIGURED: Once = Once::new();

/// Ask for `lanes` SIMD lanes, overriding `LP_NATIVE_VECTOR_WIDTH` from the environment.
/// Only takes effect before the process's first Vulkan instance ([`configure`]); call it
/// while the process has a single thread (the command line does, first thing).
pub fn request_lanes(lanes: u32) {
    std::env::set_var(WIDTH_VARIABLE, (lanes * 32).to_string());
}

/// Set the width (unless already set) and the cache folder that goes with it (unless the
/// user set one), once per process, before the first instance exists: gallivm reads the
/// width once, when it starts, and Mesa opens its cache when a device is made.
pub(super) fn configure() {
    CONFIGURED.call_once(|| {
        // The environment is written before any Vulkan object exists; other threads that
        // read it (the test harness's) wait on this Once in `Instance::new`.
        if std::env::var_os(WIDTH_VARIABLE).is_none() {
            std::env::set_var(WIDTH_VARIABLE, (DEFAULT_LANES * 32).to_string());
        }
        if std::env::var_os("MESA_SHADER_CACHE_DIR").is_none() {
            if let Some(dir) = cache_dir(&width_setting()) {
                std::env::set_var("MESA_SHADER_CACHE_DIR", dir);
            }
        }
        log::debug!(
            "lavapipe: {WIDTH_VARIABLE}={}, MESA_SHADER_CACHE_DIR={}",
            width_setting(),
            std::env::var("MESA_SHADER_CACHE_DIR").unwrap_or_default()
        );
    });
}

/// The width setting as the environment has it now (after [`configure`], what gallivm
/// read, unless the process changed it since).
pub fn width_setting() -> String {
    std::env::var(WIDTH_VARIABLE).unwrap_or_default()
}

/// Mesa's default cache home (`$XDG_CACHE_HOME`, else `~/.cache`) with a folder per width.
fn cache_dir(width: &str) -> Option<PathBuf> {
    let home = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|v| !v.is_empty())
                .map(|h| PathBuf::from(h).join(".cache"))
        })?;
    Some(cache_dir_under(&home, width))
}

fn cache_dir_under(home: &std::path::Path, width: &str) -> PathBuf {
    // The folder is named after the width gallivm reads from the variable, so that two
    // spellings of one width share it and a value it ignores shares the default's; only
    // a number reaches the path (the variable is the user's to set).
    let folder = match mesa_num_option(width) {
        Some(bits) => format!("mesa-shader-cache-lp{bits}"),
        None => "mesa-shader-cache-lpdefault".to_string(),
    };
    home.join("lanterna").join(folder)
}

/// A number as Mesa's `debug_parse_num_option` reads one (`strtoll` with base 0: leading
/// space, a sign, `0x` hex or `0` octal, the longest run of digits), or None where it
/// finds no digits and keeps its default.
fn mesa_num_option(text: &str) -> Option<i64> {
    let t = text.trim_start();
    let (negative, t) = match t.as_bytes().first() {
        Some(b'-') => (true, &t[1..]),
        Some(b'+') => (false, &t[1..]),
        _ => (false, t),
    };
    let (radix, digits) = if let Some(hex) = t.strip_prefix("0x").or(t.strip_prefix("0X")) {
        if hex.starts_with(|c: char| c.is_ascii_hexdigit()) {
            (16, hex)
        } else {
            (8, t) // "0x" without hex digits reads as the 0 before the x
        }
    } else if t.starts_with('0') {
        (8, t)
    } else {
        (10, t)
    };
    let run: String = digits.chars().take_while(|c| c.is_digit(radix)).collect();
    let value = i64::from_str_radix(&run, radix).ok()?;
    Some(if negative { -value } else { value })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn each_width_has_its_own_cache_folder() {
        let home = Path::new("/c");
        assert_eq!(
            cache_dir_under(home, "128"),
            Path::new("/c/lanterna/mesa-shader-cache-lp128")
        );
        assert_ne!(cache_dir_under(home, "128"), cache_dir_under(home, "256"));
        // Spellings of one width share its folder, as gallivm reads them (strtoll).
        for same in ["0x80", " 128", "0200", "128 bits"] {
            assert_eq!(
                cache_dir_under(home, same),
                cache_dir_under(home, "128"),
                "{same:?}"
            );
        }
        // Whatever the variable holds, the folder stays under the cache home, and a value
        // without digits (gallivm keeps its default) shares the default's.
        for odd in ["../../etc", "", "x128"] {
            assert_eq!(
                cache_dir_under(home, odd),
                Path::new("/c/lanterna/mesa-shader-cache-lpdefault"),
                "{odd:?}"
            );
        }
    }
}
