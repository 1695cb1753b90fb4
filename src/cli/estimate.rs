//! Options of the data commands: diagnose, calibrate, crlb, montecarlo, simulate.

use super::seconds;
use clap::{Args, Subcommand};

#[derive(Args)]
pub struct DiagnoseArgs {
    /// The model (.sys), as every other command takes its input:
    /// `obsan diagnose MODEL DATA` (or `--model MODEL --data DATA`).
    #[arg(value_name = "MODEL", required_unless_present = "model_flag")]
    pub model_pos: Option<String>,
    /// The dataset folder (docs/data-format.md).
    #[arg(value_name = "DATA", required_unless_present = "data_flag")]
    pub data_pos: Option<String>,
    /// The model (.sys); the same as the first positional argument.
    #[arg(long = "model", value_name = "MODEL", conflicts_with = "model_pos")]
    pub model_flag: Option<String>,
    /// The dataset folder; the same as the second positional argument.
    #[arg(long = "data", value_name = "DATA", conflicts_with = "data_pos")]
    pub data_flag: Option<String>,
    /// Candidate effects (docs/effects-format.md); default: the model's file
    /// with the extension .eff, if there is one.
    #[arg(long)]
    pub effects: Option<String>,
    /// Write a report folder: report.md, SVG plots, extended.sys, diagnosis.json.
    #[arg(long)]
    pub report: Option<String>,
    /// Replace the report folder if it exists.
    #[arg(long)]
    pub force: bool,
    #[arg(long)]
    pub json: bool,
    /// Start value of a param or state (every trajectory), NAME=VALUE; repeatable.
    #[arg(long, value_name = "NAME=VALUE")]
    pub init: Vec<String>,
    /// Probability of naming an effect on data without one, per round.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Name at most this many effects (default: while a candidate stays
    /// significant).
    #[arg(long)]
    pub max_effects: Option<usize>,
    /// The measured inputs' noise: stated (dataset.json's, if any),
    /// estimate (restricted maximum likelihood, linearised about the fit),
    /// none (ordinary least squares) or auto, the default (dataset.json's
    /// if stated, else estimated on fewer than 10 trajectories where white
    /// input noise is rejected, each candidate then also weighed at white
    /// input noise; else none).
    #[arg(long, default_value = "auto", value_name = "SOURCE")]
    pub input_noise: String,
    /// Also try candidates generated from the model's structure (scales,
    /// biases, couplings with |another input|, lags, delays of the inputs;
    /// scales, biases, harmonics of the outputs), marked as generated, each
    /// screened by its score statistic before it is fitted, under its own
    /// share of alpha (docs/diagnose.md). On by default; `--generated=false`
    /// or `--no-generated` tries the effects file's candidates alone.
    #[arg(long, value_name = "BOOL", default_value_t = true, num_args = 0..=1,
          default_missing_value = "true", action = clap::ArgAction::Set)]
    pub generated: bool,
    /// Only the effects file's candidates (the same as `--generated=false`).
    #[arg(long, overrides_with = "generated")]
    pub no_generated: bool,
    /// Give up after this many seconds (exit code 2; nothing is left behind).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
}

#[derive(Args)]
pub struct CalibrateArgs {
    /// The dataset folder (docs/data-format.md).
    pub dataset: String,
    /// det, ls, cekf or ml (joint maximum likelihood on eq. 16).
    #[arg(long, default_value = "ml")]
    pub method: String,
    /// Initial distance (m) to the feature on the first trajectory (gives rho, rR, rL, B).
    #[arg(long)]
    pub d0: Option<f64>,
    /// Bearing noise (deg); default: dataset.json's, else estimated from the residuals.
    #[arg(long)]
    pub sigma_beta_deg: Option<f64>,
    /// Write the paper's Figures 5-7 (PNG and SVG) per trajectory into this
    /// new folder: observation function with nodes, sigma(s_c), DET/LS/ML fits.
    #[arg(long)]
    pub plot: Option<String>,
    /// Replace the --plot folder if it exists.
    #[arg(long)]
    pub force: bool,
    #[arg(long)]
    pub json: bool,
    /// Give up after this many seconds (exit code 2; nothing is left behind).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
}

#[derive(Args)]
pub struct CrlbArgs {
    /// A dataset folder: the bound at its maximum-likelihood estimate
    /// (instead of a simulated set-up).
    #[arg(conflicts_with = "SimFlags")]
    pub dataset: Option<String>,
    #[command(flatten)]
    pub sim: SimFlags,
    /// q=RATIOS: the wheel-speed ratios, one circular trajectory each (eq. 17; default
    /// q=0.9,0,-1; at most 100).
    #[arg(
        long = "set",
        value_name = "q=RATIOS",
        allow_hyphen_values = true,
        conflicts_with = "dataset"
    )]
    pub set: Vec<String>,
    #[arg(long)]
    pub json: bool,
    /// Give up after this many seconds (exit code 2; nothing is left behind).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
}

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct MontecarloArgs {
    #[command(subcommand)]
    pub merge: Option<MontecarloCommand>,
    /// Runs per cell (at most 100000).
    #[arg(long, default_value_t = 100)]
    pub runs: usize,
    /// 4, 5, 6, 7 or all.
    #[arg(long, default_value = "all")]
    pub table: String,
    /// Only this cell of the table (1 = its first row of set-ups); needs a
    /// single --table.
    #[arg(long, value_name = "N")]
    pub cell: Option<usize>,
    /// Only shard K of N of the runs (contiguous blocks of run indices);
    /// with --json, a partial result for `obsan montecarlo merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long)]
    pub threads: Option<usize>,
    #[arg(long)]
    pub json: bool,
    /// Run r uses seed + r.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2; nothing is left behind).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
}

#[derive(Subcommand)]
pub enum MontecarloCommand {
    /// Combine the partial results of `obsan montecarlo --shard K/N --json`
    /// into the table one run with the same flags gives, bit for bit.
    #[command(after_help = "Examples (the parts of one sweep, in any order):
  for k in 1 2 3; do obsan montecarlo --table 5 --shard $k/3 --json > part$k.json; done
  then: obsan montecarlo merge part1.json part2.json part3.json
  or:   obsan montecarlo merge part*.json --json

Every shard 1..N of the same tables, cells, runs and seed must be given once; anything else is
refused (exit 2), naming the missing or mismatched part.

--json prints what `obsan montecarlo --json` prints for the whole sweep.")]
    Merge(MergeArgs),
}

#[derive(Args)]
pub struct MergeArgs {
    /// The partial results (JSON files written by --shard K/N --json).
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<String>,
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// A .sys model to integrate (then --out is a CSV file) instead of the paper's simulator.
    pub model: Option<String>,
    /// The dataset folder to create (it must not exist, unless --force); with MODEL, a CSV file.
    #[arg(long, required_unless_present = "model")]
    pub out: Option<String>,
    #[command(flatten)]
    pub sys: SysSimFlags,
    /// Replace the folder if it exists.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub sim: SimFlags,
    /// Give up after this many seconds (exit code 2; nothing is left behind).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
}

/// `obsan simulate MODEL.sys`: values, inputs and the output times.
#[derive(Args, Clone)]
pub struct SysSimFlags {
    /// Values of params and initial states, one `name = value` a line (`import sbml --values`).
    #[arg(long, requires = "model")]
    pub values: Option<String>,
    /// A param (or known constant) value NAME=VALUE (over --values). Without MODEL:
    /// q=RATIOS, the wheel-speed ratios, one circular trajectory each (eq. 17; default
    /// q=0.9,0,-1; at most 100).
    #[arg(long = "set", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub set: Vec<String>,
    /// An initial state NAME=VALUE (over --values).
    #[arg(long = "init", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub init: Vec<String>,
    /// An input NAME=EXPR: a number or an expression of time t (and the model's params
    /// and constants), e.g. u=1.5 or u=sin(t); every input needs this or an --inputs column.
    #[arg(long = "input", value_name = "NAME=EXPR", allow_hyphen_values = true)]
    pub input: Vec<String>,
    /// The last time T (the simulation starts at 0).
    #[arg(long, value_name = "T", requires = "every")]
    pub until: Option<f64>,
    /// The output spacing DT.
    #[arg(long, value_name = "DT", requires = "until")]
    pub every: Option<f64>,
    /// Print JSON (the CSV goes to --out, if given, or into the JSON's rows).
    #[arg(long, requires = "model")]
    pub json: bool,
}

/// The simulated set-up (section VI-A; Tables II and III by default).
#[derive(Args, Clone)]
pub struct SimFlags {
    /// The old spelling of `--set q=RATIOS`, kept working (hidden).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, hide = true)]
    pub q: Vec<f64>,
    /// Bearing noise standard deviation, degrees.
    #[arg(long, default_value_t = 1.0)]
    pub sigma_beta_deg: f64,
    /// Encoder noise K (m^1/2): increment variance K^2 |increment| / r.
    #[arg(long, default_value_t = 0.001)]
    pub k: f64,
    /// Non-circular path: relative std of each wheel's displacement per segment.
    #[arg(long, default_value_t = 0.0)]
    pub iota: f64,
    /// Systematic error of the executed wheel-speed ratio (q + dq).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub dq: f64,
    /// Right wheel angular speed (rad/s).
    #[arg(long, default_value_t = 0.168)]
    pub nu: f64,
    /// constant, sine:AMPLITUDE:PERIOD or stopgo:RUN:PAUSE (seconds).
    #[arg(long, default_value = "constant")]
    pub speed_profile: String,
    /// Bearings per second (at most the encoder rate, 50; a trajectory lasts
    /// at most 14400 s).
    #[arg(long, default_value_t = 1.0)]
    pub bearing_rate: f64,
    /// Instead of --bearing-rate: this many bearings per trajectory, evenly
    /// spread (at most 1000000, and 3000000 over all trajectories).
    #[arg(long)]
    pub bearings: Option<usize>,
    /// Initial distance to the feature (m).
    #[arg(long, default_value_t = 1.2)]
    pub d0: f64,
    /// A hidden effect NAME=VALUE (time_offset, bearing_scale, bearing_distortion, wheel_slip, radius_change, bearing_bias).
    #[arg(long = "effect", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub effects: Vec<String>,
    /// Drive one trajectory by this wheel-speed history (CSV t,wR,wL) instead of circles.
    /// With MODEL: the inputs' time course (CSV t,<inputs>; linear between rows, two rows
    /// at one t a step; covering 0 to --until).
    #[arg(long)]
    pub inputs: Option<String>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl DiagnoseArgs {
    /// The model file, given by position or by `--model` (clap requires one).
    pub fn model(&self) -> &str {
        self.model_flag
            .as_deref()
            .or(self.model_pos.as_deref())
            .unwrap_or_default()
    }

    /// The dataset folder, given by position or by `--data`.
    pub fn data(&self) -> &str {
        self.data_flag
            .as_deref()
            .or(self.data_pos.as_deref())
            .unwrap_or_default()
    }
}
