// demdesign command line: the top of the dependency graph (app -> render -> equipment ->
// geometry -> src).
//   demdesign CASE.yaml            run a case (same as `demdesign run CASE.yaml`)
//   demdesign check CASE.yaml      read and compile a case, print its set-up, run nothing
//   demdesign effects              the table of contact effects and their parameters
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <omp.h>

#include <iostream>

#include "diagnostics.h"
#include "model.h"
#include "particles.h"
#include "run.h"
#include "spec.h"

namespace {

struct RunArgs {
  std::string case_path;
  double duration = -1;
  long long max_steps = -1;
  int threads = 0;
  std::string out;
  bool quiet = false;
  bool resume = false;
};

int run_case(const RunArgs& args) {
  const dem::CaseSpec spec = dem::parse_case_file(args.case_path);
  const dem::Model model = dem::compile(spec);
  const int threads = args.threads > 0 ? args.threads : model.threads;
  if (threads > 0) omp_set_num_threads(threads);
  dem::State state = dem::initial_state(model);
  dem::Workspace work;
  dem::RunOptions options;
  options.duration = args.duration;
  options.max_steps = args.max_steps;
  options.output_directory = args.out;
  options.progress = !args.quiet;
  options.resume = args.resume;
  dem::run(model, state, work, options, std::cout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"demdesign: DEM simulation for the design of bulk-materials-handling equipment"};
  app.require_subcommand(0, 1);
  RunArgs args;
  auto add_run_options = [&](CLI::App* cmd) {
    cmd->add_option("--duration", args.duration, "simulated time [s], overrides the case");
    cmd->add_option("--max-steps", args.max_steps, "stop after this many steps (shortened run)");
    cmd->add_option("--threads", args.threads, "OpenMP threads (default: all cores)");
    cmd->add_option("--out", args.out, "output folder (default: the case's output.directory)");
    cmd->add_flag("--quiet", args.quiet, "no progress lines");
    cmd->add_flag("--resume", args.resume, "continue from OUT/checkpoint.bin (written every output.checkpoint_every, and on SIGINT/SIGTERM)");
  };
  app.add_option("case", args.case_path, "case file (YAML) to run");
  add_run_options(&app);
  CLI::App* run_cmd = app.add_subcommand("run", "run a case");
  run_cmd->add_option("case", args.case_path, "case file (YAML)")->required();
  add_run_options(run_cmd);
  std::string check_path;
  CLI::App* check_cmd = app.add_subcommand("check", "read and compile a case and print its set-up");
  check_cmd->add_option("case", check_path, "case file (YAML)")->required();
  CLI::App* effects_cmd = app.add_subcommand("effects", "list the contact effects and their parameters");

  CLI11_PARSE(app, argc, argv);
  try {
    if (effects_cmd->parsed()) {
      std::cout << dem::describe_effects();
      return 0;
    }
    if (check_cmd->parsed()) {
      const dem::Model model = dem::compile(dem::parse_case_file(check_path));
      const dem::State state = dem::initial_state(model);
      dem::print_setup(model, state, std::cout);
      return 0;
    }
    if (args.case_path.empty()) {
      std::cout << app.help();
      return 2;
    }
    return run_case(args);
  } catch (const dem::CaseError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const dem::NumericalError& e) {
    std::cerr << "numerical trouble: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
