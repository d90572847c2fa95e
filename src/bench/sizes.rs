//! Every size the suite uses, in one place: image sizes, sample counts, light counts and
//! reference quality for the full run (chosen so the whole suite takes about 15 minutes
//! on two CPU cores with lavapipe) and for `--quick` (tiny: it proves the bench works in
//! CI, it measures nothing worth reading). The results file records the sizes it used.

/// A scene rendered by a suite at one size.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SceneSize {
    /// File name in the scenes directory.
    pub scene: String,
    pub width: u32,
    /// Height; `None` follows the camera's aspect ratio.
    pub height: Option<u32>,
    /// Samples per pixel of each timed run.
    pub spp: u64,
}

/// The quality comparison of one scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct QualitySize {
    pub scene: String,
    pub width: u32,
    pub height: Option<u32>,
    /// spp of the `pt` reference (rendered in two independent halves).
    pub reference_spp: u64,
    /// Equal-spp budgets.
    pub spp: Vec<u64>,
    /// Equal-time budgets in seconds.
    pub seconds: Vec<f64>,
}

/// The Mitsuba 3 peer comparison of one scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PeerSize {
    pub scene: String,
    pub width: u32,
    pub height: Option<u32>,
    /// Independent lanterna `pt` batches (disjoint sample ranges) and their spp.
    pub batches: u32,
    pub spp: u64,
    /// Independent Mitsuba runs of `spp` each.
    pub runs: u32,
    /// spp of the Mitsuba reference the equal-time MAE is measured against.
    pub reference_spp: u64,
}

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Sizes {
    pub max_depth: u32,
    /// Warm-up budget (spp) before each configuration's recorded runs.
    pub warmup_spp: u64,
    pub throughput: Vec<SceneSize>,
    /// Street scene: emissive-triangle counts to aim for (the lamp count is searched).
    pub scaling_emissive_triangles: Vec<u64>,
    pub scaling: SceneSize,
    pub guiding: SceneSize,
    pub quality: Vec<QualitySize>,
    pub mitsuba: Vec<PeerSize>,
    pub profile: SceneSize,
    /// RIS candidate counts of the profile.
    pub profile_ris_candidates: Vec<u32>,
    /// Max depths of the profile's `pt` runs.
    pub profile_depths: Vec<u32>,
    /// Methods whose SIMD lane utilisation the profile counts (one run each, with a
    /// kernel of its own to compile).
    #[serde(default)]
    pub profile_lane_methods: Vec<String>,
    /// `trend`: scenes, image sizes and spp budgets (training paths ≈ 0.3 × pixels × spp).
    #[serde(default)]
    pub trend: Vec<TrendSize>,
}

fn scene(name: &str, width: u32, height: Option<u32>, spp: u64) -> SceneSize {
    SceneSize {
        scene: name.into(),
        width,
        height,
        spp,
    }
}

fn trend(scene: &str, width: u32, spp: Vec<u64>, reference_spp: u64) -> TrendSize {
    TrendSize {
        scene: scene.into(),
        width,
        height: None,
        spp,
        reference_spp,
    }
}

/// A peer comparison of `batches` lanterna batches and as many Mitsuba runs.
fn peer(scene: &str, width: u32, batches: u32, spp: u64, reference_spp: u64) -> PeerSize {
    PeerSize {
        scene: scene.into(),
        width,
        height: None,
        batches,
        spp,
        runs: batches,
        reference_spp,
    }
}

impl Sizes {
    pub fn full() -> Sizes {
        Sizes {
            max_depth: 4,
            warmup_spp: 4,
            // Every shipped scene (issue 13's goal is per shipped scene).
            throughput: vec![
                scene("street.gltf", 128, None, 16),
                scene("cornell-lights.gltf", 96, None, 64),
                scene("bistro-night.gltf", 128, None, 16),
                scene("street-matte.gltf", 128, None, 16),
            ],
            scaling_emissive_triangles: vec![64, 256, 1024, 4096, 16384, 65536],
            scaling: scene("street.gltf", 64, None, 16),
            guiding: scene("street.gltf", 128, None, 32),
            quality: vec![
                QualitySize {
                    scene: "cornell-lights.gltf".into(),
                    width: 64,
                    height: None,
                    reference_spp: 4096,
                    spp: vec![16],
                    seconds: vec![1.0],
                },
                QualitySize {
                    scene: "street.gltf".into(),
                    width: 64,
                    height: None,
                    reference_spp: 1024,
                    spp: vec![16],
                    seconds: vec![2.0],
                },
            ],
            mitsuba: vec![
                peer("cornell-lights.gltf", 64, 8, 64, 4096),
                peer("street.gltf", 64, 8, 16, 2048),
                // The many-light scene that exports exactly (600 light models).
                peer("street-matte.gltf", 64, 8, 16, 2048),
                // The equal-time budget is one `pt` batch: the rows above give it a
                // fraction of a second, where the guided methods cannot train and
                // per-render costs weigh; these give it seconds, as a user's renders have
                // (references with ≥ 8× the equal-time renders' Mitsuba spp).
                peer("cornell-lights.gltf", 64, 4, 1024, 65536),
                peer("street-matte.gltf", 64, 4, 512, 16384),
            ],
            profile: scene("street.gltf", 128, None, 4),
            profile_ris_candidates: vec![1, 8, 32],
            profile_depths: vec![1, 2, 3, 4],
            profile_lane_methods: crate::render::Method::ALL
                .iter()
                .map(|m| m.name().to_string())
                .collect(),
            trend: ["bistro-night.gltf", "street.gltf"]
                .into_iter()
                .flat_map(|scene| {
                    [
                        (64, vec![16, 64, 256], 1024),
                        (128, vec![128, 512], 4096),
                        (320, vec![256, 1024], 4096),
                        (1024, vec![1024], 4096),
                    ]
                    .map(|(width, spp, reference_spp)| trend(scene, width, spp, reference_spp))
                })
                .collect(),
        }
    }

    pub fn quick() -> Sizes {
        Sizes {
            max_depth: 4,
            warmup_spp: 1,
            throughput: vec![
                scene("street.gltf", 32, None, 4),
                scene("cornell-lights.gltf", 32, Some(24), 4),
            ],
            scaling_emissive_triangles: vec![64, 256],
            scaling: scene("street.gltf", 32, None, 4),
            guiding: scene("street.gltf", 32, None, 8),
            quality: vec![QualitySize {
                scene: "cornell-lights.gltf".into(),
                width: 32,
                height: Some(24),
                reference_spp: 64,
                spp: vec![4],
                seconds: vec![0.3],
            }],
            mitsuba: vec![PeerSize {
                scene: "cornell-lights.gltf".into(),
                width: 32,
                height: Some(24),
                batches: 2,
                spp: 4,
                runs: 2,
                reference_spp: 64,
            }],
            profile: scene("street.gltf", 32, None, 2),
            profile_ris_candidates: vec![1, 32],
            profile_depths: vec![1, 4],
            // Each method's lane-statistics kernel is one more lavapipe compile (tens of
            // seconds): left out of the test suite's run (tests/lane_stats.rs checks it).
            profile_lane_methods: Vec::new(),
            trend: vec![trend("bistro-night.gltf", 16, vec![4, 16], 32)],
        }
    }
}

/// One scene at one image size: the spp budgets measured there and its reference.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TrendSize {
    pub scene: String,
    pub width: u32,
    /// `None` follows the camera's aspect ratio.
    pub height: Option<u32>,
    /// Equal total spp budgets (training included for the guided methods).
    pub spp: Vec<u64>,
    /// spp of the `pt` reference at this size (two independent halves).
    pub reference_spp: u64,
}
