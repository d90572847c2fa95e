//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views stored
//! compressed by meshoptimizer's codecs (gltfpack's `-c`, `-cc`, `-ce khr`), decoded on
//! load into the buffer views' own bytes. Written from the extensions' specifications
//! (Appendix A, the bitstreams; Appendix B, the filters): attribute streams (headers 0xa0
//! and 0xa1), triangle lists (0xe1), index sequences (0xd1) and the octahedral,
//! quaternion, exponential and colour filters. Every read is
//! bounds-checked, so a damaged stream is an error naming what is wrong, never a panic.

/// The extensions' names: the vendor one and its ratified successor, which adds the
/// version 1 attribute codec and the colour filter.
pub(super) const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// How a buffer view is compressed (the extension's JSON, checked).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    /// `KHR_meshopt_compression`'s YCoCg colours.
    Color,
}

/// Decodes `data` (one compressed buffer view) into `out`, `count` elements of `stride`
/// bytes, then applies `filter`.
pub(super) fn decode(
    out: &mut [u8],
    count: usize,
    stride: usize,
    mode: Mode,
    filter: Filter,
    data: &[u8],
) -> Result<(), String> {
    if out.len() != count * stride {
        return Err(format!(
            "{count} elements of {stride} bytes do not fill its {} bytes",
            out.len()
        ));
    }
    match mode {
        Mode::Attributes => {
            if stride == 0 || stride % 4 != 0 || stride > 256 {
                return Err(format!(
                    "ATTRIBUTES byteStride {stride} is not a multiple of 4 up to 256"
                ));
            }
            decode_attributes(out, count, stride, data)?;
        }
        Mode::Triangles | Mode::Indices => {
            if stride != 2 && stride != 4 {
                return Err(format!("{mode:?} byteStride {stride} is not 2 or 4"));
            }
            if filter != Filter::None {
                return Err(format!("{mode:?} cannot have the filter {filter:?}"));
            }
            if mode == Mode::Triangles {
                decode_triangles(out, count, stride, data)?;
            } else {
                decode_indices(out, count, stride, data)?;
            }
        }
    }
    match filter {
        Filter::None => Ok(()),
        Filter::Octahedral => octahedral(out, stride),
        Filter::Quaternion => quaternion(out, stride),
        Filter::Exponential => exponential(out, stride),
        Filter::Color => color(out, stride),
    }
}

/// A cursor over a stream that reports running off its end.
struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    end: usize,
}

impl Reader<'_> {
    fn byte(&mut self) -> Result<u8, String> {
        if self.pos >= self.end {
            return Err("the stream ends early".into());
        }
        self.pos += 1;
        Ok(self.data[self.pos - 1])
    }

    fn bytes(&mut self, n: usize) -> Result<&[u8], String> {
        if self.end - self.pos < n {
            return Err("the stream ends early".into());
        }
        self.pos += n;
        Ok(&self.data[self.pos - n..self.pos])
    }

    /// Unsigned LEB128, at most 32 bits.
    fn varint(&mut self) -> Result<u32, String> {
        let mut v: u32 = 0;
        for shift in (0..35).step_by(7) {
            let b = self.byte()?;
            v |= u32::from(b & 0x7f).checked_shl(shift).unwrap_or(0);
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err("a varint is longer than 32 bits".into())
    }
}

fn unzigzag8(v: u8) -> u8 {
    if v & 1 != 0 {
        !(v >> 1)
    } else {
        v >> 1
    }
}

/// Mode 0: per-byte deltas, deinterleaved, in blocks of groups of 16 elements; version
/// 0 (header 0xa0, `EXT_meshopt_compression`) or version 1 (0xa1,
/// `KHR_meshopt_compression`: per-byte control modes, 1-bit deltas, literal bytes, and
/// per-channel 16-bit and rotated-XOR 32-bit deltas).
fn decode_attributes(
    out: &mut [u8],
    count: usize,
    stride: usize,
    data: &[u8],
) -> Result<(), String> {
    let v1 = match data.first() {
        Some(0xa0) => false,
        Some(0xa1) => true,
        other => {
            return Err(format!(
                "ATTRIBUTES stream starts with {:#04x}, not 0xa0 or 0xa1",
                other.copied().unwrap_or(0)
            ))
        }
    };
    let channel_count = stride / 4;
    let tail = stride + if v1 { channel_count } else { 0 };
    let padded = tail.max(if v1 { 24 } else { 32 });
    if data.len() < 1 + padded {
        return Err("ATTRIBUTES stream is shorter than its tail".into());
    }
    let tail_at = data.len() - tail;
    let mut last: Vec<u8> = data[tail_at..tail_at + stride].to_vec();
    let channels: Vec<u8> = if v1 {
        data[tail_at + stride..].to_vec()
    } else {
        vec![0; channel_count]
    };
    if let Some(c) = channels
        .iter()
        .find(|&&c| c & 15 > 2 || (c & 15 < 2 && c >> 4 != 0))
    {
        return Err(format!("ATTRIBUTES channel mode {c:#04x} is invalid"));
    }
    let mut r = Reader {
        data,
        pos: 1,
        end: data.len() - padded,
    };
    // Bits per delta of a group's 2-bit header: version 0, then version 1 under
    // control modes 0 and 1 (8: a raw byte per delta).
    const WIDTHS: [[u32; 4]; 3] = [[0, 2, 4, 8], [0, 1, 2, 4], [1, 2, 4, 8]];
    let block_max = ((8192 / stride) & !15).min(256);
    let mut deltas = vec![0u8; stride * 256];
    let mut done = 0;
    while done < count {
        let elements = (count - done).min(block_max);
        let groups = elements.div_ceil(16);
        let control = if v1 {
            r.bytes(channel_count)?.to_vec()
        } else {
            Vec::new()
        };
        for k in 0..stride {
            let d = &mut deltas[256 * k..256 * k + 256];
            let ctrl = if v1 {
                (control[k / 4] >> (2 * (k % 4))) & 3
            } else {
                0
            };
            match ctrl {
                2 => {
                    d.fill(0);
                    continue;
                }
                3 => {
                    d[..elements].copy_from_slice(r.bytes(elements)?);
                    continue;
                }
                _ => {}
            }
            let widths = WIDTHS[if v1 { 1 + ctrl as usize } else { 0 }];
            let header = r.bytes(groups.div_ceil(4))?.to_vec();
            for g in 0..groups {
                let d = &mut d[16 * g..16 * g + 16];
                match widths[((header[g / 4] >> (2 * (g % 4))) & 3) as usize] {
                    0 => d.fill(0),
                    8 => d.copy_from_slice(r.bytes(16)?),
                    bits => {
                        let packed = r.bytes(2 * bits as usize)?.to_vec();
                        let sentinel = (1u8 << bits) - 1;
                        let per_byte = (8 / bits) as usize;
                        for (i, d) in d.iter_mut().enumerate() {
                            // 1-bit deltas from the low bit up, wider ones from the high.
                            let slot = (i % per_byte) as u32;
                            let shift = if bits == 1 {
                                slot
                            } else {
                                8 - bits * (1 + slot)
                            };
                            let v = (packed[i / per_byte] >> shift) & sentinel;
                            *d = if v == sentinel { r.byte()? } else { v };
                        }
                    }
                }
            }
        }
        let delta = |k: usize, i: usize| deltas[256 * k + i];
        for i in 0..elements {
            let element = &mut out[(done + i) * stride..(done + i + 1) * stride];
            for (c, &mode) in channels.iter().enumerate() {
                let at = 4 * c;
                match mode & 15 {
                    0 => {
                        for (k, v) in last.iter_mut().enumerate().skip(at).take(4) {
                            *v = v.wrapping_add(unzigzag8(delta(k, i)));
                        }
                    }
                    1 => {
                        for k in [at, at + 2] {
                            let d = u16::from_le_bytes([delta(k, i), delta(k + 1, i)]);
                            let d = if d & 1 != 0 { !(d >> 1) } else { d >> 1 };
                            let v = u16::from_le_bytes([last[k], last[k + 1]]).wrapping_add(d);
                            last[k..k + 2].copy_from_slice(&v.to_le_bytes());
                        }
                    }
                    _ => {
                        let d = u32::from_le_bytes([0, 1, 2, 3].map(|b| delta(at + b, i)));
                        let p = u32::from_le_bytes(last[at..at + 4].try_into().unwrap());
                        let v = p ^ d.rotate_right(u32::from(mode >> 4));
                        last[at..at + 4].copy_from_slice(&v.to_le_bytes());
                    }
                }
            }
            element.copy_from_slice(&last);
        }
        done += elements;
    }
    if r.pos != r.end {
        return Err(format!(
            "ATTRIBUTES stream has {} bytes beyond its blocks",
            r.end - r.pos
        ));
    }
    Ok(())
}

fn write_index(out: &mut [u8], i: usize, stride: usize, v: u32) {
    if stride == 2 {
        out[2 * i..2 * i + 2].copy_from_slice(&(v as u16).to_le_bytes());
    } else {
        out[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
}

/// Mode 1: triangle lists through an edge FIFO and a vertex FIFO.
fn decode_triangles(
    out: &mut [u8],
    count: usize,
    stride: usize,
    data: &[u8],
) -> Result<(), String> {
    if count % 3 != 0 {
        return Err(format!("TRIANGLES count {count} is not a multiple of 3"));
    }
    if data.first() != Some(&0xe1) {
        return Err(format!(
            "TRIANGLES stream starts with {:#04x}, not 0xe1",
            data.first().copied().unwrap_or(0)
        ));
    }
    let triangles = count / 3;
    if data.len() < 1 + triangles + 16 {
        return Err("TRIANGLES stream is shorter than its codes and table".into());
    }
    let codes = &data[1..1 + triangles];
    let aux = &data[data.len() - 16..];
    let mut r = Reader {
        data,
        pos: 1 + triangles,
        end: data.len() - 16,
    };
    let mut edges = [[0u32; 2]; 16];
    let mut edge_at = 0usize;
    let mut verts = [0u32; 16];
    let mut vert_at = 0usize;
    let (mut next, mut last) = (0u32, 0u32);
    // The k-th most recent entry (0: the newest).
    let edge = |edges: &[[u32; 2]; 16], at: usize, k: usize| edges[(at + 15 - k) & 15];
    let vert = |verts: &[u32; 16], at: usize, k: usize| verts[(at + 15 - k) & 15];
    let index = |r: &mut Reader<'_>, last: &mut u32| -> Result<u32, String> {
        let v = r.varint()?;
        let delta = if v & 1 != 0 { !(v >> 1) } else { v >> 1 };
        *last = last.wrapping_add(delta);
        Ok(*last)
    };
    for (t, &code) in codes.iter().enumerate() {
        let (hi, lo) = ((code >> 4) as usize, (code & 15) as usize);
        let (a, b, c);
        if hi < 15 {
            [a, b] = edge(&edges, edge_at, hi);
            c = match lo {
                0 => {
                    next = next.wrapping_add(1);
                    next.wrapping_sub(1)
                }
                1..=12 => vert(&verts, vert_at, lo),
                13 | 14 => {
                    last = if lo == 13 {
                        last.wrapping_sub(1)
                    } else {
                        last.wrapping_add(1)
                    };
                    last
                }
                _ => index(&mut r, &mut last)?,
            };
            for e in [[c, b], [a, c]] {
                edges[edge_at] = e;
                edge_at = (edge_at + 1) & 15;
            }
            if !(1..=12).contains(&lo) {
                verts[vert_at] = c;
                vert_at = (vert_at + 1) & 15;
            }
        } else {
            let (zw, explicit) = if lo < 14 {
                (aux[lo], false)
            } else {
                let zw = r.byte()?;
                if zw == 0 {
                    next = 0;
                }
                (zw, true)
            };
            let (z, w) = ((zw >> 4) as usize, (zw & 15) as usize);
            let mut fresh = || {
                next = next.wrapping_add(1);
                next.wrapping_sub(1)
            };
            a = if explicit && lo == 15 {
                index(&mut r, &mut last)?
            } else {
                fresh()
            };
            let mut other = |k: usize, r: &mut Reader<'_>, fresh: &mut dyn FnMut() -> u32| {
                Ok::<u32, String>(match k {
                    0 => fresh(),
                    15 if explicit => index(r, &mut last)?,
                    _ => vert(&verts, vert_at, k - 1),
                })
            };
            b = other(z, &mut r, &mut fresh)?;
            c = other(w, &mut r, &mut fresh)?;
            for e in [[b, a], [c, b], [a, c]] {
                edges[edge_at] = e;
                edge_at = (edge_at + 1) & 15;
            }
            let pushed = |k: usize| k == 0 || (explicit && k == 15);
            for (v, push) in [(a, true), (b, pushed(z)), (c, pushed(w))] {
                if push {
                    verts[vert_at] = v;
                    vert_at = (vert_at + 1) & 15;
                }
            }
        }
        for (j, v) in [a, b, c].into_iter().enumerate() {
            write_index(out, 3 * t + j, stride, v);
        }
    }
    if r.pos != r.end {
        return Err(format!(
            "TRIANGLES stream has {} bytes beyond its triangles",
            r.end - r.pos
        ));
    }
    Ok(())
}

/// Mode 2: index deltas against two baselines.
fn decode_indices(out: &mut [u8], count: usize, stride: usize, data: &[u8]) -> Result<(), String> {
    if data.first() != Some(&0xd1) {
        return Err(format!(
            "INDICES stream starts with {:#04x}, not 0xd1",
            data.first().copied().unwrap_or(0)
        ));
    }
    if data.len() < 1 + 4 {
        return Err("INDICES stream is shorter than its tail".into());
    }
    let mut r = Reader {
        data,
        pos: 1,
        end: data.len() - 4,
    };
    let mut last = [0u32; 2];
    for i in 0..count {
        let v = r.varint()?;
        let base = (v & 1) as usize;
        let delta = if v & 2 != 0 { !(v >> 2) } else { v >> 2 };
        last[base] = last[base].wrapping_add(delta);
        write_index(out, i, stride, last[base]);
    }
    if r.pos != r.end {
        return Err(format!(
            "INDICES stream has {} bytes beyond its indices",
            r.end - r.pos
        ));
    }
    Ok(())
}

/// Reads component `i` of a 4-component element of 8- or 16-bit signed integers.
fn component(e: &[u8], i: usize, wide: bool) -> f32 {
    if wide {
        f32::from(i16::from_le_bytes([e[2 * i], e[2 * i + 1]]))
    } else {
        f32::from(e[i] as i8)
    }
}

fn set_component(e: &mut [u8], i: usize, wide: bool, v: f32) {
    if wide {
        e[2 * i..2 * i + 2].copy_from_slice(&(v.round() as i16).to_le_bytes());
    } else {
        e[i] = (v.round() as i8) as u8;
    }
}

/// Whether a filter of four components per element (`name`) has 16-bit components
/// (stride 8) rather than 8-bit ones (stride 4).
fn sixteen_bit_components(stride: usize, name: &str) -> Result<bool, String> {
    match stride {
        4 => Ok(false),
        8 => Ok(true),
        _ => Err(format!("{name} byteStride {stride} is not 4 or 8")),
    }
}

/// Filter 1: octahedral unit vectors, 4 × 8 or 4 × 16 bits, the third component K bits' 1.
fn octahedral(out: &mut [u8], stride: usize) -> Result<(), String> {
    let wide = sixteen_bit_components(stride, "OCTAHEDRAL")?;
    let max = if wide { 32767.0 } else { 127.0 };
    for e in out.chunks_exact_mut(stride) {
        let one = component(e, 2, wide);
        if one <= 0.0 {
            return Err(format!("OCTAHEDRAL element encodes 1.0 as {one}"));
        }
        let (mut x, mut y) = (component(e, 0, wide) / one, component(e, 1, wide) / one);
        let z = 1.0 - x.abs() - y.abs();
        let t = z.min(0.0);
        x -= t.copysign(x);
        y -= t.copysign(y);
        let len = (x * x + y * y + z * z).sqrt();
        for (i, v) in [x, y, z].into_iter().enumerate() {
            set_component(e, i, wide, v / len * max);
        }
    }
    Ok(())
}

/// Filter 2: quaternions as three components and the largest one's index, 4 × 16 bits.
fn quaternion(out: &mut [u8], stride: usize) -> Result<(), String> {
    if stride != 8 {
        return Err(format!("QUATERNION byteStride {stride} is not 8"));
    }
    let range = std::f32::consts::FRAC_1_SQRT_2;
    for e in out.chunks_exact_mut(8) {
        let last = i16::from_le_bytes([e[6], e[7]]);
        let one = f32::from(last | 3);
        let xyz = [0, 1, 2].map(|i| component(e, i, true) / one * range);
        let w = (1.0 - xyz.iter().map(|c| c * c).sum::<f32>())
            .max(0.0)
            .sqrt();
        let largest = (last & 3) as usize;
        for (k, v) in xyz.into_iter().enumerate() {
            set_component(e, (largest + 1 + k) % 4, true, v * 32767.0);
        }
        set_component(e, largest, true, w * 32767.0);
    }
    Ok(())
}

/// Filter 3: 32-bit floats as an 8-bit exponent and a 24-bit mantissa.
fn exponential(out: &mut [u8], stride: usize) -> Result<(), String> {
    if stride % 4 != 0 {
        return Err(format!(
            "EXPONENTIAL byteStride {stride} is not a multiple of 4"
        ));
    }
    for v in out.chunks_exact_mut(4) {
        let input = i32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        let e = input >> 24;
        let m = (input << 8) >> 8;
        let value = (m as f32) * 2f32.powi(e.clamp(-100, 100));
        v.copy_from_slice(&value.to_le_bytes());
    }
    Ok(())
}

/// Filter 4 (`KHR_meshopt_compression`): YCoCg colours, 4 × 8 or 4 × 16 bits, K bits
/// found from the alpha's top bit; output unsigned normalised RGBA.
fn color(out: &mut [u8], stride: usize) -> Result<(), String> {
    let wide = sixteen_bit_components(stride, "COLOR")?;
    let max = if wide { 65535.0 } else { 255.0 };
    for e in out.chunks_exact_mut(stride) {
        let unsigned = |i: usize| -> i32 {
            if wide {
                i32::from(u16::from_le_bytes([e[2 * i], e[2 * i + 1]]))
            } else {
                i32::from(e[i])
            }
        };
        let (y, co, cg) = (
            unsigned(0),
            component(e, 1, wide) as i32,
            component(e, 2, wide) as i32,
        );
        let alpha = unsigned(3);
        if alpha == 0 {
            return Err("COLOR element has no scale bit in its alpha".into());
        }
        let scale = (1i32 << (32 - alpha.leading_zeros())) - 1;
        let a = alpha & (scale >> 1);
        let a = (a << 1) | (a & 1);
        let ss = max / scale as f32;
        for (i, v) in [y + co - cg, y + cg, y - co - cg, a]
            .into_iter()
            .enumerate()
        {
            let v = (v as f32 * ss).round().clamp(0.0, max);
            if wide {
                e[2 * i..2 * i + 2].copy_from_slice(&(v as u16).to_le_bytes());
            } else {
                e[i] = v as u8;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use base64::Engine as _;

    struct Case {
        name: String,
        count: usize,
        stride: usize,
        mode: Mode,
        filter: Filter,
        encoded: Vec<u8>,
        decoded: Vec<u8>,
    }

    /// Streams written by meshoptimizer's own encoder and decoded by its decoder
    /// (`tests/data/meshopt/make_fixtures.mjs`).
    fn cases() -> Vec<Case> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/meshopt/fixtures.json"
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let b64 = |v: &serde_json::Value| {
            base64::engine::general_purpose::STANDARD
                .decode(v.as_str().unwrap())
                .unwrap()
        };
        json["cases"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| Case {
                name: c["name"].as_str().unwrap().into(),
                count: c["count"].as_u64().unwrap() as usize,
                stride: c["stride"].as_u64().unwrap() as usize,
                mode: match c["mode"].as_str().unwrap() {
                    "ATTRIBUTES" => Mode::Attributes,
                    "TRIANGLES" => Mode::Triangles,
                    _ => Mode::Indices,
                },
                filter: match c["filter"].as_str().unwrap() {
                    "OCTAHEDRAL" => Filter::Octahedral,
                    "QUATERNION" => Filter::Quaternion,
                    "EXPONENTIAL" => Filter::Exponential,
                    "COLOR" => Filter::Color,
                    _ => Filter::None,
                },
                encoded: b64(&c["encoded"]),
                decoded: b64(&c["decoded"]),
            })
            .collect()
    }

    /// Every fixture decodes to the reference decoder's bytes: exactly, but for the
    /// octahedral and quaternion filters' integer outputs, which the extension specifies
    /// to one unit in the last place.
    #[test]
    fn decodes_what_meshoptimizer_encodes() {
        let cases = cases();
        assert!(cases.len() >= 40);
        for c in &cases {
            let mut out = vec![0u8; c.count * c.stride];
            decode(&mut out, c.count, c.stride, c.mode, c.filter, &c.encoded)
                .unwrap_or_else(|e| panic!("{}: {e}", c.name));
            match c.filter {
                Filter::Octahedral | Filter::Quaternion | Filter::Color => {
                    let wide = c.stride == 8;
                    let signed = c.filter != Filter::Color;
                    let values = |b: &[u8]| -> Vec<i32> {
                        match (wide, signed) {
                            (true, true) => b
                                .chunks_exact(2)
                                .map(|p| i32::from(i16::from_le_bytes([p[0], p[1]])))
                                .collect(),
                            (true, false) => b
                                .chunks_exact(2)
                                .map(|p| i32::from(u16::from_le_bytes([p[0], p[1]])))
                                .collect(),
                            (false, true) => b.iter().map(|&v| i32::from(v as i8)).collect(),
                            (false, false) => b.iter().map(|&v| i32::from(v)).collect(),
                        }
                    };
                    for (i, (a, b)) in values(&out).iter().zip(values(&c.decoded)).enumerate() {
                        assert!(
                            (a - b).abs() <= 1,
                            "{}: component {i}: {a} against {b}",
                            c.name
                        );
                    }
                }
                _ => assert!(out == c.decoded, "{}: decoded bytes differ", c.name),
            }
        }
    }

    /// A damaged stream is an error, never a panic: every fixture cut short at every
    /// length, and with each byte of its first 64 flipped.
    #[test]
    fn damaged_streams_are_errors() {
        for c in cases().iter().filter(|c| c.encoded.len() < 600) {
            let mut out = vec![0u8; c.count * c.stride];
            for len in 0..c.encoded.len() {
                let cut = &c.encoded[..len];
                let r = std::panic::catch_unwind(|| {
                    let mut out = vec![0u8; c.count * c.stride];
                    decode(&mut out, c.count, c.stride, c.mode, c.filter, cut).map(|_| ())
                });
                assert!(r.is_ok(), "{}: cut to {len} bytes panicked", c.name);
            }
            for i in 0..c.encoded.len().min(64) {
                let mut bad = c.encoded.clone();
                bad[i] ^= 0x5a;
                let _ = decode(&mut out, c.count, c.stride, c.mode, c.filter, &bad);
            }
        }
    }
}
