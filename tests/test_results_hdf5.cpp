// Results writer: frames read back exactly through the HDF5 C API, the XDMF agrees with the HDF5 it
// points to (checked with tinyxml2, independently of the writer's own parser), and the atomic-write
// rules hold for crash leftovers, empty frames and unwritable directories.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <tinyxml2.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "output/results_hdf5.h"

namespace fs = std::filesystem;
using dem::FrameInfo;
using dem::FrameWriter;
using dem::ParticleFrame;

namespace {

// A small synthetic particle set whose columns change from frame to frame.
struct Columns {
  std::vector<std::int64_t> id;
  std::vector<double> x, y, z, vx, vy, vz, wx, wy, wz, radius, qw, qx, qy, qz;
  std::vector<std::int32_t> material, clump;

  Columns(std::size_t n, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t p = 0; p < n; ++p) {
      id.push_back(1000 + 7 * static_cast<std::int64_t>(p));
      for (auto* c : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz}) c->push_back(u(rng));
      radius.push_back(0.001 + 0.0005 * (u(rng) + 1.0));
      material.push_back(static_cast<std::int32_t>(p % 2));
      clump.push_back(p < 2 ? 0 : -1);
      double q[4] = {u(rng), u(rng), u(rng), u(rng)};
      const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      qw.push_back(q[0] / norm);
      qx.push_back(q[1] / norm);
      qy.push_back(q[2] / norm);
      qz.push_back(q[3] / norm);
    }
  }

  ParticleFrame frame(double time, std::int64_t step, bool with_body_columns) const {
    ParticleFrame f{};
    f.time = time;
    f.step = step;
    f.count = id.size();
    f.id = id.data();
    f.x = x.data(), f.y = y.data(), f.z = z.data();
    f.vx = vx.data(), f.vy = vy.data(), f.vz = vz.data();
    f.wx = wx.data(), f.wy = wy.data(), f.wz = wz.data();
    f.radius = radius.data();
    f.material = material.data();
    if (with_body_columns) {
      f.clump = clump.data();
      f.qw = qw.data(), f.qx = qx.data(), f.qy = qy.data(), f.qz = qz.data();
    }
    return f;
  }
};

// ---- HDF5 reading helpers (C API, independent of the writer) ----

struct Dataset {
  bool exists = false;
  std::vector<hsize_t> dims;
  H5T_class_t type_class = H5T_NO_CLASS;
  std::size_t type_size = 0;
  bool is_signed = false;
};

Dataset inspect(const fs::path& file_path, const std::string& name) {
  Dataset d;
  const hid_t file = H5Fopen(file_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return d;
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0) {
    const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(set);
    d.dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
    H5Sget_simple_extent_dims(space, d.dims.data(), nullptr);
    const hid_t type = H5Dget_type(set);
    d.type_class = H5Tget_class(type);
    d.type_size = H5Tget_size(type);
    d.is_signed = d.type_class == H5T_INTEGER && H5Tget_sign(type) == H5T_SGN_2;
    d.exists = true;
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(set);
  }
  H5Fclose(file);
  return d;
}

template <typename T>
std::vector<T> read_dataset(const fs::path& file_path, const char* name, hid_t memory_type, std::vector<hsize_t>* dims) {
  const Dataset d = inspect(file_path, name);
  EXPECT_TRUE(d.exists) << file_path << ":/" << name;
  if (dims) *dims = d.dims;
  std::size_t size = 1;
  for (hsize_t n : d.dims) size *= static_cast<std::size_t>(n);
  std::vector<T> values(size);
  if (!d.exists || size == 0) return values;
  const hid_t file = H5Fopen(file_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
  EXPECT_GE(H5Dread(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  H5Dclose(set);
  H5Fclose(file);
  return values;
}

std::string read_string_attribute(const fs::path& file_path, const char* name) {
  const hid_t file = H5Fopen(file_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0 || H5Aexists(file, name) <= 0) {
    if (file >= 0) H5Fclose(file);
    ADD_FAILURE() << "no attribute " << name << " in " << file_path;
    return {};
  }
  const hid_t attribute = H5Aopen(file, name, H5P_DEFAULT);
  const hid_t type = H5Aget_type(attribute);
  EXPECT_EQ(H5Tget_class(type), H5T_STRING);
  std::string buffer(H5Tget_size(type), '\0');
  EXPECT_GE(H5Aread(attribute, type, buffer.data()), 0);
  H5Tclose(type);
  H5Aclose(attribute);
  H5Fclose(file);
  return buffer.c_str();
}

template <typename T>
T read_scalar_attribute(const fs::path& file_path, const char* name, hid_t memory_type) {
  T value{};
  const hid_t file = H5Fopen(file_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t attribute = H5Aopen(file, name, H5P_DEFAULT);
  EXPECT_GE(attribute, 0) << name;
  EXPECT_GE(H5Aread(attribute, memory_type, &value), 0);
  H5Aclose(attribute);
  H5Fclose(file);
  return value;
}

// Every dataset and attribute of one frame file equals the columns it was written from.
void expect_frame_file(const fs::path& path, const Columns& c, double time, std::int64_t step, bool with_body_columns) {
  SCOPED_TRACE(path.string());
  const std::size_t n = c.id.size();
  std::vector<hsize_t> dims;

  const auto id = read_dataset<std::int64_t>(path, "id", H5T_NATIVE_INT64, &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n}));
  EXPECT_EQ(id, c.id);

  const auto expect_vec3 = [&](const char* name, const std::vector<double>& a, const std::vector<double>& b,
                               const std::vector<double>& d) {
    const auto v = read_dataset<double>(path, name, H5T_NATIVE_DOUBLE, &dims);
    EXPECT_EQ(dims, (std::vector<hsize_t>{n, 3})) << name;
    for (std::size_t p = 0; p < n; ++p) {
      EXPECT_EQ(v[3 * p], a[p]) << name << " " << p;
      EXPECT_EQ(v[3 * p + 1], b[p]) << name << " " << p;
      EXPECT_EQ(v[3 * p + 2], d[p]) << name << " " << p;
    }
  };
  expect_vec3("position", c.x, c.y, c.z);
  expect_vec3("velocity", c.vx, c.vy, c.vz);
  expect_vec3("angular_velocity", c.wx, c.wy, c.wz);

  EXPECT_EQ(read_dataset<double>(path, "radius", H5T_NATIVE_DOUBLE, &dims), c.radius);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n}));
  EXPECT_EQ(read_dataset<std::int32_t>(path, "material", H5T_NATIVE_INT32, &dims), c.material);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n}));

  const auto clump = read_dataset<std::int32_t>(path, "clump", H5T_NATIVE_INT32, &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n}));
  EXPECT_EQ(clump, with_body_columns ? c.clump : std::vector<std::int32_t>(n, -1));

  const auto q = read_dataset<double>(path, "orientation", H5T_NATIVE_DOUBLE, &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n, 4}));
  for (std::size_t p = 0; p < n; ++p) {
    const double want[4] = {with_body_columns ? c.qw[p] : 1.0, with_body_columns ? c.qx[p] : 0.0,
                            with_body_columns ? c.qy[p] : 0.0, with_body_columns ? c.qz[p] : 0.0};
    for (int k = 0; k < 4; ++k) EXPECT_EQ(q[4 * p + k], want[k]) << "orientation " << p << " " << k;
  }

  const auto speed = read_dataset<double>(path, "speed", H5T_NATIVE_DOUBLE, &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n}));
  for (std::size_t p = 0; p < n; ++p)
    EXPECT_EQ(speed[p], std::sqrt(c.vx[p] * c.vx[p] + c.vy[p] * c.vy[p] + c.vz[p] * c.vz[p])) << p;

  const auto connectivity = read_dataset<std::int64_t>(path, "connectivity", H5T_NATIVE_INT64, &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{n}));
  for (std::size_t p = 0; p < n; ++p) EXPECT_EQ(connectivity[p], static_cast<std::int64_t>(p));

  EXPECT_EQ(read_scalar_attribute<double>(path, "time", H5T_NATIVE_DOUBLE), time);
  EXPECT_EQ(read_scalar_attribute<std::int64_t>(path, "step", H5T_NATIVE_INT64), step);
  EXPECT_EQ(read_string_attribute(path, "units"), "SI");
  EXPECT_EQ(read_string_attribute(path, "material_names"), "glass beads,limestone");
  EXPECT_EQ(read_string_attribute(path, "software_version"), "demdesign 0.1.0");
  EXPECT_EQ(read_string_attribute(path, "length_scale"), "1.0");
  EXPECT_EQ(read_string_attribute(path, "empty_note"), "");
}

// ---- XDMF validation with tinyxml2 against the HDF5 it points to ----

std::vector<hsize_t> parse_dimensions(const char* text) {
  std::vector<hsize_t> dims;
  std::istringstream in(text ? text : "");
  for (hsize_t d; in >> d;) dims.push_back(d);
  return dims;
}

// One DataItem: relative `file.h5:/dataset` that exists, with the declared dimensions and number type.
void expect_data_item_matches_hdf5(const fs::path& dir, const tinyxml2::XMLElement* item) {
  ASSERT_NE(item, nullptr);
  ASSERT_NE(item->GetText(), nullptr);
  std::string text = item->GetText();
  text.erase(0, text.find_first_not_of(" \t\r\n"));
  text.erase(text.find_last_not_of(" \t\r\n") + 1);
  SCOPED_TRACE(text);
  EXPECT_STREQ(item->Attribute("Format"), "HDF");
  const std::size_t colon = text.find(":/");
  ASSERT_NE(colon, std::string::npos);
  const fs::path file = text.substr(0, colon);
  EXPECT_TRUE(file.is_relative());
  const Dataset d = inspect(dir / file, text.substr(colon + 1));
  ASSERT_TRUE(d.exists);
  EXPECT_EQ(parse_dimensions(item->Attribute("Dimensions")), d.dims);
  const std::string number_type = item->Attribute("NumberType") ? item->Attribute("NumberType") : "Float";
  if (number_type == "Float") {
    EXPECT_EQ(d.type_class, H5T_FLOAT);
  } else {
    EXPECT_EQ(number_type, "Int");
    EXPECT_EQ(d.type_class, H5T_INTEGER);
    EXPECT_TRUE(d.is_signed);
  }
  EXPECT_EQ(item->UnsignedAttribute("Precision", 4), d.type_size);
}

void for_each_element(const tinyxml2::XMLElement* e, const std::function<void(const tinyxml2::XMLElement*)>& visit) {
  for (; e; e = e->NextSiblingElement()) {
    visit(e);
    for_each_element(e->FirstChildElement(), visit);
  }
}

// The whole XDMF: a temporal collection listing exactly `expected`, every DataItem backed by the HDF5.
void expect_xdmf(const fs::path& dir, const std::vector<FrameInfo>& expected) {
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.LoadFile((dir / "particles.xdmf").c_str()), tinyxml2::XML_SUCCESS) << doc.ErrorStr();
  const auto* xdmf = doc.FirstChildElement("Xdmf");
  ASSERT_NE(xdmf, nullptr);
  EXPECT_STREQ(xdmf->Attribute("Version"), "3.0");
  const auto* domain = xdmf->FirstChildElement("Domain");
  ASSERT_NE(domain, nullptr);
  const auto* collection = domain->FirstChildElement("Grid");
  ASSERT_NE(collection, nullptr);
  EXPECT_STREQ(collection->Attribute("GridType"), "Collection");
  EXPECT_STREQ(collection->Attribute("CollectionType"), "Temporal");

  std::size_t k = 0;
  for (const auto* grid = collection->FirstChildElement("Grid"); grid; grid = grid->NextSiblingElement("Grid"), ++k) {
    ASSERT_LT(k, expected.size());
    const FrameInfo& want = expected[k];
    SCOPED_TRACE(want.file);
    const std::size_t n = want.count;
    EXPECT_STREQ(grid->Attribute("GridType"), "Uniform");
    const auto* time = grid->FirstChildElement("Time");
    ASSERT_NE(time, nullptr);
    EXPECT_EQ(time->DoubleAttribute("Value", -1), want.time);

    const auto* topology = grid->FirstChildElement("Topology");
    ASSERT_NE(topology, nullptr);
    EXPECT_STREQ(topology->Attribute("TopologyType"), "Polyvertex");
    EXPECT_EQ(topology->Unsigned64Attribute("NumberOfElements", 99999), n);
    const auto* cells = topology->FirstChildElement("DataItem");
    ASSERT_NE(cells, nullptr);
    EXPECT_EQ(parse_dimensions(cells->Attribute("Dimensions")), (std::vector<hsize_t>{n}));

    const auto* geometry = grid->FirstChildElement("Geometry");
    ASSERT_NE(geometry, nullptr);
    EXPECT_STREQ(geometry->Attribute("GeometryType"), "XYZ");
    const auto* points = geometry->FirstChildElement("DataItem");
    ASSERT_NE(points, nullptr);
    EXPECT_EQ(parse_dimensions(points->Attribute("Dimensions")), (std::vector<hsize_t>{n, 3}));
    EXPECT_EQ(std::string(points->GetText()), want.file + ":/position");

    std::set<std::string> names;
    for (const auto* a = grid->FirstChildElement("Attribute"); a; a = a->NextSiblingElement("Attribute")) {
      const std::string name = a->Attribute("Name");
      names.insert(name);
      EXPECT_STREQ(a->Attribute("Center"), "Node") << name;
      const auto dims = parse_dimensions(a->FirstChildElement("DataItem")->Attribute("Dimensions"));
      if (std::string(a->Attribute("AttributeType")) == "Vector")
        EXPECT_EQ(dims, (std::vector<hsize_t>{n, 3})) << name;
      else
        EXPECT_EQ(dims, (std::vector<hsize_t>{n})) << name;
    }
    EXPECT_EQ(names, (std::set<std::string>{"velocity", "angular_velocity", "speed", "radius", "material", "clump", "id"}));
  }
  EXPECT_EQ(k, expected.size());

  // Every DataItem anywhere in the document is backed by the HDF5 it names.
  std::size_t items = 0;
  for_each_element(xdmf, [&](const tinyxml2::XMLElement* e) {
    if (std::string(e->Name()) != "DataItem") return;
    ++items;
    expect_data_item_matches_hdf5(dir, e);
  });
  EXPECT_EQ(items, expected.size() * 9);
}

// ---- fixture ----

class ResultsHdf5 : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("demdesign_results_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  FrameWriter writer() const {
    return FrameWriter((dir_ / "out").string(), {"glass beads", "limestone"},
                       {{"software_version", "demdesign 0.1.0"}, {"length_scale", "1.0"}, {"empty_note", ""}});
  }

  fs::path out() const { return dir_ / "out"; }

  fs::path dir_;
};

// Frame times that need all 17 significant digits, so any rounding of Time in the XDMF shows.
constexpr double kT1 = 1e-3 / 3;
constexpr double kT2 = 0.1 + 0.2;

// Three frames: the first without clump or orientation columns (defaults), the others with them.
struct ThreeFrames {
  Columns c0{5, 1}, c1{5, 2}, c2{5, 3};
  void write(FrameWriter& w) const {
    w.write_frame(c0.frame(0.0, 0, false));
    w.write_frame(c1.frame(kT1, 100, true));
    w.write_frame(c2.frame(kT2, 210, true));
  }
};

TEST_F(ResultsHdf5, FramesReadBackExactly) {
  FrameWriter w = writer();
  const ThreeFrames f;
  f.write(w);

  ASSERT_EQ(w.frames().size(), 3u);
  EXPECT_EQ(w.frames()[0].file, "frames/frame_000000.h5");
  EXPECT_EQ(w.frames()[1].file, "frames/frame_000100.h5");
  EXPECT_EQ(w.frames()[2].file, "frames/frame_000210.h5");
  expect_frame_file(out() / "frames/frame_000000.h5", f.c0, 0.0, 0, false);
  expect_frame_file(out() / "frames/frame_000100.h5", f.c1, kT1, 100, true);
  expect_frame_file(out() / "frames/frame_000210.h5", f.c2, kT2, 210, true);
  // No temporary file survives a successful write.
  for (const auto& entry : fs::recursive_directory_iterator(out())) {
    EXPECT_NE(entry.path().extension(), ".part") << entry.path();
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
  }
}

TEST_F(ResultsHdf5, XdmfMatchesTheHdf5ItPointsTo) {
  FrameWriter w = writer();
  const ThreeFrames f;
  f.write(w);
  expect_xdmf(out(), w.frames());
  EXPECT_EQ(w.frames()[1].time, kT1);
  EXPECT_EQ(w.frames()[2].count, 5u);
}

TEST_F(ResultsHdf5, CrashLeftoversAreNotListedAndDoNotBreakLaterWrites) {
  FrameWriter w = writer();
  const ThreeFrames f;
  w.write_frame(f.c0.frame(0.0, 0, false));
  w.write_frame(f.c1.frame(kT1, 100, true));

  // A crash mid-write of step 210 left a half-written frame, and one of a step never reached again,
  // plus a half-written XDMF temporary.
  for (const char* leftover : {"frames/frame_000210.h5.part", "frames/frame_000999.h5.part", "particles.xdmf.tmp"}) {
    std::ofstream(out() / leftover) << "\x89HDF garbage from a killed process";
  }
  expect_xdmf(out(), w.frames());  // earlier frames still listed and readable

  // A resumed writer adopts the listing and writes over the leftover.
  FrameWriter resumed = writer();
  resumed.adopt_existing();
  ASSERT_EQ(resumed.frames().size(), 2u);
  resumed.write_frame(f.c2.frame(kT2, 210, true));
  EXPECT_FALSE(fs::exists(out() / "frames/frame_000210.h5.part"));
  EXPECT_FALSE(fs::exists(out() / "particles.xdmf.tmp"));
  expect_frame_file(out() / "frames/frame_000210.h5", f.c2, kT2, 210, true);
  ASSERT_EQ(resumed.frames().size(), 3u);
  expect_xdmf(out(), resumed.frames());

  std::ifstream in(out() / "particles.xdmf");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find(".part"), std::string::npos);
  EXPECT_EQ(text.find("999"), std::string::npos);
}

TEST_F(ResultsHdf5, AdoptExistingRestoresTheListAndARewindDropsLaterFrames) {
  const ThreeFrames f;
  {
    FrameWriter w = writer();
    f.write(w);
  }
  FrameWriter resumed = writer();
  resumed.adopt_existing();
  ASSERT_EQ(resumed.frames().size(), 3u);
  EXPECT_EQ(resumed.frames()[2].step, 210);
  EXPECT_EQ(resumed.frames()[2].time, kT2);
  EXPECT_EQ(resumed.frames()[2].file, "frames/frame_000210.h5");
  EXPECT_EQ(resumed.frames()[2].count, 5u);

  // Restarted from step 100: the frame at 100 is rewritten and 210 is no longer part of this history.
  const Columns again(4, 9);
  resumed.write_frame(again.frame(kT1, 100, true));
  ASSERT_EQ(resumed.frames().size(), 2u);
  EXPECT_EQ(resumed.frames()[1].count, 4u);
  expect_frame_file(out() / "frames/frame_000100.h5", again, kT1, 100, true);
  expect_xdmf(out(), resumed.frames());

  // Nothing to adopt in a fresh directory.
  FrameWriter fresh((dir_ / "fresh").string(), {}, {});
  fresh.adopt_existing();
  EXPECT_TRUE(fresh.frames().empty());

  // A file that is not ours is refused with its path.
  std::ofstream(dir_ / "particles.xdmf") << "<Xdmf/>";
  FrameWriter foreign(dir_.string(), {}, {});
  try {
    foreign.adopt_existing();
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "particles.xdmf").string()), std::string::npos) << e.what();
  }
}

TEST_F(ResultsHdf5, EmptyFrameKeepsFilesAndXdmfValid) {
  FrameWriter w = writer();
  const Columns c(3, 4);
  w.write_frame(c.frame(0.5, 5000, true));
  // All particles left: every column may be null when count is 0.
  ParticleFrame empty{};
  empty.time = 0.75;
  empty.step = 7500;
  w.write_frame(empty);
  const Columns none(0, 5);
  w.write_frame(none.frame(1.0, 10000, true));

  ASSERT_EQ(w.frames().size(), 3u);
  EXPECT_EQ(w.frames()[1].count, 0u);
  expect_frame_file(out() / "frames/frame_007500.h5", none, 0.75, 7500, false);
  expect_frame_file(out() / "frames/frame_010000.h5", none, 1.0, 10000, true);
  expect_xdmf(out(), w.frames());
}

TEST_F(ResultsHdf5, UnwritableDirectoryThrowsWithThePath) {
  // A directory below a regular file cannot exist, even for root.
  std::ofstream(dir_ / "not_a_directory") << "x";
  const fs::path target = dir_ / "not_a_directory" / "out";
  FrameWriter w(target.string(), {"a"}, {});
  const Columns c(2, 6);
  try {
    w.write_frame(c.frame(0.0, 0, false));
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(w.frames().empty());
}

TEST_F(ResultsHdf5, HdfFailureThrowsWithThePathAndLeavesNoPartFile) {
  // The frame file name is taken by a directory, so the rename onto it fails after a complete write.
  fs::create_directories(out() / "frames/frame_000000.h5/blocker");
  FrameWriter w = writer();
  const Columns c(2, 7);
  try {
    w.write_frame(c.frame(0.0, 0, false));
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((out() / "frames/frame_000000.h5").string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(w.frames().empty());
  EXPECT_FALSE(fs::exists(out() / "frames/frame_000000.h5.part"));
  EXPECT_FALSE(fs::exists(out() / "particles.xdmf"));

  // A .part name taken by a directory makes H5Fcreate itself fail; the error names the file.
  fs::create_directories(out() / "frames/frame_000001.h5.part/blocker");
  try {
    w.write_frame(c.frame(1.0, 1, false));
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((out() / "frames/frame_000001.h5.part").string()), std::string::npos) << e.what();
  }
  // The writer keeps working afterwards.
  w.write_frame(c.frame(2.0, 2, false));
  ASSERT_EQ(w.frames().size(), 1u);
  expect_xdmf(out(), w.frames());
}

TEST_F(ResultsHdf5, InvalidArgumentsAreRefused) {
  EXPECT_THROW(FrameWriter(dir_.string(), {"sand, wet"}, {}), std::invalid_argument);
  EXPECT_THROW(FrameWriter(dir_.string(), {}, {{"time", "1"}}), std::invalid_argument);
  EXPECT_THROW(FrameWriter(dir_.string(), {}, {{"a", "1"}, {"a", "2"}}), std::invalid_argument);
  FrameWriter w = writer();
  const Columns c(2, 8);
  ParticleFrame missing = c.frame(0.0, 0, false);
  missing.radius = nullptr;
  EXPECT_THROW(w.write_frame(missing), std::invalid_argument);
  ParticleFrame partial = c.frame(0.0, 0, true);
  partial.qz = nullptr;
  EXPECT_THROW(w.write_frame(partial), std::invalid_argument);
  EXPECT_FALSE(fs::exists(out()));
}

}  // namespace
