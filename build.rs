//! Build script: compiles every GLSL kernel in `shaders_glsl/` to SPIR-V, and generates
//! the Rust side of the CPU/GPU interface from the headers in `shaders_glsl/shared/`.
//!
//! The shared headers are the single source of truth for binding numbers, constants and
//! the structs that live in GPU buffers. This script parses them (a deliberately small
//! subset of GLSL: `#define NAME literal` and `struct` blocks of 32-bit members), emits
//! `#[repr(C)]` Pod structs with size/offset assertions, and then checks those offsets
//! against the `Offset` decorations glslang wrote into the compiled SPIR-V. A mismatch is
//! a build error, so the two sides cannot drift apart.

#[path = "src/shader_compiler.rs"]
#[allow(dead_code)]
mod shader_compiler;

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let root = manifest.join("shaders_glsl");
    println!("cargo:rerun-if-changed=shaders_glsl");
    println!("cargo:rerun-if-changed=src/shader_compiler.rs");
    println!("cargo:rerun-if-env-changed=LANTERNA_SHADER_DEBUG_INFO");

    // ---- shared headers → Rust ---------------------------------------------------------
    let layout = match SharedLayout::parse_dir(&root.join("shared")) {
        Ok(l) => l,
        Err(e) => fail(&[e]),
    };
    std::fs::write(out.join("shared_types.rs"), layout.to_rust()).unwrap();

    // ---- kernels → SPIR-V --------------------------------------------------------------
    let kernels = shader_compiler::find_kernels(&root).unwrap_or_default();
    let debug_info = std::env::var_os("LANTERNA_SHADER_DEBUG_INFO").is_some();
    let results: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = kernels
            .iter()
            .map(|k| {
                let root = &root;
                s.spawn(move || shader_compiler::compile_kernel(root, k, debug_info))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });

    let mut errors = Vec::new();
    let mut table = String::from("/// Kernels built into the binary: (name, SPIR-V bytes).\n");
    table.push_str("pub static KERNELS: &[(&str, &[u8])] = &[\n");
    for (kernel, result) in kernels.iter().zip(results) {
        match result {
            Ok(compiled) => {
                for src in &compiled.sources {
                    println!("cargo:rerun-if-changed={}", src.display());
                }
                if let Err(e) = layout.check_spirv(&compiled.spirv) {
                    errors.push(format!("{}: {e}", kernel.display()));
                }
                let name = shader_compiler::kernel_name(kernel);
                let file = out.join(format!("{}.spv", name.replace('/', "__")));
                let bytes: Vec<u8> = compiled
                    .spirv
                    .iter()
                    .flat_map(|w| w.to_le_bytes())
                    .collect();
                std::fs::write(&file, bytes).unwrap();
                writeln!(
                    table,
                    "    ({name:?}, include_bytes!({:?})),",
                    file.display()
                )
                .unwrap();
            }
            Err(e) => {
                for m in &e.messages {
                    let m = m.replace(&format!("{}/", manifest.display()), "");
                    errors.push(m);
                }
            }
        }
    }
    table.push_str("];\n");
    if !errors.is_empty() {
        fail(&errors);
    }
    std::fs::write(out.join("kernels.rs"), table).unwrap();
}

fn fail(errors: &[String]) -> ! {
    for e in errors {
        // One `cargo:warning` per line makes cargo show each `file:line: message`.
        for line in e.lines() {
            println!("cargo:warning={line}");
        }
        eprintln!("{e}");
    }
    eprintln!("shader build failed ({} error(s))", errors.len());
    std::process::exit(1);
}

// ---------------------------------------------------------------------------------------
// Shared header parsing
// ---------------------------------------------------------------------------------------

#[derive(Clone)]
struct Member {
    name: String,
    ty: String,
    array: Option<u32>,
}

struct StructDef {
    name: String,
    file: String,
    members: Vec<Member>,
}

enum Value {
    Int(i64),
    Uint(u64),
    Float(f64),
}

#[derive(Default)]
struct SharedLayout {
    consts: Vec<(String, Value, String)>,
    structs: Vec<StructDef>,
}

/// (Rust type, size in bytes) of a GLSL member type made of 32-bit components.
fn scalar_type(ty: &str) -> Option<(&'static str, u32)> {
    Some(match ty {
        "float" => ("f32", 4),
        "int" => ("i32", 4),
        "uint" => ("u32", 4),
        "vec2" => ("[f32; 2]", 8),
        "vec3" => ("[f32; 3]", 12),
        "vec4" => ("[f32; 4]", 16),
        "ivec2" => ("[i32; 2]", 8),
        "ivec3" => ("[i32; 3]", 12),
        "ivec4" => ("[i32; 4]", 16),
        "uvec2" => ("[u32; 2]", 8),
        "uvec3" => ("[u32; 3]", 12),
        "uvec4" => ("[u32; 4]", 16),
        "mat4" => ("[[f32; 4]; 4]", 64),
        "mat3x4" => ("[[f32; 4]; 3]", 48),
        "mat4x3" => ("[[f32; 3]; 4]", 48),
        _ => return None,
    })
}

impl SharedLayout {
    fn parse_dir(dir: &Path) -> Result<Self, String> {
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "h"))
            .collect();
        files.sort();
        let mut layout = SharedLayout::default();
        for f in files {
            let text = std::fs::read_to_string(&f).map_err(|e| format!("{}: {e}", f.display()))?;
            let short = format!(
                "shaders_glsl/shared/{}",
                f.file_name().unwrap().to_string_lossy()
            );
            layout.parse_file(&short, &text)?;
        }
        Ok(layout)
    }

    fn const_value(&self, name: &str) -> Option<u32> {
        self.consts
            .iter()
            .find(|c| c.0 == name)
            .and_then(|c| match c.1 {
                Value::Int(v) => u32::try_from(v).ok(),
                Value::Uint(v) => u32::try_from(v).ok(),
                Value::Float(_) => None,
            })
    }

    fn parse_file(&mut self, file: &str, text: &str) -> Result<(), String> {
        let mut current: Option<StructDef> = None;
        for (i, raw) in text.lines().enumerate() {
            let at = |msg: &str| format!("{file}:{}: {msg}", i + 1);
            let line = raw.split("//").next().unwrap().trim();
            if line.is_empty() {
                continue;
            }
            if let Some(s) = current.as_mut() {
                if line == "};" {
                    self.structs.push(current.take().unwrap());
                    continue;
                }
                let decl = line
                    .strip_suffix(';')
                    .ok_or_else(|| at("expected `type name;` or `};`"))?;
                let mut parts = decl.split_whitespace();
                let (ty, name) = match (parts.next(), parts.next(), parts.next()) {
                    (Some(t), Some(n), None) => (t, n),
                    _ => return Err(at("expected `type name;`")),
                };
                let (name, array) = match name.split_once('[') {
                    Some((n, rest)) => {
                        let len = rest.strip_suffix(']').ok_or_else(|| at("bad array"))?;
                        let len = len
                            .parse::<u32>()
                            .ok()
                            .or_else(|| self.const_value(len))
                            .ok_or_else(|| at("array length must be a literal or a #define"))?;
                        (n, Some(len))
                    }
                    None => (name, None),
                };
                if scalar_type(ty).is_none() && !self.structs.iter().any(|s| s.name == ty) {
                    return Err(at(&format!(
                        "type `{ty}` is not allowed in shared structs (32-bit scalars, vectors, \
                         mat4/mat3x4/mat4x3, or a struct defined earlier)"
                    )));
                }
                s.members.push(Member {
                    name: name.to_string(),
                    ty: ty.to_string(),
                    array,
                });
                continue;
            }
            if let Some(rest) = line.strip_prefix("#define") {
                let mut parts = rest.split_whitespace();
                let name = parts.next().ok_or_else(|| at("empty #define"))?;
                let Some(value) = parts.next() else { continue }; // include guard
                let value = parse_literal(value)
                    .ok_or_else(|| at("shared #define values must be integer or float literals"))?;
                self.consts
                    .push((name.to_string(), value, file.to_string()));
            } else if line.starts_with("#ifndef") || line.starts_with("#endif") {
            } else if let Some(rest) = line.strip_prefix("struct") {
                let name = rest
                    .trim()
                    .strip_suffix('{')
                    .ok_or_else(|| at("expected `struct Name {`"))?;
                current = Some(StructDef {
                    name: name.trim().to_string(),
                    file: file.to_string(),
                    members: Vec::new(),
                });
            } else {
                return Err(at(
                    "shared headers hold only #define constants and struct blocks",
                ));
            }
        }
        if current.is_some() {
            return Err(format!("{file}: unterminated struct"));
        }
        Ok(())
    }

    fn size_of(&self, ty: &str) -> u32 {
        if let Some((_, s)) = scalar_type(ty) {
            return s;
        }
        let s = self.structs.iter().find(|s| s.name == ty).unwrap();
        self.struct_offsets(s).1
    }

    /// Scalar block layout with 32-bit components only: members are packed back to back.
    fn struct_offsets(&self, s: &StructDef) -> (Vec<u32>, u32) {
        let mut offsets = Vec::new();
        let mut at = 0;
        for m in &s.members {
            offsets.push(at);
            at += self.size_of(&m.ty) * m.array.unwrap_or(1);
        }
        (offsets, at)
    }

    fn to_rust(&self) -> String {
        let mut r =
            String::from("// Generated by build.rs from shaders_glsl/shared/*.h. Do not edit.\n\n");
        for (name, value, file) in &self.consts {
            let (ty, v) = match value {
                Value::Int(v) if *v < 0 => ("i32", v.to_string()),
                Value::Int(v) => ("u32", v.to_string()),
                Value::Uint(v) => ("u32", v.to_string()),
                Value::Float(v) => ("f32", format!("{v:?}")),
            };
            writeln!(r, "/// From `{file}`.\npub const {name}: {ty} = {v};").unwrap();
        }
        for s in &self.structs {
            let (offsets, size) = self.struct_offsets(s);
            writeln!(
                r,
                "\n/// Mirror of `struct {}` in `{}` (scalar layout).",
                s.name, s.file
            )
            .unwrap();
            r.push_str("#[repr(C)]\n#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]\n");
            writeln!(r, "pub struct {} {{", s.name).unwrap();
            for m in &s.members {
                let base = scalar_type(&m.ty)
                    .map(|t| t.0.to_string())
                    .unwrap_or(m.ty.clone());
                let ty = match m.array {
                    Some(n) => format!("[{base}; {n}]"),
                    None => base,
                };
                writeln!(r, "    pub {}: {ty},", m.name).unwrap();
            }
            r.push_str("}\n");
            writeln!(
                r,
                "impl Default for {} {{ fn default() -> Self {{ bytemuck::Zeroable::zeroed() }} }}",
                s.name
            )
            .unwrap();
            writeln!(
                r,
                "const _: () = assert!(core::mem::size_of::<{}>() == {size});",
                s.name
            )
            .unwrap();
            for (m, off) in s.members.iter().zip(&offsets) {
                writeln!(
                    r,
                    "const _: () = assert!(core::mem::offset_of!({}, {}) == {off});",
                    s.name, m.name
                )
                .unwrap();
            }
        }
        r
    }

    /// Compare member offsets of every shared struct that the kernel uses with the
    /// `Offset` decorations in its SPIR-V.
    fn check_spirv(&self, words: &[u32]) -> Result<(), String> {
        let refl = SpirvReflection::parse(words);
        let mut problems = Vec::new();
        for s in &self.structs {
            let (offsets, _) = self.struct_offsets(s);
            for ty in refl.types_named(&s.name) {
                for (index, (m, off)) in s.members.iter().zip(&offsets).enumerate() {
                    let Some(name) = refl.member_names.get(&(ty, index as u32)) else {
                        continue;
                    };
                    if name != &m.name {
                        problems.push(format!(
                            "struct {} member {index} is `{name}` in SPIR-V but `{}` in the header",
                            s.name, m.name
                        ));
                    }
                    if let Some(&spv) = refl.member_offsets.get(&(ty, index as u32)) {
                        if spv != *off {
                            problems.push(format!(
                                "struct {}.{} at offset {spv} in SPIR-V but {off} on the CPU \
                                 (is the buffer declared with `layout(scalar)`?)",
                                s.name, m.name
                            ));
                        }
                    }
                }
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems.join("; "))
        }
    }
}

fn parse_literal(v: &str) -> Option<Value> {
    if let Some(h) = v.strip_prefix("0x") {
        return u64::from_str_radix(h.trim_end_matches('u'), 16)
            .ok()
            .map(Value::Uint);
    }
    if let Some(u) = v.strip_suffix('u') {
        return u.parse().ok().map(Value::Uint);
    }
    if let Ok(i) = v.parse::<i64>() {
        return Some(Value::Int(i));
    }
    v.trim_end_matches('f')
        .parse::<f64>()
        .ok()
        .filter(|_| v.contains('.') || v.contains('e'))
        .map(Value::Float)
}

/// Just enough SPIR-V parsing to read struct names and member offsets.
#[derive(Default)]
struct SpirvReflection {
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    member_offsets: BTreeMap<(u32, u32), u32>,
}

impl SpirvReflection {
    fn parse(words: &[u32]) -> Self {
        let mut r = SpirvReflection::default();
        let mut i = 5; // header
        while i < words.len() {
            let count = (words[i] >> 16) as usize;
            let op = words[i] & 0xffff;
            if count == 0 || i + count > words.len() {
                break;
            }
            let ops = &words[i + 1..i + count];
            match op {
                5 if ops.len() >= 2 => {
                    r.names.insert(ops[0], spirv_string(&ops[1..]));
                }
                6 if ops.len() >= 3 => {
                    r.member_names
                        .insert((ops[0], ops[1]), spirv_string(&ops[2..]));
                }
                72 if ops.len() >= 4 && ops[2] == 35 => {
                    r.member_offsets.insert((ops[0], ops[1]), ops[3]);
                }
                _ => {}
            }
            i += count;
        }
        r
    }

    fn types_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = u32> + 'a {
        self.names
            .iter()
            .filter(move |(_, n)| n.as_str() == name)
            .map(|(id, _)| *id)
    }
}

fn spirv_string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}
