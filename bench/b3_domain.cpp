// Benchmark B3 "split box": benchmark B1 (b1_spec.h: the lattice settling in an open-top box,
// then the dense bed) split into slabs over the ranks of `mpirun -np R` (domain decomposition,
// app/mpi/mpi_domain.h), to measure what the decomposition costs and buys. Without mpirun it is one
// process, the reference. Prints per phase: particle-steps/s of all ranks together, and rank 0's
// communication time and volume per step (what the scaling model in the README is built from).
//
// Usage: [mpirun -np R] bench_b3_domain [--n N] [--threads T] [--phase1-steps S1] [--phase2-steps S2]
//                                        [--rank-grid NXxNYxNZ] [--balance work|time] [--frames DIR]
//                                        [--bed FILE]
//   N as in B1 (20000, 100000, or 2000-4000000 for the 32-layer family); one "csv," line per phase.
//   --frames DIR: after each phase (untimed in the rate) one particle frame into DIR, written by
//   every rank together (parallel HDF5) and, for comparison, gathered on rank 0 and written by it
//   alone; prints both times.
//   --bed FILE: the settled bed as a checkpoint (output/checkpoint.h). When FILE exists, the run
//   starts from it and times the dense phase alone (the settle phase is skipped), so that one
//   settled bed is measured on 1 and 2 cores and over 2 and 4 ranks; otherwise the settle phase
//   runs and its end is written to FILE.
#include <fmt/format.h>
#include <omp.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include "b1_spec.h"
#include "base/allocator.h"
#include "core/domain.h"
#include "core/step.h"
#include "campaign/mpi_campaign.h"
#include "mpi/mpi_domain.h"
#include "mpi/mpi_frames.h"
#include "output/checkpoint.h"
#include "output/results_hdf5.h"
#include "output/run.h"
#include "statistics/diagnostics.h"

namespace {

namespace mpi = dem::app::mpi;

struct Options {
  long n = 20000;
  int threads = 0;
  long phase1 = -1, phase2 = -1;
  std::array<int, 3> grid{0, 0, 0};
  mpi::Balance balance = mpi::Balance::work;
  std::string frames;
  std::string bed;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto value = [&]() -> const char* {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++k];
    };
    if (a == "--n") o.n = std::atol(value());
    else if (a == "--threads") o.threads = std::atoi(value());
    else if (a == "--phase1-steps") o.phase1 = std::atol(value());
    else if (a == "--phase2-steps") o.phase2 = std::atol(value());
    else if (a == "--rank-grid") {
      if (std::sscanf(value(), "%dx%dx%d", &o.grid[0], &o.grid[1], &o.grid[2]) != 3) {
        std::fprintf(stderr, "--rank-grid: expected NXxNYxNZ, for example 2x2x1\n");
        std::exit(2);
      }
    } else if (a == "--balance") {
      const std::string v = value();
      if (v != "work" && v != "time") {
        std::fprintf(stderr, "--balance: work or time\n");
        std::exit(2);
      }
      o.balance = v == "time" ? mpi::Balance::time : mpi::Balance::work;
    } else if (a == "--frames") {
      o.frames = value();
    } else if (a == "--bed") {
      o.bed = value();
    } else {
      std::fprintf(stderr,
                   "unknown option %s\nusage: [mpirun -np R] %s [--n N] [--threads T] [--phase1-steps S1] [--phase2-steps S2] "
                   "[--rank-grid NXxNYxNZ] [--balance work|time] [--frames DIR] [--bed FILE]\n",
                   a.c_str(), argv[0]);
      std::exit(2);
    }
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  dem::tune_allocator();
  mpi::Session session(&argc, &argv);
  const mpi::World& world = mpi::world();
  const Options o = parse(argc, argv);
  if (o.threads > 0) omp_set_num_threads(o.threads);
  bench::b1::Size b = bench::b1::size_for(o.n);
  if (o.phase1 >= 0) b.phase1 = o.phase1;
  if (o.phase2 >= 0) b.phase2 = o.phase2;
  dem::CaseSpec spec = dem::parse_case_text(bench::b1::case_yaml(b), "b3_domain");
  spec.particles[0].positions = bench::b1::lattice(b);
  spec.particles[0].count = static_cast<std::int64_t>(spec.particles[0].positions.size());
  const dem::Model model = dem::compile(spec);
  const bool from_bed = !o.bed.empty() && std::filesystem::exists(o.bed);
  dem::State state = from_bed ? dem::load_checkpoint(o.bed, model) : dem::initial_state(model);
  const double total = static_cast<double>(state.size());
  std::string note = "one process";
  std::unique_ptr<dem::Domain> domain = world.active() ? mpi::make_domain(model, state, &note, o.grid, true, o.balance) : nullptr;
  if (world.active() && !domain) {
    std::fprintf(stderr, "cannot split: %s\n", note.c_str());
    return 2;
  }
  const dem::Model& stepped = domain ? domain->local_model() : model;
  dem::Workspace work;
  work.domain = domain.get();
  if (domain) domain->distribute(state);
  dem::prepare(stepped, state, work);
  if (world.rank == 0)
    fmt::print("B3 split box: B1 with N = {} on {} ranks x {} threads; {}\n", b.n(), world.size, omp_get_max_threads(), note);

  // One frame of the state: by every rank together (a split run) or by the one process; then,
  // split, the same gathered on rank 0 and written alone. Prints the seconds of each.
  const auto share_frame = domain ? mpi::collective_frames() : nullptr;
  const auto write_frames = [&](const char* name) {
    if (o.frames.empty()) return;
    const auto seconds_since = [](auto start) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    if (domain) domain->any(false);
    auto start = std::chrono::steady_clock::now();
    dem::FrameWriter together(o.frames + "/" + name + "_together", {"beads"}, {});
    if (domain) {
      const dem::FrameShare share = share_frame(state.owned());
      dem::write_frame(together, state, &share);
    } else {
      dem::write_frame(together, state);
    }
    if (domain) domain->any(false);
    const double written_together = seconds_since(start);
    const double bytes = static_cast<double>(total) * (8 * 4 + 8 * 3 * 3 + 8 * 4 + 4 * 2);  // id, speed, radius, connectivity; 3 vectors; quaternion; 2 ints
    if (!domain) {
      fmt::print("  frame after {}: {:.3g} GB by one process in {:.3f} s\n", name, 1e-9 * bytes, written_together);
      return;
    }
    start = std::chrono::steady_clock::now();
    const dem::State gathered = domain->gather(state);
    const double gathering = seconds_since(start);
    if (world.rank == 0) {
      dem::FrameWriter alone(o.frames + "/" + name + "_alone", {"beads"}, {});
      dem::write_frame(alone, gathered);
    }
    domain->any(false);
    const double gathered_and_written = seconds_since(start);
    if (world.rank == 0)
      fmt::print("  frame after {}: {:.3g} GB written together by {} ranks in {:.3f} s; gathered on rank 0 in {:.3f} s and written by it in {:.3f} s\n",
                 name, 1e-9 * bytes, world.size, written_together, gathering, gathered_and_written - gathering);
  };

  auto run_phase = [&](const char* name, std::int64_t steps) {
    if (domain) domain->any(false);  // start together
    const auto start = std::chrono::steady_clock::now();
    for (std::int64_t k = 0; k < steps; ++k) dem::step(stepped, state, work);
    if (domain) domain->any(false);  // the slowest rank sets the time
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_frames(name);
    // Outside the timed loop: the whole state on rank 0 for the physics check.
    dem::State gathered = domain ? domain->gather(state) : state;
    if (world.rank != 0) return;
    const dem::WholeState ready = dem::ready_for_results(model, std::move(gathered));
    const dem::State& whole = ready.state;
    const dem::Scalars sc = dem::measure(model, ready.evaluated, ready.work);
    double bed = 0;
    for (size_t p = 0; p < whole.size(); ++p) bed = std::max(bed, whole.z[p] + whole.radius[p]);
    const double rate = total * static_cast<double>(steps) / seconds;
    fmt::print("  {}: {} steps in {:.2f} s, {:.4g} particle-steps/s; contacts/particle {:.3f}, bed {:.4f} m, particles {}\n", name,
               steps, seconds, rate, static_cast<double>(sc.contacts) / total, bed, whole.size());
    if (domain) fmt::print("    rank 0: {}\n", domain->statistics());
    fmt::print("csv,{},{},{},{},{},{:.4f},{:.6g},{:.4f},{:.5f}\n", b.n(), name, steps, world.size, omp_get_max_threads(), seconds, rate,
               static_cast<double>(sc.contacts) / total, bed);
    std::fflush(stdout);
  };
  if (world.rank == 0) fmt::print("csv,N,phase,steps,ranks,threads_per_rank,seconds,particle_steps_per_s,contacts_per_particle,bed_height_m\n");
  if (from_bed) {
    if (world.rank == 0) fmt::print("  the settled bed from {} (step {})\n", o.bed, state.step);
  } else {
    run_phase("settle", b.phase1);
    if (!o.bed.empty()) {
      const dem::State gathered = domain ? domain->gather(state) : state;
      if (world.rank == 0) dem::save_checkpoint(o.bed, model, gathered);
    }
  }
  run_phase("dense", b.phase2);
  return 0;
}
