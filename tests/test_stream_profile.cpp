// Stream profiles and the chute's choke: a box sensor with bins gives each lateral bin's time-mean
// mass and velocity along the flow over the records window (spheres at rest in one half of a box:
// the placed mass shared by the filled bins, the others empty; free spheres moving uniformly: their
// velocity in every bin), each row held for its interval from records_from on, kept by a
// checkpoint; the choke fill from a known mass by hand; the transfer chute's narrowest section
// (the shipped chute's is its width times the spoon's setback, and its sensor box lies inside the
// walls; the right-angle chute's is the deck's opening); and bins refused where they do not
// belong, naming file, line, key and what is valid.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "equipment.h"
#include "output/checkpoint.h"
#include "output/run.h"
#include "report/choke.h"
#include "statistics/stream_profile.h"

namespace dem {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
/// [kg] A 10 mm sphere of 2500 kg/m^3.
constexpr double kSphere = 2500 * kPi / 6 * 0.01 * 0.01 * 0.01;

/// A box sensor 0.2 x 0.4 x 0.1 m about the origin with 4 bins of 0.1 m across y, no gravity,
/// 10 mm spheres at `positions` moving at `velocity`; a row every 20 steps of 10 us, records
/// from 0.5 ms to the end at 2 ms (a window of 1.5 ms).
std::string binned_box_case(const std::string& positions, const std::string& velocity) {
  return "simulation: {duration: 0.002, time_step: 1.0e-5, gravity: [0, 0, 0]}\n"
         "materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.5, friction: 0.5}}\n"
         "contact: {normal: hertz, damping: restitution, tangential: mindlin}\n"
         "particles:\n  - {material: beads, diameter: 0.01, velocity: " + velocity + ", positions: " + positions + "}\n"
         "sensors:\n  - {name: profile, box: {min: [-0.1, -0.2, -0.05], max: [0.1, 0.2, 0.05], across: [0, 1, 0], bins: 4}}\n"
         "output: {scalars_every: 20, records_from: 0.0005}\n";
}

/// A compiled case run to its end, writing into a fresh folder under the temporary directory.
struct Ran {
  Model model;
  State state;
  RunSummary summary;
};

Ran run_case(const std::string& text, const std::string& folder) {
  Ran r{compile(parse_case_text(text, "profile.yaml")), {}, {}};
  r.state = initial_state(r.model);
  const fs::path out = fs::temp_directory_path() / folder;
  fs::remove_all(out);
  Workspace work;
  RunOptions options;
  options.output_directory = out.string();
  options.progress = false;
  std::ostringstream log;
  r.summary = run(r.model, r.state, work, options, log);
  return r;
}

std::vector<std::string> lines_of(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Three spheres at rest in each of the two bins at y < 0, 50 mm apart (no contact), and one
// outside the box: each filled bin holds half the placed mass, to rounding, the others nothing.
TEST(StreamProfile, SpheresAtRestInOneHalfShareThePlacedMassOverTheFilledBins) {
  const std::string positions = "[[-0.05, -0.15, 0], [0, -0.15, 0], [0.05, -0.15, 0], [-0.05, -0.05, 0], [0, -0.05, 0], [0.05, -0.05, 0], "
                                "[0.5, 0.15, 0]]";
  const Ran r = run_case(binned_box_case(positions, "[0, 0, 0]"), "demdesign_stream_profile_rest");
  ASSERT_TRUE(r.summary.stopped.empty()) << r.summary.stopped;
  const double placed = 6 * kSphere, per_bin = placed / 2;  // [kg]
  const std::vector<StreamProfileRow> rows = stream_profile_rows(r.model, r.state.stream_profiles);
  ASSERT_EQ(rows.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    const StreamProfileRow& row = rows[static_cast<size_t>(k)];
    EXPECT_EQ(row.sensor, "profile");
    EXPECT_EQ(row.bin, k);
    EXPECT_NEAR(row.lateral, -0.15 + 0.1 * k, 1e-12);
    EXPECT_NEAR(row.width, 0.1, 1e-12);
    EXPECT_NEAR(row.length, 0.2, 1e-12);  // along the default flow direction, [1, 0, 0] for across [0, 1, 0]
    EXPECT_NEAR(row.window, 0.0015, 1e-9);
    if (k < 2) EXPECT_NEAR(row.mass, per_bin, 1e-9 * per_bin);
    else EXPECT_EQ(row.mass, 0.0);
    EXPECT_EQ(row.velocity, 0.0);
  }
  // The end state's bins hold the box's mass, the sphere outside left out; the rows the run keeps
  // hold no bins (the profiles do).
  Workspace work;
  const SensorReading now = measure(r.model, r.state, work).sensors.at(0);
  ASSERT_EQ(now.bin_mass.size(), 4u);
  EXPECT_NEAR(now.bin_mass[0] + now.bin_mass[1] + now.bin_mass[2] + now.bin_mass[3], now.mass, 1e-15);
  EXPECT_NEAR(now.mass, placed, 1e-9 * placed);
  EXPECT_TRUE(r.summary.scalars.back().sensors.at(0).bin_mass.empty());
  // stream_profiles.csv: a header and a line a bin.
  const std::vector<std::string> csv = lines_of(fs::temp_directory_path() / "demdesign_stream_profile_rest" / "stream_profiles.csv");
  ASSERT_EQ(csv.size(), 5u);
  EXPECT_EQ(csv[0], "sensor,bin,lateral_m,bin_width_m,length_along_m,mean_mass_kg,mean_velocity_m_s,window_s");
  EXPECT_EQ(csv[1].rfind("profile,0,-0.15,0.1,0.2,", 0), 0u) << csv[1];
  EXPECT_EQ(csv[4].rfind("profile,3,0.15,0.1,0.2,0,0,", 0), 0u) << csv[4];
}

// Free spheres, one in each bin, all moving at [0.5, 0, 0.2] m/s without gravity: every bin's
// velocity along the flow [1, 0, 0] is 0.5 m/s, to rounding, and its mass one sphere's.
TEST(StreamProfile, AUniformVelocityIsEveryBinsVelocityAlongTheFlow) {
  const Ran r = run_case(binned_box_case("[[0, -0.15, 0], [0, -0.05, 0], [0, 0.05, 0], [0, 0.15, 0]]", "[0.5, 0, 0.2]"),
                         "demdesign_stream_profile_moving");
  ASSERT_TRUE(r.summary.stopped.empty()) << r.summary.stopped;
  EXPECT_EQ(r.model.sensors[0].along, Vec3(1, 0, 0));
  const std::vector<StreamProfileRow> rows = stream_profile_rows(r.model, r.state.stream_profiles);
  ASSERT_EQ(rows.size(), 4u);
  for (const StreamProfileRow& row : rows) {
    SCOPED_TRACE(row.bin);
    EXPECT_NEAR(row.velocity, 0.5, 1e-12);
    EXPECT_NEAR(row.mass, kSphere, 1e-9 * kSphere);
  }
}

// Each row's reading holds for the time since the row before, counted from records_from: rows at
// 0, 1 and 3 s with records from 0.5 s hold for 0 (the first starts the clock), 0.5 and 2 s.
TEST(StreamProfile, EachRowHoldsForItsIntervalFromRecordsFrom) {
  Model model = compile(parse_case_text(binned_box_case("[[0, -0.15, 0]]", "[0, 0, 0]"), "profile.yaml"));
  model.output.records_from = 0.5;
  State state;
  const auto add_row = [&](double time, double first_bin, double second_bin) {
    Scalars row;
    row.time = time;
    row.sensors.resize(1);
    row.sensors[0].bin_mass = {first_bin, second_bin, 0, 0};
    row.sensors[0].bin_momentum = {2 * first_bin, 0, 0, 0};  // the first bin moves at 2 m/s, the second is at rest
    accumulate_stream_profiles(model, row, state);
  };
  add_row(0, 1, 0);
  add_row(1, 2, 0);
  add_row(3, 4, 1);
  const std::vector<StreamProfileRow> rows = stream_profile_rows(model, state.stream_profiles);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_DOUBLE_EQ(rows[0].window, 2.5);
  EXPECT_DOUBLE_EQ(rows[0].mass, (2 * 0.5 + 4 * 2) / 2.5);  // 3.6 kg
  EXPECT_DOUBLE_EQ(rows[1].mass, (1 * 2) / 2.5);            // 0.8 kg
  EXPECT_DOUBLE_EQ(rows[0].velocity, 2.0);
  EXPECT_EQ(rows[1].velocity, 0.0);
  EXPECT_EQ(rows[2].mass, 0.0);
}

// A checkpoint keeps the profiles bit for bit, so a resumed run's means cover the whole window.
TEST(StreamProfile, ACheckpointKeepsTheProfiles) {
  const Ran r = run_case(binned_box_case("[[0, -0.15, 0], [0, 0.05, 0]]", "[0.5, 0, 0]"), "demdesign_stream_profile_checkpoint");
  const StreamProfiles& before = r.state.stream_profiles;
  ASSERT_EQ(before.mass_time.size(), 4u);
  const fs::path file = fs::temp_directory_path() / "demdesign_stream_profile_checkpoint" / "profiles.bin";
  save_checkpoint(file.string(), r.model, r.state);
  const StreamProfiles after = load_checkpoint(file.string(), r.model).stream_profiles;
  EXPECT_EQ(after.mass_time, before.mass_time);
  EXPECT_EQ(after.momentum_time, before.momentum_time);
  EXPECT_EQ(after.window, before.window);
  EXPECT_EQ(after.last_row_time, before.last_row_time);
  EXPECT_EQ(after.has_row, before.has_row);
}

// ---- the choke fill -------------------------------------------------------------------------

// A section of 0.175 m^2 over 0.15 m holds 1500 x 0.175 x 0.15 = 39.375 kg at 1500 kg/m^3.
TEST(ChokeFill, FromAKnownMassInTheSection) {
  const report::ChokeFill ample = report::choke_fill(7.875, 0.7875, 1500, 0.175, 0.15);
  EXPECT_NEAR(ample.fill, 0.2, 1e-12);
  EXPECT_NEAR(ample.fill_error, 0.02, 1e-12);
  EXPECT_NEAR(ample.margin, 0.8, 1e-12);
  EXPECT_EQ(ample.verdict, report::ChokeVerdict::ample);
  EXPECT_EQ(report::choke_fill(19.6875, 0, 1500, 0.175, 0.15).verdict, report::ChokeVerdict::adequate);  // 0.5
  EXPECT_EQ(report::choke_fill(31.5, 0, 1500, 0.175, 0.15).verdict, report::ChokeVerdict::tight);        // 0.8
  const report::ChokeFill choked = report::choke_fill(47.25, 0, 1500, 0.175, 0.15);                     // 1.2
  EXPECT_EQ(choked.verdict, report::ChokeVerdict::choked);
  EXPECT_NEAR(choked.margin, -0.2, 1e-12);
  // No bulk density, area or length: no fill.
  EXPECT_TRUE(std::isnan(report::choke_fill(10, 1, 0, 0.175, 0.15).fill));
  EXPECT_TRUE(std::isnan(report::choke_fill(10, 1, 1500, std::nan(""), 0.15).fill));
  EXPECT_EQ(report::choke_fill(10, 1, 1500, 0.175, 0).verdict, report::ChokeVerdict::unknown);
  EXPECT_STREQ(report::choke_verdict_text(report::ChokeVerdict::tight), "tight: choke risk");
  // A bin's depth: 3 kg at 1500 kg/m^3 over 0.1 m x 0.2 m is 0.1 m deep.
  EXPECT_NEAR(report::stream_depth(3, 1500, 0.1, 0.2), 0.1, 1e-12);
}

// ---- the transfer chute's narrowest section ---------------------------------------------------

std::string shipped_case(const std::string& name) { return std::string(DEMDESIGN_SOURCE_DIR) + "/cases/" + name; }

/// The transfer_chute parameters of a shipped case, as the case reader keeps them.
YAML::Node chute_parameters(const std::string& case_name) {
  const YAML::Node root = YAML::LoadFile(shipped_case(case_name));
  return root["equipment"]["transfer_chute"];
}

EquipmentSpec chute_spec(const YAML::Node& params, const std::string& case_name) {
  EquipmentSpec spec;
  spec.type = "transfer_chute", spec.params = std::make_shared<YAML::Node>(params), spec.file = shipped_case(case_name);
  return spec;
}

double design(const equipment::Generated& g, const std::string& name) {
  for (const auto& [key, value] : g.design)
    if (key == name) return value;
  ADD_FAILURE() << "no design value " << name;
  return NAN;
}

const SensorSpec& sensor(const equipment::Generated& g, const std::string& name) {
  for (const SensorSpec& s : g.sensors)
    if (s.name == name) return s;
  throw std::runtime_error("no sensor " + name);
}

/// Whether any point of a mesh's triangles (sampled on a barycentric grid of 8 steps a side) lies
/// inside the box [lo, hi] shrunk by 1 um: on its faces is outside.
bool mesh_enters_box(const MeshWallSpec& mesh, const Vec3& lo, const Vec3& hi) {
  const Vec3 inner_lo = lo + Vec3::Constant(1e-6), inner_hi = hi - Vec3::Constant(1e-6);
  const auto vertex = [&](std::int32_t i) {
    const auto& v = mesh.vertices[static_cast<size_t>(i)];
    return Vec3(v[0], v[1], v[2]);
  };
  for (const auto& t : mesh.triangles) {
    const Vec3 a = vertex(t[0]), b = vertex(t[1]), c = vertex(t[2]);
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; i + j <= 8; ++j) {
        const Vec3 p = a + (b - a) * (i / 8.0) + (c - a) * (j / 8.0);
        if ((p.array() > inner_lo.array()).all() && (p.array() < inner_hi.array()).all()) return true;
      }
  }
  return false;
}

// cases/transfer_chute.yaml: inline, no rock box, so the stream comes down from the hood's exit
// and the spoon's back plate stands spoon.setback behind it: the throat is chute_width x setback =
// 0.7 m x 0.25 m = 0.175 m^2. The stream_chute box spans it between the side plates, below the
// hood's exit and above the spoon's top edge, and no wall reaches into it.
TEST(TransferChuteChoke, ShippedChutesNarrowestSectionIsItsWidthTimesTheSpoonsSetback) {
  const YAML::Node params = chute_parameters("transfer_chute.yaml");
  ASSERT_TRUE(params.IsMap());
  const EquipmentSpec spec = chute_spec(params, "transfer_chute.yaml");
  ASSERT_FALSE(params["rock_box"].IsDefined());
  ASSERT_FALSE(params["plan_angle_deg"].IsDefined());
  const double width = params["chute_width"].as<double>(), setback = params["spoon"]["setback"].as<double>();  // [m]
  const equipment::Generated g = equipment::generate(spec);
  const equipment::TransferChuteLayout c = equipment::transfer_chute_layout(spec);
  EXPECT_NEAR(design(g, "choke_section_area_m2"), width * setback, 1e-9);
  EXPECT_NEAR(design(g, "choke_section_at_height_m"), c.hood_exit_z, 1e-12);
  const SensorSpec& box = sensor(g, "stream_chute");
  EXPECT_EQ(box.kind, SensorSpec::Kind::box);
  EXPECT_EQ(box.bins, 12);
  EXPECT_EQ(box.across, Vec3(0, 1, 0));
  EXPECT_EQ(box.along, Vec3(0, 0, -1));
  EXPECT_NEAR(box.region_max.z() - box.region_min.z(), design(g, "choke_section_length_m"), 1e-12);
  // Between the side plates, the back plate and the hood's exit; above the spoon's top edge.
  EXPECT_NEAR(box.region_min.y(), -0.5 * width, 1e-12);
  EXPECT_NEAR(box.region_max.y(), 0.5 * width, 1e-12);
  EXPECT_NEAR(box.region_min.x(), c.spoon_top_x, 1e-12);
  EXPECT_NEAR(box.region_max.x(), c.hood_exit_x, 1e-12);
  EXPECT_GE(box.region_min.z(), c.spoon_top_z - 1e-12);
  EXPECT_LE(box.region_min.z(), c.hood_exit_z);
  EXPECT_GE(box.region_max.z(), c.hood_exit_z);
  for (const MeshWallSpec& mesh : g.meshes) EXPECT_FALSE(mesh_enters_box(mesh, box.region_min, box.region_max)) << mesh.name;
  // The belt's profile lies across the receiving belt, along its travel, after the loading zone.
  const SensorSpec& belt = sensor(g, "stream_belt");
  EXPECT_EQ(belt.bins, 12);
  EXPECT_EQ(belt.along, Vec3(1, 0, 0));
  EXPECT_NEAR(belt.region_max.y() - belt.region_min.y(), c.receiving_width, 1e-12);
  EXPECT_NEAR(belt.region_min.x(), sensor(g, "loading_zone").region_max.x(), 1e-12);
}

// cases/angled_transfer.yaml, 90 deg with a rock box: the hood's box and the spoon's, turned,
// overlap in the deck's opening, across the feed belt the chute's width and along it from the
// spoon box's side plate, half a chute behind the fall line, to the hood's exit.
TEST(TransferChuteChoke, RightAngleChutesNarrowestSectionIsTheDecksOpening) {
  const EquipmentSpec spec = chute_spec(chute_parameters("angled_transfer.yaml"), "angled_transfer.yaml");
  const equipment::Generated g = equipment::generate(spec);
  const equipment::TransferChuteLayout c = equipment::transfer_chute_layout(spec);
  const double width = c.chute_width, half = 0.5 * width;  // [m]
  ASSERT_NEAR(c.plan_angle, kPi / 2, 1e-12);
  // The spoon's box spans the hood's across the feed belt, and lies within it along the belt.
  ASSERT_LT(c.spoon_top_x - c.fall_x, -half);
  ASSERT_GT(c.spoon_box_x_max - c.fall_x, half);
  ASSERT_GT(c.fall_x - half, c.side_x_min);
  ASSERT_GT(c.fall_x + half, c.hood_exit_x);
  EXPECT_NEAR(design(g, "choke_section_area_m2"), (c.hood_exit_x - (c.fall_x - half)) * width, 1e-9);
  const SensorSpec& box = sensor(g, "stream_chute");
  EXPECT_NEAR(box.region_min.x(), c.fall_x - half, 1e-9);
  EXPECT_NEAR(box.region_max.x(), c.hood_exit_x, 1e-9);
  EXPECT_NEAR(box.region_min.y(), -half, 1e-9);
  EXPECT_NEAR(box.region_max.y(), half, 1e-9);
}

// ---- bins where they do not belong ------------------------------------------------------------

/// The error reading a case whose only sensor (line 7 of bins.yaml) is `sensor`; "" when none.
std::string error_of(const std::string& sensor_text) {
  const std::string text = "simulation: {duration: 0.01}\n"
                           "materials:\n  glass: {density: 2500, youngs_modulus: 5.0e7, restitution: 0.9, friction: 0.3}\n"
                           "particles:\n  - {material: glass, diameter: 0.01, positions: [[0, 0, 0.1]]}\n"
                           "sensors:\n  - " + sensor_text + "\n";
  try {
    parse_case_text(text, "bins.yaml");
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_ERROR(message, ...)                                                                                       \
  do {                                                                                                                   \
    const std::string text_ = (message);                                                                                 \
    EXPECT_FALSE(text_.empty()) << "accepted, expected an error";                                                        \
    for (const char* part : std::initializer_list<const char*>{__VA_ARGS__})                                            \
      EXPECT_NE(text_.find(part), std::string::npos) << "'" << part << "' not in: " << text_;                            \
  } while (0)

TEST(StreamProfileBadInput, BinsOutOfRangeOrOnAPlaneNameFileLineKeyAndWhatIsValid) {
  const std::string box = "min: [-0.1, -0.1, -0.1], max: [0.1, 0.1, 0.1]";
  const std::string plane = "plane: {point: [0, 0, 0], normal: [1, 0, 0]";
  const std::string region = "region: {min: [-0.1, -0.1, -0.1], max: [0.1, 0.1, 0.1]}";
  EXPECT_ERROR(error_of("{name: p, box: {" + box + ", bins: -1}}"), "bins.yaml:7:", "sensors[0].box.bins", "-1 is out of range; valid: [0, 200]");
  EXPECT_ERROR(error_of("{name: p, box: {" + box + ", bins: 201}}"), "bins.yaml:7:", "sensors[0].box.bins", "valid: [0, 200]");
  EXPECT_ERROR(error_of("{name: p, box: {" + box + ", bins: 2.5}}"), "bins.yaml:7:", "sensors[0].box.bins", "whole number");
  EXPECT_ERROR(error_of("{name: p, " + plane + ", bins: 4}, " + region + "}"), "bins.yaml:7:", "sensors[0].plane.bins",
               "a plane sensor has no bins", "valid: bins in a box sensor");
  EXPECT_ERROR(error_of("{name: p, " + plane + "}, " + region + ", bins: 4}"), "bins.yaml:7:", "sensors[0].bins", "a plane sensor has no bins",
               "valid: bins in a box sensor");
  EXPECT_ERROR(error_of("{name: p, box: {" + box + "}, bins: 4}"), "bins.yaml:7:", "sensors[0].bins", "belongs inside `box:`");
  EXPECT_ERROR(error_of("{name: p, box: {" + box + ", across: [0, 1, 0], bins: 4, along: [0, 1, 0]}}"), "bins.yaml:7:",
               "sensors[0].box.along", "perpendicular to `across`");
  EXPECT_ERROR(error_of("{name: p, box: {" + box + ", across: [0, 0, 1], bins: 4}}"), "bins.yaml:7:", "sensors[0].box.bins",
               "give `along: [x, y, z]`");
  // Valid: the flow direction defaults to across x up.
  EXPECT_EQ(error_of("{name: p, box: {" + box + ", across: [1, 0, 0], bins: 4}}"), "");
  const CaseSpec spec = parse_case_text("simulation: {duration: 0.01}\nmaterials:\n  glass: {density: 2500, youngs_modulus: 5.0e7, restitution: 0.9, "
                                        "friction: 0.3}\nparticles:\n  - {material: glass, diameter: 0.01, positions: [[0, 0, 0.1]]}\n"
                                        "sensors:\n  - {name: p, box: {" + box + ", across: [1, 0, 0], bins: 4}}\n",
                                        "bins.yaml");
  EXPECT_EQ(spec.sensors.at(0).bins, 4);
  EXPECT_EQ(spec.sensors.at(0).along, Vec3(0, -1, 0));
  // Bins on a plane sensor built in code are refused when the case is compiled.
  CaseSpec built = spec;
  built.sensors[0].kind = SensorSpec::Kind::plane;
  try {
    compile(built);
    ADD_FAILURE() << "a plane sensor with bins compiled";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("sensors[0].bins: a plane sensor has no bins"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dem
