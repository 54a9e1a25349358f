#include "core/cell_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "base/allocator.h"
#include "base/parallel.h"

namespace dem {

namespace {

/// The running sum of a column in place (a[k] becomes a[0] + ... + a[k]), in one piece per
/// thread when long (each thread sums its piece, then writes it from the sum of those before).
void running_sum(std::vector<std::int32_t>& a) {
  const long size = static_cast<long>(a.size());
  if (size < (1L << 16)) {
    std::partial_sum(a.begin(), a.end(), a.begin());
    return;
  }
  std::vector<std::int64_t> piece_sum(static_cast<size_t>(omp_get_max_threads()) + 1, 0);
#pragma omp parallel
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const long lo = size * t / nt, hi = size * (t + 1) / nt;
    piece_sum[t + 1] = std::accumulate(a.begin() + lo, a.begin() + hi, std::int64_t{0});
#pragma omp barrier
    const auto offset = std::accumulate(piece_sum.begin(), piece_sum.begin() + t + 1, std::int64_t{0});
    auto sum = static_cast<std::int32_t>(offset);
    for (long k = lo; k < hi; ++k) sum += a[k], a[k] = sum;
  }
}

}  // namespace

Grid make_grid(const Model& model, const State& s, double cell, const std::uint8_t* keep) {
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (size_t p = 0; p < s.size(); ++p) {
    if (keep && !keep[p]) continue;
    lo[0] = std::min(lo[0], s.x[p]), hi[0] = std::max(hi[0], s.x[p]);
    lo[1] = std::min(lo[1], s.y[p]), hi[1] = std::max(hi[1], s.y[p]);
    lo[2] = std::min(lo[2], s.z[p]), hi[2] = std::max(hi[2], s.z[p]);
  }
  Grid g;
  for (int a = 0; a < 3; ++a) {
    g.wrap[a] = model.period[a] > 0;
    g.period[a] = model.period[a];
    if (g.wrap[a]) lo[a] = model.domain_min[a], hi[a] = model.domain_max[a];
  }
  // Cap the number of cells at 4 per particle, or 2^19 (2 MiB of cell starts) if more: a few
  // particles flung far away must not make the grid huge, while a thin stream in a large box
  // (a chute) keeps cells one reach wide. Larger cells stay correct, only slower: a cap of 4 per
  // particle alone widened the chute's cells and multiplied the candidates to measure
  // (bench/results/design_measurements.csv).
  // Periodic axes keep whole periods.
  const double cap = std::max(4.0 * static_cast<double>(s.size()) + 64.0, 524288.0);
  for (;;) {
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
      g.dims[a] = g.wrap[a] ? std::max(1, static_cast<int>(std::floor(g.period[a] / cell)))
                            : static_cast<int>(std::floor((hi[a] - lo[a]) / cell)) + 1;
      g.cell[a] = g.wrap[a] ? g.period[a] / g.dims[a] : cell;
      g.origin[a] = lo[a];
      cells *= g.dims[a];
    }
    if (cells <= cap) break;
    cell *= 1.26;
  }
  // Major axis: the non-periodic axis of most cells (a pair across a periodic boundary of the
  // major axis would stretch the slot span to the whole system).
  std::stable_sort(g.order, g.order + 3, [&](int a, int b) {
    return std::pair(!g.wrap[a], g.dims[a]) < std::pair(!g.wrap[b], g.dims[b]);
  });
  return g;
}

// Each cell's count goes one place above its start (cell_start[c + 2]), so that after the
// running sum cell_start[c + 1] is c's start, the scatter's cursor, which ends at c + 1's.
void sort_by_cell(const std::vector<std::int32_t>& cell_of, size_t n, int n_cells, std::vector<std::int32_t>& cell_start,
                  std::vector<std::int32_t>& out) {
  const long size = static_cast<long>(n_cells) + 2;
  resize_discarding(cell_start, static_cast<size_t>(size));
  std::int32_t* start = cell_start.data();
#pragma omp parallel for schedule(static) if (size >= (1L << 16))
  for (long c = 0; c < size; ++c) start[c] = 0;
  for (size_t p = 0; p < n; ++p)
    if (cell_of[p] >= 0) ++start[cell_of[p] + 2];
  running_sum(cell_start);  // now cell_start[c + 1] is where cell c begins
  for (size_t p = 0; p < n; ++p)
    if (cell_of[p] >= 0) out[start[cell_of[p] + 1]++] = static_cast<std::int32_t>(p);
}

}  // namespace dem
