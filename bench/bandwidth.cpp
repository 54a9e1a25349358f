// Memory bandwidth of this machine (STREAM triad a = b + s c, OpenMP), and from it the bound on
// particle time steps per second for the state a DEM step must touch. The figure the engine is
// held against: particle-steps/s of B1 divided by this bound.
//
// Bytes a step must move per particle (velocity Verlet, spheres, contacts with history), at the
// least: position, velocity, angular velocity and radius read and the first three written
// (10 doubles read, 9 written = 152 bytes), force and torque written and read back once (6 + 6
// doubles = 96 bytes), and per listed pair its partner index (4 bytes) and, per touching contact,
// its tangential history read and written (48 bytes). B1's dense bed has 4.6 listed pairs and
// 2.2 touching pairs per particle: 152 + 96 + 18 + 106 = 372 bytes per particle step.
// Usage: bench_bandwidth [--threads T] [--mib MiB per array] [--bytes-per-step B]
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

double triad_gb_per_s(std::size_t n, int repetitions) {
  std::vector<double> a(n), b(n), c(n);
  const long nl = static_cast<long>(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < nl; ++i) a[i] = 0.0, b[i] = 1.0, c[i] = 2.0;  // first touch by the thread that streams it
  double best = 1e300;
  for (int r = 0; r < repetitions; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const double s = 0.5 + r;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < nl; ++i) a[i] = b[i] + s * c[i];
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  volatile double sink = a[n / 2];
  (void)sink;
  return 3.0 * sizeof(double) * static_cast<double>(n) / best / 1e9;  // read b, c; write a
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 0;
  double mib = 256, bytes_per_step = 372;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string arg = argv[k];
    const double v = std::atof(argv[k + 1]);
    if (arg == "--threads") threads = static_cast<int>(v);
    else if (arg == "--mib") mib = v;
    else if (arg == "--bytes-per-step") bytes_per_step = v;
    else {
      std::fprintf(stderr, "usage: %s [--threads T] [--mib MiB per array] [--bytes-per-step B]\n", argv[0]);
      return 1;
    }
  }
  if (threads > 0) omp_set_num_threads(threads);
  const std::size_t n = static_cast<std::size_t>(mib * 1024 * 1024 / sizeof(double));
  const double dram = triad_gb_per_s(n, 10);
  // Arrays of 1 MiB each: 3 MiB in all, what B1 20k's hot particle columns occupy (cache).
  const double cache = triad_gb_per_s(1024 * 1024 / sizeof(double), 2000);
  fmt::print("threads {}: triad {:.1f} GB/s (3 x {:.0f} MiB arrays, memory), {:.1f} GB/s (3 x 1 MiB, cache)\n",
             omp_get_max_threads(), dram, mib, cache);
  fmt::print("bound at {:.0f} bytes per particle step: {:.3g} particle-steps/s from memory, {:.3g} from cache\n",
             bytes_per_step, dram * 1e9 / bytes_per_step, cache * 1e9 / bytes_per_step);
  fmt::print("csv,{},{:.2f},{:.2f},{:.0f},{:.4g},{:.4g}\n", omp_get_max_threads(), dram, cache, bytes_per_step,
             dram * 1e9 / bytes_per_step, cache * 1e9 / bytes_per_step);
  return 0;
}
