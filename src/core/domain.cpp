#include "core/domain.h"

#include <unordered_map>

#include "core/forces.h"
#include "core/mesh_contacts.h"
#include "core/neighbors.h"

namespace dem {

namespace {

/// Every column of a mesh's wear records, one loop for packing, zeroing and summing.
template <typename Records, typename F>
void each_record_column(Records& r, F&& f) {
  for (auto* c : r.columns()) f(*c);
}

}  // namespace

std::vector<double> pack_share(const State& s, int width) {
  std::vector<double> out;
  // Header: particles, pair rows, wall rows, lost, lost mass, bodies; then per outlet its mass
  // and count, the mesh records, the bodies, the particles and the two history tables.
  const size_t owned = s.owned();
  const HistoryRows pairs = histories_by_id(s.pairs, s, width, false), walls = histories_by_id(s.wall_pairs, s, width, true);
  out.insert(out.end(), {static_cast<double>(owned), static_cast<double>(pairs.size()), static_cast<double>(walls.size()),
                         static_cast<double>(s.lost), s.lost_mass, static_cast<double>(s.bodies.size())});
  for (const OutletState& o : s.outlets) out.insert(out.end(), {o.removed_mass, static_cast<double>(o.removed)});
  for (const TriangleRecords& r : s.records) each_record_column(r, [&](const std::vector<double>& c) { out.insert(out.end(), c.begin(), c.end()); });
  for (size_t b = 0; b < s.bodies.size(); ++b) s.pack_body(b, out);
  for (size_t p = 0; p < owned; ++p) s.pack(p, out);
  for (const HistoryRows* rows : {&pairs, &walls})
    for (size_t q = 0; q < rows->size(); ++q) rows->pack(q, width, out);
  return out;
}

State shared_part(const State& like) {
  State whole = like;
  whole.compact(std::vector<std::uint8_t>(like.size(), 0));
  whole.ghosts = 0;
  whole.pairs.clear(), whole.wall_pairs.clear();
  whole.x_built.clear(), whole.y_built.clear(), whole.z_built.clear();
  whole.candidate_begin.assign(1, 0), whole.mesh_candidates.clear();
  whole.lost = 0, whole.lost_mass = 0;
  for (OutletState& o : whole.outlets) o = {};
  for (TriangleRecords& r : whole.records) each_record_column(r, [](std::vector<double>& c) { std::fill(c.begin(), c.end(), 0.0); });
  return whole;
}

State merge_shares(const State& like, const std::vector<std::vector<double>>& shares, int width) {
  State whole = shared_part(like);
  const size_t record = like.record_size();
  HistoryRows all_pairs, all_walls;
  for (const std::vector<double>& share : shares) {
    const double* in = share.data();
    const size_t particles = static_cast<size_t>(in[0]), pair_rows = static_cast<size_t>(in[1]), wall_rows = static_cast<size_t>(in[2]);
    whole.lost += static_cast<std::int64_t>(in[3]), whole.lost_mass += in[4];
    const size_t bodies = static_cast<size_t>(in[5]);
    in += 6;
    for (OutletState& o : whole.outlets) o.removed_mass += in[0], o.removed += static_cast<std::int64_t>(in[1]), in += 2;
    for (TriangleRecords& r : whole.records)
      each_record_column(r, [&](std::vector<double>& c) {
        for (double& v : c) v += *in++;
      });
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
  const auto row = [width](const HistoryRows& rows, size_t q) {
    return std::pair{rows.rows.begin() + static_cast<std::ptrdiff_t>(q * width), rows.rows.begin() + static_cast<std::ptrdiff_t>((q + 1) * width)};
  };
  for (size_t q = 0; q < all_pairs.size(); ++q) {
    const auto a = slot_of.find(all_pairs.a[q]), b = slot_of.find(all_pairs.b[q]);
    if (a == slot_of.end() || b == slot_of.end()) continue;
    whole.pairs.i.push_back(a->second), whole.pairs.j.push_back(b->second);
    const auto [first, last] = row(all_pairs, q);
    whole.pairs.history.insert(whole.pairs.history.end(), first, last);
  }
  for (size_t q = 0; q < all_walls.size(); ++q) {
    const auto a = slot_of.find(all_walls.a[q]);
    if (a == slot_of.end()) continue;
    whole.wall_pairs.i.push_back(a->second), whole.wall_pairs.j.push_back(static_cast<std::int32_t>(all_walls.b[q]));
    const auto [first, last] = row(all_walls, q);
    whole.wall_pairs.history.insert(whole.wall_pairs.history.end(), first, last);
  }
  return whole;
}

WholeState ready_for_results(const Model& model, State gathered) {
  WholeState whole;
  whole.state = std::move(gathered);
  place_meshes(model, whole.state.time, whole.work);
  rebuild_contacts(model, whole.state, whole.work);
  whole.evaluated = whole.state;
  compute_forces(model, whole.evaluated, whole.work);  // advances the copy's histories only
  return whole;
}

}  // namespace dem
