#include "mpi_domain.h"

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
  MpiDomain(const Model& model, const State& initial) : local_(model) {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (model.has_attached)
      throw CaseError(fmt::format("{}: the split into subdomains does not take spheres glued to walls (a shear cell)", model.source));
    // A clump belongs to the rank of its centre; its spheres reach `sticking_out_` beyond it,
    // so the ghost layer and the slabs are that much deeper.
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
    slab_min_ = reach_ + sticking_out_;
    // The axis on which the particles (and the domain box) spread furthest.
    double extent[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      const std::vector<double>& c = column(initial, a);
      if (!c.empty()) extent[a] = *std::max_element(c.begin(), c.end()) - *std::min_element(c.begin(), c.end());
      if (model.has_domain) extent[a] = std::max(extent[a], model.domain_max[a] - model.domain_min[a]);
      if (model.period[a] > 0) extent[a] = model.period[a];
    }
    // Particles travel along gravity (they settle, fall down chutes): slabs across it would see
    // most particles migrate and the balance shift all the time, so that axis counts half.
    const double g[3] = {std::abs(model.gravity[0]), std::abs(model.gravity[1]), std::abs(model.gravity[2])};
    const int down = static_cast<int>(std::max_element(g, g + 3) - g);
    double score[3] = {extent[0], extent[1], extent[2]};
    if (g[down] > 0) score[down] *= 0.5;
    axis_ = static_cast<int>(std::max_element(score, score + 3) - score);
    periodic_ = model.period[axis_] > 0;
    period_ = model.period[axis_];
    low_ = model.domain_min[axis_];
    if (periodic_) local_.period[axis_] = 0.0;  // the ranks carry the period across their faces
    const double needed = (periodic_ ? size_ : std::max(size_ - 2, 0)) * slab_min_;
    if (extent[axis_] < needed)
      throw CaseError(fmt::format("{}: {} ranks need a domain at least {:.4g} m long along {} (each slab one pair reach, {:.4g} m, "
                                  "wide); it is {:.4g} m, so fewer ranks would split it",
                                  model.source, size_, needed, "xyz"[axis_], slab_min_, extent[axis_]));
    down_ = rank_ > 0 ? rank_ - 1 : periodic_ ? size_ - 1 : MPI_PROC_NULL;
    up_ = rank_ < size_ - 1 ? rank_ + 1 : periodic_ ? 0 : MPI_PROC_NULL;
    // First cuts from the initial particles (the same on every rank), or evenly over the box.
    std::vector<double> coords;
    for (size_t p = 0; p < initial.size(); ++p) coords.push_back(wrapped(owner_coordinate(initial, p)));
    std::sort(coords.begin(), coords.end());
    cuts_.assign(size_ - 1, 0.0);
    double lo = periodic_ ? low_ : model.has_domain ? model.domain_min[axis_] : coords.empty() ? 0.0 : coords.front();
    double hi = periodic_ ? low_ + period_ : model.has_domain ? model.domain_max[axis_] : coords.empty() ? 1.0 : coords.back();
    for (int k = 1; k < size_; ++k) {
      if (coords.size() >= static_cast<size_t>(size_))
        cuts_[k - 1] = coords[coords.size() * k / size_];
      else
        cuts_[k - 1] = lo + (hi - lo) * k / size_;
    }
    keep_slabs_wide();
  }

  const Model& local_model() const override { return local_; }
  bool root() const override { return rank_ == 0; }
  int axis() const { return axis_; }

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

  bool owns(double x, double y, double z) const override {
    const double at[3] = {x, y, z};
    return owner(at[axis_]) == rank_;
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
    wrap_slab_axis(s);
    rebalance(s);
    const int width = model.history_width;
    const size_t n = s.size(), record = s.record_size();
    // Where each body goes (-1: stays), then free spheres and bodies with their spheres.
    std::vector<int> body_to(s.bodies.size(), -1);
    const std::vector<double>& centre = body_column(s, axis_);
    for (size_t b = 0; b < s.bodies.size(); ++b)
      if (owner(centre[b]) != rank_) body_to[b] = owner(centre[b]);
    std::unordered_map<std::int64_t, int> leaving;  // sphere id -> new owner
    std::vector<std::uint8_t> keep(n, 1);
    std::vector<std::vector<double>> spheres(size_), clumps(size_);
    std::vector<int> spheres_to(size_, 0), bodies_to(size_, 0), pair_rows_to(size_, 0), wall_rows_to(size_, 0);
    std::vector<std::vector<std::int32_t>> members(s.bodies.size());
    for (size_t p = 0; p < n; ++p) {
      const std::int32_t b = s.body[p];
      const int to = b >= 0 ? body_to[b] : owner(column(s, axis_)[p]);
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
    // Counts, then the doubles, all to all. Per destination: free spheres, clumps (body, count,
    // spheres), pair histories, wall histories.
    constexpr int kCounts = 5;
    std::vector<int> counts_out(kCounts * size_), counts_in(kCounts * size_);
    std::vector<double> send;
    std::vector<int> send_sizes(size_), receive_sizes(size_);
    for (int r = 0; r < size_; ++r) {
      const size_t before = send.size();
      for (const auto* part : {&spheres[r], &clumps[r], &pair_rows[r], &wall_rows[r]}) send.insert(send.end(), part->begin(), part->end());
      send_sizes[r] = static_cast<int>(send.size() - before);
      const int mine[kCounts] = {spheres_to[r], bodies_to[r], pair_rows_to[r], wall_rows_to[r], send_sizes[r]};
      std::copy(mine, mine + kCounts, counts_out.begin() + kCounts * r);
    }
    check(MPI_Alltoall(counts_out.data(), kCounts, MPI_INT, counts_in.data(), kCounts, MPI_INT, MPI_COMM_WORLD), "MPI_Alltoall");
    for (int r = 0; r < size_; ++r) receive_sizes[r] = counts_in[kCounts * r + 4];
    const std::vector<int> send_at = offsets_of(send_sizes), receive_at = offsets_of(receive_sizes);
    std::vector<double> received(static_cast<size_t>(receive_at.back()));
    check(MPI_Alltoallv(send.data(), send_sizes.data(), send_at.data(), MPI_DOUBLE, received.data(), receive_sizes.data(),
                        receive_at.data(), MPI_DOUBLE, MPI_COMM_WORLD),
          "MPI_Alltoallv");
    s.compact(keep);  // also drops the bodies that left with all their spheres
    for (int r = 0; r < size_; ++r) {
      const double* in = received.data() + receive_at[r];
      const int* count = counts_in.data() + kCounts * r;
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
    bytes_ += 8.0 * static_cast<double>(send.size());
  }

  void make_ghosts(const Model&, State& s) override {
    Timed timed{rebuild_seconds_};
    // The owned particles within one reach above the lower face go down as ghosts; rank 0 of a
    // periodic axis sends its to the top rank, one period up.
    send_slots_.clear();
    const std::vector<double>& c = column(s, axis_);
    const double face = slab_low();
    if (down_ != MPI_PROC_NULL)
      for (size_t p = 0; p < s.owned(); ++p)
        if (c[p] < face + reach_) send_slots_.push_back(static_cast<std::int32_t>(p));
    shift_ = rank_ == 0 && periodic_ ? period_ : 0.0;
    std::vector<double> out;
    const int record = static_cast<int>(s.record_size());
    out.reserve(send_slots_.size() * record);
    for (const std::int32_t p : send_slots_) {
      const size_t at = out.size();
      s.pack(p, out);
      out[at + axis_] += shift_;
    }
    int count = static_cast<int>(send_slots_.size()), incoming = 0;
    check(MPI_Sendrecv(&count, 1, MPI_INT, down_, 1, &incoming, 1, MPI_INT, up_, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Sendrecv");
    std::vector<double> in(static_cast<size_t>(incoming) * record);
    check(MPI_Sendrecv(out.data(), static_cast<int>(out.size()), MPI_DOUBLE, down_, 2, in.data(), static_cast<int>(in.size()),
                       MPI_DOUBLE, up_, 2, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Sendrecv");
    for (int k = 0; k < incoming; ++k) {
      s.unpack(in.data() + static_cast<size_t>(k) * record);
      s.body.back() = -1, s.attached.back() = -1;  // a copy: its body, if any, lives on its owner
    }
    s.ghosts = static_cast<size_t>(incoming);
    ++rebuilds_;
    ghosts_ += incoming;
    bytes_ += 8.0 * static_cast<double>(out.size());
  }

  void refresh_ghosts(State& s) override {
    Timed timed{step_seconds_};
    ++refreshes_;
    buffer_.clear();
    for (const std::int32_t p : send_slots_) {
      buffer_.insert(buffer_.end(), {s.x[p], s.y[p], s.z[p], s.vx[p], s.vy[p], s.vz[p], s.wx[p], s.wy[p], s.wz[p]});
      buffer_[buffer_.size() - 9 + axis_] += shift_;
    }
    incoming_.resize(9 * s.ghosts);
    check(MPI_Sendrecv(buffer_.data(), static_cast<int>(buffer_.size()), MPI_DOUBLE, down_, 3, incoming_.data(),
                       static_cast<int>(incoming_.size()), MPI_DOUBLE, up_, 3, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Sendrecv");
    bytes_ += 8.0 * static_cast<double>(buffer_.size());
    const double* in = incoming_.data();
    for (size_t p = s.owned(); p < s.size(); ++p, in += 9) {
      s.x[p] = in[0], s.y[p] = in[1], s.z[p] = in[2], s.vx[p] = in[3], s.vy[p] = in[4], s.vz[p] = in[5];
      s.wx[p] = in[6], s.wy[p] = in[7], s.wz[p] = in[8];
    }
  }

  void return_ghost_loads(State& s) override {
    Timed timed{step_seconds_};
    buffer_.clear();
    for (size_t p = s.owned(); p < s.size(); ++p) buffer_.insert(buffer_.end(), {s.fx[p], s.fy[p], s.fz[p], s.tx[p], s.ty[p], s.tz[p]});
    incoming_.resize(6 * send_slots_.size());
    check(MPI_Sendrecv(buffer_.data(), static_cast<int>(buffer_.size()), MPI_DOUBLE, up_, 4, incoming_.data(),
                       static_cast<int>(incoming_.size()), MPI_DOUBLE, down_, 4, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Sendrecv");
    bytes_ += 8.0 * static_cast<double>(buffer_.size());
    const double* in = incoming_.data();
    for (const std::int32_t p : send_slots_) {
      s.fx[p] += in[0], s.fy[p] += in[1], s.fz[p] += in[2], s.tx[p] += in[3], s.ty[p] += in[4], s.tz[p] += in[5];
      in += 6;
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
    wrap_slab_axis(s);
    for (size_t p = 0; p < s.size(); ++p) keep[p] = owner(owner_coordinate(s, p)) == rank_;
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
    // Run totals live on the root alone; the others count from zero and add theirs when gathered.
    if (rank_ != 0) {
      s.lost = 0, s.lost_mass = 0;
      for (OutletState& o : s.outlets) o = {};
      for (TriangleRecords& r : s.records)
        for (auto* c : {&r.normal_impulse, &r.shear_impulse, &r.shear_work, &r.impacts, &r.impact_energy}) std::fill(c->begin(), c->end(), 0.0);
    }
  }

  State gather(const State& s) override {
    Timed timed{gather_seconds_};
    const int width = local_.history_width;
    std::vector<double> mine;
    // Header: particles, pair rows, wall rows, lost, lost mass, then per outlet mass and count.
    const size_t owned = s.owned();
    const HistoryRows pairs = histories_by_id(s.pairs, s, width, false), walls = histories_by_id(s.wall_pairs, s, width, true);
    mine.insert(mine.end(), {static_cast<double>(owned), static_cast<double>(pairs.size()), static_cast<double>(walls.size()),
                             static_cast<double>(s.lost), s.lost_mass, static_cast<double>(s.bodies.size())});
    for (const OutletState& o : s.outlets) mine.insert(mine.end(), {o.removed_mass, static_cast<double>(o.removed)});
    for (const TriangleRecords& r : s.records)
      for (const auto* c : {&r.normal_impulse, &r.shear_impulse, &r.shear_work, &r.impacts, &r.impact_energy})
        mine.insert(mine.end(), c->begin(), c->end());
    for (size_t b = 0; b < s.bodies.size(); ++b) s.pack_body(b, mine);
    for (size_t p = 0; p < owned; ++p) s.pack(p, mine);
    for (const HistoryRows* rows : {&pairs, &walls})
      for (size_t q = 0; q < rows->size(); ++q) rows->pack(q, width, mine);
    const std::vector<std::vector<double>> parts = gather_to_root(mine);
    State whole = s;
    whole.compact(std::vector<std::uint8_t>(s.size(), 0));
    whole.ghosts = 0;
    whole.pairs.clear(), whole.wall_pairs.clear();
    whole.x_built.clear(), whole.y_built.clear(), whole.z_built.clear();
    whole.candidate_begin.assign(1, 0), whole.mesh_candidates.clear();
    if (rank_ != 0) return whole;
    whole.lost = 0, whole.lost_mass = 0;
    for (OutletState& o : whole.outlets) o = {};
    for (TriangleRecords& r : whole.records)
      for (auto* c : {&r.normal_impulse, &r.shear_impulse, &r.shear_work, &r.impacts, &r.impact_energy}) std::fill(c->begin(), c->end(), 0.0);
    const size_t record = s.record_size();
    HistoryRows all_pairs, all_walls;
    for (const std::vector<double>& part : parts) {
      const double* in = part.data();
      const size_t particles = static_cast<size_t>(in[0]), pair_rows = static_cast<size_t>(in[1]), wall_rows = static_cast<size_t>(in[2]);
      whole.lost += static_cast<std::int64_t>(in[3]), whole.lost_mass += in[4];
      const size_t bodies = static_cast<size_t>(in[5]);
      in += 6;
      for (OutletState& o : whole.outlets) o.removed_mass += in[0], o.removed += static_cast<std::int64_t>(in[1]), in += 2;
      for (TriangleRecords& r : whole.records)
        for (auto* c : {&r.normal_impulse, &r.shear_impulse, &r.shear_work, &r.impacts, &r.impact_energy})
          for (double& v : *c) v += *in++;
      const std::int32_t first_body = static_cast<std::int32_t>(whole.bodies.size());
      for (size_t k = 0; k < bodies; ++k, in += State::kBodyRecord) whole.unpack_body(in);
      for (size_t k = 0; k < particles; ++k, in += record) {
        whole.unpack(in);
        if (whole.body.back() >= 0) whole.body.back() += first_body;
      }
      in = all_pairs.unpack(in, pair_rows, width);
      all_walls.unpack(in, wall_rows, width);
    }
    // The lists by slot, as the engine keeps them (rebuild_contacts carries them by id).
    std::unordered_map<std::int64_t, std::int32_t> slot_of;
    for (size_t p = 0; p < whole.size(); ++p) slot_of[whole.id[p]] = static_cast<std::int32_t>(p);
    for (size_t q = 0; q < all_pairs.size(); ++q) {
      const auto a = slot_of.find(all_pairs.a[q]), b = slot_of.find(all_pairs.b[q]);
      if (a == slot_of.end() || b == slot_of.end()) continue;
      whole.pairs.i.push_back(a->second), whole.pairs.j.push_back(b->second);
      whole.pairs.history.insert(whole.pairs.history.end(), all_pairs.rows.begin() + static_cast<std::ptrdiff_t>(q * width),
                                 all_pairs.rows.begin() + static_cast<std::ptrdiff_t>((q + 1) * width));
    }
    for (size_t q = 0; q < all_walls.size(); ++q) {
      const auto a = slot_of.find(all_walls.a[q]);
      if (a == slot_of.end()) continue;
      whole.wall_pairs.i.push_back(a->second), whole.wall_pairs.j.push_back(static_cast<std::int32_t>(all_walls.b[q]));
      whole.wall_pairs.history.insert(whole.wall_pairs.history.end(), all_walls.rows.begin() + static_cast<std::ptrdiff_t>(q * width),
                                      all_walls.rows.begin() + static_cast<std::ptrdiff_t>((q + 1) * width));
    }
    return whole;
  }

  std::string statistics() const override {
    const double steps = static_cast<double>(std::max<std::int64_t>(rebuilds_ + refreshes_, 1));
    return fmt::format("{} steps ({} with a rebuild), mean {:.0f} ghosts, {} particles migrated, {} rebalances; communication "
                       "{:.3g} s in steps ({:.3g} ms a step), {:.3g} s at rebuilds, {:.3g} s gathering results; {:.3g} kB sent a step",
                       rebuilds_ + refreshes_, rebuilds_, static_cast<double>(ghosts_) / std::max<std::int64_t>(rebuilds_, 1), migrated_,
                       rebalances_, step_seconds_, 1e3 * step_seconds_ / steps, rebuild_seconds_, gather_seconds_, 1e-3 * bytes_ / steps);
  }

  std::string describe() const {
    std::string cuts;
    for (double c : cuts_) cuts += fmt::format("{}{:.4g}", cuts.empty() ? "" : ", ", c);
    return fmt::format("{} ranks, slabs along {}{} (cuts at {} m), ghost reach {:.3g} m", size_, "xyz"[axis_],
                       periodic_ ? " across the period" : "", cuts, reach_);
  }

 private:
  static std::vector<double>& column(State& s, int a) { return a == 0 ? s.x : a == 1 ? s.y : s.z; }
  static const std::vector<double>& column(const State& s, int a) { return a == 0 ? s.x : a == 1 ? s.y : s.z; }

  static std::vector<double>& body_column(State& s, int a) { return a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z; }
  static const std::vector<double>& body_column(const State& s, int a) { return a == 0 ? s.bodies.x : a == 1 ? s.bodies.y : s.bodies.z; }
  /// Where a sphere belongs along the slab axis: its own centre, or its clump's.
  double owner_coordinate(const State& s, size_t p) const {
    return s.body[p] >= 0 ? body_column(s, axis_)[s.body[p]] : column(s, axis_)[p];
  }
  /// Free spheres and clump centres back into the period along a periodic slab axis (a clump's
  /// spheres move with its centre).
  void wrap_slab_axis(State& s) const {
    if (!periodic_) return;
    std::vector<double>& c = column(s, axis_);
    std::vector<double>& centre = body_column(s, axis_);
    std::vector<double> shift(centre.size());
    for (size_t b = 0; b < centre.size(); ++b) shift[b] = wrapped(centre[b]) - centre[b], centre[b] += shift[b];
    for (size_t p = 0; p < s.size(); ++p) c[p] = s.body[p] >= 0 ? c[p] + shift[s.body[p]] : wrapped(c[p]);
  }
  double wrapped(double c) const { return periodic_ ? c - period_ * std::floor((c - low_) / period_) : c; }
  int owner(double c) const {
    return static_cast<int>(std::upper_bound(cuts_.begin(), cuts_.end(), wrapped(c)) - cuts_.begin());
  }
  double slab_low() const { return rank_ > 0 ? cuts_[rank_ - 1] : periodic_ ? low_ : -kInfinity; }

  /// Interior slabs (all slabs of a periodic axis) at least one reach wide.
  void keep_slabs_wide() {
    const int cuts = static_cast<int>(cuts_.size());
    if (cuts == 0) return;
    if (periodic_) cuts_[0] = std::max(cuts_[0], low_ + slab_min_);
    for (int k = 1; k < cuts; ++k) cuts_[k] = std::max(cuts_[k], cuts_[k - 1] + slab_min_);
    if (periodic_) cuts_[cuts - 1] = std::min(cuts_[cuts - 1], low_ + period_ - slab_min_);
    for (int k = cuts - 2; k >= 0; --k) cuts_[k] = std::min(cuts_[k], cuts_[k + 1] - slab_min_);
  }

  /// New cuts at the quantiles of the particle count when the fullest rank holds more than
  /// kImbalance times the mean (collective).
  void rebalance(const State& s) {
    const size_t n = s.size();
    double stats[3] = {static_cast<double>(n), kInfinity, kInfinity};  // count, -min, max
    double lo = kInfinity, hi = -kInfinity;
    for (size_t p = 0; p < n; ++p) lo = std::min(lo, wrapped(owner_coordinate(s, p))), hi = std::max(hi, wrapped(owner_coordinate(s, p)));
    stats[1] = -lo, stats[2] = hi;
    double most[3];
    check(MPI_Allreduce(stats, most, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
    const double total = sum(static_cast<double>(n));
    if (total < size_ || most[0] <= kImbalance * total / size_) return;
    if (periodic_) lo = low_, hi = low_ + period_;
    else lo = -most[1], hi = most[2];
    if (!(hi > lo)) return;
    std::vector<double> histogram(kHistogramBins, 0.0), all(kHistogramBins);
    const double width = (hi - lo) / kHistogramBins;
    for (size_t p = 0; p < n; ++p) histogram[std::clamp(static_cast<int>((wrapped(owner_coordinate(s, p)) - lo) / width), 0, kHistogramBins - 1)] += 1;
    check(MPI_Allreduce(histogram.data(), all.data(), kHistogramBins, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
    double below = 0;
    int bin = 0;
    for (int k = 1; k < size_; ++k) {
      const double target = total * k / size_;
      while (bin < kHistogramBins && below + all[bin] < target) below += all[bin++];
      const double within = bin < kHistogramBins && all[bin] > 0 ? (target - below) / all[bin] : 0.0;
      cuts_[k - 1] = lo + (bin + within) * width;
    }
    keep_slabs_wide();
    ++rebalances_;
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
  int axis_ = 0;
  bool periodic_ = false;
  double period_ = 0, low_ = 0;  // [m] along the slab axis
  double reach_ = 0;             // [m] ghost layer depth: a pair's largest listing distance (+ sticking_out_)
  double sticking_out_ = 0;      // [m] how far a clump's sphere centre lies from the clump's centre
  double slab_min_ = 0;          // [m] narrowest slab: reach_ + sticking_out_
  std::vector<double> cuts_;     // [m] between slab r and r + 1
  int down_ = -1, up_ = -1;      // neighbour ranks (MPI_PROC_NULL: none)
  std::vector<std::int32_t> send_slots_;  ///< owned slots sent down as ghosts, in message order
  double shift_ = 0;                       // [m] added along the axis to what is sent down
  HistoryRows pending_pairs_, pending_walls_;
  std::vector<double> buffer_, incoming_;
  std::int64_t migrated_ = 0, rebalances_ = 0, rebuilds_ = 0, refreshes_ = 0, ghosts_ = 0;
  double step_seconds_ = 0, rebuild_seconds_ = 0, gather_seconds_ = 0;  // [s] in MPI and packing
  double bytes_ = 0;  // [B] sent by this rank
};

}  // namespace

std::unique_ptr<Domain> make_domain(const Model& model, const State& initial, std::string* note) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size < 2) return nullptr;
  try {
    auto domain = std::make_unique<MpiDomain>(model, initial);
    if (note) *note = domain->describe();
    return domain;
  } catch (const CaseError& e) {
    if (note) *note = e.what();
    return nullptr;
  }
}

#else

std::unique_ptr<Domain> make_domain(const Model&, const State&, std::string*) { return nullptr; }

#endif

}  // namespace dem::app::mpi
