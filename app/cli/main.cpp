// demdesign command line: the top of the dependency graph (app -> materials -> equipment -> src;
// app -> geometry and app -> render, which stand alone on assimp/CGAL and OSMesa).
//   demdesign CASE.yaml            run a case (same as `demdesign run CASE.yaml`)
//   demdesign check CASE.yaml      read and compile a case, print its set-up, run nothing
//   demdesign check-mesh FILE...   import, check and repair meshes, print their health reports
//   demdesign render OUT           images of a run's saved frames
//   demdesign compare-runs A B     two finished runs side by side, figure by figure
//   demdesign effects              the table of contact effects and their parameters
//   demdesign materials            the material library
//   demdesign keys [--markdown]    every key of case, material and measurement files (docs/case-keys.md)
//   demdesign test | compare | calibrate | diagnose   virtual lab tests and material calibration
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "base/allocator.h"
#include "cli/calibration_commands.h"
#include "case/spec.h"
#include "case/yaml_check.h"
#include "cli/case_keys.h"
#include "cli/cli_checks.h"
#include "core/model.h"
#include "core/particles.h"
#include "equipment.h"
#include "pages/flow_images.h"
#include "model/library.h"
#include "mesh_health.h"
#include "campaign/mpi_campaign.h"
#include "mpi/mpi_domain.h"
#include "mpi/mpi_frames.h"
#include "output/results_hdf5.h"
#include "output/run.h"
#include "report/compare_runs.h"
#include "report/liner_loads.h"
#include "report/report.h"
#include "report/report_wear.h"
#include "statistics/diagnostics.h"
#include "campaign/sweep.h"
#include "triangle_mesh.h"
#include "pages/video.h"
#include "validation/validation_report.h"

namespace {

struct RunArgs {
  std::string case_path;
  double duration = -1;
  long long max_steps = -1;
  int threads = 0;
  std::string out;
  bool quiet = false;
  bool resume = false;
  bool overwrite = false;  ///< replace the results of an earlier run in OUT (only the files runs wrote)
  long variant = -1;  ///< run this variant of the case's sweep (the sweep runner's children)
  std::string rank_grid;  ///< "NXxNYxNZ": the grid of boxes under mpirun (empty: chosen)
  std::string balance = "work";  ///< under mpirun: what the cuts balance, work or time
  bool report = true;
  std::string command_line;  ///< as typed, for the run record
};

/// The case file as YAML, with file:line errors.
YAML::Node load_case_yaml(const std::string& path, std::string* text_out = nullptr) {
  std::ifstream in(path);
  if (!in) throw dem::CaseError(fmt::format("{}: cannot open the case file", path));
  std::stringstream text;
  text << in.rdbuf();
  if (text_out) *text_out = text.str();
  return dem::parse_yaml(text.str(), path);
}

/// Reads a case with its equipment expanded: what every command compiles.
dem::CaseSpec read_case(const std::string& path) {
  dem::CaseSpec spec = dem::parse_case_file(path, dem::materials::library_lookup());
  dem::equipment::expand_equipment(spec);
  return spec;
}

/// Mesh files go through the geometry library: import, health check, safe repair. A mesh that
/// cannot be simulated stops the run with its report.
dem::TriangleSoup load_mesh(const dem::MeshWallSpec& spec, double particle_diameter) {
  dem::geometry::ImportOptions options;
  options.unit_scale = spec.unit_scale;
  for (int a = 0; a < 3; ++a)
    options.scale[a] = spec.scale[a], options.rotate_deg[a] = spec.rotate_deg[a], options.translate[a] = spec.translate[a];
  dem::geometry::TriangleMesh mesh = dem::geometry::import_mesh(spec.file, options);
  const dem::geometry::MeshReport report = dem::geometry::check_and_repair(mesh, particle_diameter);
  if (!report.simulable())
    throw dem::CaseError(fmt::format("{}: meshes '{}': the mesh cannot be simulated:\n{}", spec.location.str(), spec.name, report.text()));
  for (const auto& issue : report.issues)
    if (issue.severity != dem::geometry::MeshIssue::Severity::info)
      std::cout << fmt::format("  mesh {}: {} ({})\n", spec.name, issue.what, issue.count);
  return {std::move(mesh.vertices), std::move(mesh.triangles)};
}

dem::Model compile_case(const dem::CaseSpec& spec) {
  // The meshes are checked against the spheres the run moves: parcels when coarse-grained.
  double diameter = 0;
  for (const auto& p : spec.particles) diameter = std::max(diameter, p.diameter.largest() * p.coarse_grain);
  for (const auto& in : spec.inlets) diameter = std::max(diameter, in.diameter.largest() * in.coarse_grain);
  return dem::compile(spec, [diameter](const dem::MeshWallSpec& m) { return load_mesh(m, diameter); });
}

dem::app::ImageOptions image_options(const dem::Model& model) {
  return {model.output.render_camera, model.output.render_colour, model.output.render_width, model.output.render_height};
}

/// Per-triangle rate per area [W/m^2] of a wall record over the recording interval; NaN where a
/// mesh has no records.
std::vector<std::vector<double>> wall_rate(const dem::Model& model, const dem::State& state, bool impact, double seconds) {
  std::vector<std::vector<double>> out(model.meshes.size());
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    const dem::TriangleSurface& surface = *model.meshes[m].surface;
    out[m].assign(surface.size(), std::numeric_limits<double>::quiet_NaN());
    if (m >= state.records.size()) continue;
    const std::vector<double>& work = impact ? state.records[m].impact_energy : state.records[m].shear_work;
    for (size_t t = 0; t < surface.size() && t < work.size(); ++t) out[m][t] = work[t] / (seconds * surface.areas[t]);
  }
  return out;
}

/// One mesh's mean pressure [kPa] per triangle over the recording interval (report/liner_loads.h).
std::vector<double> kilopascals(const dem::report::LinerLoad& load) {
  std::vector<double> out = load.pressure;
  for (double& p : out) p *= 1e-3;  // Pa to kPa
  return out;
}

/// Per-triangle mean pressure [kPa] of every mesh.
std::vector<std::vector<double>> pressure_kilopascals(const dem::report::LinerLoads& loads) {
  std::vector<std::vector<double>> out;
  for (const dem::report::LinerLoad& load : loads.meshes) out.push_back(kilopascals(load));
  return out;
}

/// Each liner's own pressure map, report/pressure_map_MESH.png (MESH as in fea/): the mesh alone,
/// seen face on from the side its load comes from (the particles' mean force on it), for the
/// gallery under the report's liner table. Liners as liner_map_meshes picks them.
std::vector<dem::report::LinerMap> write_liner_maps(const dem::Model& model, const dem::State& state, const dem::report::LinerLoads& loads,
                                                    const std::map<std::string, dem::report::Liner>& liners, const std::string& report_dir) {
  dem::app::ImageOptions view;
  view.width = 800, view.height = 600;  // shown small, side by side
  std::vector<dem::report::LinerMap> maps;
  for (const std::size_t m : dem::report::liner_map_meshes(loads, model, liners)) {
    const dem::report::LinerLoad& load = loads.meshes[m];
    const std::string path = fmt::format("{}/pressure_map_{}.png", report_dir, dem::report::fea_name(load.name));
    dem::app::render_mesh_field(model, state, m, kilopascals(load), load.total_force, "mean pressure [kPa]", view, path);
    maps.push_back({load.name, path});
  }
  return maps;
}

/// The run's report folder: renders of the flow and of the wear fields and the liner pressure on
/// the walls, then the report itself (throughput, power, wear, belt loading at steady state).
void write_run_report(const dem::Model& model, const dem::State& state, const dem::CaseSpec& spec, const dem::RunSummary& summary,
                      const std::string& case_path, const std::string& case_text) {
  const std::string out = summary.output_directory, report_dir = out + "/report";
  std::filesystem::create_directories(report_dir);
  dem::report::RunReportInput input;
  input.model = &model, input.state = &state, input.scalars = summary.scalars, input.events = summary.events;
  input.case_path = case_path, input.case_text = case_text, input.version = DEMDESIGN_VERSION;
  input.wall_seconds = summary.wall_seconds;
  input.stopped = summary.stopped;
  input.records_from = model.output.records_from;
  input.sensors = model.sensors, input.design = model.design;
  // Liners per mesh (a belt or pulley takes no default) and the hours a year their life is at.
  input.liners = dem::report::liners_for(spec, model);
  input.operating_hours_per_year = spec.wear.operating_hours_per_year;
  input.operating_hours_given = spec.wear.hours_given;
  for (const auto& outlet : spec.outlets)
    if (!outlet.spillage) input.outlet_intended.push_back(outlet.name);
  const std::string flow = fmt::format("{}/renders/frame_{:06d}.png", out, state.step);
  if (std::filesystem::exists(flow))
    input.images.push_back({"Flow at the end of the run", flow,
                            fmt::format("Particles coloured by {} at t = {:.2f} s; walls cut away where they face the camera.",
                                        model.output.render_colour, state.time)});
  const double seconds = state.time - model.output.records_from;
  if (!model.meshes.empty() && seconds > 0) {
    dem::app::ImageOptions wear_view = image_options(model);
    wear_view.camera = "iso";
    const std::string shear = report_dir + "/wear_shear_work.png", impact = report_dir + "/wear_impact_energy.png";
    dem::app::render_wall_field(model, state, wall_rate(model, state, false, seconds), "shear work rate [W/m²]", wear_view, shear);
    dem::app::render_wall_field(model, state, wall_rate(model, state, true, seconds), "impact energy rate [W/m²]", wear_view, impact);
    input.images.push_back({"Abrasive wear: shear work rate", shear,
                            fmt::format("Friction work per area and time on the walls (Archard wear input), averaged over t = {:.2f} to {:.2f} s.",
                                        model.output.records_from, state.time)});
    input.images.push_back({"Impact wear: impact energy rate", impact,
                            fmt::format("Normal impact energy per area and time on the walls, t = {:.2f} to {:.2f} s.", model.output.records_from, state.time)});
    const std::string pressure = report_dir + "/pressure_map.png";
    const dem::report::LinerLoads loads = dem::report::liner_loads(model, state, model.output.records_from);
    dem::app::render_wall_field(model, state, pressure_kilopascals(loads), "mean pressure [kPa]", wear_view, pressure);
    input.images.push_back({"Liner pressure: mean pressure", pressure,
                            fmt::format("Normal impulse per area and time on the walls (the liners' mean pressure), t = {:.2f} to {:.2f} s; "
                                        "each liner's own map is in the Liner pressure section; the loads for a structural model are in report/fea/.",
                                        model.output.records_from, state.time)});
    input.liner_maps = write_liner_maps(model, state, loads, input.liners, report_dir);
  }
  const dem::report::RunMetrics metrics = dem::report::write_run_report(input, report_dir);
  std::cout << fmt::format("  report: {}/report.html ({})\n", report_dir, metrics.steady_text);
}

/// `demdesign check CASE`: everything a run reads, without running. A case with a sweep (or a
/// bias check, or an uncertainty study) has every variant read and its equipment generated; the
/// first variant is compiled and its set-up printed, as a run prints it.
int check_case(const std::string& path) {
  const YAML::Node root = load_case_yaml(path);
  const dem::app::SweepPlan plan = dem::app::read_sweep(root, path);
  if (plan.variants.empty()) {
    const dem::Model model = compile_case(read_case(path));
    dem::print_setup(model, dem::initial_state(model), std::cout);
    return 0;
  }
  dem::CaseSpec first;
  for (size_t k = 0; k < plan.variants.size(); ++k) {
    try {
      dem::CaseSpec spec = dem::parse_case_node(dem::app::variant_case(root, plan, k), path, dem::materials::library_lookup());
      dem::equipment::expand_equipment(spec);
      if (k == 0) first = std::move(spec);
    } catch (const dem::CaseError& e) {
      throw dem::CaseError(fmt::format("sweep variant {} ({}): {}", plan.name(k), plan.label(k), e.what()));
    }
  }
  std::cout << fmt::format("sweep: {} variants of {} key{}; every variant reads and its equipment is generated; the first, {} ({}):\n",
                           plan.variants.size(), plan.paths.size(), plan.paths.size() == 1 ? "" : "s", plan.name(0), plan.label(0));
  const dem::Model model = compile_case(first);
  dem::print_setup(model, dem::initial_state(model), std::cout);
  return 0;
}

/// The case as it runs: its YAML (a sweep variant chosen, a duration given on the command line
/// written in) and its record, the text written to OUT/case.yaml.
struct CaseAsRun {
  YAML::Node root;
  std::string text;
};

/// The case file as written: its YAML and its text.
CaseAsRun read_case_as_written(const std::string& path) {
  std::string text;
  YAML::Node root = load_case_yaml(path, &text);
  return {root, std::move(text)};
}

/// A case with a sweep, run without --variant: every variant of it.
int run_every_variant(const RunArgs& args, const dem::app::SweepPlan& plan, const YAML::Node& root) {
  dem::app::SweepOptions sweep;
  sweep.case_path = args.case_path;
  sweep.out = !args.out.empty() ? args.out
                                : dem::parse_case_node(dem::app::variant_case(root, plan, 0), args.case_path, dem::materials::library_lookup()).output.directory;
  sweep.threads = args.threads, sweep.duration = args.duration, sweep.max_steps = args.max_steps, sweep.quiet = args.quiet;
  return dem::app::run_sweep(plan, sweep, std::cout);  // under MPI: the variants shared among the ranks
}

/// --variant K: the case becomes that variant of its sweep, and its record says which.
void select_variant(const RunArgs& args, const dem::app::SweepPlan& plan, CaseAsRun& as_run) {
  if (args.variant >= static_cast<long>(plan.variants.size()))
    throw dem::CaseError(fmt::format("--variant {}: the case has {} sweep variants", args.variant, plan.variants.size()));
  as_run.root = dem::app::variant_case(as_run.root, plan, static_cast<size_t>(args.variant));
  as_run.text = fmt::format("# {} of {}: {}\n", plan.name(args.variant), args.case_path, plan.label(args.variant)) + YAML::Dump(as_run.root) + "\n";
}

/// The record is the case as run: a duration given on the command line is written into it.
void write_duration_into_case(const RunArgs& args, CaseAsRun& as_run) {
  const std::string header = as_run.text.starts_with("# ") && args.variant >= 0 ? as_run.text.substr(0, as_run.text.find('\n') + 1) : "";
  as_run.root["simulation"]["duration"] = args.duration;
  as_run.text = header + fmt::format("# {} as run with --duration {:g}\n", args.case_path, args.duration) + YAML::Dump(as_run.root) + "\n";
}

/// The output folder, claimed before the case is compiled: refused when it holds another run's
/// results (without --resume or --overwrite) or a file of the run's names that no run wrote, and
/// locked while this run writes it (output/run_folder.h). What this program writes there after
/// the run (the case as run, equipment meshes, renders, the report) is guarded as the run's own.
struct OutputFolder {
  std::vector<std::string> caller_outputs;  ///< what this program writes there after the run
  std::shared_ptr<dem::RunFolder> folder;   ///< claimed on rank 0; null on the other ranks
};

OutputFolder claim_output_folder(const RunArgs& args, const dem::CaseSpec& spec) {
  OutputFolder claimed;
  claimed.caller_outputs = {"case.yaml",           "meshes/*.stl",       "renders/frame_*.png",
                            "renders/flow.mp4",    "renders/flow.mp4.log", "report/*.html",
                            "report/*.csv",        "report/*.png",       "report/plots/*.png",
                            "report/plots/*.gp",   "report/plots/*.tsv", "report/fea/*.vtk",
                            "report/fea/*.inp",    "report/pressure_map_*.png"};
  if (dem::app::mpi::world().rank == 0) {
    std::vector<std::string> names = dem::run_output_names();
    names.insert(names.end(), claimed.caller_outputs.begin(), claimed.caller_outputs.end());
    const dem::FolderUse use = args.resume ? dem::FolderUse::resume : args.overwrite ? dem::FolderUse::overwrite : dem::FolderUse::fresh;
    claimed.folder = std::make_shared<dem::RunFolder>(!args.out.empty() ? args.out : spec.output.directory, use, names, std::cout);
  }
  return claimed;
}

/// Under mpirun the case is split into a grid of boxes, one per rank (app/mpi/mpi_domain.h); rank 0 writes.
struct RankSplit {
  std::unique_ptr<dem::Domain> domain;  ///< null: not split (no MPI, or a case that cannot be split)
  bool waits = false;                   ///< a rank other than 0 while the case runs on rank 0 alone
};

RankSplit split_over_ranks(const RunArgs& args, const dem::Model& model, const dem::State& state, int threads) {
  const dem::app::mpi::World& world = dem::app::mpi::world();
  std::string domain_note;
  std::array<int, 3> grid{0, 0, 0};
  if (!args.rank_grid.empty()) {
    char x1 = 0, x2 = 0;
    std::istringstream in(args.rank_grid);
    if (!(in >> grid[0] >> x1 >> grid[1] >> x2 >> grid[2]) || x1 != 'x' || x2 != 'x' || !in.eof() || grid[0] < 1 || grid[1] < 1 || grid[2] < 1)
      throw dem::CaseError(fmt::format("--rank-grid '{}': expected three box counts as NXxNYxNZ, for example 2x2x1", args.rank_grid));
  }
  const dem::app::mpi::Balance balance = args.balance == "time" ? dem::app::mpi::Balance::time : dem::app::mpi::Balance::work;
  RankSplit split;
  split.domain = world.active() ? dem::app::mpi::make_domain(model, state, &domain_note, grid, true, balance) : nullptr;
  if (world.active() && !split.domain && grid[0] > 0 && world.size > 1) throw dem::CaseError(fmt::format("--rank-grid {}: {}", args.rank_grid, domain_note));
  if (world.active() && !split.domain) {  // cannot be split: rank 0 runs it alone, the others wait
    if (world.rank != 0) {
      split.waits = true;
      return split;
    }
    std::cout << fmt::format("note: {} MPI ranks, but this case runs on rank 0 alone: {}\n", world.size, domain_note);
  }
  if (split.domain && threads <= 0) omp_set_num_threads(dem::app::mpi::cores_per_rank());  // the ranks share the machine's cores
  if (split.domain && world.rank == 0)
    std::cout << fmt::format("domain decomposition: {}, {} OpenMP threads per rank\n", domain_note, omp_get_max_threads());
  return split;
}

/// What the engine is told: the command line's overrides, the claimed folder, the ranks' split.
dem::RunOptions run_options(const RunArgs& args, dem::Domain* domain, const OutputFolder& output) {
  dem::RunOptions options;
  options.domain = domain;
  options.duration = args.duration;
  options.max_steps = args.max_steps;
  options.output_directory = args.out;
  options.progress = !args.quiet;
  options.resume = args.resume;
  options.overwrite = args.overwrite;
  options.caller_outputs = output.caller_outputs;
  options.folder = output.folder;
  options.command_line = args.command_line;
  // A split run's ranks write each frame together, with no gather (parallel HDF5).
  if (domain) options.share_frame = dem::app::mpi::collective_frames();
  // Images of the flow: every render_every-th frame, and always the last (run.h).
  options.on_frame = [](const dem::Model& m, const dem::State& s, const dem::Workspace&, const std::string& out, bool last) {
    const std::string path = fmt::format("{}/renders/frame_{:06d}.png", out, s.step);
    std::filesystem::create_directories(out + "/renders");
    dem::app::render_state(m, s, image_options(m), path);
    if (last) std::cout << fmt::format("  rendered {}\n", path);
  };
  return options;
}

/// What the run and the files written beside its results share.
struct CaseRun {
  const RunArgs& args;
  const dem::CaseSpec& spec;
  const std::string& case_text;  ///< the record of the case as run (OUT/case.yaml)
  const dem::Model& model;
  dem::State& state;
};

/// Runs the case; a run that numerical trouble stops still gets its report.
dem::RunSummary run_reporting_a_stop(const CaseRun& case_run, dem::Workspace& work, const dem::RunOptions& options, std::ostream& log) {
  dem::RunSummary summary;
  try {
    summary = dem::run(case_run.model, case_run.state, work, options, log);
  } catch (const dem::RunStopped& stopped) {
    // Numerical trouble stopped the run: its report shows what it computed up to then, under a
    // banner that says why (a split run's state is not gathered then: no report).
    if (dem::app::mpi::world().rank == 0 && case_run.args.report && !options.domain && !stopped.summary.scalars.empty()) {
      try {
        write_run_report(case_run.model, case_run.state, case_run.spec, stopped.summary, case_run.args.case_path, case_run.case_text);
      } catch (const std::exception& e) {
        std::cout << fmt::format("  no report of the stopped run: {}\n", e.what());
      }
    }
    throw;
  }
  return summary;
}

/// Beside the run's results (rank 0): the case as run, the equipment meshes, the report.
void write_beside_results(const CaseRun& case_run, const dem::RunSummary& summary) {
  const std::string out = summary.output_directory;
  dem::write_file_atomically(out + "/case.yaml", case_run.case_text);
  if (case_run.spec.equipment) {
    const auto files = dem::equipment::write_equipment_meshes(case_run.spec, out + "/meshes");
    std::cout << fmt::format("  wrote {} equipment meshes (STL) to {}/meshes\n", files.size(), out);
  }
  if (case_run.args.report) write_run_report(case_run.model, case_run.state, case_run.spec, summary, case_run.args.case_path, case_run.case_text);
}

int run_case(const RunArgs& args) {
  CaseAsRun as_run = read_case_as_written(args.case_path);
  const dem::app::SweepPlan plan = dem::app::read_sweep(as_run.root, args.case_path);
  if (!plan.variants.empty() && args.variant < 0) return run_every_variant(args, plan, as_run.root);
  if (args.variant >= 0) select_variant(args, plan, as_run);
  if (args.duration > 0) write_duration_into_case(args, as_run);
  dem::CaseSpec spec = dem::parse_case_node(as_run.root, args.case_path, dem::materials::library_lookup());
  dem::equipment::expand_equipment(spec);
  const OutputFolder output = claim_output_folder(args, spec);
  const dem::Model model = compile_case(spec);
  const int threads = args.threads > 0 ? args.threads : model.threads;
  if (threads > 0) omp_set_num_threads(threads);
  dem::State state = dem::initial_state(model);
  dem::Workspace work;
  const RankSplit split = split_over_ranks(args, model, state, threads);
  if (split.waits) return 0;
  const dem::app::mpi::World& world = dem::app::mpi::world();
  std::ostringstream quiet;  // the other ranks' log
  std::ostream& log = world.rank == 0 ? std::cout : quiet;
  const dem::RunOptions options = run_options(args, split.domain.get(), output);
  const CaseRun case_run{args, spec, as_run.text, model, state};
  const dem::RunSummary summary = run_reporting_a_stop(case_run, work, options, log);
  if (world.rank != 0 || summary.already_complete) return 0;
  write_beside_results(case_run, summary);
  return 0;
}

/// Renders saved frames of a finished (or running) run: the case comes from run_info.yaml.
int render_results(const std::string& out, const std::string& which, const dem::app::ImageOptions& given, bool video) {
  std::ifstream info(out + "/run_info.yaml");
  if (!info) throw dem::CaseError(fmt::format("{}/run_info.yaml: not a demdesign output folder (give the --out folder of a run)", out));
  std::string line, case_path;
  while (std::getline(info, line))
    if (line.rfind("case: ", 0) == 0) case_path = line.substr(6);
  // The case as it ran (a sweep variant has its values set in OUT/case.yaml); relative paths in it
  // resolve against the original case file.
  dem::CaseSpec spec;
  if (std::filesystem::exists(out + "/case.yaml")) {
    spec = dem::parse_case_node(load_case_yaml(out + "/case.yaml"), case_path, dem::materials::library_lookup());
    dem::equipment::expand_equipment(spec);
  } else {
    spec = read_case(case_path);
  }
  const dem::Model model = compile_case(spec);
  dem::FrameWriter frames(out, {}, {});
  frames.adopt_existing();
  if (frames.frames().empty()) throw std::runtime_error(fmt::format("{}: no frames listed in particles.xdmf", out));
  std::vector<dem::FrameInfo> chosen;
  if (which == "all") chosen = frames.frames();
  else if (which == "last") chosen = {frames.frames().back()};
  else {
    const long index = std::stol(which);
    if (index < 0 || index >= static_cast<long>(frames.frames().size()))
      throw std::runtime_error(fmt::format("--frame {}: the run has frames 0 to {}", which, frames.frames().size() - 1));
    chosen = {frames.frames()[index]};
  }
  std::filesystem::create_directories(out + "/renders");
  for (const dem::FrameInfo& info_frame : chosen) {
    const dem::StoredFrame f = dem::read_frame(out + "/" + info_frame.file);
    dem::State s = dem::initial_state(model);  // walls where they start
    s.time = f.time, s.step = f.step;
    s.x.resize(f.size()), s.y.resize(f.size()), s.z.resize(f.size());
    s.vx.resize(f.size()), s.vy.resize(f.size()), s.vz.resize(f.size());
    s.radius = f.radius, s.material = f.material;
    for (size_t p = 0; p < f.size(); ++p) {
      s.x[p] = f.position[3 * p], s.y[p] = f.position[3 * p + 1], s.z[p] = f.position[3 * p + 2];
      s.vx[p] = f.velocity[3 * p], s.vy[p] = f.velocity[3 * p + 1], s.vz[p] = f.velocity[3 * p + 2];
    }
    const std::string path = fmt::format("{}/renders/frame_{:06d}.png", out, f.step);
    dem::app::render_state(model, s, given, path);
    std::cout << fmt::format("rendered {}\n", path);
  }
  if (video) {
    std::string message;
    const std::string movie = out + "/renders/flow.mp4";
    if (dem::app::make_video(out + "/renders", "frame_", movie, 10.0, &message)) std::cout << fmt::format("video {}\n", movie);
    else std::cout << message << "\n";
  }
  return 0;
}

/// The exit status of an error. Under MPI the error may be this rank's alone, and the others
/// would wait for it forever: every rank stops.
int stop_with(int code) {
  std::cerr << std::flush;
  dem::app::mpi::abort(code);
  return code;
}

std::string rank_prefix() {
  const dem::app::mpi::World& world = dem::app::mpi::world();
  return world.active() ? fmt::format("rank {}: ", world.rank) : "";
}

/// What the command line fills, command by command: CLI11 writes into it while parsing, so it
/// stays where it is until the command has run.
struct CommandLine {
  RunArgs run;  ///< demdesign CASE, demdesign run CASE
  std::string check_path;
  CLI::App* check_cmd = nullptr;
  std::vector<std::string> mesh_files;
  dem::geometry::ImportOptions mesh_options;
  double mesh_particle_diameter = 0;
  CLI::App* mesh_cmd = nullptr;
  std::string render_out, render_frame = "last";
  dem::app::ImageOptions render_options;
  bool render_video = false;
  CLI::App* render_cmd = nullptr;
  std::string compare_a, compare_b, compare_out;  ///< compare-runs A B --out DIR
  CLI::App* compare_runs_cmd = nullptr;
  CLI::App* effects_cmd = nullptr;
  CLI::App* materials_cmd = nullptr;
  bool keys_markdown = false;
  std::string keys_source;
  CLI::App* keys_cmd = nullptr;
  std::string validate_out = "out/validation", validate_source;
  CLI::App* validate_cmd = nullptr;
};

/// The options of a run, on `demdesign CASE` and on `demdesign run CASE`.
void add_run_options(CLI::App* cmd, RunArgs& args) {
  cmd->add_option("--duration", args.duration, "simulated time [s], overrides the case")->check(dem::app::number_in(0, 1e6, "s", true));
  cmd->add_option("--max-steps", args.max_steps, "stop after this many steps (shortened run)")->check(dem::app::whole_in(1, 1e15));
  cmd->add_option("--threads", args.threads, "OpenMP threads (default: all cores)")->check(dem::app::whole_in(1, 1024));
  cmd->add_option("--out", args.out, "output folder (default: the case's output.directory)");
  cmd->add_flag("--quiet", args.quiet, "no progress lines");
  cmd->add_flag("!--no-report", args.report, "skip the report (renders, plots, report.html)");
  cmd->add_option("--variant", args.variant, "run only this variant (0-based) of the case's sweep")->group("");
  cmd->add_option("--rank-grid", args.rank_grid, "under mpirun: the grid of boxes, NXxNYxNZ (default: chosen from the domain's shape)");
  cmd->add_option("--balance", args.balance,
                  "under mpirun: what the cuts balance: work (particles and contacts, reproducible) or time (each rank's measured computing time)")
      ->check(CLI::IsMember({"work", "time"}));
  CLI::Option* resume = cmd->add_flag("--resume", args.resume, "continue from OUT's checkpoint (written every output.checkpoint_every, and on SIGINT/SIGTERM; a run split over ranks resumes on any rank count)");
  cmd->add_flag("--overwrite", args.overwrite,
                "replace the results of an earlier run in OUT: removes the files runs wrote there (run_files.txt), nothing else")
      ->excludes(resume);
}

/// Running a case: `demdesign CASE` and `demdesign run CASE`.
void add_run_commands(CLI::App& app, RunArgs& args) {
  app.add_option("case", args.case_path, "case file (YAML) to run");
  add_run_options(&app, args);
  CLI::App* run_cmd = app.add_subcommand("run", "run a case");
  run_cmd->add_option("case", args.case_path, "case file (YAML)")->required();
  add_run_options(run_cmd, args);
}

/// The commands on a case, its meshes and its results: check, check-mesh, render.
void add_case_tools(CLI::App& app, CommandLine& line) {
  line.check_cmd = app.add_subcommand("check", "read and compile a case and print its set-up");
  line.check_cmd->add_option("case", line.check_path, "case file (YAML)")->required();
  line.mesh_cmd = app.add_subcommand("check-mesh", "import meshes (STL, OBJ, PLY, glTF, 3MF, ...), check and repair them");
  line.mesh_cmd->add_option("files", line.mesh_files, "mesh files")->required();
  line.mesh_cmd->add_option("--unit-scale", line.mesh_options.unit_scale, "file units to metres (0.001 for millimetres)");
  line.mesh_cmd->add_option("--particle-diameter", line.mesh_particle_diameter, "[m] enables the triangle size checks");
  line.render_cmd = app.add_subcommand("render", "render saved frames of a run to PNG (headless)");
  line.render_cmd->add_option("results", line.render_out, "output folder of a run")->required();
  line.render_cmd->add_option("--frame", line.render_frame, "frame index, last or all")
      ->check(CLI::Validator(
          [](std::string& text) {
            return text == "last" || text == "all" || dem::app::whole_in(0, 1e9)(text).empty()
                       ? std::string()
                       : fmt::format("'{}' is not a frame; valid: a frame index (0, 1, ...), last or all", text);
          },
          "INDEX|last|all"));
  line.render_cmd->add_option("--color-by", line.render_options.colour, "speed, radius or material")
      ->check(CLI::IsMember({"speed", "radius", "material"}));
  line.render_cmd->add_option("--camera", line.render_options.camera, "side, front, top or iso")
      ->check(CLI::IsMember({"side", "front", "top", "iso"}));
  line.render_cmd->add_flag("--video", line.render_video, "also encode the rendered frames as renders/flow.mp4 (needs ffmpeg)");
  line.render_cmd->add_option("--width", line.render_options.width, "[px]")->check(dem::app::whole_in(16, 8192));
  line.render_cmd->add_option("--height", line.render_options.height, "[px]")->check(dem::app::whole_in(16, 8192));
  line.compare_runs_cmd = app.add_subcommand("compare-runs", "compare two finished runs (design variants, or one design before and "
                                                              "after a change) figure by figure: A and B with their standard errors, "
                                                              "B - A and the difference in standard errors (compare.html, compare.csv)");
  line.compare_runs_cmd->add_option("A", line.compare_a, "output folder of the first run (the reference)")->required();
  line.compare_runs_cmd->add_option("B", line.compare_b, "output folder of the second run")->required();
  line.compare_runs_cmd->add_option("--out", line.compare_out, "output folder (default: beside A, compare_A_B)");
}

/// The reference commands: effects, materials, keys, validate.
void add_reference_commands(CLI::App& app, CommandLine& line) {
  line.effects_cmd = app.add_subcommand("effects", "list the contact effects and their parameters");
  line.materials_cmd = app.add_subcommand("materials", "list the material library (materials/*.yaml)");
  line.keys_source = dem::app::default_source_dir();
  line.keys_cmd = app.add_subcommand("keys", "every key of case, material and measurement files, read from the "
                                             "readers themselves (docs/case-keys.md is its --markdown output)");
  line.keys_cmd->add_flag("--markdown", line.keys_markdown, "Markdown tables, as in docs/case-keys.md");
  line.keys_cmd->add_option("--source", line.keys_source, "source tree whose shipped files are read (default: the one built from)");

  line.validate_source = dem::app::default_source_dir();
  line.validate_cmd = app.add_subcommand("validate", "run the published benchmarks (Chung & Ooi 2011 tests 1-8) and write a "
                                                     "validation page with tables and plots");
  line.validate_cmd->add_option("--out", line.validate_out, "output folder (validation.html, validation.md, validation.csv, plots/)");
  line.validate_cmd->add_option("--source", line.validate_source, "source tree whose cases/ are run (default: the one built from)");
}

/// A first word that is neither an option, a command nor a file is most likely a misspelt
/// command (CLI11 would take it for the case file and then complain about the next word): says
/// so, with the nearest command, and returns true.
bool reject_misspelt_command(CLI::App& app, int argc, char** argv) {
  if (argc > 1 && argv[1][0] != '-' && !std::filesystem::exists(argv[1])) {
    std::vector<std::string> commands;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) commands.push_back(sub->get_name());
    if (std::find(commands.begin(), commands.end(), argv[1]) == commands.end()) {
      const std::string hint = dem::nearest_word(argv[1], commands);
      std::cerr << fmt::format("error: '{}' is neither a command{} nor a case file; commands: {} (or give a case file to run)\n", argv[1],
                               hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), fmt::join(commands, ", "));
      return true;
    }
  }
  return false;
}

/// Runs the parsed command; returns the exit status.
int run_command(CLI::App& app, const CommandLine& line, dem::app::CalibrationCommands& calibration) {
  const dem::app::mpi::World& world = dem::app::mpi::world();
  if (calibration.parsed()) return calibration.run();  // compare, calibrate, diagnose: every rank; test: rank 0
  // Commands that are not campaigns run on rank 0; a case decides in run_case (a sweep uses every rank).
  if (world.active() && world.rank != 0 && line.run.case_path.empty()) return 0;
  if (line.effects_cmd->parsed()) {
    std::cout << dem::describe_effects();
    return 0;
  }
  if (line.materials_cmd->parsed()) {
    std::cout << fmt::format("material library: {}\n", dem::materials::library_folder());
    for (const auto& m : dem::materials::list_library())
      std::cout << fmt::format("  {:<20} {}\n", m.name, m.description);
    std::cout << "use in a case: materials: {NAME: {library: FILE_STEM}}\n";
    return 0;
  }
  if (line.keys_cmd->parsed()) {
    std::cout << dem::app::case_key_reference(line.keys_source, line.keys_markdown);
    return 0;
  }
  if (line.validate_cmd->parsed()) return dem::app::validate_command(line.validate_source, line.validate_out, std::cout);
  if (line.check_cmd->parsed()) return check_case(line.check_path);
  if (line.mesh_cmd->parsed()) return dem::geometry::check_mesh_command(line.mesh_files, line.mesh_options, line.mesh_particle_diameter, std::cout);
  if (line.render_cmd->parsed()) return render_results(line.render_out, line.render_frame, line.render_options, line.render_video);
  if (line.compare_runs_cmd->parsed()) return dem::report::compare_runs_command(line.compare_a, line.compare_b, line.compare_out, std::cout);
  if (line.run.case_path.empty()) {
    std::cout << app.help();
    return 2;
  }
  return run_case(line.run);
}

}  // namespace

int main(int argc, char** argv) {
  dem::tune_allocator();
  // MPI only when mpirun (or another MPI launcher) started this process; see app/campaign/mpi_campaign.h.
  dem::app::mpi::Session mpi_session(&argc, &argv);
  CLI::App app{"demdesign: DEM simulation for the design of bulk-materials-handling equipment"};
  app.require_subcommand(0, 1);
  CommandLine line;
  add_run_commands(app, line.run);
  add_case_tools(app, line);
  add_reference_commands(app, line);

  // Calibration: test, compare, calibrate, diagnose (materials/ simulates, app/ reports and renders).
  dem::app::CalibrationCommands calibration(app, [](const dem::Model& m, const dem::State& s, const std::string& png) {
    dem::app::render_state(m, s, {"", "speed", 1280, 720}, png);
  });

  if (reject_misspelt_command(app, argc, argv)) return 2;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end with 0; a bad command line with 2, as every other bad input.
    return app.exit(e) == 0 ? 0 : 2;
  }
  for (int k = 0; k < argc; ++k) line.run.command_line += (k ? " " : "") + std::string(argv[k]);
  try {
    return run_command(app, line, calibration);
  } catch (const dem::CaseError& e) {
    std::cerr << rank_prefix() << "error: " << e.what() << "\n";
    return stop_with(2);
  } catch (const dem::NumericalError& e) {
    std::cerr << rank_prefix() << "numerical trouble: " << e.what() << "\n";
    return stop_with(3);
  } catch (const std::exception& e) {
    std::cerr << rank_prefix() << "error: " << e.what() << "\n";
    return stop_with(1);
  }
}
