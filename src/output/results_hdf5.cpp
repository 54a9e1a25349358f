// Particle frames as HDF5 plus an XDMF 3 index; see results_hdf5.h for the layout and the atomicity rules.
#include "output/results_hdf5.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <type_traits>

namespace dem {
namespace {

namespace fs = std::filesystem;

constexpr const char* kXdmfName = "particles.xdmf";
constexpr const char* kFramesDir = "frames";

// One HDF5 identifier, closed on every exit path: the file is opened with H5F_CLOSE_SEMI, so a leaked
// dataset or attribute would make H5Fclose fail instead of silently deferring the flush.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id_ >= 0) closer_(id_);
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  /// Closes now and reports the result (the destructor cannot).
  herr_t close() {
    const hid_t id = id_;
    id_ = -1;
    return id >= 0 ? closer_(id) : 0;
  }

 private:
  hid_t id_;
  Closer closer_;
};

// HDF5 prints its error stack to stderr by default; we turn it into the exception message instead,
// and restore the caller's handler afterwards (it is process-wide state).
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

// The two innermost descriptions of the current HDF5 error stack (they carry errno and the file name).
std::string hdf5_error_text() {
  struct Collected {
    std::string text;
    int entries = 0;
  } collected;
  const auto visit = [](unsigned, const H5E_error2_t* error, void* data) -> herr_t {
    auto& c = *static_cast<Collected*>(data);
    if (c.entries >= 2 || error->desc == nullptr || *error->desc == '\0') return 0;
    if (!c.text.empty()) c.text += "; ";
    c.text += error->desc;
    std::replace(c.text.begin(), c.text.end(), '\n', ' ');
    ++c.entries;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, visit, &collected);
  return collected.text.empty() ? "no HDF5 error detail" : collected.text;
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(fmt::format("cannot write {}: {}", path, what));
}

template <typename T>
T check(T result, const std::string& path, const char* what) {
  if (result < 0) fail(path, fmt::format("{} failed ({})", what, hdf5_error_text()));
  return result;
}

static_assert(std::is_same_v<hid_t, std::int64_t>, "FrameShare carries HDF5 identifiers as std::int64_t");

// The rows of a dataset this process writes: all of them (one process), or one rank's block of a
// file every rank writes together, through a collective transfer list.
struct Rows {
  hsize_t offset = 0, total = 0;
  hid_t transfer = H5P_DEFAULT;
};

// Datasets are contiguous and uncompressed: simplest for every reader, and n = 0 is a valid extent.
void write_dataset(hid_t file, const std::string& path, const char* name, hid_t file_type, hid_t memory_type,
                   std::size_t n, std::size_t width, const void* data, const Rows& rows) {
  const int dimensions = width == 1 ? 1 : 2;
  const hsize_t dims[2] = {rows.total, static_cast<hsize_t>(width)};
  Handle space(check(H5Screate_simple(dimensions, dims, nullptr), path, "H5Screate_simple"), H5Sclose);
  Handle set(H5Dcreate2(file, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  if (!set.valid()) fail(path, fmt::format("creating dataset '{}' failed ({})", name, hdf5_error_text()));
  // An empty frame has nothing to write. Otherwise every rank takes part in the (collective)
  // write, with its block of rows or with none.
  if (rows.total > 0) {
    const hsize_t start[2] = {rows.offset, 0}, count[2] = {static_cast<hsize_t>(n), static_cast<hsize_t>(width)};
    Handle memory(check(H5Screate_simple(dimensions, count, nullptr), path, "H5Screate_simple"), H5Sclose);
    if (n > 0) {
      check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), path, "H5Sselect_hyperslab");
    } else {
      check(H5Sselect_none(space.get()), path, "H5Sselect_none");
      check(H5Sselect_none(memory.get()), path, "H5Sselect_none");
    }
    static const double nothing = 0;  // H5Dwrite rejects a null buffer even for an empty selection
    if (H5Dwrite(set.get(), memory_type, memory.get(), space.get(), rows.transfer, n > 0 ? data : &nothing) < 0)
      fail(path, fmt::format("writing dataset '{}' failed ({})", name, hdf5_error_text()));
  }
  check(set.close(), path, "H5Dclose");
}

void write_attribute(hid_t object, const std::string& path, const std::string& name, hid_t file_type,
                     hid_t memory_type, const void* value) {
  Handle space(check(H5Screate(H5S_SCALAR), path, "H5Screate"), H5Sclose);
  Handle attribute(H5Acreate2(object, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attribute.valid()) fail(path, fmt::format("creating attribute '{}' failed ({})", name, hdf5_error_text()));
  if (H5Awrite(attribute.get(), memory_type, value) < 0)
    fail(path, fmt::format("writing attribute '{}' failed ({})", name, hdf5_error_text()));
  check(attribute.close(), path, "H5Aclose");
}

// Fixed-length, null-terminated UTF-8: readable by h5py, h5dump and ParaView alike.
void write_string_attribute(hid_t object, const std::string& path, const std::string& name, const std::string& value) {
  Handle type(check(H5Tcopy(H5T_C_S1), path, "H5Tcopy"), H5Tclose);
  check(H5Tset_size(type.get(), value.size() + 1), path, "H5Tset_size");
  check(H5Tset_strpad(type.get(), H5T_STR_NULLTERM), path, "H5Tset_strpad");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), path, "H5Tset_cset");
  write_attribute(object, path, name, type.get(), type.get(), value.c_str());
}

// Pushes a file's (or directory's) data to the disk, so a rename never publishes data still in the
// page cache: after a power loss the renamed name points at complete data.
void sync_to_disk(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) fail(path, fmt::format("open for fsync failed ({})", std::generic_category().message(errno)));
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (result != 0) fail(path, fmt::format("fsync failed ({})", std::generic_category().message(error)));
}

// Replaces `to` by `from` in one step (rename(2) is atomic within a file system).
void publish(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) fail(to.string(), fmt::format("renaming {} failed ({})", from.string(), ec.message()));
}

// Temporary file + fsync + rename: readers see the old file or the new one, never a partial one.
void write_text_atomically(const std::string& directory, const std::string& name, const std::string& text) {
  const fs::path final_path = fs::path(directory) / name;
  const fs::path temp_path = fs::path(directory) / (name + ".tmp");
  {
    std::ofstream file(temp_path, std::ios::binary | std::ios::trunc);
    if (!file) fail(temp_path.string(), "cannot open for writing");
    file.write(text.data(), static_cast<std::streamsize>(text.size()));
    file.close();
    if (!file) {
      std::error_code ec;
      fs::remove(temp_path, ec);
      fail(temp_path.string(), "write failed (disk full?)");
    }
  }
  sync_to_disk(temp_path.string(), false);
  publish(temp_path, final_path);
  sync_to_disk(directory.empty() ? "." : directory, true);
}

std::string frame_file_name(std::int64_t step) { return fmt::format("frame_{:06d}.h5", step); }

// Value of `name="..."` inside the tag that starts at `tag` (up to its closing '>').
std::string tag_attribute(const std::string& text, std::size_t tag, const std::string& name) {
  const std::size_t end = text.find('>', tag);
  const std::string key = " " + name + "=\"";
  const std::size_t at = text.find(key, tag);
  if (at == std::string::npos || at > end) throw std::runtime_error(fmt::format("a tag without {}=", name));
  const std::size_t begin = at + key.size();
  const std::size_t close = text.find('"', begin);
  if (close == std::string::npos) throw std::runtime_error("an unterminated attribute");
  return text.substr(begin, close - begin);
}

template <typename T>
T parse_number(const std::string& s) {
  T value{};
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) throw std::runtime_error(fmt::format("bad number '{}'", s));
  return value;
}

// One DataItem pointing at `file:/dataset`; Precision is bytes per value, as XDMF defines it.
std::string data_item(const std::string& file, const char* dataset, std::size_t n, std::size_t width,
                      const char* number_type, int precision) {
  const std::string dims = width == 1 ? fmt::format("{}", n) : fmt::format("{} {}", n, width);
  return fmt::format(R"(<DataItem Dimensions="{}" NumberType="{}" Precision="{}" Format="HDF">{}:/{}</DataItem>)",
                     dims, number_type, precision, file, dataset);
}

}  // namespace

FrameWriter::FrameWriter(std::string directory, std::vector<std::string> material_names,
                         std::vector<std::pair<std::string, std::string>> attributes)
    : directory_(std::move(directory)), attributes_(std::move(attributes)) {
  // Names are stored comma-separated, so a comma inside one would be read back as two.
  for (std::size_t m = 0; m < material_names.size(); ++m) {
    if (material_names[m].find(',') != std::string::npos)
      throw std::invalid_argument(
          fmt::format("material name '{}' contains a comma, which separates names in the frame files", material_names[m]));
    material_names_ += (m ? "," : "") + material_names[m];
  }
  // Attribute keys share the root with the writer's own attributes; HDF5 refuses duplicates mid-write.
  for (std::size_t a = 0; a < attributes_.size(); ++a) {
    const std::string& key = attributes_[a].first;
    if (key.empty() || key == "time" || key == "step" || key == "units" || key == "material_names")
      throw std::invalid_argument(fmt::format("frame attribute key '{}' is empty or reserved", key));
    for (std::size_t b = 0; b < a; ++b)
      if (attributes_[b].first == key) throw std::invalid_argument(fmt::format("frame attribute key '{}' given twice", key));
  }
}

void FrameWriter::check_columns(const ParticleFrame& f) const {
  // Every column but clump and orientation is required; the four quaternion columns come together.
  if (f.count == 0) return;
  const void* required[] = {f.id, f.x, f.y, f.z, f.vx, f.vy, f.vz, f.wx, f.wy, f.wz, f.radius, f.material};
  for (const void* column : required)
    if (column == nullptr) throw std::invalid_argument(fmt::format("frame at step {}: a required column is null", f.step));
  const int quaternion_columns = (f.qw != nullptr) + (f.qx != nullptr) + (f.qy != nullptr) + (f.qz != nullptr);
  if (quaternion_columns != 0 && quaternion_columns != 4)
    throw std::invalid_argument(fmt::format("frame at step {}: give all four orientation columns or none", f.step));
}

void FrameWriter::prepare(std::int64_t step) {
  const fs::path frames_dir = fs::path(directory_) / kFramesDir;
  std::error_code ec;
  fs::create_directories(frames_dir, ec);
  if (ec) fail(frames_dir.string(), fmt::format("cannot create the directory ({})", ec.message()));
  // A resumed run rewinds: unlist the frames from this step on before their files are replaced, so the
  // XDMF never describes a file whose content changed under it.
  if (!frames_.empty() && frames_.back().step >= step) {
    std::vector<FrameInfo> kept;
    std::copy_if(frames_.begin(), frames_.end(), std::back_inserter(kept), [&](const FrameInfo& i) { return i.step < step; });
    write_xdmf(kept);
    frames_ = std::move(kept);
  }
}

void FrameWriter::publish_and_list(const std::string& part, const FrameInfo& frame) {
  const fs::path frames_dir = fs::path(directory_) / kFramesDir;
  try {
    sync_to_disk(part, false);
    publish(part, fs::path(directory_) / frame.file);
  } catch (...) {
    std::error_code ec;
    fs::remove(part, ec);
    throw;
  }
  sync_to_disk(frames_dir.string(), true);
  // List the frame; if the XDMF cannot be replaced the old one stays valid and so does our list.
  std::vector<FrameInfo> listed = frames_;
  listed.push_back(frame);
  write_xdmf(listed);
  frames_ = std::move(listed);
}

void FrameWriter::write_frame(const ParticleFrame& f) {
  check_columns(f);
  prepare(f.step);
  // Write beside the final name and publish by rename only once the file is complete on disk.
  const std::string name = frame_file_name(f.step);
  const std::string part = (fs::path(directory_) / kFramesDir / (name + ".part")).string();
  try {
    write_hdf5(part, f, FrameShare{0, f.count, true, -1, -1, {}});
  } catch (...) {
    std::error_code ec;
    fs::remove(part, ec);
    throw;
  }
  publish_and_list(part, {f.time, f.step, std::string(kFramesDir) + "/" + name, f.count});
}

void FrameWriter::write_frame(const ParticleFrame& mine, const FrameShare& share) {
  const std::string name = frame_file_name(mine.step);
  const std::string part = (fs::path(directory_) / kFramesDir / (name + ".part")).string();
  // Every rank learns of a failure on any rank at each of the three stages, so none waits for the
  // others in a collective call they never reach.
  std::string error;
  const auto stage = [&](const auto& work) {
    try {
      work();
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (share.all(error.empty())) return;
    if (share.root) {
      std::error_code ec;
      fs::remove(part, ec);
    }
    throw std::runtime_error(error.empty() ? fmt::format("frame at step {}: another rank could not write its part (its message is on its "
                                                         "standard error)", mine.step)
                                           : error);
  };
  stage([&] {
    check_columns(mine);
    if (share.root) prepare(mine.step);  // the directory exists before any rank opens the file
  });
  stage([&] { write_hdf5(part, mine, share); });
  const FrameInfo frame{mine.time, mine.step, std::string(kFramesDir) + "/" + name, share.total};
  stage([&] {
    if (share.root) publish_and_list(part, frame);
  });
  if (!share.root) {  // the same list as the root's, though only the root writes it
    std::erase_if(frames_, [&](const FrameInfo& i) { return i.step >= frame.step; });
    frames_.push_back(frame);
  }
}

void FrameWriter::write_hdf5(const std::string& path, const ParticleFrame& f, const FrameShare& share) {
  const std::size_t n = f.count;
  const QuietHdf5 quiet;
  const Rows rows{share.offset, share.total, share.transfer >= 0 ? share.transfer : H5P_DEFAULT};

  // H5F_CLOSE_SEMI: H5Fclose fails rather than defer the close while something is open, so its
  // success below really means the file is flushed and complete.
  Handle access(check(share.file_access >= 0 ? H5Pcopy(share.file_access) : H5Pcreate(H5P_FILE_ACCESS), path, "H5Pcreate"), H5Pclose);
  check(H5Pset_fclose_degree(access.get(), H5F_CLOSE_SEMI), path, "H5Pset_fclose_degree");
  Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.get()), H5Fclose);
  if (!file.valid()) fail(path, fmt::format("H5Fcreate failed ({})", hdf5_error_text()));
  const hid_t root = file.get();

  // Interleave three columns into n x 3 rows, the layout XDMF and ParaView expect for vectors.
  const auto interleave = [&](const double* a, const double* b, const double* c) {
    vec3_.resize(3 * n);
    for (std::size_t p = 0; p < n; ++p) {
      vec3_[3 * p] = a[p];
      vec3_[3 * p + 1] = b[p];
      vec3_[3 * p + 2] = c[p];
    }
    return vec3_.data();
  };
  const hid_t f64 = H5T_IEEE_F64LE, i64 = H5T_STD_I64LE, i32 = H5T_STD_I32LE;
  write_dataset(root, path, "id", i64, H5T_NATIVE_INT64, n, 1, f.id, rows);
  write_dataset(root, path, "position", f64, H5T_NATIVE_DOUBLE, n, 3, interleave(f.x, f.y, f.z), rows);
  write_dataset(root, path, "velocity", f64, H5T_NATIVE_DOUBLE, n, 3, interleave(f.vx, f.vy, f.vz), rows);
  write_dataset(root, path, "angular_velocity", f64, H5T_NATIVE_DOUBLE, n, 3, interleave(f.wx, f.wy, f.wz), rows);
  write_dataset(root, path, "radius", f64, H5T_NATIVE_DOUBLE, n, 1, f.radius, rows);
  write_dataset(root, path, "material", i32, H5T_NATIVE_INT32, n, 1, f.material, rows);

  int32_.assign(n, -1);
  if (f.clump != nullptr) std::copy(f.clump, f.clump + n, int32_.begin());
  write_dataset(root, path, "clump", i32, H5T_NATIVE_INT32, n, 1, int32_.data(), rows);

  // Orientation rows are w x y z; identity for free spheres when the engine gives no quaternions.
  quat_.resize(4 * n);
  for (std::size_t p = 0; p < n; ++p) {
    const bool given = f.qw != nullptr;
    quat_[4 * p] = given ? f.qw[p] : 1.0;
    quat_[4 * p + 1] = given ? f.qx[p] : 0.0;
    quat_[4 * p + 2] = given ? f.qy[p] : 0.0;
    quat_[4 * p + 3] = given ? f.qz[p] : 0.0;
  }
  write_dataset(root, path, "orientation", f64, H5T_NATIVE_DOUBLE, n, 4, quat_.data(), rows);

  // |v| [m/s], stored so ParaView can colour by speed without a Calculator filter.
  scalar_.resize(n);
  for (std::size_t p = 0; p < n; ++p) scalar_[p] = std::sqrt(f.vx[p] * f.vx[p] + f.vy[p] * f.vy[p] + f.vz[p] * f.vz[p]);
  write_dataset(root, path, "speed", f64, H5T_NATIVE_DOUBLE, n, 1, scalar_.data(), rows);

  // Polyvertex cells 0..total-1 (this rank's rows from its offset): the Xdmf3 reader makes no cells without them, and ParaView then draws nothing.
  int64_.resize(n);
  for (std::size_t p = 0; p < n; ++p) int64_[p] = static_cast<std::int64_t>(share.offset + p);
  write_dataset(root, path, "connectivity", i64, H5T_NATIVE_INT64, n, 1, int64_.data(), rows);

  write_attribute(root, path, "time", f64, H5T_NATIVE_DOUBLE, &f.time);
  write_attribute(root, path, "step", i64, H5T_NATIVE_INT64, &f.step);
  write_string_attribute(root, path, "units", "SI");
  write_string_attribute(root, path, "material_names", material_names_);
  for (const auto& [key, value] : attributes_) write_string_attribute(root, path, key, value);

  check(file.close(), path, "H5Fclose");
}

void FrameWriter::write_xdmf(const std::vector<FrameInfo>& frames) const {
  // Doubles print in shortest round-trip form ("{}"), so times read back bit-exact.
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
         "<!-- demdesign particle frames: open in ParaView with the Xdmf3 reader. Paths are relative to this file. -->\n"
         "<Xdmf Version=\"3.0\">\n"
         "  <Domain>\n"
         "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const FrameInfo& i : frames) {
    const std::size_t n = i.count;
    const std::string& h5 = i.file;
    out << fmt::format("      <Grid Name=\"{}\" GridType=\"Uniform\">\n", fs::path(h5).stem().string());
    out << fmt::format("        <Time Value=\"{}\"/>\n", i.time);
    out << fmt::format("        <Information Name=\"step\" Value=\"{}\"/>\n", i.step);
    out << fmt::format("        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{}\" NodesPerElement=\"1\">\n", n);
    out << "          " << data_item(h5, "connectivity", n, 1, "Int", 8) << "\n";
    out << "        </Topology>\n";
    out << "        <Geometry GeometryType=\"XYZ\">\n";
    out << "          " << data_item(h5, "position", n, 3, "Float", 8) << "\n";
    out << "        </Geometry>\n";
    struct Field {
      const char* name;
      const char* type;
      std::size_t width;
      const char* number_type;
      int precision;
    };
    static constexpr Field fields[] = {
        {"velocity", "Vector", 3, "Float", 8}, {"angular_velocity", "Vector", 3, "Float", 8},
        {"speed", "Scalar", 1, "Float", 8},    {"radius", "Scalar", 1, "Float", 8},
        {"material", "Scalar", 1, "Int", 4},   {"clump", "Scalar", 1, "Int", 4},
        {"id", "Scalar", 1, "Int", 8},
    };
    for (const Field& field : fields) {
      out << fmt::format("        <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"Node\">\n", field.name, field.type);
      out << "          " << data_item(h5, field.name, n, field.width, field.number_type, field.precision) << "\n";
      out << "        </Attribute>\n";
    }
    out << "      </Grid>\n";
  }
  out << "    </Grid>\n"
         "  </Domain>\n"
         "</Xdmf>\n";

  write_text_atomically(directory_, kXdmfName, out.str());
}

void FrameWriter::adopt_existing() {
  const fs::path path = fs::path(directory_) / kXdmfName;
  const std::string where = path.string();
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    frames_.clear();
    return;
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(fmt::format("cannot read {}", where));
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());

  // We only read back what write_xdmf writes: each Uniform grid's Time, step, Topology size and file.
  std::vector<FrameInfo> frames;
  try {
    if (text.find("CollectionType=\"Temporal\"") == std::string::npos) throw std::runtime_error("no temporal collection");
    for (std::size_t at = text.find("<Grid "); at != std::string::npos; at = text.find("<Grid ", at + 1)) {
      if (tag_attribute(text, at, "GridType") != "Uniform") continue;
      const std::size_t end = text.find("</Grid>", at);
      const std::size_t time = text.find("<Time ", at);
      const std::size_t step = text.find("<Information Name=\"step\"", at);
      const std::size_t topology = text.find("<Topology ", at);
      const std::size_t geometry = text.find("<Geometry ", at);
      if (end == std::string::npos || time > end || step > end || topology > end || geometry > end)
        throw std::runtime_error("an incomplete frame grid");
      const std::size_t item = text.find('>', text.find("<DataItem ", geometry)) + 1;
      const std::size_t colon = text.find(":/", item);
      if (colon == std::string::npos || colon > end) throw std::runtime_error("a geometry without an HDF5 path");
      frames.push_back({parse_number<double>(tag_attribute(text, time, "Value")),
                        parse_number<std::int64_t>(tag_attribute(text, step, "Value")), text.substr(item, colon - item),
                        parse_number<std::size_t>(tag_attribute(text, topology, "NumberOfElements"))});
    }
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("cannot adopt {}: {} (not written by dem::FrameWriter?)", where, e.what()));
  }
  frames_ = std::move(frames);
}

namespace {

template <typename T>
std::vector<T> read_dataset(hid_t file, const char* name, hid_t memory_type, size_t per_item, const std::string& path) {
  const hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
  if (set < 0) throw std::runtime_error(fmt::format("{}: no dataset '{}' (not a demdesign frame?)", path, name));
  const hid_t space = H5Dget_space(set);
  const hssize_t points = H5Sget_simple_extent_npoints(space);
  std::vector<T> out(static_cast<size_t>(std::max<hssize_t>(points, 0)));
  herr_t status = 0;
  if (!out.empty()) status = H5Dread(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
  H5Sclose(space);
  H5Dclose(set);
  if (status < 0 || out.size() % per_item != 0) throw std::runtime_error(fmt::format("{}: cannot read '{}'", path, name));
  return out;
}

double read_attribute(hid_t file, const char* name, hid_t type, const std::string& path) {
  double value = 0;
  std::int64_t integer = 0;
  const hid_t attribute = H5Aopen(file, name, H5P_DEFAULT);
  if (attribute < 0) throw std::runtime_error(fmt::format("{}: no attribute '{}'", path, name));
  const herr_t status = H5Aread(attribute, type, type == H5T_NATIVE_DOUBLE ? static_cast<void*>(&value) : static_cast<void*>(&integer));
  H5Aclose(attribute);
  if (status < 0) throw std::runtime_error(fmt::format("{}: cannot read attribute '{}'", path, name));
  return type == H5T_NATIVE_DOUBLE ? value : static_cast<double>(integer);
}

}  // namespace

StoredFrame read_frame(const std::string& path) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error(fmt::format("{}: cannot open the frame file", path));
  StoredFrame frame;
  try {
    frame.time = read_attribute(file, "time", H5T_NATIVE_DOUBLE, path);
    frame.step = static_cast<std::int64_t>(read_attribute(file, "step", H5T_NATIVE_INT64, path));
    frame.id = read_dataset<std::int64_t>(file, "id", H5T_NATIVE_INT64, 1, path);
    frame.position = read_dataset<double>(file, "position", H5T_NATIVE_DOUBLE, 3, path);
    frame.velocity = read_dataset<double>(file, "velocity", H5T_NATIVE_DOUBLE, 3, path);
    frame.radius = read_dataset<double>(file, "radius", H5T_NATIVE_DOUBLE, 1, path);
    frame.material = read_dataset<std::int32_t>(file, "material", H5T_NATIVE_INT32, 1, path);
  } catch (...) {
    H5Fclose(file);
    throw;
  }
  H5Fclose(file);
  return frame;
}

void write_paraview_script(const std::string& directory) {
  static const char* const kScript = R"PY(# Opens this run's results in ParaView, coloured as the run's report colours them: particles as
# spheres of their radius coloured by speed [m/s], walls by shear work rate [W/m^2] (abrasive wear),
# at the last saved time. Written by demdesign beside particles.xdmf.
#   ParaView: View > Python Shell > Run Script, then pick this file.
#   pvbatch open_in_paraview.py --png view.png    renders an image (without a display:
#   xvfb-run -a pvbatch ..., Debian's ParaView draws through X).
# The files are XDMF 3: ParaView's Xdmf3 readers (the "XDMF Reader" of the File > Open dialog is
# the older Xdmf2 reader and rejects a frame with no particles).
import os
import sys
from paraview.simple import *

here = os.path.dirname(os.path.abspath(__file__))
view = GetActiveViewOrCreate("RenderView")
particles = Xdmf3ReaderT(registrationName="particles", FileName=[os.path.join(here, "particles.xdmf")])
particles.UpdatePipelineInformation()
times = list(particles.TimestepValues or [0.0])
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = times[-1]
spheres = Glyph(registrationName="spheres", Input=particles, GlyphType="Sphere")
spheres.ScaleArray = ["POINTS", "radius"]
spheres.ScaleFactor = 2.0  # the glyph sphere has unit diameter
spheres.GlyphMode = "All Points"
shown = Show(spheres, view)
ColorBy(shown, ("POINTS", "speed"))
shown.RescaleTransferFunctionToDataRange(True, False)
shown.SetScalarBarVisibility(view, True)
speed_bar = GetScalarBar(GetColorTransferFunction("speed"), view)
speed_bar.Title = "particle speed [m/s]"
speed_bar.ComponentTitle = ""
speed_bar.WindowLocation = "Upper Right Corner"
speed_bar.TitleFontSize = 10
speed_bar.LabelFontSize = 9
if os.path.exists(os.path.join(here, "walls.xdmf")):
    walls = Xdmf3ReaderS(registrationName="walls", FileName=[os.path.join(here, "walls.xdmf")])
    wall_display = Show(walls, view)
    ColorBy(wall_display, ("CELLS", "shear_work_rate_W_per_m2"))
    wall_display.RescaleTransferFunctionToDataRange(True, False)
    wall_display.SetScalarBarVisibility(view, True)
    wall_display.Opacity = 0.6
    wall_bar = GetScalarBar(GetColorTransferFunction("shear_work_rate_W_per_m2"), view)
    wall_bar.Title = "wall shear work rate [W/m^2]"
    wall_bar.ComponentTitle = ""
    wall_bar.WindowLocation = "Upper Left Corner"
    wall_bar.TitleFontSize = 10
    wall_bar.LabelFontSize = 9
# An oblique view from the side (z is up), fitted to the data.
view.CameraPosition = [1.0, -1.6, 1.0]
view.CameraFocalPoint = [0.0, 0.0, 0.0]
view.CameraViewUp = [0.0, 0.0, 1.0]
view.ResetCamera()
Render(view)
if "--png" in sys.argv:
    SaveScreenshot(sys.argv[sys.argv.index("--png") + 1], view, ImageResolution=[1280, 720])
)PY";
  write_text_atomically(directory, "open_in_paraview.py", kScript);
}

}  // namespace dem
