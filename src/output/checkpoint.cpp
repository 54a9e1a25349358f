#include "output/checkpoint.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <optional>
#include <type_traits>

#include "core/domain.h"

namespace dem {

namespace {

/// Version 9: magic, model hash, run id, the State with the force impulses of the wall records
/// (TriangleRecords::force_impulse_x, _y, _z) and the stream profiles (State::stream_profiles; visit).
constexpr char kMagic[8] = {'D', 'E', 'M', 'C', 'K', 'P', 'T', '9'};
/// Version 8 lacks the force impulses: read as zeros, so a run resumed from it counts the mean
/// traction and the liner loads (report/liner_loads.h) from the resume on, though its pressure
/// counts from output.records_from.
constexpr char kMagic8[8] = {'D', 'E', 'M', 'C', 'K', 'P', 'T', '8'};
/// Version 7 lacks MeshLoads::interval: read as empty, so the first row after resuming averages
/// the mesh loads from the resume on.
constexpr char kMagic7[8] = {'D', 'E', 'M', 'C', 'K', 'P', 'T', '7'};
/// Version 6 has no run id (read as 0).
constexpr char kMagic6[8] = {'D', 'E', 'M', 'C', 'K', 'P', 'T', '6'};
/// A rank's share: magic, model hash, step, rank, ranks, count, then `count` doubles (pack_share,
/// core/domain.h). Version 2 packs the eight columns of the wall records; a share of version 1
/// (five columns) is refused as not of this version.
constexpr char kShareMagic[8] = {'D', 'E', 'M', 'S', 'H', 'A', 'R', '2'};
/// Version 5 lacks State::lists_drift_velocity: read as zero, which is always a valid drift
/// (verlet.h), so its runs resume.
constexpr char kMagic5[8] = {'D', 'E', 'M', 'C', 'K', 'P', 'T', '5'};

/// Every field of the State, in one order, for both directions (`version` 5 to 9; 7 stores the State as 6).
template <typename Io, typename S>
void visit(Io& io, S& s, int version = 9) {
  io(s.time), io(s.step), io(s.next_id), io(s.lost), io(s.lost_mass);
  for (auto* c : {&s.x, &s.y, &s.z, &s.vx, &s.vy, &s.vz, &s.wx, &s.wy, &s.wz, &s.fx, &s.fy, &s.fz, &s.tx, &s.ty, &s.tz,
                  &s.radius, &s.inv_mass, &s.inv_inertia, &s.offset_x, &s.offset_y, &s.offset_z, &s.x_built, &s.y_built,
                  &s.z_built})
    io(*c);
  io(s.material), io(s.id), io(s.body), io(s.attached);
  auto& b = s.bodies;
  for (auto* c : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.qw, &b.qx, &b.qy, &b.qz, &b.lx, &b.ly, &b.lz, &b.fx, &b.fy,
                  &b.fz, &b.tx, &b.ty, &b.tz, &b.mass, &b.ix, &b.iy, &b.iz})
    io(*c);
  io(b.id);
  auto& w = s.walls;
  for (auto* c : {&w.px, &w.py, &w.pz, &w.vx, &w.vy, &w.vz, &w.fx, &w.fy, &w.fz}) io(*c);
  io(s.inlets), io(s.outlets);
  for (auto* list : {&s.pairs, &s.wall_pairs}) io(list->i), io(list->j), io(list->history);
  io(s.has_meshes), io(s.mesh_history_width);
  auto& mc = s.mesh_contacts;
  io(mc.count), io(mc.mesh), io(mc.triangle), io(mc.px), io(mc.py), io(mc.pz), io(mc.history);
  io(s.candidate_begin), io(s.mesh_candidates), io(s.lists_built_time);
  if (version >= 6) io(s.lists_drift_velocity);
  std::uint64_t meshes = s.records.size();
  io(meshes);
  if constexpr (!std::is_const_v<S>) s.records.resize(meshes);
  for (auto& r : s.records) {
    io(r.normal_impulse), io(r.shear_impulse), io(r.shear_work), io(r.impacts), io(r.impact_energy);
    // Before version 9 the force impulses were not kept: zeros, one per triangle.
    if (version >= 9) {
      io(r.force_impulse_x), io(r.force_impulse_y), io(r.force_impulse_z);
    } else if constexpr (!std::is_const_v<S>) {
      for (auto* c : {&r.force_impulse_x, &r.force_impulse_y, &r.force_impulse_z}) c->assign(r.normal_impulse.size(), 0.0);
    }
  }
  for (auto* c : {&s.mesh_loads.fx, &s.mesh_loads.fy, &s.mesh_loads.fz, &s.mesh_loads.tx, &s.mesh_loads.ty, &s.mesh_loads.tz,
                  &s.mesh_loads.power})
    io(*c);
  if (version >= 8) io(s.mesh_loads.interval), io(s.mesh_loads.interval_time);
  // Version 9 also keeps the stream profiles (State::stream_profiles); before it they are empty,
  // and a resumed run's profiles count from the resume on (their window says how long).
  if (version >= 9) {
    auto& p = s.stream_profiles;
    io(p.mass_time), io(p.momentum_time), io(p.window), io(p.last_row_time), io(p.has_row);
  }
}

struct Writer {
  std::ofstream& out;
  template <typename T>
  void operator()(const T& value) {
    if constexpr (std::is_trivially_copyable_v<T>) {
      out.write(reinterpret_cast<const char*>(&value), sizeof(T));
    } else {
      const std::uint64_t count = value.size();
      out.write(reinterpret_cast<const char*>(&count), sizeof count);
      out.write(reinterpret_cast<const char*>(value.data()), static_cast<std::streamsize>(count * sizeof(value[0])));
    }
  }
};

struct Reader {
  std::ifstream& in;
  const std::string& path;
  std::uint64_t remaining;  // bytes left in the file, bounds every allocation
  void read(void* data, std::uint64_t bytes) {
    if (bytes > remaining) throw std::runtime_error(fmt::format("{}: checkpoint is truncated or corrupt", path));
    in.read(static_cast<char*>(data), static_cast<std::streamsize>(bytes));
    if (!in) throw std::runtime_error(fmt::format("{}: checkpoint is truncated", path));
    remaining -= bytes;
  }
  template <typename T>
  void operator()(T& value) {
    if constexpr (std::is_trivially_copyable_v<T>) {
      read(&value, sizeof(T));
    } else {
      std::uint64_t count = 0;
      read(&count, sizeof count);
      if (count > remaining / sizeof(value[0]) + 1) throw std::runtime_error(fmt::format("{}: checkpoint is corrupt", path));
      value.resize(count);
      read(value.data(), count * sizeof(value[0]));
    }
  }
};

}  // namespace

void save_checkpoint(const std::string& path, const Model& model, const State& state, std::uint64_t run_id) {
  const std::filesystem::path target(path);
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
  const std::string temporary = path + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(kMagic, sizeof kMagic);
    Writer writer{out};
    writer(model.hash);
    writer(run_id);
    visit(writer, state);
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write the checkpoint (disk full?)", temporary));
  }
  std::filesystem::rename(temporary, target);
}

State load_checkpoint(const std::string& path, const Model& model, std::uint64_t* run_id) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: no checkpoint to resume from", path));
  Reader reader{in, path, static_cast<std::uint64_t>(std::filesystem::file_size(path))};
  char magic[sizeof kMagic];
  reader.read(magic, sizeof magic);
  const int version = std::memcmp(magic, kMagic, sizeof kMagic) == 0     ? 9
                      : std::memcmp(magic, kMagic8, sizeof kMagic8) == 0 ? 8
                      : std::memcmp(magic, kMagic7, sizeof kMagic7) == 0 ? 7
                      : std::memcmp(magic, kMagic6, sizeof kMagic6) == 0 ? 6
                      : std::memcmp(magic, kMagic5, sizeof kMagic5) == 0 ? 5
                                                                         : 0;
  if (version == 0) throw std::runtime_error(fmt::format("{}: not a demdesign checkpoint of this version", path));
  std::uint64_t hash = 0;
  reader(hash);
  if (hash != model.hash)
    throw std::runtime_error(fmt::format("{}: the checkpoint belongs to a different model (the case's physics changed "
                                         "since it was written); run without --resume to start again",
                                         path));
  std::uint64_t written_by = 0;
  if (version >= 7) reader(written_by);
  if (run_id) *run_id = written_by;
  State state;
  visit(reader, state, version);
  return state;
}

namespace {

namespace fs = std::filesystem;

fs::path shares_directory(const std::string& directory) { return fs::path(directory) / "checkpoint.ranks"; }

std::string share_name(std::int64_t step, int rank, int ranks) { return fmt::format("step-{}.rank-{}-of-{}.bin", step, rank, ranks); }

/// A share file's step, rank and ranks' count, from its name; nullopt for any other file
/// (a temporary one among them).
struct ShareName {
  std::int64_t step;
  int rank, ranks;
};
std::optional<ShareName> parse_share_name(const fs::path& file) {
  long long step = 0;
  int rank = 0, ranks = 0;
  if (std::sscanf(file.filename().c_str(), "step-%lld.rank-%d-of-%d", &step, &rank, &ranks) != 3) return std::nullopt;
  if (file.filename() != share_name(step, rank, ranks)) return std::nullopt;
  return ShareName{step, rank, ranks};
}

/// The ranks' count of the shares of `step` in `shares`, from their names (0 when there are none).
int share_count(const fs::path& shares, std::int64_t step) {
  int count = 0;
  std::error_code error;
  for (const fs::directory_entry& e : fs::directory_iterator(shares, error))
    if (const std::optional<ShareName> name = parse_share_name(e.path()); name && name->step == step) count = std::max(count, name->ranks);
  return count;
}

std::vector<double> load_share(const fs::path& path, const Model& model, std::int64_t step, int rank, int ranks) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error(fmt::format("{}: the share of rank {} of {} at step {} is missing; this per-rank checkpoint cannot be resumed",
                                         path.string(), rank, ranks, step));
  Reader reader{in, path.string(), static_cast<std::uint64_t>(fs::file_size(path))};
  char magic[sizeof kShareMagic];
  reader.read(magic, sizeof magic);
  if (std::memcmp(magic, kShareMagic, sizeof magic) != 0) throw std::runtime_error(fmt::format("{}: not a demdesign checkpoint share of this version", path.string()));
  std::uint64_t hash = 0;
  std::int64_t at = 0;
  std::int32_t r = 0, n = 0;
  reader(hash), reader(at), reader(r), reader(n);
  if (hash != model.hash) throw std::runtime_error(fmt::format("{}: the share belongs to a different model; run without --resume to start again", path.string()));
  if (at != step || r != rank || n != ranks) throw std::runtime_error(fmt::format("{}: the share's header does not match its name", path.string()));
  std::vector<double> share;
  reader(share);
  return share;
}

}  // namespace

void save_checkpoint_share(const std::string& directory, const Model& model, std::int64_t step, int rank, int ranks,
                           const std::vector<double>& share) {
  const fs::path shares = shares_directory(directory);
  fs::create_directories(shares);
  const fs::path target = shares / share_name(step, rank, ranks);
  const std::string temporary = target.string() + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(kShareMagic, sizeof kShareMagic);
    Writer writer{out};
    writer(model.hash), writer(static_cast<std::int64_t>(step)), writer(static_cast<std::int32_t>(rank)), writer(static_cast<std::int32_t>(ranks));
    writer(share);
    out.flush();
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write the checkpoint share (disk full?)", temporary));
  }
  fs::rename(temporary, target);
}

void commit_checkpoint_shares(const std::string& directory, const Model& model, const State& like, std::uint64_t run_id) {
  save_checkpoint((fs::path(directory) / "checkpoint.ranks.bin").string(), model, shared_part(like), run_id);
  std::error_code error;
  fs::remove(fs::path(directory) / "checkpoint.bin", error);
  std::vector<fs::path> stale;
  for (const fs::directory_entry& e : fs::directory_iterator(shares_directory(directory), error)) {
    const std::optional<ShareName> name = parse_share_name(e.path());
    if (e.path().extension() == ".part" || (name && name->step != like.step)) stale.push_back(e.path());
  }
  for (const fs::path& p : stale) fs::remove(p, error);
}

void save_whole_checkpoint(const std::string& directory, const Model& model, const State& state, std::uint64_t run_id) {
  save_checkpoint((fs::path(directory) / "checkpoint.bin").string(), model, state, run_id);
  std::error_code error;
  fs::remove(fs::path(directory) / "checkpoint.ranks.bin", error);
  fs::remove_all(shares_directory(directory), error);
}

State load_resumable(const std::string& directory, const Model& model, std::string* from, std::uint64_t* run_id) {
  const fs::path whole_path = fs::path(directory) / "checkpoint.bin", ranks_path = fs::path(directory) / "checkpoint.ranks.bin";
  const bool whole_exists = fs::exists(whole_path), ranks_exist = fs::exists(ranks_path);
  if (!whole_exists && !ranks_exist) throw std::runtime_error(fmt::format("{}: no checkpoint to resume from", whole_path.string()));
  std::optional<State> whole;
  std::uint64_t whole_run = 0, ranks_run = 0;
  if (whole_exists) whole = load_checkpoint(whole_path.string(), model, &whole_run);
  if (ranks_exist) {
    const State like = load_checkpoint(ranks_path.string(), model, &ranks_run);
    if (!whole || like.step > whole->step) {
      const fs::path shares = shares_directory(directory);
      const int ranks = share_count(shares, like.step);
      if (ranks == 0) throw std::runtime_error(fmt::format("{}: no share of step {} in {}; this per-rank checkpoint cannot be resumed",
                                                           ranks_path.string(), like.step, shares.string()));
      std::vector<std::vector<double>> parts;
      for (int rank = 0; rank < ranks; ++rank) parts.push_back(load_share(shares / share_name(like.step, rank, ranks), model, like.step, rank, ranks));
      if (from) *from = fmt::format("{} and the shares of {} ranks in {}", ranks_path.string(), ranks, shares.string());
      if (run_id) *run_id = ranks_run;
      return merge_shares(like, parts, model.history_width);
    }
  }
  if (from) *from = whole_path.string();
  if (run_id) *run_id = whole_run;
  return std::move(*whole);
}

}  // namespace dem
