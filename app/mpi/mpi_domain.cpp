#include "mpi/mpi_domain.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "case/spec.h"

#ifdef DEMDESIGN_WITH_MPI
#include <mpi.h>
#endif

namespace dem::app::mpi {

#ifdef DEMDESIGN_WITH_MPI
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr int kHistogramBins = 4096;
constexpr double kImbalance = 1.10;  ///< rebalance when the fullest rank holds 10 % above the mean
/// ... and when the ranks have waited for the fullest, since the last rebalance, at least this many
/// steps' worth of the mean rank's work (the sum over the steps of most / mean - 1): what moving
/// the cuts costs (histograms, all-to-all migration, new ghosts), in steps. Without it a stream
/// that keeps moving (an inlet feeding one rank) had its cuts moved at nearly every rebuild.
constexpr double kRebalanceAfterSteps = 20;

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(fmt::format("MPI error in {} (code {})", what, code));
}

/// Adds the seconds of its scope to a counter.
struct Timed {
  double& into;
  double start = MPI_Wtime();
  ~Timed() { into += MPI_Wtime() - start; }
};

/// Offsets of a count list (exclusive prefix sum).
std::vector<int> offsets_of(const std::vector<int>& counts) {
  std::vector<int> out(counts.size() + 1, 0);
  for (size_t k = 0; k < counts.size(); ++k) out[k + 1] = out[k] + counts[k];
  return out;
}

/// The 26 neighbour offsets of a box in the rank grid, in a fixed order (the message tags).
struct Offset {
  int d[3];
  /// Lexicographically positive (z first): this rank receives that neighbour's particles as
  /// ghosts and lists the pairs across their common faces, edges and corners; the neighbour
  /// receives none of this rank's. Every pair across ranks is thus listed once.
  bool upper() const { return d[2] > 0 || (d[2] == 0 && (d[1] > 0 || (d[1] == 0 && d[0] > 0))); }
};
std::vector<Offset> all_offsets() {
  std::vector<Offset> out;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x || y || z) out.push_back({{x, y, z}});
  return out;
}
int index_of(const int d[3]) {  // into all_offsets()
  const int k = (d[0] + 1) + 3 * (d[1] + 1) + 9 * (d[2] + 1);
  return k < 13 ? k : k - 1;
}

/// Whether every box of the grid `n` is at least `narrowest` [m] wide along each cut axis
/// (`periodic`: every box; otherwise the outer boxes reach to infinity).
bool grid_fits(const std::array<int, 3>& n, const double extent[3], const bool periodic[3], double narrowest) {
  for (int a = 0; a < 3; ++a) {
    const int needed = periodic[a] ? n[a] : std::max(n[a] - 2, 0);
    if (n[a] > 1 && extent[a] < needed * narrowest) return false;
  }
  return true;
}

/// A rank grid for `ranks` over boxes of `extent` [m] (per axis, a score: the axis of gravity
/// counts half), each cut axis at least `narrowest` [m] a box (`periodic`: every box; otherwise
/// the outer boxes reach to infinity): the factorisation whose busiest box shares the least face
/// area with its neighbours, and of equal ones the one with fewer cut axes (fewer neighbours,
/// fewer messages); {0, 0, 0} when none fits.
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
      double box[3], area = 0;
      int cut = 0;
      for (int a = 0; a < 3; ++a) box[a] = std::max(extent[a], narrowest) / n[a];
      for (int a = 0; a < 3; ++a) {
        if (n[a] == 1) continue;
        const int faces = periodic[a] || n[a] > 2 ? 2 : 1;  // of an interior box
        area += faces * box[(a + 1) % 3] * box[(a + 2) % 3], ++cut;
      }
      if (area < least * (1 - 1e-9) || (area <= least * (1 + 1e-9) && cut < fewest)) least = area, fewest = cut, best = n;
    }
  }
  return best;
}

class MpiDomain final : public Domain {
 public:
  MpiDomain(const Model& model, const State& initial, const std::array<int, 3>& requested, bool neighbour_migration, Balance balance)
      : local_(model), neighbour_migration_(neighbour_migration), balance_(balance) {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (model.has_attached)
      throw CaseError(fmt::format("{}: the split into subdomains does not take spheres glued to walls (a shear cell)", model.source));
    // A clump belongs to the rank of its centre; its spheres reach `sticking_out_` beyond it,
    // so the ghost layer and the boxes are that much deeper.
    for (size_t p = 0; p < initial.size(); ++p)
      if (initial.body[p] >= 0)
        sticking_out_ = std::max(sticking_out_, std::sqrt(initial.offset_x[p] * initial.offset_x[p] + initial.offset_y[p] * initial.offset_y[p] +
                                                          initial.offset_z[p] * initial.offset_z[p]));
    for (const Inlet& inlet : model.inlets)
      if (inlet.clump >= 0)
        sticking_out_ = std::max(sticking_out_, model.clumps[inlet.clump].bounding_radius * inlet.spec.diameter.largest());
    double radius_max = model.radius_max;
    for (double r : initial.radius) radius_max = std::max(radius_max, r);
    reach_ = 2.0 * radius_max + model.interaction_range + model.skin + sticking_out_;
    box_min_ = reach_ + sticking_out_;
    // How far the particles (and the domain box) spread along each axis.
    double extent[3] = {0, 0, 0}, score[3];
    bool periodic[3];
    for (int a = 0; a < 3; ++a) {
      const std::vector<double>& c = column(initial, a);
      if (!c.empty()) extent[a] = *std::max_element(c.begin(), c.end()) - *std::min_element(c.begin(), c.end());
      if (model.has_domain) extent[a] = std::max(extent[a], model.domain_max[a] - model.domain_min[a]);
      periodic[a] = model.period[a] > 0;
      if (periodic[a]) extent[a] = model.period[a];
      score[a] = extent[a];
    }
    // Particles travel along gravity (they settle, fall down chutes): cuts across it would see
    // most particles migrate and the balance shift all the time, so that axis counts half.
    const double g[3] = {std::abs(model.gravity[0]), std::abs(model.gravity[1]), std::abs(model.gravity[2])};
    const int down = static_cast<int>(std::max_element(g, g + 3) - g);
    if (g[down] > 0) score[down] *= 0.5;
    std::array<int, 3> grid = choose_grid(size_, score, periodic, box_min_);
    if (requested[0] > 0) {
      if (requested[0] * requested[1] * requested[2] != size_)
        throw CaseError(fmt::format("{}: a rank grid of {} x {} x {} has {} boxes, not the {} ranks running", model.source, requested[0], requested[1],
                                    requested[2], requested[0] * requested[1] * requested[2], size_));
      if (!grid_fits(requested, extent, periodic, box_min_))
        throw CaseError(fmt::format("{}: a rank grid of {} x {} x {} makes boxes narrower than one pair reach ({:.4g} m) in a domain of {:.4g} x "
                                    "{:.4g} x {:.4g} m",
                                    model.source, requested[0], requested[1], requested[2], box_min_, extent[0], extent[1], extent[2]));
      grid = requested;
    }
    if (grid[0] == 0)
      throw CaseError(fmt::format("{}: {} ranks cannot share a domain of {:.4g} x {:.4g} x {:.4g} m (each box at least one pair reach, {:.4g} m, "
                                  "wide along every axis it is cut across), so fewer ranks would split it",
                                  model.source, size_, extent[0], extent[1], extent[2], box_min_));
    int rest = rank_;
    for (int a = 0; a < 3; ++a) {
      dims_[a] = grid[a];
      coord_[a] = rest % dims_[a], rest /= dims_[a];
      periodic_[a] = periodic[a] && dims_[a] > 1;
      period_[a] = model.period[a];
      low_[a] = model.domain_min[a];
      if (periodic_[a]) local_.period[a] = 0.0;  // the ranks carry the period across their faces
    }
    // The neighbours: the offsets whose box exists (an axis not cut has none; a non-periodic
    // axis none beyond its outer boxes), with the shift a particle sent there takes.
    for (const Offset& o : all_offsets()) {
      Neighbour n{o, 0, {0, 0, 0}};
      int at[3];
      bool exists = true;
      for (int a = 0; a < 3 && exists; ++a) {
        at[a] = coord_[a] + o.d[a];
        if (o.d[a] != 0 && dims_[a] == 1) exists = false;
        else if (at[a] < 0 || at[a] >= dims_[a]) {
          if (!periodic_[a]) exists = false;
          n.shift[a] = at[a] < 0 ? period_[a] : -period_[a];  // what I send there is seen one period on
          at[a] = (at[a] + dims_[a]) % dims_[a];
        }
      }
      if (!exists) continue;
      n.rank = rank_of(at);
      (o.upper() ? from_ : to_).push_back(n);
      if (n.rank != rank_) near_.push_back(n.rank);
    }
    std::sort(near_.begin(), near_.end());
    near_.erase(std::unique(near_.begin(), near_.end()), near_.end());
    // First cuts from the initial particles (the same on every rank), or evenly over the box.
    for (int a = 0; a < 3; ++a) {
      std::vector<double> coords;
      for (size_t p = 0; p < initial.size(); ++p) coords.push_back(wrapped(owner_coordinate(initial, p, a), a));
      std::sort(coords.begin(), coords.end());
      cuts_[a].assign(dims_[a] - 1, 0.0);
      const double lo = periodic_[a] ? low_[a] : model.has_domain ? model.domain_min[a] : coords.empty() ? 0.0 : coords.front();
      const double hi = periodic_[a] ? low_[a] + period_[a] : model.has_domain ? model.domain_max[a] : coords.empty() ? 1.0 : coords.back();
      for (int k = 1; k < dims_[a]; ++k)
        cuts_[a][k - 1] = coords.size() >= static_cast<size_t>(dims_[a]) ? coords[coords.size() * k / dims_[a]] : lo + (hi - lo) * k / dims_[a];
      keep_boxes_wide(a);
    }
  }

  const Model& local_model() const override { return local_; }
  bool root() const override { return rank_ == 0; }
  int rank() const override { return rank_; }
  int ranks() const override { return size_; }

  bool any(bool mine) override {
    Timed timed{step_seconds_};
    int flag = mine ? 1 : 0, all = 0;
    check(MPI_Allreduce(&flag, &all, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD), "MPI_Allreduce");
    return all != 0;
  }

  double sum(double mine) override {
    double all = 0;
    check(MPI_Allreduce(&mine, &all, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
    return all;
  }

  void sum(std::vector<double>& values) override {
    Timed timed{step_seconds_};
    check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
  }

  double max(double mine) override {
    Timed timed{step_seconds_};
    double most = 0;
    check(MPI_Allreduce(&mine, &most, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
    return most;
  }

  bool owns(double x, double y, double z) const override {
    const double at[3] = {x, y, z};
    return owner(at) == rank_;
  }

  std::vector<std::array<double, 4>> particles_in(const State& s, const double lo[3], const double hi[3]) override {
    Timed timed{gather_seconds_};
    std::vector<double> mine;
    for (size_t p = 0; p < s.owned(); ++p) {
      const double at[3] = {s.x[p], s.y[p], s.z[p]};
      if (at[0] < lo[0] || at[0] > hi[0] || at[1] < lo[1] || at[1] > hi[1] || at[2] < lo[2] || at[2] > hi[2]) continue;
      mine.insert(mine.end(), {at[0], at[1], at[2], s.radius[p]});
    }
    const std::vector<double> all = all_gather(mine);
    std::vector<std::array<double, 4>> out(all.size() / 4);
    for (size_t k = 0; k < out.size(); ++k) out[k] = {all[4 * k], all[4 * k + 1], all[4 * k + 2], all[4 * k + 3]};
    return out;
  }

  void migrate(const Model& model, State& s, HistoryRows& pairs, HistoryRows& walls) override {
    Timed timed{rebuild_seconds_};
    pairs.append(pending_pairs_), walls.append(pending_walls_);
    pending_pairs_ = {}, pending_walls_ = {};
    wrap_periodic_axes(s);
    const bool cuts_moved = rebalance(s, pairs, walls);
    const int width = model.history_width;
    const size_t n = s.size(), record = s.record_size();
    // Where each body goes (-1: stays), then free spheres and bodies with their spheres.
    std::vector<int> body_to(s.bodies.size(), -1);
    for (size_t b = 0; b < s.bodies.size(); ++b) {
      const double at[3] = {s.bodies.x[b], s.bodies.y[b], s.bodies.z[b]};
      if (owner(at) != rank_) body_to[b] = owner(at);
    }
    std::unordered_map<std::int64_t, int> leaving;  // sphere id -> new owner
    std::vector<std::uint8_t> keep(n, 1);
    std::vector<std::vector<double>> spheres(size_), clumps(size_);
    std::vector<int> spheres_to(size_, 0), bodies_to(size_, 0), pair_rows_to(size_, 0), wall_rows_to(size_, 0);
    std::vector<std::vector<std::int32_t>> members(s.bodies.size());
    for (size_t p = 0; p < n; ++p) {
      const std::int32_t b = s.body[p];
      const double at[3] = {s.x[p], s.y[p], s.z[p]};
      const int to = b >= 0 ? body_to[b] : owner(at);
      if (to < 0 || to == rank_) continue;
      keep[p] = 0;
      leaving[s.id[p]] = to;
      if (b >= 0) {
        members[b].push_back(static_cast<std::int32_t>(p));
      } else {
        s.pack(p, spheres[to]);
        ++spheres_to[to];
      }
    }
    for (size_t b = 0; b < s.bodies.size(); ++b) {
      const int to = body_to[b];
      if (to < 0) continue;
      s.pack_body(b, clumps[to]);
      clumps[to].push_back(static_cast<double>(members[b].size()));
      for (const std::int32_t p : members[b]) s.pack(p, clumps[to]);
      ++bodies_to[to];
    }
    // Every history of a leaving sphere goes with it (the new owner lists the pairs it now
    // evaluates and ignores the rest).
    std::vector<std::vector<double>> pair_rows(size_), wall_rows(size_);
    auto add_rows = [&](const HistoryRows& rows, bool wall_rows_only_a, std::vector<std::vector<double>>& out, std::vector<int>& count) {
      for (size_t q = 0; q < rows.size() && width > 0; ++q) {
        auto it = leaving.find(rows.a[q]);
        if (it == leaving.end() && !wall_rows_only_a) it = leaving.find(rows.b[q]);
        if (it == leaving.end()) continue;
        rows.pack(q, width, out[it->second]);
        ++count[it->second];
      }
    };
    if (!leaving.empty()) {
      add_rows(pairs, false, pair_rows, pair_rows_to);
      add_rows(walls, true, wall_rows, wall_rows_to);
    }
    // Per destination: free spheres, clumps (body, count, spheres), pair histories, wall
    // histories, in one message with its counts. A particle that left its box since the last
    // rebuild is in a neighbour's, so the messages go to the neighbours alone; all to all
    // (counts, then the doubles) after the cuts moved, or when some rank has a particle bound
    // beyond its neighbours. Either way the parts arrive in rank order: the same state.
    constexpr int kCounts = 5;
    const auto message_to = [&](int r) {
      std::vector<double> m;
      for (const auto* part : {&spheres[r], &clumps[r], &pair_rows[r], &wall_rows[r]}) m.insert(m.end(), part->begin(), part->end());
      return m;
    };
    const auto counts_to = [&](int r, size_t doubles) {
      return std::array<int, kCounts>{spheres_to[r], bodies_to[r], pair_rows_to[r], wall_rows_to[r], static_cast<int>(doubles)};
    };
    int far = 0;
    for (const auto& [id, to] : leaving) far = far || !std::binary_search(near_.begin(), near_.end(), to);
    int anywhere = far;
    check(MPI_Allreduce(&far, &anywhere, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD), "MPI_Allreduce");
    std::vector<std::vector<double>> arrived;  // per source, in rank order
    std::vector<std::array<int, kCounts>> in_counts;
    size_t sent = 0;
    if (!neighbour_migration_ || cuts_moved || anywhere) {
      std::vector<int> counts_out(kCounts * size_), counts_in(kCounts * size_);
      std::vector<double> send;
      std::vector<int> send_sizes(size_), receive_sizes(size_);
      for (int r = 0; r < size_; ++r) {
        const std::vector<double> m = message_to(r);
        send.insert(send.end(), m.begin(), m.end());
        send_sizes[r] = static_cast<int>(m.size());
        const std::array<int, kCounts> c = counts_to(r, m.size());
        std::copy(c.begin(), c.end(), counts_out.begin() + kCounts * r);
      }
      check(MPI_Alltoall(counts_out.data(), kCounts, MPI_INT, counts_in.data(), kCounts, MPI_INT, MPI_COMM_WORLD), "MPI_Alltoall");
      for (int r = 0; r < size_; ++r) receive_sizes[r] = counts_in[kCounts * r + 4];
      const std::vector<int> send_at = offsets_of(send_sizes), receive_at = offsets_of(receive_sizes);
      std::vector<double> received(static_cast<size_t>(receive_at.back()));
      check(MPI_Alltoallv(send.data(), send_sizes.data(), send_at.data(), MPI_DOUBLE, received.data(), receive_sizes.data(),
                          receive_at.data(), MPI_DOUBLE, MPI_COMM_WORLD),
            "MPI_Alltoallv");
      for (int r = 0; r < size_; ++r) {
        arrived.emplace_back(received.begin() + receive_at[r], received.begin() + receive_at[r + 1]);
        in_counts.emplace_back();
        std::copy(counts_in.begin() + kCounts * r, counts_in.begin() + kCounts * (r + 1), in_counts.back().begin());
      }
      sent = send.size();
      ++migrations_all_;
    } else {
      const size_t m = near_.size();
      std::vector<std::vector<double>> out(m);
      std::vector<std::array<int, kCounts>> out_counts(m);
      arrived.resize(m), in_counts.resize(m);
      for (size_t k = 0; k < m; ++k) out[k] = message_to(near_[k]), out_counts[k] = counts_to(near_[k], out[k].size()), sent += out[k].size();
      requests_.clear();
      for (size_t k = 0; k < m; ++k) {
        requests_.emplace_back();
        check(MPI_Irecv(in_counts[k].data(), kCounts, MPI_INT, near_[k], 32 * kMigrationCounts, MPI_COMM_WORLD, &requests_.back()), "MPI_Irecv");
        requests_.emplace_back();
        check(MPI_Isend(out_counts[k].data(), kCounts, MPI_INT, near_[k], 32 * kMigrationCounts, MPI_COMM_WORLD, &requests_.back()), "MPI_Isend");
      }
      check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
      requests_.clear();
      for (size_t k = 0; k < m; ++k) {
        arrived[k].resize(static_cast<size_t>(in_counts[k][4]));
        requests_.emplace_back();
        check(MPI_Irecv(arrived[k].data(), in_counts[k][4], MPI_DOUBLE, near_[k], 32 * kMigrationData, MPI_COMM_WORLD, &requests_.back()), "MPI_Irecv");
        requests_.emplace_back();
        check(MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_DOUBLE, near_[k], 32 * kMigrationData, MPI_COMM_WORLD,
                        &requests_.back()),
              "MPI_Isend");
      }
      check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
      ++migrations_near_;
    }
    s.compact(keep);  // also drops the bodies that left with all their spheres
    for (size_t source = 0; source < arrived.size(); ++source) {
      const double* in = arrived[source].data();
      const int* count = in_counts[source].data();
      for (int k = 0; k < count[0]; ++k, in += record) s.unpack(in);
      for (int k = 0; k < count[1]; ++k) {
        const std::int32_t b = static_cast<std::int32_t>(s.unpack_body(in));
        in += State::kBodyRecord;
        const int spheres_in_body = static_cast<int>(*in++);
        for (int q = 0; q < spheres_in_body; ++q, in += record) {
          s.unpack(in);
          s.body.back() = b;
        }
      }
      in = pairs.unpack(in, static_cast<size_t>(count[2]), width);
      walls.unpack(in, static_cast<size_t>(count[3]), width);
    }
    migrated_ += static_cast<std::int64_t>(leaving.size());
    bytes_ += 8.0 * static_cast<double>(sent);
  }

  void make_ghosts(const Model&, State& s) override {
    Timed timed{rebuild_seconds_};
    // To each lower neighbour, the owned particles within one reach of the faces, edges or
    // corner this box shares with it, shifted by a period where the grid wraps.
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = box_low(a), hi[a] = box_high(a);
    const int record = static_cast<int>(s.record_size());
    const size_t owned = s.owned();
    std::vector<std::vector<double>> out(to_.size());
    for (size_t k = 0; k < to_.size(); ++k) {
      Neighbour& n = to_[k];
      n.slots.clear();
      for (size_t p = 0; p < owned; ++p) {
        const double at[3] = {s.x[p], s.y[p], s.z[p]};
        bool near = true;
        for (int a = 0; a < 3 && near; ++a)
          near = n.offset.d[a] == 0 || (n.offset.d[a] < 0 ? at[a] < lo[a] + reach_ : at[a] > hi[a] - reach_);
        if (near) n.slots.push_back(static_cast<std::int32_t>(p));
      }
      out[k].reserve(n.slots.size() * record);
      for (const std::int32_t p : n.slots) {
        const size_t at = out[k].size();
        s.pack(p, out[k]);
        for (int a = 0; a < 3; ++a) out[k][at + a] += n.shift[a];
      }
    }
    std::vector<int> sent(to_.size()), counts(from_.size());
    for (size_t k = 0; k < to_.size(); ++k) sent[k] = static_cast<int>(to_[k].slots.size());
    exchange_counts(sent, counts, 1);
    std::vector<std::vector<double>> in(from_.size());
    for (size_t k = 0; k < from_.size(); ++k) in[k].resize(static_cast<size_t>(counts[k]) * record);
    exchange(out, in, 2, false);
    size_t ghosts = 0;
    for (size_t k = 0; k < from_.size(); ++k) {
      from_[k].count = counts[k];
      for (int q = 0; q < counts[k]; ++q) {
        s.unpack(in[k].data() + static_cast<size_t>(q) * record);
        s.body.back() = -1, s.attached.back() = -1;  // a copy: its body, if any, lives on its owner
      }
      ghosts += static_cast<size_t>(counts[k]);
    }
    s.ghosts = ghosts;
    ++rebuilds_;
    ghosts_ += static_cast<std::int64_t>(ghosts);
    for (const auto& o : out) bytes_ += 8.0 * static_cast<double>(o.size());
  }

  void refresh_ghosts(State& s) override {
    Timed timed{step_seconds_};
    ++refreshes_;
    out_.resize(to_.size()), in_.resize(from_.size());
    for (size_t k = 0; k < to_.size(); ++k) {
      std::vector<double>& o = out_[k];
      o.clear();
      const double* shift = to_[k].shift;
      for (const std::int32_t p : to_[k].slots)
        o.insert(o.end(), {s.x[p] + shift[0], s.y[p] + shift[1], s.z[p] + shift[2], s.vx[p], s.vy[p], s.vz[p], s.wx[p], s.wy[p], s.wz[p]});
      bytes_ += 8.0 * static_cast<double>(o.size());
    }
    for (size_t k = 0; k < from_.size(); ++k) in_[k].resize(9 * static_cast<size_t>(from_[k].count));
    exchange(out_, in_, 3, false);
    size_t p = s.owned();
    for (const std::vector<double>& block : in_)
      for (const double* in = block.data(); in < block.data() + block.size(); in += 9, ++p) {
        s.x[p] = in[0], s.y[p] = in[1], s.z[p] = in[2], s.vx[p] = in[3], s.vy[p] = in[4], s.vz[p] = in[5];
        s.wx[p] = in[6], s.wy[p] = in[7], s.wz[p] = in[8];
      }
  }

  void return_ghost_loads(State& s) override {
    Timed timed{step_seconds_};
    // Back along the ghosts' way: each upper neighbour gets the loads on its particles.
    out_.resize(from_.size()), in_.resize(to_.size());
    size_t p = s.owned();
    for (size_t k = 0; k < from_.size(); ++k) {
      std::vector<double>& o = out_[k];
      o.clear();
      for (int q = 0; q < from_[k].count; ++q, ++p) o.insert(o.end(), {s.fx[p], s.fy[p], s.fz[p], s.tx[p], s.ty[p], s.tz[p]});
      bytes_ += 8.0 * static_cast<double>(o.size());
    }
    for (size_t k = 0; k < to_.size(); ++k) in_[k].resize(6 * to_[k].slots.size());
    exchange(out_, in_, 4, true);
    for (size_t k = 0; k < to_.size(); ++k) {
      const double* in = in_[k].data();
      for (const std::int32_t q : to_[k].slots) {
        s.fx[q] += in[0], s.fy[q] += in[1], s.fz[q] += in[2], s.tx[q] += in[3], s.ty[q] += in[4], s.tz[q] += in[5];
        in += 6;
      }
    }
  }

  void sum_wall_loads(State& s) override {
    Timed timed{step_seconds_};
    const size_t walls = s.walls.fx.size();
    buffer_.resize(3 * walls);
    for (size_t w = 0; w < walls; ++w) buffer_[3 * w] = s.walls.fx[w], buffer_[3 * w + 1] = s.walls.fy[w], buffer_[3 * w + 2] = s.walls.fz[w];
    check(MPI_Allreduce(MPI_IN_PLACE, buffer_.data(), static_cast<int>(buffer_.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
    for (size_t w = 0; w < walls; ++w) s.walls.fx[w] = buffer_[3 * w], s.walls.fy[w] = buffer_[3 * w + 1], s.walls.fz[w] = buffer_[3 * w + 2];
  }

  void distribute(State& s) override {
    const int width = local_.history_width;
    std::vector<std::uint8_t> keep(s.size(), 0);
    wrap_periodic_axes(s);
    for (size_t p = 0; p < s.size(); ++p) {
      const double at[3] = {owner_coordinate(s, p, 0), owner_coordinate(s, p, 1), owner_coordinate(s, p, 2)};
      keep[p] = owner(at) == rank_;
    }
    // Histories of a checkpoint: kept (by ids) for the first rebuild, where a pair with a
    // particle of another rank finds its partner among the ghosts.
    for (size_t k = 0; k < s.pairs.size() && width > 0; ++k)
      if (keep[s.pairs.i[k]] || keep[s.pairs.j[k]])
        pending_pairs_.add(s.id[s.pairs.i[k]], s.id[s.pairs.j[k]], &s.pairs.history[k * width], width);
    for (size_t k = 0; k < s.wall_pairs.size() && width > 0; ++k)
      if (keep[s.wall_pairs.i[k]]) pending_walls_.add(s.id[s.wall_pairs.i[k]], s.wall_pairs.j[k], &s.wall_pairs.history[k * width], width);
    s.compact(keep);
    s.ghosts = 0;
    s.pairs.clear(), s.wall_pairs.clear();
    s.x_built.clear(), s.y_built.clear(), s.z_built.clear();
    // Each rank integrates the loads of its own particles from here: the next row averages them
    // over the same time on every rank (MeshLoads::interval).
    s.mesh_loads.restart_interval();
    // Run totals live on the root alone; the others count from zero and add theirs when gathered.
    if (rank_ != 0) {
      s.lost = 0, s.lost_mass = 0;
      for (OutletState& o : s.outlets) o = {};
      for (TriangleRecords& r : s.records)
        for (std::vector<double>* c : r.columns()) std::fill(c->begin(), c->end(), 0.0);
    }
  }

  State gather(const State& s) override {
    Timed timed{gather_seconds_};
    const std::vector<std::vector<double>> parts = gather_to_root(pack_share(s, local_.history_width));
    return rank_ == 0 ? merge_shares(s, parts, local_.history_width) : shared_part(s);
  }

  std::string statistics() const override {
    const double steps = static_cast<double>(std::max<std::int64_t>(rebuilds_ + refreshes_, 1));
    return fmt::format("{} steps ({} with a rebuild), mean {:.0f} ghosts from {} neighbours, {} particles migrated ({} times to the neighbours, {} "
                       "all to all), {} rebalances; communication "
                       "{:.3g} s in steps ({:.3g} ms a step), {:.3g} s at rebuilds, {:.3g} s gathering results; {:.3g} kB sent a step",
                       rebuilds_ + refreshes_, rebuilds_, static_cast<double>(ghosts_) / std::max<std::int64_t>(rebuilds_, 1), from_.size(),
                       migrated_, migrations_near_, migrations_all_, rebalances_, step_seconds_, 1e3 * step_seconds_ / steps, rebuild_seconds_, gather_seconds_, 1e-3 * bytes_ / steps);
  }

  std::string describe() const {
    std::string cuts;
    for (int a = 0; a < 3; ++a) {
      if (cuts_[a].empty()) continue;
      std::string at;
      for (double c : cuts_[a]) at += fmt::format("{}{:.4g}", at.empty() ? "" : ", ", c);
      cuts += fmt::format("{}{} at {} m{}", cuts.empty() ? "" : "; ", "xyz"[a], at, periodic_[a] ? " across the period" : "");
    }
    return fmt::format("{} ranks as a {} x {} x {} grid of boxes (cuts: {}), ghost reach {:.3g} m, balanced by {}", size_, dims_[0], dims_[1], dims_[2],
                       cuts, reach_, balance_ == Balance::time ? "measured time" : "particles and contacts");
  }

 private:
  /// A box next to this one: its rank, where it lies, the shift [m] of what is sent to it, and
  /// what is sent (to a lower neighbour: owned slots, in message order) or received (from an
  /// upper one: the ghost count, the ghosts in the order of from_).
  /// Message kinds of a migration between neighbours (tags 32 x kind; 1-4 are the ghosts').
  static constexpr int kMigrationCounts = 5, kMigrationData = 6;

  struct Neighbour {
    Offset offset;
    int rank = MPI_PROC_NULL;
    double shift[3] = {0, 0, 0};
    std::vector<std::int32_t> slots;
    int count = 0;
  };

  static std::vector<double>& column(State& s, int a) { return a == 0 ? s.x : a == 1 ? s.y : s.z; }
  static const std::vector<double>& column(const State& s, int a) { return a == 0 ? s.x : a == 1 ? s.y : s.z; }
  static std::vector<double>& body_column(State& s, int a) { return a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z; }
  static const std::vector<double>& body_column(const State& s, int a) { return a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z; }

  int rank_of(const int at[3]) const { return at[0] + dims_[0] * (at[1] + dims_[1] * at[2]); }
  /// Where a sphere belongs along axis a: its own centre, or its clump's.
  double owner_coordinate(const State& s, size_t p, int a) const { return s.body[p] >= 0 ? body_column(s, a)[s.body[p]] : column(s, a)[p]; }
  /// Free spheres and clump centres back into the period along every periodic axis the grid cuts
  /// (a clump's spheres move with its centre).
  void wrap_periodic_axes(State& s) const {
    for (int a = 0; a < 3; ++a) {
      if (!periodic_[a]) continue;
      std::vector<double>& c = column(s, a);
      std::vector<double>& centre = body_column(s, a);
      std::vector<double> shift(centre.size());
      for (size_t b = 0; b < centre.size(); ++b) shift[b] = wrapped(centre[b], a) - centre[b], centre[b] += shift[b];
      for (size_t p = 0; p < s.size(); ++p) c[p] = s.body[p] >= 0 ? c[p] + shift[s.body[p]] : wrapped(c[p], a);
    }
  }
  double wrapped(double c, int a) const { return periodic_[a] ? c - period_[a] * std::floor((c - low_[a]) / period_[a]) : c; }
  int slot_along(double c, int a) const { return static_cast<int>(std::upper_bound(cuts_[a].begin(), cuts_[a].end(), wrapped(c, a)) - cuts_[a].begin()); }
  int owner(const double at[3]) const {
    const int slot[3] = {slot_along(at[0], 0), slot_along(at[1], 1), slot_along(at[2], 2)};
    return rank_of(slot);
  }
  double box_low(int a) const { return coord_[a] > 0 ? cuts_[a][coord_[a] - 1] : periodic_[a] ? low_[a] : -kInfinity; }
  double box_high(int a) const {
    return coord_[a] < dims_[a] - 1 ? cuts_[a][coord_[a]] : periodic_[a] ? low_[a] + period_[a] : kInfinity;
  }

  /// Interior boxes along axis a (all boxes of a periodic axis) at least one reach wide.
  void keep_boxes_wide(int a) {
    std::vector<double>& cuts = cuts_[a];
    const int n = static_cast<int>(cuts.size());
    if (n == 0) return;
    if (periodic_[a]) cuts[0] = std::max(cuts[0], low_[a] + box_min_);
    for (int k = 1; k < n; ++k) cuts[k] = std::max(cuts[k], cuts[k - 1] + box_min_);
    if (periodic_[a]) cuts[n - 1] = std::min(cuts[n - 1], low_[a] + period_[a] - box_min_);
    for (int k = n - 2; k >= 0; --k) cuts[k] = std::min(cuts[k], cuts[k + 1] - box_min_);
  }

  /// New cuts when the most loaded rank carries more than kImbalance times the mean work and the
  /// waiting for it since the last rebalance adds up to kRebalanceAfterSteps (collective). A particle's work is one plus its contacts (the pairs and wall contacts with a
  /// history: in a dense bed the contacts, not the particles, cost the time); each cut axis gets
  /// its cuts at the quantiles of the work along it. Balanced by time (Balance::time), a rank's
  /// work is the time it computed since the last rebuild (its wall time less the time in
  /// communication and packing), shared among its particles by their work: what a pair across a
  /// face, a mesh contact or a slower core costs is then measured, not modelled.
  /// Returns whether the cuts moved (the same on every rank).
  bool rebalance(const State& s, const HistoryRows& pairs, const HistoryRows& walls) {
    const size_t n = s.size();
    std::unordered_map<std::int64_t, double> contacts;
    for (size_t q = 0; q < pairs.size(); ++q) contacts[pairs.a[q]] += 1, contacts[pairs.b[q]] += 1;
    for (size_t q = 0; q < walls.size(); ++q) contacts[walls.a[q]] += 1;
    std::vector<double> work(n, 1.0);
    double mine = 0;
    for (size_t p = 0; p < n; ++p) {
      const auto it = contacts.find(s.id[p]);
      if (it != contacts.end()) work[p] += it->second;
      mine += work[p];
    }
    if (balance_ == Balance::time) {
      const double now = MPI_Wtime(), communicated = step_seconds_ + rebuild_seconds_ + gather_seconds_;
      const double computed = std::max(0.0, (now - balanced_at_) - (communicated - communicated_at_));
      balanced_at_ = now, communicated_at_ = communicated;
      const double per_work = mine > 0 ? computed / mine : 0.0;
      for (double& w : work) w *= per_work;
      mine = computed;
    }
    double stats[7] = {mine};  // work, then -low and high along each axis
    for (int a = 0; a < 3; ++a) {
      double lo = kInfinity, hi = -kInfinity;
      for (size_t p = 0; p < n; ++p) lo = std::min(lo, wrapped(owner_coordinate(s, p, a), a)), hi = std::max(hi, wrapped(owner_coordinate(s, p, a), a));
      stats[1 + 2 * a] = -lo, stats[2 + 2 * a] = hi;
    }
    double most[7];
    check(MPI_Allreduce(stats, most, 7, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
    const double total = sum(mine);
    if (balance_ == Balance::work ? total < size_ : !(total > 0)) return false;
    // The waiting since the last check, in steps of the mean rank's work: the same on every rank
    // (from reduced values and step counts), so every rank decides alike, and with Balance::work
    // reproducibly.
    const std::int64_t steps = rebuilds_ + refreshes_;
    waited_steps_ += std::max(0.0, most[0] / (total / size_) - 1.0) * static_cast<double>(steps - checked_at_step_);
    checked_at_step_ = steps;
    if (most[0] <= kImbalance * total / size_ || waited_steps_ < kRebalanceAfterSteps) return false;
    waited_steps_ = 0;
    for (int a = 0; a < 3; ++a) {
      if (dims_[a] == 1) continue;
      const double lo = periodic_[a] ? low_[a] : -most[1 + 2 * a], hi = periodic_[a] ? low_[a] + period_[a] : most[2 + 2 * a];
      if (!(hi > lo)) continue;
      std::vector<double> histogram(kHistogramBins, 0.0), all(kHistogramBins);
      const double width = (hi - lo) / kHistogramBins;
      for (size_t p = 0; p < n; ++p)
        histogram[std::clamp(static_cast<int>((wrapped(owner_coordinate(s, p, a), a) - lo) / width), 0, kHistogramBins - 1)] += work[p];
      check(MPI_Allreduce(histogram.data(), all.data(), kHistogramBins, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
      double below = 0;
      int bin = 0;
      for (int k = 1; k < dims_[a]; ++k) {
        const double target = total * k / dims_[a];
        while (bin < kHistogramBins && below + all[bin] < target) below += all[bin++];
        const double within = bin < kHistogramBins && all[bin] > 0 ? (target - below) / all[bin] : 0.0;
        cuts_[a][k - 1] = lo + (bin + within) * width;
      }
      keep_boxes_wide(a);
    }
    ++rebalances_;
    return true;
  }

  /// One message to each lower neighbour (`out`, by to_) and one from each upper one (`in`, sized
  /// by the caller, by from_); `back` reverses the roles (loads returned to the ghosts' owners).
  /// The tag names the offset as the receiver sees the sender, so two messages between the same
  /// two ranks (two boxes across a period) do not mix.
  void exchange(const std::vector<std::vector<double>>& out, std::vector<std::vector<double>>& in, int kind, bool back) {
    const std::vector<Neighbour>& senders_to = back ? from_ : to_;
    const std::vector<Neighbour>& receivers_from = back ? to_ : from_;
    requests_.clear();
    for (size_t k = 0; k < receivers_from.size(); ++k) {
      requests_.emplace_back();
      check(MPI_Irecv(in[k].data(), static_cast<int>(in[k].size()), MPI_DOUBLE, receivers_from[k].rank, tag(kind, receivers_from[k].offset.d, false),
                      MPI_COMM_WORLD, &requests_.back()),
            "MPI_Irecv");
    }
    for (size_t k = 0; k < senders_to.size(); ++k) {
      requests_.emplace_back();
      check(MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_DOUBLE, senders_to[k].rank, tag(kind, senders_to[k].offset.d, true),
                      MPI_COMM_WORLD, &requests_.back()),
            "MPI_Isend");
    }
    check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  }
  void exchange_counts(const std::vector<int>& sent, std::vector<int>& counts, int kind) {
    requests_.clear();
    for (size_t k = 0; k < from_.size(); ++k) {
      requests_.emplace_back();
      check(MPI_Irecv(&counts[k], 1, MPI_INT, from_[k].rank, tag(kind, from_[k].offset.d, false), MPI_COMM_WORLD, &requests_.back()), "MPI_Irecv");
    }
    for (size_t k = 0; k < to_.size(); ++k) {
      requests_.emplace_back();
      check(MPI_Isend(&sent[k], 1, MPI_INT, to_[k].rank, tag(kind, to_[k].offset.d, true), MPI_COMM_WORLD, &requests_.back()), "MPI_Isend");
    }
    check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  }
  /// A message's tag: its kind and the offset of the receiver's box from the sender's (`sending`:
  /// `d` is the offset of the receiver as the sender sees it; otherwise of the sender as the
  /// receiver sees it, so negated).
  static int tag(int kind, const int d[3], bool sending) {
    const int seen[3] = {sending ? d[0] : -d[0], sending ? d[1] : -d[1], sending ? d[2] : -d[2]};
    return 32 * kind + index_of(seen);
  }

  std::vector<double> all_gather(const std::vector<double>& mine) {
    int count = static_cast<int>(mine.size());
    std::vector<int> counts(size_);
    check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
    const std::vector<int> at = offsets_of(counts);
    std::vector<double> all(static_cast<size_t>(at.back()));
    check(MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), at.data(), MPI_DOUBLE, MPI_COMM_WORLD), "MPI_Allgatherv");
    return all;
  }

  std::vector<std::vector<double>> gather_to_root(const std::vector<double>& mine) {
    int count = static_cast<int>(mine.size());
    std::vector<int> counts(size_);
    check(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
    const std::vector<int> at = offsets_of(counts);
    std::vector<double> all(rank_ == 0 ? static_cast<size_t>(at.back()) : 0);
    check(MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), at.data(), MPI_DOUBLE, 0, MPI_COMM_WORLD), "MPI_Gatherv");
    std::vector<std::vector<double>> parts;
    if (rank_ != 0) return parts;
    for (int r = 0; r < size_; ++r) parts.emplace_back(all.begin() + at[r], all.begin() + at[r + 1]);
    return parts;
  }

  Model local_;
  int rank_ = 0, size_ = 1;
  int dims_[3] = {1, 1, 1}, coord_[3] = {0, 0, 0};  // the rank grid and this rank's place in it
  bool periodic_[3] = {false, false, false};        // periodic and cut by the grid
  double period_[3] = {0, 0, 0}, low_[3] = {0, 0, 0};  // [m]
  double reach_ = 0;             // [m] ghost layer depth: a pair's largest listing distance (+ sticking_out_)
  double sticking_out_ = 0;      // [m] how far a clump's sphere centre lies from the clump's centre
  double box_min_ = 0;           // [m] narrowest box along a cut axis: reach_ + sticking_out_
  std::vector<double> cuts_[3];  // [m] between box k and k + 1 along each axis
  std::vector<Neighbour> to_, from_;  // lower neighbours (get my ghosts, return their loads), upper ones
  HistoryRows pending_pairs_, pending_walls_;
  std::vector<double> buffer_;
  std::vector<std::vector<double>> out_, in_;
  std::vector<MPI_Request> requests_;
  std::int64_t migrated_ = 0, rebalances_ = 0, rebuilds_ = 0, refreshes_ = 0, ghosts_ = 0;
  std::int64_t checked_at_step_ = 0;  ///< the step of the last rebalance check
  double waited_steps_ = 0;           ///< steps' worth of waiting for the fullest rank since the last rebalance
  std::int64_t migrations_near_ = 0, migrations_all_ = 0;  // rebuilds whose migration went to the neighbours, all to all
  bool neighbour_migration_ = true;
  Balance balance_ = Balance::work;
  double balanced_at_ = MPI_Wtime(), communicated_at_ = 0;  // [s] wall clock and time in communication at the last rebalance check
  std::vector<int> near_;  // the neighbours' ranks (each once, not this one), ascending
  double step_seconds_ = 0, rebuild_seconds_ = 0, gather_seconds_ = 0;  // [s] in MPI and packing
  double bytes_ = 0;  // [B] sent by this rank
};

}  // namespace

std::unique_ptr<Domain> make_domain(const Model& model, const State& initial, std::string* note, const std::array<int, 3>& grid, bool neighbour_migration,
                                    Balance balance) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size < 2) return nullptr;
  try {
    auto domain = std::make_unique<MpiDomain>(model, initial, grid, neighbour_migration, balance);
    if (note) *note = domain->describe();
    return domain;
  } catch (const CaseError& e) {
    if (note) *note = e.what();
    return nullptr;
  }
}

#else

std::unique_ptr<Domain> make_domain(const Model&, const State&, std::string*, const std::array<int, 3>&, bool, Balance) { return nullptr; }

#endif

}  // namespace dem::app::mpi
