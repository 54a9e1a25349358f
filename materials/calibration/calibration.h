// Compare, calibrate, diagnose: the material model against a measurement file.
//
//   compare    simulates every experiment with replicas (different seeds, so different packings)
//              and forms one normalised residual per observation,
//                r = (simulated mean - measured) / sqrt(sigma_measured^2 + sigma_simulated^2),
//              sigma_simulated being the standard error of the replica mean, and at least the
//              runs' own extraction errors (SimulatedOutcome::uncertainty: the fitted heap angle's)
//              divided by sqrt(replicas): two replicas that agree by chance do not make a noisy
//              observable look sure. Outcomes (blocked,
//              no_heap, slipping) are observations: a mismatch is a residual of
//              outcome_residual x |measured fraction - simulated fraction| (3 sigma by default).
//              Residuals of one test are regressed on the set-up quantity varied across its
//              experiments (constant, linear, quadratic) to name the pattern of the misfit.
//   calibrate  fits parameters inside their ranges through a surrogate: a Latin hypercube design
//              (fixed seed) in the parameter box, one simulation of every experiment per point
//              (common random numbers: the same packing seed at every point), a quadratic
//              response surface per observation fitted by least squares, chi^2 of the surrogate
//              minimised with NLopt (BOBYQA) from several starts, a second, smaller box around
//              that optimum, and finally real simulations (with replicas) at the optimum.
//              Uncertainty from the surrogate's Jacobian J at the optimum: cov = (J^T W J)^-1,
//              W = diag(1/sigma^2); identifiability from the eigenvalues of J^T W J in
//              range-normalised coordinates.
//   diagnose   calibrates the model as it is, then for every effect it lacks measures the
//              effect's signature (change of each observation, in sigma, when added at a moderate
//              strength) and the fraction of the remaining chi^2 a least-squares multiple of it
//              could remove (signature made orthogonal to what the fitted parameters can already
//              do); the leading two are confirmed by adding each and recalibrating, and ranked
//              by BIC = chi^2 + k ln n.
//
// The simulator is a std::function, so tests replace the DEM virtual tests by analytic
// stand-ins with known answers.
#pragma once

#include <Eigen/Dense>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/material_model.h"
#include "lab/measurements.h"
#include "lab/virtual_tests.h"
#include "lab/yield_locus.h"

namespace dem::materials {

/// Runs one virtual test; the default is run_virtual_test.
using Simulator = std::function<SimulatedOutcome(const MaterialModel&, const TestSetup&, const TestOptions&)>;

/// One simulation of a batch: its outcome, or the error that stopped it.
struct BatchOutcome {
  enum class Error { none, not_run, input, numerical, other };
  Error error = Error::not_run;  ///< input: CaseError; numerical: NumericalError; other: any other exception
  std::string message;           ///< what() of the error
  SimulatedOutcome outcome;      ///< when error is none
  bool stored = false;           ///< taken from the simulation store (CalibrationOptions::store), not run
};

/// Runs the independent simulations 0..count-1 of one batch (a design round, the replicas of a
/// comparison) and returns their outcomes in order. `simulate(k)` runs simulation k and never
/// throws; `done(k, outcome)` is called as each outcome becomes known (for progress lines).
/// After an outcome for which `fatal` is true, a runner may leave later simulations not_run:
/// the caller throws the first fatal error in batch order, so the outcome equals the serial one.
/// The default (empty) runs them one after the other in this process; the app's MPI runner
/// (app/campaign/mpi_campaign.h) shares them among ranks and gives every rank every outcome.
using BatchRunner = std::function<std::vector<BatchOutcome>(size_t count, const std::function<BatchOutcome(size_t)>& simulate,
                                                            const std::function<void(size_t, const BatchOutcome&)>& done,
                                                            const std::function<bool(const BatchOutcome&)>& fatal)>;

struct Diagnosis;

namespace detail {
struct CommandContext;  // calibration_support.h
}

/// What shrinking the apparatus does to one observation (term `experiment/observable`), measured
/// once, at the start values: the full-size mean minus the shrunk mean, and the standard error of
/// that difference (both means' standard errors combined).
struct SizeShift {
  double shift = 0;
  double sigma = 0;
};

struct CalibrationOptions {
  Simulator simulator;          ///< empty: run_virtual_test
  BatchRunner batch;            ///< empty: simulations of a batch one after the other, in this process
  int replicas = 3;             ///< packings per experiment when comparing (>= 2 measures the noise)
  /// Packings a comparison may give an experiment where its verdict depends on them: when chi^2/n
  /// lies between fits_within_noise and 4 x it (and chi^2 at most no_rival_above_chi2), each
  /// experiment with a term beyond 2 sigma whose packings scatter gets one more packing at a
  /// time, up to this many (compare()). A mean of two
  /// packings that happen to agree can sit far from the model's own mean (a hopper near its
  /// arching limit scatters by 20 %). At most `replicas`: none are added.
  int most_replicas = 6;
  double size_factor = 1.0;     ///< passed to the virtual tests
  /// Per term name, the shift that takes a simulation at size_factor < 1 to the full-size
  /// apparatus of the measurements: added to each of its replicas' values, its sigma added to the
  /// term's simulation noise (compare_runs). Empty, or size_factor 1: nothing is added (the
  /// measurements are then of the apparatus as simulated). A diagnosis that shrinks the apparatus
  /// to fit its budget measures it (diagnose()).
  std::map<std::string, SizeShift> size_shift;
  /// diagnose with size_factor < 1: the measurements are of the full-size apparatus; the model as
  /// it is is compared at both sizes first and the shrinking corrected (size_shift), and the
  /// model named is compared at full size. false: the measurements are of the apparatus as
  /// shrunk (synthetic data made at that size), nothing is corrected.
  bool correct_size = true;
  double rayleigh_fraction = 0; ///< the virtual tests' time step (TestOptions); 0: their rule
  int threads = 0;              ///< OpenMP threads of each simulation; 0: default (1 when parallel > 1)
  /// Simulations of a batch run at once in this process when no `batch` runner is set, each on
  /// its own thread with `threads` OpenMP threads (1 by default): the small apparatus of the lab
  /// tests keep one core busy each far better than they use two. Outcomes do not depend on it.
  int parallel = 1;
  /// Folder of the simulation store (simulation_store.h): every finished simulation is kept there
  /// and one whose inputs match a kept one is not run again. Empty: nothing is kept. Only the
  /// engine's own virtual tests are stored (not a `simulator` stand-in).
  std::string store;
  std::uint64_t seed = 1;       ///< first packing seed; the design uses this one
  int design_points = 0;        ///< per round; 0: from design_factor
  /// Design points per round when design_points is 0: max(b + 1, ceil(design_factor x b) + 2),
  /// b the quadratic coefficients (3 for one parameter, 6 for two). Below 2 for fast screening.
  double design_factor = 2.0;
  int rounds = 2;               ///< surrogate rounds; round 2 spans a quarter of each range around round 1's optimum
  /// Rounds added when the confirming simulations miss what the surrogate predicted (chi^2/n
  /// above fits_within_noise and above 2 x predicted + 1) or the optimum lies on an edge of the
  /// box inside the parameter's limit: each spans half the last box around the best point
  /// simulated so far, and is confirmed in turn. The better confirmed point is the result.
  int refine_rounds = 1;
  /// A runner-up of a diagnosis is no rival to the best candidate confirmed so far, either way,
  /// when its chi^2 lies above this: a diagnosis sets it from that one's BIC plus twice
  /// rival_margin. Such a runner-up gets no refinement round (when the surrogate's prediction
  /// lies above it too) and no packings beyond `replicas` in its comparisons (compare()).
  /// Infinity: refine and add packings as above.
  double no_rival_above_chi2 = std::numeric_limits<double>::infinity();
  /// [s on the outermost command's clock (CommandContext)] A refinement round starts only when
  /// it would end before this, at what the calibration's own first round cost a simulation; a
  /// round not started is said, and CalibrationResult::unrefined set. A diagnosis sets it for a
  /// runner-up the screen could rank. Infinity: refine whenever asked.
  double refine_deadline = std::numeric_limits<double>::infinity();
  int refine_before_deadline = 0;  ///< refinement rounds run whatever refine_deadline says (the first ones)
  /// Design factor of a refinement round when below design_factor; 0: design_factor. A diagnosis
  /// gives its runners-up 1 (the quadratic's coefficients and two more): a runner-up's fit only
  /// has to show whether it rivals the leader's. Rejected for the leading confirmation: with
  /// design factor 1 (14 and 16 points for four parameters against 32), epsd on LIGGGHTS rolling
  /// resistance with a guessed liner friction stayed at chi^2/n 2.74 and 2.25 where 32 points
  /// reached 0.93.
  double refine_design_factor = 0;
  int starts = 8;               ///< NLopt starts (best design points and the centre)
  double outcome_residual = 3.0;    ///< [sigma] residual of a mismatched outcome
  double fits_within_noise = 1.5;   ///< chi^2/n at or below which a model fits within the noise
  double bic_margin = 10.0;         ///< an effect is recommended when it lowers BIC by more than this
  /// A confirmed runner-up whose BIC is within this of the recommended effect's is named as a
  /// rival the data cannot rule out (a BIC difference under 6 is not strong evidence: Kass &
  /// Raftery 1995).
  double rival_margin = 6.0;
  int confirm_candidates = 2;       ///< leading candidates confirmed by recalibration
  /// Packings of each signature run (at two strengths per candidate); at most `replicas`.
  int signature_replicas = 2;
  /// Candidates whose explained fractions lie within this of the leader's cannot be told apart by
  /// the screen: all of them are confirmed by recalibration (up to confirm_candidates + 2).
  double screen_margin = 0.1;
  /// When the data cannot tell two candidates apart, simulate both fitted models on variants of the
  /// file's experiments and on standard set-ups of the tests it lacks, and name the experiment
  /// whose predictions lie furthest apart (discrimination.h).
  bool propose_experiments = true;
  double separation_needed = 3.0;  ///< [sigma] a proposed experiment decides when the two predictions lie this far apart
  bool wall_candidates = true;      ///< diagnose also tries the wall parameters the fit leaves out
  /// Before the bulk fit, each particle-wall pair's restitution is fitted to the rebound heights
  /// of the drop tests on that wall alone (walls_first.cpp): a single contact measures it
  /// directly, and a guessed wall restitution would otherwise misfit like missing physics.
  /// Skipped for a pair whose restitution was measured or is among the fitted parameters.
  bool walls_first = true;
  /// [s] wall time the command may take; 0: no limit. After the first comparison (which measures
  /// what a simulation of each experiment costs) the rest is planned to fit: fewer surrogate
  /// rounds and design points, fewer packings, fewer candidates, in that order, and the result
  /// says what was given up (plan_within_budget).
  double budget_seconds = 0;
  /// Candidates diagnose considers: effect names (candidate_names()) and wall parameters
  /// (WALL.KEY); empty: every effect the model lacks and every wall parameter it does not fit.
  std::vector<std::string> effects;
  /// Progress lines (with time left); empty: quiet.
  std::function<void(const std::string&)> progress;
  /// A diagnosis so far, at each stage (the model as it is calibrated, the signatures measured,
  /// each candidate confirmed), so an interrupted diagnosis still shows what it knew; may be empty.
  std::function<void(const Diagnosis&, const std::string& stage)> on_partial;
  /// Final state of every simulation (the app renders the last); may be empty.
  std::function<void(const Model&, const State&)> on_final;
  /// The command these options run in: its count of simulations done and planned, its clock, and
  /// what its simulations cost (detail::CommandContext). Every copy of the options shares it, so
  /// the compare and the calibrations a diagnosis calls count into the diagnosis and use the costs
  /// it measured. Empty (the default): compare, calibrate and diagnose each begin a command of
  /// their own, and two calls share nothing.
  std::shared_ptr<detail::CommandContext> context;
};

// ---- comparison ---------------------------------------------------------------------------

/// One experiment simulated with replicas.
struct ExperimentRun {
  std::string id, test;
  std::map<std::string, double> mean;                  ///< observable -> mean over replicas
  std::map<std::string, double> sigma;                 ///< observable -> standard error of the mean (with one replica: the run's extraction error, else 0)
  std::map<std::string, std::vector<double>> values;   ///< observable -> per replica
  std::map<std::string, std::vector<double>> extraction;  ///< observable -> each replica's own extraction error (when the test gives one)
  std::map<std::string, double> flag_fraction;         ///< outcome flag -> fraction of replicas
  std::vector<std::string> notes;
  int replicas = 0;
  std::int64_t particles = 0;
  double wall_seconds = 0;
};

/// One compared quantity: an observation, or an observed outcome.
struct Term {
  std::string experiment, test, observable;  ///< observable "outcome" for an outcome term
  double measured = 0, sigma_measured = 0;
  double simulated = 0, sigma_simulated = 0;
  double residual = 0;                        ///< normalised, simulated - measured
  std::string measured_outcome, simulated_outcome;  ///< outcome terms: "" when none
  std::string varied;                         ///< the set-up key this test's experiments vary ("" if none)
  double varied_value = 0;
  bool is_outcome() const { return observable == "outcome"; }
  std::string name() const { return experiment + "/" + observable; }
};

/// The misfit pattern of one observable of one test over its experiments.
struct Pattern {
  std::string test, observable, varied;
  std::string kind;   ///< fits, offset, trend, curvature, scatter, single
  int count = 0;
  double mean = 0;    ///< mean residual [sigma]
  // Weighted fits of simulated - measured in the observable's own unit (weights 1/sigma^2):
  double offset = 0;     ///< weighted mean difference
  double slope = 0;      ///< change of the difference from the lowest to the highest varied value (linear fit)
  double at_low = 0, at_high = 0;  ///< the linear fit's difference at the lowest and highest varied value
  double curvature = 0;  ///< quadratic coefficient in normalised x in [-1, 1]
  double chi2 = 0;
  std::string words;
};

struct Comparison {
  std::vector<ExperimentRun> runs;
  std::vector<Term> terms;
  double chi2 = 0;
  int n = 0;
  std::vector<Pattern> patterns;
  std::vector<std::string> notes;  ///< e.g. observations not simulated
  double chi2_per_n() const { return n > 0 ? chi2 / n : 0.0; }
  /// Simulations run for it (every replica of every experiment).
  int simulations() const {
    int s = 0;
    for (const ExperimentRun& r : runs) s += r.replicas;
    return s;
  }
  /// The residual of `experiment/observable`; NaN when absent.
  double residual(const std::string& experiment, const std::string& observable) const;
};

/// Simulates one experiment `replicas` times (seeds options.seed, +1, ...).
ExperimentRun simulate_experiment(const MaterialModel& model, const Experiment& experiment, const CalibrationOptions& options, int replicas);

/// Terms, chi^2 and patterns of simulated runs (one per experiment, in file order).
/// `sigma_floor`: per term name, a simulation noise measured with another model on the same
/// apparatus: the least noise a term is given (the noise of a one-replica run).
Comparison compare_runs(const MeasurementSet& measured, const std::vector<ExperimentRun>& runs, const CalibrationOptions& options,
                        const std::map<std::string, double>& sigma_floor = {});

/// Simulates every experiment with options.replicas replicas and compares; where the verdict
/// depends on it, adds packings up to options.most_replicas (see there).
Comparison compare(const MaterialModel& model, const MeasurementSet& measured, const CalibrationOptions& options);

/// Residual patterns per (test, observable): regression on the varied set-up quantity.
std::vector<Pattern> analyse_patterns(const std::vector<Term>& terms);

/// The yield loci of a comparison's direct shear terms (lab/yield_locus.h): per locus the
/// measured values with sigma_measured and the simulated means with sigma_simulated, on the
/// normal stresses of the experiments' set-ups in `measured`, each fitted and compared in words.
std::vector<LocusComparison> yield_loci(const MeasurementSet& measured, const Comparison& comparison);

// ---- calibration --------------------------------------------------------------------------

struct FitParameter {
  std::string key;
  double min = 0, max = 1;  ///< the box the first round's design spans
  /// The range the fit may leave the box for, when its optimum lies on an edge of the box (NaN:
  /// the box is the range). A diagnosis designs a candidate's first round over the strengths its
  /// signature points to and keeps the effect's whole range as the limit.
  double limit_min = std::numeric_limits<double>::quiet_NaN(), limit_max = std::numeric_limits<double>::quiet_NaN();
  double lowest() const { return std::isnan(limit_min) ? min : limit_min; }
  double highest() const { return std::isnan(limit_max) ? max : limit_max; }
};

/// The model's tunable ranges; with `keys`, only those (each must have a range, from the
/// material file or the effect table's full range). Throws std::invalid_argument naming the key.
std::vector<FitParameter> fit_parameters(const MaterialModel& model, const std::vector<std::string>& keys = {});

/// Quadratic response surfaces, one per numeric term, in x normalised to [-1, 1] over `box`.
/// A point of a parameter space whose simulations were made: parameter values (physical units,
/// in the order of the calibration's parameters) and the simulated value of each term
/// (experiment/observable).
struct SimulatedPoint {
  std::vector<double> x;
  std::map<std::string, double> values;
};

struct Surrogate {
  std::vector<FitParameter> box;
  std::vector<std::string> terms;   ///< term names (experiment/observable)
  Eigen::MatrixXd coefficients;     ///< (terms x basis)
  Eigen::MatrixXd points;           ///< (design points x parameters), physical units
  Eigen::MatrixXd values;           ///< (design points x terms)
  std::vector<double> fit_rms;      ///< per term: RMS of the fit residual, in units of the term's sigma
  /// Per term, the form chosen by leave-one-out error: "linear", "separable" or "quadratic".
  std::vector<std::string> form;
  Eigen::VectorXd predict(const Eigen::VectorXd& x) const;   ///< x physical -> (terms)
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const;  ///< (terms x parameters), physical units
};

/// Fits a surface to each term's values (points x terms) at points (points x parameters): linear,
/// separable quadratic or full quadratic, whichever predicts the left-out points best.
Surrogate fit_surrogate(const std::vector<FitParameter>& box, const std::vector<std::string>& terms, const Eigen::MatrixXd& points,
                        const Eigen::MatrixXd& values, const Eigen::VectorXd& sigma);

/// n points of a Latin hypercube in the box (best of 20 by the smallest distance), fixed seed.
Eigen::MatrixXd latin_hypercube(const std::vector<FitParameter>& box, int n, std::uint64_t seed);

/// A 2-D map of the surrogate (Fig. 5): two observations over two parameters, the others at the fit.
struct ContourMap {
  std::string x_key, y_key;
  std::vector<double> x, y;                 ///< grid axes (physical)
  struct Field {
    std::string term;                       ///< experiment/observable
    std::string label;                      ///< "aor_1 angle_deg"
    double measured = 0, sigma = 0;
    std::vector<std::vector<double>> value; ///< [iy][ix]
  };
  std::vector<Field> fields;
  std::vector<std::vector<double>> chi2;    ///< [iy][ix] surrogate chi^2 of all terms
  double fit_x = 0, fit_y = 0;
};

struct CalibrationResult {
  std::vector<FitParameter> parameters;
  std::vector<double> start, value, sigma;          ///< physical units
  std::vector<std::vector<double>> correlation;
  std::vector<double> eigenvalues;                  ///< of J^T W J in half-range units, ascending
  std::vector<std::vector<double>> eigenvectors;    ///< [k] = direction of eigenvalues[k]
  double condition = 0;                             ///< largest / smallest eigenvalue
  std::vector<std::string> unidentified;            ///< keys the data do not pin down
  /// Keys whose fitted value lies outside its plausible range (plausible_range) or at the edge
  /// of its own: most often the fit absorbing physics the model lacks.
  std::vector<std::string> implausible;
  std::vector<std::string> words;
  Surrogate surrogate;                              ///< of the last round
  double surrogate_chi2 = 0;                        ///< at the optimum
  MaterialModel fitted;
  Comparison before, after;                         ///< real simulations at the start and at the fit
  std::vector<ContourMap> contours;
  /// Every point whose simulations fed a surrogate (design points, confirmations and the known
  /// points it was given), with the simulated value of each numeric term (the mean over packings
  /// for a confirmation).
  std::vector<SimulatedPoint> points;
  int simulations = 0;
  double wall_seconds = 0;
  /// A refinement round was asked for (the simulations missed the surrogate, or the optimum lay
  /// on an edge of its box) and not run: it would have ended past refine_deadline.
  bool unrefined = false;
};

/// What a calibration may take from simulations made before it (a diagnosis's).
struct EarlierPoints {
  /// Points (values of the parameters, physical units) the first round's design takes in place of
  /// as many of its own, where they lie inside the box: points already simulated (a diagnosis's
  /// signature runs) then come from the store (options.store) instead of running again.
  std::vector<std::vector<double>> include;
  /// Points simulated with a model that equals the calibrated one at them (the model without an
  /// effect is the model with it at the strength where it changes nothing): data of every
  /// surrogate whose box holds them, beside the design's own points; nothing is run for them.
  /// Left out when the walls' first stage (CalibrationOptions::walls_first) changes a wall pair's
  /// parameter: they were simulated with the value before.
  std::vector<SimulatedPoint> known;
};

/// Where a fitted value of `key` plausibly lies for this material: its file's `plausible:` range,
/// else its parameter row's (ParamSpec::plausible: dry bulk solids' friction, restitution and
/// rolling friction); none otherwise.
std::optional<std::pair<double, double>> plausible_range(const MaterialModel& model, const std::string& key);
/// Keys of the values out of their plausible range by more than twice their standard error
/// (`sigma`, same order; empty: none known) or at the edge of their tunable range, with the words
/// saying so appended to `words`. A value at an edge whose standard error is a quarter of the range
/// or more is not one of them: the words say the experiments do not determine it.
std::vector<std::string> implausible_fits(const MaterialModel& model, const std::vector<FitParameter>& parameters, const std::vector<double>& values,
                                          const std::vector<double>& sigma, std::vector<std::string>& words);

/// Fits `parameters` (empty: the model's tunable ranges). `before`: an existing comparison of
/// `model` (its simulation noise is reused); nullptr: compared first.
CalibrationResult calibrate(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters,
                            const CalibrationOptions& options, const Comparison* before = nullptr, const EarlierPoints& earlier = {});

/// The Fig. 5 map for parameters px, py of a result, for the two observations whose contours
/// cross most steeply (from different tests when there are).
ContourMap contour_map(const CalibrationResult& result, int px, int py, int grid = 41);

// ---- diagnosis ----------------------------------------------------------------------------

struct CandidateResult {
  std::string name, title, description;
  std::string why;        ///< why its signature fits a misfit (the effect's own words)
  std::string switch_on;  ///< the YAML that switches it on
  std::string kind;       ///< "effect", "shape" or "parameter" (EffectCandidate::kind)
  std::vector<FitParameter> adds;    ///< parameters the effect adds to the fit
  std::vector<double> signature;     ///< per term of the base comparison: change in units of its sigma
  double explained = 0;              ///< fraction of the base chi^2 the signature could remove (the better of its two strengths)
  double explained_start = 0, explained_stronger = 0;  ///< at the start values and at the stronger step
  /// Cosine of the signatures at the two strengths (made orthogonal to the fitted parameters): near 1
  /// when the effect acts linearly, low when the screen cannot be trusted for it.
  double agreement = 1;
  /// Whether the screen's linear share can rank it: its two strengths agree (agreement >= 0.5)
  /// and no outcome (arching, no heap, slipping) flips between the model as it is and its two
  /// strengths. An unstable candidate is ranked by the chi^2 of the runs themselves instead.
  bool stable = true;
  /// chi^2 the screen expects of the candidate after a short recalibration: the fitted parameters
  /// moved linearly to take up what they can (the surrogate's directions), its own strength on
  /// the line through its two signature runs (stable) or at the better of the two (unstable).
  double screen_chi2 = 0;
  double expected_gain = 0;          ///< expected BIC gain: base chi^2 - screen_chi2 - (added parameters) ln n
  double cost = 0;                   ///< [s] what its signature simulations took (wall seconds, one core each)
  int simulations = 0;               ///< how many signature simulations `cost` is the time of
  std::string ranked_why;            ///< why it stands where it is in the ranking
  bool confirmed = false;
  /// Confirmed without the refinement round its surrogate's miss asked for, which would have ended
  /// past the budget: its chi^2 is an upper bound, and as a rival it counts at the surrogate's
  /// prediction when lower.
  bool unrefined = false;
  CalibrationResult fit;             ///< when confirmed
  double chi2 = 0, bic = 0, delta_bic = 0;  ///< confirmed: after recalibration; delta = base BIC - this BIC
  int k = 0;                         ///< fitted parameters
  std::string words;
};

/// An experiment that would separate two models (discrimination.h).
struct Separator {
  std::string id;          ///< "shear_2000 at normal_stress 8000" or "direct_shear (standard set-up)"
  TestSetup setup;
  std::string observable;
  double predicted_a = 0, predicted_b = 0;  ///< means over replicas
  double sigma = 0;        ///< lab repeatability assumed plus both simulations' standard errors
  double separation = 0;   ///< |a - b| / sigma
  std::string words;
};

/// How sure a diagnosis is (Diagnosis::grade).
enum class Verdict {
  nothing_missing,  ///< the model as it is fits within the noise
  missing,          ///< an effect added and recalibrated fits within the noise and beats every confirmed rival by the BIC margin
  cannot_tell,      ///< two confirmed effects fit within the noise and the data cannot tell them apart (a separating experiment is named)
  improves,         ///< the best effect lowers BIC by the margin but the model with it still misfits: not named as missing
  parameter,        ///< a wall parameter the fit left out explains the misfit: not missing physics
  none_found,       ///< the model misfits and no candidate lowers BIC by the margin
};
/// "nothing missing", "missing", "cannot tell", "improves, not explained", "a parameter", "no effect found".
std::string verdict_words(Verdict v);

struct Diagnosis {
  CalibrationResult base;
  double base_bic = 0;
  std::vector<CandidateResult> candidates;  ///< ranked: confirmed by BIC, then by explained fraction
  Verdict grade = Verdict::none_found;
  std::string best;                         ///< the confirmed candidate of lowest BIC, whatever the grade ("" for none)
  /// The candidate named as missing (grades missing, cannot_tell) or the parameter (grade
  /// parameter); "" otherwise: an effect that improves the fit without explaining it is not.
  std::string recommended;
  std::vector<std::string> unexplained;     ///< improves: the terms the best model still misses by more than 2 sigma
  std::string confirm_next;                 ///< improves: the unconfirmed candidate to recalibrate next ("" for none)
  std::vector<std::string> rivals;          ///< confirmed candidates the data cannot tell from the recommended one
  /// Candidates not recalibrated that the data do not rule out against the recommended one: the
  /// grade is then cannot_tell, with the command that confirms them.
  std::vector<std::string> unconfirmed_rivals;
  /// Per rival: the experiments that would tell it from the recommended candidate, best first.
  std::map<std::string, std::vector<Separator>> separators;
  std::vector<std::string> words;
  /// The apparatus' size after the first comparison: below 1 when the budget could not be met at
  /// full size, the simulations then carrying size_shift (CalibrationOptions::size_shift).
  double size_factor = 1.0;
  std::map<std::string, SizeShift> size_shift;
  /// diagnose with size_factor < 1: the measurements are of the full-size apparatus; the model as
  /// it is is compared at both sizes first and the shrinking corrected (size_shift), and the
  /// model named is compared at full size. false: the measurements are of the apparatus as
  /// shrunk (synthetic data made at that size), nothing is corrected.
  bool correct_size = true;
  /// Shrunk diagnoses: the best candidate's fitted model compared at full size, on which its grade
  /// rests (empty runs when none was checked).
  Comparison full_size;
};

/// The settings of a calibration or diagnosis that fit options.budget_seconds, from the cost of a
/// pass over the experiments measured by `first` (a comparison of the starting model), with `p`
/// fitted parameters, `effects` effect candidates and `walls` wall-parameter candidates to
/// screen (both 0: a calibration). `spent` [s] is what the command has taken so far (the first
/// comparison): the rest is planned into what is left of the budget. `given_up` says what was
/// reduced, and `seconds` the planned wall time of what remains.
struct BudgetPlan {
  CalibrationOptions options;
  std::vector<std::string> given_up;
  double seconds = 0;
};
BudgetPlan plan_within_budget(const CalibrationOptions& options, const Comparison& first, int p, int effects, int walls, double spent = 0);
/// The same for what a diagnosis has left after calibrating the model as it is (the signature
/// screen and the confirmations), at `pass` [s] a pass over the experiments as measured so far
/// (a candidate's passes cost more: detail::kScreenCost, kConfirmationCost), into `left` [s] of
/// the budget `budget` [s].
BudgetPlan plan_screen_within_budget(const CalibrationOptions& options, double pass, int p, int effects, int walls, double left, double budget);

/// BIC = chi^2 + k ln n.
double bic(double chi2, int k, int n);

/// The chi^2/n at or below which a model of k fitted parameters fits n terms within the noise:
/// options.fits_within_noise, or the 95 % point of chi^2 with n - k degrees of freedom over n
/// where that is higher (8 terms and 2 parameters: 1.57); fits_within_noise <= 0: itself (no model
/// fits, every candidate is screened and confirmed).
double noise_line(const CalibrationOptions& options, int n, int k);

Diagnosis diagnose(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters,
                   const CalibrationOptions& options);

// ---- error ledger -------------------------------------------------------------------------

/// One model version with its error on every experiment.
struct LedgerEntry {
  int version = 0;
  std::string label;   ///< "start", "calibrated", "+ liquid_bridge", ...
  std::string time;    ///< local time of the run
  std::vector<std::string> effects;               ///< contact effects switched on (and clump shape)
  std::map<std::string, double> parameters;       ///< fitted (or tunable) parameter values
  std::map<std::string, double> residuals;        ///< term name -> normalised residual
  double chi2 = 0;
  int n = 0;
  /// The diagnosis' verdict on this version, where one was made ("missing: epsd ...",
  /// "improves, not explained: jkr ..."; Verdict): "" for none.
  std::string verdict;
  /// [-] The coarse_grain the version's virtual tests ran at (MaterialModel::coarse_grain): a
  /// version fitted with parcels is another fit than one with real particles. 1: real particles.
  double coarse_grain = 1.0;
  double chi2_per_n() const { return n > 0 ? chi2 / n : 0.0; }
};

/// The effects of a model as words: "hertz", "restitution", "mindlin", "epsd", "liquid_bridge", "clump".
std::vector<std::string> model_effects(const MaterialModel& model);
LedgerEntry ledger_entry(const MaterialModel& model, const Comparison& comparison, const std::string& label,
                         const std::vector<std::string>& parameter_keys);
/// Reads OUT/ledger.yaml (empty when the file does not exist).
std::vector<LedgerEntry> read_ledger(const std::string& path);
/// Appends `entries` (numbered after the existing ones) and rewrites the file.
std::vector<LedgerEntry> append_ledger(const std::string& path, const std::string& material, std::vector<LedgerEntry> entries);

}  // namespace dem::materials
