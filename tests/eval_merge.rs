//! `merge`: renders of disjoint sample ranges add up bit-exactly to one render of the
//! union (through EXR files and through the CLI), and inputs that cannot belong to one
//! render are refused with messages naming the files.

use std::path::Path;
use std::process::Command;

use lanterna::eval::merge::{merge, MergeError};
use lanterna::image_io::{read_exr, write_exr, Aov, Image, RenderMeta};

const W: u32 = 7;
const H: u32 = 5;

/// A deterministic per-sample film contribution (fixed point, up to ~4 in radiance).
fn sample_value(pixel: usize, c: usize, s: u64) -> u64 {
    let mut x = (pixel as u64) << 40 ^ (c as u64) << 32 ^ s;
    x = x.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 29;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    (x >> 42) & 0x3F_FFFF
}

fn meta() -> RenderMeta {
    let mut m = RenderMeta::new();
    m.method = Some("guided-ris".into());
    m.seed = Some(7);
    m.max_depth = Some(4);
    m.scene_hash = Some("hash-A".into());
    m.scene_path = Some("scenes/a.gltf".into());
    m.device = Some("llvmpipe".into());
    m.render_seconds = Some(1.5);
    m.extra.insert("exposure".into(), "0".into());
    m
}

/// The image of samples [first, first + count), as the renderer would produce it.
fn render(first: u64, count: u64) -> Image {
    let n = (W * H) as usize;
    let sums = (0..n)
        .map(|p| [0, 1, 2].map(|c| (first..first + count).map(|s| sample_value(p, c, s)).sum()))
        .collect();
    let mut m = meta();
    m.spp = Some(count);
    m.sample_offset = Some(first);
    let mut image = Image::from_sums(W, H, sums, m).unwrap();
    let depth = (0..n).map(|p| p as f32 + first as f32).collect();
    image.aovs.push(Aov::new("depth", &["Z"], depth).unwrap());
    image
}

fn save(dir: &Path, name: &str, image: &Image) -> String {
    let path = dir.join(name);
    let s = write_exr(&path, image).unwrap();
    assert_eq!(s.nonfinite, 0);
    path.display().to_string()
}

fn assert_same_pixels(a: &Image, b: &Image) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert_eq!(a.sums, b.sums);
    let bits = |i: &Image| {
        i.rgb
            .iter()
            .map(|p| p.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(a), bits(b));
}

#[test]
fn merged_chunks_equal_one_shot_bitwise() {
    let dir = tempfile::tempdir().unwrap();
    let one_shot = render(0, 48);
    let parts = [render(0, 5), render(5, 16), render(21, 27)];
    let paths: Vec<String> = parts
        .iter()
        .enumerate()
        .map(|(i, p)| save(dir.path(), &format!("p{i}.exr"), p))
        .collect();
    let read: Vec<Image> = paths
        .iter()
        .map(|p| read_exr(Path::new(p)).unwrap())
        .collect();
    // Any order.
    let order = [2, 0, 1];
    let pairs: Vec<(&str, &Image)> = order
        .iter()
        .map(|&i| (paths[i].as_str(), &read[i]))
        .collect();
    let merged = merge(&pairs).unwrap();
    assert!(merged.exact);
    assert!(merged.warnings.is_empty(), "{:?}", merged.warnings);
    assert_same_pixels(&merged.image, &one_shot);
    let m = &merged.image.meta;
    assert_eq!((m.spp, m.sample_offset), (Some(48), Some(0)));
    assert_eq!(m.method.as_deref(), Some("guided-ris"));
    assert_eq!((m.seed, m.max_depth), (Some(7), Some(4)));
    assert_eq!(m.scene_hash.as_deref(), Some("hash-A"));
    assert_eq!(m.render_seconds, Some(4.5));
    assert_eq!(m.device.as_deref(), Some("llvmpipe"));
    assert_eq!(m.extra.get("exposure").map(String::as_str), Some("0"));
    assert!(!m.extra.contains_key("sample_ranges"));
    // AOVs are spp-weighted means: depth = p + (0*5 + 5*16 + 21*27) / 48.
    let depth = &merged.image.aovs[0];
    let expected = (5.0 * 16.0 + 21.0 * 27.0) / 48.0;
    assert!((depth.data[3] - (3.0 + expected as f32)).abs() < 1e-5);
}

#[test]
fn gaps_are_recorded_and_filling_them_is_exact() {
    let a = render(0, 4);
    let c = render(12, 4);
    let merged = merge(&[("a.exr", &a), ("c.exr", &c)]).unwrap();
    assert_eq!(
        merged
            .image
            .meta
            .extra
            .get("sample_ranges")
            .map(String::as_str),
        Some("0..4,12..16")
    );
    assert!(merged.warnings.iter().any(|w| w.contains("not contiguous")));
    // Round trip through EXR keeps the ranges, and the gap piece completes it exactly.
    let dir = tempfile::tempdir().unwrap();
    let ac = read_exr(Path::new(&save(dir.path(), "ac.exr", &merged.image))).unwrap();
    let b = render(4, 8);
    let full = merge(&[("ac.exr", &ac), ("b.exr", &b)]).unwrap();
    assert!(!full.image.meta.extra.contains_key("sample_ranges"));
    assert_same_pixels(&full.image, &render(0, 16));
    // The gap bookkeeping also catches overlaps inside the recorded ranges.
    let e = merge(&[("ac.exr", &ac), ("x.exr", &render(13, 1))]).unwrap_err();
    assert!(matches!(e, MergeError::Overlap { .. }), "{e}");
}

#[test]
fn refusals_name_both_files_and_the_difference() {
    let a = render(0, 8);
    type Change = Box<dyn Fn(&mut Image)>;
    let cases: Vec<(&str, Change)> = vec![
        (
            "scene (hash)",
            Box::new(|i: &mut Image| i.meta.scene_hash = Some("hash-B".into())),
        ),
        (
            "method",
            Box::new(|i: &mut Image| i.meta.method = Some("pt".into())),
        ),
        ("seed", Box::new(|i: &mut Image| i.meta.seed = Some(8))),
        (
            "max_depth",
            Box::new(|i: &mut Image| i.meta.max_depth = Some(5)),
        ),
    ];
    for (field, change) in cases {
        let mut b = render(8, 8);
        change(&mut b);
        let e = merge(&[("first.exr", &a), ("second.exr", &b)]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, MergeError::Mismatch { .. }), "{msg}");
        assert!(
            msg.contains("first.exr") && msg.contains("second.exr") && msg.contains(field),
            "{msg}"
        );
    }
    // Resolution.
    let mut small = Image::from_sums(3, 3, vec![[1, 2, 3]; 9], {
        let mut m = meta();
        m.spp = Some(8);
        m.sample_offset = Some(8);
        m
    })
    .unwrap();
    small.aovs.clear();
    let msg = merge(&[("first.exr", &a), ("small.exr", &small)])
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("resolution") && msg.contains("7x5") && msg.contains("3x3"),
        "{msg}"
    );
    // Overlap.
    let msg = merge(&[
        ("first.exr", &a),
        ("b.exr", &render(4, 8)),
        ("c.exr", &render(20, 1)),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        msg.contains("overlap") && msg.contains("first.exr") && msg.contains("b.exr"),
        "{msg}"
    );
    assert!(msg.contains("0..8") && msg.contains("4..12"), "{msg}");
    // Same file twice is an overlap too.
    assert!(matches!(
        merge(&[("a", &a), ("a", &a)]),
        Err(MergeError::Overlap { .. })
    ));
    // Unknown spp.
    let foreign = Image::new(W, H, vec![[0.5; 3]; (W * H) as usize]).unwrap();
    let e = merge(&[("a.exr", &a), ("foreign.exr", &foreign)]).unwrap_err();
    assert!(e.to_string().contains("foreign.exr"), "{e}");
    // Fewer than two.
    assert!(matches!(merge(&[("a.exr", &a)]), Err(MergeError::TooFew)));
}

#[test]
fn without_sums_merges_by_weighted_mean_with_a_warning() {
    let a = render(0, 1);
    let mut b = render(1, 3);
    b.sums = None;
    let merged = merge(&[("a.exr", &a), ("b.exr", &b)]).unwrap();
    assert!(!merged.exact);
    assert!(merged.image.sums.is_none());
    assert!(
        merged
            .warnings
            .iter()
            .any(|w| w.contains("b.exr") && w.contains("not bit-exact")),
        "{:?}",
        merged.warnings
    );
    let exact = render(0, 4);
    for (p, q) in merged.image.rgb.iter().zip(&exact.rgb) {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-6 * q[c].abs().max(1.0),
                "{p:?} vs {q:?}"
            );
        }
    }
    assert_eq!(merged.image.meta.spp, Some(4));
}

#[test]
fn cli_merge_writes_exact_result_and_refuses_mismatches() {
    let dir = tempfile::tempdir().unwrap();
    let a = save(dir.path(), "a.exr", &render(0, 3));
    let b = save(dir.path(), "b.exr", &render(3, 5));
    let out = dir.path().join("out.exr");
    let bin = env!("CARGO_BIN_EXE_lanterna");
    let status = Command::new(bin)
        .args(["merge", &a, &b, "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    assert_same_pixels(&read_exr(&out).unwrap(), &render(0, 8));

    let mut other = render(8, 2);
    other.meta.scene_hash = Some("hash-B".into());
    let c = save(dir.path(), "c.exr", &other);
    let out2 = dir.path().join("out2.exr");
    let result = Command::new(bin)
        .args(["merge", &a, &c, "-o"])
        .arg(&out2)
        .output()
        .unwrap();
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(
        stderr.contains("a.exr") && stderr.contains("c.exr") && stderr.contains("scene"),
        "{stderr}"
    );
    assert!(!out2.exists());

    let missing = dir.path().join("missing.exr");
    let result = Command::new(bin)
        .args(["merge", &a])
        .arg(&missing)
        .arg("-o")
        .arg(&out2)
        .output()
        .unwrap();
    assert!(!result.status.success());
    assert!(String::from_utf8_lossy(&result.stderr).contains("missing.exr"));
}
