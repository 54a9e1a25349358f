// The diagnosis' phases (diagnose() in diagnosis.cpp reads as their list): the state a diagnosis
// passes from phase to phase. Each phase lives in its own file: the model as it is, the shrunk
// apparatus and the full-size check (diagnosis.cpp), the screen of candidate effects
// (screen.cpp), their confirmation by recalibration (confirmations.cpp) and the verdict with its
// words (verdict.cpp). Internal to materials/diagnosis/.
#pragma once

#include <Eigen/Dense>

#include <map>
#include <string>
#include <vector>

#include "calibration/calibration.h"
#include "calibration/calibration_support.h"

namespace dem::materials::diagnosis {

using detail::join;
using detail::Progress;
using detail::simulate_experiments;

/// Wall parameters the fit leaves out, offered as candidates (diagnosis.cpp).
std::vector<EffectCandidate> wall_parameter_candidates(const MaterialModel& model, const std::vector<FitParameter>& fitted);

// The screen's state (defined with the screen, screen.cpp).
struct ScreenResidual;
struct ScreenBasis;
struct SignaturePass;
struct CandidateScreen;

/// The state a diagnosis passes from phase to phase; diagnose() below reads as the list of them.
class DiagnosisRun {
 public:
  DiagnosisRun(const MaterialModel& model, const MeasurementSet& measured, std::vector<FitParameter> parameters, const CalibrationOptions& given)
      : model_(model),
        measured_(measured),
        parameters_(parameters.empty() ? fit_parameters(model) : std::move(parameters)),
        given_(given),
        options_(detail::within_command(given)),
        experiments_(static_cast<int>(measured.experiments.size())),
        fitted_(static_cast<int>(parameters_.size())),
        walls_(static_cast<int>(wall_parameter_candidates(model, parameters_).size())),
        lacking_(static_cast<int>(missing_effects(model).size())),
        command_(options_.context, "diagnose",
                 experiments_ * (std::max(1, options_.replicas) + detail::diagnosis_passes(options_, fitted_, lacking_, walls_))),
        count_(command_.count()) {}

  void calibrate_as_it_is();
  void probe_guessed_walls(const Comparison& first);
  void check_at_full_size();
  bool nothing_to_look_for();
  void replan_for_the_screen();
  void screen_signatures();
  bool fits_as_it_is() const { return fits_; }
  void say_it_fits();
  void confirm_leaders();
  void write_verdict();
  void describe_candidates();
  Diagnosis result() {
    // After the verdict: the plain fit's values out of the plausible, and before them the guessed
    // wall parameters it calibrated.
    if (!implausible_.empty()) d_.words.insert(d_.words.begin() + std::min<std::ptrdiff_t>(1, std::ssize(d_.words)), implausible_);
    d_.words.insert(d_.words.begin() + std::min<std::ptrdiff_t>(1, std::ssize(d_.words)), guessed_walls_.begin(), guessed_walls_.end());
    return std::move(d_);
  }

 private:
  const MaterialModel& model_;
  const MeasurementSet& measured_;
  std::vector<FitParameter> parameters_;  ///< a guessed wall parameter the data depend on joins them (probe_guessed_walls)
  const CalibrationOptions& given_;
  CalibrationOptions options_;  ///< a budget may reduce it; the commands it calls share its context
  const int experiments_;
  int fitted_, walls_;
  const int lacking_;
  const detail::CommandScope command_;
  detail::CommandProgress& count_;
  Diagnosis d_;
  int n_ = 0;            ///< terms of the base comparison
  bool fits_ = false;    ///< the model as it is fits within the noise
  double line_ = 0;      ///< its chi^2/n line
  std::vector<EffectCandidate> effects_;           ///< the candidates screened
  std::map<std::string, Comparison> at_start_;     ///< each candidate's comparison at its start values
  std::vector<std::string> left_out_;              ///< candidates whose simulations could not run
  std::vector<std::string> undecided_, nonlinear_, unconfirmed_;
  std::string screen_leader_;  ///< the screen's first: the candidates are ranked again by their fits later
  bool screen_silent_ = false;
  std::vector<std::string> guessed_walls_;         ///< the guessed wall parameters calibrated with the others, and why
  std::string implausible_;                        ///< the plain fit's values out of the plausible

  std::string shrunk_words_;      ///< why and how the apparatus was shrunk (shrink)
  double full_size_reserve_ = 0;  ///< [s] of the budget kept for the full-size check of a shrunk diagnosis
  double cost_mark_seconds_ = 0;  ///< the command's time and simulations when the apparatus was shrunk:
  int cost_mark_done_ = 0;        ///< later costs are measured from there

  bool budgeted() const { return given_.budget_seconds > 0 && command_.outermost() && count_.done() > 0; }
  /// [s] wall time a simulation has cost so far, at the apparatus' present size.
  double seconds_per_simulation() const {
    const int done = count_.done() - cost_mark_done_;
    return done > 0 ? (count_.elapsed() - cost_mark_seconds_) / done : count_.elapsed() / std::max(1, count_.done());
  }
  double confirmation_seconds_per_simulation(const CandidateResult& cr) const;
  bool shrink(Comparison& first, double size, const std::string& why);
  void unshrink();
  const EffectCandidate& effect_of(const CandidateResult& cr) const {
    return *std::find_if(effects_.begin(), effects_.end(), [&](const EffectCandidate& c) { return c.name == cr.name; });
  }
  void say(std::string words) {
    d_.words.push_back(std::move(words));
    if (options_.progress) options_.progress("diagnose: " + d_.words.back());
  }
  ScreenResidual screen_residual() const;
  void choose_candidates();
  void plan_signatures(SignaturePass& pass);
  ScreenBasis screen_basis(ScreenResidual residual) const;
  void screen_candidate(const EffectCandidate& c, const detail::SignatureRuns& runs, const ScreenBasis& basis, SignaturePass& pass);
  CandidateResult entry_of(const EffectCandidate& c) const;
  bool leave_out(const EffectCandidate& c, const detail::SignatureRuns& runs);
  void measure_strengths(const EffectCandidate& c, const detail::SignatureRuns& signature_runs, const ScreenBasis& basis, CandidateResult& cr,
                         CandidateScreen& screen);
  Eigen::VectorXd signature_of_runs(const ScreenBasis& basis, const Comparison& changed, std::vector<std::string>& flips) const;
  double own_runs_chi2(const ScreenBasis& basis, double reachable, const Eigen::VectorXd& s) const;
  void rank_candidate(const EffectCandidate& c, const ScreenBasis& basis, SignaturePass& pass, CandidateScreen& screen, CandidateResult& cr);
  void rank_by_share();
  template <class SignatureOf, class OwnChi2>
  std::string weaker_strength(const EffectCandidate& c, int side, double multiple, double linear, double rr, const SignatureOf& signature_of,
                              const OwnChi2& own_chi2, int replicas, const std::map<std::string, double>& floor, detail::Progress& progress,
                              double& measured_chi2, CandidateResult& cr);
  void fit_confirmations_to_budget(std::vector<size_t>& confirming, std::map<std::string, int>& design_points_of);
  CalibrationOptions confirmation_options(const CandidateResult& cr) const;
  void confirm(CandidateResult& cr, const CalibrationOptions& options);
  void separate(const CandidateResult& best, const CandidateResult& rival);
  std::vector<std::string> unexplained_by(const CandidateResult& best) const;
  std::string next_to_confirm(const CandidateResult& best) const;
};

}  // namespace dem::materials::diagnosis
