//! Command-line arguments.

use clap::{Args, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "obsan",
    version,
    about = "Exact nonlinear observability analysis and sensor self-calibration"
)]
#[command(after_help = "Examples:
  obsan rank systems/calib.sys                  # rank 7 of 7: weakly locally observable (exact)
  obsan symmetries systems/calib.sys --input q  # what circles cannot tell apart
  obsan modes systems/calib_q_nopsi.sys         # observable modes and the reduced system
  obsan simulate --out data/sim && obsan calibrate data/sim

Every command has --help with examples; the tutorial is docs/tutorial.md.
Exit codes: 0 success, 1 a check failed, 2 bad input or error.")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Print a system in input-affine normal form: states, params, consts,
    /// inputs, f0, each f_i, outputs (after a restriction, if one is named).
    #[command(after_help = "Examples:
  obsan show systems/calib.sys
  obsan show systems/calib.sys --input q --set q=0.9
  obsan show systems/calib.sys --json

--json prints {system, file, description, restriction, states, params, consts, inputs, f0,
fields, outputs, exact}, each formula as {text, latex}; \"exact\": true.")]
    Show(ShowArgs),
    /// Print the exact canonical form of an expression.
    #[command(after_help = "Examples:
  obsan simplify 'sin(g-p)*cos(p) + cos(g-p)*sin(p) - sin(g)'     # 0
  obsan simplify '-x^2 + (x+1)^2'                                # 2*x + 1
  obsan simplify '(a^2-b^2)/(a-b)' --latex
  obsan simplify 'log(x*y) - log(x) - log(y)'                    # not decided: atoms listed

--json prints {input, canonical, latex, is_zero, decided, undecided_atoms, exact}: is_zero is
null and decided false when the form is nonzero over atoms that may be related (listed in
undecided_atoms); a zero form is always decided.")]
    Simplify(ExprArgs),
    /// Print the derivative of an expression with respect to a symbol, in canonical form.
    #[command(after_help = "Examples:
  obsan diff 'atan2(sin(g), -mu - cos(g))' g
  obsan diff 'x^3*exp(x)' x --latex

--json prints {input, variable, canonical, latex, is_zero, decided, undecided_atoms, exact}
(as simplify: is_zero null when not decided).")]
    Diff(DiffArgs),
    /// The observability rank test (Hermann-Krener): generic rank, a basis of
    /// Lie derivatives, which variables are observable on their own.
    #[command(after_help = "Examples:
  obsan rank systems/calib.sys                      # rank 7 of 7, proven
  obsan rank systems/calib.sys --input q            # on circles (eq. 17): rank 4
  obsan rank systems/calib.sys --input q --set q=0.9 --json
  obsan rank systems/calib.sys --experiment 'q: q=0.9' --experiment 'q: q=0' --experiment 'q: q=-1'
  obsan rank systems/calib.sys --input q --experiments auto   # how many circles (3)
  obsan rank systems/classic/two_compartment.sys --known-generic x1,x2   # known initial conditions
  obsan rank systems/calib.sys --along data/sim --window 20        # along a dataset's truth
  obsan rank systems/benchmarks/unknown-inputs/time_gain.sys       # explicit time t (y = t*x1)

--json prints {system, restriction, state (the analysed variables), n, rank,
weakly_locally_observable (null when full rank rests on undecided atoms), decided,
undecided_atoms (atoms that may be related), observable_variables, unobservable_variables, exact,
error_bound, degree_bound, seed, basis (Lie words with their order), max_order, evaluated, experiments (the
stacked experiments, or null)}. --known/--known-generic, --experiments auto and a model with
unknown inputs print their own objects (docs/experiments.md, docs/engine.md). A model may use time
t explicitly: it is known along the trajectory (a clock t' = 1), and state, n, rank and basis
leave the clock out (docs/sys-format.md, \"Explicit time\"); --along, --known and --experiments
refuse it.

--along --json prints {system, along, window, n, state, tolerance_safety, rounding_floor,
input_rel_tol, windows: [{trajectory, t0, t1, rows, rank, condition, singular_values,
tolerance, kernel, weakest, input_relations}], stretches: [{trajectory, t0, t1, windows, rank,
lost, input_relations, symmetry: {restricted_rank, vectors, angles_deg, kernel_to_symmetries_deg,
symmetries_to_kernel_deg, angle_bound_deg, matches, exact}}], dataset: {columns, n, rank,
singular_values, tolerance, kernel}}.")]
    Rank(RankArgs),
    /// A basis of the continuous symmetries (null space of the Lie-derivative
    /// gradients), each certified before it is printed: cheap structure and
    /// small systems exactly, others by reconstruction from values modulo a
    /// prime, certified at random points with a stated error bound.
    #[command(after_help = "Examples:
  obsan symmetries systems/localization.sys         # d/dphiR + d/dthetaR (eq. 3)
  obsan symmetries systems/calib.sys --input q
  obsan symmetries systems/psi.sys --exact      # the exact route and closure check

The default --timeout is 60 s, all of it for the work; a run past it stops with exit code 2
and says how far it got. Parts of the system that share only common variables (or none) are
solved as separate blocks.
--json prints {system, restriction, state, n, rank, symmetries (one object per vector: variable ->
{text, latex}), free_directions (the variables no output reaches: each d/dx is a symmetry too,
listed by name), rows_checked, blocks, exact, certificate (closure | invariance | random), certification
(for random: {points, primes, identities, degree, error_bound}, else null), decided, undecided_atoms
(atoms that may be related: then each vector still annihilates the codistribution, but the count
and the independence rest on the rank over them, an upper bound: exact is false)}.

A model with unknown inputs (obsan symmetries systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys)
gives the kernel of its observable codistribution, certified exactly (docs/engine.md, \"Symmetries
with unknown inputs\"); with unknown inputs --json prints {system, restriction, state, unknown_inputs,
n, rank, symmetries, observable_variables, unobservable_variables (moved by a symmetry: exact),
reconstructable_inputs, exact, certificate (unknown_input_invariance), identities, error_bound
(of the rank test for the observable ones), seed}.")]
    Symmetries(SymArgs),
    /// The Lie derivatives of the outputs up to an order, in canonical form.
    #[command(after_help = "Examples:
  obsan lie systems/localization.sys --order 2
  obsan lie systems/calib.sys --order 1 --latex

--json prints {system, restriction, lie_derivatives: [{lie_derivative, order, text, latex}],
exact}.")]
    Lie(LieArgs),
    /// Check candidate observable modes against the symmetry PDE (eq. 11).
    #[command(after_help = "Examples:
  obsan check systems/localization.sys --mode D --mode 'thetaR - phiR'
  obsan check systems/localization.sys --mode D --json

--json prints {system, restriction, rank, symmetries, checks: [{mode, observable_mode
(null: not decided), decided, undecided_atoms, residuals}], independent, independent_count, complete, exact, certificate (closure | invariance |
random), certification}: the residuals are exact; the symmetries are certified as `certificate`
says (random: error_bound in certification; --exact for the exact route). Exit 1 when a mode fails.")]
    Check(CheckArgs),
    /// Check a claimed local decomposition (new state, reduced dynamics, output) exactly.
    #[command(after_help = "Examples:
  obsan verify systems/decomp_localization.dec
  obsan verify systems/decomp_21_22.dec --json

--json prints {system, restriction, decomposition, checks: [{check, pass, detail, decided,
undecided_atoms}], pass, decided, undecided_atoms, exact, verdict, certificate (closure |
invariance | random), certification, symmetries}. The symmetries take the default route (--exact:
the exact one); a passing decomposition that writes every output is exact by closure whatever
certified them. Exit 1 when a check fails.")]
    Verify(VerifyArgs),
    /// Derive observable modes and the reduced system, each proven exactly (eqs. 9-11).
    #[command(after_help = "Examples:
  obsan modes systems/localization.sys
  obsan modes systems/calib_q_nopsi.sys --json
  obsan modes systems/classic/two_compartment.sys --out data/two_compartment_modes

--json prints {system, restriction, n, rank, full_rank, symmetries, unreached (variables no
output reaches: unobservable, in no mode), modes: [{name, expr, kind,
angle, domain}], reduced: {inputs, dynamics: [{name, rhs}], outputs: [{name, expr}], closed,
missing}, decided, undecided_atoms (atoms that may be related: then the rank is an upper bound,
full_rank, modes_exact and complete are null, independent and verified null unless false for
certain, and certificate says what is still proven),
certificate: {text, modes_exact, independent, complete, verified, checks}, sys, dec}.
--out PREFIX writes PREFIX.sys (the reduced system) and PREFIX.dec (for obsan verify).
Exit 1 when the reduced system could not be closed or a check failed.")]
    Modes(ModesArgs),
    /// Simulate the paper's calibration experiment (section VI-A) and write a dataset, or
    /// integrate any MODEL.sys from given values.
    #[command(after_help = "Examples:
  obsan simulate --out data/sim                              # section VI-A, q = 0.9, 0, -1
  obsan simulate --out data/sim2 --q 0.5,-0.5 --seed 7 --effect bearing_scale=0.04
  obsan simulate --out data/sine --speed-profile sine:0.5:60
  obsan simulate systems/classic/lotka_volterra.sys --set a=1 --set b=0.5 --set c=1 --set d=0.2 --init x=4 --init y=2 --until 5 --every 1 --json
  obsan simulate systems/classic/two_compartment.sys --set k01=0.1 --set k02=0 --set k12=0.2 --set k21=0.3 --init x1=1 --init x2=0 --input u=0 --until 10 --every 0.5 --out data/two.csv

Without MODEL: writes dataset.json, one folder per trajectory (inputs.csv, outputs.csv,
meta.json) and truth.json; --force replaces only a folder obsan wrote.
With MODEL (values from --values FILE, as import sbml --values writes, and the flags over it):
prints (or writes to --out FILE.csv) the CSV time,<states>,<outputs> at
0, DT, 2 DT, ... up to T (at most 1000000 rows), integrated by RK4 with step doubling
until the estimated error of every value is within 1e-9 (|value| + 1).
--json prints {model, columns, rows, steps, error_estimate, tolerance}.")]
    Simulate(SimulateArgs),
    /// Calibrate from a dataset of circles: phi, psi, eta, delta, xi with
    /// standard deviations (and rho, rR, rL, B with --d0), per trajectory
    /// xi_q, L, c, k.
    #[command(after_help = "Examples:
  obsan calibrate data/sim                         # joint maximum likelihood
  obsan calibrate data/sim --method ls --d0 1.2    # DET + LS; rho, rR, rL, B from one distance
  obsan calibrate data/sim --plot figs             # Figures 5-7 per trajectory (PNG, SVG)

--json prints {method, params (name -> {value, sd}), metric, trajectories, sigma_beta,
sigma_beta_estimated, encoder_noise ({route: stated | estimated | bearings_only, k, c,
samples}, or null for methods other than ml), ml, exact}.")]
    Calibrate(CalibrateArgs),
    /// The Cramér–Rao lower bound of phi, psi, eta, delta, xi for a simulated
    /// set-up (the simulate flags) or a measured dataset (at its ML estimate).
    #[command(after_help = "Examples:
  obsan crlb --bearings 100
  obsan crlb data/sim --json

--json prints {setup, bearings, crlb_sd, crlb_sd_with_encoder_noise}.")]
    Crlb(CrlbArgs),
    /// Monte Carlo runs laid out like the paper's Tables IV-VII, beside the
    /// paper's figures and the Cramér–Rao bound.
    #[command(after_help = "Examples:
  obsan montecarlo --table 5 --runs 100
  obsan montecarlo --table 5 --cell 3 --runs 100     # one cell: iota = 0.04, sigma_beta = 1 deg
  obsan montecarlo --table 4 --runs 20 --threads 2 --json

A sweep in shards, on any batch system (docs/montecarlo.md: Slurm, Dask); the merge is bit for
bit the table one run gives, since run r always uses seed + r:
  for k in 1 2 3; do obsan montecarlo --table 5 --shard $k/3 --json > part$k.json; done
  then: obsan montecarlo merge part1.json part2.json part3.json

--json prints a list of tables {table, title, columns, runs, seed, cells}, each cell {cell,
label, paper, methods (mean_abs_error, rms_error, mean_estimate, failures, first_failure per
method), crlb_sd, crlb_sd_with_encoder_noise}; with --shard, a partial result instead (every
run's values as IEEE-754 bits) for `obsan montecarlo merge`. The run time goes to stderr.")]
    Montecarlo(MontecarloArgs),
    /// Where a model and measured data disagree: fit the model, test the
    /// residuals, try each candidate effect the data can reveal (rank test
    /// first), name the significant ones.
    #[command(after_help = "Examples:
  obsan diagnose --model systems/calib.sys --data data/sim
  obsan diagnose --model systems/calib.sys --data data/sim --report data/report
  obsan diagnose --model systems/mrclam.sys --data data/mrclam1 --json

--json prints {model, nominal, rounds, named, suggested, combinations, competing, input_checks, final_fit,
extended_sys, sigma, input_noise, lr_critical, lr_critical_generated, generated_dropped,
screen_threshold, ...};
candidates and named effects carry origin (\"effects file\", \"generated\", \"input
relation\"), generated candidates their score and screened_out, every candidate moved (its
fit left its start), joint_levels (weighed at levels estimated with it) and structure (the
residual tests its fit leaves, [test, z]), candidates that rewrite angle
outputs their heading-free check common_mode {applies, note, full, differences, z, limit,
vetoed, ...}, named effects their correlations with the final fit's other params at |r| >= 0.9
correlated [{param, with, with_effect, r}]; pairs fixed only in combination (two named effects,
or two suggested ones fitted together) are combinations [{params, effects, values, sds, r,
robust_covariance, weight, estimate, sd, robust_sd, wald_z, wald_z_alone, named, established}]:
params[0] + weight params[1], the smallest-variance direction of the pair. A generated winner
fitted together with a competing file candidate is in competing [{round, effects, lr_alone,
estimates, robust_sd, wald_z, wald_z_critical, structure, established}] (established null: neither
named, competing explanations not separated by these data). Candidates generated from the model's structure are
tried too (--no-generated: the effects file's alone). --report writes report.md (verdict, estimates,
residuals pooled per output before and after, candidate scores), PNG and SVG charts, extended.sys
and diagnosis.json (docs/diagnose.md).")]
    Diagnose(DiagnoseArgs),
    /// Convert an external data set into the obsan data format.
    #[command(
        subcommand,
        after_help = "Examples:
  obsan import mrclam ../shared/data/mrclam --robot 1 --out data/mrclam1

Each format is a subcommand (obsan import mrclam --help); none has --json: the dataset is
written to --out and a one-line summary to stdout."
    )]
    Import(ImportCommand),
    /// Global identifiability: for each param and initial state, globally
    /// identifiable, locally with k values, or not identifiable; the number of
    /// (params, initial states) giving the output of a generic one; the
    /// discrete symmetries (signed permutations) between them, each checked
    /// exactly. SIAN's route: Taylor coefficients of the outputs, a Gröbner
    /// basis over F_p at a random point (docs/engine.md).
    #[command(after_help = "Examples:
  obsan global systems/global/squared_rate.sys    # a: 2 values (a -> -a); x global
  obsan global systems/global/two_decays.sys      # every variable 2 values: the swap
  obsan global systems/classic/hiv.sys --json
  obsan global systems/global/angle_mod_pi.sys   # theta: 2 values (known modulo pi only)

Counts are over the complex numbers, as SIAN and StructuralIdentifiability.jl count; two
independent random points modulo two primes must agree. Rational models, and sin/cos of a
state or param (an angle, counted modulo 2 pi through tan(theta/2)); no atan/exp/log/sqrt.
--json prints {system, restriction, variables: [{name, kind (param | state), angle,
verdict (global | local | not identifiable), values}], solutions, all_local, maps, group_order,
order, rank_order, output_orders: [{output, order}], error_bound, degree_bound_local,
log10_degree_bound_global, unknowns, equations, primes, exact: false, method}.")]
    Global(GlobalArgs),
    /// Which sensor, which trajectory: the minimal sets of candidate outputs
    /// (by count, then cost) that make the system (or --target) observable,
    /// each with the symmetries it breaks; and which input families
    /// (restrictions) make everything observable, alone or combined.
    #[command(after_help = "Examples:
  obsan design systems/vins.sys --candidates systems/design/vins_sensors.cand
  obsan design systems/vins.sys --candidates systems/design/vins_sensors.cand --target rx,ry,rz
  obsan design systems/calib.sys                  # input families: circles alone never, 3 yes
  obsan design systems/design/c2m_inputs.sys      # constant input never, a ramp yes

A candidates file holds `candidate NAME [cost C]` lines, each followed by the `output`
statements of that sensor (docs/experiments.md). Without --candidates (or with --families)
the input families are compared. --json prints {system, restriction, sensors: {state, n,
outputs, base_rank, base_unobservable_variables, all_rank, target, already, reachable,
symmetries, symmetry_note, candidates: [{name, cost, outputs, rank, breaks}], sets:
[{candidates, count, cost, rank, n, exact, error_bound, breaks, unobservable_variables}],
subsets_screened, complete_to_size, exhaustive, error_bound} | null, inputs: {families:
[{restriction, single_rank, single_n, single_full, experiments, rank, n, full}], combinations:
[{families, rank, n}], combinations_tried, combinations_complete, error_bound} | null, seed}
(obsan schema design).")]
    Design(DesignArgs),
    /// The JSON Schema of a command's --json output (docs/json.md), derived from the types
    /// that print it; the field descriptions are the schema's.
    #[command(after_help = "Examples:
  obsan schema --list               # the commands with a schema, and those not yet typed
  obsan schema calibrate            # what `obsan calibrate DATASET --json` prints
  obsan schema rank-known           # obsan rank --known ... --json
  obsan schema --markdown           # docs/json.md")]
    Schema(SchemaArgs),
}

#[derive(Args)]
pub struct SchemaArgs {
    /// The command (as `obsan schema --list` names it).
    #[arg(required_unless_present_any = ["list", "markdown"])]
    pub command: Option<String>,
    /// List the commands with a schema, and those without one yet.
    #[arg(long, conflicts_with_all = ["command", "markdown"])]
    pub list: bool,
    /// Print docs/json.md: every schema as tables.
    #[arg(long, conflicts_with = "command")]
    pub markdown: bool,
}

#[derive(Args)]
pub struct GlobalArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

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

x'(t) = EXPR makes x a state, y(t) = EXPR an output, another u(t) an input, a bare name a
parameter; set_parameter_values(ode, Dict(p => QQ(1, 2))) values are substituted. The .sys is
read back before it is written: a model outside obsan's class (not affine in its inputs) is
refused at its equation's line in the source, exit 2. --all writes every model that converts
and exits 2 if any was refused.")]
    SiJl(SiJlArgs),
    /// An SBML model (Level 2 or 3 core) to .sys: species changed by reactions as states,
    /// rate laws as their equations, compartments folded in, parameters unknown
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import sbml model.xml                        (.sys text to stdout; every state measured)
  obsan import sbml model.xml --observe S1,S2 --out model.sys
  obsan import sbml model.xml --out model.sys --values model.values

Assignment rules are substituted and function definitions inlined; events, algebraic rules,
delays, time, piecewise and varying compartments are refused naming the element and its line,
exit 2.")]
    Sbml(SbmlArgs),
    /// A PEtab v1 problem (YAML, SBML model, tables) to .sys: observables as outputs,
    /// estimated parameters as params, fixed ones as consts, one model copy per condition
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import petab problem.yaml                    (.sys text to stdout)
  obsan import petab problem.yaml --condition c1 --out model.sys

Errors name the file (YAML, SBML or table), line and column, exit 2.")]
    Petab(PetabArgs),
    /// A STRIKE-GOLDD model file (z_create_NAME.m: MATLAB syms with x, p, u, w, f, h) to .sys
    /// (docs/import.md).
    #[command(after_help = "Examples:
  obsan import strike-goldd z_create_model.m                (.sys text to stdout)
  obsan import strike-goldd z_create_model.m --out model.sys

x are the states, p the unknown parameters, u the known inputs, w the unknown inputs, f the
dynamics and h the outputs (y1, y2, ...); other assignments are substituted where used.")]
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
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
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

/// `obsan simulate MODEL.sys`: values, constant inputs and the output times.
#[derive(Args, Clone)]
pub struct SysSimFlags {
    /// Values of params and initial states, one `name = value` a line (`import sbml --values`).
    #[arg(long, requires = "model")]
    pub values: Option<String>,
    /// A param (or known constant) value NAME=VALUE (over --values).
    #[arg(long = "set", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub set: Vec<String>,
    /// An initial state NAME=VALUE (over --values).
    #[arg(long = "init", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub init: Vec<String>,
    /// A constant input NAME=VALUE (every input of the model needs one).
    #[arg(long = "input", value_name = "NAME=VALUE", allow_hyphen_values = true)]
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
    /// Wheel-speed ratios, one circular trajectory each (eq. 17); at most 100.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0.9,0,-1",
        allow_hyphen_values = true
    )]
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

impl Command {
    /// The engine's term budget of the commands that do exact symbolic work
    /// on user text; `None` for the others (estimation).
    pub fn max_terms(&self) -> Option<usize> {
        match self {
            Command::Rank(a) => Some(a.an.max_terms),
            Command::Symmetries(a) => Some(a.an.max_terms),
            Command::Check(a) => Some(a.an.max_terms),
            Command::Verify(a) => Some(a.an.max_terms),
            Command::Simplify(a) => Some(a.limit.max_terms),
            Command::Diff(a) => Some(a.limit.max_terms),
            Command::Show(a) => Some(a.limit.max_terms),
            Command::Lie(a) => Some(a.limit.max_terms),
            Command::Modes(a) => Some(a.max_terms),
            Command::Global(a) => Some(a.an.max_terms),
            Command::Design(a) => Some(a.max_terms),
            _ => None,
        }
    }

    /// The `--timeout` of the commands that take one.
    pub fn timeout(&self) -> Option<f64> {
        match self {
            Command::Rank(a) => a.an.timeout,
            Command::Symmetries(a) => Some(a.timeout()),
            Command::Check(a) => a.an.timeout,
            Command::Verify(a) => a.an.timeout,
            Command::Modes(a) => a.timeout,
            Command::Simplify(a) => a.limit.timeout,
            Command::Diff(a) => a.limit.timeout,
            Command::Show(a) => a.limit.timeout,
            Command::Lie(a) => a.limit.timeout,
            Command::Simulate(a) => a.timeout,
            Command::Calibrate(a) => a.timeout,
            Command::Crlb(a) => a.timeout,
            Command::Montecarlo(a) => a.timeout,
            Command::Diagnose(a) => a.timeout,
            Command::Import(ImportCommand::Mrclam(a)) => a.timeout,
            Command::Global(a) => a.an.timeout,
            Command::Design(a) => a.timeout,
            _ => None,
        }
    }
}

/// Options of the analysis commands.
#[derive(Args, Clone)]
pub struct AnalysisArgs {
    /// Seed of the random evaluation points (same seed, same answer).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Largest polynomial (terms) the engine may build before it stops with
    /// "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
}

/// The time limit of the commands that do exact work but take no analysis options.
#[derive(Args, Clone)]
pub struct LimitArgs {
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Largest polynomial (terms) the engine may build before it stops with
    /// "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
}

/// A `--timeout` value: finite, 0 (give up at once) to a year (a Duration must hold it).
fn seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (0.0..=3.2e7).contains(&v) => Ok(v),
        _ => Err(format!(
            "'{s}' is not a number of seconds between 0 and 3.2e7 (a year)"
        )),
    }
}

#[derive(Args)]
pub struct RankArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// With unknown inputs: the highest output derivative order examined
    /// (default: the state dimension + 1).
    #[arg(long, value_name = "M")]
    pub order: Option<usize>,
    /// A state whose initial value is known, e.g. `--known S=0`: the rank in
    /// the other unknowns with every Lie derivative evaluated at that value
    /// (docs/experiments.md). In several experiments `S` means every copy,
    /// `S@2` one.
    #[arg(long = "known", value_name = "NAME=VALUE", value_delimiter = ',')]
    pub known: Vec<String>,
    /// A state whose initial value is known but generic (comma-separated or repeated).
    #[arg(long = "known-generic", value_name = "NAME", value_delimiter = ',')]
    pub known_generic: Vec<String>,
    /// With --known: evaluate every Lie derivative up to this order at the point.
    #[arg(long = "known-order", value_name = "K", default_value_t = 12)]
    pub known_order: usize,
    /// Observability along a dataset (docs/experiments.md): window by window,
    /// the numerical rank at the recorded truth's states with the recorded
    /// inputs, and the degenerate stretches with the symmetries they match.
    #[arg(long = "along", value_name = "DATASET")]
    pub along: Option<String>,
    /// With --along: the window length in seconds.
    #[arg(
        long = "window",
        value_name = "SECONDS",
        default_value_t = 10.0,
        requires = "along"
    )]
    pub window: f64,
    /// With --along: the states and params to start each trajectory from, a
    /// JSON file shaped like truth.json (default: DATASET/truth.json).
    #[arg(long = "truth", value_name = "FILE", requires = "along")]
    pub truth: Option<String>,
}

#[derive(Args)]
pub struct SymArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Always take the exact route (canonical forms and the exact closure
    /// check), however long it takes, instead of reconstruction.
    #[arg(long)]
    pub exact: bool,
}

impl SymArgs {
    /// Symmetries stop after 60 s unless told otherwise.
    pub fn timeout(&self) -> f64 {
        self.an.timeout.unwrap_or(60.0)
    }
}

#[derive(Args)]
pub struct LieArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// Highest order (all words of every order up to it).
    #[arg(long)]
    pub order: usize,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct CheckArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// A candidate observable mode (repeat the flag for several).
    #[arg(
        long = "mode",
        value_name = "EXPR",
        required = true,
        allow_hyphen_values = true
    )]
    pub modes: Vec<String>,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Compute the symmetries by the exact route (canonical forms and the
    /// exact closure check), however long it takes, instead of the default.
    #[arg(long)]
    pub exact: bool,
}

#[derive(Args)]
pub struct ModesArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// Seed of the random evaluation points (same seed, same answer).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Write PREFIX.sys (the reduced system) and PREFIX.dec (its decomposition file).
    #[arg(long = "out", value_name = "PREFIX")]
    pub out_prefix: Option<String>,
    /// Largest polynomial (terms) the engine may build before it stops with
    /// "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Replace existing PREFIX.sys / PREFIX.dec.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct VerifyArgs {
    /// A decomposition file (docs/decomposition-format.md).
    pub file: String,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Compute the symmetries by the exact route (canonical forms and the
    /// exact closure check), however long it takes, instead of the default.
    #[arg(long)]
    pub exact: bool,
}

/// Options shared by every command that reads a system.
#[derive(Args, Clone)]
pub struct SystemArgs {
    /// A system description in the .sys format.
    pub system: String,
    /// Apply the named input restriction declared in the file (e.g. `q`).
    #[arg(long = "input", value_name = "NAME")]
    pub restriction: Option<String>,
    /// Give a known constant a value, e.g. `--set q=0.9` (others stay generic).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// One of several experiments (repeat): `RESTRICTION: c=VALUE, ...`, e.g.
    /// `--experiment 'q: q=0.9'`; an empty restriction is none. Each has its own
    /// states (`x@1`, `x@2` ...); params are shared (docs/experiments.md).
    #[arg(
        long = "experiment",
        value_name = "SPEC",
        conflicts_with = "restriction"
    )]
    pub experiment: Vec<String>,
    /// Experiments from a file, one SPEC a line (`#` comments); or `auto`
    /// (obsan rank): the smallest number of generic experiments that identifies
    /// all it can, under --input's restriction or none.
    #[arg(long = "experiments", value_name = "FILE|auto")]
    pub experiments: Option<String>,
}

#[derive(Args)]
pub struct OutputArgs {
    /// Machine-readable JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Formulas as LaTeX.
    #[arg(long, conflicts_with = "json")]
    pub latex: bool,
}

#[derive(Args)]
pub struct ShowArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct ExprArgs {
    /// An expression, e.g. 'sin(x)^2 + cos(x)^2' (a leading '-' is part of it).
    #[arg(allow_hyphen_values = true)]
    pub expr: String,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct DiffArgs {
    /// An expression (a leading '-' is part of it).
    #[arg(allow_hyphen_values = true)]
    pub expr: String,
    /// The symbol to differentiate by.
    pub var: String,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct DesignArgs {
    /// A system description in the .sys format.
    pub system: String,
    /// Candidate sensors: `candidate NAME [cost C]` lines, each followed by
    /// `output` statements (docs/experiments.md).
    #[arg(long, value_name = "FILE")]
    pub candidates: Option<String>,
    /// The variables the added sensors must make observable (default: all).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub target: Vec<String>,
    /// Compare the input families (restrictions) too when --candidates is given.
    #[arg(long)]
    pub families: bool,
    /// Sensors under this input restriction of the model.
    #[arg(long = "input", value_name = "NAME")]
    pub restriction: Option<String>,
    /// Give a known constant a value, e.g. `--set q=0.9`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Screen at most this many subsets of candidates.
    #[arg(long, value_name = "N", default_value_t = 1 << 20)]
    pub max_subsets: usize,
    /// Seed of the random evaluation points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Largest polynomial (terms) the engine may build.
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Machine-readable JSON on stdout.
    #[arg(long)]
    pub json: bool,
}
