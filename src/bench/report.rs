//! The results file: everything a bench run measured, with the machine and the sizes it
//! used, as one JSON document (`bench/results/<date>-<device>.json`). Suites that did not
//! run are absent; the Mitsuba suite says why it was skipped.

use super::guiding::GuidingOverhead;
use super::machine::Machine;
use super::mitsuba::Peer;
use super::profile::Profile;
use super::quality::Quality;
use super::scaling::Scaling;
use super::sizes::Sizes;
use super::throughput::Throughput;
use super::trend::Trend;

/// Changes when a key changes meaning.
pub const SCHEMA: u32 = 1;

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct BenchReport {
    pub schema: u32,
    /// UTC date of the run (`YYYY-MM-DD`).
    pub date: String,
    pub unix_time: u64,
    /// `--quick`: tiny sizes, proves the bench works; not a measurement.
    pub quick: bool,
    /// The command line that made this file.
    pub command: String,
    pub machine: Machine,
    /// Recorded runs per configuration (after one warm-up run).
    pub repeat: usize,
    pub seed: u32,
    pub sizes: Sizes,
    /// Suites that ran, in order.
    pub suites: Vec<String>,
    pub throughput: Option<Throughput>,
    pub scaling: Option<Scaling>,
    pub guiding: Option<GuidingOverhead>,
    pub quality: Option<Quality>,
    pub mitsuba: Option<Peer>,
    /// Why the Mitsuba suite did not run (not installed, `--skip-mitsuba`, or its error).
    pub mitsuba_skipped: Option<String>,
    pub profile: Option<Profile>,
    /// Ray traversal alone: ray queries against the software traversal.
    #[serde(default)]
    pub traversal: Option<super::traversal::TraversalBench>,
    /// `--suite trend` only.
    #[serde(default)]
    pub trend: Option<Trend>,
    /// /proc/loadavg before and after the run: other work on the machine shows up here
    /// (and in every timing).
    pub load_average_start: Option<String>,
    pub load_average_end: Option<String>,
    /// Wall seconds of the whole bench.
    pub total_seconds: f64,
}
