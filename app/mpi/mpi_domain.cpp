// The MPI transport of the domain decomposition (mpi_domain.h): the sends, receives, all-to-alls
// and reductions that carry particles, ghosts, loads and sums between the ranks, around the
// grid, cuts, owners and ghost sets of the engine (core/decomposition.h).
#include "mpi/mpi_domain.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

#include "case/spec.h"
#include "core/decomposition.h"

#ifdef DEMDESIGN_WITH_MPI
#include <mpi.h>
#endif

namespace dem::app::mpi {

#ifdef DEMDESIGN_WITH_MPI
namespace {

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

class MpiDomain final : public Domain {
 public:
  MpiDomain(const Model& model, const State& initial, const std::array<int, 3>& requested, bool neighbour_migration, Balance balance)
      : local_(model), neighbour_migration_(neighbour_migration), balance_(balance) {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (model.has_attached)
      throw CaseError(fmt::format("{}: the split into subdomains does not take spheres glued to walls (a shear cell)", model.source));
    const GhostReach depth = ghost_reach(model, initial);
    reach_ = depth.reach;
    grid_ = box_grid(grid_for(model, initial, requested, depth.box_min), model, depth.box_min);
    grid_.place_of(rank_, coord_);
    clear_cut_periods(grid_, local_);
    const Neighbourhood around = grid_.neighbourhood(coord_);
    for (const NeighbourBox& n : around.lower) to_.emplace_back(n);
    for (const NeighbourBox& n : around.upper) from_.emplace_back(n);
    near_ = around.near;
    // First cuts from the initial particles (the same on every rank), or evenly over the box.
    first_cuts(grid_, model, initial);
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
    return grid_.owner(at) == rank_;
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
    wrap_periodic_axes(grid_, s);
    const bool cuts_moved = rebalance(s, pairs, walls);
    const int width = model.history_width;
    const size_t record = s.record_size();
    const Parcels parcels = pack_parcels(s, departures(grid_, s, rank_), pairs, walls, width);
    // A particle that left its box since the last rebuild is in a neighbour's, so the parcels go
    // to the neighbours alone; all to all (counts, then the doubles) after the cuts moved, or when
    // some rank has a particle bound beyond its neighbours. Either way the parts arrive in rank
    // order: the same state.
    int far = 0;
    for (const auto& [id, to] : parcels.leaving) far = far || !std::binary_search(near_.begin(), near_.end(), to);
    int anywhere = far;
    check(MPI_Allreduce(&far, &anywhere, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD), "MPI_Allreduce");
    const Arrivals arrived = !neighbour_migration_ || cuts_moved || anywhere ? send_all_to_all(parcels) : send_to_neighbours(parcels);
    s.compact(parcels.keep);  // also drops the bodies that left with all their spheres
    unpack_arrivals(arrived, record, width, s, pairs, walls);
    migrated_ += static_cast<std::int64_t>(parcels.leaving.size());
    bytes_ += 8.0 * static_cast<double>(arrived.sent);
  }

  void make_ghosts(const Model&, State& s) override {
    Timed timed{rebuild_seconds_};
    // To each lower neighbour, the owned particles within one reach of the faces, edges or
    // corner this box shares with it, shifted by a period where the grid wraps.
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = grid_.box_low(coord_, a), hi[a] = grid_.box_high(coord_, a);
    const int record = static_cast<int>(s.record_size());
    std::vector<std::vector<double>> out(to_.size());
    for (size_t k = 0; k < to_.size(); ++k) {
      Neighbour& n = to_[k];
      ghost_slots(s, n.offset, lo, hi, reach_, n.slots);
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
    wrap_periodic_axes(grid_, s);
    for (size_t p = 0; p < s.size(); ++p) {
      const double at[3] = {owner_coordinate(s, p, 0), owner_coordinate(s, p, 1), owner_coordinate(s, p, 2)};
      keep[p] = grid_.owner(at) == rank_;
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
      if (grid_.cuts[a].empty()) continue;
      std::string at;
      for (double c : grid_.cuts[a]) at += fmt::format("{}{:.4g}", at.empty() ? "" : ", ", c);
      cuts += fmt::format("{}{} at {} m{}", cuts.empty() ? "" : "; ", "xyz"[a], at, grid_.periodic[a] ? " across the period" : "");
    }
    return fmt::format("{} ranks as a {} x {} x {} grid of boxes (cuts: {}), ghost reach {:.3g} m, balanced by {}", size_, grid_.dims[0], grid_.dims[1],
                       grid_.dims[2], cuts, reach_, balance_ == Balance::time ? "measured time" : "particles and contacts");
  }

 private:
  /// Message kinds of a migration between neighbours (tags 32 x kind; 1-4 are the ghosts').
  static constexpr int kMigrationCounts = 5, kMigrationData = 6;

  /// A box next to this one (where it lies, its rank, the shift [m] of what is sent to it), and
  /// what is sent (to a lower neighbour: owned slots, in message order) or received (from an
  /// upper one: the ghost count, the ghosts in the order of from_).
  struct Neighbour : NeighbourBox {
    explicit Neighbour(const NeighbourBox& box) : NeighbourBox(box) {}
    std::vector<std::int32_t> slots;
    int count = 0;
  };

  /// What a rank sends each rank at a migration (per destination rank): free spheres, clumps
  /// (body, sphere count, spheres), pair histories, wall histories, in one message with its
  /// counts (kParcelCounts: the four, then the message's doubles).
  static constexpr int kParcelCounts = 5;
  struct Parcels {
    Parcels(int destinations, size_t n)
        : spheres(destinations), clumps(destinations), pair_rows(destinations), wall_rows(destinations), spheres_to(destinations, 0),
          bodies_to(destinations, 0), pair_rows_to(destinations, 0), wall_rows_to(destinations, 0), keep(n, 1) {}
    std::vector<std::vector<double>> spheres, clumps, pair_rows, wall_rows;
    std::vector<int> spheres_to, bodies_to, pair_rows_to, wall_rows_to;
    std::unordered_map<std::int64_t, int> leaving;  // sphere id -> new owner
    std::vector<std::uint8_t> keep;                 // (n) 0: the slot leaves
    std::vector<double> message_to(int r) const {
      std::vector<double> m;
      for (const auto* part : {&spheres[r], &clumps[r], &pair_rows[r], &wall_rows[r]}) m.insert(m.end(), part->begin(), part->end());
      return m;
    }
    std::array<int, kParcelCounts> counts_to(int r, size_t doubles) const {
      return {spheres_to[r], bodies_to[r], pair_rows_to[r], wall_rows_to[r], static_cast<int>(doubles)};
    }
  };
  /// What arrived at a migration, per source (in rank order, or in the order of near_), with its
  /// counts; and the doubles this rank sent.
  struct Arrivals {
    std::vector<std::vector<double>> data;
    std::vector<std::array<int, kParcelCounts>> counts;
    size_t sent = 0;
  };

  /// The particles leaving (`away`) packed per destination: free spheres, then each clump with
  /// its spheres, then every history of a leaving sphere (the new owner lists the pairs it now
  /// evaluates and ignores the rest).
  Parcels pack_parcels(const State& s, const Departures& away, const HistoryRows& pairs, const HistoryRows& walls, int width) const {
    Parcels out(size_, s.size());
    std::vector<std::vector<std::int32_t>> members(s.bodies.size());
    for (size_t p = 0; p < s.size(); ++p) {
      const int to = away.slot_to[p];
      if (to < 0) continue;
      const std::int32_t b = s.body[p];
      out.keep[p] = 0;
      out.leaving[s.id[p]] = to;
      if (b >= 0) {
        members[b].push_back(static_cast<std::int32_t>(p));
      } else {
        s.pack(p, out.spheres[to]);
        ++out.spheres_to[to];
      }
    }
    for (size_t b = 0; b < s.bodies.size(); ++b) {
      const int to = away.body_to[b];
      if (to < 0) continue;
      s.pack_body(b, out.clumps[to]);
      out.clumps[to].push_back(static_cast<double>(members[b].size()));
      for (const std::int32_t p : members[b]) s.pack(p, out.clumps[to]);
      ++out.bodies_to[to];
    }
    if (!out.leaving.empty()) {
      pack_rows(pairs, false, width, out.leaving, out.pair_rows, out.pair_rows_to);
      pack_rows(walls, true, width, out.leaving, out.wall_rows, out.wall_rows_to);
    }
    return out;
  }
  /// The history rows of leaving spheres, to their new owners (`wall_rows`: b is a wall, not a sphere).
  static void pack_rows(const HistoryRows& rows, bool wall_rows, int width, const std::unordered_map<std::int64_t, int>& leaving,
                        std::vector<std::vector<double>>& out, std::vector<int>& count) {
    for (size_t q = 0; q < rows.size() && width > 0; ++q) {
      auto it = leaving.find(rows.a[q]);
      if (it == leaving.end() && !wall_rows) it = leaving.find(rows.b[q]);
      if (it == leaving.end()) continue;
      rows.pack(q, width, out[it->second]);
      ++count[it->second];
    }
  }

  /// Every rank's parcel to every rank: the counts all to all, then the doubles (collective).
  Arrivals send_all_to_all(const Parcels& parcels) {
    Arrivals in;
    std::vector<int> counts_out(kParcelCounts * size_), counts_in(kParcelCounts * size_);
    std::vector<double> send;
    std::vector<int> send_sizes(size_), receive_sizes(size_);
    for (int r = 0; r < size_; ++r) {
      const std::vector<double> m = parcels.message_to(r);
      send.insert(send.end(), m.begin(), m.end());
      send_sizes[r] = static_cast<int>(m.size());
      const std::array<int, kParcelCounts> c = parcels.counts_to(r, m.size());
      std::copy(c.begin(), c.end(), counts_out.begin() + kParcelCounts * r);
    }
    check(MPI_Alltoall(counts_out.data(), kParcelCounts, MPI_INT, counts_in.data(), kParcelCounts, MPI_INT, MPI_COMM_WORLD), "MPI_Alltoall");
    for (int r = 0; r < size_; ++r) receive_sizes[r] = counts_in[kParcelCounts * r + 4];
    const std::vector<int> send_at = offsets_of(send_sizes), receive_at = offsets_of(receive_sizes);
    std::vector<double> received(static_cast<size_t>(receive_at.back()));
    check(MPI_Alltoallv(send.data(), send_sizes.data(), send_at.data(), MPI_DOUBLE, received.data(), receive_sizes.data(), receive_at.data(),
                        MPI_DOUBLE, MPI_COMM_WORLD),
          "MPI_Alltoallv");
    for (int r = 0; r < size_; ++r) {
      in.data.emplace_back(received.begin() + receive_at[r], received.begin() + receive_at[r + 1]);
      in.counts.emplace_back();
      std::copy(counts_in.begin() + kParcelCounts * r, counts_in.begin() + kParcelCounts * (r + 1), in.counts.back().begin());
    }
    in.sent = send.size();
    ++migrations_all_;
    return in;
  }

  /// Each neighbour's parcel to it and its parcel from it: the counts, then the doubles.
  Arrivals send_to_neighbours(const Parcels& parcels) {
    Arrivals in;
    const size_t m = near_.size();
    std::vector<std::vector<double>> out(m);
    std::vector<std::array<int, kParcelCounts>> out_counts(m);
    in.data.resize(m), in.counts.resize(m);
    for (size_t k = 0; k < m; ++k) out[k] = parcels.message_to(near_[k]), out_counts[k] = parcels.counts_to(near_[k], out[k].size()), in.sent += out[k].size();
    requests_.clear();
    for (size_t k = 0; k < m; ++k) {
      requests_.emplace_back();
      check(MPI_Irecv(in.counts[k].data(), kParcelCounts, MPI_INT, near_[k], 32 * kMigrationCounts, MPI_COMM_WORLD, &requests_.back()), "MPI_Irecv");
      requests_.emplace_back();
      check(MPI_Isend(out_counts[k].data(), kParcelCounts, MPI_INT, near_[k], 32 * kMigrationCounts, MPI_COMM_WORLD, &requests_.back()), "MPI_Isend");
    }
    check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
    requests_.clear();
    for (size_t k = 0; k < m; ++k) {
      in.data[k].resize(static_cast<size_t>(in.counts[k][4]));
      requests_.emplace_back();
      check(MPI_Irecv(in.data[k].data(), in.counts[k][4], MPI_DOUBLE, near_[k], 32 * kMigrationData, MPI_COMM_WORLD, &requests_.back()), "MPI_Irecv");
      requests_.emplace_back();
      check(MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_DOUBLE, near_[k], 32 * kMigrationData, MPI_COMM_WORLD, &requests_.back()),
            "MPI_Isend");
    }
    check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
    ++migrations_near_;
    return in;
  }

  /// The arrived particles appended to `s` (a clump's spheres after their body) and their
  /// histories to `pairs` and `walls`, source after source.
  static void unpack_arrivals(const Arrivals& arrived, size_t record, int width, State& s, HistoryRows& pairs, HistoryRows& walls) {
    for (size_t source = 0; source < arrived.data.size(); ++source) {
      const double* in = arrived.data[source].data();
      const int* count = arrived.counts[source].data();
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
  }

  /// The rank grid: the one asked for, checked, or the one chosen (decomposition.h).
  std::array<int, 3> grid_for(const Model& model, const State& initial, const std::array<int, 3>& requested, double box_min) const {
    const GridSpan span = grid_span(model, initial);
    const double* extent = span.extent;
    std::array<int, 3> grid = choose_grid(size_, span.score, span.periodic, box_min);
    if (requested[0] > 0) {
      if (requested[0] * requested[1] * requested[2] != size_)
        throw CaseError(fmt::format("{}: a rank grid of {} x {} x {} has {} boxes, not the {} ranks running", model.source, requested[0], requested[1],
                                    requested[2], requested[0] * requested[1] * requested[2], size_));
      if (!grid_fits(requested, extent, span.periodic, box_min))
        throw CaseError(fmt::format("{}: a rank grid of {} x {} x {} makes boxes narrower than one pair reach ({:.4g} m) in a domain of {:.4g} x "
                                    "{:.4g} x {:.4g} m",
                                    model.source, requested[0], requested[1], requested[2], box_min, extent[0], extent[1], extent[2]));
      grid = requested;
    }
    if (grid[0] == 0)
      throw CaseError(fmt::format("{}: {} ranks cannot share a domain of {:.4g} x {:.4g} x {:.4g} m (each box at least one pair reach, {:.4g} m, "
                                  "wide along every axis it is cut across), so fewer ranks would split it",
                                  model.source, size_, extent[0], extent[1], extent[2], box_min));
    return grid;
  }

  /// The rebalancing of decomposition.h over the ranks (collective): each rank's work, the most
  /// loaded rank's and the sum, and when the cuts move, per cut axis the histogram of the work
  /// summed over the ranks. Balanced by time (Balance::time), a rank's work is the time it
  /// computed since the last check (its wall time less its time in communication and packing).
  /// Returns whether the cuts moved (the same on every rank).
  bool rebalance(const State& s, const HistoryRows& pairs, const HistoryRows& walls) {
    ParticleWork work = particle_work(s, pairs, walls);
    if (balance_ == Balance::time) {
      const double now = MPI_Wtime(), communicated = step_seconds_ + rebuild_seconds_ + gather_seconds_;
      const double computed = std::max(0.0, (now - balanced_at_) - (communicated - communicated_at_));
      balanced_at_ = now, communicated_at_ = communicated;
      share_time(work, computed);
    }
    double stats[7] = {work.total};  // work, then -low and high along each axis
    owner_bounds(grid_, s, stats + 1);
    double most[7];
    check(MPI_Allreduce(stats, most, 7, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
    const double total = sum(work.total);
    if (!clock_.due(most[0], total, size_, rebuilds_ + refreshes_, balance_ == Balance::time)) return false;
    for (int a = 0; a < 3; ++a) {
      const AxisSpan span = histogram_span(grid_, a, most + 1);
      if (span.empty()) continue;
      const std::vector<double> histogram = work_histogram(grid_, s, work.work, a, span);
      std::vector<double> all(kWorkHistogramBins);
      check(MPI_Allreduce(histogram.data(), all.data(), kWorkHistogramBins, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
      cuts_from_histogram(grid_, a, all, total, span);
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
    return 32 * kind + offset_index(seen);
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
  BoxGrid grid_;                  // the rank grid and its cuts
  int coord_[3] = {0, 0, 0};      // this rank's place in it
  double reach_ = 0;              // [m] ghost layer depth (GhostReach)
  std::vector<Neighbour> to_, from_;  // lower neighbours (get my ghosts, return their loads), upper ones
  HistoryRows pending_pairs_, pending_walls_;
  std::vector<double> buffer_;
  std::vector<std::vector<double>> out_, in_;
  std::vector<MPI_Request> requests_;
  std::int64_t migrated_ = 0, rebalances_ = 0, rebuilds_ = 0, refreshes_ = 0, ghosts_ = 0;
  RebalanceClock clock_;  ///< when the cuts move
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
