//! `obsan montecarlo --shard K/N --json`: the partial result `obsan montecarlo merge` reads.

/// A partial result, as written by `--shard K/N --json`. Values are IEEE-754
/// bits in hex, so that the merge sums exactly the numbers one run sums.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Partial {
    /// The marker "obsan montecarlo --shard K/N --json".
    pub partial: String,
    /// The format's version (a merge refuses any other).
    pub version: u32,
    /// Run r uses seed + r.
    pub seed: u64,
    /// (K, N).
    pub shard: (usize, usize),
    /// The tables' runs in this shard.
    pub tables: Vec<PartialTable>,
}

/// One table's runs in the shard.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema, PartialEq)]
pub struct PartialTable {
    /// The paper's table number.
    pub table: u8,
    /// Runs per cell in the whole sweep.
    pub runs: usize,
    /// The cells run.
    pub cells: Vec<PartialCell>,
}

/// One cell's runs in the shard.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema, PartialEq)]
pub struct PartialCell {
    /// 1-based, as --cell.
    pub cell: usize,
    /// The set-up.
    pub label: String,
    /// The methods run, in the order of each run's outcomes.
    pub methods: Vec<String>,
    /// [first, end) of the run indices.
    pub run_range: (usize, usize),
    /// Every run of the shard.
    pub records: Vec<PartialRun>,
}

/// One run: each method's outcome.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema, PartialEq)]
pub struct PartialRun {
    /// The run index (seed + run).
    pub run: usize,
    /// Per method: its outcome.
    pub outcomes: Vec<PartialOutcome>,
}

/// A method's outcome in one run.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema, PartialEq)]
#[serde(untagged)]
pub enum PartialOutcome {
    /// The method's estimates and errors per column, as IEEE-754 bits in hex.
    Ok {
        errors: Vec<String>,
        estimates: Vec<String>,
    },
    /// The method failed: why.
    Failed { failed: String },
}
