#include "core/neighbors.h"

#include "core/cell_grid.h"
#include "core/domain.h"
#include "core/mesh_contacts.h"

#include "base/parallel.h"
#include "core/verlet.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>

namespace dem {

namespace {

/// Without a branch per value: whether a row is zero is a coin toss to the branch predictor (in
/// a dense bed a large share of the listed pairs touch; bench/results/design_measurements.csv).
bool row_is_zero(const double* row, int width) {
  bool any = false;
  for (int k = 0; k < width; ++k) any |= row[k] != 0.0;
  return !any;
}

/// Finds the spheres that left the domain (along non-periodic axes) or entered an outlet, with
/// the whole body they belong to, and counts them: keep[p] = 0 for each. Returns whether any
/// left; the caller drops them (State::compact, or the cell sort's permutation).
bool find_lost(const Model& model, State& state, std::vector<std::uint8_t>& keep) {
  const size_t n = state.size();
  keep.assign(n, 1);
  if (!model.has_domain && model.outlets.empty()) return false;
  std::vector<std::int32_t> body_outlet(state.bodies.size(), -2);  // -2 kept, -1 lost, k outlet
  auto inside = [](double x, double y, double z, const auto& lo, const auto& hi) {
    return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
  };
  bool any = false;
  for (size_t p = 0; p < n; ++p) {
    int verdict = -2;
    for (size_t k = 0; k < model.outlets.size() && verdict == -2; ++k)
      if (!model.outlets[k].domain && inside(state.x[p], state.y[p], state.z[p], model.outlets[k].region_min, model.outlets[k].region_max))
        verdict = static_cast<int>(k);
    if (verdict == -2 && model.has_domain) {
      for (int a = 0; a < 3; ++a) {
        if (model.period[a] > 0) continue;
        const double c = a == 0 ? state.x[p] : a == 1 ? state.y[p] : state.z[p];
        if (c < model.domain_min[a] || c > model.domain_max[a]) verdict = model.domain_outlet;  // -1 without one: lost
      }
    }
    if (verdict == -2) continue;
    any = true;
    // Removals happen at a list rebuild, after the step's drift: the positions are of time + dt.
    if (verdict >= 0 && state.first_removed.size() < model.outlets.size()) state.first_removed.resize(model.outlets.size());
    State::Removal& first = verdict >= 0 ? state.first_removed[verdict] : state.first_lost;
    if (first.time < 0) first = {state.time + model.dt, {state.id[p], state.x[p], state.y[p], state.z[p], state.vx[p], state.vy[p], state.vz[p]}};
    if (state.body[p] >= 0) {
      std::int32_t& b = body_outlet[state.body[p]];
      if (b == -2 || verdict >= 0) b = verdict;
    } else {
      keep[p] = 0;
      if (verdict >= 0) {
        state.outlets[verdict].removed_mass += 1.0 / state.inv_mass[p];
        ++state.outlets[verdict].removed;
      } else {
        ++state.lost;
        state.lost_mass += 1.0 / state.inv_mass[p];
      }
    }
    if (verdict == -1) {
      state.last_lost = {state.id[p], state.x[p], state.y[p], state.z[p], state.vx[p], state.vy[p], state.vz[p]};
    }
  }
  if (!any) return false;
  for (size_t b = 0; b < body_outlet.size(); ++b) {
    if (body_outlet[b] == -2) continue;
    if (body_outlet[b] >= 0) {
      state.outlets[body_outlet[b]].removed_mass += state.bodies.mass[b];
      ++state.outlets[body_outlet[b]].removed;
    } else {
      ++state.lost;
      state.lost_mass += state.bodies.mass[b];
    }
  }
  for (size_t p = 0; p < n; ++p)
    if (state.body[p] >= 0 && body_outlet[state.body[p]] != -2) keep[p] = 0;
  return true;
}

/// The velocity the lists follow until the next rebuild: the middle of the range of the free
/// spheres' velocities along each axis, so that the drift carries the build positions as near to
/// every sphere as one velocity can (the fastest and the slowest equally far off).
std::array<double, 3> common_velocity(const State& s) {
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool any = false;
  for (size_t p = 0; p < s.owned(); ++p) {
    if (s.body[p] >= 0) continue;
    const double v[3] = {s.vx[p], s.vy[p], s.vz[p]};
    for (int a = 0; a < 3; ++a) lo[a] = any ? std::min(lo[a], v[a]) : v[a], hi[a] = any ? std::max(hi[a], v[a]) : v[a];
    any = true;
  }
  return {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
}

/// Moves free spheres and body centres that crossed a periodic boundary back into the period
/// (member spheres follow their body and may stick out; distances use the minimum image).
void wrap_into_period(const Model& model, State& s) {
  if (!model.periodic()) return;
  for (int a = 0; a < 3; ++a) {
    const double period = model.period[a];
    if (period <= 0) continue;
    const double lo = model.domain_min[a];
    auto wrap = [&](double& v) { v -= period * std::floor((v - lo) / period); };
    std::vector<double>& column = a == 0 ? s.x : a == 1 ? s.y : s.z;
    for (size_t p = 0; p < s.size(); ++p) {
      if (s.body[p] >= 0) continue;
      wrap(column[p]);
    }
    std::vector<double>& centre = a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z;
    std::vector<double> shift(s.bodies.size());
    for (size_t b = 0; b < s.bodies.size(); ++b) {
      const double before = centre[b];
      wrap(centre[b]);
      shift[b] = centre[b] - before;
    }
    for (size_t p = 0; p < s.size(); ++p) {
      if (s.body[p] < 0 || shift[s.body[p]] == 0.0) continue;
      column[p] += shift[s.body[p]];
    }
  }
}

/// Finds the partners of a slot for the pair list: the spheres j > i whose gap is below the
/// reach, in the cells around i's, visited in the grid's own order (major, middle, minor axis),
/// so that the partners of a sorted slot come out ascending.
///
/// Fast path (no ghosts, no periodic axis): the slots of a cell are a run, and the three cells
/// next to each other along the minor axis one longer run; the distance loop over such a run
/// writes every candidate and keeps it by advancing the count (no branch the predictor would
/// lose on). Otherwise, cell by cell with the minimum image. Pairs inside one clump or glued to
/// one wall are dropped after the distance test (few pass it).
struct PairFinder {
  const Model& model;
  const State& s;
  const Grid& grid;
  const std::int32_t* cell_of;
  const std::int32_t* cell_start;
  const std::int32_t* members;  ///< slots by cell with ghosts; null: a cell's slots are a run
  double reach;                 ///< [m] gap that still lists a pair

  bool grouped() const { return s.bodies.size() > 0 || model.has_attached; }

  /// Appends the partners of i to `out` from index m on (growing it as needed); returns the new m.
  size_t partners(std::int32_t i, std::vector<std::int32_t>& out, size_t m) const {
    int at[3];
    grid.decode(cell_of[i], at);
    const size_t start = m;
    if (!members && !model.periodic()) m = runs(i, at, out, m);
    else m = cells(i, at, out, m);
    if (!grouped()) return m;
    size_t kept = start;
    for (size_t q = start; q < m; ++q) {
      const std::int32_t j = out[q];
      const bool same_body = s.body[i] >= 0 && s.body[i] == s.body[j];
      const bool same_wall = s.attached[i] >= 0 && s.attached[i] == s.attached[j];
      if (!same_body && !same_wall) out[kept++] = j;
    }
    return kept;
  }

 private:
  size_t runs(std::int32_t i, const int at[3], std::vector<std::int32_t>& out, size_t m) const {
    const int o0 = grid.order[0], o1 = grid.order[1], o2 = grid.order[2];
    const int lo0 = std::max(at[o0] - 1, 0), hi0 = std::min(at[o0] + 1, grid.dims[o0] - 1);
    const double *x = s.x.data(), *y = s.y.data(), *z = s.z.data(), *radius = s.radius.data();
    const double xi = x[i], yi = y[i], zi = z[i], ri = radius[i] + reach;
    // Only the rows of cells from i's own on: those before it hold slots below i only.
    for (int v2 = at[o2]; v2 <= std::min(at[o2] + 1, grid.dims[o2] - 1); ++v2)
      for (int v1 = v2 == at[o2] ? at[o1] : std::max(at[o1] - 1, 0); v1 <= std::min(at[o1] + 1, grid.dims[o1] - 1); ++v1) {
        const int base = (v2 * grid.dims[o1] + v1) * grid.dims[o0];
        const std::int32_t first = std::max(cell_start[base + lo0], i + 1), last = cell_start[base + hi0 + 1];
        if (first >= last) continue;
        if (out.size() < m + static_cast<size_t>(last - first)) out.resize(2 * (m + static_cast<size_t>(last - first)));
        std::int32_t* o = out.data();
        for (std::int32_t j = first; j < last; ++j) {
          const double dx = xi - x[j], dy = yi - y[j], dz = zi - z[j], cut = ri + radius[j];
          o[m] = j;
          m += dx * dx + dy * dy + dz * dz < cut * cut;
        }
      }
    return m;
  }

  size_t cells(std::int32_t i, const int at[3], std::vector<std::int32_t>& out, size_t m) const {
    // The up to 3 distinct cells along each axis (fewer where a periodic axis has < 3 cells).
    int axis_cells[3][3] = {}, axis_count[3] = {};
    for (int a = 0; a < 3; ++a)
      for (int d = -1; d <= 1; ++d) {
        int v = at[a] + d;
        if (grid.wrap[a]) v = (v + grid.dims[a]) % grid.dims[a];
        else if (v < 0 || v >= grid.dims[a]) continue;
        bool seen = false;
        for (int q = 0; q < axis_count[a]; ++q) seen |= axis_cells[a][q] == v;
        if (!seen) axis_cells[a][axis_count[a]++] = v;
      }
    const int o0 = grid.order[0], o1 = grid.order[1], o2 = grid.order[2];
    for (int q2 = 0; q2 < axis_count[o2]; ++q2)
      for (int q1 = 0; q1 < axis_count[o1]; ++q1)
        for (int q0 = 0; q0 < axis_count[o0]; ++q0) {
          int around[3];
          around[o2] = axis_cells[o2][q2], around[o1] = axis_cells[o1][q1], around[o0] = axis_cells[o0][q0];
          const int cell = grid.encode(around);
          const std::int32_t first = members ? cell_start[cell] : std::max(cell_start[cell], i + 1);
          for (std::int32_t q = first; q < cell_start[cell + 1]; ++q) {
            const std::int32_t j = members ? members[q] : q;
            if (j <= i) continue;
            double d[3] = {s.x[i] - s.x[j], s.y[i] - s.y[j], s.z[i] - s.z[j]};
            minimum_image(model, d);
            const double cut = s.radius[i] + s.radius[j] + reach;
            if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= cut * cut) continue;
            if (out.size() <= m) out.resize(2 * m + 16);
            out[m++] = j;
          }
        }
    return m;
  }
};

void build_csr(std::vector<std::int32_t>& begin, const std::vector<std::int32_t>& owner, size_t n) {
  begin.assign(n + 1, 0);
  for (const std::int32_t o : owner) ++begin[o + 1];
  for (size_t p = 0; p < n; ++p) begin[p + 1] += begin[p];
}

/// build_csr for a list in rows (owner ascending: the pair and wall lists), shared by the
/// threads: each entry that starts a row writes where the rows since the one before begin.
void build_csr_of_rows(std::vector<std::int32_t>& begin, const std::vector<std::int32_t>& owner, size_t n) {
  resize_discarding(begin, n + 1);
  const long entries = static_cast<long>(owner.size());
  const std::int32_t* o = owner.data();
  std::int32_t* b = begin.data();
#pragma omp parallel for schedule(static) if (entries >= kParallelMin)
  for (long k = 0; k <= entries; ++k) {
    const std::int32_t from = k == 0 ? 0 : o[k - 1] + 1, to = k == entries ? static_cast<std::int32_t>(n) : o[k];
    for (std::int32_t r = from; r <= to; ++r) b[r] = static_cast<std::int32_t>(k);
  }
}

}  // namespace

void ContactForces::resize(std::size_t n) {
  for (auto* c : {&fx, &fy, &fz}) c->assign(n, 0.0);
  active.assign(n, 0);
}

HistoryRows histories_by_id(const ContactList& list, const State& state, int width, bool walls) {
  HistoryRows out;
  histories_by_id(list, state, width, walls, out);
  return out;
}

void histories_by_id(const ContactList& list, const State& state, int width, bool walls, HistoryRows& out) {
  if (width == 0) {
    out.a.clear(), out.b.clear(), out.rows.clear();
    return;
  }
  // Counted first and sized exactly (grown by doubling, these rows, tens of MiB in a large bed,
  // would hold up to twice their size at the rebuild's peak); both passes in pieces shared by
  // the threads, each piece's rows written from its own start: the rows in list order.
  const long m = static_cast<long>(list.size());
  const bool parallel = m >= kParallelMin;
  const long pieces = parallel ? 4L * omp_get_max_threads() : 1;
  const auto first = [&](long piece) { return m * piece / pieces; };
  std::vector<size_t> start(static_cast<size_t>(pieces) + 1, 0);
#pragma omp parallel if (parallel)
  {
#pragma omp for schedule(static)
    for (long piece = 0; piece < pieces; ++piece) {
      size_t count = 0;
      for (long k = first(piece); k < first(piece + 1); ++k) count += !row_is_zero(&list.history[k * width], width);
      start[piece + 1] = count;
    }
#pragma omp single
    {
      for (long piece = 0; piece < pieces; ++piece) start[piece + 1] += start[piece];
      // Every row is written below, so the rows are not cleared first: resizing sets only those
      // beyond the last call's count to zero (not MiB by one thread while the others wait).
      resize_discarding(out.a, start[pieces]), resize_discarding(out.b, start[pieces]);
      resize_discarding(out.rows, start[pieces] * width);
    }
#pragma omp for schedule(static)
    for (long piece = 0; piece < pieces; ++piece) {
      size_t q = start[piece];
      for (long k = first(piece); k < first(piece + 1); ++k) {
        const double* row = &list.history[k * width];
        if (row_is_zero(row, width)) continue;
        out.a[q] = state.id[list.i[k]], out.b[q] = walls ? list.j[k] : state.id[list.j[k]];
        std::copy_n(row, width, &out.rows[q * width]);
        ++q;
      }
    }
  }
}

void drop_ghosts(State& s) {
  if (s.ghosts == 0) return;
  std::vector<std::uint8_t> keep(s.size(), 0);
  std::fill_n(keep.begin(), s.owned(), 1);
  s.compact(keep);
  s.ghosts = 0;
}

void index_contacts(const Model& model, const State& s, Workspace& work) {
  const size_t n = s.size();
  build_csr_of_rows(work.pair_begin, s.pairs.i, n);
  build_csr_of_rows(work.wall_begin, s.wall_pairs.i, n);
  work.mesh_rows.clear();
  if (!model.meshes.empty()) {
    if (s.candidate_begin.size() != s.owned() + 1 || s.mesh_contacts.count.size() < s.owned())
      throw std::logic_error("index_contacts: the mesh candidates or contacts do not match the particles");
    for (size_t p = 0; p < s.owned(); ++p)
      if (s.candidate_begin[p] != s.candidate_begin[p + 1] || s.mesh_contacts.count[p] > 0)
        work.mesh_rows.push_back(static_cast<std::int32_t>(p));
  }
  // Block size of the force evaluation: every pair's partner lies in its own block or the next
  // (pairs with ghosts are evaluated apart, forces.cpp).
  std::int32_t span = 0;
  const std::int32_t owned = static_cast<std::int32_t>(s.owned());
  const long n_pairs = static_cast<long>(s.pairs.size());
  const std::int32_t *pair_i = s.pairs.i.data(), *pair_j = s.pairs.j.data();
#pragma omp parallel for schedule(static) reduction(max : span) if (n_pairs >= kParallelMin)
  for (long k = 0; k < n_pairs; ++k)
    if (pair_j[k] < owned) span = std::max(span, pair_j[k] - pair_i[k]);
  work.ghost_owners.clear();
  if (s.ghosts > 0)
    for (long k = 0; k < n_pairs; ++k)
      if (pair_j[k] >= owned && (work.ghost_owners.empty() || work.ghost_owners.back() != pair_i[k])) work.ghost_owners.push_back(pair_i[k]);
  work.block = std::max<std::int32_t>(span + 1, 64);
  // Spheres of each body, in slot order.
  std::vector<std::int32_t> owner;
  for (size_t p = 0; p < n; ++p)
    if (s.body[p] >= 0) owner.push_back(s.body[p]);
  build_csr(work.body_begin, owner, s.bodies.size());
  work.body_members.resize(owner.size());
  {
    std::vector<std::int32_t> cursor(work.body_begin.begin(), work.body_begin.end() - 1);
    for (size_t p = 0; p < n; ++p)
      if (s.body[p] >= 0) work.body_members[cursor[s.body[p]]++] = static_cast<std::int32_t>(p);
  }
  PairForces& pf = work.pair_forces;
  for (auto* c : {&pf.fx, &pf.fy, &pf.fz}) c->assign(work.keep_pair_forces ? s.pairs.size() : 0, 0.0);
  assign_discarding(pf.active, s.pairs.size(), std::uint8_t{0});
  work.wall_forces.resize(s.wall_pairs.size());
  Workspace::NearPairs& near = work.near;
  for (auto* c : {&near.k, &near.i, &near.j}) resize_discarding(*c, s.pairs.size());
  for (auto* c : {&near.x, &near.y, &near.z}) resize_discarding(*c, s.owned());
  resize_discarding(near.end, (s.owned() + work.block - 1) / work.block);
  near.margin = near.margin > 0 ? std::clamp(near.margin, 0.05 * model.skin, 0.5 * model.skin) : 0.1 * model.skin;
  near.valid = near.trusted = false;  // the next contact pass scans the whole list
  // A contact with a history counts as active until it is next evaluated: the contact loop
  // clears the history of an inactive contact only when it was active (idle pairs of the skin
  // are then read, never written, and their history rows not touched at all).
  const int width = model.history_width;
  for (auto [list, active] : {std::pair{&s.pairs, &pf.active}, std::pair{&s.wall_pairs, &work.wall_forces.active}}) {
    const long rows = width > 0 ? static_cast<long>(list->size()) : 0;
    const double* history = list->history.data();
    std::uint8_t* flag = active->data();
#pragma omp parallel for schedule(static) if (rows >= kParallelMin)
    for (long k = 0; k < rows; ++k) flag[k] = !row_is_zero(&history[k * width], width);
  }
  work.valid = true;
}

bool lists_follow_drift(const Model& model, const Workspace& work) {
  if (work.domain || model.has_attached) return false;
  for (const PlaneWall& wall : model.planes)
    if (wall.servo || wall.velocity[0] != 0.0 || wall.velocity[1] != 0.0 || wall.velocity[2] != 0.0) return false;
  for (const MeshWall& mesh : model.meshes)
    if (!mesh.motion.is_static()) return false;
  return true;
}

bool needs_rebuild(const Model& model, const State& s, const Workspace& work, double time, bool free_spheres_checked) {
  if (!work.valid || s.x_built.size() != s.size()) return true;
  const DriftLimits limits = drift_limits(model, s, work, /*near_valid=*/false, time);
  const long n = static_cast<long>(s.owned());
  const bool all = !free_spheres_checked;
  const bool others = s.bodies.size() > 0 || model.has_attached;
  int moved = 0;
  if (all || others) {
#pragma omp parallel for reduction(| : moved) schedule(static) if (n >= kParallelMin)
    for (long p = 0; p < n; ++p) {
      if (!all && s.body[p] < 0 && s.attached[p] < 0) continue;
      moved |= outside_skin(limits, p, s.x[p], s.y[p], s.z[p]);
    }
  }
  if (moved) return true;
  // Walls move too: each side may use half the skin. A plane only by its motion along its normal,
  // an infinite cylinder across its axis (the rest slides the surface within itself).
  if (work.plane_built.size() == model.planes.size())
    for (size_t w = 0; w < model.planes.size(); ++w) {
      const PlaneWall& wall = model.planes[w];
      double d[3] = {s.walls.px[w] - work.plane_built[w][0], s.walls.py[w] - work.plane_built[w][1], s.walls.pz[w] - work.plane_built[w][2]};
      const double along = d[0] * wall.normal[0] + d[1] * wall.normal[1] + d[2] * wall.normal[2];
      if (wall.shape == PlaneWall::Shape::plane) d[0] = along, d[1] = d[2] = 0;
      if (wall.shape == PlaneWall::Shape::cylinder)
        for (int a = 0; a < 3; ++a) d[a] -= along * wall.normal[a];
      if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 0.25 * model.skin * model.skin) return true;
    }
  return !model.meshes.empty() && mesh_displacement_since_build(model, s, work.mesh_time) > 0.5 * model.skin;
}

namespace {

/// Drops the spheres that left (find_lost) by State::compact where the cell sort cannot; returns the slots kept.
inline size_t drop_lost(const Model& model, State& s, std::vector<std::uint8_t>& keep) {
  if (find_lost(model, s, keep) && (s.bodies.size() > 0 || std::find(keep.begin(), keep.end(), 1) == keep.end())) {
    s.compact(keep);
    keep.assign(s.size(), 1);
  }
  return static_cast<size_t>(std::count(keep.begin(), keep.end(), 1));
}

/// Sorts the kept owned slots by cell, dropping the others, with each one's cell in work.cell_of; returns the grid.
inline std::optional<Grid> sort_slots_by_cell(const Model& model, State& s, Workspace& work, double cell_size, size_t kept) {
  const std::vector<std::uint8_t>& keep = work.keep;
  std::optional<Grid> sorted_by;
  if (s.size() > 0) {
    sorted_by = make_grid(model, s, cell_size, keep.data());
    const Grid& grid = *sorted_by;
    const size_t owned = s.size();
    const int n_cells = grid.dims[0] * grid.dims[1] * grid.dims[2];
    work.cell_of.resize(owned);
    const long nl = static_cast<long>(owned);
#pragma omp parallel for schedule(static) if (nl >= kParallelMin)
    for (long p = 0; p < nl; ++p) work.cell_of[p] = keep[p] ? grid.index(s.x[p], s.y[p], s.z[p]) : -1;
    work.order.resize(kept);  // the slots kept, by cell: the permutation drops the others
    sort_by_cell(work.cell_of, owned, n_cells, work.cell_start, work.order);
    s.permute(work.order, work.permute_scratch);
    // Each sorted slot's cell, for the pair search below (without ghosts), gathered into the
    // sort's scratch.
    const long nk = static_cast<long>(kept);
    std::vector<std::int32_t>& sorted_cells = work.permute_scratch.i32;
    resize_discarding(sorted_cells, kept);
#pragma omp parallel for schedule(static) if (nk >= kParallelMin)
    for (long k = 0; k < nk; ++k) sorted_cells[k] = work.cell_of[work.order[k]];
    work.cell_of.swap(sorted_cells);
  }
  return sorted_by;
}

/// Empty lists, indexed, when there is no sphere to list.
inline void clear_lists(const Model& model, State& s, Workspace& work) {
  s.pairs.clear(), s.wall_pairs.clear();
  s.candidate_begin.assign(1, 0), s.mesh_candidates.clear();
  s.x_built.clear(), s.y_built.clear(), s.z_built.clear();
  index_contacts(model, s, work);
}

/// The cells of every slot for the pair search (with ghosts, on a grid over all slots); returns the grid.
inline const Grid& cell_every_slot(const Model& model, const State& s, Workspace& work, double radius_max, double reach,
                                   std::optional<Grid>& sorted_by) {
  // Cells of every slot. The owned slots are sorted, so a cell's owned spheres are a run of
  // slots (cell_start); ghosts, unsorted after them, need a second grid over all slots with the
  // slots listed by cell (`members`).
  const size_t n = s.size(), n_owned = s.owned();
  const bool with_ghosts = s.ghosts > 0;
  if (with_ghosts) {
    for (size_t p = n_owned; p < n; ++p) radius_max = std::max(radius_max, s.radius[p]);
    sorted_by = make_grid(model, s, std::max(2.0 * radius_max + reach, 1e-12));
  }
  const Grid& grid = *sorted_by;
  const int n_cells = grid.dims[0] * grid.dims[1] * grid.dims[2];
  work.cell_of.resize(n);
  if (with_ghosts) {
    for (size_t p = 0; p < n; ++p) work.cell_of[p] = grid.index(s.x[p], s.y[p], s.z[p]);
    work.members.resize(n);
    sort_by_cell(work.cell_of, n, n_cells, work.cell_start, work.members);
  }
  return grid;
}

/// The particle pairs (s.pairs, rows work.pair_begin): each owned slot's partners j > i within the reach.
inline void list_pairs(const Model& model, State& s, Workspace& work, const Grid& grid, double reach) {
  const size_t n = s.size(), n_owned = s.owned();
  const bool with_ghosts = s.ghosts > 0;
  // Particle pairs, in one pass (fill_rows). Ghosts list no pairs (ghost-ghost pairs are
  // another rank's).
  const PairFinder finder{model, s, grid, work.cell_of.data(), work.cell_start.data(),
                          with_ghosts ? work.members.data() : nullptr, reach};
  const long nl = static_cast<long>(n_owned);
  fill_rows(nl, nl >= kParallelMin, work.partner_scratch, work.pair_begin, s.pairs.j,
            [&](long i, std::vector<std::int32_t>& out, size_t m) { return finder.partners(static_cast<std::int32_t>(i), out, m); });
  work.pair_begin.resize(n + 1, work.pair_begin[nl]);
  resize_discarding(s.pairs.i, s.pairs.j.size());
#pragma omp parallel for schedule(static) if (nl >= kParallelMin)
  for (long i = 0; i < nl; ++i)
    std::fill(s.pairs.i.data() + work.pair_begin[i], s.pairs.i.data() + work.pair_begin[i + 1], static_cast<std::int32_t>(i));
}

/// The plane-wall pairs (s.wall_pairs, rows work.wall_begin): each owned slot's planes within the reach.
inline void list_wall_pairs(const Model& model, State& s, Workspace& work, double reach) {
  const size_t n = s.size();
  const long nl = static_cast<long>(s.owned());
  // Wall pairs, grouped by particle (ghosts touch no wall: their owners' contacts), in one
  // pass shared by the threads as the pairs' (a plane's distance for every sphere and plane).
  s.wall_pairs.i.clear();
  s.wall_pairs.j.clear();
  if (model.planes.empty()) {
    work.wall_begin.assign(n + 1, 0);
  } else {
    fill_rows(nl, nl >= kParallelMin, work.partner_scratch, work.wall_begin, s.wall_pairs.j,
              [&](long p, std::vector<std::int32_t>& out, size_t m) {
                if (s.attached[p] >= 0) return m;  // part of a wall: walls do not touch walls
                for (size_t w = 0; w < model.planes.size(); ++w) {
                  const double at[3] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]}, x[3] = {s.x[p], s.y[p], s.z[p]};
                  double normal[3];
                  const double d = model.planes[w].distance(at, x, normal);
                  if (d < s.radius[p] + reach && d > -s.radius[p]) {
                    if (out.size() <= m) out.resize(2 * m + 16);
                    out[m++] = static_cast<std::int32_t>(w);
                  }
                }
                return m;
              });
    resize_discarding(s.wall_pairs.i, s.wall_pairs.j.size());
#pragma omp parallel for schedule(static) if (nl >= kParallelMin)
    for (long i = 0; i < nl; ++i)
      std::fill(s.wall_pairs.i.data() + work.wall_begin[i], s.wall_pairs.i.data() + work.wall_begin[i + 1], static_cast<std::int32_t>(i));
    work.wall_begin.resize(n + 1, work.wall_begin[nl]);  // ghosts: no walls
  }
}

/// The new lists' histories: zero, then each old row (work.old_pairs, old_walls) carried to its pair by particle id.
inline void carry_histories(const Model& model, State& s, const Workspace& work) {
  const int width = model.history_width;
  const HistoryRows &old_pairs = work.old_pairs, &old_walls = work.old_walls;
  const size_t n = s.size(), n_pairs = s.pairs.size();
  // Carry histories to the new lists by particle id: each old row finds its pair in the new
  // list's row of the lower slot (a handful of partners), so the carry needs no index of its own.
  // Each old row has a new row of its own (or none), so the threads share the old rows.
  // The new lists' histories start at zero, set by the threads together (MiB of them: on one
  // thread a noticeable part of a rebuild; bench/results/design_measurements.csv).
  resize_discarding(s.pairs.history, n_pairs * width);
  s.wall_pairs.history.resize(s.wall_pairs.size() * width);
  for (std::vector<double>* history : {&s.pairs.history, &s.wall_pairs.history}) {
    const long size = static_cast<long>(history->size());
    double* h = history->data();
#pragma omp parallel for schedule(static) if (size >= kParallelMin)
    for (long begin = 0; begin < size; begin += kChunk) std::fill(h + begin, h + std::min(size, begin + kChunk), 0.0);
  }
  if (width > 0 && (old_pairs.size() > 0 || old_walls.size() > 0)) {
    std::vector<std::int32_t> slot_of(static_cast<size_t>(s.next_id), -1);
    for (size_t p = 0; p < n; ++p) slot_of[s.id[p]] = static_cast<std::int32_t>(p);
    auto slot = [&](std::int64_t id) { return id >= 0 && id < s.next_id ? slot_of[id] : -1; };
    // A pair whose bodies swapped roles (the old i is now j) takes its odd history negated.
    auto carry = [&](const HistoryRows& old, bool walls, ContactList& list, const std::vector<std::int32_t>& begin) {
      const long rows = static_cast<long>(old.size());
#pragma omp parallel for schedule(static) if (rows >= kParallelMin)
      for (long q = 0; q < rows; ++q) {
        const std::int32_t a = slot(old.a[q]);
        const std::int32_t b = walls ? static_cast<std::int32_t>(old.b[q]) : slot(old.b[q]);
        if (a < 0 || b < 0) continue;  // a particle left
        const bool swapped = !walls && b < a;
        const std::int32_t lower = swapped ? b : a, other = swapped ? a : b;
        for (std::int32_t k = begin[lower]; k < begin[lower + 1]; ++k) {
          if (list.j[k] != other) continue;
          double* row = &list.history[static_cast<size_t>(k) * width];
          std::memcpy(row, &old.rows[q * width], width * sizeof(double));
          if (swapped)
            for (int h = 0; h < width; ++h)
              if (model.history_odd[h]) row[h] = -row[h];
          break;
        }
      }
    };
    carry(old_pairs, false, s.pairs, work.pair_begin);
    carry(old_walls, true, s.wall_pairs, work.wall_begin);
  }
}

/// Where the spheres and plane walls are as the lists are built, and the drift the lists follow from there.
inline void record_build_positions(const Model& model, State& s, Workspace& work) {
  const size_t n = s.size();
  s.lists_drift_velocity = lists_follow_drift(model, work) ? common_velocity(s) : std::array<double, 3>{0.0, 0.0, 0.0};
  for (auto* c : {&s.x_built, &s.y_built, &s.z_built}) resize_discarding(*c, n);
  const long all = static_cast<long>(n);
#pragma omp parallel for schedule(static) if (all >= kParallelMin)
  for (long p = 0; p < all; ++p) s.x_built[p] = s.x[p], s.y_built[p] = s.y[p], s.z_built[p] = s.z[p];
  work.plane_built.resize(model.planes.size());
  for (size_t w = 0; w < model.planes.size(); ++w) work.plane_built[w] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]};
}

}  // namespace

void rebuild_contacts(const Model& model, State& s, Workspace& work) {
  const int width = model.history_width;
  HistoryRows &old_pairs = work.old_pairs, &old_walls = work.old_walls;
  histories_by_id(s.pairs, s, width, false, old_pairs);
  histories_by_id(s.wall_pairs, s, width, true, old_walls);
  Domain* domain = work.domain;

  drop_ghosts(s);
  // Migration first: it carries particles across a periodic face the ranks share (the local
  // model no longer wraps that axis), which find_lost would take for particles that left.
  if (domain) domain->migrate(model, s, old_pairs, old_walls);
  // Spheres that left are dropped by the cell sort below, which gathers every column anyway;
  // with bodies (renumbered) or nothing left, by State::compact.
  const size_t kept = drop_lost(model, s, work.keep);
  double radius_max = model.radius_max;
  for (size_t p = 0; p < s.size(); ++p) radius_max = std::max(radius_max, s.radius[p]);
  const double reach = model.interaction_range + model.skin;  // [m] gap that still lists a pair
  const double cell_size = std::max(2.0 * radius_max + reach, 1e-12);

  // Sort the owned slots by cell (counting sort); cells are at least one pair reach wide.
  wrap_into_period(model, s);
  std::optional<Grid> sorted_by = sort_slots_by_cell(model, s, work, cell_size, kept);
  if (domain) domain->make_ghosts(model, s);
  if (s.size() == 0) {  // nothing yet (an inlet will bring particles) or everything left
    clear_lists(model, s, work);
    ++work.rebuilds;
    return;
  }
  const Grid& grid = cell_every_slot(model, s, work, radius_max, reach, sorted_by);

  list_pairs(model, s, work, grid, reach);
  list_wall_pairs(model, s, work, reach);
  carry_histories(model, s, work);

  find_mesh_candidates(model, s, work, reach);
  record_build_positions(model, s, work);
  index_contacts(model, s, work);
  ++work.rebuilds;
}

}  // namespace dem
