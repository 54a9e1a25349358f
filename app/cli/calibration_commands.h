// The calibration commands of the CLI: test, compare, calibrate, diagnose.
//   demdesign test MATERIAL.yaml --test rotating_drum --set rpm=20 --set drum_diameter=0.2 ... [--size-factor F]
//   demdesign compare MATERIAL.yaml MEASUREMENTS.yaml [--replicas N] [--out DIR]
//   demdesign calibrate MATERIAL.yaml MEASUREMENTS.yaml [--params friction,rolling_friction] [--out DIR]
//   demdesign diagnose MATERIAL.yaml MEASUREMENTS.yaml [--out DIR]
// Each takes --coarse-grain F: the virtual tests in the real apparatus filled with parcels of F
// times the diameter (core/coarse_grain.h), to calibrate the material at the parcel size a
// coarse-grained case runs.
// Wiring in main(): construct before CLI11_PARSE, then inside the try block
//   if (calibration.parsed()) return calibration.run();
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

#include "calibration/calibration.h"
#include "core/model.h"
#include "core/state.h"

namespace dem::app {

/// Renders a final state to a PNG (supplied by main, which owns the renderer).
using RenderFinal = std::function<void(const Model&, const State&, const std::string& png_path)>;

class CalibrationCommands {
 public:
  CalibrationCommands(CLI::App& app, RenderFinal render);
  bool parsed() const;
  /// Runs the parsed command; returns the exit status. Throws CaseError for bad input.
  int run();

 private:
  /// What the phases of compare, calibrate and diagnose share (calibration_commands.cpp).
  struct Campaign;

  int run_test();
  /// compare, calibrate or diagnose: reads, simulates, prints and writes the report in OUT.
  int run_measured(const std::string& command);
  // The phases of run_measured, in order.
  void read_campaign_inputs(Campaign& campaign);
  void set_campaign_options(Campaign& campaign);
  void start_campaign_report(Campaign& campaign);
  void report_diagnosis_stages(Campaign& campaign);
  void print_comparison(Campaign& campaign);
  void record_calibration(Campaign& campaign);
  void record_diagnosis(Campaign& campaign);
  void write_calibrated(const Campaign& campaign);
  void write_campaign_report(Campaign& campaign, const materials::MaterialModel& shown);

  RenderFinal render_;
  CLI::App* test_ = nullptr;
  CLI::App* compare_ = nullptr;
  CLI::App* calibrate_ = nullptr;
  CLI::App* diagnose_ = nullptr;
  std::string budget_;
  std::string material_, measurements_, test_name_, out_ = "calibration", params_, png_, effects_, synthetic_from_;
  std::vector<std::string> set_;
  double size_factor_ = 1.0, rayleigh_fraction_ = 0.0, stiffness_scaling_ = 1.0, design_factor_ = 2.0;
  double stiffness_check_ = 0;  ///< compare --stiffness-check: factor of the second comparison (0: none)
  /// --coarse-grain: the virtual tests with parcels of this factor (MaterialModel::coarse_grain); 1: real particles
  double coarse_grain_ = 1.0;
  int replicas_ = 3, threads_ = 0, rounds_ = 2, confirm_ = 2, parallel_ = 0;
  bool no_store_ = false, no_renders_ = false, no_walls_first_ = false;
  long long noise_seed_ = 1;
  int write_synthetic();
  /// compare --stiffness-check: the comparison again with stiffer particles, each observable's
  /// shift against its measurement sigma (printed, and OUT/stiffness_check.csv).
  void stiffness_check(const materials::MaterialModel& model, const materials::MeasurementSet& measured,
                       const materials::CalibrationOptions& options, const materials::Comparison& as_run);
  /// One render of the final state per test type of the measurement file, with `model`.
  std::vector<std::string> render_tests(const materials::MaterialModel& model, const materials::MeasurementSet& measured,
                                        const materials::CalibrationOptions& options);
  long long seed_ = 1;
  bool quiet_ = false;
};

}  // namespace dem::app
