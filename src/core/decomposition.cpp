// The geometry and rules of the domain decomposition (decomposition.h): grid, cuts, owners,
// ghosts, rebalancing. Nothing here sends a message.
#include "core/decomposition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace dem {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

const std::vector<double>& column(const State& s, int a) { return a == 0 ? s.x : a == 1 ? s.y : s.z; }
std::vector<double>& column(State& s, int a) { return a == 0 ? s.x : a == 1 ? s.y : s.z; }
const std::vector<double>& body_column(const State& s, int a) { return a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z; }
std::vector<double>& body_column(State& s, int a) { return a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z; }

/// The face area [m^2] the busiest box of grid `n` shares with its neighbours, and how many axes
/// the grid cuts.
double shared_area(const std::array<int, 3>& n, const double extent[3], const bool periodic[3], double narrowest, int& cut) {
  double box[3], area = 0;
  cut = 0;
  for (int a = 0; a < 3; ++a) box[a] = std::max(extent[a], narrowest) / n[a];
  for (int a = 0; a < 3; ++a) {
    if (n[a] == 1) continue;
    const int faces = periodic[a] || n[a] > 2 ? 2 : 1;  // of an interior box
    area += faces * box[(a + 1) % 3] * box[(a + 2) % 3], ++cut;
  }
  return area;
}

}  // namespace

GhostReach ghost_reach(const Model& model, const State& initial) {
  GhostReach out;
  // A clump belongs to the rank of its centre; its spheres reach `sticking_out` beyond it, so the
  // ghost layer and the boxes are that much deeper.
  for (size_t p = 0; p < initial.size(); ++p)
    if (initial.body[p] >= 0)
      out.sticking_out = std::max(out.sticking_out, std::sqrt(initial.offset_x[p] * initial.offset_x[p] + initial.offset_y[p] * initial.offset_y[p] +
                                                              initial.offset_z[p] * initial.offset_z[p]));
  for (const Inlet& inlet : model.inlets)
    if (inlet.clump >= 0) out.sticking_out = std::max(out.sticking_out, model.clumps[inlet.clump].bounding_radius * inlet.spec.diameter.largest());
  double radius_max = model.radius_max;
  for (double r : initial.radius) radius_max = std::max(radius_max, r);
  out.reach = 2.0 * radius_max + model.interaction_range + model.skin + out.sticking_out;
  out.box_min = out.reach + out.sticking_out;
  return out;
}

GridSpan grid_span(const Model& model, const State& initial) {
  GridSpan out;
  for (int a = 0; a < 3; ++a) {
    const std::vector<double>& c = column(initial, a);
    if (!c.empty()) out.extent[a] = *std::max_element(c.begin(), c.end()) - *std::min_element(c.begin(), c.end());
    if (model.has_domain) out.extent[a] = std::max(out.extent[a], model.domain_max[a] - model.domain_min[a]);
    out.periodic[a] = model.period[a] > 0;
    if (out.periodic[a]) out.extent[a] = model.period[a];
    out.score[a] = out.extent[a];
  }
  // Particles travel along gravity (they settle, fall down chutes): cuts across it would see most
  // particles migrate and the balance shift all the time, so that axis counts half.
  const double g[3] = {std::abs(model.gravity[0]), std::abs(model.gravity[1]), std::abs(model.gravity[2])};
  const int down = static_cast<int>(std::max_element(g, g + 3) - g);
  if (g[down] > 0) out.score[down] *= 0.5;
  return out;
}

bool grid_fits(const std::array<int, 3>& n, const double extent[3], const bool periodic[3], double narrowest) {
  for (int a = 0; a < 3; ++a) {
    const int needed = periodic[a] ? n[a] : std::max(n[a] - 2, 0);
    if (n[a] > 1 && extent[a] < needed * narrowest) return false;
  }
  return true;
}

std::array<int, 3> choose_grid(int ranks, const double extent[3], const bool periodic[3], double narrowest) {
  std::array<int, 3> best{0, 0, 0};
  double least = kInfinity;
  int fewest = 4;
  for (int nx = 1; nx <= ranks; ++nx) {
    if (ranks % nx) continue;
    for (int ny = 1; ny <= ranks / nx; ++ny) {
      if ((ranks / nx) % ny) continue;
      const std::array<int, 3> n{nx, ny, ranks / nx / ny};
      if (!grid_fits(n, extent, periodic, narrowest)) continue;
      int cut = 0;
      const double area = shared_area(n, extent, periodic, narrowest, cut);
      if (area < least * (1 - 1e-9) || (area <= least * (1 + 1e-9) && cut < fewest)) least = area, fewest = cut, best = n;
    }
  }
  return best;
}

std::vector<BoxOffset> box_offsets() {
  std::vector<BoxOffset> out;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x || y || z) out.push_back({{x, y, z}});
  return out;
}

int offset_index(const int d[3]) {
  const int k = (d[0] + 1) + 3 * (d[1] + 1) + 9 * (d[2] + 1);
  return k < 13 ? k : k - 1;  // (0, 0, 0) is not among them
}

void BoxGrid::place_of(int rank, int at[3]) const {
  int rest = rank;
  for (int a = 0; a < 3; ++a) at[a] = rest % dims[a], rest /= dims[a];
}

double BoxGrid::wrapped(double c, int a) const { return periodic[a] ? c - period[a] * std::floor((c - low[a]) / period[a]) : c; }

int BoxGrid::slot_along(double c, int a) const {
  return static_cast<int>(std::upper_bound(cuts[a].begin(), cuts[a].end(), wrapped(c, a)) - cuts[a].begin());
}

int BoxGrid::owner(const double at[3]) const {
  const int slot[3] = {slot_along(at[0], 0), slot_along(at[1], 1), slot_along(at[2], 2)};
  return rank_of(slot);
}

double BoxGrid::box_low(const int at[3], int a) const { return at[a] > 0 ? cuts[a][at[a] - 1] : periodic[a] ? low[a] : -kInfinity; }

double BoxGrid::box_high(const int at[3], int a) const {
  return at[a] < dims[a] - 1 ? cuts[a][at[a]] : periodic[a] ? low[a] + period[a] : kInfinity;
}

Neighbourhood BoxGrid::neighbourhood(const int at[3]) const {
  Neighbourhood out;
  const int self = rank_of(at);
  for (const BoxOffset& o : box_offsets()) {
    NeighbourBox n{o, 0, {0, 0, 0}};
    int there[3];
    bool exists = true;
    for (int a = 0; a < 3 && exists; ++a) {
      there[a] = at[a] + o.d[a];
      if (o.d[a] != 0 && dims[a] == 1) exists = false;
      else if (there[a] < 0 || there[a] >= dims[a]) {
        if (!periodic[a]) exists = false;
        n.shift[a] = there[a] < 0 ? period[a] : -period[a];  // what is sent there is seen one period on
        there[a] = (there[a] + dims[a]) % dims[a];
      }
    }
    if (!exists) continue;
    n.rank = rank_of(there);
    (o.upper() ? out.upper : out.lower).push_back(n);
    if (n.rank != self) out.near.push_back(n.rank);
  }
  std::sort(out.near.begin(), out.near.end());
  out.near.erase(std::unique(out.near.begin(), out.near.end()), out.near.end());
  return out;
}

void BoxGrid::keep_boxes_wide(int a) {
  std::vector<double>& c = cuts[a];
  const int n = static_cast<int>(c.size());
  if (n == 0) return;
  if (periodic[a]) c[0] = std::max(c[0], low[a] + box_min);
  for (int k = 1; k < n; ++k) c[k] = std::max(c[k], c[k - 1] + box_min);
  if (periodic[a]) c[n - 1] = std::min(c[n - 1], low[a] + period[a] - box_min);
  for (int k = n - 2; k >= 0; --k) c[k] = std::min(c[k], c[k + 1] - box_min);
}

BoxGrid box_grid(const std::array<int, 3>& dims, const Model& model, double box_min) {
  BoxGrid grid;
  grid.box_min = box_min;
  for (int a = 0; a < 3; ++a) {
    grid.dims[a] = dims[a];
    grid.periodic[a] = model.period[a] > 0 && dims[a] > 1;
    grid.period[a] = model.period[a];
    grid.low[a] = model.domain_min[a];
  }
  return grid;
}

void clear_cut_periods(const BoxGrid& grid, Model& local) {
  for (int a = 0; a < 3; ++a)
    if (grid.periodic[a]) local.period[a] = 0.0;
}

std::vector<double> quantile_cuts(const std::vector<double>& sorted, int boxes, double lo, double hi) {
  std::vector<double> cuts(static_cast<size_t>(std::max(boxes - 1, 0)), 0.0);
  for (int k = 1; k < boxes; ++k)
    cuts[k - 1] = sorted.size() >= static_cast<size_t>(boxes) ? sorted[sorted.size() * k / boxes] : lo + (hi - lo) * k / boxes;
  return cuts;
}

void first_cuts(BoxGrid& grid, const Model& model, const State& initial) {
  for (int a = 0; a < 3; ++a) {
    std::vector<double> coords;
    for (size_t p = 0; p < initial.size(); ++p) coords.push_back(grid.wrapped(owner_coordinate(initial, p, a), a));
    std::sort(coords.begin(), coords.end());
    // Evenly over the period, the domain box, or the particles' span when the boxes outnumber them.
    const bool wraps = grid.periodic[a];
    const double lo = wraps ? grid.low[a] : model.has_domain ? model.domain_min[a] : coords.empty() ? 0.0 : coords.front();
    const double hi = wraps ? grid.low[a] + grid.period[a] : model.has_domain ? model.domain_max[a] : coords.empty() ? 1.0 : coords.back();
    grid.cuts[a] = quantile_cuts(coords, grid.dims[a], lo, hi);
    grid.keep_boxes_wide(a);
  }
}

double owner_coordinate(const State& s, size_t p, int a) { return s.body[p] >= 0 ? body_column(s, a)[s.body[p]] : column(s, a)[p]; }

void wrap_periodic_axes(const BoxGrid& grid, State& s) {
  for (int a = 0; a < 3; ++a) {
    if (!grid.periodic[a]) continue;
    std::vector<double>& c = column(s, a);
    std::vector<double>& centre = body_column(s, a);
    std::vector<double> shift(centre.size());
    for (size_t b = 0; b < centre.size(); ++b) shift[b] = grid.wrapped(centre[b], a) - centre[b], centre[b] += shift[b];
    for (size_t p = 0; p < s.size(); ++p) c[p] = s.body[p] >= 0 ? c[p] + shift[s.body[p]] : grid.wrapped(c[p], a);
  }
}

Departures departures(const BoxGrid& grid, const State& s, int rank) {
  Departures out;
  out.body_to.assign(s.bodies.size(), -1);
  for (size_t b = 0; b < s.bodies.size(); ++b) {
    const double at[3] = {s.bodies.x[b], s.bodies.y[b], s.bodies.z[b]};
    const int home = grid.owner(at);
    if (home != rank) out.body_to[b] = home;
  }
  out.slot_to.assign(s.size(), -1);
  for (size_t p = 0; p < s.size(); ++p) {
    const std::int32_t b = s.body[p];
    const double at[3] = {s.x[p], s.y[p], s.z[p]};
    const int to = b >= 0 ? out.body_to[b] : grid.owner(at);
    if (to >= 0 && to != rank) out.slot_to[p] = to;
  }
  return out;
}

bool near_shared_boundary(const BoxOffset& offset, const double at[3], const double lo[3], const double hi[3], double reach) {
  bool near = true;
  for (int a = 0; a < 3 && near; ++a) near = offset.d[a] == 0 || (offset.d[a] < 0 ? at[a] < lo[a] + reach : at[a] > hi[a] - reach);
  return near;
}

void ghost_slots(const State& s, const BoxOffset& offset, const double lo[3], const double hi[3], double reach, std::vector<std::int32_t>& slots) {
  slots.clear();
  const size_t owned = s.owned();
  for (size_t p = 0; p < owned; ++p) {
    const double at[3] = {s.x[p], s.y[p], s.z[p]};
    if (near_shared_boundary(offset, at, lo, hi, reach)) slots.push_back(static_cast<std::int32_t>(p));
  }
}

ParticleWork particle_work(const State& s, const HistoryRows& pairs, const HistoryRows& walls) {
  std::unordered_map<std::int64_t, double> contacts;  // particle id -> contacts
  for (size_t q = 0; q < pairs.size(); ++q) contacts[pairs.a[q]] += 1, contacts[pairs.b[q]] += 1;
  for (size_t q = 0; q < walls.size(); ++q) contacts[walls.a[q]] += 1;  // b is the wall
  ParticleWork out;
  out.work.assign(s.size(), 1.0);
  for (size_t p = 0; p < s.size(); ++p) {
    const auto it = contacts.find(s.id[p]);
    if (it != contacts.end()) out.work[p] += it->second;
    out.total += out.work[p];
  }
  return out;
}

void share_time(ParticleWork& work, double computed) {
  const double per_work = work.total > 0 ? computed / work.total : 0.0;
  for (double& w : work.work) w *= per_work;
  work.total = computed;
}

void owner_bounds(const BoxGrid& grid, const State& s, double bounds[6]) {
  for (int a = 0; a < 3; ++a) {
    double lo = kInfinity, hi = -kInfinity;
    for (size_t p = 0; p < s.size(); ++p) {
      const double c = grid.wrapped(owner_coordinate(s, p, a), a);
      lo = std::min(lo, c), hi = std::max(hi, c);
    }
    bounds[2 * a] = -lo, bounds[2 * a + 1] = hi;
  }
}

AxisSpan histogram_span(const BoxGrid& grid, int a, const double bounds[6]) {
  if (grid.dims[a] == 1) return {};
  if (grid.periodic[a]) return {grid.low[a], grid.low[a] + grid.period[a]};
  return {-bounds[2 * a], bounds[2 * a + 1]};
}

std::vector<double> work_histogram(const BoxGrid& grid, const State& s, const std::vector<double>& work, int a, AxisSpan span) {
  std::vector<double> histogram(kWorkHistogramBins, 0.0);
  const double width = (span.hi - span.lo) / kWorkHistogramBins;
  for (size_t p = 0; p < s.size(); ++p)
    histogram[std::clamp(static_cast<int>((grid.wrapped(owner_coordinate(s, p, a), a) - span.lo) / width), 0, kWorkHistogramBins - 1)] += work[p];
  return histogram;
}

void cuts_from_histogram(BoxGrid& grid, int a, const std::vector<double>& histogram, double total, AxisSpan span) {
  const double width = (span.hi - span.lo) / kWorkHistogramBins;
  double below = 0;
  int bin = 0;
  grid.cuts[a].resize(static_cast<size_t>(std::max(grid.dims[a] - 1, 0)));
  for (int k = 1; k < grid.dims[a]; ++k) {
    const double target = total * k / grid.dims[a];
    while (bin < kWorkHistogramBins && below + histogram[bin] < target) below += histogram[bin++];
    const double within = bin < kWorkHistogramBins && histogram[bin] > 0 ? (target - below) / histogram[bin] : 0.0;
    grid.cuts[a][k - 1] = span.lo + (bin + within) * width;
  }
  grid.keep_boxes_wide(a);
}

bool RebalanceClock::due(double most, double total, int ranks, std::int64_t steps, bool measured_time) {
  if (measured_time ? !(total > 0) : total < ranks) return false;
  waited_steps += std::max(0.0, most / (total / ranks) - 1.0) * static_cast<double>(steps - checked_at_step);
  checked_at_step = steps;
  if (most <= kRebalanceImbalance * total / ranks || waited_steps < kRebalanceAfterSteps) return false;
  waited_steps = 0;
  return true;
}

}  // namespace dem
