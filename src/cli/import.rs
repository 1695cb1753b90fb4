//! `obsan import`'s sub-commands and their options.

use super::seconds;
use clap::{Args, Subcommand};

#[derive(Subcommand)]
pub enum ImportCommand {
    /// One robot of the UTIAS MRCLAM data set (Leung et al., IJRR 2011), cut
    /// into windows for systems/mrclam.sys; ground truth goes to truth.json.
    #[command(after_help = "Examples:
  obsan import mrclam MRCLAM_DIR --robot 1 --out data/mrclam1
  obsan import mrclam MRCLAM_DIR --robot 1 --out data/vicon1 --vicon-poses

MRCLAM_DIR is one unpacked data set of the UTIAS MRCLAM collection (e.g. MRCLAM_Dataset1,
from http://asrl.utias.utoronto.ca/datasets/mrclam/): Landmark_Groundtruth.dat and, for robot
N, robotN_Odometry.txt, robotN_Measurement.txt and robotN_Groundtruth.txt.
Writes a dataset (docs/data-format.md) with the Vicon ground truth in truth.json.")]
    Mrclam(MrclamArgs),
    /// StructuralIdentifiability.jl's `@ODEmodel` text (a Julia file with one
    /// or more models, e.g. its benchmarking/benchmarks.jl) to .sys
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import si-jl model.jl                       (one model: .sys text to stdout)
  obsan import si-jl benchmarks.jl --list
  obsan import si-jl benchmarks.jl --model Goodwin --out goodwin.sys
  obsan import si-jl benchmarks.jl --all systems/benchmarks/si-jl
  obsan import si-jl benchmarks.jl --model Goodwin --out goodwin.sys --json

x'(t) = EXPR makes x a state, y(t) = EXPR an output, another u(t) an input, a bare name a
parameter; set_parameter_values(ode, Dict(p => QQ(1, 2))) values are substituted. The .sys is
read back before it is written: a model outside obsan's class (not affine in its inputs) is
refused at its equation's line in the source, exit 2. --all writes every model that converts
and exits 2 if any was refused.
--json prints {format, inputs_out, known_inputs, models (key, path, system, text), refused,
source, values}: the files written, or the .sys text in models[].text without --out.")]
    SiJl(SiJlArgs),
    /// An SBML model (Level 2 or 3 core) to .sys: species changed by reactions as states,
    /// rate laws as their equations, compartments folded in, parameters unknown
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import sbml model.xml                        (.sys text to stdout; every state measured)
  obsan import sbml model.xml --observe S1,S2 --out model.sys
  obsan import sbml model.xml --out model.sys --values model.values
  obsan import sbml dosing.xml --out m.sys --values m.values --inputs-out m.csv --until 50
  obsan import sbml model.xml --out model.sys --json

Assignment rules are substituted and function definitions inlined. A <piecewise> of time and
constants (a dosing switch) becomes a known input u_ID (ID: its rule's variable or reaction);
--inputs-out writes its exact course over [0, --until] from the file's numbers (conditions
comparing time with a constant expression, pieces affine in time; others refused at the
piecewise), for simulate --inputs. Events, algebraic rules, delays, a piecewise reading a state
and varying compartments are refused naming the element and its line, exit 2.
--json prints {format, inputs_out, known_inputs, models (key, path, system, text), refused,
source, values}: the files written, or the .sys text in models[].text without --out.")]
    Sbml(SbmlArgs),
    /// A PEtab v1 problem (YAML, SBML model, tables) to .sys: observables as outputs,
    /// estimated parameters as params, fixed ones as consts, one model copy per condition
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import petab problem.yaml                    (.sys text to stdout)
  obsan import petab problem.yaml --condition c1 --out model.sys
  obsan import petab problem.yaml --out model.sys --json

Errors name the file (YAML, SBML or table), line and column, exit 2.
--json prints {format, inputs_out, known_inputs, models (key, path, system, text), refused,
source, values}: the files written, or the .sys text in models[].text without --out.")]
    Petab(PetabArgs),
    /// A STRIKE-GOLDD model file (z_create_NAME.m: MATLAB syms with x, p, u, w, f, h) to .sys
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import strike-goldd z_create_model.m                (.sys text to stdout)
  obsan import strike-goldd z_create_model.m --out model.sys
  obsan import strike-goldd z_create_model.m --out model.sys --json

x are the states, p the unknown parameters, u the known inputs, w the unknown inputs, f the
dynamics and h the outputs (y1, y2, ...); other assignments are substituted where used.
--json prints {format, inputs_out, known_inputs, models (key, path, system, text), refused,
source, values}: the files written, or the .sys text in models[].text without --out.")]
    StrikeGoldd(StrikeGolddArgs),
}

#[derive(Args)]
pub struct StrikeGolddArgs {
    /// The MATLAB model file.
    pub source: String,
    /// Write the .sys here instead of stdout.
    #[arg(long)]
    pub out: Option<String>,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
    /// Largest polynomial (terms) the check of the written .sys may build before it stops
    /// with "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Machine-readable JSON on stdout (what was converted and written).
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct PetabArgs {
    /// The PEtab problem file (YAML).
    pub source: String,
    /// Only this simulation condition (default: every condition the measurements use, each a
    /// copy of the model).
    #[arg(long)]
    pub condition: Option<String>,
    /// Write the .sys here instead of stdout.
    #[arg(long)]
    pub out: Option<String>,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
    /// Largest polynomial (terms) the check of the written .sys may build before it stops
    /// with "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Machine-readable JSON on stdout (what was converted and written).
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SbmlArgs {
    /// The SBML file.
    pub source: String,
    /// The measured ids (species, parameters or assignment-rule variables), comma-separated:
    /// each becomes an output y_ID. Default: every state.
    #[arg(long, value_delimiter = ',')]
    pub observe: Vec<String>,
    /// Write the .sys here instead of stdout.
    #[arg(long)]
    pub out: Option<String>,
    /// Also write the numbers the SBML file gives, one `name = value` line each (parameter
    /// values, compartment sizes, species' initial values as their states are written).
    #[arg(long)]
    pub values: Option<String>,
    /// Write the exact time course of the known inputs (each <piecewise> of time) here, as
    /// `simulate --inputs` reads it (header t,<inputs>; a repeated t is a step). Needs --until.
    #[arg(long, requires = "until")]
    pub inputs_out: Option<String>,
    /// The horizon of --inputs-out: rows cover [0, UNTIL].
    #[arg(long, requires = "inputs_out")]
    pub until: Option<f64>,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
    /// Largest polynomial (terms) the check of the written .sys may build before it stops
    /// with "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Machine-readable JSON on stdout (what was converted and written).
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SiJlArgs {
    /// The Julia file.
    pub source: String,
    /// The model to convert: its Dict key (`Goodwin` for `:Goodwin => Dict(...)`) or the
    /// variable it is bound to. Needed when the file holds more than one.
    #[arg(long)]
    pub model: Option<String>,
    /// Write the .sys here instead of stdout.
    #[arg(long)]
    pub out: Option<String>,
    /// Convert every model into this folder, as KEY.sys.
    #[arg(long, conflicts_with_all = ["model", "out"])]
    pub all: Option<String>,
    /// List the models found (key, line, name) and exit.
    #[arg(long)]
    pub list: bool,
    /// Replace existing .sys files.
    #[arg(long)]
    pub force: bool,
    /// Largest polynomial (terms) the check of the written .sys may build before it stops
    /// with "expression too large" (docs/engine.md, Limits).
    /// (Not with --all, where each model is checked under the default budget.)
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS, conflicts_with = "all")]
    pub max_terms: usize,
    /// Machine-readable JSON on stdout (what was converted and written).
    #[arg(long, conflicts_with = "list")]
    pub json: bool,
}

#[derive(Args)]
pub struct MrclamArgs {
    /// The folder with robotN_Odometry.txt, robotN_Measurement.txt,
    /// robotN_Groundtruth.txt, Landmark_Groundtruth.dat.
    pub source: String,
    /// Robot number.
    #[arg(long, default_value_t = 1)]
    pub robot: u32,
    /// The dataset folder to create.
    #[arg(long)]
    pub out: String,
    /// Window length (s): each window is a trajectory with its own initial state.
    #[arg(long, default_value_t = 60.0)]
    pub window: f64,
    /// Skip windows with fewer landmark measurements than this.
    #[arg(long, default_value_t = 30)]
    pub min_measurements: usize,
    /// Only the first N windows (0: all).
    #[arg(long, default_value_t = 0)]
    pub max_windows: usize,
    /// Outputs are the Vicon poses (px, py, pth every 0.5 s) instead of the
    /// landmark measurements, in the same windows: for systems/mrclam-pose.sys,
    /// the ground truth's own estimate of the odometry effects.
    #[arg(long)]
    pub vicon_poses: bool,
    #[arg(long)]
    pub force: bool,
    /// Give up after this many seconds (exit code 2; nothing is left behind).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
}
