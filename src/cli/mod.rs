//! Command-line arguments: the commands and their help here, each group's options in
//! analysis.rs (the exact commands), estimate.rs (data and estimation), import.rs.

mod analysis;
mod estimate;
mod import;

pub use analysis::{
    AnalysisArgs, CheckArgs, DesignArgs, DiffArgs, ExprArgs, GlobalArgs, LieArgs, LimitArgs,
    ModesArgs, OutputArgs, RankArgs, SchemaArgs, ShowArgs, SymArgs, SystemArgs, VerifyArgs,
};
pub use estimate::{
    CalibrateArgs, CrlbArgs, DiagnoseArgs, MergeArgs, MontecarloArgs, MontecarloCommand, SimFlags,
    SimulateArgs,
};
pub use import::{ImportCommand, MrclamArgs, PetabArgs, SbmlArgs, SiJlArgs, StrikeGolddArgs};

use clap::{Parser, Subcommand};

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
stacked experiments, or null), measured_inputs (the known inputs outputs read: measured, their
derivatives known, left out of state, n and rank; docs/sys-format.md), roots_field_degree (k when
the roots took their values in the field of p^k elements, no point mod p satisfying their
relations; else null)}. --known/--known-generic and --experiments auto print their own
objects (docs/experiments.md). With unknown inputs, --json prints {system, restriction, state,
unknown_inputs, n, rank, weakly_locally_observable, decided, undecided_atoms,
observable_variables ([{name, order}]: the lowest output derivative order that shows each),
unobservable_variables, reconstructable_inputs ([{name, order}]), unreconstructable_inputs, steps,
max_order, converged, agree, martinelli (Martinelli's algorithm's proven verdicts), complete,
basis, evaluated, error_bound, degree_bound, seed, roots_field_degree (k when no point mod p
satisfies the roots' relations and every decision taken at free root values was proven in the
field of p^k elements; else null)} (docs/engine.md). A model may use time
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
reconstructable_inputs, exact, certificate (unknown_input_invariance), identities, made_states
(the unknown inputs an output holds: made states for the certificate), input_dependent (the
vectors move with the known inputs), input_jets (the known inputs' jets the components hold: u' the derivative of u),
error_bound (of the rank test for the observable ones), seed}.")]
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
certified them. Exit 1 when a check fails. With unknown inputs the checks run against the
certified unknown-input symmetries, plus one per unknown input the reduced dynamics need: it
must be reconstructable.")]
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
Exit 1 when the reduced system could not be closed or a check failed.

A model with unknown inputs (obsan modes systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys)
gets the first integrals of its certified symmetries as modes and a reduced system driven by the
known inputs and the reconstructable unknown inputs, or combinations factor*w of them
(docs/engine.md, \"Modes with unknown inputs\"); exit 2 naming the mode and the input when it
would need one that is not reconstructable. When the symmetries move with the known inputs
(cstr_observer.sys: u3, u3' in them) the modes are functions of the state and those jets, and
the reduced system reads the inputs' time derivatives (u3', u3'': reduced.inputs; no files
written). With unknown inputs --json prints {system,
restriction, n, rank, full_rank, unknown_inputs, symmetries, modes, reduced (null at full rank),
reduced_inputs ([{name, input, factor (null: the input itself), offset (drift and known-input
terms added), mode, order (of the output
derivatives it is recovered from; null for a combination)}]), verified, checks, certificate,
error_bound (of the rank test the modes' count rests on), seed, decided, undecided_atoms, sys,
dec}.")]
    Modes(ModesArgs),
    /// Simulate the paper's calibration experiment (section VI-A) and write a dataset, or
    /// integrate any MODEL.sys from given values.
    #[command(after_help = "Examples:
  obsan simulate --out data/sim                              # section VI-A, q = 0.9, 0, -1
  obsan simulate --out data/sim2 --set q=0.5,-0.5 --seed 7 --effect bearing_scale=0.04
  obsan simulate --out data/sine --speed-profile sine:0.5:60
  obsan simulate systems/classic/lotka_volterra.sys --set a=1 --set b=0.5 --set c=1 --set d=0.2 --init x=4 --init y=2 --until 5 --every 1 --json
  obsan simulate systems/classic/two_compartment.sys --set k01=0.1 --set k02=0 --set k12=0.2 --set k21=0.3 --init x1=1 --init x2=0 --input u=0 --until 10 --every 0.5 --out data/two.csv
  obsan simulate systems/classic/two_compartment.sys --set k01=0.1 --set k02=0 --set k12=0.2 --set k21=0.3 --init x1=1 --init x2=0 --input 'u=1+sin(t)' --until 10 --every 0.5
  obsan simulate systems/classic/two_compartment.sys --set k01=0.1 --set k02=0 --set k12=0.2 --set k21=0.3 --init x1=0 --init x2=0 --inputs systems/classic/two_compartment_dose.csv --until 10 --every 0.5

Without MODEL: writes dataset.json, one folder per trajectory (inputs.csv, outputs.csv,
meta.json) and truth.json; --force replaces only a folder obsan wrote.
With MODEL (values from --values FILE, as import sbml --values writes, and the flags over it):
prints (or writes to --out FILE.csv) the CSV time,<states>,<outputs> at
0, DT, 2 DT, ... up to T (at most 1000000 rows), integrated by RK4 with step doubling
until the estimated error of every value is within 1e-9 (|value| + 1).
Explicit time t in the model, --input u=EXPR of t and --inputs FILE.csv (header t,<inputs>,
rows in increasing t, linear between rows, two rows at one t a step) are evaluated at every
RK4 stage time; the integrator stops at every row time of the file, so a step is not smeared.
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
  obsan crlb --set q=0.9,0 --bearings 100            # two circles instead of the paper's three
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

--json prints {model, start, sigma, sigma_estimated, input_noise, input_noise_source,
input_noise_lr, input_class, nominal, nominal_converged, refits, rounds, named, suggested,
combinations, competing, input_checks, final_fit, hidden, extended_sys, lr_critical, lr_critical_generated,
generated_dropped, screen_threshold, relevels} (every field: obsan schema diagnose; a float that cannot be
formed, such as a robust sd on one trajectory, is null); candidates and named effects carry origin (\"effects file\", \"generated\", \"input
relation\"), generated candidates their score and screened_out, every candidate moved (its
fit left its start), joint_levels (weighed at levels estimated with it) and structure (the
residual tests its fit leaves, [test, z]), candidates that rewrite angle
outputs their heading-free check common_mode {applies, note, full, differences, z, limit,
vetoed, ...}, named effects their correlations with the final fit's other params at |r| >= 0.9
correlated [{param, with, with_effect, r}] and stand_in (the outputs the effect rewrites still curve
in their predicted value: it stands in for an effect of another form) with that test's curvature
{outputs, n, span, coefficient, sd, z, correlation_factor}; pairs fixed only in combination (two named effects,
or two suggested ones fitted together) are combinations [{params, effects, values, sds, r,
robust_covariance, weight, estimate, sd, robust_sd, wald_z, wald_z_alone, named, established}]:
params[0] + weight params[1], the smallest-variance direction of the pair. A generated winner
fitted together with a competing file candidate is in competing [{round, effects, lr_alone,
estimates, robust_sd, wald_z, wald_z_critical, structure, established, named_form}] (established null:
not separated by these data; named_form: each significant alone, one effect in two forms, the
stronger together named and the search goes on, else neither named). Candidates generated from the model's structure are
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
    /// discrete symmetries between them (signed permutations, and angles
    /// mapped by theta -> phi, -phi, phi + pi or pi - phi), each checked
    /// exactly. SIAN's route: Taylor coefficients of the outputs, a Gröbner
    /// basis over F_p at a random point (docs/engine.md).
    #[command(after_help = "Examples:
  obsan global systems/global/squared_rate.sys    # a: 2 values (a -> -a); x global
  obsan global systems/global/two_decays.sys      # every variable 2 values: the swap
  obsan global systems/classic/hiv.sys --json
  obsan global systems/global/angle_mod_pi.sys   # theta: 2 values (known modulo pi only)
  obsan global systems/global/forced_oscillator_offset.sys --multi-experiment
                                                  # b, c global over several experiments

Counts are over the complex numbers, as SIAN and StructuralIdentifiability.jl count; two
independent random points modulo two primes must agree. Rational models, and sin/cos of a
state or param (an angle, counted modulo 2 pi through tan(theta/2)); no atan/exp/log/sqrt.
Memory: the Taylor system, the Gröbner basis and its F4 matrices may hold 2048 bytes per
--max-terms unit (about 195 MiB by default); past it, exit 2 with the stage named ('too large:
the Groebner basis (F4 matrix of R rows x C columns) would need ...; raise it with --max-terms')
unless --route auto (the default) answers by the input-output relations (the parameters; then
the initial states by the Taylor route with the params they found global known:
states_after_io), else by the Lie route, with the reason in `fallback` (--route io, --route lie: that route
alone; --route taylor: SIAN's alone). The Lie route (docs/engine.md) equates the outputs'
iterated Lie derivatives along the drift and each input's field: parameters and initial
states indistinguishable for every input (Hermann-Krener, the paper's notion); without inputs
the same question as one experiment, with inputs one generic experiment may leave more values.
Outputs through sqrt or atan are counted through their argument; an angle output (an atan2
bearing) through its tangent, modulo pi: a count above 1 is then 'at most' unless the maps'
signs on the angle settle it.
One experiment is counted; --multi-experiment counts the params over enough independent
experiments (each from its own generic initial state; SI.jl's multi-experiment
identifiability) by the input-output relations, also where a relation's monomials are
dependent along an output (a zero Wronskian: one experiment does not fix its coefficients,
and --route io refuses); multi_experiment says whether the counts are of that kind only.
--json prints {system, restriction, variables: [{name, kind (param | state), angle,
verdict (global | local | not identifiable), values, at_most}], solutions, solutions_at_most,
all_local, maps, maps_modulo_pi, maps_of_parameters, group_order, order, rank_order,
output_forms: [{output, counted_as}], output_orders: [{output, order}], error_bound,
degree_bound_local, log10_degree_bound_global, unknowns, equations, primes, exact: false,
method, route (taylor | input-output | lie), fallback, multi_experiment, states_after_io:
{counted, fixed_params, output_orders, unknowns, equations, error_bound, why_not} or null}.")]
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
            // An imported model is checked by building its normal form.
            Command::Import(ImportCommand::Sbml(a)) => Some(a.max_terms),
            Command::Import(ImportCommand::Petab(a)) => Some(a.max_terms),
            // With --all one model past the budget must not stop the others: a
            // tripped thread budget holds for the rest of its scope, so each
            // model's check keeps its own (the normal form's, the default).
            Command::Import(ImportCommand::SiJl(a)) if a.all.is_none() => Some(a.max_terms),
            Command::Import(ImportCommand::StrikeGoldd(a)) => Some(a.max_terms),
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

/// A `--timeout` value: finite, 0 (give up at once) to a year (a Duration must hold it).
pub(crate) fn seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (0.0..=3.2e7).contains(&v) => Ok(v),
        _ => Err(format!(
            "'{s}' is not a number of seconds between 0 and 3.2e7 (a year)"
        )),
    }
}

/// The one deadline of a command given `--timeout secs`, from the instant it
/// started: every stage (rank test, symmetries, modes) polls this same
/// instant, so the whole command stops at `--timeout`, not each stage at its
/// own; the watchdog of lib.rs waits one more second for the message.
pub fn deadline_after(start: std::time::Instant, secs: Option<f64>) -> Option<std::time::Instant> {
    secs.map(|s| start + std::time::Duration::from_secs_f64(s.max(0.0)))
}
