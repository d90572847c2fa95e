//! Scene generators: `lanterna scene generate KIND` writes procedurally built glTF 2.0
//! scenes that stand in for content that cannot be shipped (the paper's Bistro) and
//! provide the analytic scenes the tests need. Every kind is a pure function of its
//! options and seed, so the same options give byte-identical files; each file records its
//! kind, resolved options and any analytic parameters in `asset.extras.lanterna`.
//!
//! The kinds live one per file (`street`, `bistro_night`, `cornell`, `furnace`,
//! `analytic`, `gap`, `alpha_test`, `conformance`); `writer` turns meshes, materials and nodes into glTF JSON + `.bin` +
//! PNG, `mesh` builds geometry, `textures` paints the textures and `rng` is the seeded
//! random stream they all draw from.

mod alpha_test;
mod analytic;
mod bistro_lamps;
mod bistro_night;
mod conformance;
mod cornell;
mod furnace;
mod gap;
pub mod mesh;
pub mod rng;
mod street;
mod street_facade;
mod street_props;
pub mod textures;
pub mod writer;

use serde_json::{json, Map, Value};
use std::fmt;
use std::path::{Path, PathBuf};

/// The kinds of scene the generator can write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The Bistro stand-in: a night street lit by hundreds (up to tens of thousands) of lights.
    Street,
    /// A Cornell box lit by small coloured emissive quads, some behind a blocker.
    CornellLights,
    /// A closed box (or sphere) that reflects with albedo ρ and emits Le inward.
    Furnace,
    /// A Lambertian plane under a square emitter: closed-form irradiance under its centre.
    PlaneQuad,
    /// A Lambertian plane under a point (or spot) light: radiance ρ/π·I/h² under it.
    PlanePoint,
    /// Two rooms joined by a narrow doorway; the only emitter is in the room not seen.
    Gap,
    /// An alpha-masked checkerboard quad in front of an emitter.
    AlphaTest,
    /// Lamps on, near and inside walls and ledges (the conformance suite).
    Sconces,
    /// Point and spot lights centimetres from surfaces (the conformance suite).
    PunctualNear,
    /// A lantern: a lamp inside an alpha-masked lattice cage (the conformance suite).
    AlphaLights,
    /// A night square with Bistro's character: lanterns, café interiors seen through
    /// openings, an arcade with cove lights, string lights; most light arrives indirectly.
    BistroNight,
}

impl Kind {
    pub const ALL: [Kind; 11] = [
        Kind::Street,
        Kind::CornellLights,
        Kind::Furnace,
        Kind::PlaneQuad,
        Kind::PlanePoint,
        Kind::Gap,
        Kind::AlphaTest,
        Kind::Sconces,
        Kind::PunctualNear,
        Kind::AlphaLights,
        Kind::BistroNight,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::Street => "street",
            Kind::CornellLights => "cornell-lights",
            Kind::Furnace => "furnace",
            Kind::PlaneQuad => "plane-quad",
            Kind::PlanePoint => "plane-point",
            Kind::Gap => "gap",
            Kind::AlphaTest => "alpha-test",
            Kind::Sconces => "sconces",
            Kind::PunctualNear => "punctual-near",
            Kind::AlphaLights => "alpha-lights",
            Kind::BistroNight => "bistro-night",
        }
    }

    pub fn from_name(name: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The options (by their CLI names) that this kind accepts besides `seed` and `aspect`.
    fn accepted(self) -> &'static [&'static str] {
        match self {
            Kind::Street => &["lamps"],
            Kind::CornellLights => &["lights"],
            Kind::Furnace => &["albedo", "emission", "shape"],
            Kind::PlaneQuad => &["albedo", "emission", "height", "size"],
            Kind::PlanePoint => &["albedo", "intensity", "height", "spot"],
            Kind::Gap => &["albedo", "emission"],
            Kind::AlphaTest => &["emission"],
            Kind::Sconces | Kind::AlphaLights => &[],
            Kind::PunctualNear => &["intensity"],
            Kind::BistroNight => &["detail", "glass"],
        }
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The furnace's enclosure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Box,
    Sphere,
}

/// Generator options. `None` means the kind's default; an option a kind does not use is
/// an error rather than silently ignored.
#[derive(Clone, Debug)]
pub struct Options {
    pub seed: u64,
    /// Camera aspect ratio (width / height).
    pub aspect: Option<f32>,
    /// `street`: number of emissive light models.
    pub lamps: Option<u32>,
    /// `cornell-lights`: number of emissive quads.
    pub lights: Option<u32>,
    /// `bistro-night`: scale of the square (its area grows N×; 1 is the shipped scene).
    pub detail: Option<u32>,
    /// Lambertian albedo of the main surface.
    pub albedo: Option<f32>,
    /// Emitted radiance of the main emitter.
    pub emission: Option<f32>,
    /// `plane-quad`/`plane-point`: height of the light above the plane (m).
    pub height: Option<f32>,
    /// `plane-quad`: side of the emitting square (m).
    pub size: Option<f32>,
    /// `plane-point`: radiant intensity of the light (per steradian).
    pub intensity: Option<f32>,
    /// `plane-point`: a spot light pointing down instead of a point light.
    pub spot: bool,
    /// `furnace`: box or sphere.
    pub shape: Option<Shape>,
    /// Every kind: translate the whole scene, cameras and lights included (precision
    /// tests far from the origin).
    pub offset: Option<[f32; 3]>,
    /// Every kind: every material Lambertian and opaque (an exactly exportable variant),
    /// except thin glass, which stays but becomes smooth and non-reflecting (exact too).
    pub matte: bool,
    /// `bistro-night`: the café wind screens of thin transmitting glass
    /// (`KHR_materials_transmission`) instead of opaque glossy panels.
    pub glass: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            seed: 1,
            aspect: None,
            lamps: None,
            lights: None,
            detail: None,
            albedo: None,
            emission: None,
            height: None,
            size: None,
            intensity: None,
            spot: false,
            shape: None,
            offset: None,
            matte: false,
            glass: false,
        }
    }
}

impl Options {
    fn given(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        let flags = [
            ("lamps", self.lamps.is_some()),
            ("lights", self.lights.is_some()),
            ("detail", self.detail.is_some()),
            ("albedo", self.albedo.is_some()),
            ("emission", self.emission.is_some()),
            ("height", self.height.is_some()),
            ("size", self.size.is_some()),
            ("intensity", self.intensity.is_some()),
            ("spot", self.spot),
            ("shape", self.shape.is_some()),
            ("glass", self.glass),
        ];
        for (name, set) in flags {
            if set {
                v.push(name);
            }
        }
        v
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    #[error("option --{option} does not apply to `{kind}` scenes (it accepts: {accepted})")]
    UnusedOption {
        kind: Kind,
        option: &'static str,
        accepted: String,
    },
    #[error("invalid --{option} {value}: {reason}")]
    InvalidOption {
        option: &'static str,
        value: String,
        reason: String,
    },
    #[error("cannot write {}: {reason}", path.display())]
    BadOutput { path: PathBuf, reason: String },
    #[error("cannot write the scene: {0}")]
    File(#[from] crate::files::FileError),
    #[error("cannot encode a texture: {0}")]
    Texture(String),
}

/// What was written, with the statistics a test or the CLI reports.
#[derive(Clone, Debug)]
pub struct GenerateSummary {
    pub kind: Kind,
    /// The .gltf first, then the .bin and textures.
    pub files: Vec<PathBuf>,
    pub bytes: u64,
    pub nodes: u64,
    /// Triangles in the scene after instancing.
    pub triangles: u64,
    /// Triangles stored in the buffer (before instancing).
    pub stored_triangles: u64,
    /// Nodes whose mesh emits: one light model each.
    pub light_models: u64,
    /// Emissive triangles in the scene after instancing.
    pub emissive_triangles: u64,
    pub punctual_lights: u64,
    /// Emitted power (π·area·mean radiance) of the weakest and strongest light model.
    pub min_light_power: f64,
    pub max_light_power: f64,
}

/// What a kind's builder hands back: the document, its resolved options and any analytic
/// parameters the tests need.
pub(crate) struct Built {
    pub gltf: writer::Gltf,
    pub options: Map<String, Value>,
    pub analytic: Option<Value>,
}

pub(crate) fn check_range(
    option: &'static str,
    value: f32,
    lo: f32,
    hi: f32,
    what: &str,
) -> Result<f32, GenerateError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(GenerateError::InvalidOption {
            option,
            value: value.to_string(),
            reason: format!("must be {what}"),
        })
    }
}

/// Builds the scene of `kind` and writes it to `out` (a `.gltf` path), with its `.bin`
/// and PNG textures beside it.
pub fn generate(
    kind: Kind,
    options: &Options,
    out: &Path,
) -> Result<GenerateSummary, GenerateError> {
    for option in options.given() {
        if !kind.accepted().contains(&option) {
            let accepted = ["seed", "aspect", "offset", "matte"]
                .iter()
                .chain(kind.accepted())
                .map(|s| format!("--{s}"))
                .collect::<Vec<_>>();
            return Err(GenerateError::UnusedOption {
                kind,
                option,
                accepted: accepted.join(", "),
            });
        }
    }
    if out.extension().and_then(|e| e.to_str()) != Some("gltf") {
        return Err(GenerateError::BadOutput {
            path: out.to_path_buf(),
            reason: "the output must be a .gltf file".into(),
        });
    }
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(GenerateError::BadOutput {
            path: out.to_path_buf(),
            reason: format!("the directory {} does not exist", dir.display()),
        });
    }
    if let Some(a) = options.aspect {
        check_range("aspect", a, 0.1, 10.0, "between 0.1 and 10")?;
    }
    let built = match kind {
        Kind::Street => street::build(options)?,
        Kind::CornellLights => cornell::build(options)?,
        Kind::Furnace => furnace::build(options)?,
        Kind::PlaneQuad => analytic::build_plane_quad(options)?,
        Kind::PlanePoint => analytic::build_plane_point(options)?,
        Kind::Gap => gap::build(options)?,
        Kind::AlphaTest => alpha_test::build(options)?,
        Kind::Sconces => conformance::build_sconces(options)?,
        Kind::PunctualNear => conformance::build_punctual_near(options)?,
        Kind::AlphaLights => conformance::build_alpha_lights(options)?,
        Kind::BistroNight => bistro_night::build(options)?,
    };
    let mut built = built;
    if let Some(offset) = options.offset {
        if offset.iter().any(|x| !x.is_finite() || x.abs() > 1e7) {
            return Err(GenerateError::InvalidOption {
                option: "offset",
                value: format!("{offset:?}"),
                reason: "must be three finite numbers of magnitude at most 1e7".into(),
            });
        }
        built.gltf.set_offset(glam::Vec3::from_array(offset));
        built.options.insert(
            "offset".into(),
            Value::String(offset.map(|x| x.to_string()).join(",")),
        );
    }
    if options.matte {
        built.gltf.make_matte();
        built.options.insert("matte".into(), Value::Bool(true));
    }
    let stats = built.gltf.stats().clone();
    let mut lanterna = Map::new();
    lanterna.insert("kind".into(), json!(kind.name()));
    lanterna.insert("seed".into(), json!(options.seed));
    lanterna.insert("options".into(), Value::Object(built.options.clone()));
    lanterna.insert(
        "command".into(),
        json!(command_line(kind, options.seed, &built.options, out)),
    );
    lanterna.insert(
        "provenance".into(),
        json!(
            "Procedurally generated by lanterna's scene generator; no third-party assets. \
               Regenerate with the command above: the same options and seed give identical files."
        ),
    );
    lanterna.insert("generator_version".into(), json!(env!("CARGO_PKG_VERSION")));
    if let Some(a) = built.analytic {
        lanterna.insert("analytic".into(), a);
    }
    lanterna.insert(
        "statistics".into(),
        json!({
            "triangles": stats.triangles,
            "light_models": stats.light_models,
            "emissive_triangles": stats.emissive_triangles,
            "punctual_lights": stats.punctual_lights,
        }),
    );
    let files = built.gltf.write(out, json!({ "lanterna": lanterna }))?;
    let bytes = files
        .iter()
        .map(|f| std::fs::metadata(f).map(|m| m.len()).unwrap_or(0))
        .sum();
    let mut files = files;
    files.rotate_right(1);
    Ok(GenerateSummary {
        kind,
        files,
        bytes,
        nodes: stats.nodes,
        triangles: stats.triangles,
        stored_triangles: stats.stored_triangles,
        light_models: stats.light_models,
        emissive_triangles: stats.emissive_triangles,
        punctual_lights: stats.punctual_lights,
        min_light_power: if stats.light_models > 0 {
            stats.min_light_power
        } else {
            0.0
        },
        max_light_power: stats.max_light_power,
    })
}

/// The command that regenerates this file, with every resolved option spelled out.
fn command_line(kind: Kind, seed: u64, options: &Map<String, Value>, out: &Path) -> String {
    let mut cmd = format!("lanterna scene generate {} --seed {seed}", kind.name());
    for (k, v) in options {
        match v {
            Value::Bool(true) => cmd.push_str(&format!(" --{k}")),
            Value::Bool(false) => {}
            Value::String(s) => cmd.push_str(&format!(" --{k} {s}")),
            v => cmd.push_str(&format!(" --{k} {v}")),
        }
    }
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    cmd.push_str(&format!(" -o {name}"));
    cmd
}
