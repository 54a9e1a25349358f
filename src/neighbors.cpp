#include "neighbors.h"

#include "parallel.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace dem {

namespace {

/// A contact's history found before the rebuild, keyed by particle ids.
struct CarriedHistory {
  std::int64_t id_a, other;  ///< other: particle id, or wall index for wall contacts
  size_t row;                ///< in the old history array
};

bool row_is_zero(const double* row, int width) {
  for (int k = 0; k < width; ++k)
    if (row[k] != 0.0) return false;
  return true;
}

/// Histories worth keeping (non-zero), with the ids they belong to.
std::vector<CarriedHistory> collect(const ContactList& list, const State& state, int width, bool walls) {
  std::vector<CarriedHistory> out;
  if (width == 0) return out;
  for (size_t k = 0; k < list.size(); ++k) {
    if (row_is_zero(&list.history[k * width], width)) continue;
    out.push_back({state.id[list.i[k]], walls ? list.j[k] : state.id[list.j[k]], k});
  }
  return out;
}

void remove_lost(const Model& model, State& state) {
  if (!model.has_domain) return;
  const size_t n = state.size();
  std::vector<std::uint8_t> keep(n, 1);
  size_t lost = 0;
  for (size_t p = 0; p < n; ++p) {
    const bool inside = state.x[p] >= model.domain_min[0] && state.x[p] <= model.domain_max[0] &&
                        state.y[p] >= model.domain_min[1] && state.y[p] <= model.domain_max[1] &&
                        state.z[p] >= model.domain_min[2] && state.z[p] <= model.domain_max[2];
    if (!inside) keep[p] = 0, ++lost;
  }
  if (lost == 0) return;
  state.compact(keep);
  state.lost += static_cast<std::int64_t>(lost);
}

struct Grid {
  double origin[3];
  double cell;
  int dims[3];
  int index(double x, double y, double z) const {
    const int cx = std::clamp(static_cast<int>((x - origin[0]) / cell), 0, dims[0] - 1);
    const int cy = std::clamp(static_cast<int>((y - origin[1]) / cell), 0, dims[1] - 1);
    const int cz = std::clamp(static_cast<int>((z - origin[2]) / cell), 0, dims[2] - 1);
    return (cz * dims[1] + cy) * dims[0] + cx;
  }
};

Grid make_grid(const State& s, double cell) {
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (size_t p = 0; p < s.size(); ++p) {
    lo[0] = std::min(lo[0], s.x[p]), hi[0] = std::max(hi[0], s.x[p]);
    lo[1] = std::min(lo[1], s.y[p]), hi[1] = std::max(hi[1], s.y[p]);
    lo[2] = std::min(lo[2], s.z[p]), hi[2] = std::max(hi[2], s.z[p]);
  }
  Grid g;
  // Cap the number of cells near 4 per particle: a few particles flung far away must not make
  // the grid huge. Larger cells stay correct, only slower.
  const double cap = 4.0 * static_cast<double>(s.size()) + 64.0;
  for (;;) {
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) cells *= std::floor((hi[a] - lo[a]) / cell) + 1.0;
    if (cells <= cap) break;
    cell *= 1.26;
  }
  g.cell = cell;
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = lo[a];
    g.dims[a] = static_cast<int>(std::floor((hi[a] - lo[a]) / cell)) + 1;
  }
  return g;
}

void build_csr(std::vector<std::int32_t>& begin, const std::vector<std::int32_t>& owner, size_t n) {
  begin.assign(n + 1, 0);
  for (const std::int32_t o : owner) ++begin[o + 1];
  for (size_t p = 0; p < n; ++p) begin[p + 1] += begin[p];
}

}  // namespace

void ContactForces::resize(std::size_t n) {
  for (auto* c : {&fx, &fy, &fz, &tix, &tiy, &tiz, &tjx, &tjy, &tjz}) c->assign(n, 0.0);
  active.assign(n, 0);
}

bool needs_rebuild(const Model& model, const State& s, const Workspace& work) {
  if (!work.valid || work.x_built.size() != s.size()) return true;
  const double limit2 = 0.25 * model.skin * model.skin;
  const long n = static_cast<long>(s.size());
  int moved = 0;
#pragma omp parallel for reduction(| : moved) schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) {
    const double dx = s.x[p] - work.x_built[p], dy = s.y[p] - work.y_built[p], dz = s.z[p] - work.z_built[p];
    moved |= (dx * dx + dy * dy + dz * dz > limit2);
  }
  return moved != 0;
}

void rebuild_contacts(const Model& model, State& s, Workspace& work) {
  const int width = model.history_width;
  const std::vector<CarriedHistory> old_pairs = collect(s.pairs, s, width, false);
  const std::vector<CarriedHistory> old_walls = collect(s.wall_pairs, s, width, true);
  const std::vector<double> old_pair_history = std::move(s.pairs.history);
  const std::vector<double> old_wall_history = std::move(s.wall_pairs.history);

  remove_lost(model, s);
  const size_t n = s.size();
  double radius_max = model.radius_max;
  for (size_t p = 0; p < n; ++p) radius_max = std::max(radius_max, s.radius[p]);
  const double reach = model.interaction_range + model.skin;  // [m] gap that still lists a pair

  // Sort slots by cell (counting sort); cells are at least one pair reach wide.
  const Grid grid = make_grid(s, std::max(2.0 * radius_max + reach, 1e-12));
  const int n_cells = grid.dims[0] * grid.dims[1] * grid.dims[2];
  work.cell_of.resize(n);
  work.cell_start.assign(static_cast<size_t>(n_cells) + 1, 0);
  for (size_t p = 0; p < n; ++p) {
    work.cell_of[p] = grid.index(s.x[p], s.y[p], s.z[p]);
    ++work.cell_start[work.cell_of[p] + 1];
  }
  for (int c = 0; c < n_cells; ++c) work.cell_start[c + 1] += work.cell_start[c];
  work.order.resize(n);
  {
    std::vector<std::int32_t> cursor(work.cell_start.begin(), work.cell_start.end() - 1);
    for (size_t p = 0; p < n; ++p) work.order[cursor[work.cell_of[p]]++] = static_cast<std::int32_t>(p);
  }
  s.permute(work.order);
  for (size_t p = 0; p < n; ++p) work.cell_of[p] = grid.index(s.x[p], s.y[p], s.z[p]);

  // Particle pairs: each slot lists partners j > i in the 27 cells around it.
  std::vector<std::int32_t> count(n + 1, 0);
  auto visit = [&](size_t i, auto&& emit) {
    const int c = work.cell_of[i];
    const int cx = c % grid.dims[0], cy = (c / grid.dims[0]) % grid.dims[1], cz = c / (grid.dims[0] * grid.dims[1]);
    for (int dz = -1; dz <= 1; ++dz) {
      const int z = cz + dz;
      if (z < 0 || z >= grid.dims[2]) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        const int y = cy + dy;
        if (y < 0 || y >= grid.dims[1]) continue;
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = cx + dx;
          if (x < 0 || x >= grid.dims[0]) continue;
          const int cell = (z * grid.dims[1] + y) * grid.dims[0] + x;
          for (int j = std::max<int>(work.cell_start[cell], static_cast<int>(i) + 1); j < work.cell_start[cell + 1]; ++j) {
            const double ddx = s.x[i] - s.x[j], ddy = s.y[i] - s.y[j], ddz = s.z[i] - s.z[j];
            const double cut = s.radius[i] + s.radius[j] + reach;
            if (ddx * ddx + ddy * ddy + ddz * ddz < cut * cut) emit(j);
          }
        }
      }
    }
  };
  const long nl = static_cast<long>(n);
#pragma omp parallel for schedule(static) if (nl >= kParallelMin)
  for (long i = 0; i < nl; ++i) {
    std::int32_t k = 0;
    visit(static_cast<size_t>(i), [&](int) { ++k; });
    count[i + 1] = k;
  }
  work.pair_begin.assign(n + 1, 0);
  for (size_t p = 0; p < n; ++p) work.pair_begin[p + 1] = work.pair_begin[p] + count[p + 1];
  const size_t n_pairs = static_cast<size_t>(work.pair_begin[n]);
  s.pairs.i.resize(n_pairs);
  s.pairs.j.resize(n_pairs);
#pragma omp parallel for schedule(static) if (nl >= kParallelMin)
  for (long i = 0; i < nl; ++i) {
    std::int32_t k = work.pair_begin[i];
    visit(static_cast<size_t>(i), [&](int j) {
      s.pairs.i[k] = static_cast<std::int32_t>(i);
      s.pairs.j[k++] = j;
    });
  }

  // Wall pairs, grouped by particle.
  s.wall_pairs.i.clear();
  s.wall_pairs.j.clear();
  for (size_t p = 0; p < n; ++p) {
    for (size_t w = 0; w < model.planes.size(); ++w) {
      const PlaneWall& wall = model.planes[w];
      const double d = (s.x[p] - wall.point[0]) * wall.normal[0] + (s.y[p] - wall.point[1]) * wall.normal[1] +
                       (s.z[p] - wall.point[2]) * wall.normal[2];
      if (d < s.radius[p] + reach && d > -s.radius[p]) {
        s.wall_pairs.i.push_back(static_cast<std::int32_t>(p));
        s.wall_pairs.j.push_back(static_cast<std::int32_t>(w));
      }
    }
  }
  build_csr(work.wall_begin, s.wall_pairs.i, n);

  // Incoming index: pairs in which slot p is j, in pair order.
  build_csr(work.incoming_begin, s.pairs.j, n);
  work.incoming.resize(n_pairs);
  {
    std::vector<std::int32_t> cursor(work.incoming_begin.begin(), work.incoming_begin.end() - 1);
    for (size_t k = 0; k < n_pairs; ++k) work.incoming[cursor[s.pairs.j[k]]++] = static_cast<std::int32_t>(k);
  }

  // Carry histories to the new lists by particle id.
  s.pairs.history.assign(n_pairs * width, 0.0);
  s.wall_pairs.history.assign(s.wall_pairs.size() * width, 0.0);
  if (width > 0 && (!old_pairs.empty() || !old_walls.empty())) {
    std::vector<std::int32_t> slot_of(static_cast<size_t>(s.next_id), -1);
    for (size_t p = 0; p < n; ++p) slot_of[s.id[p]] = static_cast<std::int32_t>(p);
    // Bucket old histories by the lower new slot of the pair.
    struct Entry { std::int32_t other; size_t row; };
    std::vector<std::vector<Entry>> bucket(n);
    for (const CarriedHistory& h : old_pairs) {
      const std::int32_t a = slot_of[h.id_a], b = slot_of[h.other];
      if (a < 0 || b < 0) continue;  // a particle left
      bucket[std::min(a, b)].push_back({std::max(a, b), h.row});
    }
    for (size_t k = 0; k < n_pairs; ++k) {
      for (const Entry& e : bucket[s.pairs.i[k]])
        if (e.other == s.pairs.j[k]) {
          std::memcpy(&s.pairs.history[k * width], &old_pair_history[e.row * width], width * sizeof(double));
          break;
        }
    }
    for (auto& b : bucket) b.clear();
    for (const CarriedHistory& h : old_walls) {
      const std::int32_t a = slot_of[h.id_a];
      if (a >= 0) bucket[a].push_back({static_cast<std::int32_t>(h.other), h.row});
    }
    for (size_t k = 0; k < s.wall_pairs.size(); ++k) {
      for (const Entry& e : bucket[s.wall_pairs.i[k]])
        if (e.other == s.wall_pairs.j[k]) {
          std::memcpy(&s.wall_pairs.history[k * width], &old_wall_history[e.row * width], width * sizeof(double));
          break;
        }
    }
  }

  work.pair_forces.resize(n_pairs);
  work.wall_forces.resize(s.wall_pairs.size());
  work.x_built = s.x;
  work.y_built = s.y;
  work.z_built = s.z;
  work.valid = true;
  ++work.rebuilds;
}

}  // namespace dem
