// ParaView opens the results: a short run of a case with a mesh wall and an inlet is read with
// ParaView's own Python (pvpython, the Xdmf3 readers) and every time step, point count and point
// array range is checked against the HDF5 frames; the walls' cells against walls.h5; then
// `pvbatch open_in_paraview.py --png` (the script every run writes) renders an image.
// Skipped, with a message, when ParaView is not installed (Debian `paraview`, rendering in a
// virtual X display from Debian `xvfb`; .ci/install-deps installs both).
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "output/results_hdf5.h"

namespace dem {
namespace {

namespace fs = std::filesystem;

/// Runs a shell command; returns its exit status and puts its output in `out`.
int run(const std::string& command, std::string& out) {
  out.clear();
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
  return ::pclose(pipe);
}

bool on_path(const std::string& program) {
  std::string out;
  return run("command -v " + program, out) == 0;
}

const char* kCheck = R"PY(
import sys
from paraview.simple import *
here = sys.argv[1]
p = Xdmf3ReaderT(FileName=[here + "/particles.xdmf"])
p.UpdatePipelineInformation()
for t in p.TimestepValues:
    p.UpdatePipeline(t)
    info = p.GetDataInformation()
    print("frame %.17g %d %d" % (t, info.GetNumberOfPoints(), info.GetNumberOfCells()))
    for a in p.PointData:
        lo, hi = a.GetRange()
        print("point %.17g %s %.17g %.17g" % (t, a.Name, lo, hi))
w = Xdmf3ReaderS(FileName=[here + "/walls.xdmf"])
w.UpdatePipeline()
wi = w.GetDataInformation()
print("walls %d" % wi.GetNumberOfCells())
for a in w.CellData:
    lo, hi = a.GetRange()
    print("cell %s %.17g %.17g" % (a.Name, lo, hi))
)PY";

/// Triangles over every mesh group of walls.h5.
long wall_triangles(const std::string& path) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return -1;
  H5G_info_t info{};
  H5Gget_info(file, &info);
  long total = 0;
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    char name[256] = {};
    H5Lget_name_by_idx(file, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT);
    const hid_t set = H5Dopen2(file, (std::string(name) + "/triangles").c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(set);
    hsize_t dims[2] = {};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    total += static_cast<long>(dims[0]);
    H5Sclose(space);
    H5Dclose(set);
  }
  H5Fclose(file);
  return total;
}

TEST(ParaView, OpensTheResultsAndRendersTheRunsScript) {
  if (!on_path("pvpython") || !on_path("pvbatch")) GTEST_SKIP() << "ParaView (pvpython, pvbatch) is not installed: Debian package paraview";
  const fs::path out = fs::temp_directory_path() / "demdesign_paraview_test";
  fs::remove_all(out);
  std::string log;
  // The hopper and drum: a mesh wall, particles fed by an inlet (the first frame holds none).
  ASSERT_EQ(run(std::string(DEMDESIGN_BINARY) + " " + DEMDESIGN_SOURCE_DIR + "/cases/hopper_drum.yaml --max-steps 4000 --no-report --quiet --out " +
                    out.string(),
                log),
            0)
      << log;
  ASSERT_TRUE(fs::exists(out / "open_in_paraview.py"));
  std::ofstream(out / "check.py") << kCheck;
  ASSERT_EQ(run("pvpython --force-offscreen-rendering " + (out / "check.py").string() + " " + out.string(), log), 0) << log;
  std::printf("%s", log.c_str());

  // What ParaView read, against the HDF5 frames the XDMF lists.
  std::map<double, std::pair<long, long>> frames;                // time -> points, cells
  std::map<std::pair<double, std::string>, std::pair<double, double>> ranges;  // (time, array) -> range
  std::map<std::string, std::pair<double, double>> cells;
  long wall_cells = -1;
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream in(line);
    std::string kind;
    in >> kind;
    if (kind == "frame") {
      double t;
      long points, n;
      in >> t >> points >> n;
      frames[t] = {points, n};
    } else if (kind == "point") {
      double t, lo, hi;
      std::string name;
      in >> t >> name >> lo >> hi;
      ranges[{t, name}] = {lo, hi};
    } else if (kind == "walls") {
      in >> wall_cells;
    } else if (kind == "cell") {
      std::string name;
      double lo, hi;
      in >> name >> lo >> hi;
      cells[name] = {lo, hi};
    }
  }
  std::vector<StoredFrame> stored;
  for (const auto& entry : fs::directory_iterator(out / "frames"))
    if (entry.path().extension() == ".h5") stored.push_back(read_frame(entry.path().string()));
  ASSERT_GE(stored.size(), 2u);
  ASSERT_EQ(frames.size(), stored.size()) << "every frame file is a time step in ParaView";
  for (const StoredFrame& f : stored) {
    const auto it = std::find_if(frames.begin(), frames.end(), [&](const auto& kv) { return std::abs(kv.first - f.time) <= 1e-12 * std::max(1.0, f.time); });
    ASSERT_NE(it, frames.end()) << "time " << f.time << " is not a ParaView time step";
    EXPECT_EQ(it->second.first, static_cast<long>(f.size())) << "points at t = " << f.time;
    EXPECT_EQ(it->second.second, static_cast<long>(f.size())) << "one vertex cell per particle at t = " << f.time;
    if (f.size() == 0) continue;
    double r_lo = 1e300, r_hi = -1e300, v_lo = 1e300, v_hi = -1e300;
    for (size_t k = 0; k < f.size(); ++k) {
      r_lo = std::min(r_lo, f.radius[k]), r_hi = std::max(r_hi, f.radius[k]);
      const double v = std::hypot(f.velocity[3 * k], f.velocity[3 * k + 1], f.velocity[3 * k + 2]);
      v_lo = std::min(v_lo, v), v_hi = std::max(v_hi, v);
    }
    const auto radius = ranges.find({it->first, "radius"}), speed = ranges.find({it->first, "speed"});
    ASSERT_NE(radius, ranges.end());
    ASSERT_NE(speed, ranges.end());
    EXPECT_NEAR(radius->second.first, r_lo, 1e-12);
    EXPECT_NEAR(radius->second.second, r_hi, 1e-12);
    EXPECT_NEAR(speed->second.first, v_lo, 1e-9 * std::max(1.0, v_hi));
    EXPECT_NEAR(speed->second.second, v_hi, 1e-9 * std::max(1.0, v_hi));
    for (const char* name : {"velocity", "angular_velocity", "id", "material", "clump"})
      EXPECT_TRUE(ranges.count({it->first, name})) << name << " at t = " << f.time;
  }
  EXPECT_EQ(wall_cells, wall_triangles((out / "walls.h5").string()));
  for (const char* name : {"shear_work_rate_W_per_m2", "impact_energy_rate_W_per_m2", "mean_pressure_Pa"}) {
    ASSERT_TRUE(cells.count(name)) << name;
    EXPECT_GE(cells[name].first, 0.0) << name;
  }

  // The run's own script renders the view.
  const fs::path png = out / "paraview.png";
  // Debian's ParaView renders through X: without a display, in a virtual one (Debian xvfb). The
  // server picks a free display and writes its number once it accepts connections (-displayfd).
  // Under ctest -j2 pvbatch was once refused by a server that had just written its number ("bad X
  // server connection"): the render is tried up to three times, a second apart.
  const std::string render = "pvbatch open_in_paraview.py --png " + png.string();
  const std::string command =
      std::getenv("DISPLAY") || !on_path("Xvfb")
          ? "cd " + out.string() + " && " + render
          : "cd " + out.string() + " && rm -f display.txt && (Xvfb -displayfd 3 -nolisten tcp -screen 0 1280x1024x24 3>display.txt >/dev/null 2>&1 & "
            "echo $! > xvfb.pid) && for i in $(seq 300); do [ -s display.txt ] && break; sleep 0.1; done && "
            "for try in 1 2 3; do DISPLAY=:$(cat display.txt) " + render + "; status=$?; [ $status -eq 0 ] && break; sleep 1; done; "
            "kill $(cat xvfb.pid); exit $status";
  ASSERT_EQ(run(command, log), 0) << log;
  ASSERT_TRUE(fs::exists(png)) << log;
  EXPECT_GT(fs::file_size(png), 20000u) << "a 1280 x 720 view of particles and walls";
  std::printf("rendered %s (%ju bytes)\n", png.c_str(), static_cast<std::uintmax_t>(fs::file_size(png)));
}

}  // namespace
}  // namespace dem
