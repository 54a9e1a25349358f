// The table of virtual tests: name, observables, the function that runs it (one file each, the
// virtual laboratory: lab_drop_rebound.cpp, lab_bulk_density.cpp, lab_angle_of_repose.cpp,
// lab_rotating_drum.cpp, lab_hopper_discharge.cpp, lab_direct_shear.cpp). Set-ups and extraction rules:
// each file's header, summarised in docs/materials-and-calibration.md ("The virtual lab tests").
// A new test is its file (materials/lab/lab_NAME.cpp, which the build finds) and, here, the
// declaration of its function and its row. Rejected: tests registering themselves from their own
// files, as the effect table also rejects (a static library's linker drops an object nothing
// references, and the table's order would follow the link order).
#include "lab/virtual_tests.h"

#include <fmt/format.h>

#include <omp.h>

#include <algorithm>

#include "lab/lab_direct_shear.h"
#include "lab/virtual_test_support.h"

namespace dem::materials {

namespace detail {
SimulatedOutcome run_drop_rebound(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);
SimulatedOutcome run_bulk_density(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);
SimulatedOutcome run_angle_of_repose_cylinder(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);
SimulatedOutcome run_rotating_drum(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);
SimulatedOutcome run_hopper_discharge(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);
}  // namespace detail

namespace {

struct TestEntry {
  const char* name;
  std::vector<std::string> observables;
  SimulatedOutcome (*run)(const MaterialModel&, const TestSetup&, const TestOptions&);
};

const std::vector<TestEntry>& table() {
  static const std::vector<TestEntry> entries = {
      {"drop_rebound", {"restitution", "tangential_restitution"}, &detail::run_drop_rebound},
      {"bulk_density", {"bulk_density"}, &detail::run_bulk_density},
      {"angle_of_repose_cylinder", {"angle_deg"}, &detail::run_angle_of_repose_cylinder},
      {"rotating_drum", {"dynamic_angle_deg"}, &detail::run_rotating_drum},
      {"hopper_discharge", {"mass_flow_rate"}, &detail::run_hopper_discharge},
      {"direct_shear", {"peak_shear_stress", "steady_shear_stress", "bulk_density"}, &run_direct_shear},
  };
  return entries;
}

const TestEntry* find(const std::string& name) {
  for (const TestEntry& e : table())
    if (e.name == name) return &e;
  return nullptr;
}

}  // namespace

std::vector<std::string> test_names() {
  std::vector<std::string> names;
  for (const TestEntry& e : table()) names.push_back(e.name);
  return names;
}

std::vector<std::string> observable_names(const std::string& test) {
  const TestEntry* e = find(test);
  return e ? e->observables : std::vector<std::string>{};
}

SimulatedOutcome run_virtual_test(const MaterialModel& model, const TestSetup& setup, const TestOptions& options) {
  const TestEntry* e = find(setup.test);
  if (!e) throw CaseError(fmt::format("{}: test: unknown test '{}'; valid: {}", setup.location.str(), setup.test, fmt::join(test_names(), ", ")));
  if (!(options.size_factor > 0 && options.size_factor <= 1))
    throw CaseError(fmt::format("size factor {:g} is out of range; valid: above 0, at most 1 (--size-factor)", options.size_factor));
  if (!(model.coarse_grain >= 1.0 && model.coarse_grain <= kMostCoarseGrain))
    throw CaseError(fmt::format("coarse grain {:g} is out of range; valid: [1, {:g}] (--coarse-grain; 1: real particles)", model.coarse_grain,
                                kMostCoarseGrain));
  // `threads` is this thread's OpenMP setting for the test's duration, given back afterwards:
  // the engine's parallel regions read it (omp_get_max_threads), not the compiled model.
  const int before = omp_get_max_threads();
  if (options.threads > 0) omp_set_num_threads(options.threads);
  struct Restore {
    int threads;
    ~Restore() { omp_set_num_threads(threads); }
  } restore{before};
  return e->run(model, setup, options);
}

}  // namespace dem::materials
