//! Where a scene's bytes come from: the scene file itself (refused early when it starts
//! like neither glTF JSON nor GLB, read no further than its declared or allowed size), the
//! buffers and images its URIs name, and a budget on what loading may allocate.
//!
//! URI policy: `data:` URIs are decoded in memory; a relative path or a `file:` URI must
//! resolve (symlinks followed) to a file inside the scene's folder, unless the caller
//! allows outside URIs (`--allow-outside-uris`); every other scheme (`http:`, …) is
//! refused, since lanterna never touches the network. So a scene from an untrusted source
//! cannot make lanterna read `/etc/passwd` as geometry.

use crate::files::{read_input, FileError, Start};
use std::path::{Path, PathBuf};

/// Reads the scene file: GLB is read up to the length its header declares, JSON up to
/// `limit`; anything else is refused after its first bytes.
pub(super) fn read_scene_file(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    read_input(path, limit, &|start| {
        if start.starts_with(b"glTF") {
            return match start.get(8..12) {
                Some(len) => Ok(Start::Length(u64::from(u32::from_le_bytes(
                    len.try_into().expect("four bytes"),
                )))),
                None => Err("truncated GLB header".into()),
            };
        }
        let text = start.strip_prefix(b"\xef\xbb\xbf").unwrap_or(start);
        match text.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(b'{') => Ok(Start::Continue),
            None if start.len() < 64 => Err("empty file, not a glTF scene".into()),
            None => Ok(Start::Continue),
            Some(_) => Err(
                "not a glTF scene: it starts neither with a JSON object nor with the GLB magic `glTF`"
                    .into(),
            ),
        }
    })
}

/// What loading may still allocate (geometry, instances, decoded textures), so that a
/// small file cannot expand into unbounded memory (one buffer referenced by thousands
/// of primitives, a node hierarchy multiplying instances, a PNG bomb).
pub(super) struct Budget {
    pub limit: u64,
    pub used: u64,
}

impl Budget {
    pub fn new(limit: u64) -> Budget {
        Budget { limit, used: 0 }
    }

    pub fn left(&self) -> u64 {
        self.limit.saturating_sub(self.used)
    }

    /// Accounts for `bytes` more, or says what exceeded the limit.
    pub fn take(&mut self, bytes: u64, what: &str) -> Result<(), String> {
        if bytes > self.left() {
            return Err(format!(
                "{what} would take the scene past {} MiB in memory (the input limit; raise it \
                 with {}=MIB if the scene is genuine)",
                self.limit >> 20,
                crate::files::MAX_INPUT_ENV
            ));
        }
        self.used += bytes;
        Ok(())
    }
}

/// Resolves and reads the external files a scene's URIs name.
pub(super) struct UriReader {
    /// The scene's folder as given (for messages) and canonical (for the policy).
    base: PathBuf,
    base_canonical: Option<PathBuf>,
    allow_outside: bool,
    limit: u64,
    /// Every external file read, canonical (the scene's inputs besides the file itself).
    pub files: Vec<PathBuf>,
}

impl UriReader {
    pub fn new(scene: &Path, allow_outside: bool, limit: u64) -> UriReader {
        let base = match scene.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        UriReader {
            base_canonical: std::fs::canonicalize(&base).ok(),
            base,
            allow_outside,
            limit,
            files: Vec::new(),
        }
    }

    /// The bytes of a `data:` URI, or of the file a URI names (at most `max_len` bytes).
    pub fn read(&mut self, uri: &str, max_len: Option<u64>) -> Result<Vec<u8>, String> {
        if uri.starts_with("data:") {
            return gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                .map(|d| d.0)
                .map_err(|e| format!("bad data URI: {e}"));
        }
        let path = self.resolve(uri)?;
        let data = read_input(&path, self.limit, &|_| {
            Ok(match max_len {
                Some(n) => Start::Length(n),
                None => Start::Continue,
            })
        })
        .map_err(|e| e.to_string())?;
        self.files.push(path);
        Ok(data)
    }

    /// The file a (non-data) URI names, checked against the policy.
    fn resolve(&self, uri: &str) -> Result<PathBuf, String> {
        let relative = match uri_scheme(uri) {
            None => percent_decode(uri)?,
            Some(s) if s.eq_ignore_ascii_case("file") => {
                let rest = &uri[s.len() + 1..];
                percent_decode(rest.strip_prefix("//").unwrap_or(rest))?
            }
            Some(s) => {
                return Err(format!(
                    "URI scheme `{s}:` is not supported (lanterna reads local files and data \
                     URIs only, never the network)"
                ))
            }
        };
        let joined = self.base.join(&relative);
        let canonical =
            std::fs::canonicalize(&joined).map_err(|e| format!("{}: {e}", joined.display()))?;
        if !self.allow_outside {
            let inside = self
                .base_canonical
                .as_ref()
                .is_some_and(|b| canonical.starts_with(b));
            if !inside {
                return Err(format!(
                    "`{uri}` resolves to {}, outside the scene's folder {}; lanterna reads \
                     only files inside it unless you pass --allow-outside-uris",
                    canonical.display(),
                    self.base.display()
                ));
            }
        }
        Ok(canonical)
    }
}

/// The scheme of an absolute URI (`ALPHA *(ALPHA / DIGIT / "+" / "-" / ".") ":"`), if any.
fn uri_scheme(uri: &str) -> Option<&str> {
    let (scheme, _) = uri.split_once(':')?;
    let mut chars = scheme.chars();
    let first = chars.next()?;
    (first.is_ascii_alphabetic()
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.')))
    .then_some(scheme)
}

/// `%XX` escapes decoded; the result must be UTF-8.
fn percent_decode(s: &str) -> Result<String, String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8(out).map_err(|_| format!("URI `{s}` does not decode to UTF-8"))
}

/// Decodes a PNG, JPEG or WebP (`EXT_texture_webp`) into the crate's image data,
/// allocating at most `max_bytes`.
pub(super) fn decode_image(bytes: &[u8], max_bytes: u64) -> Result<gltf::image::Data, String> {
    use gltf::image::Format;
    use image::DynamicImage as D;
    use image::ImageFormat as F;
    let format = match image::guess_format(bytes) {
        Ok(f @ (F::Png | F::Jpeg | F::WebP)) => f,
        Ok(f) => {
            return Err(format!(
                "unsupported image encoding {f:?} (PNG, JPEG or WebP expected)"
            ))
        }
        Err(_) => return Err("not a PNG, JPEG or WebP image".into()),
    };
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(max_bytes.min(limits.max_alloc.unwrap_or(u64::MAX)));
    reader.limits(limits);
    let image = reader.decode().map_err(|e| e.to_string())?;
    // The same formats the gltf crate's importer produces, so textures convert alike.
    let format = match &image {
        D::ImageLuma8(_) => Format::R8,
        D::ImageLumaA8(_) => Format::R8G8,
        D::ImageRgb8(_) => Format::R8G8B8,
        D::ImageRgba8(_) => Format::R8G8B8A8,
        D::ImageLuma16(_) => Format::R16,
        D::ImageLumaA16(_) => Format::R16G16,
        D::ImageRgb16(_) => Format::R16G16B16,
        D::ImageRgba16(_) => Format::R16G16B16A16,
        D::ImageRgb32F(_) => Format::R32G32B32FLOAT,
        D::ImageRgba32F(_) => Format::R32G32B32A32FLOAT,
        _ => return Err("unsupported pixel format".into()),
    };
    let (width, height) = (image.width(), image.height());
    Ok(gltf::image::Data {
        pixels: image.into_bytes(),
        format,
        width,
        height,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemes_and_escapes() {
        assert_eq!(uri_scheme("a.bin"), None);
        assert_eq!(uri_scheme("file:///x"), Some("file"));
        assert_eq!(uri_scheme("http://h/x"), Some("http"));
        assert_eq!(uri_scheme("dir/a:b.bin"), None);
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("100%").unwrap(), "100%");
        assert_eq!(percent_decode("%4").unwrap(), "%4");
        assert!(percent_decode("%FF.bin").is_err());
    }

    #[test]
    fn uris_stay_inside_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("scene");
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(sub.join("a.bin"), [1u8; 8]).unwrap();
        std::fs::write(dir.path().join("outside.bin"), [2u8; 8]).unwrap();
        let scene = sub.join("s.gltf");
        let mut r = UriReader::new(&scene, false, 1 << 20);
        assert_eq!(r.read("a.bin", Some(8)).unwrap(), [1u8; 8]);
        assert_eq!(r.read("./a.bin", Some(4)).unwrap(), [1u8; 4]);
        for uri in [
            "../outside.bin",
            "/etc/passwd",
            "file:///etc/passwd",
            "http://example.com/a.bin",
        ] {
            let e = r.read(uri, Some(8)).unwrap_err();
            assert!(
                e.contains("outside the scene's folder") || e.contains("not supported"),
                "{uri}: {e}"
            );
        }
        let mut open = UriReader::new(&scene, true, 1 << 20);
        assert_eq!(open.read("../outside.bin", None).unwrap(), [2u8; 8]);
        assert!(open.read("https://example.com/x", None).is_err());
    }

    /// Every PNG pixel layout (grey, grey + alpha, RGB, RGBA, at 8 and 16 bits) and
    /// JPEG decode to the RGBA texels the renderer uploads: grey spread over R, G and B,
    /// its alpha kept, 8-bit images as 8-bit texels and 16-bit ones with all 16 bits
    /// (until 2026-11-29 they were rounded to 8).
    #[test]
    fn png_layouts_and_jpeg_decode_to_rgba_texels() {
        use crate::vk::Texels;
        use image::{DynamicImage as D, ImageBuffer, ImageFormat};
        let texels = |image: D, format: ImageFormat| -> Texels {
            let mut bytes = Vec::new();
            image
                .write_to(&mut std::io::Cursor::new(&mut bytes), format)
                .unwrap();
            let data = decode_image(&bytes, 1 << 20).unwrap();
            super::super::texture::to_texels(&data).unwrap()
        };
        let png = |image: D| texels(image, ImageFormat::Png);
        let rgba8 = |image: D| match png(image) {
            Texels::Rgba8(v) => v,
            other => panic!("8-bit image decoded to {other:?}"),
        };
        let rgba16 = |image: D| match png(image) {
            Texels::Rgba16(v) => v,
            other => panic!("16-bit image decoded to {other:?}"),
        };
        assert_eq!(
            rgba8(D::ImageLuma8(
                ImageBuffer::from_raw(2, 1, vec![10, 200]).unwrap()
            )),
            [10, 10, 10, 255, 200, 200, 200, 255]
        );
        assert_eq!(
            rgba8(D::ImageLumaA8(
                ImageBuffer::from_raw(2, 1, vec![10, 50, 200, 255]).unwrap()
            )),
            [10, 10, 10, 50, 200, 200, 200, 255]
        );
        assert_eq!(
            rgba8(D::ImageRgb8(
                ImageBuffer::from_raw(2, 1, vec![1, 2, 3, 4, 5, 6]).unwrap()
            )),
            [1, 2, 3, 255, 4, 5, 6, 255]
        );
        let rgba = vec![1, 2, 3, 4, 250, 251, 252, 253];
        assert_eq!(
            rgba8(D::ImageRgba8(
                ImageBuffer::from_raw(2, 1, rgba.clone()).unwrap()
            )),
            rgba
        );
        // 16-bit samples whose low bytes matter: 0x01F0 is 1.94 8-bit codes.
        assert_eq!(
            rgba16(D::ImageLuma16(
                ImageBuffer::from_raw(3, 1, vec![0x01F0, 0xFFFF, 0x0080]).unwrap()
            )),
            [
                0x01F0, 0x01F0, 0x01F0, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF, 0x80, 0x80, 0x80,
                0xFFFF
            ]
        );
        assert_eq!(
            rgba16(D::ImageLumaA16(
                ImageBuffer::from_raw(2, 1, vec![10, 5000, 60000, 7]).unwrap()
            )),
            [10, 10, 10, 5000, 60000, 60000, 60000, 7]
        );
        assert_eq!(
            rgba16(D::ImageRgb16(
                ImageBuffer::from_raw(2, 1, vec![1, 2, 3, 40000, 50000, 60000]).unwrap()
            )),
            [1, 2, 3, 0xFFFF, 40000, 50000, 60000, 0xFFFF]
        );
        let rgba_wide = vec![1, 2, 3, 4, 65530, 65531, 65532, 65533];
        assert_eq!(
            rgba16(D::ImageRgba16(
                ImageBuffer::from_raw(2, 1, rgba_wide.clone()).unwrap()
            )),
            rgba_wide
        );
        // JPEG is lossy: an even colour comes back within a few steps.
        let even = [200u8, 100, 50].repeat(64);
        let Texels::Rgba8(jpeg) = texels(
            D::ImageRgb8(ImageBuffer::from_raw(8, 8, even).unwrap()),
            ImageFormat::Jpeg,
        ) else {
            panic!("JPEG decoded to 16-bit texels")
        };
        for texel in jpeg.chunks_exact(4) {
            for (got, want) in texel.iter().zip([200u8, 100, 50, 255]) {
                assert!(got.abs_diff(want) <= 4, "JPEG texel {texel:?}");
            }
        }
        assert!(decode_image(b"GIF89a", 1 << 20).is_err());
    }
}
