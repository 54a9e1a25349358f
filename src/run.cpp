#include "run.h"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <ostream>

#include "step.h"

namespace dem {

namespace {

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
  if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

std::string scalars_csv(const std::vector<Scalars>& rows) {
  std::string out =
      "time_s,step,particles,kinetic_translation_J,kinetic_rotation_J,contacts,max_overlap_ratio,mean_overlap_ratio,"
      "dt_s,lost\n";
  for (const Scalars& r : rows)
    out += fmt::format("{:.9g},{},{},{:.9g},{:.9g},{},{:.6g},{:.6g},{:.6g},{}\n", r.time, r.step, r.particles,
                       r.kinetic_translation, r.kinetic_rotation, r.contacts, r.max_overlap_ratio, r.mean_overlap_ratio,
                       r.dt, r.lost);
  return out;
}

}  // namespace

void write_file_atomically(const std::string& path, const std::string& content) {
  const std::filesystem::path target(path);
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
  const std::string temporary = path + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << content;
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write (disk full or no permission?)", temporary));
  }
  std::filesystem::rename(temporary, target);
}

void print_setup(const Model& model, const State& state, std::ostream& log) {
  fmt::print(log, "demdesign: {}{}\n", model.source, model.title.empty() ? "" : " - " + model.title);
  fmt::print(log, "  {} particles, {} materials, {} plane walls, {} threads\n", state.size(), model.materials.size(),
             model.planes.size(), omp_get_max_threads());
  std::string law;
  for (const ActiveEffect& e : model.effects)
    law += fmt::format("{}{}: {}", law.empty() ? "" : ", ", kStageKeys[static_cast<int>(e.spec->stage)], e.spec->name);
  fmt::print(log, "  contact law: {}\n", law);
  for (const ActiveEffect& e : model.effects) fmt::print(log, "    {}: {}\n", e.spec->name, e.spec->citation);
  fmt::print(log, "{}\n", model.advice.report);
  fmt::print(log, "  neighbour skin {:.3g} m, interaction range {:.3g} m\n", model.skin, model.interaction_range);
  for (const std::string& note : model.notes) fmt::print(log, "  note: {}\n", note);
}

RunSummary run(const Model& model, State& state, Workspace& work, const RunOptions& options, std::ostream& log) {
  RunSummary summary;
  summary.output_directory = options.output_directory.empty() ? model.output.directory : options.output_directory;
  const double duration = options.duration >= 0 ? options.duration : model.duration;
  std::int64_t total_steps = static_cast<std::int64_t>(std::ceil(duration / model.dt - 1e-9));
  if (options.max_steps >= 0) total_steps = std::min(total_steps, options.max_steps);
  const std::int64_t every =
      model.output.scalars_every > 0 ? model.output.scalars_every : std::max<std::int64_t>(1, total_steps / 200);

  print_setup(model, state, log);
  prepare(model, state, work);
  summary.scalars.push_back(measure(model, state, work));

  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last_progress = start;
  std::int64_t particle_steps = 0;
  for (std::int64_t k = 1; k <= total_steps; ++k) {
    step(model, state, work);
    particle_steps += static_cast<std::int64_t>(state.size());
    if (k % every == 0 || k == total_steps) {
      check_numerics(model, state, work);
      summary.scalars.push_back(measure(model, state, work));
    }
    const auto now = Clock::now();
    if (options.progress && std::chrono::duration<double>(now - last_progress).count() >= model.output.progress_seconds) {
      last_progress = now;
      const double elapsed = std::chrono::duration<double>(now - start).count();
      const double left = elapsed / static_cast<double>(k) * static_cast<double>(total_steps - k);
      fmt::print(log, "  t = {:.4g} / {:.4g} s ({:.0f} %), {} particles, {:.3g} particle-steps/s, time left {}\n",
                 state.time, duration, 100.0 * k / total_steps, state.size(), particle_steps / elapsed, format_duration(left));
      log.flush();
    }
  }
  summary.steps = total_steps;
  summary.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.particle_steps_per_second = summary.wall_seconds > 0 ? particle_steps / summary.wall_seconds : 0.0;

  const Scalars& last = summary.scalars.back();
  fmt::print(log, "  done: {} steps to t = {:.6g} s in {:.2f} s ({:.3g} particle-steps/s, {} neighbour-list rebuilds)\n",
             summary.steps, state.time, summary.wall_seconds, summary.particle_steps_per_second, work.rebuilds);
  fmt::print(log, "  end: {} particles, {} contacts, kinetic energy {:.4g} J, max overlap {:.2g} % of radius{}\n",
             last.particles, last.contacts, last.kinetic_translation + last.kinetic_rotation, 100 * last.max_overlap_ratio,
             state.lost ? fmt::format(", {} particles left the domain", state.lost) : "");
  if (options.write_files) {
    const std::string path = summary.output_directory + "/scalars.csv";
    write_file_atomically(path, scalars_csv(summary.scalars));
    fmt::print(log, "  wrote {}\n", path);
  }
  return summary;
}

}  // namespace dem
