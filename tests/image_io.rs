//! Round trips and failure modes of `lanterna::image_io`: every pixel, sum, AOV and
//! metadata field must come back bit-exact, and bad files must give errors naming them.

use std::collections::BTreeMap;
use std::path::Path;

use lanterna::image_io::{
    film_mean, read_exr, tonemap, write_exr, write_png, Aov, Image, ImageError, RenderMeta,
    FILM_SCALE, NONFINITE_COLOR,
};

fn sample_image() -> Image {
    let (w, h) = (5u32, 3u32);
    let n = (w * h) as usize;
    // Sums spanning both u32 halves, including values above 2^32 and u64::MAX-ish.
    let sums: Vec<[u64; 3]> = (0..n as u64)
        .map(|i| [i * 1_000_003, (i << 33) + 7 * i + 1, u64::MAX - i])
        .collect();
    let mut meta = RenderMeta::new();
    meta.spp = Some(48);
    meta.sample_offset = Some(16);
    meta.method = Some("guided-ris".into());
    meta.seed = Some(u64::MAX - 3);
    meta.max_depth = Some(4);
    meta.render_seconds = Some(1.0 / 3.0);
    meta.device = Some("llvmpipe (LLVM 15.0.7, 256 bits)".into());
    meta.scene_path = Some("scenes/cornell – box ü.gltf".into());
    meta.scene_hash = Some("blake3:0123456789abcdef".into());
    meta.extra = BTreeMap::from([
        (
            "note".to_string(),
            "free text, with = and ; and unicode é".to_string(),
        ),
        ("ris.candidates".to_string(), "32".to_string()),
    ]);
    let mut image = Image::from_sums(w, h, sums, meta).unwrap();
    let albedo: Vec<f32> = (0..n * 3).map(|i| i as f32 * 0.125).collect();
    let normal: Vec<f32> = (0..n * 3).map(|i| -(i as f32) / 7.0).collect();
    let depth: Vec<f32> = (0..n).map(|i| 1.0 + i as f32 * 1e-7).collect();
    image
        .aovs
        .push(Aov::new("albedo", &["R", "G", "B"], albedo).unwrap());
    image
        .aovs
        .push(Aov::new("normal", &["X", "Y", "Z"], normal).unwrap());
    image.aovs.push(Aov::new("depth", &["Z"], depth).unwrap());
    image
}

#[test]
fn exr_round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("img.exr");
    let image = sample_image();
    let summary = write_exr(&path, &image).unwrap();
    assert_eq!(summary.nonfinite, 0);
    let back = read_exr(&path).unwrap();
    assert_eq!(back, image);
    // Bitwise, not just ==, for the floats.
    for (a, b) in back.rgb.iter().zip(&image.rgb) {
        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits));
    }
    // No temporary files are left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("img.exr")]);
}

#[test]
fn mean_is_sum_over_scale_over_spp() {
    let image = sample_image();
    let spp = image.meta.spp.unwrap();
    let s = image.sums.as_ref().unwrap()[3][1];
    assert_eq!(image.rgb[3][1], (s as f64 / FILM_SCALE / spp as f64) as f32);
    assert_eq!(film_mean(3 * (1 << 20), 2), 1.5);
    assert_eq!(FILM_SCALE, 1048576.0);
}

#[test]
fn plain_image_round_trip_without_sums() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plain.exr");
    let image = Image::new(
        2,
        2,
        vec![[0.1, 0.2, 0.3], [1e30, -1.0, 0.0], [5.0; 3], [1e-30; 3]],
    )
    .unwrap();
    let _ = write_exr(&path, &image).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!(back, image);
    assert!(back.sums.is_none());
    assert_eq!(
        back.meta.version.as_deref(),
        Some(env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn foreign_exr_f16_rgba_reads_without_metadata() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("foreign.exr");
    let layer = Layer::new(
        (3, 2),
        LayerAttributes::named("main"),
        Encoding::FAST_LOSSLESS,
        SpecificChannels::rgba(|p: Vec2<usize>| {
            (
                f16::from_f32(p.x() as f32),
                f16::from_f32(0.5),
                f16::from_f32(2.0),
                f16::ONE,
            )
        }),
    );
    Image::from_layer(layer).write().to_file(&path).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!((back.width, back.height), (3, 2));
    assert_eq!(back.rgb[2], [2.0, 0.5, 2.0]);
    assert_eq!(back.meta, RenderMeta::default());
    assert!(back.sums.is_none() && back.aovs.is_empty());
}

#[test]
fn missing_file_not_exr_missing_channels() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.exr");
    let e = read_exr(&missing).unwrap_err();
    assert!(matches!(e, ImageError::NotFound { .. }));
    assert!(e.to_string().contains("nope.exr"), "{e}");

    let text = dir.path().join("text.exr");
    std::fs::write(&text, "hello, this is not an image").unwrap();
    let e = read_exr(&text).unwrap_err();
    assert!(matches!(e, ImageError::NotExr { .. }), "{e}");
    assert!(e.to_string().contains("text.exr"), "{e}");

    // A truncated lanterna EXR: magic present, content broken.
    let good = dir.path().join("good.exr");
    let _ = write_exr(&good, &sample_image()).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.path().join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let e = read_exr(&truncated).unwrap_err();
    assert!(e.to_string().contains("truncated.exr"), "{e}");

    // Luminance-only file: no R, G, B.
    use exr::prelude::*;
    let gray = dir.path().join("gray.exr");
    let ch = AnyChannel::new("Y", FlatSamples::F32(vec![0.5; 4]));
    let layer = Layer::new(
        (2, 2),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(std::iter::once(ch).collect()),
    );
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(&gray)
        .unwrap();
    let e = read_exr(&gray).unwrap_err();
    assert!(matches!(e, ImageError::MissingChannels { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("gray.exr") && msg.contains("R, G, B") && msg.contains("Y"),
        "{msg}"
    );
}

#[test]
fn header_resolution_mismatch_is_an_error() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("liar.exr");
    let mut attrs = LayerAttributes::default();
    attrs.other.insert(
        Text::from("lanterna.resolution"),
        AttributeValue::Text(Text::from("4x4")),
    );
    let chans = ["B", "G", "R"].map(|c| AnyChannel::new(c, FlatSamples::F32(vec![0.0; 6])));
    let layer = Layer::new(
        (3, 2),
        attrs,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(chans.into_iter().collect()),
    );
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(&path)
        .unwrap();
    let e = read_exr(&path).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("liar.exr") && msg.contains("size mismatch") && msg.contains("4x4"),
        "{msg}"
    );
}

#[test]
fn shape_errors() {
    assert!(Image::new(2, 2, vec![[0.0; 3]; 3]).is_err());
    assert!(Image::new(0, 2, vec![]).is_err());
    assert!(
        Image::from_sums(1, 1, vec![[0; 3]], RenderMeta::new()).is_err(),
        "spp required"
    );
    assert!(Aov::new("a.b", &["R"], vec![0.0]).is_err());
    assert!(Aov::new("a", &["R", "R"], vec![0.0; 2]).is_err());
    assert!(Aov::new("a", &["R", "G", "B", "A", "X"], vec![0.0; 5]).is_err());
    let mut image = Image::new(1, 1, vec![[0.0; 3]]).unwrap();
    image
        .aovs
        .push(Aov::new("depth", &["Z"], vec![0.0; 2]).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.exr");
    assert!(matches!(
        write_exr(&path, &image),
        Err(ImageError::Shape(_))
    ));
    assert!(!path.exists());
}

#[test]
fn nonfinite_values_are_reported_and_png_shows_magenta() {
    let dir = tempfile::tempdir().unwrap();
    let mut image = Image::new(
        2,
        2,
        vec![[0.0; 3], [1.0, f32::NAN, 0.0], [f32::INFINITY; 3], [0.5; 3]],
    )
    .unwrap();
    image
        .aovs
        .push(Aov::new("depth", &["Z"], vec![1.0, 1.0, 1.0, f32::NEG_INFINITY]).unwrap());
    let exr_path = dir.path().join("nan.exr");
    let s = write_exr(&exr_path, &image).unwrap();
    assert_eq!(s.nonfinite, 5);
    let first = s.first_nonfinite.unwrap();
    assert_eq!((first.x, first.y, first.channel.as_str()), (1, 0, "G"));
    let e = image.check_finite("nan.exr").unwrap_err();
    assert!(
        e.to_string().contains("nan.exr") && e.to_string().contains("(1, 0)"),
        "{e}"
    );
    // NaN survives the EXR round trip (as NaN).
    let back = read_exr(&exr_path).unwrap();
    assert!(back.rgb[1][1].is_nan());

    let png_path = dir.path().join("nan.png");
    let s = write_png(&png_path, &image, 0.0).unwrap();
    assert_eq!(s.nonfinite, 5);
    let png = image::open(&png_path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (2, 2));
    assert_eq!(png.get_pixel(1, 0).0, NONFINITE_COLOR);
    assert_eq!(png.get_pixel(0, 1).0, NONFINITE_COLOR);
    assert_eq!(png.get_pixel(0, 0).0, [0, 0, 0]);
    // 0.5 linear -> sRGB 0.7354 -> 188
    assert_eq!(png.get_pixel(1, 1).0, [188, 188, 188]);
}

#[test]
fn tonemap_exposure_clamp_and_srgb() {
    let px = [[0.25, 1.0, 2.0], [-1.0, 0.001, 0.0031308]];
    let t = tonemap(&px, 1.0); // x2
    assert_eq!(t[0], [188, 255, 255]);
    // 0.002 -> 12.92*0.002 = 0.02584 -> 6.59 -> 7; 0.0062616 -> 1.055*x^(1/2.4)-0.055
    let v = 1.055 * (0.0062616f64).powf(1.0 / 2.4) - 0.055;
    assert_eq!(t[1], [0, 7, (v * 255.0 + 0.5) as u8]);
}

#[test]
fn write_errors_name_the_file() {
    let image = Image::new(1, 1, vec![[0.0; 3]]).unwrap();
    let e = write_exr(Path::new("/nonexistent-dir-lanterna/x.exr"), &image).unwrap_err();
    assert!(
        e.to_string().contains("/nonexistent-dir-lanterna/x.exr"),
        "{e}"
    );
}
